#!/usr/bin/env python3
"""What the unit's typical bias (`alignment.typical_gyro_bias_rad_s` in configs/gdins.toml)
costs a unit whose bias is not the typical one: each normal-gait walk with a constant bias
added to every sample (another unit, simulated), run whole (with its rest) and started without
its rest (cut 0.2 s before its first footprint, as the suite's start without rest), with the
shipped configuration and with a copy without the two typical-bias keys (the start at zero ±
10 mrad/s). Prints per offset the median and worst cost of the start without rest against the
whole run, % of path, and on how many walks it stays within +0.1. Needs the release binary.

    python3 docs/experiments/typical-bias-other-unit.py        # from the repository root
"""
import os, re, statistics, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from suite_walks import walks
import json, subprocess

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
shipped = os.path.join(root, "configs/gdins.toml")
tmp = tempfile.mkdtemp(prefix="typical-")
plain = os.path.join(tmp, "no-typical.toml")
text = open(shipped).read()
text = re.sub(r"^typical_gyro_bias_(rad_s|sd_rad_s) = .*$", "", text, flags=re.M)
open(plain, "w").write(text)


def rms(config, imu, truth, sh, bias):
    out = os.path.join(tmp, "out")
    args = [binary, "run", "--imu", imu, "--truth", truth, "--config", config,
            "--start-heading-deg", str(sh), "--out", out]
    if any(bias):
        args += ["--inject-gyro-bias", ",".join(str(b) for b in bias)]
    subprocess.run(args, capture_output=True)
    try:
        return json.load(open(os.path.join(out, "summary.json")))["eval"]["rms_error_pct_of_path"]
    except (OSError, KeyError, TypeError, ValueError):
        return None


def cut(imu, truth):
    t0 = float(open(truth).read().splitlines()[1].split(",")[0]) - 0.2
    lines = open(imu).read().splitlines()
    kept = [lines[0]] + [l for l in lines[1:] if float(l.split(",", 1)[0]) >= t0]
    path = os.path.join(tmp, "cut.csv")
    open(path, "w").write("\n".join(kept) + "\n")
    return path


offsets = [(0.0, 0.0, 0.0), (0.005, -0.005, 0.005), (-0.005, 0.005, -0.005), (0.0, 0.0, -0.01),
           (0.01, 0.01, 0.0)]
for bias in offsets:
    costs = {"typical": [], "zero": []}
    for name, imu, truth, sh in walks(root):
        short = cut(imu, truth)
        for label, config in (("typical", shipped), ("zero", plain)):
            whole = rms(config, imu, truth, sh, bias)
            start = rms(config, short, truth, sh, bias)
            if whole is not None and start is not None:
                costs[label].append(start - whole)
    line = f"added bias {[round(b * 1e3, 1) for b in bias]} mrad/s:"
    for label, c in costs.items():
        line += (f"  {label}: median {statistics.median(c):+.2f}, worst {max(c):+.2f}, "
                 f"within +0.1 on {sum(x <= 0.1 for x in c)} of {len(c)}")
    print(line, flush=True)
