#!/usr/bin/env python3
"""Where the default's footprint error comes from: leg lengths or leg directions.

    python3 docs/experiments/error-budget.py            # from the repository root (needs numpy)
    CONFIG=configs/gdins_zupt_baseline.toml MODE=zupt python3 docs/experiments/error-budget.py

Runs `corridor run` on every recording of `configs/eval/gdins.toml` with its start heading and
aligns the estimate on the first leg as `eval_traj.py` does (footprint 0, and the direction to
the first footprint at least 5 m away). The error at footprint k is the sum over the legs before
it of (estimated leg - surveyed leg), a leg being the displacement between consecutive
footprints. Each leg's difference is split into
- its length part: (estimated length - surveyed length) along the surveyed leg, and
- its direction part: the surveyed leg turned by the estimate's direction error,
and each part is summed over the legs alone and scored like the total (RMS over footprints 1..N,
% of the surveyed path). A constant scale is the part of the length errors that one ratio over
the whole walk explains. For a walk whose survey is closed (last footprint on the first) the
estimate's own closure |p_last - p_0| is printed with the leg whose length is furthest off.
Needs the release binary (`cargo build --release -p corridor-service --bin corridor`).
"""
import math, os, re, subprocess, sys, tempfile

import numpy as np

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
config = os.environ.get("CONFIG", os.path.join(root, "configs/gdins.toml"))
mode = os.environ.get("MODE")
suite = open(os.path.join(root, "configs/eval/gdins.toml")).read()
tmp = tempfile.mkdtemp(prefix="error-budget-")


def columns(path, names):
    header = open(path).readline().strip().split(",")
    return np.loadtxt(path, delimiter=",", skiprows=1, usecols=[header.index(n) for n in names], ndmin=2)


def rot(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


rows = []
for block in suite.split("[[recording]]")[1:]:
    name = re.search(r'name = "([^"]+)"', block).group(1)
    path = lambda key: re.search(key + r' = "([^"]+)"', block).group(1).replace("../../", root + "/")
    sh = re.search(r"start_heading_deg = ([-\d.]+)", block)
    gait = re.search(r'gait = "(\w+)"', block)
    out = os.path.join(tmp, name.split()[0])
    cmd = [binary, "run", "--imu", path("imu"), "--config", config, "--out", out,
           "--start-heading-deg", sh.group(1) if sh else "0"]
    if mode:
        cmd += ["--mode", mode, "--prior", "rest_mean"]
    subprocess.run(cmd, check=True, capture_output=True)
    est = columns(os.path.join(out, "estimates.csv"), ["t_s", "x_m", "y_m"])
    truth = columns(path("truth"), ["t_s", "x_m", "y_m"])
    # the estimate at each footprint time (nearest sample), aligned on the first leg
    j = np.clip(np.searchsorted(est[:, 0], truth[:, 0]), 1, len(est) - 1)
    j = np.where(truth[:, 0] - est[j - 1, 0] <= est[j, 0] - truth[:, 0], j - 1, j)
    p, g = est[j, 1:3], truth[:, 1:3]
    k = next(i for i in range(1, len(g)) if np.linalg.norm(g[i] - g[0]) >= 5.0)
    a = math.atan2(*(g[k] - g[0])[::-1]) - math.atan2(*(p[k] - p[0])[::-1])
    q = (p - p[0]) @ rot(a).T + g[0]
    dg, dq = np.diff(g, axis=0), np.diff(q, axis=0)
    lg, lq = np.linalg.norm(dg, axis=1), np.linalg.norm(dq, axis=1)
    psi = np.arctan2(dg[:, 1], dg[:, 0])
    dpsi = np.where(lg > 0.3, wrap(np.arctan2(dq[:, 1], dq[:, 0]) - psi), 0.0)
    along = np.column_stack([np.cos(psi), np.sin(psi)])
    turned = np.column_stack([np.cos(psi + dpsi), np.sin(psi + dpsi)])
    ratio = float(np.sum(lq * lg) / np.sum(lg * lg))
    path_m = float(lg.sum())
    pct = lambda legs: 100 * float(np.sqrt(np.mean(np.sum(np.cumsum(legs, axis=0) ** 2, axis=1)))) / path_m
    closed = np.linalg.norm(g[-1] - g[0]) < 0.05
    worst = int(np.argmax(np.abs(lq - lg)))
    rows.append(dict(
        name=name.split()[0], fast=bool(gait and gait.group(1) != "normal"), n=len(g),
        total=pct(dq - dg), length=pct((lq - lg)[:, None] * along), scale=pct(((ratio - 1) * lg)[:, None] * along),
        ratio=ratio, direction=pct(lg[:, None] * (turned - along)),
        closure=f"{np.linalg.norm(p[-1] - p[0]):.2f} m (leg {worst + 1}: {lq[worst] - lg[worst]:+.2f} m of {lg[worst]:.1f})" if closed else "",
    ))

print("| walk | footprints | first-leg RMS | length part | of it one scale (ratio) | direction part | closed survey: the estimate's closure (leg furthest off) |")
print("|---|---|---|---|---|---|---|")
for r in rows:
    print(f"| {r['name']}{' (fast)' if r['fast'] else ''} | {r['n']} | {r['total']:.3f} | {r['length']:.3f} | {r['scale']:.3f} ({r['ratio']:.4f}) | {r['direction']:.3f} | {r['closure']} |")
normal = [r for r in rows if not r["fast"]]
for key in ["total", "length", "scale", "direction"]:
    v = np.array([r[key] for r in normal])
    print(f"normal gait, {key}: median {np.median(v):.3f}, worst {v.max():.3f}, mean {v.mean():.3f} % of path")
