#!/usr/bin/env python3
"""Gaps cut out at the worst phase of a stride: `LEN` seconds (default 0.3) of samples removed
starting `OFFSET` seconds after the end of a stance (as the detector places it in the uncut run),
at the stance ends nearest 30, 50 and 70 % of each normal-gait walk; the footprint RMS (% of
path) against the same walk without the cut. `gap-cuts.py` cuts at places that do not depend on
the gait, where most cuts fall in a stance or late in a swing and cost little; here every cut
takes the toe-off or the swing after it.

    python3 docs/experiments/gap-cuts-at-toe-off.py -0.3,-0.1,0,0.1,0.2 [LEN]   # repository root
    CONFIG=copy-of-gdins.toml python3 docs/experiments/gap-cuts-at-toe-off.py 0,0.1

Prints per offset the median, mean and worst change and how many cuts are worse by more than
0.1 % of path. Needs the release binary (`cargo build --release -p corridor-service --bin
corridor`).
"""
import csv, json, os, re, statistics, subprocess, sys, tempfile
from concurrent.futures import ThreadPoolExecutor

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

tmp = tempfile.mkdtemp(prefix="gap-cuts-at-toe-off-")
offsets = [float(x) for x in sys.argv[1].split(",")]
length = float(sys.argv[2]) if len(sys.argv) > 2 else 0.3


def rms_pct(imu, truth, sh, out):
    subprocess.run([binary, "run", "--imu", imu, "--truth", truth, "--config", config,
                    "--start-heading-deg", str(sh), "--out", out], capture_output=True)
    try:
        return json.load(open(os.path.join(out, "summary.json")))["eval"]["rms_error_pct_of_path"]
    except (OSError, KeyError, TypeError, ValueError):
        return None


def walk(rec):
    name, imu, truth, sh = rec
    tag = re.sub(r"\W", "", name)
    lines = open(imu).read().splitlines()
    header, rows = lines[0], lines[1:]
    ts = [float(r.split(",", 1)[0]) for r in rows]
    out = os.path.join(tmp, tag)
    base = rms_pct(imu, truth, sh, out)
    est = list(csv.DictReader(open(os.path.join(out, "estimates.csv"))))
    ends = [float(est[i]["t_s"]) for i in range(1, len(est))
            if est[i - 1]["stance"] == "1" and est[i]["stance"] == "0"]
    res = []
    for pos in (0.3, 0.5, 0.7):
        t_end = min(ends, key=lambda e: abs(e - (ts[0] + pos * (ts[-1] - ts[0]))))
        for off in offsets:
            i0 = min(range(len(ts)), key=lambda i: abs(ts[i] - (t_end + off)))
            cut = os.path.join(tmp, f"cut_{tag}.csv")
            k = int(round(length * 200))
            open(cut, "w").write("\n".join([header] + rows[:i0] + rows[i0 + k:]) + "\n")
            v = rms_pct(cut, truth, sh, os.path.join(tmp, tag + "_cut"))
            res.append((off, name, pos, base, v))
            print(name[:5], pos, f"{off:+.2f}", f"{base:.2f}", "—" if v is None else f"{v:.2f}",
                  flush=True)
    return res


with ThreadPoolExecutor(2) as ex:
    res = [r for rs in ex.map(walk, recs) for r in rs]
for off in offsets:
    d = [(v - b, n, p) for o, n, p, b, v in res if o == off and v is not None]
    ch = [x[0] for x in d]
    worst = max(d)
    print(f"offset {off:+.2f} s: median {statistics.median(ch):+.3f}, mean {statistics.mean(ch):+.3f}, "
          f"worst {worst[0]:+.2f} ({worst[1][:5]} at {worst[2]}), worse by > 0.1: {sum(x > 0.1 for x in ch)} of {len(ch)}")
