//! Injected-bias recovery, the hindsight time it settles, and how the real-time convergence
//! flag compares with that hindsight.

use crate::runner::RunOutcome;
use serde::Serialize;

/// How much of the injection the estimate has recovered at one instant, per axis, when the
/// relative error stays within this.
pub const SETTLED_TOLERANCE: f64 = 0.05;

/// The convergence flag of one injected run against hindsight. Times are s after the log's
/// first sample (a log stamped in epoch seconds reads as one stamped from 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Convergence {
    /// When the walk started (the end of the initial rest, where the late injection starts), s.
    pub walking_from_s: f64,
    /// When the run's flag first rose, s (`None`: never).
    pub flag_at_s: Option<f64>,
    /// The recovered part of the injection per axis at that instant (fraction).
    pub recovered_at_flag: Option<[f64; 3]>,
    /// Hindsight: from when on the recovery stays within ±5 % on every axis.
    pub settled_at_s: Option<f64>,
}

impl Convergence {
    /// The flag rose and the recovery was within ±5 % on every axis at that instant.
    pub fn agrees(&self) -> bool {
        self.recovered_at_flag
            .is_some_and(|r| r.iter().all(|v| (v - 1.0).abs() <= SETTLED_TOLERANCE))
    }

    /// Seconds of walking before the flag rose.
    pub fn flag_after_walking_s(&self) -> Option<f64> {
        self.flag_at_s.map(|t| t - self.walking_from_s)
    }
}

/// The flag of `with` (the injected run) against the recovery `with − without`; the walk
/// started at `walking_from_s` and the log at `log_from_s` (both on the log's clock).
pub fn convergence(
    with: &RunOutcome,
    without: &RunOutcome,
    inj: [f64; 3],
    walking_from_s: f64,
    log_from_s: f64,
) -> Convergence {
    let flag_at_s = with.converged_at_s;
    let recovered_at_flag = flag_at_s.and_then(|tf| {
        let n = with.trace.t_s.len().min(without.trace.t_s.len());
        let i = with.trace.t_s[..n].iter().position(|&t| t >= tf)?;
        Some(std::array::from_fn(|k| {
            (with.trace.bias_rad_s[i][k] - without.trace.bias_rad_s[i][k]) / inj[k]
        }))
    });
    let since_log = |t: f64| t - log_from_s;
    Convergence {
        walking_from_s: since_log(walking_from_s),
        flag_at_s: flag_at_s.map(since_log),
        recovered_at_flag,
        settled_at_s: settled_at(with, without, inj).map(since_log),
    }
}

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
                    > SETTLED_TOLERANCE
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
