#!/usr/bin/env python3
"""The peaks a gyro rail cuts off, put back (`eskf.restore_clipped_peaks`, `rail_peaks.rs`).

Two checks, neither fitted to footprints:

1. The parabola on peaks the rail did not cut (no footprints): the 16 gdins walks' rates clipped
   at lower rails (7, 5, 4 rad/s by default), each run of samples at the rail reconstructed as the
   estimator does it (least squares through the two samples before and the two after, at most
   half the rail above it), against the rates that were recorded there. (The runs here are the
   samples at the rail itself; the estimator takes every sample within 2 % of its configured
   range, which the suite below sets to rail / 0.99, so samples from 0.99 × the rail on.) Prints, per rail, the
   runs, the RMS of a run's lost rotation without and with the reconstruction, the share of the
   lost rotation put back, and the rate's error per clipped sample (what `eskf.
   clipped_rate_sd_rad_s` stands for).
   And near the top of the peaks, where the sensor's own rail lies (`TOP_RAILS`, default 8 and
   7.5 rad/s): the runs chosen on their parabola, not on the truth (see `check_near_top`).
2. The suite on the clipped walks: the same walks clipped at `RAILS` (default 6, 5 and 4 rad/s;
   the configuration's `sensor.gyro_range_rad_s` set to rail / 0.99, so that the rail is flagged),
   run by `corridor eval` with the peaks put back and not, footprint RMS per walk and the
   normal-gait median, mean and worst. The walks as recorded too (rail "none").

    python3 docs/experiments/rail-peaks.py                       # from the repository root
    CHECK=0 RAILS=none,5 python3 docs/experiments/rail-peaks.py  # the suite part only

Needs the release binary (`cargo build --release -p corridor-service --bin corridor`; `BIN` to
use another) and numpy; writes its copies under `OUT` (default /tmp/rail-peaks).
"""
import glob, json, os, re, shutil, statistics, subprocess, sys
import numpy as np

root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
out_root = os.environ.get("OUT", "/tmp/rail-peaks")
RANGE = 8.727  # configs/gdins.toml sensor.gyro_range_rad_s
CLIP_FRACTION = 0.98  # shared/src/sensor.rs
MAX_EXCESS_OF_RAIL = 0.5  # rail_peaks.rs
walks = sorted(glob.glob(os.path.join(root, "tests/data/gdins_*")))


def load(d):
    return np.loadtxt(os.path.join(d, "imu.csv"), delimiter=",", skiprows=1)


def runs(x, rail):
    """Runs (start, end) of samples at the rail, same sign, on one axis."""
    at = np.abs(x) >= rail
    i, n = 0, len(x)
    while i < n:
        if not at[i]:
            i += 1
            continue
        j = i
        while j < n and at[j] and np.sign(x[j]) == np.sign(x[i]):
            j += 1
        yield i, j
        i = j


def put_back(t, x, i, j, rail):
    """The rates of run i..j put back (None without two samples off the rail either side)."""
    if i < 2 or j + 2 > len(x):
        return None
    around = np.r_[i - 2:i, j:j + 2]
    if (np.abs(x[around]) >= rail).any():
        return None
    s = np.sign(x[i])
    p = np.polyfit(t[around] - t[i], x[around], 2)
    fit = np.polyval(p, t[i:j] - t[i])
    return x[i:j] + s * np.clip(s * (fit - x[i:j]), 0.0, MAX_EXCESS_OF_RAIL * rail)


def check(rails):
    data = [load(d) for d in walks]
    for rail in rails:
        lost, left, put, err_plain, err_put = [], [], [], [], []
        for a in data:
            t, w = a[:, 0], a[:, 1:4]
            dt = np.diff(t, prepend=t[0] - 0.005)
            for ax in range(3):
                x = np.clip(w[:, ax], -rail, rail)
                # Peaks the sensor's own rail cut are not the truth: left out.
                real = np.abs(w[:, ax]) >= CLIP_FRACTION * RANGE
                for i, j in runs(x, rail):
                    if real[i:j].any():
                        continue
                    r = put_back(t, x, i, j, rail)
                    if r is None:
                        continue
                    s = np.sign(x[i])
                    truth = w[i:j, ax]
                    lost.append(np.sum(s * (truth - x[i:j]) * dt[i:j]))
                    left.append(np.sum(s * (truth - r) * dt[i:j]))
                    put.append(np.sum(s * (r - x[i:j]) * dt[i:j]))
                    err_plain += list(truth - x[i:j])
                    err_put += list(truth - r)
        lost, left = np.array(lost), np.array(left)
        rms = lambda v: float(np.sqrt(np.mean(np.square(v))))
        print(f"rail {rail} rad/s: {len(lost)} runs, {len(err_plain)} samples; a run's lost rotation "
              f"RMS {rms(lost) * 1e3:.0f} mrad, after putting back {rms(left) * 1e3:.0f} mrad; put back "
              f"{sum(put) / lost.sum() * 100:.0f} % of the {lost.sum():.1f} rad lost; the rate's error per "
              f"sample RMS {rms(err_plain):.2f} -> {rms(err_put):.2f} rad/s")


def check_near_top(rails, fit_top_max):
    """The parabola near the top of the peaks, where the sensor's own rail lies (session 48).

    As the estimator flags them: runs of samples from 0.98 x the rail on (the flag of a range at
    the rail), the parabola through the two samples before and the two after each. At a rail
    just under the sensor's own flag (8.55 rad/s) the runs whose recorded rates stay under that
    flag are the peaks that happened to top out low: choosing the runs on the truth drops those
    that went higher than their parabola, and the parabola looks worse than it is. Chosen on the
    parabola instead (its top under `fit_top_max`, which the estimator knows too), and their
    truth under the flag (else there is none), per rail: the runs, a run's lost rotation RMS
    without and with the reconstruction; then the same chosen on the truth."""
    data = [load(d) for d in walks]
    sensor_flag = CLIP_FRACTION * RANGE
    rms = lambda v: float(np.sqrt(np.mean(np.square(v)))) * 1e3
    for rail in rails:
        flag = CLIP_FRACTION * rail
        on_fit, on_truth = [], []
        for a in data:
            t, w = a[:, 0], a[:, 1:4]
            dt = np.diff(t, prepend=t[0] - 0.005)
            for ax in range(3):
                x = np.clip(w[:, ax], -rail, rail)
                for i, j in runs(x, flag):
                    around = np.r_[i - 2:i, j:j + 2]
                    if i < 2 or j + 2 > len(x) or (np.abs(x[around]) >= flag).any():
                        continue
                    s = np.sign(x[i])
                    fit = np.polyval(np.polyfit(t[around] - t[i], x[around], 2), t[i:j] - t[i])
                    r = x[i:j] + s * np.clip(s * (fit - x[i:j]), 0.0, MAX_EXCESS_OF_RAIL * rail)
                    truth = w[i:j, ax]
                    pair = (np.sum(s * (truth - x[i:j]) * dt[i:j]), np.sum(s * (truth - r) * dt[i:j]))
                    if (np.abs(w[i - 2:j + 2, ax]) < sensor_flag).all():
                        on_truth.append(pair)
                    if np.max(s * fit) < fit_top_max and (np.abs(truth) < sensor_flag).all():
                        on_fit.append(pair)
        for label, v in (("chosen on the parabola", on_fit), ("chosen on the truth", on_truth)):
            v = np.array(v)
            print(f"rail {rail} rad/s (flag {flag:.2f}), {label}: {len(v)} runs; a run's lost "
                  f"rotation RMS {rms(v[:, 0]):.2f} mrad, after putting back {rms(v[:, 1]):.2f} mrad")


def clipped_suite(rail):
    """A copy of the suite whose walks are clipped at `rail` ("none": as recorded)."""
    d = os.path.join(out_root, f"rail-{rail}")
    if os.path.exists(d):
        shutil.rmtree(d)
    os.makedirs(d)
    cfg = open(os.path.join(root, "configs/gdins.toml")).read()
    if rail != "none":
        cfg = re.sub(r"\ngyro_range_rad_s = [0-9.]+", f"\ngyro_range_rad_s = {float(rail) / 0.99:.4f}", cfg)
    for restore in ("true", "false"):
        c = re.sub(r"\nrestore_clipped_peaks = \w+", f"\nrestore_clipped_peaks = {restore}", cfg)
        open(os.path.join(d, f"gdins_{restore}.toml"), "w").write(c)
    shutil.copy(os.path.join(root, "configs/gdins_zupt_baseline.toml"), d)
    for w in walks:
        name = os.path.basename(w)
        os.makedirs(os.path.join(d, name))
        shutil.copy(os.path.join(w, "ground_truth.csv"), os.path.join(d, name))
        if rail == "none":
            shutil.copy(os.path.join(w, "imu.csv"), os.path.join(d, name))
            continue
        lines = open(os.path.join(w, "imu.csv")).read().splitlines()
        with open(os.path.join(d, name, "imu.csv"), "w") as f:
            f.write(lines[0] + "\n")
            for line in lines[1:]:
                v = line.split(",")
                for k in (1, 2, 3):
                    g = float(v[k])
                    if abs(g) > float(rail):
                        v[k] = repr(float(rail) if g > 0 else -float(rail))
                f.write(",".join(v) + "\n")
    suite = open(os.path.join(root, "configs/eval/gdins.toml")).read().replace("../../tests/data/", "")
    suite = suite.replace('"../gdins_zupt_baseline.toml"', '"gdins_zupt_baseline.toml"')
    figures = {}
    for restore in ("true", "false"):
        s = suite.replace('"../gdins.toml"', f'"gdins_{restore}.toml"')
        path = os.path.join(d, f"suite_{restore}.toml")
        open(path, "w").write(s)
        res = os.path.join(d, f"out_{restore}")
        subprocess.run([binary, "eval", "--suite", path, "--out", res], check=True,
                       stdout=subprocess.DEVNULL)
        rows = json.load(open(os.path.join(res, "results.json")))
        figures[restore] = {r["recording"]: (r["gait"], r["best_rest"]["rms_pct"]) for r in rows}
    return figures


def suite(rails):
    for rail in rails:
        f = clipped_suite(rail)
        print(f"\nrail {rail}: footprint RMS, % of path, peaks not put back -> put back")
        normal = {"false": [], "true": []}
        for name, (gait, on) in f["true"].items():
            off = f["false"][name][1]
            print(f"  {name:34s} {gait:6s} {off:7.3f} -> {on:7.3f}")
            if gait == "normal":
                normal["false"].append(off)
                normal["true"].append(on)
        for k, label in (("false", "not put back"), ("true", "put back")):
            v = normal[k]
            print(f"  normal gait, {label}: median {statistics.median(v):.3f}, mean "
                  f"{statistics.mean(v):.3f}, worst {max(v):.3f}")


if __name__ == "__main__":
    if os.environ.get("CHECK", "1") != "0":
        check([float(r) for r in os.environ.get("CHECK_RAILS", "7,5,4").split(",")])
        check_near_top([float(r) for r in os.environ.get("TOP_RAILS", "8,7.5").split(",")],
                       float(os.environ.get("FIT_TOP_MAX", "8.3")))
    suite(os.environ.get("RAILS", "none,6,5,4").split(","))
