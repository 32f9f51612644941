#!/usr/bin/env python3
"""Gaps cut out of the suite's normal-gait walks: the footprint RMS (% of path) of each walk with
`LEN` seconds of samples removed at three places (30, 50 and 70 % of the log, plus a fixed
pseudo-random offset of up to 1 s), against the same walk without the cut.

    python3 docs/experiments/gap-cuts.py 0.055,0.1,0.2,0.3      # from the repository root
    CONFIG=configs/gdins_segment.toml python3 docs/experiments/gap-cuts.py 0.055
    TOE_OFF=-0.3,-0.1,0,0.1,0.2 python3 docs/experiments/gap-cuts.py 0.3

With `TOE_OFF`, the cuts are made at the worst phase of a stride instead: starting each given
offset (s) after the end of a stance, as the detector places it in the uncut run, at the stance
ends nearest 30, 50 and 70 % of the log. The places above do not depend on the gait, so most of
their cuts fall in a stance or late in a swing and cost little; these take the toe-off or the
swing after it. The summary is then per offset.

The samples, not only the time, are removed: the motion in the gap is lost. Prints one line per
cut, then per length the median and worst change and how many cuts are worse by more than 0.1 %
of path. The figures of `estimator.max_bridge_s` and `estimator.max_fill_s` in
`configs/gdins.toml` came from this script (with `max_fill_s = 0`, and `max_bridge_s = 0` for the
bridge's figures, in a copy of the config for the "new segment" column). Needs the
release binary (`cargo build --release -p corridor-service --bin corridor`).
"""
import csv, os, random, statistics, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from suite_walks import footprint_rms, walks

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
config = os.environ.get("CONFIG", os.path.join(root, "configs/gdins.toml"))
recs = walks(root)

tmp = tempfile.mkdtemp(prefix="gap-cuts-")


def rms_pct(imu, truth, sh, out=os.path.join(tmp, "out")):
    return footprint_rms(binary, config, imu, truth, sh, out)


lengths = [float(x) for x in sys.argv[1].split(",")]
toe_off = [float(x) for x in os.environ["TOE_OFF"].split(",")] if "TOE_OFF" in os.environ else None
res = []
for name, imu, truth, sh in recs:
    lines = open(imu).read().splitlines()
    header, rows = lines[0], lines[1:]
    base = rms_pct(imu, truth, sh)
    if toe_off:
        ts = [float(r.split(",", 1)[0]) for r in rows]
        est = list(csv.DictReader(open(os.path.join(tmp, "out", "estimates.csv"))))
        ends = [float(est[i]["t_s"]) for i in range(1, len(est))
                if est[i - 1]["stance"] == "1" and est[i]["stance"] == "0"]
    places = [(pos, off) for pos in (0.3, 0.5, 0.7) for off in (toe_off or [None])]
    for length in lengths:
        k = int(round(length * 200))
        for pos, off in places:
            if off is None:
                random.seed(f"{name}/{pos}")
                i0 = int(len(rows) * pos) + random.randint(0, 200)
            else:
                t_end = min(ends, key=lambda e: abs(e - (ts[0] + pos * (ts[-1] - ts[0]))))
                i0 = min(range(len(ts)), key=lambda i: abs(ts[i] - (t_end + off)))
            cut = os.path.join(tmp, "cut.csv")
            open(cut, "w").write("\n".join([header] + rows[:i0] + rows[i0 + k:]) + "\n")
            v = rms_pct(cut, truth, sh)
            res.append((length, off, base, v))
            at = pos if off is None else f"{pos} {off:+.2f}"
            print(name[:5], length, at, f"{base:.2f}", "—" if v is None else f"{v:.2f}", flush=True)
for length in lengths:
    for off in toe_off or [None]:
        d = [v - b for (L, o, b, v) in res if L == length and o == off and v is not None]
        at = "" if off is None else f" from {off:+.2f} s after a stance's end"
        print(f"gap {length} s{at}: median {statistics.median(d):+.2f}, worst {max(d):+.2f} % of "
              f"path; {sum(x > 0.1 for x in d)} of {len(d)} cuts worse by more than 0.1 "
              f"(by more than 1: {sum(x > 1 for x in d)}, 3: {sum(x > 3 for x in d)}; "
              f"mean {statistics.mean(d):+.2f})")
