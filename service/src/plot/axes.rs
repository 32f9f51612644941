//! Ranges, axes and 1-2-5 ticks.

use super::Prepared;

/// One axis: data range mapped onto a pixel range, and its ticks.
#[derive(Debug, Clone)]
pub(super) struct Axis {
    pub(super) lo: f64,
    pub(super) hi: f64,
    pub(super) ticks: Vec<f64>,
    pub(super) step: f64,
}

impl Axis {
    /// Pixel position of `v` on a span from `p0` (at `lo`) to `p1` (at `hi`).
    pub(super) fn px(&self, v: f64, p0: f64, p1: f64) -> f64 {
        p0 + (v - self.lo) / (self.hi - self.lo) * (p1 - p0)
    }
}

pub(super) type Range = (f64, f64);

pub(super) fn union(a: Range, b: Range) -> Range {
    (a.0.min(b.0), a.1.max(b.1))
}

/// x and y ranges of the finite points (y including the band); (inf, -inf) when empty.
pub(super) fn data_range(series: &[Prepared]) -> (Range, Range) {
    let empty = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut xr, mut yr) = (empty, empty);
    for s in series {
        for k in 0..s.idx.len() {
            let (x, y) = (s.x(k), s.y(k));
            if !(x.is_finite() && y.is_finite()) {
                continue;
            }
            xr = union(xr, (x, x));
            yr = union(yr, (y, y));
            let b = s.band(k);
            if b.is_finite() {
                yr = union(yr, (y - b.abs(), y + b.abs()));
            }
        }
    }
    (xr, yr)
}

/// A non-empty, non-degenerate range around `r`.
pub(super) fn widen(r: Range) -> Range {
    if !(r.0.is_finite() && r.1.is_finite()) {
        return (0.0, 1.0);
    }
    if r.1 > r.0 {
        return r;
    }
    let pad = if r.0 == 0.0 { 1.0 } else { r.0.abs() * 0.1 };
    (r.0 - pad, r.1 + pad)
}

/// A 1-2-5 step near `span / target`.
pub(super) fn nice_step(span: f64, target: usize) -> f64 {
    let raw = span / target.max(1) as f64;
    let p = 10f64.powi(raw.log10().floor() as i32);
    let f = raw / p;
    // Small tolerance so that e.g. 1.0000000000000002 still counts as 1.
    let m = [1.0, 2.0, 5.0]
        .into_iter()
        .find(|&m| f <= m * (1.0 + 1e-9))
        .unwrap_or(10.0);
    m * p
}

/// Ticks at multiples of a 1-2-5 step, about `target` of them, the first at or below
/// `lo` and the last at or above `hi`.
pub(super) fn nice_ticks(lo: f64, hi: f64, target: usize) -> (Vec<f64>, f64) {
    let (lo, hi) = widen((lo, hi));
    let step = nice_step(hi - lo, target);
    let k0 = (lo / step).floor() as i64;
    let k1 = (hi / step).ceil() as i64;
    let ticks = (k0..=k1).map(|k| clean(k as f64 * step)).collect();
    (ticks, step)
}

/// Rounds away the float noise of `k * step` and turns -0 into 0.
pub(super) fn clean(v: f64) -> f64 {
    let r = format!("{v:.12e}").parse::<f64>().unwrap_or(v);
    if r == 0.0 { 0.0 } else { r }
}

/// Axis over data range `r`, extended to the enclosing ticks.
pub(super) fn axis_for(r: Range, target: usize) -> Axis {
    let (ticks, step) = nice_ticks(r.0, r.1, target);
    Axis {
        lo: ticks[0],
        hi: ticks[ticks.len() - 1],
        ticks,
        step,
    }
}

/// Axis over exactly `r`, with the multiples of `step` that fall inside it.
pub(super) fn axis_exact(r: Range, step: f64) -> Axis {
    let eps = step * 1e-9;
    let k0 = ((r.0 - eps) / step).ceil() as i64;
    let k1 = ((r.1 + eps) / step).floor() as i64;
    let ticks = (k0..=k1).map(|k| clean(k as f64 * step)).collect();
    Axis {
        lo: r.0,
        hi: r.1,
        ticks,
        step,
    }
}

/// `r` widened by `frac` of its span on each side (so data does not touch the frame).
pub(super) fn pad(r: Range, frac: f64) -> Range {
    let (lo, hi) = widen(r);
    let d = (hi - lo) * frac;
    (lo - d, hi + d)
}

/// Equal-aspect axes: both ranges padded, the one with more pixels per unit widened
/// about its centre to the other's scale, and one tick step for both (square grid).
pub(super) fn equal_axes(
    xr: Range,
    yr: Range,
    w: f64,
    h: f64,
    tx: usize,
    ty: usize,
) -> (Axis, Axis) {
    let (xr, yr) = (pad(xr, 0.04), pad(yr, 0.04));
    let s = (w / (xr.1 - xr.0)).min(h / (yr.1 - yr.0));
    let grow = |r: Range, px: f64| {
        let half = px / s / 2.0;
        let c = 0.5 * (r.0 + r.1);
        (c - half, c + half)
    };
    let (gx, gy) = (grow(xr, w), grow(yr, h));
    let step = nice_step(gx.1 - gx.0, tx).max(nice_step(gy.1 - gy.0, ty));
    (axis_exact(gx, step), axis_exact(gy, step))
}

/// Text for a tick value printed with the precision of `step`: the digits after the first
/// that tell ticks `step` apart (a time axis of a log stamped in Unix seconds, 1.7e9 s ticked
/// every 10 s, read "1.7e9" at every tick); large values ticked a whole unit or more apart in
/// full ("1700000010").
pub(super) fn tick_label(v: f64, step: f64) -> String {
    let decimals = (-step.log10() - 1e-9).ceil().max(0.0) as usize;
    let digits = (v.abs().log10().floor() - (step.log10() + 1e-9).floor()).max(1.0) as usize;
    let s = if v != 0.0 && v.abs() >= 1e6 && step >= 1.0 && digits > 1 {
        format!("{v:.0}")
    } else if v != 0.0 && (v.abs() >= 1e6 || step < 1e-4) {
        format!("{v:.digits$e}")
    } else {
        format!("{v:.decimals$}")
    };
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_owned()
    } else {
        s
    }
}
