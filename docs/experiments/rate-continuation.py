#!/usr/bin/env python3
"""How often a real loss of samples looks like a clock step to a test of the rate's continuation
alone, and what that would cost: at every 7th sample of the 16 gdins walks (from the 400th on),
the first rate after a loss of `LEN` s is compared with the straight continuation of the last two
rates before it, within the tolerance `gaps.rs` uses (1.5 times the larger of the last step's
change of the rate and the RMS second difference of the last 30, at least 0.05 rad/s). Prints per
length how many clock steps (the next sample itself) pass that test, how many real losses pass it
too, and on how many of those the lost samples had turned the foot by more than 0.1 and 0.3 rad.

    python3 docs/experiments/rate-continuation.py 0.055,0.1,0.2,0.3,1.0   # from the repository root

Why `gaps.rs` asks the stride before as well: the continuation alone is no test of a loss.
"""
import glob, sys
import numpy as np

N = 30
lengths = [float(x) for x in sys.argv[1].split(",")]
res = {}
for d in sorted(glob.glob("tests/data/gdins_*")):
    a = np.loadtxt(d + "/imu.csv", delimiter=",", skiprows=1)
    w = a[:, 1:4]
    d2 = w[2:] - 2 * w[1:-1] + w[:-2]
    for gap_s in lengths:
        k = int(round(gap_s * 200))
        for i in range(400, len(w) - k - 2, 7):
            # The last sample before the gap is i - 1; a clock step's next sample is i, a loss's i + k.
            change = w[i - 1] - w[i - 2]
            pred = w[i - 1] + change
            spread = max(np.linalg.norm(change), np.sqrt(np.mean(np.sum(d2[i - 2 - N:i - 2] ** 2, axis=1))))
            tol = max(0.05, 1.5 * spread)
            step = np.linalg.norm(w[i] - pred) <= tol
            loss = np.linalg.norm(w[i + k] - pred) <= tol
            turned = np.linalg.norm(w[i:i + k].sum(axis=0) * 0.005)
            res.setdefault(gap_s, []).append((step, loss, turned))
for gap_s, v in res.items():
    v = np.array(v, dtype=float)
    step, loss, turned = v[:, 0], v[:, 1], v[:, 2]
    print(f"{gap_s} s: clock steps passing {step.mean() * 100:.1f} %; real losses passing "
          f"{loss.mean() * 100:.1f} % ({int(loss.sum())} of {len(loss)}), of which turned the foot "
          f"by > 0.1 rad {int(np.sum(loss * (turned > 0.1)))}, > 0.3 rad {int(np.sum(loss * (turned > 0.3)))}")
