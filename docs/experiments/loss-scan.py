#!/usr/bin/env python3
"""Real losses cut at every `EVERY`-th sample (default 23) of the given walks: how many does the
estimator take for a clock step (`gaps_clock_steps` in the summary), and what did those cost in
footprint RMS (% of path) against the walk as recorded? The dense check of the clock-step test's
false alarms that `clock-steps.py`'s five places per walk cannot give.

    python3 docs/experiments/loss-scan.py exp22,exp38 0.06,0.1,0.15      # from the repository root

Walks by the start of their suite name. Needs the release binary. Prints every loss taken for a
step, then per walk and length the count.
"""
import json, os, shutil, subprocess, sys, tempfile
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from suite_walks import walks

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
config = os.environ.get("CONFIG", os.path.join(root, "configs/gdins.toml"))
every = int(os.environ.get("EVERY", "23"))
names = sys.argv[1].split(",")
lengths = [float(x) for x in sys.argv[2].split(",")]
tmp = tempfile.mkdtemp(prefix="loss-scan-")


def run(args):
    imu, truth, sh, out = args
    subprocess.run([binary, "run", "--imu", imu, "--truth", truth, "--config", config,
                    "--start-heading-deg", str(sh), "--out", out], capture_output=True)
    try:
        s = json.load(open(os.path.join(out, "summary.json")))
        return s["eval"]["rms_error_pct_of_path"], s["gaps_clock_steps"]
    except (OSError, KeyError, TypeError, ValueError):
        return None, None
    finally:
        shutil.rmtree(out, ignore_errors=True)
        os.remove(imu) if imu.startswith(tmp) else None


for name, imu, truth, sh in walks(root, fast=True):
    if not any(name.startswith(n) for n in names):
        continue
    lines = open(imu).read().splitlines()
    header, rows = lines[0], lines[1:]
    base = run((imu, truth, sh, os.path.join(tmp, "base")))[0]
    for length in lengths:
        k = int(round(length * 200))
        jobs = []
        for i0 in range(400, len(rows) - k - 400, every):
            cut = os.path.join(tmp, f"{i0}.csv")
            open(cut, "w").write("\n".join([header] + rows[:i0] + rows[i0 + k:]) + "\n")
            jobs.append((cut, truth, sh, os.path.join(tmp, f"o{i0}")))
        with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
            got = list(pool.map(run, jobs))
        taken = [(j[0], g) for j, g in zip(jobs, got) if g[1]]
        for cut, (rms, _) in taken:
            print(f"{name[:5]} {length} s cut at row {os.path.basename(cut)[:-4]}: taken for a step, "
                  f"{base:.3f} -> {rms:.3f} %")
        print(f"{name[:5]} {length} s: {len(taken)} of {len(jobs)} real losses taken for a clock step",
              flush=True)
shutil.rmtree(tmp, ignore_errors=True)
