#!/usr/bin/env python3
"""The suite on its own walks seen in a mirror: a check that nothing in the configuration or the
estimator prefers one side (left turns over right ones, a foot that toes out one way, a bias of
one sign).

    python3 docs/experiments/mirror-walks.py      # from the repository root, release binary built

Each bundled walk is reflected in the vertical plane through its sensor's x and z axes: a
mirror-image walker with a mirror-image sensor. Rates are pseudovectors, so under the reflection
y -> -y of the body frame the gyro becomes (-gx, gy, -gz); the specific force becomes
(ax, -ay, az); the footprints (x, y) -> (x, -y); the start heading psi -> -psi on the same grid.
This is a physically valid walk (the sensor's own errors mirror with it: a bias, a clipped rail,
a misalignment), so a side-free estimator scores it as it scores the walk itself, up to its
arithmetic. `corridor eval` runs the mirrored suite (a copy of configs/eval/gdins.toml pointing
at mirrored copies of the logs, meta.json kept) and the script prints both suites' rows and
summaries side by side. OUT=dir keeps the mirrored suite's output.
"""
import json, os, re, shutil, subprocess, sys, tempfile

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
tmp = tempfile.mkdtemp(prefix="mirror-walks-")
out = os.environ.get("OUT", os.path.join(tmp, "out"))
suite_path = os.path.join(root, "configs/eval/gdins.toml")
suite = open(suite_path).read()


def mirror_imu(src, dst):
    with open(src) as f, open(dst, "w") as g:
        header = f.readline()
        g.write(header)
        cols = header.strip().split(",")
        flip = [cols.index(c) for c in ("gx_rad_s", "gz_rad_s", "ay_m_s2")]
        # a magnetometer is a pseudovector's kin too (a field): mirrored as the rates
        flip += [cols.index(c) for c in ("mx_gauss", "mz_gauss") if c in cols]
        for line in f:
            v = line.rstrip("\n").split(",")
            for i in flip:
                if v[i] not in ("", "NaN"):
                    v[i] = v[i][1:] if v[i].startswith("-") else "-" + v[i]
            g.write(",".join(v) + "\n")


def mirror_truth(src, dst):
    with open(src) as f, open(dst, "w") as g:
        header = f.readline()
        g.write(header)
        y = header.strip().split(",").index("y_m")
        for line in f:
            v = line.rstrip("\n").split(",")
            v[y] = repr(-float(v[y]))
            g.write(",".join(v) + "\n")


blocks = suite.split("[[recording]]")
mirrored = [blocks[0]]
for block in blocks[1:]:
    path = lambda key: re.search(key + r' = "([^"]+)"', block).group(1)
    imu, truth = path("imu"), path("truth")
    walk = os.path.basename(os.path.dirname(imu))
    d = os.path.join(tmp, walk)
    os.makedirs(d)
    base = os.path.dirname(suite_path)
    mirror_imu(os.path.normpath(os.path.join(base, imu)), os.path.join(d, "imu.csv"))
    mirror_truth(os.path.normpath(os.path.join(base, truth)), os.path.join(d, "ground_truth.csv"))
    meta = os.path.normpath(os.path.join(base, os.path.dirname(truth), "meta.json"))
    if os.path.exists(meta):
        shutil.copy(meta, d)
    b = block.replace(imu, os.path.join(d, "imu.csv")).replace(truth, os.path.join(d, "ground_truth.csv"))
    for key in ("config", "baseline_config"):
        rel = re.search(key + r' = "([^"]+)"', b)
        if rel:
            b = b.replace(rel.group(0), f'{key} = "{os.path.normpath(os.path.join(base, rel.group(1)))}"')
    sh = re.search(r"start_heading_deg = ([-\d.]+)", b)
    b = b.replace(sh.group(0), f"start_heading_deg = {-float(sh.group(1))}")
    mirrored.append(b)
mirrored_suite = os.path.join(tmp, "mirrored.toml")
open(mirrored_suite, "w").write("[[recording]]".join(mirrored))

runs = {}
for label, s, o in (("as recorded", suite_path, os.path.join(tmp, "plain")), ("mirrored", mirrored_suite, out)):
    subprocess.run([binary, "eval", "--suite", s, "--out", o], check=True, capture_output=True)
    runs[label] = {r["recording"]: r for r in json.load(open(os.path.join(o, "results.json")))}


def pct(r, mode):
    return r[mode]["rms_pct"]


print("| recording | gait | baseline | baseline mirrored | default | default mirrored |")
print("|---|---|---|---|---|---|")
summary = {k: {"zupt_rest": [], "best_rest": []} for k in runs}
for name, r in runs["as recorded"].items():
    m = runs["mirrored"][name]
    cells = []
    for mode in ("zupt_rest", "best_rest"):
        for label, x in (("as recorded", r), ("mirrored", m)):
            v = pct(x, mode)
            cells.append(f"{v:.2f} %")
            if x["gait"] == "normal":
                summary[label][mode].append(v)
    print(f"| {name} | {r['gait']} | " + " | ".join(cells) + " |")


def med(v):
    v = sorted(v)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


for label in runs:
    b, d = summary[label]["zupt_rest"], summary[label]["best_rest"]
    worse = sum(1 for x, y in zip(b, d) if y > x + 0.05)
    print(f"{label}: normal gait ({len(d)}) default median {med(d):.3f} %, worst {max(d):.2f} %; "
          f"baseline median {med(b):.3f} %, worst {max(b):.2f} %; default worse than the baseline "
          f"by > 0.05 on {worse}")
