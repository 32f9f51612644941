#!/usr/bin/env python3
"""Write the synthetic trajectory/truth CSV fixtures for the eval.rs golden tests.

Run from the repository root: python3 service/tests/data/eval/gen_fixtures.py
Standard library only, fixed seed, so the CSVs are reproducible byte for byte.
The golden *.expected.json files are then made with the reference evaluator;
the exact commands are in the comment at the top of the tests in service/src/eval.rs.
"""

import math
import os
import random

HERE = os.path.dirname(os.path.abspath(__file__))


def lerp_path(waypoints, t):
    """Position on a piecewise-linear path given as [(t, x, y), ...]; clamps at the ends."""
    if t <= waypoints[0][0]:
        return waypoints[0][1], waypoints[0][2]
    for (t0, x0, y0), (t1, x1, y1) in zip(waypoints, waypoints[1:]):
        if t <= t1:
            a = 0.0 if t1 == t0 else (t - t0) / (t1 - t0)
            return x0 + a * (x1 - x0), y0 + a * (y1 - y0)
    return waypoints[-1][1], waypoints[-1][2]


def corrupt(times, truth_xy, rng, scale, drift_deg_s, frame_deg, offset, noise):
    """Dead-reckoning-like estimate: scaled increments rotated by a growing heading
    error, expressed in an arbitrary frame, plus white position noise."""
    out = []
    ex, ey = 0.0, 0.0
    for k, t in enumerate(times):
        if k > 0:
            dx = truth_xy[k][0] - truth_xy[k - 1][0]
            dy = truth_xy[k][1] - truth_xy[k - 1][1]
            a = math.radians(drift_deg_s * t)
            c, s = math.cos(a), math.sin(a)
            ex += scale * (c * dx - s * dy)
            ey += scale * (s * dx + c * dy)
        f = math.radians(frame_deg)
        c, s = math.cos(f), math.sin(f)
        x = c * ex - s * ey + offset[0] + rng.gauss(0.0, noise)
        y = s * ex + c * ey + offset[1] + rng.gauss(0.0, noise)
        out.append((x, y))
    return out


def write_csv(name, header, rows):
    with open(os.path.join(HERE, name), "w", encoding="utf-8", newline="\n") as fh:
        fh.write(header + "\n")
        for r in rows:
            fh.write(",".join(repr(v) if isinstance(v, float) else str(v) for v in r) + "\n")


def rect_loop(rng):
    """20 m x 10 m rectangle, start = end, GCPs at corners and mid-sides (stride column)."""
    speed = 1.25
    corners = [(0.0, 0.0), (10.0, 0.0), (20.0, 0.0), (20.0, 10.0), (10.0, 10.0), (0.0, 10.0), (0.0, 0.0)]
    t = 2.037
    wp = [(0.0, 0.0, 0.0), (t, 0.0, 0.0)]
    gcps = [(t, 0.0, 0.0)]
    for (x0, y0), (x1, y1) in zip(corners, corners[1:]):
        t += math.hypot(x1 - x0, y1 - y0) / speed
        wp.append((t, x1, y1))
        gcps.append((t, x1, y1))
    t_end = t + 2.0
    wp.append((t_end, 0.0, 0.0))
    times = [0.1 * k for k in range(int(t_end / 0.1) + 1)]
    truth_xy = [lerp_path(wp, tk) for tk in times]
    est = corrupt(times, truth_xy, rng, 1.015, 0.12, 37.0, (3.0, -2.0), 0.01)
    write_csv("loop.traj.csv", "t_s,x_m,y_m,z_m", [(tk, x, y, 0.0) for tk, (x, y) in zip(times, est)])
    write_csv(
        "loop.truth.csv",
        "t_s,x_m,y_m,z_m,stride,sample_index",
        [(tg, xg, yg, 0.0, 7 * i, int(tg * 200)) for i, (tg, xg, yg) in enumerate(gcps)],
    )


def out_and_back(rng):
    """Straight corridor out and back, every footprint is a GCP, ends 0.7 m from the start
    (not closed). Trajectory rows are per sample with two rows swapped (unsorted) and start
    10 ms after GCP0 (clamped, with a warning)."""
    stride_len, stride_t, stance_t = 0.75, 0.9, 0.3
    foot = [(0.0, 0.0)]
    for i in range(1, 25):
        foot.append((stride_len * i + rng.uniform(-0.05, 0.05), rng.uniform(-0.12, 0.12)))
    xt = foot[-1][0]
    for i in range(1, 24):
        foot.append((xt - stride_len * i + rng.uniform(-0.05, 0.05), 0.9 + rng.uniform(-0.12, 0.12)))
    foot.append((0.4, 0.55))
    # Footprint i: foot still on it over [t_i - stance_t, t_i]; GCP time is the stance end t_i.
    t0 = 1.503
    tg = [t0 + stride_t * i for i in range(len(foot))]
    wp = []
    for ti, (x, y) in zip(tg, foot):
        wp.append((ti - stance_t, x, y))
        wp.append((ti, x, y))
    t_end = tg[-1] + 1.0
    times = [0.1 * k for k in range(int(t0 / 0.1) + 1, int(t_end / 0.1) + 1)]
    truth_xy = [lerp_path(wp, tk) for tk in times]
    est = corrupt(times, truth_xy, rng, 0.98, -0.25, -115.0, (-4.0, 7.5), 0.005)
    rows = [(tk, x, y) for tk, (x, y) in zip(times, est)]
    rows[100], rows[101] = rows[101], rows[100]
    # The first sample is at 1.6 s, after GCP0 (1.503 s): out of span by 97 ms.
    write_csv("out_and_back.traj.csv", "t_s,x_m,y_m", rows)
    write_csv("out_and_back.truth.csv", "t_s,x_m,y_m,stride", [(t, x, y, i) for i, (t, (x, y)) in enumerate(zip(tg, foot))])


def closure_only(rng):
    """About 40 m loop; truth is two rows at the origin (start and end), no stride column."""
    t_end = 45.0
    times = [0.15 * k for k in range(int(t_end / 0.15) + 1)]
    truth_xy = []
    for tk in times:
        if tk < 5.0 or tk > 40.0:
            a = 0.0 if tk < 5.0 else 1.0
        else:
            a = (tk - 5.0) / 35.0
        phi = 2.0 * math.pi * a
        truth_xy.append((6.4 * math.sin(phi), 6.4 * (1.0 - math.cos(phi))))
    est = corrupt(times, truth_xy, rng, 1.01, 0.3, 80.0, (1.0, 1.0), 0.004)
    write_csv("closure.traj.csv", "t_s,x_m,y_m", [(tk, x, y) for tk, (x, y) in zip(times, est)])
    write_csv("closure.truth.csv", "t_s,x_m,y_m,z_m", [(0.0, 0.0, 0.0, 0.0), (times[-1], 0.0, 0.0, 0.0)])


def main():
    rng = random.Random(20240611)
    rect_loop(rng)
    out_and_back(rng)
    closure_only(rng)


if __name__ == "__main__":
    main()
