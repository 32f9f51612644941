#!/usr/bin/env python3
"""A clock that steps forward with nothing lost against a real loss of the same length, at the
same places of the suite's walks: does the estimator tell them apart (`GapCrossing::ClockStep`),
and what does each cost in footprint RMS (% of path) against the walk as recorded?

    python3 docs/experiments/clock-steps.py 0.2,0.3,0.4        # from the repository root

Places: 30, 50 and 70 % of each log plus a fixed pseudo-random offset of up to 1 s (as
`gap-cuts.py`), and the stance ends (as the detector places them in the uncut run) nearest 30
and 70 %, where a gap takes the toe-off. A clock step shifts every row from the place on by the
length (the footprints' times too: the walk is the same); a loss removes that many rows. Every
walk of the suite, fast gait included. Prints one line per case, then per length and kind: how
often a clock step was taken (`gaps_clock_steps` in the summary; on a loss that is a mistake),
the median and worst change, and how many cases are worse by more than 0.1 % of path. Needs the
release binary (`cargo build --release -p corridor-service --bin corridor`).
"""
import json, os, shutil, statistics, subprocess, sys, tempfile
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from suite_walks import places, stamp, walks

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
config = os.environ.get("CONFIG", os.path.join(root, "configs/gdins.toml"))
recs = walks(root, fast=True)

tmp = tempfile.mkdtemp(prefix="clock-steps-")


def run(imu, truth, sh, out):
    subprocess.run([binary, "run", "--imu", imu, "--truth", truth, "--config", config,
                    "--start-heading-deg", str(sh), "--out", out], capture_output=True)
    try:
        s = json.load(open(os.path.join(out, "summary.json")))
        return s["eval"]["rms_error_pct_of_path"], s.get("gaps_clock_steps", 0), s["gaps_filled"]
    except (OSError, KeyError, TypeError, ValueError):
        return None, None, None
    finally:
        # Each run writes megabytes of estimates: 480 cases filled gigabytes.
        if not out.endswith("base"):
            shutil.rmtree(out, ignore_errors=True)


lengths = [float(x) for x in sys.argv[1].split(",")]
cases = []
for n, (name, imu, truth, sh) in enumerate(recs):
    lines = open(imu).read().splitlines()
    header, rows = lines[0], lines[1:]
    tl = open(truth).read().splitlines()
    out = os.path.join(tmp, f"{n}-base")
    base = run(imu, truth, sh, out)[0]
    ts = [float(r.split(",", 1)[0]) for r in rows]
    at_places = places(name, rows, os.path.join(out, "estimates.csv"))
    for length in lengths:
        k = int(round(length * 200))
        for at, i0 in at_places:
            d = os.path.join(tmp, f"{n}-{length}-{at}")
            os.makedirs(d, exist_ok=True)
            # A clock step: the rows from i0 on (and the footprints after them) later by k steps.
            t0 = ts[i0 - 1]
            open(f"{d}/step.csv", "w").write("\n".join(
                [header] + rows[:i0] + [stamp(r, k * 0.005) for r in rows[i0:]]) + "\n")
            open(f"{d}/truth.csv", "w").write("\n".join(
                tl[:1] + [stamp(r, k * 0.005) if float(r.split(",", 1)[0]) > t0 else r
                          for r in tl[1:]]) + "\n")
            # A loss: k rows removed (the same footprints).
            open(f"{d}/loss.csv", "w").write("\n".join([header] + rows[:i0] + rows[i0 + k:]) + "\n")
            cases.append((name, length, at, base, (f"{d}/step.csv", f"{d}/truth.csv", sh, f"{d}/o_step"),
                          (f"{d}/loss.csv", truth, sh, f"{d}/o_loss")))

with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
    steps = list(pool.map(lambda c: run(*c[4]), cases))
    losses = list(pool.map(lambda c: run(*c[5]), cases))
shutil.rmtree(tmp, ignore_errors=True)
res = []
for c, s, l in zip(cases, steps, losses):
    name, length, at, base = c[:4]
    res.append((length, name, base, s, l))
    f = lambda v: "—" if v[0] is None else f"{v[0]:.2f} ({'step' if v[1] else 'fill' if v[2] else 'gap'})"
    print(f"{name[:5]} {length} {at:8s} {base:.2f}  step {f(s)}  loss {f(l)}")
for length in lengths:
    for kind, idx in (("clock step", 3), ("loss", 4)):
        v = [(r[idx][0] - r[2], r[idx][1]) for r in res if r[0] == length and r[idx][0] is not None]
        d = [x for x, _ in v]
        print(f"{length} s {kind}: taken as a clock step {sum(1 for _, c in v if c)} of {len(v)}; "
              f"change median {statistics.median(d):+.2f}, mean {statistics.mean(d):+.2f}, worst "
              f"{max(d):+.2f} % of path; {sum(x > 0.1 for x in d)} worse by more than 0.1")
