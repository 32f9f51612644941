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
//! Each fixable effect is also scored by a nested-model F test: the model with the effect added
//! against the current one, on the heading innovations (see [`score_by_likelihood`]); its score
//! is the larger of the two.
//!
//! Catalogue and test of each effect (scores are −log₁₀ p, significant from 3):
//! - `heading_offset`: the walking direction (stride displacement) differs from the map
//!   direction by a constant with the same sign on every direction (t test, and the one-way
//!   ANOVA across directions must not reject equal means);
//! - `bias_drift`: a trend of `r` in time (regression) or a drift/step in its cumulative sum
//!   (CUSUM); the fix is bias-rate states for a ramp, a faster bias random walk for a step;
//! - `gyro_scale_factor`: `r` proportional to the signed turn since the last used observation;
//! - `g_sensitivity`: `r` proportional to ∫| |f| − g |;
//! - `axis_misalignment`: `r` proportional to the total rotation ∫|ω| (cadence), not to the turn;
//! - `timing`: `r` proportional to the time-step deviations (jitter, gaps);
//! - `mounting_tilt`: the accelerometer's tilt at stance differs from the tilt at the initial
//!   rest (only an effect for the paper's model, which takes the foot as flat);
//! - `unexplained`: the residuals are inconsistent (NIS above its χ² band or not white) and no
//!   effect of the catalogue reaches significance.

use crate::eval::EvalOptions;
use crate::runner::{RunError, heading_aid, run_log};
use crate::stats::{self, anova_oneway, cusum, group_means, nis_consistency, regress, whiteness};
use corridor_shared::config::{ConfigFile, Mode};
use corridor_shared::imu_csv::ImuLog;
use corridor_shared::injection::BiasInjection;
use corridor_shared::truth_csv::TruthPoint;
use nalgebra::{UnitQuaternion, Vector3};
use serde::Serialize;
use std::path::Path;

/// Score from which an effect counts as significant (p < 0.001).
pub const SIGNIFICANT: f64 = 3.0;
/// Residual-test score an effect needs before the F test can raise it (p < 0.05).
pub const CORROBORATED: f64 = 1.3;
/// Largest number of model extensions added in one diagnosis.
pub const MAX_ITERATIONS: usize = 3;

/// One heading residual with its regressors.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct HeadingResidual {
    /// Time, s.
    pub t_s: f64,
    /// Residual `ψ_map − ψ̂_foot`, rad.
    pub r_rad: f64,
    /// Innovation variance, rad².
    pub s_rad2: f64,
    /// Used by the filter (else rejected by the gate or the straight-walk test).
    pub accepted: bool,
    /// Foot heading the model predicted, rad.
    pub foot_heading_rad: f64,
    /// Position at the observation, m, map frame.
    pub p_xy: [f64; 2],
    /// Direction index (`round((ψ_map − grid)/step)`, modulo the number of directions).
    pub direction: i64,
    /// Time since the previous used observation, s.
    pub dt_s: f64,
    /// Signed turn since the previous used observation, from the map directions, rad.
    pub turn_rad: f64,
    /// The same turn from the gyro (∫ω about the vertical), rad.
    pub gyro_turn_rad: f64,
    /// Total rotation ∫|ω| since the previous observation, rad.
    pub rotation_rad: f64,
    /// ∫| |f| − g | since the previous observation, m/s.
    pub force_excess_m_s: f64,
    /// Σ |dt − median dt| since the previous observation, s.
    pub dt_deviation_s: f64,
    /// Angle between the gravity direction at this stance and at the initial rest, rad, as a
    /// rotation vector in sensor axes.
    pub tilt_change: [f64; 3],
}

/// One candidate effect with its evidence.
#[derive(Debug, Clone, Serialize)]
pub struct Effect {
    /// Catalogue name.
    pub name: &'static str,
    /// −log₁₀ p of its test (capped at 30).
    pub score: f64,
    /// What was found, in words and numbers.
    pub evidence: String,
    /// The model change that adds it, if corridor has one.
    pub fix: Option<&'static str>,
}

/// Consistency figures of one run.
#[derive(Debug, Clone, Serialize)]
pub struct Consistency {
    /// Footprint RMS, m (when truth is given).
    pub gcp_rms_m: Option<f64>,
    /// Footprint RMS, % of path.
    pub gcp_rms_pct: Option<f64>,
    /// Mean NIS of the accepted heading observations.
    pub nis_mean: f64,
    /// Its 95 % χ² band (lower, upper).
    pub nis_band: [f64; 2],
    /// Ljung–Box p-value of the normalised residuals (whiteness).
    pub whiteness_p: f64,
    /// Fraction of autocorrelations outside ±1.96/√N (lags 1..10).
    pub whiteness_fraction_outside: f64,
    /// Heading observations used.
    pub observations: usize,
    /// Sum of the squared heading innovations of the used observations, rad².
    pub rss_rad2: f64,
    /// The NIS is above its band.
    pub nis_too_large: bool,
    /// p-value of the NIS test.
    pub nis_p: f64,
    /// Final bias, rad/s, and its σ.
    pub bias_rad_s: [f64; 3],
    /// Final bias σ.
    pub bias_sd_rad_s: [f64; 3],
}

/// The analysis of one model.
#[derive(Debug, Clone, Serialize)]
pub struct Analysis {
    /// Model extensions in force (config keys).
    pub model: Vec<String>,
    /// Consistency figures.
    pub consistency: Consistency,
    /// Effects, best first.
    pub effects: Vec<Effect>,
    /// Final gyro scale factors per sensor axis with their σ, when the model estimates them.
    pub scale_factor: Option<[[f64; 2]; 3]>,
    /// The residuals (for plots and the report).
    #[serde(skip)]
    pub residuals: Vec<HeadingResidual>,
}

/// One step of the loop: the effect added and the model before and after.
#[derive(Debug, Clone, Serialize)]
pub struct Iteration {
    /// Effect added.
    pub effect: &'static str,
    /// Its score when it was chosen.
    pub score: f64,
    /// Config change.
    pub fix: &'static str,
    /// Before.
    pub before: Consistency,
    /// After.
    pub after: Consistency,
    /// Kept (the error or, without truth, the NIS/whiteness improved).
    pub kept: bool,
}

/// `report.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// The effects ranked on the starting model.
    pub effects: Vec<Effect>,
    /// The first effect, or `none` when nothing is significant.
    pub top_effect: String,
    /// The starting model.
    pub before: Consistency,
    /// The final model.
    pub after: Consistency,
    /// The loop.
    pub iterations: Vec<Iteration>,
    /// Effects of the final model.
    pub final_effects: Vec<Effect>,
    /// The final model's extensions.
    pub final_model: Vec<String>,
}

/// Runs the model of `file` on `log` and analyses its residuals.
pub fn analyse(
    log: &ImuLog,
    file: &ConfigFile,
    truth: Option<&[TruthPoint]>,
    map: Option<&Path>,
) -> Result<Analysis, RunError> {
    let cfg = file.validate()?;
    let aid = heading_aid(&cfg, map)?;
    let grid = cfg.heading.grid_rad;
    let step = cfg.heading.grid_step_rad.get();
    let sigma2 = cfg.heading.sigma_rad.get().powi(2);
    let n_dirs = (std::f64::consts::TAU / step).round() as i64;
    let median_dt = median_dt(log);
    let mut acc = Accumulator::default();
    let mut res = Vec::new();
    let mut rest_up: Option<Vector3<f64>> = None;
    let mut rest_sum = Vector3::zeros();
    let mut stance_sum = (Vector3::zeros(), 0u32);
    let mut last_t: Option<f64> = None;
    let mut last_dir: Option<f64> = None;
    let outcome = run_log(log, &cfg, &aid, &BiasInjection::default(), |input, e| {
        let w = Vector3::from(input.gyro_rad_s);
        let f = Vector3::from(input.accel_m_s2);
        let dt = last_t.map_or(0.0, |t| input.t_s - t);
        last_t = Some(input.t_s);
        if e.phase == crate::core::Phase::Aligning {
            if e.stance {
                rest_sum += f;
            }
            return;
        }
        let up = *rest_up.get_or_insert_with(|| rest_sum.normalize());
        let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            e.nav_from_body[0],
            e.nav_from_body[1],
            e.nav_from_body[2],
            e.nav_from_body[3],
        ));
        acc.dt_s += dt;
        acc.turn_rad += (q * w).z * dt;
        acc.rotation_rad += w.norm() * dt;
        acc.force_excess_m_s += (f.norm() - 9.80665).abs() * dt;
        acc.dt_deviation_s += (dt - median_dt).abs();
        if e.stance {
            stance_sum.0 += f;
            stance_sum.1 += 1;
        } else {
            stance_sum = (Vector3::zeros(), 0);
        }
        let Some(h) = &e.heading else { return };
        if h.direction_rad.is_nan() {
            return; // rejected before association: keep accumulating to the next observation
        }
        let r = crate::core::rotation::wrap_pi(h.direction_rad - h.foot_heading_rad);
        let (accepted, s) = match &h.outcome {
            Ok(i) if i.dim == 1 => (true, i.s_diag[0]),
            Ok(_) => (true, sigma2),
            Err(_) => (false, sigma2),
        };
        let k = ((h.direction_rad - grid) / step).round() as i64;
        // The turn the map says the walker made since the last used observation: free of the
        // stride-to-stride scatter of the foot angle, which the gyro-integrated turn carries
        // (and which correlates with the residual by construction).
        let map_turn =
            last_dir.map_or(0.0, |d| crate::core::rotation::wrap_pi(h.direction_rad - d));
        let tilt = if stance_sum.1 > 0 {
            up.cross(&stance_sum.0.normalize())
        } else {
            Vector3::zeros()
        };
        res.push(HeadingResidual {
            t_s: e.t_s,
            r_rad: r,
            s_rad2: s,
            accepted,
            foot_heading_rad: h.foot_heading_rad,
            p_xy: [e.p_m[0], e.p_m[1]],
            direction: k.rem_euclid(n_dirs.max(1)),
            dt_s: acc.dt_s,
            turn_rad: map_turn,
            gyro_turn_rad: acc.turn_rad,
            rotation_rad: acc.rotation_rad,
            force_excess_m_s: acc.force_excess_m_s,
            dt_deviation_s: acc.dt_deviation_s,
            tilt_change: tilt.into(),
        });
        if accepted {
            acc = Accumulator::default();
            last_dir = Some(h.direction_rad);
        }
    });
    let n = outcome.trace.t_s.len();
    let (bias, bias_sd) = if n > 0 {
        (
            outcome.trace.bias_rad_s[n - 1],
            outcome.trace.bias_sd_rad_s[n - 1],
        )
    } else {
        ([f64::NAN; 3], [f64::NAN; 3])
    };
    let eval = truth.and_then(|t| outcome.trace.evaluate(t, &EvalOptions::default()).ok());
    let used: Vec<&HeadingResidual> = res.iter().filter(|r| r.accepted).collect();
    let nis: Vec<f64> = used.iter().map(|r| r.r_rad * r.r_rad / r.s_rad2).collect();
    let z: Vec<f64> = used.iter().map(|r| r.r_rad / r.s_rad2.sqrt()).collect();
    let nis_t = nis_consistency(&nis, 1, 0.95).ok();
    let white = whiteness(&z, 10.min(used.len().saturating_sub(2)).max(1)).ok();
    let consistency = Consistency {
        gcp_rms_m: eval.as_ref().and_then(|e| e.rms_error_m),
        gcp_rms_pct: eval.as_ref().and_then(|e| e.rms_error_pct_of_path),
        nis_mean: nis_t.as_ref().map_or(f64::NAN, |t| t.mean),
        nis_band: nis_t.as_ref().map_or([f64::NAN; 2], |t| [t.lower, t.upper]),
        whiteness_p: white.as_ref().map_or(f64::NAN, |w| w.ljung_box_p),
        whiteness_fraction_outside: white.as_ref().map_or(f64::NAN, |w| w.fraction_outside),
        observations: used.len(),
        rss_rad2: used.iter().map(|r| r.r_rad * r.r_rad).sum(),
        nis_too_large: nis_t
            .as_ref()
            .is_some_and(|t| t.verdict == stats::NisVerdict::TooLarge),
        nis_p: nis_t.as_ref().map_or(f64::NAN, |t| t.p_value),
        bias_rad_s: bias,
        bias_sd_rad_s: bias_sd,
    };
    let effects = rank_effects(&used, cfg.mode);
    let scale_factor = outcome
        .extensions
        .and_then(|(x, sd)| sd.map(|sd| std::array::from_fn(|k| [x.scale_factor[k], sd[k]])));
    Ok(Analysis {
        model: model_keys(file),
        consistency,
        effects,
        scale_factor,
        residuals: res,
    })
}

#[derive(Debug, Clone, Copy, Default)]
struct Accumulator {
    dt_s: f64,
    turn_rad: f64,
    rotation_rad: f64,
    force_excess_m_s: f64,
    dt_deviation_s: f64,
}

fn median_dt(log: &ImuLog) -> f64 {
    let mut d: Vec<f64> = log.rows.windows(2).map(|w| w[1].t_s - w[0].t_s).collect();
    if d.is_empty() {
        return 0.0;
    }
    let mid = d.len() / 2;
    *d.select_nth_unstable_by(mid, f64::total_cmp).1
}

fn score(p: f64) -> f64 {
    if p.is_nan() {
        0.0
    } else {
        (-p.max(1e-30).log10()).max(0.0)
    }
}

/// The catalogue's effects with their residual evidence, scored by the residual tests alone
/// (regression, CUSUM, group means); [`score_by_likelihood`] re-scores the fixable ones.
fn rank_effects(used: &[&HeadingResidual], mode: Mode) -> Vec<Effect> {
    let mut out = Vec::new();
    if used.len() < 8 {
        out.push(Effect {
            name: "unexplained",
            score: 0.0,
            evidence: format!("only {} heading observations: too few to test", used.len()),
            fix: None,
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
        out.push(Effect {
            name: "heading_offset",
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
            fix: Some("model.heading_offset_sd_deg = 5"),
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
    out.push(Effect {
        name: "bias_drift",
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
            "eskf.gyro_bias_rw_rad_s_sqrt_s × 10"
        } else {
            "model.bias_rate_rw_rad_s2_sqrt_s = 1e-6"
        }),
    });
    let mut reg_effect =
        |name: &'static str, key: &str, what: &str, unit: &str, fix: Option<&'static str>| {
            if let Some(c) = coef(key) {
                out.push(Effect {
                    name,
                    score: score(c.p_value),
                    evidence: format!(
                        "residual ∝ {what}: {:+.3e} rad per {unit} (t = {:.1}, p = {:.1e})",
                        c.value, c.t, c.p_value
                    ),
                    fix,
                });
            }
        };
    reg_effect(
        "gyro_scale_factor",
        "turn",
        "the map turn since the last used observation",
        "rad of turn",
        Some("model.scale_factor_sd = 0.02"),
    );
    reg_effect(
        "g_sensitivity",
        "force",
        "∫| |f| − g | since the last observation",
        "m/s",
        Some("model.g_sensitivity_sd = 1e-3"),
    );
    reg_effect(
        "axis_misalignment",
        "rotation",
        "total rotation ∫|ω| (cadence)",
        "rad",
        None,
    );
    reg_effect("timing", "dt_deviation", "time-step deviations", "s", None);
    if let Some(g) = reg.as_ref() {
        for d in &g.dropped {
            if d.name == "dt_deviation" {
                out.push(Effect {
                    name: "timing",
                    score: 0.0,
                    evidence: "time steps are regular: no jitter or gap to test".into(),
                    fix: None,
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
    out.push(Effect {
        name: "mounting_tilt",
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
        fix: paper.then_some("estimator.mode = rotation_aware"),
    });

    out.sort_by(|a, b| b.score.total_cmp(&a.score));
    out
}

/// Adds `unexplained` in front when the residuals are inconsistent and nothing is significant.
fn add_unexplained(effects: &mut Vec<Effect>, c: &Consistency) {
    let best = effects.first().map_or(0.0, |e| e.score);
    let not_white = c.whiteness_p < 0.01;
    if (c.nis_too_large || not_white) && best < SIGNIFICANT {
        effects.insert(
            0,
            Effect {
                name: "unexplained",
                score: score(c.whiteness_p).max(if c.nis_too_large { score(c.nis_p) } else { 0.0 }),
                evidence: format!(
                    "residuals inconsistent (NIS mean {:.2}, band {:.2}–{:.2}; whiteness p = {:.1e}) and no catalogue effect is significant",
                    c.nis_mean, c.nis_band[0], c.nis_band[1], c.whiteness_p
                ),
                fix: None,
            },
        );
    }
}

/// A clock running at the wrong rate scales every integrated angle alike: when the scale-factor
/// model that explains the residuals finds the same factor on all three axes (within 2σ, and
/// different from zero by 3σ), the effect is `timing` (a clock-rate error), not the gyro's
/// scale factor. The fix is the same states, which absorb it; the report says which.
fn split_timing_from_scale(effects: &mut [Effect], candidates: &[Candidate]) {
    let Some(sf) = candidates
        .iter()
        .find(|c| c.effect == "gyro_scale_factor")
        .and_then(|c| c.analysis.scale_factor)
    else {
        return;
    };
    let w: Vec<f64> = sf
        .iter()
        .map(|[_, sd]| 1.0 / (sd * sd).max(1e-300))
        .collect();
    let wsum: f64 = w.iter().sum();
    let mean = sf.iter().zip(&w).map(|([s, _], w)| s * w).sum::<f64>() / wsum;
    let mean_sd = (1.0 / wsum).sqrt();
    let agree = sf.iter().all(|[s, sd]| (s - mean).abs() <= 2.0 * sd);
    let Some(i) = effects.iter().position(|e| e.name == "gyro_scale_factor") else {
        return;
    };
    let detail = format!(
        "scale factors of the fitted model ({:+.4} ± {:.4}, {:+.4} ± {:.4}, {:+.4} ± {:.4})",
        sf[0][0], sf[0][1], sf[1][0], sf[1][1], sf[2][0], sf[2][1]
    );
    if agree && mean.abs() > 3.0 * mean_sd {
        let sc = effects[i].score;
        effects[i].evidence = format!("{}; {detail}: the same on every axis", effects[i].evidence);
        effects[i].score = 0.5 * sc;
        if let Some(t) = effects.iter_mut().find(|e| e.name == "timing") {
            t.score = sc;
            t.fix = Some("model.scale_factor_sd = 0.02");
            t.evidence = format!(
                "{}; every gyro axis shows the same scale factor {:+.4} ± {:.4}: time stamps running {:.2} % {} (a clock-rate error)",
                t.evidence,
                mean,
                mean_sd,
                100.0 * mean.abs(),
                if mean > 0.0 { "fast" } else { "slow" }
            );
        }
    } else {
        effects[i].evidence = format!("{}; {detail}", effects[i].evidence);
    }
}

/// The fixes tried for an effect, with the number of parameters each adds.
fn fixes_for(name: &str) -> &'static [(&'static str, usize)] {
    match name {
        "heading_offset" => &[("model.heading_offset_sd_deg = 5", 1)],
        "bias_drift" => &[
            ("model.bias_rate_rw_rad_s2_sqrt_s = 1e-6", 3),
            ("eskf.gyro_bias_rw_rad_s_sqrt_s × 10", 1),
        ],
        "gyro_scale_factor" | "timing" => &[("model.scale_factor_sd = 0.02", 3)],
        "g_sensitivity" => &[("model.g_sensitivity_sd = 1e-3", 3)],
        "mounting_tilt" => &[("estimator.mode = rotation_aware", 3)],
        _ => &[],
    }
}

/// A candidate model: an effect's fix applied, and its analysis.
#[derive(Debug, Clone)]
pub struct Candidate {
    /// Effect.
    pub effect: &'static str,
    /// Fix.
    pub fix: &'static str,
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
        for &(fix, k) in fixes_for(e.name) {
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
                e.evidence = format!(
                    "{}; adding `{}`: F = {:.1} for {} parameter{} (p = {:.1e})",
                    e.evidence,
                    cand.fix,
                    lr,
                    k,
                    if k == 1 { "" } else { "s" },
                    p
                );
                candidates.push(cand);
            }
            None if !fixes_for(e.name).is_empty() => {
                e.score = 0.0;
                e.evidence = format!("{}; already in the model", e.evidence);
                e.fix = None;
            }
            None => {}
        }
    }
    split_timing_from_scale(&mut base.effects, &candidates);
    base.effects.sort_by(|a, b| b.score.total_cmp(&a.score));
    add_unexplained(&mut base.effects, &base.consistency);
    Ok(candidates)
}

/// The extension keys switched on in `file`.
fn model_keys(file: &ConfigFile) -> Vec<String> {
    let m = &file.model;
    let mut v = Vec::new();
    if m.bias_rate_rw_rad_s2_sqrt_s.is_some() {
        v.push("bias_rate".into());
    }
    if m.scale_factor_sd.is_some() {
        v.push("scale_factor".into());
    }
    if m.heading_offset_sd_deg.is_some() {
        v.push("heading_offset".into());
    }
    if m.g_sensitivity_sd.is_some() {
        v.push("g_sensitivity".into());
    }
    if let Some(rw) = file.eskf.gyro_bias_rw_rad_s_sqrt_s {
        v.push(format!("gyro_bias_rw = {rw:e}"));
    }
    v.push(format!(
        "mode = {}",
        file.estimator.mode.map_or("eskf", Mode::name)
    ));
    v
}

/// Applies a fix (one of the catalogue's labels) to `file`; `false` when it is unknown or
/// already in the model.
pub fn apply_fix(fix: &str, file: &mut ConfigFile) -> bool {
    // The extension states live in the error-state filter: from the paper's bias filter (or
    // its rotation-aware variant) a model extension also moves the heading observations there.
    if fix.starts_with("model.")
        && matches!(file.estimator.mode, Some(Mode::Paper | Mode::RotationAware))
    {
        let mut f = file.clone();
        f.estimator.mode = Some(Mode::Eskf);
        if apply_fix(fix, &mut f) {
            *file = f;
            return true;
        }
        return false;
    }
    let m = &mut file.model;
    match Some(fix) {
        Some("model.heading_offset_sd_deg = 5") if m.heading_offset_sd_deg.is_none() => {
            m.heading_offset_sd_deg = Some(5.0)
        }
        Some("model.bias_rate_rw_rad_s2_sqrt_s = 1e-6")
            if m.bias_rate_rw_rad_s2_sqrt_s.is_none() =>
        {
            m.bias_rate_rw_rad_s2_sqrt_s = Some(1e-6)
        }
        Some("model.scale_factor_sd = 0.02") if m.scale_factor_sd.is_none() => {
            m.scale_factor_sd = Some(0.02)
        }
        Some("model.g_sensitivity_sd = 1e-3") if m.g_sensitivity_sd.is_none() => {
            m.g_sensitivity_sd = Some(1e-3)
        }
        Some("eskf.gyro_bias_rw_rad_s_sqrt_s × 10") => {
            let rw = file.eskf.gyro_bias_rw_rad_s_sqrt_s.unwrap_or(1e-4);
            if rw >= 1e-3 {
                return false;
            }
            file.eskf.gyro_bias_rw_rad_s_sqrt_s = Some(rw * 10.0);
        }
        Some("estimator.mode = rotation_aware") if file.estimator.mode == Some(Mode::Paper) => {
            file.estimator.mode = Some(Mode::RotationAware)
        }
        _ => return false,
    }
    true
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

/// The whole loop.
pub fn diagnose(
    log: &ImuLog,
    start: &ConfigFile,
    truth: Option<&[TruthPoint]>,
    map: Option<&Path>,
) -> Result<(Report, Analysis, Analysis, ConfigFile), RunError> {
    let mut first = analyse(log, start, truth, map)?;
    let mut candidates = score_by_likelihood(log, start, &mut first, truth, map)?;
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
            kept,
        });
        if !kept {
            break;
        }
        file = cand.file;
        current = cand.analysis;
        candidates = score_by_likelihood(log, &file, &mut current, truth, map)?;
    }
    let report = Report {
        top_effect: first
            .effects
            .first()
            .filter(|e| e.score >= SIGNIFICANT)
            .map_or("none".to_string(), |e| e.name.to_string()),
        effects: first.effects.clone(),
        before: first.consistency.clone(),
        after: current.consistency.clone(),
        iterations,
        final_effects: current.effects.clone(),
        final_model: current.model.clone(),
    };
    Ok((report, first, current, file))
}

/// `report.md`, with the figures written next to it.
pub fn write_report(
    dir: &Path,
    report: &Report,
    before: &Analysis,
    after: &Analysis,
) -> Result<(), RunError> {
    use crate::plot::{Figure, Panel, Series};
    use crate::runner::io_at;
    let series = |a: &Analysis, label: &str| {
        let used: Vec<&HeadingResidual> = a.residuals.iter().filter(|r| r.accepted).collect();
        Series::markers(
            label.to_string(),
            used.iter().map(|r| r.t_s).collect(),
            used.iter().map(|r| r.r_rad.to_degrees()).collect(),
        )
    };
    let turn = |a: &Analysis, label: &str| {
        let used: Vec<&HeadingResidual> = a.residuals.iter().filter(|r| r.accepted).collect();
        Series::markers(
            label.to_string(),
            used.iter().map(|r| r.turn_rad.to_degrees()).collect(),
            used.iter().map(|r| r.r_rad.to_degrees()).collect(),
        )
    };
    let fig = Figure::new("Heading residuals before and after the diagnosis")
        .with_panel(
            Panel::new("residual against time", "t (s)", "ψ_map − ψ̂ (°)")
                .with_series(series(before, "before"))
                .with_series(series(after, "after")),
        )
        .with_panel(
            Panel::new(
                "residual against the turn since the last observation",
                "turn (°)",
                "ψ_map − ψ̂ (°)",
            )
            .with_series(turn(before, "before"))
            .with_series(turn(after, "after")),
        );
    let f = dir.join("residuals.svg");
    fig.write_svg(&f).map_err(io_at(&f))?;

    let mut md = String::from("# corridor diagnose\n\n");
    md.push_str(&format!(
        "Top effect on the starting model: **{}**.\n\n",
        report.top_effect
    ));
    md.push_str("## Effects on the starting model (score = −log₁₀ p; significant from 3)\n\n| effect | score | evidence | fix |\n|---|---|---|---|\n");
    for e in &report.effects {
        md.push_str(&format!(
            "| {} | {:.1} | {} | {} |\n",
            e.name,
            e.score,
            e.evidence.replace('|', "/"),
            e.fix.unwrap_or("—")
        ));
    }
    md.push_str("\n## Loop\n\n| step | effect added | fix | RMS before | RMS after | NIS before | NIS after | whiteness p before | after | kept |\n|---|---|---|---|---|---|---|---|---|---|\n");
    let rms = |c: &Consistency| c.gcp_rms_m.map_or("—".into(), |v| format!("{v:.2} m"));
    for (i, it) in report.iterations.iter().enumerate() {
        md.push_str(&format!(
            "| {} | {} | `{}` | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {} |\n",
            i + 1,
            it.effect,
            it.fix,
            rms(&it.before),
            rms(&it.after),
            it.before.nis_mean,
            it.after.nis_mean,
            it.before.whiteness_p,
            it.after.whiteness_p,
            if it.kept { "yes" } else { "no" }
        ));
    }
    md.push_str(&format!(
        "\nBefore: {} ; after: {} ; final model: {}.\n\n![residuals](residuals.svg)\n",
        describe(&report.before),
        describe(&report.after),
        report.final_model.join(", ")
    ));
    let f = dir.join("report.md");
    std::fs::write(&f, md).map_err(io_at(&f))?;
    let f = dir.join("report.json");
    std::fs::write(
        &f,
        serde_json::to_string_pretty(report).expect("serialises") + "\n",
    )
    .map_err(io_at(&f))?;
    Ok(())
}

fn describe(c: &Consistency) -> String {
    format!(
        "footprint RMS {}, NIS {:.2} (band {:.2}–{:.2}), whiteness p {:.2}, bias ({:.5}, {:.5}, {:.5}) ± ({:.1e}, {:.1e}, {:.1e}) rad/s",
        c.gcp_rms_m.map_or("n/a".into(), |v| format!("{v:.2} m")),
        c.nis_mean,
        c.nis_band[0],
        c.nis_band[1],
        c.whiteness_p,
        c.bias_rad_s[0],
        c.bias_rad_s[1],
        c.bias_rad_s[2],
        c.bias_sd_rad_s[0],
        c.bias_sd_rad_s[1],
        c.bias_sd_rad_s[2]
    )
}
