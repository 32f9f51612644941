#!/usr/bin/env python3
"""How the rates' continuation tells a clock set back from other things that make the stamps go
back: at every 7th sample of the 16 gdins walks (from the 400th on), the two samples after a step
back are tested as `gaps::clock_stepped_back` tests them (each within a factor times the forward
clock step's tolerance of the straight line through the two before it: 1.5 times the larger of
the last step's change of the rate and the RMS second difference of the last 30, at least 0.05
rad/s). Prints per factor how often a real step back with nothing lost passes, and per lag and
factor how often samples re-sent from that long before (not exact copies: exact ones are refused
by their values) or samples after a loss of that length pass too, and on how many of those the
samples between had turned the foot by more than 0.1 and 0.3 rad.

    python3 docs/experiments/step-back.py 0.02,0.05,0.1,0.3     # from the repository root

Chose `STEP_BACK_TOLERANCE` (2): a step back refused costs what a loss of its length costs.
"""
import glob, sys
import numpy as np
N = 30
factors = [1.0, 1.5, 2.0, 3.0, 4.0]
lags = [float(x) for x in sys.argv[1].split(",")] if len(sys.argv) > 1 else [0.02, 0.05, 0.1, 0.3]
steps = {f: [] for f in factors}
other = {}
for d in sorted(glob.glob("tests/data/gdins_*")):
    a = np.loadtxt(d + "/imu.csv", delimiter=",", skiprows=1)
    w = a[:, 1:4]
    d2 = w[2:] - 2 * w[1:-1] + w[:-2]
    for i in range(400, len(w) - 200, 7):
        change = w[i - 1] - w[i - 2]
        spread = max(np.linalg.norm(change), np.sqrt(np.mean(np.sum(d2[i - 2 - N:i - 2] ** 2, axis=1))))
        tol = max(0.05, 1.5 * spread)
        def runs_on(first, now, f):
            return (np.linalg.norm(first - (w[i - 1] + change)) <= f * tol
                    and np.linalg.norm(now - (2 * first - w[i - 1])) <= f * tol)
        for f in factors:
            steps[f].append(runs_on(w[i], w[i + 1], f))
        for lag in lags:
            k = int(round(lag * 200))
            # re-sent (k samples back) and lost (k samples ahead)
            for kind, j in (("resent", i - k), ("lost", i + k)):
                turned = np.linalg.norm(w[min(i, j):max(i, j)].sum(axis=0) * 0.005)
                for f in factors:
                    other.setdefault((kind, lag, f), []).append((runs_on(w[j], w[j + 1], f), turned))
for f in factors:
    print(f"factor {f}: steps back taken {np.mean(steps[f]) * 100:.1f} % of {len(steps[f])}")
for (kind, lag, f), v in sorted(other.items()):
    v = np.array(v, dtype=float)
    p, t = v[:, 0], v[:, 1]
    print(f"{kind} {lag} s factor {f}: pass {p.mean() * 100:.1f} %, of those turned > 0.1 rad {int(np.sum(p * (t > 0.1)))}, > 0.3 rad {int(np.sum(p * (t > 0.3)))} (of {len(p)})")
