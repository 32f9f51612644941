#!/usr/bin/env python3
"""How well the stride before stands in for samples lost in a gap: rates alone, no footprints.

    python3 docs/experiments/stride-template.py 0.2      # from the repository root; needs numpy

For each of the 16 gdins walks, 40 pseudo-random places between 20 and 90 % of the log: LEN
seconds of samples are taken as lost. The stride lag is found as the estimator finds it
(`service/src/core/estimator/stride_memory.rs`): within ±20 % of the last stride period (here
from a plain |ω| < 0.6 rad/s footfall list), the lag whose remembered rates best match the 30
rates before the gap and the one after it (RMS difference: the "mismatch"). Prints, per mismatch
band, on how many cuts the remembered stride's rotation over the gap is closer to the real one
than the real one is to no rotation at all (what a new segment loses), and the median of both
angles; and the median error relative to the rotation. The estimator's refusal above 2.5 rad/s
and the σ of a fifth of the filled rotation (`FILL_MAX_MISMATCH_RAD_S`, `FILL_RELATIVE_SD` in
`service/src/core/estimator/gaps.rs`) come from this table.
"""
import glob, os, random, sys

import numpy as np


def expq(v):
    a = np.linalg.norm(v)
    if a < 1e-12:
        return np.array([1.0, 0, 0, 0])
    return np.concatenate([[np.cos(a / 2)], np.sin(a / 2) * v / a])


def qmul(p, q):
    w1, x1, y1, z1 = p
    w2, x2, y2, z2 = q
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def rotation(ws, dts):
    q = np.array([1.0, 0, 0, 0])
    for w, dt in zip(ws, dts):
        q = qmul(q, expq(w * dt))
    return q


def angle(q):
    return 2 * np.arccos(min(1.0, abs(q[0])))


length = float(sys.argv[1])
rows = []
for d in sorted(glob.glob(os.path.join("tests", "data", "gdins_exp*"))):
    imu = np.loadtxt(os.path.join(d, "imu.csv"), delimiter=",", skiprows=1, usecols=range(7))
    t, w = imu[:, 0], imu[:, 1:4]
    n = len(t)
    still = np.linalg.norm(w, axis=1) < 0.6
    falls, i = [], 0
    while i < n:
        if still[i]:
            j = i
            while j < n and still[j]:
                j += 1
            if t[j - 1] - t[i] >= 0.08:
                falls.append(i)
            i = j
        else:
            i += 1
    random.seed(d)
    for _ in range(40):
        i0 = random.randint(int(0.2 * n), int(0.9 * n))
        i1 = i0 + int(round(length * 200))
        before = [f for f in falls if f < i0]
        if len(before) < 3:
            continue
        period = t[before[-1]] - t[before[-2]]
        if not 0.6 < period < 2.0:
            continue
        best = None
        for lag in range(int(0.8 * period * 200), int(1.2 * period * 200) + 1):
            if i0 - 30 - lag < 0:
                continue
            cost = (np.sum((w[i0 - 30:i0] - w[i0 - 30 - lag:i0 - lag]) ** 2)
                    + np.sum((w[i1] - w[i1 - lag]) ** 2)) / 31
            if best is None or cost < best[0]:
                best = (cost, lag)
        if best is None:
            continue
        lag = best[1]
        dts = np.diff(t[i0:i1 + 1])
        real = rotation(w[i0:i1], dts)
        remembered = rotation(w[i0 - lag:i1 - lag], dts)
        inverse = np.array([real[0], -real[1], -real[2], -real[3]])
        rows.append((angle(real), angle(qmul(inverse, remembered)), np.sqrt(best[0])))

r = np.array(rows)
print(f"{length} s lost, {len(r)} cuts: rotation over the gap median {np.median(r[:, 0]):.3f} rad; "
      f"the stride before off by median {np.median(r[:, 1]):.3f} rad, "
      f"{np.median(r[:, 1] / np.maximum(r[:, 0], 1e-3)):.2f} of the rotation")
for lo, hi in [(0, 0.5), (0.5, 1), (1, 1.5), (1.5, 2), (2, 2.5), (2.5, 3.5), (3.5, 1e9)]:
    sel = r[(r[:, 2] >= lo) & (r[:, 2] < hi)]
    if len(sel):
        print(f"mismatch [{lo}, {hi if hi < 1e9 else 'inf'}) rad/s: {len(sel)} cuts, closer than no rotation "
              f"on {int(np.sum(sel[:, 1] < sel[:, 0]))}; off by median {np.median(sel[:, 1]):.3f} rad, "
              f"rotation median {np.median(sel[:, 0]):.3f} rad")
