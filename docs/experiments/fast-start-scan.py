#!/usr/bin/env python3
"""A daemon started at any moment of a fast walk: exp34 and exp38 cut every `STEP` s (0.1) from
their first footprint to 10 s before their last (their first sample is wherever the cut falls:
a swing, a stance, a turn). Per cut: how long after the cut the first estimate came (the
filter's start, found by the fast-gait rule), how far the start went back from there
(`alignment.fast_gait_replay_s`: the filter started on an earlier stance and ran over the
samples since), and so how long after the cut the filter's origin lies; and the footprint RMS
on the footprints after the cut (first-leg alignment, % of path; the rows before the first
estimate say "aligning" at the origin, and their footprints count). With `AFTER_FIRST=1` only
the footprints after the first estimate are scored: the first-leg alignment then takes the
origin out, and what is left is the filter itself. Prints percentiles per walk. Needs the
release binary; about 30 s on 2 cores (twice that with `AFTER_FIRST`).

    python3 docs/experiments/fast-start-scan.py            # from the repository root
    CONFIG=my.toml STEP=0.2 python3 docs/experiments/fast-start-scan.py
"""
import concurrent.futures, csv, json, os, statistics, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from suite_walks import walks

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
config = os.environ.get("CONFIG", os.path.join(root, "configs/gdins.toml"))
step_s = float(os.environ.get("STEP", "0.1"))
after_first = os.environ.get("AFTER_FIRST") == "1"
tmp = tempfile.mkdtemp(prefix="fast-start-")


def run(job):
    """One cut: (walk, cut time, first estimate's delay after the cut or None, how far the start
    went back, s, footprint RMS or None)."""
    w, t_cut, header, rows, truth_lines, sh = job
    d = tempfile.mkdtemp(dir=tmp)
    imu, truth = os.path.join(d, "imu.csv"), os.path.join(d, "truth.csv")
    open(imu, "w").write("\n".join([header] + rows) + "\n")
    open(truth, "w").write("\n".join(truth_lines) + "\n")
    args = [binary, "run", "--imu", imu, "--config", config, "--start-heading-deg", str(sh)]
    if after_first:
        # When the first estimate came, then the footprints after it.
        subprocess.run(args + ["--out", d], capture_output=True)
        first = next((float(e["t_s"]) for e in csv.DictReader(open(os.path.join(d, "estimates.csv")))
                      if e["phase"] != "aligning"), None)
        later = [r for r in truth_lines[1:] if first is not None and float(r.split(",", 1)[0]) > first + 0.05]
        open(truth, "w").write("\n".join(truth_lines[:1] + later) + "\n")
        if len(later) < 4:
            truth = None
    if truth:
        subprocess.run(args + ["--truth", truth, "--out", d], capture_output=True)
    if not os.path.exists(os.path.join(d, "estimates.csv")) or not truth:
        # A run whose evaluation failed (it started after the legs the footprints are aligned
        # on) writes nothing: when it started, without the footprints.
        subprocess.run(args + ["--out", d], capture_output=True)
    try:
        first = next((float(e["t_s"]) for e in csv.DictReader(open(os.path.join(d, "estimates.csv")))
                      if e["phase"] != "aligning"), None)
        s = json.load(open(os.path.join(d, "summary.json")))
        rms = s["eval"]["rms_error_pct_of_path"] if s.get("eval") else None
        back_s = s.get("start_replayed_ms", 0) / 1e3
    except (OSError, KeyError, TypeError, ValueError):
        first, rms, back_s = None, None, 0.0
    subprocess.run(["rm", "-rf", d])
    return w, t_cut, None if first is None else first - t_cut, back_s, rms


def pct(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(q * len(xs)))] if xs else float("nan")


jobs = []
for name, imu, truth, sh in walks(root, fast=True):
    w = name[:5]
    if w not in ("exp34", "exp38"):
        continue
    lines = open(imu).read().splitlines()
    header, rows = lines[0], lines[1:]
    tl = open(truth).read().splitlines()
    ts = [float(r.split(",", 1)[0]) for r in rows]
    t_fp = [float(r.split(",", 1)[0]) for r in tl[1:]]
    k = 0
    while t_fp[0] + k * step_s < t_fp[-1] - 10.0:
        t_cut = t_fp[0] + k * step_s
        i0 = next(i for i, t in enumerate(ts) if t >= t_cut)
        after = [r for r in tl[1:] if float(r.split(",", 1)[0]) > t_cut + 0.05]
        jobs.append((w, round(t_cut, 3), header, rows[i0:], [tl[0]] + after, sh))
        k += 1

with concurrent.futures.ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as ex:
    res = list(ex.map(run, jobs))
out = os.environ.get("OUT")
if out:
    json.dump(res, open(out, "w"))
for w in ("exp34", "exp38"):
    rs = [r for r in res if r[0] == w]
    started = [r for r in rs if r[2] is not None]
    scored = [r[4] for r in rs if r[4] is not None]
    delay = [r[2] for r in started]
    origin = [r[2] - r[3] for r in started]
    back = [r[3] for r in started if r[3] > 0]
    print(f"{w}: {len(rs)} cuts, {len(rs) - len(started)} never started, {len(rs) - len(scored)} "
          f"not scored, {len(back)} went back "
          f"(median {statistics.median(back) if back else 0:.2f} s)")
    print(f"  first estimate after the cut, s: median {statistics.median(delay):.2f}, "
          f"90th percentile {pct(delay, 0.9):.2f}, longest {max(delay):.2f}")
    print(f"  the filter's origin after the cut, s: median {statistics.median(origin):.2f}, "
          f"90th percentile {pct(origin, 0.9):.2f}, longest {max(origin):.2f}; "
          f"over 1 s: {sum(o > 1.0 for o in origin)}")
    print(f"  footprint RMS, % of path ({len(scored)} scored): median {statistics.median(scored):.2f}, "
          f"90th percentile {pct(scored, 0.9):.2f}, worst {max(scored):.2f}")
