//! One run of a model and its residuals: the heading residuals with their regressors, the
//! consistency figures (NIS, whiteness, footprint error) and the ranked effects.

use super::ranking::{Finding, rank_effects};
use crate::core::heading::Candidates;
use crate::eval::EvalOptions;
use crate::runner::{RunError, heading_aid, run_log};
use crate::stats::{self, nis_consistency, whiteness};
use corridor_shared::config::{ConfigFile, Mode};
use corridor_shared::imu_csv::ImuLog;
use corridor_shared::injection::BiasInjection;
use corridor_shared::truth_csv::TruthPoint;
use nalgebra::{UnitQuaternion, Vector3};
use serde::Serialize;
use std::path::Path;

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

/// Which heading a stance residual compares with the map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ResidualKind {
    /// The foot axis (the heading the model predicts for the foot).
    FootAxis,
    /// The stride direction: from the previous stance's position to this one's.
    Stride,
}

/// The heading residual of one stance, used or not: the most likely map direction (the
/// nearest) minus the heading, with the probability that the walker walked along that
/// direction ([`association_weight`](crate::core::estimator::association_weight) with
/// [`DIAGNOSIS_ALIGNED_PRIOR`]).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct StanceResidual {
    /// Index of the sample in the log (the same stance in a run of the same log with an
    /// injected error).
    pub sample: usize,
    /// Time, s.
    pub t_s: f64,
    /// Foot axis or stride direction.
    pub kind: ResidualKind,
    /// Nearest map direction minus the heading, rad.
    pub r_rad: f64,
    /// The nearest map direction, rad.
    pub direction_rad: f64,
    /// Association weight (0–1).
    pub weight: f64,
    /// The σ the weight was computed with, rad.
    pub sd_rad: f64,
    /// The other directions the walker may have walked along there (a junction's too).
    #[serde(skip)]
    pub candidates: Candidates,
    /// The filter used this observation (foot axis only).
    pub accepted: bool,
    /// The residual a unit amount of each effect of [`super::power::REFERENCES`] would add at
    /// this stance (see [`super::power`]).
    pub signature: [f64; super::power::N_REFERENCES],
}

/// Prior probability of walking along a map direction used to weigh every stance's residual:
/// the shipped `heading.aligned_prior` of `configs/gdins.toml` (chosen there on the weave
/// strides of the suite), independent of the gate the model under diagnosis uses.
pub const DIAGNOSIS_ALIGNED_PRIOR: f64 = 0.7;

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
    /// Why the footprints given could not be scored against this run (another clock, too few),
    /// when they could not: [`super::judge_names`] refuses the diagnosis then.
    #[serde(skip)]
    pub truth_error: Option<crate::eval::EvalError>,
    /// What the scoring of the footprints warned of (footprints outside the log's span,
    /// clamped to its ends), as `corridor run`'s `summary.json` gives it.
    #[serde(skip)]
    pub truth_warnings: Vec<String>,
    /// What the input cost the run, when anything ([`crate::runner::RunOutcome::input_report`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub input: Option<String>,
    /// Consistency figures.
    pub consistency: Consistency,
    /// Effects, best first.
    pub effects: Vec<Finding>,
    /// Final gyro scale factors per sensor axis with their σ, when the model estimates them.
    pub scale_factor: Option<[[f64; 2]; 3]>,
    /// Final cross-couplings into the sensor z axis (from x, from y), rad, with their σ, when
    /// the model estimates them.
    pub coupling_z_rad: Option<[[f64; 2]; 2]>,
    /// Final g-sensitivity per sensor axis, rad/s per m/s², with its σ, when the model
    /// estimates it.
    pub g_sensitivity: Option<[[f64; 2]; 3]>,
    /// The stride scale against the footprints (with truth only).
    pub stride_length: Option<super::StrideLength>,
    /// Every surveyed leg's `(estimated, surveyed)` length, m (with truth only;
    /// [`super::stride_length::leg_lengths`]).
    #[serde(skip)]
    pub legs: Vec<Option<(f64, f64)>>,
    /// The residuals (for plots and the report).
    #[serde(skip)]
    pub residuals: Vec<HeadingResidual>,
    /// The heading residuals of every stance (foot axis and stride direction).
    #[serde(skip)]
    pub stances: Vec<StanceResidual>,
    /// The model fused no heading observation (foot axis or stride direction) at any of its
    /// stances: its heading was never held by the map, and its stance residuals then measure
    /// how far off its corridors it is, whatever put it there (a start in a weave, a wrong start
    /// heading, or an effect as large as a 5 % z scale factor on a spiral). The report says so
    /// beside what it names.
    #[serde(skip)]
    pub heading_never_held: bool,
    /// The power of this walk for the catalogue's effects.
    pub power: Vec<super::power::Power>,
    /// The test of the filter's bias estimate against its random walk (error-state modes
    /// without bias-rate states).
    pub bias_change: Option<super::bias_change::BiasChange>,
    /// The model is one whose bias the test above applies to (a random walk in the error-state
    /// filter), and tracking began: without a test then, the walk was too short for it (or no
    /// block had a usable σ).
    pub bias_change_applies: bool,
    /// The bias change that came with the onset of walking (see
    /// [`super::bias_change::onset_change`]).
    pub onset: Option<super::bias_change::OnsetChange>,
}

/// Runs the model of `file` on `log` and analyses its residuals, with the power of the walk
/// for each effect (see [`super::power`]).
pub fn analyse(
    log: &ImuLog,
    file: &ConfigFile,
    truth: Option<&[TruthPoint]>,
    map: Option<&Path>,
) -> Result<Analysis, RunError> {
    let cfg = file.validate()?;
    let aid = heading_aid(&cfg, map)?;
    let grid = cfg.heading.grid_rad.get();
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
    let mut stances = Vec::new();
    let mut sample = 0usize;
    let mut last_stance_xy: Option<[f64; 2]> = None;
    let sd_foot = cfg.heading.sigma_rad.get();
    let sd_stride = cfg.heading.stride_sigma_rad.get();
    let mut rest_n = 0u32;
    // yaw error built up by a unit amount of each effect since the filter last removed it
    let mut yaw_error = [0.0; super::power::N_REFERENCES];
    let mut tracking_from_s: Option<f64> = None;
    // Σ (f − f_rest) and its samples over the bias-change test's first block (sensor axes)
    let mut onset_sum = (Vector3::zeros(), 0u32);
    let outcome = run_log(log, &cfg, &aid, &BiasInjection::default(), |input, e| {
        sample += 1;
        let w = Vector3::from(input.gyro_rad_s);
        let f = Vector3::from(input.accel_m_s2);
        let dt = last_t.map_or(0.0, |t| input.t_s - t);
        last_t = Some(input.t_s);
        if e.phase == crate::core::Phase::Aligning {
            if e.stance {
                rest_sum += f;
                rest_n += 1;
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
        if e.phase == crate::core::Phase::Tracking {
            let from = *tracking_from_s.get_or_insert(e.t_s);
            let f_rest = rest_sum / f64::from(rest_n.max(1));
            let first = from + super::bias_change::SETTLE_S;
            if (first..first + super::bias_change::BLOCK_S).contains(&e.t_s) {
                onset_sum.0 += f - f_rest;
                onset_sum.1 += 1;
            }
            for (k, r) in super::power::REFERENCES.iter().enumerate() {
                yaw_error[k] += (q * (r.rate_error)(&w, &f, &f_rest)).z * dt;
            }
        } else {
            yaw_error = [0.0; super::power::N_REFERENCES]; // the frame is set at calibration
        }
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
        // Every stance: the foot axis and the stride direction against the nearest map
        // direction, weighted by the probability of walking along it.
        let xy = [e.p_m[0], e.p_m[1]];
        // What an update leaves of the yaw error: R/S.
        let leaves = |o: &Result<crate::core::eskf::Innovation, _>, sd: f64| match o {
            Ok(i) if i.dim == 1 && i.s_diag[0] > 0.0 => (sd * sd / i.s_diag[0]).min(1.0),
            _ => 1.0,
        };
        let stride_signature = yaw_error.map(|v| -v);
        if let Some(s) = &e.stride {
            let k = leaves(&s.outcome, sd_stride);
            yaw_error.iter_mut().for_each(|v| *v *= k);
        }
        let foot_signature = yaw_error.map(|v| -v);
        let k = leaves(&h.outcome, sd_foot);
        yaw_error.iter_mut().for_each(|v| *v *= k);
        let mut push = |kind, heading: f64, sd: f64, accepted, signature| {
            if let Ok((d, candidates)) = aid.associate_among(xy, heading, std::f64::consts::PI) {
                let r = crate::core::rotation::wrap_pi(d - heading);
                stances.push(StanceResidual {
                    sample,
                    t_s: e.t_s,
                    kind,
                    r_rad: r,
                    direction_rad: d,
                    weight: crate::core::estimator::association_weight(
                        r,
                        sd * sd,
                        DIAGNOSIS_ALIGNED_PRIOR,
                        &candidates,
                    ),
                    sd_rad: sd,
                    candidates,
                    accepted,
                    signature,
                });
            }
        };
        if h.foot_heading_rad.is_finite() {
            push(
                ResidualKind::FootAxis,
                h.foot_heading_rad,
                sd_foot,
                h.outcome.is_ok(),
                foot_signature,
            );
        }
        if let Some(prev) = last_stance_xy {
            let (dx, dy) = (xy[0] - prev[0], xy[1] - prev[1]);
            if dx.hypot(dy) >= cfg.heading.min_stride_m.get() {
                push(
                    ResidualKind::Stride,
                    dy.atan2(dx),
                    sd_stride,
                    false,
                    stride_signature,
                );
            }
        }
        last_stance_xy = Some(xy);
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
    // A log that never aligned has nothing to diagnose: `corridor run`'s error, not a report
    // of NaN (a review: `diagnose` on 2 s of rest wrote one and exited 0).
    let c = &outcome.counters;
    if c.samples > 0 && outcome.mount_yaw_rad.is_none() && c.stances == 0 {
        return Err(RunError::NeverAligned {
            path: log.path.clone(),
            min_rest_s: cfg.alignment.min_rest_s.get(),
            not_gravity: c.alignment_not_gravity,
        });
    }
    let n = outcome.trace.t_s.len();
    let (bias, bias_sd) = if n > 0 {
        (
            outcome.trace.bias_rad_s[n - 1],
            outcome.trace.bias_sd_rad_s[n - 1],
        )
    } else {
        ([f64::NAN; 3], [f64::NAN; 3])
    };
    let evaluated = truth.map(|t| outcome.trace.evaluate(t, &EvalOptions::default()));
    let truth_error = evaluated.as_ref().and_then(|r| r.as_ref().err().cloned());
    let eval = evaluated.and_then(Result::ok);
    let truth_warnings = eval.as_ref().map_or_else(Vec::new, |e| e.warnings.clone());
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
    let mut effects = rank_effects(&used, cfg.mode);
    // The bias is a pure random walk in the error-state filter unless bias-rate states drive it.
    let from_s = tracking_from_s.filter(|_| {
        matches!(cfg.mode, Mode::Eskf | Mode::Zupt)
            && file.model.bias_rate_rw_rad_s2_sqrt_s.is_none()
    });
    let trace = from_s.map(|from_s| super::bias_change::BiasTrace {
        t_s: &outcome.trace.t_s,
        bias_rad_s: &outcome.trace.bias_rad_s,
        bias_sd_rad_s: &outcome.trace.bias_sd_rad_s,
        rw_rad_s_sqrt_s: cfg.eskf.gyro_bias_rw_rad_s_sqrt_s.get(),
        from_s,
    });
    let mut bias_change = trace.and_then(|t| t.change());
    let onset_force = (onset_sum.1 > 0).then(|| onset_sum.0 / f64::from(onset_sum.1));
    let onset = bias_change
        .as_ref()
        .zip(onset_force)
        .and_then(|(c, f)| super::bias_change::onset_change(c, &f.into()));
    // A change that came with the motion is the motion's: the drift test goes on across it.
    if let (Some(o), Some(t)) = (onset.filter(|o| o.explains()), trace) {
        bias_change = t.change_across(&o.force_m_s2);
    }
    if let Some(c) = &bias_change {
        super::bias_change::apply_bias_change(&mut effects, c);
    }
    // First among equals: a rail explains the bias changes it causes.
    if let Some(f) = super::clipping::clipping_finding(
        &super::clipping::find_rails(&log.rows),
        cfg.sensor.gyro_range_rad_s(),
        // the error-state filter widens its attitude at a clipped sample and puts the peak
        // back; the paper's does neither
        (cfg.eskf.clipped_rate_sd_rad_s.get() > 0.0 || cfg.eskf.restore_clipped_peaks)
            && matches!(cfg.mode, Mode::Eskf | Mode::Zupt),
    ) {
        effects.insert(0, f);
    }
    let power = super::power::walk_power(&stances);
    super::power::apply_power(
        &mut effects,
        &power,
        matches!(cfg.mode, Mode::Eskf | Mode::Zupt),
    );
    if let Some(o) = &onset {
        super::bias_change::apply_onset_change(&mut effects, o);
    }
    // (Both kinds: with `heading.observations = "stride"`, or strides holding the heading while
    // every foot axis is refused, no foot-axis residual is accepted.)
    let heading_never_held =
        outcome.counters.heading_used + outcome.counters.stride_used == 0 && !stances.is_empty();
    let scale_factor = outcome.extensions.and_then(|(x, sd)| {
        sd.scale_factor
            .map(|sd| std::array::from_fn(|k| [x.scale_factor[k], sd[k]]))
    });
    let coupling_z_rad = outcome.extensions.and_then(|(x, sd)| {
        sd.coupling_z_rad
            .map(|sd| std::array::from_fn(|k| [x.coupling_z_rad[k], sd[k]]))
    });
    let g_sensitivity = outcome.extensions.and_then(|(x, sd)| {
        sd.g_sensitivity
            .map(|sd| std::array::from_fn(|k| [x.g_sensitivity[k], sd[k]]))
    });
    Ok(Analysis {
        model: model_keys(file),
        truth_error,
        truth_warnings,
        input: outcome.input_report(log),
        consistency,
        effects,
        scale_factor,
        coupling_z_rad,
        g_sensitivity,
        stride_length: truth.and_then(|t| super::stride_length(&outcome.trace, t)),
        legs: truth.map_or_else(Vec::new, |t| {
            super::stride_length::leg_lengths(&outcome.trace, t)
        }),
        residuals: res,
        stances,
        heading_never_held,
        power,
        bias_change,
        bias_change_applies: trace.is_some(),
        onset,
    })
}

impl Analysis {
    /// The stride-length line of this analysis of the model `file` (with truth only).
    pub fn stride_line(&self, file: &ConfigFile) -> Option<super::StrideLine> {
        let rolling = file.eskf.zupt_rolling_height_m.unwrap_or(0.0) > 0.0;
        self.stride_length.map(|fit| super::StrideLine {
            fit,
            finding: super::stride_length::stride_length_finding(&fit, rolling),
        })
    }

    /// The sensor-error states' final estimates with their σ, in words.
    pub fn estimates_in_words(&self) -> Vec<String> {
        let mut v = Vec::new();
        if let Some(sf) = self.scale_factor {
            for (axis, [s, sd]) in ["x", "y", "z"].iter().zip(sf) {
                v.push(format!(
                    "{axis} scale factor {:+.2} % ± {:.2} %",
                    100.0 * s,
                    100.0 * sd
                ));
            }
        }
        if let Some(m) = self.coupling_z_rad {
            for (from, [c, sd]) in ["x", "y"].iter().zip(m) {
                v.push(format!(
                    "z←{from} coupling {:+.2}° ± {:.2}°",
                    c.to_degrees(),
                    sd.to_degrees()
                ));
            }
        }
        // (a kept g-sensitivity was reported with no estimate, a review)
        if let Some(g) = self.g_sensitivity {
            for (axis, [k, sd]) in ["x", "y", "z"].iter().zip(g) {
                v.push(format!(
                    "{axis} g-sensitivity {k:+.2e} ± {sd:.2e} rad/s per m/s²"
                ));
            }
        }
        v
    }
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

/// The final model in words: [`model_keys`] of `end`, and the settings the gyro rail's fix and
/// the stride scale's change where they differ from `start`'s (a loop that kept them listed a
/// final model without them, read as the starting one, a review).
pub(super) fn final_model_words(start: &ConfigFile, end: &ConfigFile) -> Vec<String> {
    let mut v = model_keys(end);
    let mode = v.pop();
    if let Some(r) = end
        .sensor
        .gyro_range_rad_s
        .filter(|_| end.sensor.gyro_range_rad_s != start.sensor.gyro_range_rad_s)
    {
        v.push(format!("gyro_range = {r:.3} rad/s"));
    }
    if let Some(k) = end
        .model
        .accel_scale_factor
        .filter(|_| end.model.accel_scale_factor != start.model.accel_scale_factor)
    {
        v.push(format!("accel_scale_factor = {:+.2} %", 100.0 * k));
    }
    v.extend(mode);
    v
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
    if m.gyro_coupling_z_sd_deg.is_some() {
        v.push("gyro_coupling_z".into());
    }
    if let Some(h) = file.eskf.zupt_rolling_height_m.filter(|&h| h > 0.0) {
        v.push(format!("zupt_rolling_height = {h} m"));
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
