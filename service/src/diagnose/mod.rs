//! Residual diagnosis (`corridor diagnose`): run the configured model, test its heading
//! residuals for consistency, rank the effects of a catalogue by the evidence in the residuals,
//! add the top effect to the model, run again and report the error before and after; repeat
//! while a significant, fixable effect remains.
//!
//! The residual is the heading innovation of each stance observation: the map direction minus
//! the foot heading the model predicts, `r = ψ_map − ψ̂_foot`, with its innovation variance
//! `S` (from the filter, or σ² in the bias-filter modes). Between two used observations the
//! runner accumulates the candidate regressors: elapsed time, the signed turn (from the map
//! directions: the gyro-integrated turn carries the stride-to-stride scatter of the foot angle,
//! which correlates with the residual by construction and looked like a 30–60 % scale factor),
//! the total rotation (∫|ω|), the specific-force excess (∫| |f| − g |), and the deviation of
//! the time steps from their median.
//!
//! Every stance also gives a residual, used or not: the foot axis and the stride direction
//! against the most likely (nearest) map direction, weighted by the association probability.
//! These feed the power analysis (`power`; its regression in `signature_fit`): each
//! parametric effect's signature (the residual a unit of it adds, through the model's attitude
//! and updates) is fitted to them, and the fit scores the scale factor, the axis misalignment
//! and the g-sensitivity and gives every measured effect its detectable size on this walk (or
//! says the walk cannot show it).
//!
//! Each fixable effect is also scored by a nested-model F test: the model with the effect added
//! against the current one, on the heading innovations (see [`score_by_likelihood`]); its score
//! is the larger of the two.
//!
//! Catalogue and test of each effect (scores are −log₁₀ p, significant from 3):
//! - `heading_offset`: the walking direction (stride displacement) differs from the map
//!   direction by a constant with the same sign on every direction (t test, and the one-way
//!   ANOVA across directions must not reject equal means);
//! - `bias_drift`: a trend of `r` in time (regression) or a drift/step in its cumulative sum
//!   (CUSUM), or the filter's bias estimate moving faster than its random walk allows
//!   (`bias_change`: a bias the filter followed leaves no trend in the residuals; its detectable
//!   step and ramp from probe injections, `drift_power`); the fix is
//!   bias-rate states for a ramp, a faster bias random walk for a step;
//! - `gyro_scale_factor`: `r` proportional to the signed turn since the last used observation;
//! - `g_sensitivity`: `r` proportional to ∫| |f| − g |, or the g-sensitivity signature, or the
//!   filter's bias moving along the specific force walking adds as walking begins (the onset
//!   test of `bias_change`: a bias has no reason to change then, a rate error that depends on
//!   the motion does); the fix is g-sensitivity states (`model.g_sensitivity_sd`);
//! - `axis_misalignment`: `r` proportional to the total rotation ∫|ω| (cadence), not to the turn,
//!   or the y→z / x→z coupling signatures; the fix is cross-coupling states into the sensor z
//!   axis (`model.gyro_coupling_z_sd_deg`);
//! - `timing`: `r` proportional to the time-step deviations (jitter, gaps), or a scale factor
//!   that is the same on every gyro axis and, with footprints, in the strides (`clock_rate`);
//! - `gyro_clipping`: the gyro runs into a rail below its configured range (flat tops in the
//!   data, `clipping`); the fix sets the range at the rail so its samples are flagged and the
//!   rotation lost there modelled;
//! - `mounting_tilt`: the accelerometer's tilt at stance differs from the tilt at the initial
//!   rest (only an effect for the paper's model, which takes the foot as flat);
//! - `unexplained`: the residuals are inconsistent (NIS above its χ² band or not white) and no
//!   effect of the catalogue reaches significance.
//!
//! Map of the submodules (their public items are re-exported here):
//! - `catalogue`: the effects ([`Effect`]) and fixes ([`Fix`]), which fixes each effect
//!   tries, and [`apply_fix`];
//! - `analysis`: one run of a model and its residuals ([`analyse`] → [`Analysis`],
//!   [`Consistency`], [`HeadingResidual`]);
//! - `ranking`: the evidence for each effect ([`Finding`]), the residual tests and the
//!   nested-model F test ([`score_by_likelihood`]);
//! - `bias_change`: whether the filter's own bias estimate moved more than its random walk
//!   allows ([`BiasChange`]), a second test of `bias_drift`, and whether it moved along the
//!   specific force of walking as walking began ([`OnsetChange`]), a test of `g_sensitivity`;
//! - `drift_power`: the smallest bias step and ramp the bias-change test detects on the walk,
//!   from probe injections ([`drift_mde`]);
//! - `clipping`: rails in the data below the configured gyro range ([`Rail`]);
//! - `clock_rate`: a clock-rate error told from a gyro scale factor (every axis alike, and the
//!   strides stretched by (1 + ε)² where footprints show them);
//! - `power`: the power of the walk for each effect: every stance's residual fitted on the
//!   effect's signature ([`Power`]);
//! - `signature_fit`: the regression behind `power`'s fits (weighted least squares of the
//!   stance residuals on a signature, with a Newey–West standard error);
//! - `stride_length`: the stride scale against the footprints, when they are given
//!   ([`StrideLength`]): an effect only position information shows, tried after the heading
//!   effects (its fix, the rolling-foot stance update, changes the navigation filter);
//! - `report`: `report.md`, `report.json` and `residuals.svg` ([`write_report`]);
//! - this file: the loop ([`run_diagnosis`] → [`Diagnosis`]).

mod analysis;
mod bias_change;
mod catalogue;
mod clipping;
mod clock_rate;
mod drift_power;
mod power;
mod ranking;
mod report;
mod signature_fit;
mod stride_length;

pub use analysis::{
    Analysis, Consistency, DIAGNOSIS_ALIGNED_PRIOR, HeadingResidual, ResidualKind, StanceResidual,
    analyse,
};
pub use bias_change::{BLOCK_S, BiasChange, BiasTrace, BlockChange, OnsetChange, onset_change};
pub use catalogue::{Effect, Fix, RAIL_OF_RANGE, apply_fix};
pub use clipping::{Rail, find_rails};
pub use drift_power::{
    DriftProbe, RAMP_FROM_FRACTION, STEP_AT_FRACTION, calibrate_drift, drift_mde, drift_words,
};
pub use power::{
    MDE_Z, MIN_RESPONSE, N_REFERENCES, PLACEBO_SHIFTS, Power, REFERENCES, Reference,
    calibrate_by_injection, format_unit, placebo_z, quarter_turns,
};
pub use ranking::{Candidate, Finding, score_by_likelihood};
pub use report::write_report;
pub use signature_fit::{HAC_LAGS, Row, SignatureFit, fit_signature};
pub use stride_length::{
    LegKind, MAX_LEG_M, MIN_CORNER_LEGS, MIN_LEG_M, MIN_LEGS, OUTLIER_SD, StrideLength, StrideLine,
    stride_length,
};

use crate::runner::RunError;
use corridor_shared::config::ConfigFile;
use corridor_shared::imu_csv::ImuLog;
use corridor_shared::truth_csv::TruthPoint;
use serde::Serialize;
use std::path::Path;

/// Score from which an effect counts as significant (p < 0.001).
pub const SIGNIFICANT: f64 = 3.0;
/// Residual-test score an effect needs before the F test can raise it (p < 0.05).
pub const CORROBORATED: f64 = 1.3;
/// Largest number of model extensions added in one diagnosis.
pub const MAX_ITERATIONS: usize = 3;

/// One step of the loop: the effect added and the model before and after.
#[derive(Debug, Clone, Serialize)]
pub struct Iteration {
    /// Effect added.
    pub effect: Effect,
    /// Its score when it was chosen.
    pub score: f64,
    /// Config change.
    pub fix: Fix,
    /// Before.
    pub before: Consistency,
    /// After.
    pub after: Consistency,
    /// For a fix fitted on the footprints (the stride scale): its check on footprints it was
    /// not fitted on.
    pub held_out: Option<HeldOut>,
    /// Kept (the error or, without truth, the NIS/whiteness improved).
    pub kept: bool,
}

/// How a fix fitted on the footprints (the stride scale) was checked on footprints it was not
/// fitted on: the error there without and with it, m. The loop keeps it only when that fell.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum HeldOut {
    /// Fitted on the first half of the footprints (by time): the footprint RMS of the second
    /// half alone.
    SecondHalf {
        /// Without and with the fix, m.
        rms_m: [f64; 2],
    },
    /// A walk surveyed at its corners, whose first half has too few legs to fit: each corner
    /// leg held out in turn, the scale fitted on the others and the walk run with it; the RMS
    /// over the legs of the held-out leg's length error.
    EachLeg {
        /// Legs held out (those the whole walk's fit keeps).
        legs: usize,
        /// Without and with the fix, m.
        rms_m: [f64; 2],
    },
}

impl HeldOut {
    /// The held-out error without and with the fix, m.
    pub fn rms_m(self) -> [f64; 2] {
        match self {
            HeldOut::SecondHalf { rms_m } | HeldOut::EachLeg { rms_m, .. } => rms_m,
        }
    }
}

/// `report.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// The effects ranked on the starting model.
    pub effects: Vec<Finding>,
    /// The first effect, or `none` when nothing is significant.
    pub top_effect: String,
    /// The verdict in words: the top effect, or what the walk could have shown (the detectable
    /// sizes) and what it cannot show.
    pub verdict: String,
    /// The effects whose signature on this walk is indistinguishable from the top effect's
    /// (|ρ| above [`power::INDISTINGUISHABLE_CORRELATION`]), as `effect (variant, ρ)`: the heading
    /// residuals cannot tell the top effect from these.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub top_indistinguishable_from: Vec<String>,
    /// When the top effect's score is the signature fit of a variant this walk cannot show:
    /// that, in words ([`power::named_but_cannot_show`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub verdict_caveat: Option<String>,
    /// The power of the walk on the starting model, per effect variant.
    pub power: Vec<Power>,
    /// The bias change that came with the onset of walking, on the starting model, with its
    /// detectable g-sensitivity.
    pub onset: Option<OnsetChange>,
    /// The test of the filter's bias against its random walk, on the starting model, with the
    /// bias step and ramp it detects on this walk.
    pub bias_change: Option<BiasChange>,
    /// The stride length against the footprints (with truth only), on the model the heading
    /// effects left: the line the loop's last step acted on.
    pub stride_length: Option<StrideLine>,
    /// What the scoring of the footprints warned of (e.g. footprints outside the log's span,
    /// clamped to its ends: the footprint RMS before and after counts them).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub truth_warnings: Vec<String>,
    /// The starting model.
    pub before: Consistency,
    /// The final model.
    pub after: Consistency,
    /// The loop.
    pub iterations: Vec<Iteration>,
    /// Effects of the final model.
    pub final_effects: Vec<Finding>,
    /// The final model's extensions.
    pub final_model: Vec<String>,
    /// What the final model's sensor-error states estimated, in words (the size of the effect
    /// the loop added), e.g. `z←x coupling +1.93° ± 0.41°`.
    pub final_estimates: Vec<String>,
}

/// What a diagnosis found: the report, the analyses of the starting and the final model, and
/// the final model's configuration.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    /// `report.json`.
    pub report: Report,
    /// The analysis of the starting model.
    pub before: Analysis,
    /// The analysis of the final model.
    pub after: Analysis,
    /// The final model.
    pub final_model: ConfigFile,
}

/// Did the model improve? With truth: the footprint error fell. Without: the NIS moved toward
/// 1 or the whiteness p-value rose, and neither got clearly worse.
fn improved(before: &Consistency, after: &Consistency) -> bool {
    match (before.gcp_rms_m, after.gcp_rms_m) {
        (Some(b), Some(a)) => a < b,
        _ => {
            let d = |c: &Consistency| (c.nis_mean.ln()).abs();
            d(after) < d(before) || after.whiteness_p > before.whiteness_p
        }
    }
}

/// The stride scale of `file`'s run fitted on the first half of the footprints (by time), and
/// the footprint RMS of the second half alone without and with it taken out, m; `None` when the
/// first half has too few legs to fit (fewer than [`MIN_LEGS`] single strides and fewer than
/// [`MIN_CORNER_LEGS`] legs after the outlier rule: a walk surveyed at its four or five corners
/// never has enough; [`stride_scale_each_leg_held_out`] checks those) or the second half cannot
/// be scored.
fn stride_scale_out_of_sample(
    log: &ImuLog,
    file: &ConfigFile,
    truth: &[TruthPoint],
    map: Option<&Path>,
) -> Result<Option<(Fix, HeldOut)>, RunError> {
    let mid = truth.len() / 2;
    let (first, second) = (&truth[..=mid], &truth[mid..]);
    let Some(fit) = analyse(log, file, Some(first), map)?.stride_length else {
        return Ok(None);
    };
    let fix = Fix::stride_scale(fit.ratio);
    let mut fixed = file.clone();
    if !apply_fix(fix, &mut fixed) {
        return Ok(None);
    }
    let rms = |f: &ConfigFile| -> Result<Option<f64>, RunError> {
        Ok(analyse(log, f, Some(second), map)?.consistency.gcp_rms_m)
    };
    Ok(rms(file)?
        .zip(rms(&fixed)?)
        .map(|(b, a)| (fix, HeldOut::SecondHalf { rms_m: [b, a] })))
}

/// The stride scale of a walk surveyed at its corners (`current`: `file` analysed on all of
/// `truth`), fitted on all its legs, and checked leg by leg: each leg the fit keeps is held out
/// in turn, the scale fitted on the others ([`stride_length::corner_scale`]), the walk run with
/// that scale taken out, and the held-out leg's length error compared with the run's without it.
/// `None` when the fit is not a corner-leg fit. Leaving a leg out of four leaves three, fewer
/// than the fit's test needs but enough to predict the fourth.
fn stride_scale_each_leg_held_out(
    log: &ImuLog,
    file: &ConfigFile,
    current: &Analysis,
    truth: &[TruthPoint],
    map: Option<&Path>,
) -> Result<Option<(Fix, HeldOut)>, RunError> {
    let kept = stride_length::kept_corner_legs(&current.legs);
    let Some(fit) = current
        .stride_length
        .filter(|_| kept.len() >= MIN_CORNER_LEGS)
    else {
        return Ok(None);
    };
    let mut squares = [0.0; 2];
    for &i in &kept {
        let others: Vec<(f64, f64)> = kept
            .iter()
            .filter(|&&j| j != i)
            .filter_map(|&j| current.legs[j])
            .collect();
        let (Some(ratio), Some((before_m, surveyed_m))) =
            (stride_length::corner_scale(&others), current.legs[i])
        else {
            return Ok(None);
        };
        let mut fixed = file.clone();
        // (a scale of exactly 1 is no change: the leg is what it was)
        let after_m = if apply_fix(Fix::stride_scale(ratio), &mut fixed) {
            match analyse(log, &fixed, Some(truth), map)?.legs.get(i) {
                Some(&Some((e, _))) => e,
                _ => return Ok(None),
            }
        } else {
            before_m
        };
        squares[0] += (before_m - surveyed_m).powi(2);
        squares[1] += (after_m - surveyed_m).powi(2);
    }
    let n = kept.len();
    Ok(Some((
        Fix::stride_scale(fit.ratio),
        HeldOut::EachLeg {
            legs: n,
            rms_m: squares.map(|s| (s / n as f64).sqrt()),
        },
    )))
}

/// The first step of the loop: `start` analysed, every fixable effect scored (and its
/// candidate model), and the power of each effect with its response measured by injection.
/// What the loop starts from, and all that a check of what is named, and of the detectable
/// sizes, needs.
pub fn judge(
    log: &ImuLog,
    start: &ConfigFile,
    truth: Option<&[TruthPoint]>,
    map: Option<&Path>,
) -> Result<(Analysis, Vec<Candidate>), RunError> {
    let (mut first, candidates) = judge_names(log, start, truth, map)?;
    power::calibrate_by_injection(log, start, map, &mut first)?;
    Ok((first, candidates))
}

/// What [`judge`] names, without the detectable sizes: `start` analysed and every fixable
/// effect scored, the probe injections that only measure sizes left out (the scores do not
/// depend on them). The detection matrix's scan judges its injected walks so.
pub fn judge_names(
    log: &ImuLog,
    start: &ConfigFile,
    truth: Option<&[TruthPoint]>,
    map: Option<&Path>,
) -> Result<(Analysis, Vec<Candidate>), RunError> {
    let mut first = analyse(log, start, truth, map)?;
    // Footprints that cannot be scored are refused, as `corridor run` refuses them (the report
    // said "footprint RMS n/a", exit 0, a review).
    if let Some(e) = first.truth_error.take() {
        return Err(RunError::TruthUnusable(e));
    }
    let candidates = score_by_likelihood(log, start, &mut first, truth, map)?;
    Ok((first, candidates))
}

/// The whole loop: analyse `start`, add the top significant effect while one has a fix and
/// the model improves (at most [`MAX_ITERATIONS`] times); then, with footprints, the stride
/// length's fix when it is significant (kept when the footprint error falls).
pub fn run_diagnosis(
    log: &ImuLog,
    start: &ConfigFile,
    truth: Option<&[TruthPoint]>,
    map: Option<&Path>,
) -> Result<Diagnosis, RunError> {
    let (first, mut candidates) = judge(log, start, truth, map)?;
    let mut current = first.clone();
    let mut file = start.clone();
    let mut iterations = Vec::new();
    for _ in 0..MAX_ITERATIONS {
        let Some(top) = current
            .effects
            .first()
            .filter(|e| e.score >= SIGNIFICANT)
            .cloned()
        else {
            break;
        };
        let Some(cand) = candidates.iter().find(|c| c.effect == top.name).cloned() else {
            break; // significant but corridor has no fix for it
        };
        let kept = improved(&current.consistency, &cand.analysis.consistency);
        iterations.push(Iteration {
            effect: top.name,
            score: top.score,
            fix: cand.fix,
            before: current.consistency.clone(),
            after: cand.analysis.consistency.clone(),
            held_out: None,
            kept,
        });
        if !kept {
            break;
        }
        file = cand.file;
        current = cand.analysis;
        candidates = score_by_likelihood(log, &file, &mut current, truth, map)?;
    }
    // Then the stride length, which only the footprints show: its fix changes the navigation
    // filter, so it comes after the heading effects were judged on the model they were built on
    // (and last: the heading effects are not tried again on the fixed model).
    let mut stride_line = current.stride_line(&file);
    if let Some(top) = stride_line
        .as_ref()
        .map(|l| &l.finding)
        .filter(|f| f.score >= SIGNIFICANT)
        .cloned()
    {
        let mut f = file.clone();
        // The stride scale is fitted on the footprints themselves: it is fitted on the first
        // half of them and must lower the second half's error alone, so that "the error fell"
        // is not true by construction.
        let (fix, held_out) = match (top.fix, truth) {
            (Some(Fix::StrideScale { .. }), Some(t)) => {
                let checked = match stride_scale_out_of_sample(log, &file, t, map)? {
                    Some(c) => Some(c),
                    None => stride_scale_each_leg_held_out(log, &file, &current, t, map)?,
                };
                match checked {
                    Some((fix, held_out)) => (Some(fix), Some(held_out)),
                    None => {
                        // Not tried, and said so: the line offers the fix, the loop has no step.
                        if let Some(l) = stride_line.as_mut() {
                            l.finding.evidence.push_str(
                                "; the scale fix is not tried: it could not be checked on \
                                 footprints it was not fitted on (the first half of them is too \
                                 few legs to fit it, and there are no corner legs to hold out in \
                                 turn)",
                            );
                        }
                        (None, None)
                    }
                }
            }
            (fix, _) => (fix, None),
        };
        if let Some(fix) = fix.filter(|&fix| apply_fix(fix, &mut f)) {
            let mut a = analyse(log, &f, truth, map)?;
            // (and the whole walk's error must fall too, as for every other fix)
            let kept = held_out.is_none_or(|h| h.rms_m()[1] < h.rms_m()[0])
                && improved(&current.consistency, &a.consistency);
            iterations.push(Iteration {
                effect: top.name,
                score: top.score,
                fix,
                before: current.consistency.clone(),
                after: a.consistency.clone(),
                held_out,
                kept,
            });
            if kept {
                score_by_likelihood(log, &f, &mut a, truth, map)?;
                file = f;
                current = a;
            }
        }
    }
    let top = first.effects.first().filter(|e| e.score >= SIGNIFICANT);
    let report = Report {
        top_effect: top.map_or("none".to_string(), |e| e.name.to_string()),
        verdict: top.map_or_else(
            || {
                power::nothing_found(
                    &first.power,
                    &first.effects,
                    first.onset.as_ref(),
                    first.bias_change.as_ref(),
                    first.bias_change_applies,
                )
            },
            |e| format!("{} (score {:.1})", e.name, e.score),
        ) + &if first.heading_never_held {
            format!(
                "; but the starting model fused none of its {} heading observations (foot axis \
                 and stride direction): its heading was never held by the map, and the residuals \
                 measure how far off its corridors it is, which a start in a weave or a wrong \
                 start heading does as well as an effect",
                first.stances.len()
            )
        } else {
            String::new()
        },
        verdict_caveat: top.and_then(|e| power::named_but_cannot_show(&first.power, e)),
        top_indistinguishable_from: top.map_or_else(Vec::new, |e| {
            power::indistinguishable_from_named(&first.power, e)
                .into_iter()
                .map(|(effect, variant, rho)| format!("{effect} ({variant}, ρ = {rho:+.2})"))
                .collect()
        }),
        power: first.power.clone(),
        onset: first.onset,
        bias_change: first.bias_change.clone(),
        stride_length: stride_line,
        truth_warnings: first.truth_warnings.clone(),
        effects: first.effects.clone(),
        before: first.consistency.clone(),
        after: current.consistency.clone(),
        iterations,
        final_effects: current.effects.clone(),
        final_model: analysis::final_model_words(start, &file),
        final_estimates: current.estimates_in_words(),
    };
    Ok(Diagnosis {
        report,
        before: first,
        after: current,
        final_model: file,
    })
}
