//! 2-D helpers and the trajectory sampling, with numpy's arithmetic.

use super::Interp;

pub(super) type P2 = [f64; 2];

pub(super) fn norm(v: P2) -> f64 {
    (v[0] * v[0] + v[1] * v[1]).sqrt()
}

pub(super) fn sub(a: P2, b: P2) -> P2 {
    [a[0] - b[0], a[1] - b[1]]
}

/// Rotates `v` by `theta` (counter-clockwise), then adds `t`.
pub(super) fn rot_add(theta: f64, v: P2, t: P2) -> P2 {
    let (s, c) = theta.sin_cos();
    [c * v[0] - s * v[1] + t[0], s * v[0] + c * v[1] + t[1]]
}

/// Wraps an angle in degrees to [-180, 180), with Python's floored modulo.
pub fn wrap_deg(a: f64) -> f64 {
    let m = (a + 180.0) % 360.0;
    let m = if m < 0.0 { m + 360.0 } else { m };
    m - 180.0
}

pub(super) fn polyline_length(xy: &[P2]) -> f64 {
    xy.windows(2).map(|w| norm(sub(w[1], w[0]))).sum()
}

pub(super) fn mean(xy: &[P2]) -> P2 {
    let n = xy.len() as f64;
    let s = xy
        .iter()
        .fold([0.0, 0.0], |a, p| [a[0] + p[0], a[1] + p[1]]);
    [s[0] / n, s[1] / n]
}

/// Trajectory positions at the query times, and |time used − query time| per query.
/// `t` must be sorted and hold at least two rows.
pub(super) fn sample_traj(t: &[f64], xy: &[P2], tq: &[f64], mode: Interp) -> (Vec<P2>, Vec<f64>) {
    let (t0, t1) = (t[0], t[t.len() - 1]);
    let mut pos = Vec::with_capacity(tq.len());
    let mut dt = Vec::with_capacity(tq.len());
    for &q in tq {
        let qc = q.clamp(t0, t1);
        match mode {
            Interp::Linear => {
                pos.push([interp(qc, t, xy, 0), interp(qc, t, xy, 1)]);
                dt.push((q - qc).abs());
            }
            Interp::Nearest => {
                // numpy: searchsorted(side="left"), clip to [1, n-1], ties to the left.
                let j = t.partition_point(|&v| v < qc).clamp(1, t.len() - 1);
                let j = if qc - t[j - 1] <= t[j] - qc { j - 1 } else { j };
                pos.push(xy[j]);
                dt.push((t[j] - q).abs());
            }
        }
    }
    (pos, dt)
}

/// `numpy.interp(x, t, xy[:, c])` for x inside [t[0], t[-1]].
pub(super) fn interp(x: f64, t: &[f64], xy: &[P2], c: usize) -> f64 {
    let n = t.len();
    if x >= t[n - 1] {
        return xy[n - 1][c];
    }
    if x < t[0] {
        return xy[0][c];
    }
    // Last index j with t[j] <= x, as numpy's binary search.
    let j = t.partition_point(|&v| v <= x) - 1;
    if t[j] == x {
        return xy[j][c];
    }
    let slope = (xy[j + 1][c] - xy[j][c]) / (t[j + 1] - t[j]);
    let mut r = slope * (x - t[j]) + xy[j][c];
    if r.is_nan() {
        r = slope * (x - t[j + 1]) + xy[j + 1][c];
        if r.is_nan() && xy[j][c] == xy[j + 1][c] {
            r = xy[j][c];
        }
    }
    r
}

/// Slope of the least-squares line y = a + b x (what `numpy.polyfit(x, y, 1)[0]` gives).
pub(super) fn line_slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let xm = x.iter().sum::<f64>() / n;
    let ym = y.iter().sum::<f64>() / n;
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - xm) * (b - ym)).sum();
    let sxx: f64 = x.iter().map(|a| (a - xm) * (a - xm)).sum();
    sxy / sxx
}
