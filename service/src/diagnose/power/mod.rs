//! The power of a walk for each effect: what a known amount of the effect does to the heading
//! residuals of every stance, the size of the effect the residuals show, and the smallest size
//! this walk can show at the ranking's false-alarm rate.
//!
//! Method (a matched filter): each parametric effect of [`REFERENCES`] makes a known gyro
//! error per unit of its size (a z scale factor `s` adds `s·ω_z` to the z rate). Along the run
//! of the model under diagnosis, that error is turned into the navigation frame with the
//! model's attitude and its vertical part integrated: the yaw error a unit of the effect would
//! have built up at each stance (the mounting tilt projects a sensor-axis error onto the
//! vertical, and the foot's swing adds what the turns alone do not). At every heading update
//! the filter removes part of it, so the accumulated error is multiplied by `R/S` (what the
//! update leaves). The residual of each stance (foot axis and stride direction, used or not) is
//! `r = −(yaw error)`, so minus this accumulated error is the effect's *signature* `g` on this
//! walk. The residuals are regressed on `g` with one intercept per residual kind and weights
//! `w/σ²` (association weight over the kind's residual variance): `β̂` estimates the effect's
//! size in its own unit. The signature is computed from the model's own run, not by running an
//! injected log again: a re-run changes which observations the filter accepts, and such a
//! change correlates the difference of the residuals with the residuals themselves (tried
//! first: it named an axis misalignment on 9 of 14 walks with a bias ramp or a z scale
//! injected). Consecutive stances share accumulated gyro error, so the standard error is the
//! Newey–West (Bartlett, [`HAC_LAGS`]) sandwich, not the textbook one. The score is −log₁₀ of
//! the two-sided normal p of `β̂/se`; the detectable size (MDE) is `z·se` with `z` = 3.29, the
//! two-sided quantile of p = 10⁻³ ([`SIGNIFICANT`]): the size whose expected score is the
//! threshold, detected half the time. A walk *cannot show* an effect when that size is beyond
//! any plausible one ([`Reference::plausible_max`]). The detection matrix
//! (`corridor diagnose --suite`) checks these sizes against injections.
//!
//! `calibration`: the response of each signature to a probe injection, which scales the size,
//! and the size checked by injection at twice itself, raised or refused where the walk does not
//! bear it out ([`calibrate_by_injection`]).

use super::SIGNIFICANT;
use super::analysis::{Analysis, analyse};
use super::analysis::{ResidualKind, StanceResidual};
use super::catalogue::Effect;
use super::ranking::Finding;
use super::signature_fit::{HAC_LAGS, Row, SignatureFit, fit_signature, reweighted_fit};
use crate::runner::RunError;
use corridor_shared::config::ConfigFile;
use corridor_shared::imu_csv::ImuLog;
use corridor_shared::injection::LogInjection;
use nalgebra::Vector3;
use serde::Serialize;
use std::collections::HashMap;
use std::path::Path;

/// Signatures that correlate above this cannot be told apart on the walk.
pub const INDISTINGUISHABLE_CORRELATION: f64 = 0.9;

/// The power of a walk for one effect (one variant: an effect such as the axis misalignment has
/// one per coupling).
#[derive(Debug, Clone, Serialize)]
pub struct Power {
    /// The effect.
    pub effect: Effect,
    /// The variant (`z scale`, `y→z coupling` …).
    pub variant: &'static str,
    /// Unit of `estimate`, `std_err` and `mde`.
    pub unit: &'static str,
    /// The size the residuals show, `β̂`.
    pub estimate: f64,
    /// Its Newey–West standard error.
    pub std_err: f64,
    /// −log₁₀ p of `β̂/se`.
    pub score: f64,
    /// The smallest size this walk shows at p < 10⁻³ half the time; `None` when it cannot show
    /// the effect.
    pub mde: Option<f64>,
    /// Why the walk cannot show the effect.
    pub cannot: Option<String>,
    /// Residuals in the fit.
    pub residuals: usize,
    /// The part of the signature an injected amount really shows in the residuals (the fit of
    /// their change on the signature): below 1 where the filter's bias state absorbs the
    /// effect. `None` until measured ([`calibrate_by_injection`]).
    pub response: Option<f64>,
    /// The detectable size before the response is taken into account (`z·se`).
    pub mde_signature: Option<f64>,
    /// The sizes at which the check of the detectable size by injection failed before `mde`
    /// passed it, each with the score the check took (the injected fit's own, or its shift's
    /// where the clean fit is significant) and the shift of the estimate there
    /// ([`calibration`]'s `checked_mde`): empty where the probe's prediction passed at once.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub mde_check_failed: Vec<[f64; 3]>,
    /// Other variants whose signature correlates above [`INDISTINGUISHABLE_CORRELATION`] with
    /// this one, with the correlation.
    pub indistinguishable_from: Vec<(String, f64)>,
}

impl Power {
    /// `size` in words, in the unit people use for it (%, °, rad/s² …).
    pub fn format_size(&self, size: f64) -> String {
        format_unit(self.unit, size)
    }
}

/// The gyro error of a unit amount of an effect, from the measured rate, the specific force and
/// the specific force of the initial rest (all sensor axes).
pub type RateError = fn(w: &Vector3<f64>, f: &Vector3<f64>, f_rest: &Vector3<f64>) -> Vector3<f64>;

/// A parametric effect whose power is measured, with the gyro error a unit amount of it makes.
#[derive(Debug, Clone, Copy)]
pub struct Reference {
    /// Effect.
    pub effect: Effect,
    /// Variant.
    pub variant: &'static str,
    /// Unit of the size.
    pub unit: &'static str,
    /// Larger than any plausible value of a working sensor: a detectable size beyond it means
    /// the walk cannot show the effect.
    pub plausible_max: f64,
    /// The gyro error, rad/s in sensor axes, of a unit amount of the effect, from the measured
    /// rate `w` and specific force `f` and the specific force `f_rest` of the initial rest (whose
    /// gyro mean is the bias prior, so a constant error there is absorbed).
    pub rate_error: RateError,
    /// The amount injected to measure the response ([`calibrate_by_injection`]).
    pub probe_size: f64,
    /// The injection of `size` of the effect.
    pub probe: fn(size: f64) -> LogInjection,
}

/// The effects whose power is measured by a signature (bias drift and heading offset keep their
/// own tests and sizes: the bias state follows a drift, whose sizes are the bias-change test's,
/// [`super::drift_power`]; an offset is constant, like the intercept).
pub const REFERENCES: [Reference; 5] = [
    Reference {
        effect: Effect::GyroScaleFactor,
        variant: "z scale",
        unit: "fraction",
        plausible_max: 0.2,
        rate_error: |w, _, _| Vector3::new(0.0, 0.0, w.z),
        probe_size: 0.05,
        probe: |s| LogInjection::GyroScale {
            axis: 2,
            fraction: s,
        },
    },
    Reference {
        effect: Effect::AxisMisalignment,
        variant: "y→z coupling",
        unit: "rad",
        plausible_max: 0.2,
        rate_error: |w, _, _| Vector3::new(0.0, 0.0, w.y),
        probe_size: 0.034_906_585_039_886_59,
        probe: |s| LogInjection::GyroCoupling {
            from: 1,
            to: 2,
            coupling_rad: s,
        },
    },
    Reference {
        effect: Effect::AxisMisalignment,
        variant: "x→z coupling",
        unit: "rad",
        plausible_max: 0.2,
        rate_error: |w, _, _| Vector3::new(0.0, 0.0, w.x),
        probe_size: 0.034_906_585_039_886_59,
        probe: |s| LogInjection::GyroCoupling {
            from: 0,
            to: 2,
            coupling_rad: s,
        },
    },
    Reference {
        effect: Effect::Timing,
        variant: "clock rate",
        unit: "fraction",
        plausible_max: 0.2,
        rate_error: |w, _, _| *w,
        probe_size: 0.03,
        probe: |s| LogInjection::ClockRate { fraction: s },
    },
    Reference {
        effect: Effect::GSensitivity,
        variant: "g-sensitivity",
        unit: "rad/s per m/s²",
        plausible_max: 2e-2,
        rate_error: |_, f, f_rest| f - f_rest,
        probe_size: 2e-3,
        probe: |s| LogInjection::GSensitivity {
            k_rad_s_per_m_s2: s,
        },
    },
];

/// Number of [`REFERENCES`] (the length of [`StanceResidual::signature`]).
pub const N_REFERENCES: usize = REFERENCES.len();

/// Placebo fits per walk and effect (see [`placebo_z`]).
pub const PLACEBO_SHIFTS: usize = 19;

/// Placebo fits of reference `k`: its signature moved along the walk by `shifts` circular
/// offsets spread over the middle half of the walk (from a quarter to three quarters of the
/// residuals, far beyond the Newey–West window), so that it lines up with nothing the walk
/// does, fitted as the real one (marginally, with the same reweighting). Where the standard
/// error is right their `β̂/se` are standard normal; an RMS well above 1 says it is too small.
pub fn placebo_z(base: &[StanceResidual], k: usize, shifts: usize) -> Vec<f64> {
    let pairs: Vec<(&StanceResidual, f64)> = base
        .iter()
        .filter(|s| s.signature[k].is_finite())
        .map(|s| (s, s.signature[k]))
        .collect();
    let n = pairs.len();
    if n < 8 || shifts == 0 {
        return Vec::new();
    }
    (0..shifts)
        .filter_map(|j| {
            let frac = 0.25 + 0.5 * j as f64 / (shifts.max(2) - 1) as f64;
            let offset = ((frac * n as f64).round() as usize).clamp(1, n - 1);
            let shifted: Vec<(&StanceResidual, f64)> = (0..n)
                .map(|i| (pairs[i].0, pairs[(i + offset) % n].1))
                .collect();
            let (_, fit) = reweighted_fit(&shifted);
            fit.map(|f| f.beta / f.std_err).filter(|z| z.is_finite())
        })
        .collect()
}

/// Fits the residuals of every stance on each effect's signature.
pub fn walk_power(base: &[StanceResidual]) -> Vec<Power> {
    let turns = quarter_turns(base);
    let signature = |i: usize| -> Vec<Option<f64>> {
        base.iter()
            .map(|s| Some(s.signature[i]).filter(|v| v.is_finite()))
            .collect()
    };
    let signatures: Vec<Vec<Option<f64>>> = (0..N_REFERENCES).map(signature).collect();
    let mut out = Vec::new();
    // the first reference's final weights and fit, for the partial tests of the others
    let mut primary: Option<(Vec<f64>, SignatureFit)> = None;
    for (i, reference) in REFERENCES.iter().enumerate() {
        let partial = PARTIAL.contains(&reference.effect);
        let pairs: Vec<(&StanceResidual, f64)> = base
            .iter()
            .zip(&signatures[i])
            .filter_map(|(s, g)| g.map(|g| (s, g)))
            .collect();
        let (mut rows, mut fit) = reweighted_fit(&pairs);
        if let (Some((w0, f0)), true) = (&primary, partial) {
            // Frisch–Waugh: both the residual and this signature with the first reference's
            // signature (its fit, its weights) taken out; what is left is what this effect
            // explains beyond it.
            let g0: Vec<f64> = base
                .iter()
                .zip(&signatures[i])
                .zip(&signatures[0])
                .filter_map(|((_, g), g0)| g.and(Some(g0.unwrap_or(0.0))))
                .collect();
            let w_rows: Vec<Row> = rows
                .iter()
                .zip(w0)
                .zip(&g0)
                .map(|((r, &w), &x0)| Row {
                    weight: w,
                    y: x0,
                    ..*r
                })
                .collect();
            // γ: this signature on the first one (regress x on x0 with the first's weights)
            let xs: Vec<Row> = w_rows
                .iter()
                .zip(&rows)
                .map(|(a, r)| Row {
                    y: r.x,
                    x: a.y,
                    ..*a
                })
                .collect();
            let gamma = fit_signature(&xs, 0).map_or(0.0, |f| f.beta);
            rows = w_rows
                .iter()
                .zip(&rows)
                .map(|(a, r)| Row {
                    group: r.group,
                    weight: a.weight,
                    y: r.y - f0.beta * a.y,
                    x: r.x - gamma * a.y,
                })
                .collect();
            fit = fit_signature(&rows, HAC_LAGS);
        }
        if i == 0 {
            primary = fit
                .clone()
                .map(|f| (rows.iter().map(|r| r.weight).collect(), f));
        }
        // Too few residuals, or a size no sensor has: a degenerate fit, whose standard error
        // says nothing (a review: 3 residuals of a 10 s log gave a z scale of −99 % at score 30;
        // a straight leg, an x→z coupling of −33° at 9.5 σ).
        let few = rows.len() < MIN_FIT_RESIDUALS;
        let beyond = fit
            .as_ref()
            .is_some_and(|f| f.beta.abs() > DEGENERATE_FACTOR * reference.plausible_max);
        let mde = fit.as_ref().map(|f| MDE_Z * f.std_err);
        let cannot = match mde {
            _ if few => Some(format!(
                "{} stance residuals are too few to fit (at least {MIN_FIT_RESIDUALS})",
                rows.len()
            )),
            Some(_) if beyond => Some(format!(
                "its fit gives {}, beyond {DEGENERATE_FACTOR} × any plausible {}: the walk does not tell it from the residuals' mean (it turns {turns:.1} quarter turns)",
                format_unit(reference.unit, fit.as_ref().map_or(f64::NAN, |f| f.beta)),
                format_unit(reference.unit, reference.plausible_max),
            )),
            Some(m) if m.is_finite() && m <= reference.plausible_max => None,
            _ => Some(format!(
                "the smallest size it shows would be {} (beyond any plausible {}); the walk turns {:.1} quarter turns",
                mde.filter(|m| m.is_finite())
                    .map_or("unbounded".into(), |m| format_unit(reference.unit, m)),
                format_unit(reference.unit, reference.plausible_max),
                turns
            )),
        };
        if few || beyond {
            fit = None;
            if i == 0 {
                primary = None;
            }
        }
        let mut indistinguishable = Vec::new();
        for (j, other) in REFERENCES.iter().enumerate() {
            if j != i
                && other.effect != reference.effect
                && let Some(rho) = correlation(base, &signatures[i], &signatures[j])
                && rho.abs() > INDISTINGUISHABLE_CORRELATION
            {
                indistinguishable.push((other.variant.to_string(), rho));
            }
        }
        out.push(Power {
            effect: reference.effect,
            variant: reference.variant,
            unit: reference.unit,
            estimate: fit.as_ref().map_or(f64::NAN, |f| f.beta),
            std_err: fit.as_ref().map_or(f64::NAN, |f| f.std_err),
            score: fit.as_ref().map_or(0.0, |f| z_score(f.beta / f.std_err)),
            mde: if cannot.is_none() { mde } else { None },
            mde_signature: mde,
            mde_check_failed: Vec::new(),
            response: None,
            cannot,
            residuals: rows.len(),
            indistinguishable_from: indistinguishable,
        });
    }
    out
}

/// The score of a fit's `z = β̂/se`: −log₁₀ of its two-sided normal p (0 for a NaN `z`: no fit).
fn z_score(z: f64) -> f64 {
    super::ranking::score(2.0 * (1.0 - crate::stats::normal_cdf(z.abs())))
}

/// Fewer stance residuals than this make no signature fit (a 10 s log has 3).
pub const MIN_FIT_RESIDUALS: usize = 12;

/// A fitted size beyond this many times [`Reference::plausible_max`] is no sensor's: the fit is
/// degenerate (a signature that the walk does not tell from the residuals' mean).
pub const DEGENERATE_FACTOR: f64 = 2.0;

/// Below this response the model absorbs the effect: the walk cannot show it.
pub const MIN_RESPONSE: f64 = 0.1;

/// Effects tested beyond the first reference (the z scale factor): their signature and the
/// residuals with the scale factor's signature taken out. A cross-coupling into yaw and a
/// g-sensitivity act mostly through the turns as a scale factor does (the mounting tilt
/// projects them onto the vertical), so only what they explain beyond it names them.
pub const PARTIAL: [Effect; 2] = [Effect::AxisMisalignment, Effect::GSensitivity];

/// The two-sided normal quantile of p = 10⁻³ (the [`SIGNIFICANT`] score): the detectable size
/// is this many standard errors.
pub const MDE_Z: f64 = 3.290_526_731_491_926;

/// `v` in words in `unit` (a [`Reference::unit`]): a fraction in %, rad in °, others as they are.
pub fn format_unit(unit: &str, v: f64) -> String {
    match unit {
        "fraction" => format!("{:.2} %", 100.0 * v),
        "rad" => format!("{:.2}°", v.to_degrees()),
        u => format!("{v:.2e} {u}"),
    }
}

/// Quarter turns of the walk: the summed change of the most likely direction between
/// consecutive foot-axis stances that walk along it (weight > 0.5), over 90°.
pub fn quarter_turns(stances: &[StanceResidual]) -> f64 {
    let mut last: Option<f64> = None;
    let mut sum = 0.0;
    for s in stances
        .iter()
        .filter(|s| s.kind == ResidualKind::FootAxis && s.weight > 0.5)
    {
        if let Some(d) = last {
            sum += crate::core::rotation::wrap_pi(s.direction_rad - d).abs();
        }
        last = Some(s.direction_rad);
    }
    sum / std::f64::consts::FRAC_PI_2
}

/// Weighted correlation of two signatures over the stances both have.
fn correlation(base: &[StanceResidual], a: &[Option<f64>], b: &[Option<f64>]) -> Option<f64> {
    let pts: Vec<(f64, f64, f64)> = base
        .iter()
        .zip(a.iter().zip(b))
        .filter_map(|(s, (x, y))| Some((s.weight, (*x)?, (*y)?)))
        .collect();
    let sw: f64 = pts.iter().map(|p| p.0).sum();
    if sw <= 0.0 {
        return None;
    }
    let mx = pts.iter().map(|p| p.0 * p.1).sum::<f64>() / sw;
    let my = pts.iter().map(|p| p.0 * p.2).sum::<f64>() / sw;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (w, x, y) in &pts {
        sxy += w * (x - mx) * (y - my);
        sxx += w * (x - mx).powi(2);
        syy += w * (y - my).powi(2);
    }
    let r = sxy / (sxx * syy).sqrt();
    r.is_finite().then_some(r)
}

/// The effects whose score is their signature test's (in the error-state modes).
const SCORED_BY_SIGNATURE: [Effect; 3] = [
    Effect::GyroScaleFactor,
    Effect::AxisMisalignment,
    Effect::GSensitivity,
];

/// Puts the power into the findings: the signature test scores the effects that only it tests
/// well (scale factor, axis misalignment, g-sensitivity: the best variant); for timing and bias
/// drift, whose own tests stay, it adds the detectable size to the evidence. With `score` false
/// (the bias-filter modes: their heading observations correct the bias, not the heading, which
/// the signature's `R/S` does not model, and the signature then grows like a drift) the
/// evidence is added and the residual tests keep scoring.
///
/// An effect the signature test scores gets its finding even where the residual regression on
/// the used heading observations has none (fewer than eight used, or its regressor did not
/// vary): the signature is fitted to every stance's residual, and a walk whose heading
/// observations the effect itself drove outside the gate is where it shows most.
pub fn apply_power(effects: &mut Vec<Finding>, power: &[Power], score: bool) {
    if score {
        for p in power {
            if SCORED_BY_SIGNATURE.contains(&p.effect)
                && !effects.iter().any(|f| f.name == p.effect)
            {
                effects.push(Finding {
                    name: p.effect,
                    score: 0.0,
                    evidence: "not tested (too few used heading observations, or its \
                               regressor did not vary)"
                        .into(),
                    fix: p.effect.fixes().first().map(|&(fix, _)| fix),
                    mde: None,
                });
            }
        }
    }
    for f in effects.iter_mut() {
        let mine: Vec<&Power> = power.iter().filter(|p| p.effect == f.name).collect();
        let Some(best) = mine.iter().max_by(|a, b| a.score.total_cmp(&b.score)) else {
            continue;
        };
        let words: Vec<String> = mine
            .iter()
            .map(|p| {
                let size = match (&p.mde, &p.cannot) {
                    (Some(m), _) => format!(
                        "detectable from {} if the residuals follow the signature",
                        p.format_size(*m)
                    ),
                    (None, Some(why)) => format!("this walk cannot show it: {why}"),
                    _ => String::new(),
                };
                let confused = if p.indistinguishable_from.is_empty() {
                    String::new()
                } else {
                    format!(
                        "; on this walk indistinguishable from {}",
                        p.indistinguishable_from
                            .iter()
                            .map(|(v, r)| format!("{v} (ρ = {r:+.2})"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                };
                let fit = if p.estimate.is_finite() {
                    format!(
                        "signature fit {} ± {}",
                        p.format_size(p.estimate),
                        p.format_size(p.std_err)
                    )
                } else {
                    "no signature fit".to_string()
                };
                format!(
                    "{}: {fit} over {} stance residuals (score {:.1}), {size}{confused}",
                    p.variant, p.residuals, p.score
                )
            })
            .collect();
        let scored_here = score && SCORED_BY_SIGNATURE.contains(&f.name);
        if scored_here {
            f.score = best.score;
            f.evidence = format!("{}; residual regression: {}", words.join("; "), f.evidence);
        } else {
            f.evidence = format!("{}; {}", f.evidence, words.join("; "));
        }
        f.mde = best.mde;
    }
    effects.sort_by(|a, b| b.score.total_cmp(&a.score));
}

/// The caveat for a `named` effect whose score is the signature fit of a variant this walk
/// cannot show (its detectable size is beyond any plausible one, or its probe injection barely
/// moves the residuals): the report named it and said, a column further, that the walk cannot
/// show it (a review: exp38's clean walk named a z scale at 7.2 whose probe moved the residuals
/// by −53 % of its signature).
pub fn named_but_cannot_show(power: &[Power], named: &Finding) -> Option<String> {
    power
        .iter()
        .filter(|p| p.effect == named.name && p.score == named.score)
        .find_map(|p| {
            p.cannot.as_ref().map(|why| {
                format!(
                    "this walk cannot show {} ({why}): the score {:.1} is its signature \
                     fit's, which no size the walk can show confirms",
                    p.variant, p.score
                )
            })
        })
}

/// The other effects whose signature on this walk is indistinguishable from the `named`
/// effect's (its best-scoring variant's [`Power::indistinguishable_from`]), as `(effect, variant,
/// ρ)`, best correlated first: the heading residuals cannot tell the named effect from these, so
/// the name is no more confident than the alternatives'. Empty for an effect without a signature
/// fit (a heading offset, a bias drift, clipping).
pub fn indistinguishable_from_named(
    power: &[Power],
    named: &Finding,
) -> Vec<(Effect, String, f64)> {
    let Some(best) = power
        .iter()
        .filter(|p| p.effect == named.name)
        .max_by(|a, b| a.score.total_cmp(&b.score))
    else {
        return Vec::new();
    };
    let mut out: Vec<(Effect, String, f64)> = best
        .indistinguishable_from
        .iter()
        .filter_map(|(variant, rho)| {
            REFERENCES
                .iter()
                .find(|r| r.variant == variant)
                .map(|r| (r.effect, variant.clone(), *rho))
        })
        .collect();
    out.sort_by(|a, b| b.2.abs().total_cmp(&a.2.abs()));
    out
}

/// The verdict when nothing is significant: the detectable sizes of the effects the walk can
/// show, and the ones it cannot with the reason (the bias-change test's step and ramp where it
/// applies to the model: `bias_change_applies`).
pub fn nothing_found(
    power: &[Power],
    effects: &[Finding],
    onset: Option<&super::bias_change::OnsetChange>,
    bias_change: Option<&super::bias_change::BiasChange>,
    bias_change_applies: bool,
) -> String {
    let (drift_shown, drift_cannot) =
        super::drift_power::drift_words(bias_change, bias_change_applies);
    // a g-sensitivity the onset test shows (within the plausible sizes)
    let onset_mde = onset.and_then(|o| o.mde).filter(|&m| {
        REFERENCES
            .iter()
            .any(|r| r.effect == Effect::GSensitivity && m <= r.plausible_max)
    });
    let shown: Vec<String> = power
        .iter()
        .filter_map(|p| p.mde.map(|m| format!("{} {}", p.variant, p.format_size(m))))
        .chain(onset_mde.map(|m| {
            format!(
                "g-sensitivity {} (the bias at the onset of walking)",
                format_unit("rad/s per m/s²", m)
            )
        }))
        .chain(
            effects
                .iter()
                .filter(|f| f.name == Effect::HeadingOffset)
                .filter_map(|f| {
                    f.mde
                        .map(|m| format!("heading offset {:.2}°", m.to_degrees()))
                }),
        )
        .chain(drift_shown)
        .collect();
    let cannot: Vec<String> = power
        .iter()
        .filter(|p| !(p.effect == Effect::GSensitivity && onset_mde.is_some()))
        .filter_map(|p| {
            p.cannot
                .as_ref()
                .map(|why| format!("{} ({why})", p.variant))
        })
        .chain(drift_cannot)
        .collect();
    let mut s = format!(
        "nothing significant (score < {SIGNIFICANT}): nothing above the detectable sizes {}",
        if shown.is_empty() {
            "(none measured)".to_string()
        } else {
            shown.join(", ")
        }
    );
    if !cannot.is_empty() {
        s.push_str(&format!("; this walk cannot show {}", cannot.join("; ")));
    }
    s
}

mod calibration;
pub use calibration::calibrate_by_injection;

#[cfg(test)]
mod tests;
