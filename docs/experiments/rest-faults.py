#!/usr/bin/env python3
"""Losses and stalls in the initial rest: the footprint RMS (% of path) of each suite walk with
`LEN` seconds lost (samples removed) or stalled (the samples kept, every stamp after the place
`LEN` later: a stream that paused, the footprints' times moved with them) at 30, 60 and 85 % of its initial rest, against the walk
without the fault.

    python3 docs/experiments/rest-faults.py 0.1,0.2,0.3      # from the repository root
    python3 docs/experiments/rest-faults.py 0.1,0.2,0.3 0.5,0.55,0.6,0.7

With a second list, also each walk with only its last `KEPT` seconds of initial rest (a short
rest, nothing lost after it); with a third, a loss and a stall of that length (s) in the middle of
each such short rest as well.

The initial rest is the uncut run's alignment phase (`estimates.csv`). Prints one line per run,
then per kind and length the median and worst change and how many runs are worse by more than
0.3 % of path. Needs the release binary (`cargo build --release -p corridor-service --bin
corridor`).
"""
import csv, os, statistics, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from suite_walks import footprint_rms, stamp, walks

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
config = os.environ.get("CONFIG", os.path.join(root, "configs/gdins.toml"))
tmp = tempfile.mkdtemp(prefix="rest-faults-")


def run(imu, truth, sh, out=os.path.join(tmp, "out")):
    return footprint_rms(binary, config, imu, truth, sh, out)


def damaged(header, rows, i, length_s, kind, truth):
    """`rows` with `length_s` lost (`kind` "loss": the samples removed) or stalled ("stall":
    every stamp from row `i` on `length_s` later, and the footprints' with them, since they are
    matched by time) at row `i`, written out: (IMU CSV, truth CSV)."""
    imu, cut_truth = os.path.join(tmp, "cut.csv"), truth
    if kind == "loss":
        out = rows[:i] + rows[i + int(round(length_s * 200)):]
    else:
        out = rows[:i] + [stamp(r, length_s) for r in rows[i:]]
        t_cut = float(rows[i].split(",", 1)[0])
        lines = open(truth).read().splitlines()
        cut_truth = os.path.join(tmp, "truth.csv")
        open(cut_truth, "w").write("\n".join(
            [lines[0]] + [stamp(r, length_s) if float(r.split(",", 1)[0]) >= t_cut else r
                          for r in lines[1:]]) + "\n")
    open(imu, "w").write("\n".join([header] + out) + "\n")
    return imu, cut_truth


lengths = [float(x) for x in sys.argv[1].split(",")]
kept = [float(x) for x in sys.argv[2].split(",")] if len(sys.argv) > 2 else []
mid_fault_s = float(sys.argv[3]) if len(sys.argv) > 3 else None
res = []
for name, imu, truth, sh in walks(root, fast=True):
    lines = open(imu).read().splitlines()
    header, rows = lines[0], lines[1:]
    base = run(imu, truth, sh)
    est = list(csv.DictReader(open(os.path.join(tmp, "out", "estimates.csv"))))
    t0 = float(rows[0].split(",", 1)[0])
    t_end = next(float(e["t_s"]) for e in est if e["phase"] != "aligning")
    ts = [float(r.split(",", 1)[0]) for r in rows]
    for length in kept:
        i0 = min(range(len(ts)), key=lambda i: abs(ts[i] - (t_end - length)))
        cut = os.path.join(tmp, "cut.csv")
        open(cut, "w").write("\n".join([header] + rows[i0:]) + "\n")
        v = run(cut, truth, sh)
        res.append(("short", length, base, v))
        print(name[:5], "short", length, "-", f"rest {t_end - t0:.2f} s", f"{base:.2f}",
              "—" if v is None else f"{v:.2f}", flush=True)
        if mid_fault_s is None:
            continue
        short = rows[i0:]
        im = min(range(len(ts)), key=lambda i: abs(ts[i] - (t_end - length / 2))) - i0
        for kind in ("short+loss", "short+stall"):
            v = run(*damaged(header, short, im, mid_fault_s, kind.split("+")[1], truth), sh)
            res.append((kind, length, base, v))
            print(name[:5], kind, length, "-", f"rest {t_end - t0:.2f} s", f"{base:.2f}",
                  "—" if v is None else f"{v:.2f}", flush=True)
    for length in lengths:
        for pos in (0.3, 0.6, 0.85):
            i0 = min(range(len(ts)), key=lambda i: abs(ts[i] - (t0 + pos * (t_end - t0))))
            for kind in ("loss", "stall"):
                v = run(*damaged(header, rows, i0, length, kind, truth), sh)
                res.append((kind, length, base, v))
                print(name[:5], kind, length, pos, f"rest {t_end - t0:.2f} s", f"{base:.2f}",
                      "—" if v is None else f"{v:.2f}", flush=True)
for kind in ("loss", "stall", "short", "short+loss", "short+stall"):
    for length in kept if kind.startswith("short") else lengths:
        d = [v - b for (K, L, b, v) in res if K == kind and L == length and v is not None]
        if not d:
            continue
        failed = sum(v is None for (K, L, b, v) in res if K == kind and L == length)
        print(f"{kind} {length} s: median {statistics.median(d):+.3f}, worst {max(d):+.2f} % of "
              f"path; {sum(x > 0.3 for x in d)} of {len(d)} worse by more than 0.3"
              f"{f'; {failed} failed' if failed else ''}")
d = [v - b for (K, L, b, v) in res if v is not None]
print(f"all: {sum(x > 0.3 for x in d)} of {len(d)} worse by more than 0.3, worst {max(d):+.2f}")
