//! Stride length against position information: an effect the heading residuals cannot show.
//!
//! When footprints are given, every surveyed leg (footprint i − 1 → i) has a length the run
//! estimates (its positions at the two footprint times) and one the survey measured. A stride
//! scale `k` makes `L̂ = k·L`: the least-squares `k̂ = Σ w·L̂·L / Σ w·L²` over the legs (equal
//! weights for single strides; a corner leg's weight falls with its length, [`weight`]), its
//! standard error from the weighted scatter about that line (n − 1 degrees of freedom),
//! `−log₁₀` of the two-sided Student-t p of `(k̂ − 1)/se` as the score and `t·se` as the
//! detectable size, `t` the quantile of p = 10⁻³ (3.29, [`MDE_Z`], for many legs; 5.4 for eight,
//! 12.9 for four), as for the other effects.
//! Consecutive legs share a footprint, so a position error at one shortens one leg and
//! lengthens the next: the plain standard error overstates the scatter of `k̂`, which errs on
//! the side of naming less.
//!
//! Single strides count where the survey has at least [`MIN_LEGS`] of them: legs shorter than
//! [`MIN_LEG_M`] (a shuffle, a turn on the spot) or longer than [`MAX_LEG_M`] (several strides)
//! are left out. A walk surveyed only at its corners has few legs, each many strides long; there
//! the legs from [`MIN_LEG_M`] up make the fit when they are at least [`MIN_CORNER_LEGS`]
//! ([`LegKind`]): a corridor leg's chord is the walked length to within a few hundredths of a
//! percent (a heading that wanders by 3° along it shortens the chord by 0.04 %), and each leg
//! averages the strides' scatter. Either way a leg that lies more than [`OUTLIER_SD`] robust σ
//! from the median scale (its ratio's deviation for single strides; for corner legs its misfit
//! in metres over its own σ, [`weight`]) is left out: a footprint the survey placed wrong
//! (exp31's leg 31 measures 0.57 of its surveyed length in every model, a leg its data set's own
//! check flags; exp29's start footprint, a floor tile from where the walker stood, makes its
//! first corridor 7 % short) would otherwise decide the fit.
//!
//! The fix the diagnosis tries is the rolling-foot stance update
//! (`eskf.zupt_rolling_height_m`), when the model has none: a plain zero-velocity update holds
//! the sensor still while the foot rolls about its heel and its ball, and cuts that motion out
//! of every stride (the 2.0–2.4 % short strides of the first measured walks). A model that
//! already has it names a remaining stride scale without a fix: only position observations
//! (loop closures, footprints) could estimate it in the filter.

use super::catalogue::{Effect, Fix};
use super::power::MDE_Z;
use super::ranking::Finding;
use crate::runner::Trace;
use crate::stats::student_t_two_sided_p;
use corridor_shared::truth_csv::TruthPoint;
use serde::Serialize;

/// Surveyed legs shorter than this are left out, m.
pub const MIN_LEG_M: f64 = 0.5;

/// Surveyed legs longer than this are more than one stride, m: left out where the survey has
/// [`MIN_LEGS`] single strides.
pub const MAX_LEG_M: f64 = 2.5;

/// A leg that lies more than this many robust σ (1.4826 × the median absolute deviation) from
/// the median scale is left out: a single stride by its ratio (estimated / surveyed), a corner
/// leg by its misfit in metres over its own σ ([`weight`]).
pub const OUTLIER_SD: f64 = 4.0;

/// The fewest single strides the fit needs.
pub const MIN_LEGS: usize = 8;

/// The fewest legs the fit needs on a walk surveyed at its corners (fewer than [`MIN_LEGS`]
/// single strides): a rectangle's four sides. With so few the Student-t quantile is large (12.9
/// for three degrees of freedom), so the stride finding is named only for a scale the legs agree
/// on closely; the clock-rate test takes the ratio with the gait's own spread
/// ([`super::clock_rate::GAIT_SCALE_SD`]).
pub const MIN_CORNER_LEGS: usize = 4;

/// Which legs a stride-scale fit was made on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LegKind {
    /// Surveyed single strides ([`MIN_LEG_M`]–[`MAX_LEG_M`]).
    SingleStrides,
    /// Every surveyed leg from [`MIN_LEG_M`] up: a walk surveyed at its corners.
    CornerLegs,
}

impl LegKind {
    /// In words, after "over N".
    pub fn words(self) -> &'static str {
        match self {
            LegKind::SingleStrides => "single strides",
            LegKind::CornerLegs => "legs between surveyed corners",
        }
    }
}

/// The stride scale a run shows against the footprints.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StrideLength {
    /// `k̂`: estimated over surveyed leg length (1 = right).
    pub ratio: f64,
    /// Its standard error.
    pub std_err: f64,
    /// Legs in the fit.
    pub legs: usize,
    /// Which legs: single strides, or a corner-surveyed walk's legs.
    pub kind: LegKind,
    /// Legs left out as outliers (shorter legs are not counted).
    pub outliers: usize,
    /// −log₁₀ p of `(k̂ − 1)/se` (capped at 30).
    pub score: f64,
    /// The smallest stride scale error (|k − 1|) this walk shows at p < 10⁻³ half the time.
    pub mde: f64,
}

/// The stride-length line of a report: the fit and its finding on one model.
#[derive(Debug, Clone, Serialize)]
pub struct StrideLine {
    /// The fit.
    pub fit: StrideLength,
    /// Its finding (score, evidence, fix).
    pub finding: Finding,
}

/// Fits the stride scale of `trace` against the footprints: on the surveyed single strides when
/// there are [`MIN_LEGS`] of them, else on every leg from [`MIN_LEG_M`] up when there are
/// [`MIN_CORNER_LEGS`]; `None` otherwise.
pub fn stride_length(trace: &Trace, truth: &[TruthPoint]) -> Option<StrideLength> {
    let legs: Vec<(f64, f64)> = leg_lengths(trace, truth).into_iter().flatten().collect();
    fit_legs(&legs)
}

/// Every surveyed leg's `(estimated, surveyed)` length, m, indexed by its first footprint (leg
/// `i` runs from footprint `i` to `i + 1`): `None` for a leg shorter than [`MIN_LEG_M`] or with a
/// footprint outside the run (during the alignment, or after the log's end).
pub fn leg_lengths(trace: &Trace, truth: &[TruthPoint]) -> Vec<Option<(f64, f64)>> {
    // The run's position at a footprint time (the first sample at or after it).
    let (Some(first), Some(last)) = (trace.t_s.first(), trace.t_s.last()) else {
        return vec![None; truth.len().saturating_sub(1)];
    };
    let at = |t: f64| {
        if t < *first || t > *last {
            return None;
        }
        trace
            .xy_m
            .get(trace.t_s.partition_point(|&x| x < t))
            .copied()
    };
    truth
        .windows(2)
        .map(|w| {
            let surveyed = (w[1].x_m - w[0].x_m).hypot(w[1].y_m - w[0].y_m);
            let (a, b) = (at(w[0].t_s)?, at(w[1].t_s)?);
            let estimated = (b[0] - a[0]).hypot(b[1] - a[1]);
            (surveyed >= MIN_LEG_M && estimated.is_finite()).then_some((estimated, surveyed))
        })
        .collect()
}

/// The corner legs a fit over `legs` ([`leg_lengths`]) keeps, by index, when it is a fit on a
/// walk surveyed at its corners (fewer than [`MIN_LEGS`] single strides); empty otherwise (a
/// single-stride fit, or too few legs).
pub fn kept_corner_legs(legs: &[Option<(f64, f64)>]) -> Vec<usize> {
    let all: Vec<(usize, (f64, f64))> = legs
        .iter()
        .enumerate()
        .filter_map(|(i, l)| l.map(|l| (i, l)))
        .collect();
    let values: Vec<(f64, f64)> = all.iter().map(|&(_, l)| l).collect();
    if fit_legs(&values).is_none_or(|f| f.kind != LegKind::CornerLegs) {
        return Vec::new();
    }
    let kept = kept_mask(&values, LegKind::CornerLegs);
    all.iter()
        .zip(kept)
        .filter_map(|(&(i, _), k)| k.then_some(i))
        .collect()
}

/// The weighted least-squares scale over corner legs, without the outlier rule or the least
/// number of legs: the prediction of a held-out leg from the others ([`kept_corner_legs`] has
/// already left the outliers out).
pub fn corner_scale(legs: &[(f64, f64)]) -> Option<f64> {
    let w = |s: f64| weight(LegKind::CornerLegs, s);
    let sxx: f64 = legs.iter().map(|&(_, s)| w(s) * s * s).sum();
    (sxx > 0.0).then(|| legs.iter().map(|&(e, s)| w(s) * e * s).sum::<f64>() / sxx)
}

/// The fit over the `(estimated, surveyed)` lengths of every leg from [`MIN_LEG_M`] up: on the
/// single strides when there are enough of them, else on all of them.
fn fit_legs(legs: &[(f64, f64)]) -> Option<StrideLength> {
    let single: Vec<(f64, f64)> = legs
        .iter()
        .copied()
        .filter(|&(_, s)| s <= MAX_LEG_M)
        .collect();
    // (8 single strides of which the outlier rule leaves fewer than 8 fall back on every leg.)
    (single.len() >= MIN_LEGS)
        .then(|| fit(&single, LegKind::SingleStrides))
        .flatten()
        .or_else(|| fit(legs, LegKind::CornerLegs))
}

/// The fit over `(estimated, surveyed)` leg lengths of one kind.
fn fit(legs: &[(f64, f64)], kind: LegKind) -> Option<StrideLength> {
    let min = match kind {
        LegKind::SingleStrides => MIN_LEGS,
        LegKind::CornerLegs => MIN_CORNER_LEGS,
    };
    if legs.len() < min {
        return None;
    }
    let mask = kept_mask(legs, kind);
    let kept: Vec<(f64, f64)> = legs
        .iter()
        .zip(&mask)
        .filter_map(|(&l, &k)| k.then_some(l))
        .collect();
    let n = kept.len();
    if n < min {
        return None;
    }
    let w = |s: f64| weight(kind, s);
    let sxx: f64 = kept.iter().map(|&(_, s)| w(s) * s * s).sum();
    let ratio = kept.iter().map(|&(e, s)| w(s) * e * s).sum::<f64>() / sxx;
    let rss: f64 = kept
        .iter()
        .map(|&(e, s)| w(s) * (e - ratio * s).powi(2))
        .sum();
    let std_err = (rss / (n - 1) as f64 / sxx).sqrt();
    let df = (n - 1) as f64;
    let p = student_t_two_sided_p((ratio - 1.0) / std_err, df);
    Some(StrideLength {
        ratio,
        std_err,
        legs: n,
        kind,
        outliers: legs.len() - n,
        score: super::ranking::score(p),
        mde: t_critical(df) * std_err,
    })
}

/// Which of `legs` the fit keeps: those within [`OUTLIER_SD`] robust σ of the median scale.
fn kept_mask(legs: &[(f64, f64)], kind: LegKind) -> Vec<bool> {
    let mut ratios: Vec<f64> = legs.iter().map(|(e, s)| e / s).collect();
    let median = crate::stats::median(&mut ratios);
    // Each leg's deviation from the median scale, in units of its own σ (up to a common factor).
    let deviation = |&(e, s): &(f64, f64)| match kind {
        LegKind::SingleStrides => e / s - median,
        LegKind::CornerLegs => (e - median * s) * weight(kind, s).sqrt(),
    };
    let mut dev: Vec<f64> = legs.iter().map(|l| deviation(l).abs()).collect();
    let mad = crate::stats::median(&mut dev);
    let limit = OUTLIER_SD * 1.4826 * mad;
    legs.iter()
        .map(|l| mad == 0.0 || deviation(l).abs() <= limit)
        .collect()
}

/// The weight of a leg `surveyed_m` long in the fit, the inverse of its length error's variance up
/// to a common factor. Single strides are all about one stride long: equal weights. A corner leg's
/// error has a part from its two end footprints (where the foot stood and where the survey put it,
/// as for one stride) and a part the filter's position error builds stride by stride along it,
/// which grows with the distance walked: variance ∝ `L + LEG_END_M`. On the diagnosis's model the
/// legs' misfits bear this out (exp28: 2–4 cm on its 1.2 m legs, up to 15 cm on its 29 and 65 m
/// legs).
/// Unweighted, with the outliers judged by their ratio, the rule threw out good short legs (exp28's
/// 1.2 m ones, 2–4 cm off being 2–3 % of them) and kept a bad long one (exp20's 31 m corridor,
/// 53 cm long where the others are within 3 cm: 1.7 % of it), and dropped a leg of exp22's four (a
/// review).
fn weight(kind: LegKind, surveyed_m: f64) -> f64 {
    match kind {
        LegKind::SingleStrides => 1.0,
        LegKind::CornerLegs => 1.0 / (surveyed_m + LEG_END_M),
    }
}

/// The length over which a corner leg's accumulated error equals the share of its two end
/// footprints: one stride ([`weight`]). Chosen before looking at the fits, not on them.
pub const LEG_END_M: f64 = 1.4;

/// The two-sided Student-t quantile of p = 10⁻³ with `df` degrees of freedom (bisection; the
/// normal's [`MDE_Z`] is its limit).
fn t_critical(df: f64) -> f64 {
    let (mut lo, mut hi) = (MDE_Z, 1e3);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if student_t_two_sided_p(mid, df) > 1e-3 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The finding of the fit, with the rolling-foot stance update as its fix when the model has
/// none (`rolling`: the model's rolling height is set), and once it has it, the scale itself
/// taken out as the accelerometer's (the footprints are position information).
pub fn stride_length_finding(s: &StrideLength, rolling: bool) -> Finding {
    Finding {
        name: Effect::StrideLength,
        score: s.score,
        evidence: format!(
            "estimated / surveyed leg length {:.4} ± {:.4} over {} {} ({} left out as outliers); \
             {}",
            s.ratio,
            s.std_err,
            s.legs,
            s.kind.words(),
            s.outliers,
            if rolling {
                "the model has the rolling-foot stance update: the scale left is taken out as an accelerometer scale error (the footprints are the position information a filter state would lack)"
            } else {
                "a plain zero-velocity update cuts the foot's rolling out of every stride"
            }
        ),
        fix: Some(if rolling {
            Fix::stride_scale(s.ratio)
        } else {
            Fix::RollingStance
        }),
        mde: Some(s.mde),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Legs of 1.2-1.5 m with a scatter of up to ±2 cm (a fixed pseudo-random sequence), scaled
    /// by `k`.
    fn legs(k: f64, n: usize) -> Vec<(f64, f64)> {
        (0..n)
            .map(|i| {
                let s = 1.2 + 0.3 * ((i * 7) % 5) as f64 / 4.0;
                let noise = 0.02 * (((i * 37 + 5) % 11) as f64 / 5.0 - 1.0);
                (k * s + noise, s)
            })
            .collect()
    }

    fn fit_strides(l: &[(f64, f64)]) -> Option<StrideLength> {
        fit(l, LegKind::SingleStrides)
    }

    #[test]
    fn a_two_percent_short_stride_is_named_and_a_right_one_is_not() {
        let short = fit_strides(&legs(0.98, 60)).unwrap();
        assert!((short.ratio - 0.98).abs() < 2e-3, "{short:?}");
        assert!(short.score >= 3.0, "{short:?}");
        assert!(short.mde < 0.02, "{short:?}");
        let right = fit_strides(&legs(1.0, 60)).unwrap();
        assert!((right.ratio - 1.0).abs() < 2e-3, "{right:?}");
        assert!(right.score < 3.0, "{right:?}");
        // Fewer legs, a larger detectable size.
        assert!(fit_strides(&legs(1.0, 15)).unwrap().mde > right.mde);
        assert!(fit_strides(&legs(1.0, MIN_LEGS - 1)).is_none());
    }

    /// A rectangle walked `laps` times, surveyed at its corners (6.4 × 9.6 m, exp17's), each
    /// side scaled by `k` with a scatter of up to ±3 cm.
    fn corner_legs(k: f64, laps: usize) -> Vec<(f64, f64)> {
        (0..4 * laps)
            .map(|i| {
                let s = if i % 2 == 0 { 6.4 } else { 9.6 };
                let noise = 0.03 * (((i * 37 + 5) % 11) as f64 / 5.0 - 1.0);
                (k * s + noise, s)
            })
            .collect()
    }

    #[test]
    fn a_walk_surveyed_at_its_corners_is_fitted_on_its_legs() {
        // exp17, exp18, exp22 and exp26 have four legs and no single stride: they were not
        // tested at all, so a clock error there could not be told by its strides.
        let short = fit_legs(&corner_legs(0.98, 1)).unwrap();
        assert_eq!(short.kind, LegKind::CornerLegs);
        assert_eq!(short.legs, 4);
        assert!((short.ratio - 0.98).abs() < 2e-3, "{short:?}");
        assert!(fit_legs(&corner_legs(1.0, 1)[..3]).is_none());
        // Two laps, the start footprint a floor tile off (exp29's first corridor 7 % short):
        // left out.
        let mut l = corner_legs(1.0, 2);
        l[0].0 *= 0.93;
        let f = fit_legs(&l).unwrap();
        assert_eq!((f.legs, f.outliers), (7, 1), "{f:?}");
        assert!((f.ratio - 1.0).abs() < 2e-3, "{f:?}");
        // Enough single strides: the long legs between them are left out.
        let mut l = legs(0.98, 20);
        l.extend(corner_legs(1.05, 1));
        let f = fit_legs(&l).unwrap();
        assert_eq!((f.kind, f.legs), (LegKind::SingleStrides, 20), "{f:?}");
        assert!((f.ratio - 0.98).abs() < 2e-3, "{f:?}");
        // Eight single strides, one a misplaced footprint's: the legs between the corners too.
        let mut l = legs(0.98, 8);
        l[3].0 *= 0.57;
        l.extend(corner_legs(0.98, 1));
        let f = fit_legs(&l).unwrap();
        assert_eq!(
            (f.kind, f.legs, f.outliers),
            (LegKind::CornerLegs, 11, 1),
            "{f:?}"
        );
    }

    /// exp20's legs on the default model (`configs/gdins.toml`): its 31.2 m corridor 53 cm long,
    /// the other legs within 3 cm (its start footprint's survey).
    fn exp20_legs() -> Vec<(f64, f64)> {
        measured(&[
            (31.2, 1.017),
            (10.2, 1.000),
            (7.2, 1.003),
            (9.0, 1.003),
            (24.0, 1.000),
            (1.2, 1.024),
        ])
    }

    /// Legs `(surveyed, estimated / surveyed)` as a run of a bundled walk gives them.
    fn measured(legs: &[(f64, f64)]) -> Vec<(f64, f64)> {
        legs.iter().map(|&(s, r)| (s * r, s)).collect()
    }

    #[test]
    fn a_corner_legs_misfit_is_judged_against_its_own_length() {
        // exp20 on the default model (`configs/gdins.toml`): its 31.2 m corridor comes out 53 cm
        // long, the other legs within 3 cm (its start footprint's survey). The ratio rule kept
        // that leg (1.7 % off) and left out the 1.2 m one (3 cm, 2.4 %): scale 1.0096 ± 0.0041
        // where the legs without the corridor give 1.000 (a review).
        let exp20 = exp20_legs();
        let f = fit_legs(&exp20).unwrap();
        assert_eq!(
            (f.kind, f.legs, f.outliers),
            (LegKind::CornerLegs, 5, 1),
            "{f:?}"
        );
        assert!((f.ratio - 1.0).abs() < 2e-3, "{f:?}");
        // exp28 on the default model: its 1.2 m legs, 2 and 4 cm off, are as good as its long
        // ones: kept, where the ratio rule left both out.
        let exp28 = measured(&[
            (9.0, 0.994),
            (7.2, 1.001),
            (9.0, 1.003),
            (28.8, 0.999),
            (1.2, 1.034),
            (64.5, 1.001),
            (1.2, 1.017),
            (28.6, 1.004),
        ]);
        let f = fit_legs(&exp28).unwrap();
        assert_eq!((f.legs, f.outliers), (8, 0), "{f:?}");
        assert!((f.ratio - 1.001).abs() < 2e-3, "{f:?}");
        // exp22's four legs on the diagnosis's model (plain zero-velocity update): none left out
        // (the ratio rule dropped one, and the line with it), the short strides named.
        let exp22 = measured(&[(26.4, 0.968), (7.2, 0.968), (26.4, 0.970), (7.2, 0.974)]);
        let f = fit_legs(&exp22).unwrap();
        assert_eq!((f.legs, f.outliers), (4, 0), "{f:?}");
        assert!((f.ratio - 0.969).abs() < 2e-3, "{f:?}");
        assert!(f.score >= 3.0, "{f:?}");
    }

    #[test]
    fn the_legs_held_out_in_turn_are_those_the_fit_keeps_and_each_is_predicted_by_the_others() {
        // exp20's legs with the 31 m corridor 53 cm long, and two legs that are no leg (a turn
        // on the spot, a footprint outside the run): the corridor is left out, the others kept
        // by their index.
        let mut l: Vec<Option<(f64, f64)>> = exp20_legs().into_iter().map(Some).collect();
        l.insert(2, None);
        l.push(None);
        assert_eq!(kept_corner_legs(&l), [1, 3, 4, 5, 6]);
        // a scale the legs share is predicted from any of them, by the fit's weights
        let scaled: Vec<(f64, f64)> = [1.2, 7.2, 26.4].iter().map(|&s| (1.02 * s, s)).collect();
        assert!((corner_scale(&scaled).unwrap() - 1.02).abs() < 1e-12);
        assert_eq!(corner_scale(&[]), None);
        // a walk with enough single strides is not a corner-leg fit: nothing to hold out leg by
        // leg (its first half is fitted instead)
        let strides: Vec<Option<(f64, f64)>> = legs(0.98, 40).into_iter().map(Some).collect();
        assert!(kept_corner_legs(&strides).is_empty());
    }

    #[test]
    fn the_t_quantile_takes_the_degrees_of_freedom() {
        assert!(
            (t_critical(7.0) - 5.408).abs() < 1e-3,
            "{}",
            t_critical(7.0)
        );
        assert!((t_critical(1e6) - MDE_Z).abs() < 1e-3);
    }

    #[test]
    fn a_misplaced_footprint_does_not_decide_the_fit() {
        let mut l = legs(1.0, 40);
        l[20].0 *= 0.57; // exp31's leg 31
        let f = fit_strides(&l).unwrap();
        assert_eq!(f.outliers, 1, "{f:?}");
        assert!((f.ratio - 1.0).abs() < 2e-3, "{f:?}");
        assert!(f.score < 3.0, "{f:?}");
    }

    #[test]
    fn the_fix_is_the_rolling_stance_update_until_the_model_has_it_then_the_scale() {
        let s = fit_strides(&legs(0.98, 60)).unwrap();
        assert_eq!(
            stride_length_finding(&s, false).fix,
            Some(Fix::RollingStance)
        );
        let f = stride_length_finding(&s, true);
        let Some(Fix::StrideScale { ratio_ppm }) = f.fix else {
            panic!("{:?}", f.fix)
        };
        assert!((f64::from(ratio_ppm) * 1e-6 - (s.ratio - 1.0)).abs() < 1e-6);
        assert!(f.evidence.contains("accelerometer"), "{}", f.evidence);
        // applied twice, the scales compose: the model's factor becomes (1 + k₀)·ratio − 1
        let mut file = corridor_shared::config::ConfigFile::default();
        assert!(crate::diagnose::apply_fix(f.fix.unwrap(), &mut file));
        let k0 = file.model.accel_scale_factor.unwrap();
        assert!((k0 - (s.ratio - 1.0)).abs() < 1e-6, "{k0}");
        assert!(crate::diagnose::apply_fix(
            Fix::StrideScale { ratio_ppm: 10_000 },
            &mut file
        ));
        let k1 = file.model.accel_scale_factor.unwrap();
        assert!((k1 - ((1.0 + k0) * 1.01 - 1.0)).abs() < 1e-9, "{k1}");
    }
}
