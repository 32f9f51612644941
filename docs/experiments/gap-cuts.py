#!/usr/bin/env python3
"""Gaps cut out of the suite's normal-gait walks: the footprint RMS (% of path) of each walk with
`LEN` seconds of samples removed at three places (30, 50 and 70 % of the log, plus a fixed
pseudo-random offset of up to 1 s), against the same walk without the cut.

    python3 docs/experiments/gap-cuts.py 0.055,0.1,0.2,0.3      # from the repository root
    CONFIG=configs/gdins_segment.toml python3 docs/experiments/gap-cuts.py 0.055

The samples, not only the time, are removed: the motion in the gap is lost. Prints one line per
cut, then per length the median and worst change and how many cuts are worse by more than 0.1 %
of path. The figures of `estimator.max_bridge_s` and `estimator.max_fill_s` in
`configs/gdins.toml` came from this script (with `max_fill_s = 0`, and `max_bridge_s = 0` for the
bridge's figures, in a copy of the config for the "new segment" column). Needs the
release binary (`cargo build --release -p corridor-service --bin corridor`).
"""
import json, os, random, re, statistics, subprocess, sys, tempfile

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
config = os.environ.get("CONFIG", os.path.join(root, "configs/gdins.toml"))
suite = open(os.path.join(root, "configs/eval/gdins.toml")).read()
recs = []
for block in suite.split("[[recording]]")[1:]:
    name = re.search(r'name = "([^"]+)"', block).group(1)
    path = lambda key: re.search(key + r' = "([^"]+)"', block).group(1).replace("../../", root + "/")
    sh = re.search(r"start_heading_deg = ([-\d.]+)", block)
    gait = re.search(r'gait = "(\w+)"', block)
    if gait and gait.group(1) != "normal":
        continue
    recs.append((name, path("imu"), path("truth"), float(sh.group(1)) if sh else 0.0))

tmp = tempfile.mkdtemp(prefix="gap-cuts-")


def rms_pct(imu, truth, sh):
    out = os.path.join(tmp, "out")
    subprocess.run([binary, "run", "--imu", imu, "--truth", truth, "--config", config,
                    "--start-heading-deg", str(sh), "--out", out], capture_output=True)
    try:
        return json.load(open(os.path.join(out, "summary.json")))["eval"]["rms_error_pct_of_path"]
    except (OSError, KeyError, TypeError, ValueError):
        return None


lengths = [float(x) for x in sys.argv[1].split(",")]
res = []
for name, imu, truth, sh in recs:
    lines = open(imu).read().splitlines()
    header, rows = lines[0], lines[1:]
    base = rms_pct(imu, truth, sh)
    for length in lengths:
        k = int(round(length * 200))
        for pos in (0.3, 0.5, 0.7):
            random.seed(f"{name}/{pos}")
            i0 = int(len(rows) * pos) + random.randint(0, 200)
            cut = os.path.join(tmp, "cut.csv")
            open(cut, "w").write("\n".join([header] + rows[:i0] + rows[i0 + k:]) + "\n")
            v = rms_pct(cut, truth, sh)
            res.append((length, base, v))
            print(name[:5], length, pos, f"{base:.2f}", "—" if v is None else f"{v:.2f}", flush=True)
for length in lengths:
    d = [v - b for (L, b, v) in res if L == length and v is not None]
    print(f"gap {length} s: median {statistics.median(d):+.2f}, worst {max(d):+.2f} % of path; "
          f"{sum(x > 0.1 for x in d)} of {len(d)} cuts worse by more than 0.1 "
          f"(by more than 1: {sum(x > 1 for x in d)}, 3: {sum(x > 3 for x in d)}; "
          f"mean {statistics.mean(d):+.2f})")
