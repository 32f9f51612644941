#!/usr/bin/env python3
"""A daemon started while the wearer walks: each suite walk's log cut at the stance end nearest
30, 50 and 70 % of its footprints' time (its first sample a swing's), scored on the footprints
after the cut (places with fewer than 4 left out), the start heading the first surveyed stride
of at least 0.5 m after the cut turned to the building's grid (as the suite chooses every start
heading). Prints, per cut, how long after the cut the filter started (its first sample not
"aligning") and the footprint RMS, % of path; "None" where the evaluation failed (the filter
started after the first legs the footprints are aligned on; its start then from a run without
them) or the filter never started; and how far a start in fast gait went back
(`alignment.fast_gait_replay_s`: the filter then started on an earlier stance, and ran over the
samples since). Needs the release binary.

    python3 docs/experiments/mid-walk-starts.py                      # from the repository root
    CONFIG=my.toml python3 docs/experiments/mid-walk-starts.py
"""
import csv, json, math, os, statistics, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from suite_walks import footprint_rms, walks
root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
config = os.environ.get("CONFIG", os.path.join(root, "configs/gdins.toml"))
tmp = tempfile.mkdtemp(prefix="midwalk-")
res = []
for name, imu, truth, sh in walks(root, fast=True):
    lines = open(imu).read().splitlines(); header, rows = lines[0], lines[1:]
    ts = [float(r.split(",", 1)[0]) for r in rows]
    out = os.path.join(tmp, "base")
    footprint_rms(binary, config, imu, truth, sh, out)
    est = list(csv.DictReader(open(os.path.join(out, "estimates.csv"))))
    ends = [float(est[i]["t_s"]) for i in range(1, len(est)) if est[i-1]["stance"] == "1" and est[i]["stance"] == "0"]
    tl = open(truth).read().splitlines()
    tp = [(float(r.split(",")[0]), float(r.split(",")[1]), float(r.split(",")[2])) for r in tl[1:]]
    for pos in (0.3, 0.5, 0.7):
        t_target = tp[0][0] + pos * (tp[-1][0] - tp[0][0])
        t_cut = min(ends, key=lambda e: abs(e - t_target))
        i0 = next(i for i, t in enumerate(ts) if t >= t_cut)
        after = [p for p in tp if p[0] > t_cut + 0.05]
        if len(after) < 4: continue
        # start heading: first stride >= 0.5 m, grid 90 deg
        p0 = after[0]; q = next((p for p in after[1:] if math.hypot(p[1]-p0[1], p[2]-p0[2]) >= 0.5), None)
        if q is None: continue
        hd = math.degrees(math.atan2(q[2]-p0[2], q[1]-p0[1])); hd = round(hd / 90) * 90
        cut = os.path.join(tmp, "cut.csv"); open(cut, "w").write("\n".join([header] + rows[i0:]) + "\n")
        ct = os.path.join(tmp, "truth.csv"); open(ct, "w").write("\n".join([tl[0]] + [r for r in tl[1:] if float(r.split(",")[0]) > t_cut + 0.05]) + "\n")
        o = os.path.join(tmp, "cutout%s%s" % (name[:5], pos))
        v = footprint_rms(binary, config, cut, ct, hd, o)
        if v is None:
            # A run whose evaluation failed writes no estimates: when it started, without it.
            subprocess.run([binary, "run", "--imu", cut, "--config", config,
                            "--start-heading-deg", str(hd), "--out", o], capture_output=True)
        try:
            e2 = list(csv.DictReader(open(os.path.join(o, "estimates.csv"))))
            t_al = next((float(e["t_s"]) for e in e2 if e["phase"] != "aligning"), None)
        except OSError:
            t_al = None
        try:
            back_s = json.load(open(os.path.join(o, "summary.json"))).get("start_replayed_ms", 0) / 1e3
        except OSError:
            back_s = 0
        res.append((name[:5], pos, v, (t_al - t_cut) if t_al else None))
        print(name[:5], pos, "started after", None if t_al is None else round(t_al - t_cut, 2),
              "s" + (f" (went back {back_s:.2f} s)" if back_s else "") + ";",
              None if v is None else round(v, 2), "%", flush=True)
print("not scored (started too late or never):", [(r[0], r[1]) for r in res if r[2] is None])
d = [r[2] for r in res if r[2] is not None]
started = [r[3] for r in res if r[3] is not None]
print(f"{len(d)} of {len(res)} cuts scored: median {statistics.median(d):.2f} %, worst "
      f"{max(d):.2f} %; started after a median {statistics.median(started):.2f} s, at most "
      f"{max(started):.2f} s")
