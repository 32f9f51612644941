//! The evidence for each effect of the catalogue: residual tests (regression, CUSUM, group
//! means) scored as −log₁₀ p, then a nested-model F test for the fixable ones.

use super::analysis::{Analysis, Consistency, HeadingResidual, analyse};
use super::catalogue::{Effect, Fix, apply_fix};
use super::clock_rate::split_timing_from_scale;
use super::{CORROBORATED, SIGNIFICANT};
use crate::runner::RunError;
use crate::stats::{self, anova_oneway, cusum, group_means, regress};
use corridor_shared::config::{ConfigFile, Mode};
use corridor_shared::imu_csv::ImuLog;
use corridor_shared::truth_csv::TruthPoint;
use serde::Serialize;
use std::path::Path;

/// One effect of the catalogue with its evidence.
#[derive(Debug, Clone, Serialize)]
pub struct Finding {
    /// The effect.
    pub name: Effect,
    /// −log₁₀ p of its test (capped at 30).
    pub score: f64,
    /// What was found, in words and numbers.
    pub evidence: String,
    /// The model change that adds it, if corridor has one.
    pub fix: Option<Fix>,
    /// The smallest size of the effect this walk shows at the ranking's false-alarm rate, in
    /// the effect's unit (see [`super::power`]); `None` when not predicted.
    pub mde: Option<f64>,
}

/// The largest score (p = 10⁻³⁰).
pub const MAX_SCORE: f64 = 30.0;

/// −log₁₀ `p`, at most [`MAX_SCORE`]; 0 for a NaN `p` (no test).
pub(super) fn score(p: f64) -> f64 {
    if p.is_nan() {
        0.0
    } else {
        (-p.max(1e-30).log10()).max(0.0)
    }
}

/// The catalogue's effects with their residual evidence, scored by the residual tests alone
/// (regression, CUSUM, group means); [`score_by_likelihood`] re-scores the fixable ones.
pub(super) fn rank_effects(used: &[&HeadingResidual], mode: Mode) -> Vec<Finding> {
    let mut out = Vec::new();
    if used.len() < 8 {
        out.push(Finding {
            name: Effect::Unexplained,
            score: 0.0,
            evidence: format!("only {} heading observations: too few to test", used.len()),
            fix: None,
            mde: None,
        });
        return out;
    }
    let r: Vec<f64> = used.iter().map(|x| x.r_rad).collect();
    let deg = f64::to_degrees;

    // heading_offset: the walking direction (stride displacement between two used
    // observations on the same corridor direction) against the map, same sign on every
    // direction. The filter pulls the foot heading onto the map, so an offset between foot and
    // walking direction shows in the strides, not in the heading innovations; a lagging bias
    // estimate tilts the strides by about half the mean innovation, which is removed.
    let mut w = Vec::new();
    let mut wg = Vec::new();
    for pair in used.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (dx, dy) = (b.p_xy[0] - a.p_xy[0], b.p_xy[1] - a.p_xy[1]);
        if b.turn_rad == 0.0 && a.direction == b.direction && dx.hypot(dy) > 0.3 {
            let dir = crate::core::rotation::wrap_pi(b.r_rad + b.foot_heading_rad);
            w.push(crate::core::rotation::wrap_pi(dir - dy.atan2(dx)) - 0.5 * b.r_rad);
            wg.push(b.direction);
        }
    }
    let all = group_means(&w, &vec![0; w.len()]).ok();
    let by_dir = group_means(&w, &wg).ok();
    let anova = anova_oneway(&w, &wg).ok();
    if let Some(a) = all.as_ref().and_then(|g| g.first()) {
        let same_sign = by_dir.as_ref().is_some_and(|g| {
            g.iter()
                .filter(|s| s.n >= 3)
                .all(|s| s.mean.signum() == a.mean.signum())
        });
        let anova_p = anova.as_ref().map_or(1.0, |a| a.p_value);
        let mut s = score(a.p_value);
        if !same_sign || anova_p < 0.01 {
            s *= 0.3; // direction-dependent: not a single offset
        }
        out.push(Finding {
            name: Effect::HeadingOffset,
            score: s,
            evidence: format!(
                "walking direction minus map direction {:+.2}° ± {:.2}° over {} straight strides (p = {:.1e}); per direction {}; equal-means ANOVA p = {:.2}",
                deg(a.mean),
                deg(a.std_err),
                a.n,
                a.p_value,
                by_dir.as_ref().map_or(String::new(), |g| g
                    .iter()
                    .map(|s| format!("{}: {:+.2}° (n {})", s.group, deg(s.mean), s.n))
                    .collect::<Vec<_>>()
                    .join(", ")),
                anova_p
            ),
            fix: Some(Fix::HeadingOffset),
            // the mean's standard error at the ranking's false-alarm rate
            mde: Some(super::power::MDE_Z * a.std_err).filter(|m| m.is_finite()),
        });
    }

    // joint regression on the candidate regressors
    let col = |f: fn(&HeadingResidual) -> f64| -> Vec<f64> { used.iter().map(|x| f(x)).collect() };
    let t = col(|x| x.t_s);
    let turn = col(|x| x.turn_rad);
    let rot = col(|x| x.rotation_rad);
    let force = col(|x| x.force_excess_m_s);
    let dtdev = col(|x| x.dt_deviation_s);
    let reg = regress(
        &r,
        &[
            ("time", &t),
            ("turn", &turn),
            ("rotation", &rot),
            ("force", &force),
            ("dt_deviation", &dtdev),
        ],
    )
    .ok();
    let coef = |name: &str| reg.as_ref().and_then(|g| g.coef(name).cloned());
    let cs = cusum(&r).ok();
    // bias drift: trend in time or a drift in the cumulative sum
    let (p_time, slope) = coef("time").map_or((f64::NAN, 0.0), |c| (c.p_value, c.value));
    let p_cusum = cs.as_ref().map_or(f64::NAN, |c| c.p_value);
    let step_like = cs.as_ref().is_some_and(|c| c.drift_detected) && p_cusum < p_time;
    out.push(Finding {
        name: Effect::BiasDrift,
        score: score(p_time).max(score(p_cusum)),
        evidence: format!(
            "residual trend {:+.3}°/min (p = {:.1e}); CUSUM p = {:.1e}{}",
            deg(slope) * 60.0,
            p_time,
            p_cusum,
            cs.as_ref().map_or(String::new(), |c| format!(
                ", largest excursion at observation {} (t = {:.1} s): {}",
                c.argmax,
                used.get(c.argmax).map_or(f64::NAN, |x| x.t_s),
                if step_like { "step-like" } else { "ramp-like" }
            ))
        ),
        fix: Some(if step_like {
            Fix::BiasRandomWalkTimes10
        } else {
            Fix::BiasRate
        }),
        mde: None,
    });
    let mut reg_effect = |name: Effect, key: &str, what: &str, unit: &str, fix: Option<Fix>| {
        if let Some(c) = coef(key) {
            out.push(Finding {
                name,
                score: score(c.p_value),
                evidence: format!(
                    "residual ∝ {what}: {:+.3e} rad per {unit} (t = {:.1}, p = {:.1e})",
                    c.value, c.t, c.p_value
                ),
                fix,
                mde: None,
            });
        }
    };
    reg_effect(
        Effect::GyroScaleFactor,
        "turn",
        "the map turn since the last used observation",
        "rad of turn",
        Some(Fix::ScaleFactor),
    );
    reg_effect(
        Effect::GSensitivity,
        "force",
        "∫| |f| − g | since the last observation",
        "m/s",
        Some(Fix::GSensitivity),
    );
    reg_effect(
        Effect::AxisMisalignment,
        "rotation",
        "total rotation ∫|ω| (cadence)",
        "rad",
        None,
    );
    reg_effect(
        Effect::Timing,
        "dt_deviation",
        "time-step deviations",
        "s",
        None,
    );
    if let Some(g) = reg.as_ref() {
        for d in &g.dropped {
            if d.name == "dt_deviation" {
                out.push(Finding {
                    name: Effect::Timing,
                    score: 0.0,
                    evidence: "time steps are regular: no jitter or gap to test".into(),
                    fix: None,
                    mde: None,
                });
            }
        }
    }

    // mounting tilt: the paper's flat-foot assumption against the accelerometer
    let tilt_deg: Vec<[f64; 3]> = used.iter().map(|x| x.tilt_change.map(deg)).collect();
    let mut best_p: f64 = 1.0;
    let mut means = [0.0; 3];
    for (k, m) in means.iter_mut().enumerate() {
        let comp: Vec<f64> = tilt_deg.iter().map(|v| v[k]).collect();
        if let Some(gs) = group_means(&comp, &vec![0; comp.len()])
            .ok()
            .and_then(|g| g.first().cloned())
        {
            *m = gs.mean;
            if gs.mean.abs() > 0.5 {
                best_p = best_p.min(gs.p_value);
            }
        }
    }
    let paper = mode == Mode::Paper;
    out.push(Finding {
        name: Effect::MountingTilt,
        score: if paper { score(best_p) } else { 0.0 },
        evidence: format!(
            "gravity at stance vs at the initial rest: mean rotation ({:+.2}, {:+.2}, {:+.2})° in sensor axes{}",
            means[0],
            means[1],
            means[2],
            if paper {
                ""
            } else {
                "; the error-state filter estimates the tilt from ZUPTs, so it is modelled already"
            }
        ),
        fix: paper.then_some(Fix::RotationAware),
        mde: None,
    });

    out.sort_by(|a, b| b.score.total_cmp(&a.score));
    out
}

/// Adds `unexplained` in front when the residuals are inconsistent and nothing is significant.
fn add_unexplained(effects: &mut Vec<Finding>, c: &Consistency) {
    let best = effects.first().map_or(0.0, |e| e.score);
    let not_white = c.whiteness_p < 0.01;
    if (c.nis_too_large || not_white) && best < SIGNIFICANT {
        effects.insert(
            0,
            Finding {
                name: Effect::Unexplained,
                score: score(c.whiteness_p).max(if c.nis_too_large { score(c.nis_p) } else { 0.0 }),
                evidence: format!(
                    "residuals inconsistent (NIS mean {:.2}, band {:.2}–{:.2}; whiteness p = {:.1e}) and no catalogue effect is significant",
                    c.nis_mean, c.nis_band[0], c.nis_band[1], c.whiteness_p
                ),
                fix: None,
                mde: None,
            },
        );
    }
}

/// A candidate model: an effect's fix applied, and its analysis.
#[derive(Debug, Clone)]
pub struct Candidate {
    /// Effect.
    pub effect: Effect,
    /// Fix.
    pub fix: Fix,
    /// The model with the fix.
    pub file: ConfigFile,
    /// Its analysis.
    pub analysis: Analysis,
}

/// Re-scores every fixable effect by a nested-model F test on the heading innovations: the
/// model with the effect's fix against the current one, `F = ((RSS₀ − RSS₁)/k) / (RSS₁/(n − k))`
/// with `k` added parameters. Sums of squares rather than the Gaussian likelihood, because the
/// configured heading σ is deliberately conservative (NIS 0.3–1) and a likelihood would reward
/// models for their S, not for their residuals. The residual tests stay in the evidence; the F
/// test decides, because a lagging bias estimate, an offset and a scale error can all leave a
/// residual of constant sign.
pub fn score_by_likelihood(
    log: &ImuLog,
    file: &ConfigFile,
    base: &mut Analysis,
    truth: Option<&[TruthPoint]>,
    map: Option<&Path>,
) -> Result<Vec<Candidate>, RunError> {
    let mut candidates = Vec::new();
    for e in &mut base.effects {
        let mut best: Option<(f64, usize, Candidate)> = None;
        // A fix that carries the data's figures comes with the finding.
        let own;
        let fixes = match e.fix {
            Some(f @ Fix::GyroRail { .. }) => {
                own = [(f, 1)];
                &own[..]
            }
            _ => e.name.fixes(),
        };
        for &(fix, k) in fixes {
            let mut f = file.clone();
            if !apply_fix(fix, &mut f) {
                continue;
            }
            let a = analyse(log, &f, truth, map)?;
            let n = a.consistency.observations as f64;
            let (rss0, rss1) = (base.consistency.rss_rad2, a.consistency.rss_rad2);
            let lr = if n > k as f64 + 2.0 && rss1 > 0.0 {
                ((rss0 - rss1) / k as f64) / (rss1 / (n - k as f64))
            } else {
                0.0
            };
            if best.as_ref().is_none_or(|(b, _, _)| lr > *b) {
                best = Some((
                    lr,
                    k,
                    Candidate {
                        effect: e.name,
                        fix,
                        file: f,
                        analysis: a,
                    },
                ));
            }
        }
        match best {
            Some((lr, k, cand)) => {
                let n = cand.analysis.consistency.observations as f64;
                let p = stats::f_sf(lr.max(0.0), k as f64, (n - k as f64).max(1.0));
                // The F test only counts for an effect whose own signature is there (residual
                // test p < 0.05): extension states are flexible (three g-sensitivity states
                // also absorb a bias drift at stance, where f ≈ g), so a lower RSS alone does
                // not name the effect. Then the larger of the two: an offset does not show in
                // the innovations (see `rank_effects`), a drift the filter lags behind shows
                // more in the F test than in the residual tests.
                if e.score >= CORROBORATED {
                    e.score = e.score.max(if lr > 0.0 { score(p) } else { 0.0 });
                }
                e.fix = Some(cand.fix);
                let (rss0, rss1) = (
                    base.consistency.rss_rad2,
                    cand.analysis.consistency.rss_rad2,
                );
                // The fix is a change of the filter, not a nested least-squares model: it can
                // raise the residuals' sum of squares, where an F statistic would come out
                // negative ("F = -0.3" was printed).
                e.evidence = if rss1 > rss0 && rss0 > 0.0 {
                    format!(
                        "{}; adding `{}` raised the residuals' sum of squares by {:.1} % (no F \
                         test)",
                        e.evidence,
                        cand.fix,
                        100.0 * (rss1 / rss0 - 1.0)
                    )
                } else {
                    format!(
                        "{}; adding `{}`: F = {:.1} for {} parameter{} (p = {:.1e})",
                        e.evidence,
                        cand.fix,
                        lr,
                        k,
                        if k == 1 { "" } else { "s" },
                        p
                    )
                };
                candidates.push(cand);
            }
            None if !fixes.is_empty() => {
                e.score = 0.0;
                e.evidence = format!("{}; already in the model", e.evidence);
                e.fix = None;
            }
            None => {}
        }
    }
    split_timing_from_scale(base, &mut candidates, file);
    base.effects.sort_by(|a, b| b.score.total_cmp(&a.score));
    add_unexplained(&mut base.effects, &base.consistency);
    Ok(candidates)
}
