#!/usr/bin/env python3
"""The Allan deviation of the gyro and the accelerometer where the foot stands still, as issue 8
asks of the noise figures ("derived from data without ground truth: Allan variance or the NIS").
For every recording of the suite (fast ones too) the default run's stance flags (`estimates.csv`)
give the still samples: the *rests* are the stances of at least 1 s, each trimmed by 0.1 s at both
ends (the foot landing and leaving); the *stances* are all stances of at least 0.1 s, trimmed by
25 ms. Gapped data: the overlapping Allan variance is pooled over the segments (the differences
of adjacent cluster means inside each segment, none across a gap). Printed per τ: the median over
the walks of each axis's Allan deviation, and σ(τ)·√τ, which is flat where white noise dominates
(the noise density, rad/s/√Hz or m/s²/√Hz) and grows where motion does.

What it shows (session 51): nowhere flat. On the rests σ(τ)·√τ grows 2.2–2.7 times per doubling of
τ from 5 to 40 ms on the gyro, 1.6–2.1 on the accelerometer (σ(τ) about ∝ τ: a smooth signal, the
standing foot's sway), the deviation
peaks near 0.1 s and falls beyond; the stances the same, larger. So the white noise of the sensor
lies under the motion at every τ these walks hold, and only its upper bound is measured: σ(5 ms)·√5 ms.
No parameter is chosen from this. Needs numpy and the release binary (BIN= to use another).

    python3 docs/experiments/allan-rests.py        # from the repository root
"""
import csv, os, subprocess, sys, tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from suite_walks import walks

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
config = os.path.join(root, "configs/gdins.toml")
tmp = tempfile.mkdtemp(prefix="allan-rests-")
CLUSTERS = [1, 2, 4, 8, 16, 32, 64, 128]
AXES = ["gyro x", "gyro y", "gyro z", "accel x", "accel y", "accel z"]


def segments(stance, dt, min_s, trim_s):
    """(first, end) sample indices of the stances of at least `min_s`, trimmed by `trim_s`."""
    out, start = [], None
    for i, s in enumerate(list(stance) + [False]):
        if s and start is None:
            start = i
        elif not s and start is not None:
            if (i - start) * dt >= min_s:
                k = int(round(trim_s / dt))
                if i - k - (start + k) >= 2:
                    out.append((start + k, i - k))
            start = None
    return out


def pooled_avar(x, segs, m):
    """Overlapping Allan variance at cluster size `m`, pooled over the segments; NaN if none holds
    two clusters."""
    total, count = 0.0, 0
    for a, b in segs:
        y = x[a:b]
        if len(y) < 2 * m:
            continue
        c = np.concatenate([[0.0], np.cumsum(y)])
        means = (c[m:] - c[:-m]) / m
        d = means[m:] - means[:-m]
        total += float(np.sum(d * d))
        count += len(d)
    return total / (2 * count) if count else float("nan")


results = {"rests": [], "stances": []}
for name, imu, truth_csv, sh in walks(root, fast=True):
    out = os.path.join(tmp, "out")
    subprocess.run([binary, "run", "--imu", imu, "--config", config, "--out", out],
                   capture_output=True, check=True)
    stance = np.array([r["stance"] == "1" for r in csv.DictReader(open(os.path.join(out, "estimates.csv")))])
    data = np.loadtxt(imu, delimiter=",", skiprows=1, usecols=range(7))
    n = min(len(stance), len(data))
    stance, data = stance[:n], data[:n]
    dt = float(np.median(np.diff(data[:, 0])))
    for kind, min_s, trim_s in (("rests", 1.0, 0.1), ("stances", 0.1, 0.025)):
        segs = segments(stance, dt, min_s, trim_s)
        seconds = sum(b - a for a, b in segs) * dt
        adev = [[np.sqrt(pooled_avar(data[:, 1 + ax], segs, m)) for ax in range(6)] for m in CLUSTERS]
        results[kind].append((name, dt, seconds, np.array(adev)))

for kind, rows in results.items():
    rows = [r for r in rows if r[2] > 0]
    dt = rows[0][1]
    print(f"\n{kind}: {len(rows)} walks, {sum(r[2] for r in rows):.1f} s in all "
          f"({min(r[2] for r in rows):.1f}-{max(r[2] for r in rows):.1f} s a walk); "
          "median over the walks, Allan deviation (rad/s, m/s²) and σ(τ)·√τ (/√Hz)\n")
    print("| τ, s | " + " | ".join(AXES) + " | " + " | ".join(a + " ·√τ" for a in AXES) + " |")
    print("|---" * (1 + 2 * len(AXES)) + "|")
    stack = np.array([r[3] for r in rows])  # walk × τ × axis
    for j, m in enumerate(CLUSTERS):
        med = np.nanmedian(stack[:, j, :], axis=0)
        tau = m * dt
        print(f"| {tau:.3f} | " + " | ".join(f"{v:.1e}" for v in med) + " | "
              + " | ".join(f"{v * np.sqrt(tau):.1e}" for v in med) + " |")
    first = np.nanmedian(stack[:, 0, :], axis=0) * np.sqrt(dt)
    print(f"\nUpper bound of the white-noise density (σ at one sample × √dt, median): gyro "
          + " / ".join(f"{v:.1e}" for v in first[:3]) + " rad/s/√Hz, accel "
          + " / ".join(f"{v:.1e}" for v in first[3:]) + " m/s²/√Hz")
