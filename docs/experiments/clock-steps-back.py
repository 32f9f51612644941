#!/usr/bin/env python3
"""A clock that steps back with nothing lost (a host clock set back, stamps that run on from the
earlier time at the sensor's period): does the estimator take the step (`clock_steps_back` in the
summary), and what does it cost in footprint RMS (% of path) against the walk as recorded?

    python3 docs/experiments/clock-steps-back.py 0.03,0.1,0.3,0.9     # from the repository root

Places as `clock-steps.py`: 30, 50 and 70 % of each log plus a fixed pseudo-random offset of up
to 1 s, and the stance ends (as the detector places them in the uncut run) nearest 30 and 70 %.
Every row from the place on is stamped earlier by the length, and so is every footprint after
it; a footprint within the length after the place would be stamped inside the overlap, where a
time means two moments, so it is left out of the truth of both the stepped and the unstepped
run that it is compared with. The same places with the rows of the length before the place sent
a second time (a driver that re-sends a buffer: the same stamps and values), which must not be
taken for a step. Prints one line per case, then per length and kind the steps taken, the rows
refused, and the median, mean and worst change. `BIN=...` runs another build (a build that
refuses the rows up to the old time may stop at the reader's 1 % limit: shown as "—");
`JITTER=0.004` stamps every row up to that much late first (host arrival times, seeded). Needs the
release binary (`cargo build --release -p corridor-service --bin corridor`).
"""
import json, os, random, shutil, statistics, subprocess, sys, tempfile
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from suite_walks import places, stamp, walks

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
config = os.environ.get("CONFIG", os.path.join(root, "configs/gdins.toml"))
recs = walks(root, fast=True)

tmp = tempfile.mkdtemp(prefix="clock-steps-back-")


def run(imu, truth, sh, out, keep=False):
    subprocess.run([binary, "run", "--imu", imu, "--truth", truth, "--config", config,
                    "--start-heading-deg", str(sh), "--out", out], capture_output=True)
    try:
        s = json.load(open(os.path.join(out, "summary.json")))
        refused = sum(s["samples_refused_counts"].values()) + sum(s["input_rows_rejected"].values())
        return s["eval"]["rms_error_pct_of_path"], s.get("clock_steps_back", 0), refused
    except (OSError, KeyError, TypeError, ValueError):
        return None, None, None
    finally:
        if not keep:
            shutil.rmtree(out, ignore_errors=True)


lengths = [float(x) for x in sys.argv[1].split(",")]
cases = []
for n, (name, imu, truth, sh) in enumerate(recs):
    lines = open(imu).read().splitlines()
    header, rows = lines[0], lines[1:]
    jitter = float(os.environ.get("JITTER", "0"))
    if jitter > 0:
        random.seed(name)
        rows = [stamp(r, jitter * random.random()) for r in rows]
        rows = [r for i, r in enumerate(rows)
                if i == 0 or float(r.split(",", 1)[0]) > float(rows[i - 1].split(",", 1)[0])]
        imu = os.path.join(tmp, f"{n}-jittered.csv")
        open(imu, "w").write("\n".join([header] + rows) + "\n")
    tl = open(truth).read().splitlines()
    out = os.path.join(tmp, f"{n}-base")
    run(imu, truth, sh, out, keep=True)
    ts = [float(r.split(",", 1)[0]) for r in rows]
    at_places = places(name, rows, os.path.join(out, "estimates.csv"))
    shutil.rmtree(out, ignore_errors=True)
    for length in lengths:
        back = round(length * 200) * 0.005
        for at, i0 in at_places:
            d = os.path.join(tmp, f"{n}-{length}-{at}")
            os.makedirs(d, exist_ok=True)
            t0 = ts[i0 - 1]
            t_of = lambda r: float(r.split(",", 1)[0])
            kept = [r for r in tl[1:] if not t0 < t_of(r) <= t0 + back + 0.005]
            open(f"{d}/truth.csv", "w").write("\n".join(tl[:1] + kept) + "\n")
            open(f"{d}/truth_step.csv", "w").write("\n".join(
                tl[:1] + [stamp(r, -back) if t_of(r) > t0 else r for r in kept]) + "\n")
            open(f"{d}/step.csv", "w").write("\n".join(
                [header] + rows[:i0] + [stamp(r, -back) for r in rows[i0:]]) + "\n")
            k = round(length * 200)
            open(f"{d}/resent.csv", "w").write("\n".join(
                [header] + rows[:i0] + rows[i0 - k:i0] + rows[i0:]) + "\n")
            cases.append((name, length, at, (imu, f"{d}/truth.csv", sh, f"{d}/o_base"),
                          (f"{d}/step.csv", f"{d}/truth_step.csv", sh, f"{d}/o_step"),
                          (f"{d}/resent.csv", f"{d}/truth.csv", sh, f"{d}/o_resent")))

with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
    bases = list(pool.map(lambda c: run(*c[3]), cases))
    steps = list(pool.map(lambda c: run(*c[4]), cases))
    resent = list(pool.map(lambda c: run(*c[5]), cases))
shutil.rmtree(tmp, ignore_errors=True)
res = []
f = lambda s: "—" if s[0] is None else f"{s[0]:.2f} (steps back {s[1]}, refused {s[2]})"
for c, b, s, r in zip(cases, bases, steps, resent):
    name, length, at = c[:3]
    res.append((length, b[0], s, r))
    print(f"{name[:5]} {length} {at:8s} {b[0]:.2f}  stepped {f(s)}  re-sent {f(r)}")
for length in lengths:
    for kind, i in (("stepped back", 2), ("re-sent", 3)):
        v = [(x[i][0] - x[1], x[i][1], x[i][2]) for x in res if x[0] == length and x[i][0] is not None]
        d = [x for x, _, _ in v]
        print(f"{length} s {kind}: {len(res) // len(lengths) - len(v)} runs failed; taken as a "
              f"step back {sum(1 for _, c, _ in v if c)} of {len(v)}, rows refused "
              f"{sum(r for _, _, r in v)}; change median {statistics.median(d):+.2f}, mean "
              f"{statistics.mean(d):+.2f}, worst {max(d):+.2f} % of path; "
              f"{sum(x > 0.1 for x in d)} worse by more than 0.1")
