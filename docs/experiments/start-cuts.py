#!/usr/bin/env python3
"""How the alignment survives the way a log or a stream may begin: every suite walk cut at
each `STEP` s of its first `SPAN` s (a daemon started at any moment of the rest or of the first
strides), and losses of 0.1–3 s starting 0.3 and 0.4 s into the initial rest (a stream that
drops out before the rest was long enough and comes back during it, or in the walk).

    python3 docs/experiments/start-cuts.py            # from the repository root, ~5 min
    SPAN=5 STEP=0.05 CONFIG=my.toml python3 docs/experiments/start-cuts.py

Each run is scored on the footprints after its first sample, or after the loss (first-leg
alignment, % of path), against the uncut walk, or against the log cut where the loss ends, and by its `health_restores` (the health check threw the filter's
state away: it had started from a state it could not keep). Prints, per kind, the runs that
never aligned, the runs with health restores, the runs worse than the uncut walk by more than
0.3 % of path, and the worst of them. Needs the release binary.
"""
import concurrent.futures, json, os, statistics, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from suite_walks import walks

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
config = os.environ.get("CONFIG", os.path.join(root, "configs/gdins.toml"))
span_s = float(os.environ.get("SPAN", "5"))
step_s = float(os.environ.get("STEP", "0.05"))
tmp = tempfile.mkdtemp(prefix="start-cuts-")


def run(job):
    """One `corridor run` of a log given as rows: (label, footprint RMS or None, health
    restores or None)."""
    label, header, rows, truth_lines, sh = job
    d = tempfile.mkdtemp(dir=tmp)
    imu, truth = os.path.join(d, "imu.csv"), os.path.join(d, "truth.csv")
    open(imu, "w").write("\n".join([header] + rows) + "\n")
    open(truth, "w").write("\n".join(truth_lines) + "\n")
    subprocess.run([binary, "run", "--imu", imu, "--truth", truth, "--config", config,
                    "--start-heading-deg", str(sh), "--out", d], capture_output=True)
    try:
        s = json.load(open(os.path.join(d, "summary.json")))
        rms = s["eval"]["rms_error_pct_of_path"] if s.get("eval") else None
        return label, rms, s["health_restores"]
    except (OSError, KeyError, TypeError, ValueError):
        return label, None, None
    finally:
        subprocess.run(["rm", "-rf", d])


jobs, base = [], {}
for name, imu, truth, sh in walks(root, fast=True):
    lines = open(imu).read().splitlines()
    header, rows = lines[0], lines[1:]
    tl = open(truth).read().splitlines()
    ts = [float(r.split(",", 1)[0]) for r in rows]
    w = name[:5]
    jobs.append(((w, "whole", 0.0), header, rows, tl, sh))
    # The initial rest ends where the gyro first reads more than 1 rad/s.
    g = [sum(float(x) ** 2 for x in r.split(",")[1:4]) ** 0.5 for r in rows]
    t_move = next(ts[i] for i in range(len(ts)) if g[i] > 1.0)
    k = 0
    while k * step_s < span_s:
        t_cut = ts[0] + k * step_s
        i0 = next(i for i, t in enumerate(ts) if t >= t_cut)
        after = [r for r in tl[1:] if float(r.split(",", 1)[0]) > t_cut + 0.05]
        if len(after) >= 4:
            jobs.append(((w, "cut", round(k * step_s, 3)), header, rows[i0:], [tl[0]] + after, sh))
        k += 1
    for start in (0.3, 0.4):
        if ts[0] + start + 0.1 > t_move:
            continue
        i0 = next(i for i, t in enumerate(ts) if t >= ts[0] + start)
        for n in range(1, 31):
            lost = round(n * 0.1, 1)
            i1 = i0 + int(round(lost * 200))
            # Scored on the footprints after the loss, against the log cut where it ends:
            # what the foot did in the loss is lost motion whatever the alignment does.
            after = [r for r in tl[1:] if float(r.split(",", 1)[0]) > ts[i1] + 0.05]
            if len(after) < 4:
                continue
            label = "loss@%.1f" % start
            jobs.append(((w, label, lost), header, rows[:i0] + rows[i1:], [tl[0]] + after, sh))
            jobs.append(((w, label + " cut", lost), header, rows[i1:], [tl[0]] + after, sh))

with concurrent.futures.ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as ex:
    res = list(ex.map(run, jobs))
for (w, kind, x), rms, restores in res:
    if kind == "whole":
        base[w] = rms
    elif kind.endswith(" cut"):
        base[(w, kind[:-4], x)] = rms
out = os.environ.get("OUT")
if out:
    json.dump([[list(l), r, h] for l, r, h in res], open(out, "w"))
for kind in ("cut", "loss@0.3", "loss@0.4"):
    rs = [(l, r, h) for l, r, h in res if l[1] == kind]
    never = [l for l, r, h in rs if r is None]
    restored = [l for l, r, h in rs if h]
    ref = lambda l: base[l[0]] if kind == "cut" else base[tuple(l)]
    d = [(r - ref(l), l) for l, r, h in rs if r is not None and ref(l) is not None]
    worse = [x for x in d if x[0] > 0.3]
    print(f"{kind}: {len(rs)} runs; never scored {len(never)}; with health restores "
          f"{len(restored)}; worse by > 0.3 % of path {len(worse)}"
          + (f", worst {max(worse)[0]:+.2f} ({max(worse)[1][0]} at {max(worse)[1][2]})" if worse else "")
          + (f"; median change {statistics.median(x[0] for x in d):+.3f}" if d else ""))
    per_walk = {}
    for (v, l) in worse:
        per_walk.setdefault(l[0], []).append(l[2])
    for w in sorted(per_walk):
        print(f"  {w}: worse at {per_walk[w]}")
    if never:
        print("  never scored:", [(l[0], l[2]) for l in never][:20])
