#!/usr/bin/env python3
"""The first zero-velocity update of each stance, its residual split along and across the
sensor's heading: mean ± spread per walk (mm/s) over every bundled gdins walk, default config.

    python3 docs/experiments/touchdown-residual.py      # from the repository root

A systematic lateral part is a touchdown velocity the model lacks (docs/known-issues.md; a 5
mrad/s vertical gyro bias leaves about 7 mm/s there). A stance's first update is the `zupt` row
at the sample whose estimate says `stance_began` (one per footfall). Needs the release binary
(`cargo build --release -p corridor-service --bin corridor`).
"""
import csv, glob, math, os, statistics, subprocess, tempfile

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
config = os.environ.get("CONFIG", os.path.join(root, "configs/gdins.toml"))
with tempfile.TemporaryDirectory() as tmp:
    for imu in sorted(glob.glob(os.path.join(root, "tests/data/gdins_exp*/imu.csv"))):
        name = os.path.basename(os.path.dirname(imu))
        out = os.path.join(tmp, name)
        subprocess.run([binary, "run", "--imu", imu, "--config", config, "--out", out],
                       check=True, capture_output=True)
        # The heading at each footfall's first sample.
        yaw = {r["t_s"]: float(r["yaw_rad"])
               for r in csv.DictReader(open(out + "/estimates.csv")) if r["stance_began"] == "1"}
        along, lateral = [], []
        for r in csv.DictReader(open(out + "/innovations.csv")):
            if r["kind"] != "zupt" or r["t_s"] not in yaw:
                continue
            y, r0, r1 = yaw[r["t_s"]], float(r["r0"]), float(r["r1"])
            along.append(1e3 * (r0 * math.cos(y) + r1 * math.sin(y)))
            lateral.append(1e3 * (-r0 * math.sin(y) + r1 * math.cos(y)))
        sd = statistics.pstdev(lateral)
        print(f"{name[6:11]}  stances {len(lateral):3d}  lateral {statistics.mean(lateral):+6.1f} "
              f"± {sd:5.1f} (standard error {sd / math.sqrt(len(lateral)):4.1f})  "
              f"along {statistics.mean(along):+6.1f} ± {statistics.pstdev(along):5.1f} mm/s")
