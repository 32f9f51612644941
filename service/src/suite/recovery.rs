//! Injected-bias recovery and the hindsight time it settles.

use crate::runner::RunOutcome;

/// Hindsight, not a real-time criterion: the time after which the recovered bias
/// (with − without injection) stays within ±5 % of the injected value on every axis, or `None`
/// when it does not end within it.
pub fn settled_at(with: &RunOutcome, without: &RunOutcome, inj: [f64; 3]) -> Option<f64> {
    let t = &with.trace.t_s;
    let mut last_outside: Option<usize> = None;
    for i in 0..t.len().min(without.trace.t_s.len()) {
        let outside = (0..3).any(|k| {
            inj[k] != 0.0
                && ((with.trace.bias_rad_s[i][k] - without.trace.bias_rad_s[i][k]) / inj[k] - 1.0)
                    .abs()
                    > 0.05
        });
        if outside {
            last_outside = Some(i);
        }
    }
    match last_outside {
        None => t.first().copied(),
        Some(i) if i + 1 < t.len() => Some(t[i + 1]),
        Some(_) => None,
    }
}

/// Recovery per axis: mean of (with − without)/injected after both converged (else the last
/// quarter of the log).
pub fn recovery(with: &RunOutcome, without: &RunOutcome, inj: [f64; 3]) -> [f64; 3] {
    let t = &with.trace.t_s;
    let from = match (with.converged_at_s, without.converged_at_s) {
        (Some(a), Some(b)) => a.max(b),
        _ => {
            t.first().copied().unwrap_or(0.0)
                + 0.75 * (t.last().copied().unwrap_or(0.0) - t.first().copied().unwrap_or(0.0))
        }
    };
    let mut sum = [0.0; 3];
    let mut n = 0usize;
    for (i, &ti) in t.iter().enumerate() {
        if ti >= from && i < without.trace.t_s.len() {
            for (k, s) in sum.iter_mut().enumerate() {
                *s += with.trace.bias_rad_s[i][k] - without.trace.bias_rad_s[i][k];
            }
            n += 1;
        }
    }
    std::array::from_fn(|k| {
        if n == 0 || inj[k] == 0.0 {
            f64::NAN
        } else {
            sum[k] / n as f64 / inj[k]
        }
    })
}
