#!/usr/bin/env python3
"""How much of each walk's first-leg figure is its first stride: the start heading anchors the
first stride the filter sees to the corridor the walk starts in (`heading.start_heading_sd_deg`),
but the surveyed first stride may run a few degrees off it. For every recording of the suite
(fast ones too): the surveyed first stride's direction against the start heading, the heading
error of the default run over the first stride and over the first leg (to the first footprint at
least 5 m away, the leg the first-leg alignment turns the run by), and the footprint RMS, % of
path, first-leg and in the map frame (translated onto the first footprint, not turned). The
"first stride" is the first surveyed leg of at least 0.5 m: a stride only on the walks surveyed
at every stride (exp31 on), the first corridor's whole leg on those surveyed at their corners.
No parameter is chosen from this. Needs the release binary (BIN= to use another).

    python3 docs/experiments/first-stride.py        # from the repository root
"""
import bisect, csv, json, math, os, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from suite_walks import walks

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
config = os.path.join(root, "configs/gdins.toml")
tmp = tempfile.mkdtemp(prefix="first-stride-")


def wrap(deg):
    return (deg + 180.0) % 360.0 - 180.0


def direction(a, b):
    return math.degrees(math.atan2(b[1] - a[1], b[0] - a[0]))


def map_frame_rms(est, truth, path_m):
    """Footprint RMS, % of path, of the run translated onto the first footprint, not turned."""
    p0, g0 = est[0], truth[0]
    sq = [(p[0] - p0[0] + g0[0] - g[0]) ** 2 + (p[1] - p0[1] + g0[1] - g[1]) ** 2
          for p, g in zip(est[1:], truth[1:])]
    return 100.0 * math.sqrt(sum(sq) / len(sq)) / path_m


print("| recording | surveyed first stride − start heading | estimate − survey: first stride | "
      "first leg | footprint RMS first-leg / map frame |")
print("|---|---|---|---|---|")
for name, imu, truth_csv, sh in walks(root, fast=True):
    out = os.path.join(tmp, "out")
    subprocess.run([binary, "run", "--imu", imu, "--truth", truth_csv, "--config", config,
                    "--start-heading-deg", str(sh), "--out", out], capture_output=True, check=True)
    ev = json.load(open(os.path.join(out, "summary.json")))["eval"]
    ts, xy = [], []
    for r in csv.DictReader(open(os.path.join(out, "estimates.csv"))):
        ts.append(float(r["t_s"]))
        xy.append((float(r["x_m"]), float(r["y_m"])))
    gt = [(float(r["t_s"]), float(r["x_m"]), float(r["y_m"])) for r in csv.DictReader(open(truth_csv))]
    truth = [(x, y) for _, x, y in gt]
    est = [xy[min(bisect.bisect_left(ts, t), len(ts) - 1)] for t, _, _ in gt]
    first = next(i for i in range(1, len(truth)) if math.dist(truth[i], truth[0]) >= 0.5)
    leg = next(i for i in range(1, len(truth)) if math.dist(truth[i], truth[0]) >= 5.0)
    stride_off = wrap(direction(truth[0], truth[first]) - sh)
    err_stride = wrap(direction(est[0], est[first]) - direction(truth[0], truth[first]))
    err_leg = wrap(direction(est[0], est[leg]) - direction(truth[0], truth[leg]))
    print(f"| {name} | {stride_off:+.1f}° | {err_stride:+.1f}° | {err_leg:+.1f}° | "
          f"{ev['rms_error_pct_of_path']:.2f} / "
          f"{map_frame_rms(est, truth, ev['truth_path_length_m']):.2f} % |")
