#!/usr/bin/env python3
"""The diagnosis's stride-length line on corner legs, checked where the answer is known: the five
walks surveyed at every stride, their footprints thinned to the corners (every footprint where
the walk turns by more than 45°, and the first and last), diagnosed with both truths on the
diagnosis's own model (`diagnosis_model` of the detection matrix: `configs/gdins.toml` without
`[model]`, the foot axis alone, the plain gate, the baseline's `[eskf]`), the walk's start heading
0° on the grid at 0°. Two parts:

1. clean, plain zero-velocity update: the stride scale fitted on the corner legs against the one
   fitted on every single stride (the short strides the rolling update then fixes);
2. the accelerometer scale of +2 % the matrix injects (the CSV's specific force scaled), with the
   rolling update in the model, so that the fix offered is the stride scale itself: which check
   judged it (the second half of the footprints, or, where the first half is too few legs, each
   corner leg held out in turn) and what it decided, with the whole walk's error before and after.

What it shows (session 52): part 1, the corner legs give 0.9785 ± 0.0029 / 0.9850 ± 0.0033 /
0.9804 ± 0.0016 / 0.9799 ± 0.0036 against 0.9819 / 0.9823 / 0.9801 / 0.9852 on every stride
(exp31, exp32, exp36, exp37: within 1.5 σ of the corner fit; exp40's corners are a serpentine's,
a stride apart, so its thinned truth is a single-stride fit again, 0.9856 ± 0.0042 against
0.9770); part 2, exp32's and exp36's thinned truths have first halves too few legs to fit, and the
leg-by-leg check keeps the fix as the second-half check does on their full truths (whole walk
0.578 -> 0.541 m and 0.767 -> 0.567 m); exp37's thinned truth (13 legs) is judged on its second
half and not kept where its full truth keeps it, exp40 is kept by neither, exp31's corner fit is
not significant (score 2.4). Needs the release binary (BIN= to use another).

    python3 docs/experiments/corner-thinned-truth.py        # from the repository root
"""
import csv, json, math, os, subprocess, tempfile

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
walks = [
    "exp31_corridor_back_and_forth",
    "exp32_box_and_corridor",
    "exp36_corridor_out_and_back",
    "exp37_spiral_and_corridor",
    "exp40_serpentine_return",
]


def sections(path):
    out, cur = {}, None
    for line in open(path).read().split("\n"):
        if line.startswith("["):
            cur = line.strip()
        out.setdefault(cur, []).append(line)
    return out


def diagnosis_model(rolling):
    """`configs/gdins.toml` as the detection matrix's `diagnosis_model` makes it."""
    g, b = sections("configs/gdins.toml"), sections("configs/gdins_zupt_baseline.toml")
    lines = []
    for name, body in g.items():
        if name == "[model]":
            body = ["[model]"]
        elif name == "[eskf]":
            body = b["[eskf]"] + (["zupt_rolling_height_m = 0.08"] if rolling else [])
        elif name == "[heading]":
            body = [
                'observations = "foot_axis"' if l.startswith("observations =")
                else "aligned_prior = 1.0" if l.startswith("aligned_prior =") else l
                for l in body
            ]
        lines += body
    return "\n".join(lines)


def corners(truth_in, truth_out):
    rows = list(csv.reader(open(truth_in)))
    head, pts = rows[0], rows[1:]
    xy = [(float(r[1]), float(r[2])) for r in pts]
    keep = [0]
    for i in range(1, len(xy) - 1):
        a = math.atan2(xy[i][1] - xy[i - 1][1], xy[i][0] - xy[i - 1][0])
        b = math.atan2(xy[i + 1][1] - xy[i][1], xy[i + 1][0] - xy[i][0])
        if abs((b - a + math.pi) % (2 * math.pi) - math.pi) > math.radians(45):
            keep.append(i)
    keep.append(len(xy) - 1)
    with open(truth_out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(head)
        for i in keep:
            w.writerow(pts[i])
    return len(keep) - 1


def scale_accel(imu_in, imu_out, fraction):
    with open(imu_in) as f, open(imu_out, "w", newline="") as g:
        r, w = csv.reader(f), csv.writer(g)
        head = next(r)
        w.writerow(head)
        cols = [head.index(c) for c in ("ax_m_s2", "ay_m_s2", "az_m_s2")]
        for row in r:
            for i in cols:
                row[i] = repr(float(row[i]) * (1 + fraction))
            w.writerow(row)


def diagnose(tmp, imu, truth, config, out):
    p = subprocess.run(
        [binary, "diagnose", "--imu", imu, "--truth", truth, "--config", config,
         "--start-heading-deg", "0", "--grid-deg", "0", "--out", os.path.join(tmp, out)],
        capture_output=True, text=True)
    if p.returncode:
        raise SystemExit(f"{out}: {p.stderr.strip()}")
    r = json.load(open(os.path.join(tmp, out, "report.json")))
    line = r.get("stride_length")
    if not line:
        return "no stride-length line"
    f = line["fit"]
    words = (f"{f['ratio']:.4f} ± {f['std_err']:.4f} over {f['legs']} {f['kind']}, "
             f"score {line['finding']['score']:.1f}")
    for it in r["iterations"]:
        if it["effect"] != "stride_length":
            continue
        held = it.get("held_out")
        check = ("" if not held else
                 f"; {held['kind']} {held['rms_m'][0]:.3f} -> {held['rms_m'][1]:.3f} m")
        words += (f"; fix {it['fix']}{check}; walk {it['before']['gcp_rms_m']:.3f} -> "
                  f"{it['after']['gcp_rms_m']:.3f} m, {'kept' if it['kept'] else 'not kept'}")
    return words


with tempfile.TemporaryDirectory() as tmp:
    configs = {}
    for rolling in (False, True):
        configs[rolling] = os.path.join(tmp, f"diag_{rolling}.toml")
        open(configs[rolling], "w").write(diagnosis_model(rolling))
    for part, (rolling, fraction) in enumerate([(False, 0.0), (True, 0.02)], start=1):
        print(f"\n{part}. " + ("clean, plain zero-velocity update" if part == 1 else
                               "accelerometer scale +2 %, rolling update in the model"))
        for walk in walks:
            data = os.path.join(root, "tests/data", f"gdins_{walk}")
            thinned = os.path.join(tmp, f"{walk}_corners.csv")
            legs = corners(os.path.join(data, "ground_truth.csv"), thinned)
            imu = os.path.join(data, "imu.csv")
            if fraction:
                imu = os.path.join(tmp, f"{walk}_imu.csv")
                scale_accel(os.path.join(data, "imu.csv"), imu, fraction)
            name = walk.split("_")[0]
            every = diagnose(tmp, imu, os.path.join(data, "ground_truth.csv"), configs[rolling],
                             f"{walk}_{part}_every")
            thin = diagnose(tmp, imu, thinned, configs[rolling], f"{walk}_{part}_corners")
            print(f"  {name} every stride: {every}")
            print(f"  {name} {legs} corner legs: {thin}")
