//! Trajectory evaluation against surveyed footprint ground truth.
//!
//! A faithful port of the reference evaluator `tools/eval_traj.py` (its `evaluate()`
//! function): the same options, the same figures, the same JSON field names and the same
//! error cases. The method, in short:
//!
//! 1. **Sampling.** For each ground control point (GCP) time the trajectory position is
//!    taken from the trajectory row nearest in time ([`Interp::Nearest`]) or by linear
//!    interpolation ([`Interp::Linear`]). GCP times outside the trajectory's span are
//!    clamped to its ends; those more than 1 ms outside are listed under `warnings`.
//! 2. **Alignment.** [`Align::FirstLeg`] (the headline figure) puts the trajectory's
//!    GCP0 position on GCP0 and rotates about it so that the direction GCP0→GCPk matches
//!    the truth, where k is the first GCP at least `heading_min_dist_m` from GCP0; GCP0
//!    is then left out of the RMS and max. [`Align::Lsq`] fits the least-squares 2-D
//!    rigid transform (rotation + translation, no scale) over all GCPs. [`Align::Translation`]
//!    (not in the script) only puts GCP0 on GCP0: the trajectory's own heading is scored.
//! 3. **Figures.** RMS / max / final-GCP error, loop-closure error for closed walks,
//!    path lengths, the heading error of every GCP-to-GCP leg at least 5 m long and the
//!    heading drift rate (slope of a least-squares line through those errors).
//!
//! A loop-closure-only truth (all GCPs at one point) reports only the loop-closure error.
//!
//! The script rounds its JSON to 6 decimals when printing; [`evaluate`] does not round.
//!
//! Files: this one holds [`evaluate`]; `types.rs` its options, report and error; `report.rs`
//! the figures of a sampled trajectory; `sampler.rs` the streaming [`GcpSampler`];
//! `geometry.rs` the 2-D helpers and the numpy-compatible sampling; `tests.rs` the golden tests.

mod geometry;
mod report;
mod sampler;
mod types;

pub use geometry::wrap_deg;
pub use sampler::GcpSampler;
pub use types::{Align, EvalError, EvalOptions, EvalReport, GcpRow, Interp, Leg, TruthGcp};

use geometry::{P2, polyline_length, sample_traj};
use report::{Sampled, report};

/// Legs (consecutive GCP pairs) shorter than this in the truth get no heading-error entry.
pub const LEG_MIN_DIST_M: f64 = 5.0;

/// GCP times more than this far outside the trajectory's time span are warned about
/// (1 ms: CSV rounding).
pub(super) const SPAN_SLACK_S: f64 = 1e-3;

/// A GCP whose trajectory rows before and after lie further apart than this, s, falls in a gap
/// of the trajectory (a loss in the log): it is scored, as `eval_traj.py` scores it, and warned
/// about (it was not: a review scored 18.5 % of path for a log with a 1e6 s hole, no warning).
pub(super) const GAP_WARN_S: f64 = 2.0;

/// The warning for the GCPs that fall in gaps of the trajectory: `(index, gap length in s)`.
pub(super) fn gap_warning(in_gaps: &[(usize, f64)]) -> Option<String> {
    let longest = in_gaps.iter().map(|g| g.1).fold(0.0, f64::max);
    (!in_gaps.is_empty()).then(|| {
        format!(
            "GCP time(s) in a gap of the trajectory (the estimates around each more than {GAP_WARN_S} s apart; \
             the longest gap {longest:.1} s), scored at the rows around it: indices [{}]",
            in_gaps
                .iter()
                .map(|g| g.0.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )
    })
}

/// At least two GCP times within the trajectory's span, `eval_traj.py`'s 1 ms of tolerance
/// included (beyond it a GCP is clamped to an end with a warning; with every GCP clamped the
/// reference fails later, on a trajectory that "did not move", which says nothing of the cause).
pub(crate) fn check_overlap(gcp_t_s: &[f64], from_s: f64, to_s: f64) -> Result<(), EvalError> {
    let inside = gcp_t_s
        .iter()
        .filter(|&&t| t >= from_s - SPAN_SLACK_S && t <= to_s + SPAN_SLACK_S)
        .count();
    if inside >= 2 {
        return Ok(());
    }
    let (lo, hi) = gcp_t_s
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| {
            (a.min(t), b.max(t))
        });
    Err(EvalError::TruthOutsideTrajectory {
        truth_from_s: lo,
        truth_to_s: hi,
        traj_from_s: from_s,
        traj_to_s: to_s,
        inside,
    })
}

/// Evaluates a 2-D trajectory against ground-truth GCPs, exactly as the reference
/// script `tools/eval_traj.py` does.
///
/// `t_s`, `x_m`, `y_m` are the trajectory's columns (one row per sample or per stance,
/// on the truth's clock, right-handed x/y frame with arbitrary origin and heading).
/// Rows and GCPs with a non-finite time or coordinate are dropped first, as the
/// script's CSV reader does; unsorted rows are sorted (stable) with a warning.
///
/// # Errors
/// [`EvalError`] when the columns differ in length, fewer than two rows or GCPs are
/// left, fewer than two GCP times lie within the trajectory's span, or first-leg alignment
/// cannot set a heading.
pub fn evaluate(
    t_s: &[f64],
    x_m: &[f64],
    y_m: &[f64],
    truth: &[TruthGcp],
    opts: &EvalOptions,
) -> Result<EvalReport, EvalError> {
    if t_s.len() != x_m.len() || t_s.len() != y_m.len() {
        return Err(EvalError::LengthMismatch {
            t: t_s.len(),
            x: x_m.len(),
            y: y_m.len(),
        });
    }
    let mut warnings = Vec::new();
    let mut rows: Vec<(f64, P2)> = t_s
        .iter()
        .zip(x_m.iter().zip(y_m))
        .filter(|(t, (x, y))| t.is_finite() && x.is_finite() && y.is_finite())
        .map(|(&t, (&x, &y))| (t, [x, y]))
        .collect();
    if rows.len() < 2 {
        return Err(EvalError::TooFewTrajRows { rows: rows.len() });
    }
    if rows.windows(2).any(|w| w[1].0 < w[0].0) {
        rows.sort_by(|a, b| a.0.total_cmp(&b.0)); // stable, as argsort(kind="stable")
        warnings.push("trajectory rows were not in time order; sorted".to_owned());
    }
    let t: Vec<f64> = rows.iter().map(|r| r.0).collect();
    let xy: Vec<P2> = rows.iter().map(|r| r.1).collect();

    let truth = finite_gcps(truth)?;
    let n = truth.len();
    let tg: Vec<f64> = truth.iter().map(|g| g.t_s).collect();
    check_overlap(&tg, t[0], t[t.len() - 1])?;
    let (p, dt_used) = sample_traj(&t, &xy, &tg, opts.interp);
    let in_gaps: Vec<(usize, f64)> = tg
        .iter()
        .enumerate()
        .filter_map(|(i, &q)| {
            // The first row at or after q, and the one before it, as the streamed sampler
            // brackets it; a footprint on a row is scored there exactly.
            let k = t.partition_point(|&tk| tk < q);
            let gap = t[k.min(t.len() - 1)] - t[k.saturating_sub(1)];
            (k > 0 && k < t.len() && t[k] != q && gap > GAP_WARN_S).then_some((i, gap))
        })
        .collect();
    warnings.extend(gap_warning(&in_gaps));
    let in_span: Vec<P2> = t
        .iter()
        .zip(&xy)
        .filter(|&(&tk, _)| tk >= tg[0] && tk <= tg[n - 1])
        .map(|(_, &pk)| pk)
        .collect();
    let traj_len = if in_span.len() >= 2 {
        polyline_length(&in_span)
    } else {
        0.0
    };
    let sampled = Sampled {
        p,
        dt_used,
        t_first: t[0],
        t_last: t[t.len() - 1],
        traj_len_m: traj_len,
    };
    report(sampled, &truth, opts, warnings)
}

/// The GCPs with a finite time and position (at least two).
pub(super) fn finite_gcps(truth: &[TruthGcp]) -> Result<Vec<TruthGcp>, EvalError> {
    let truth: Vec<TruthGcp> = truth
        .iter()
        .filter(|g| g.t_s.is_finite() && g.x_m.is_finite() && g.y_m.is_finite())
        .copied()
        .collect();
    if truth.len() < 2 {
        return Err(EvalError::TooFewGcps { gcps: truth.len() });
    }
    Ok(truth)
}

#[cfg(test)]
mod tests;
