//! The results table: every recording of a suite through the baselines and the bias modes, with
//! footprint error and injected-bias recovery (`corridor eval --suite FILE`).
//!
//! Per recording:
//! - (1) `zupt`: the ZUPT filter alone, no prior (the standard foot INS).
//! - (1b) `zupt+rest`: the same with the gyro mean of the first rest subtracted.
//! - (2) `zupt+inj`: the injected bias, uncorrected (ZUPT filter, no prior).
//! - (3) `paper+inj`: the paper's mode with the injected bias, no prior.
//! - (4) `best+inj`: the best mode with the injected bias, no prior.
//!
//! Recovery = (bias with injection − bias without) / injected, averaged over the samples after
//! both runs have converged (the real-time σ criterion), no prior; and separately with the
//! rest-mean prior and the injection starting when the initial rest ends.

use crate::eval::EvalOptions;
use crate::runner::{self, RunError, RunOutcome, heading_aid};
use corridor_shared::config::{BiasPrior, Config, ConfigFile, Mode};
use corridor_shared::imu_csv::{ImuCsvOptions, ImuLog, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::truth_csv::{TruthPoint, read_truth_csv};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The suite file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SuiteFile {
    /// Injected bias for the recovery rows, rad/s (default the paper's [0.001, 0.001, 0.005]).
    #[serde(default)]
    pub inject_gyro_bias_rad_s: Option<[f64; 3]>,
    /// The mode reported as "best" (default `eskf`).
    #[serde(default)]
    pub best_mode: Option<Mode>,
    /// Recordings.
    #[serde(rename = "recording")]
    pub recordings: Vec<SuiteRecording>,
}

/// One recording of the suite; paths are relative to the suite file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SuiteRecording {
    /// Short name.
    pub name: String,
    /// IMU log.
    pub imu: PathBuf,
    /// Footprint truth.
    pub truth: PathBuf,
    /// Sensor configuration (one per sensor).
    pub config: PathBuf,
    /// Configuration of the ZUPT baselines (rows 1, 1b, 2), when their noise set differs from
    /// the default's (one per sensor; default: `config`).
    #[serde(default)]
    pub baseline_config: Option<PathBuf>,
    /// Walking direction of the first leg in the map frame, degrees (map knowledge).
    pub start_heading_deg: f64,
    /// Grid orientation, degrees.
    #[serde(default)]
    pub grid_deg: f64,
    /// Gait of the walk: fast or varying gait is reported but kept out of the normal-gait
    /// summary.
    #[serde(default)]
    pub gait: Gait,
}

/// The gait of a suite recording, as its data set documents it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Gait {
    /// Normal walking.
    #[default]
    Normal,
    /// Fast or varying gait.
    Fast,
}

/// Errors of the suite.
#[derive(Debug, thiserror::Error)]
pub enum SuiteError {
    /// Suite file unreadable or invalid.
    #[error("{path}: {message}")]
    File {
        /// File.
        path: PathBuf,
        /// Cause.
        message: String,
    },
    /// A run failed.
    #[error("recording {name}: {source}")]
    Run {
        /// Recording.
        name: String,
        /// Cause.
        source: Box<RunError>,
    },
}

/// Footprint figures of one run.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Footprint {
    /// RMS over the GCPs after first-leg alignment, m.
    pub rms_m: f64,
    /// RMS as % of the truth path length.
    pub rms_pct: f64,
    /// Error at the last GCP, m.
    pub final_m: f64,
}

/// One row of the results table.
#[derive(Debug, Clone, Serialize)]
pub struct SuiteRow {
    /// Recording.
    pub recording: String,
    /// Its gait.
    pub gait: Gait,
    /// Truth path length, m.
    pub path_m: f64,
    /// 1. ZUPT filter alone.
    pub zupt: Footprint,
    /// 1b. ZUPT filter with the rest-mean prior.
    pub zupt_rest: Footprint,
    /// Best mode without injection, no prior.
    pub best: Footprint,
    /// Best mode without injection, with the rest-mean prior.
    pub best_rest: Footprint,
    /// 2. Injected, uncorrected.
    pub zupt_inj: Footprint,
    /// 3. Paper mode, injected.
    pub paper_inj: Footprint,
    /// 4. Best mode, injected.
    pub best_inj: Footprint,
    /// Recovery of the paper mode, per axis (fraction), no prior.
    pub paper_recovery: [f64; 3],
    /// Recovery of the best mode, per axis, no prior.
    pub best_recovery: [f64; 3],
    /// Recovery of the best mode with the prior and the injection after the first rest.
    pub best_recovery_prior_late: [f64; 3],
    /// Convergence time of the best mode with injection (s after the start of the log).
    pub best_converged_at_s: Option<f64>,
    /// Convergence time of the paper mode with injection.
    pub paper_converged_at_s: Option<f64>,
    /// Hindsight: when the best mode's recovered bias settles within ±5 % (no prior).
    pub best_settled_at_s: Option<f64>,
    /// Hindsight: the same with the prior and the injection after the rest.
    pub best_settled_prior_late_at_s: Option<f64>,
    /// Error reduction of the best mode over the uncorrected injected run, %.
    pub best_reduction_pct: f64,
    /// Stances of the default run (best mode, rest-mean prior).
    pub stances: u64,
    /// Foot-axis heading observations used in the default run.
    pub heading_used: u64,
    /// Stride-direction observations used in the default run.
    pub stride_used: u64,
    /// NIS of the default run: the first ZUPT of each stance, the stride directions and the
    /// foot axes used.
    pub nis: [Option<NisFigure>; 3],
    /// Use of heading information on straight and weave strides (walks with every footprint).
    pub stride_use: Option<StrideUse>,
    /// Stride-length ratio of the default run: the summed distances between its positions at
    /// the surveyed footprints over the surveyed distances.
    pub stride_ratio: f64,
    /// Detected stances against the surveyed footprints (walks with every footprint).
    pub stances_found: Option<StanceMatch>,
}

/// Detected stances against the footprint list: a listed footprint (the end of its stance)
/// is found when a detected stance ends within [`STANCE_MATCH_S`] of it.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct StanceMatch {
    /// Listed footprints.
    pub listed: usize,
    /// Of them, found.
    pub found: usize,
    /// Detected stances within the listed span.
    pub detected: usize,
    /// Of them, matching a listed footprint.
    pub matching: usize,
}

/// Largest distance between a detected and a listed stance end, s.
pub const STANCE_MATCH_S: f64 = 0.05;

impl StanceMatch {
    fn of(truth: &[TruthPoint], stances: &[(f64, f64)]) -> Self {
        let (t0, t1) = match (truth.first(), truth.last()) {
            (Some(a), Some(b)) => (a.t_s - STANCE_MATCH_S, b.t_s + STANCE_MATCH_S),
            _ => return Self::default(),
        };
        let near = |a: f64, b: f64| (a - b).abs() <= STANCE_MATCH_S;
        let detected: Vec<f64> = stances
            .iter()
            .map(|s| s.1)
            .filter(|&e| e >= t0 && e <= t1)
            .collect();
        Self {
            listed: truth.len(),
            found: truth
                .iter()
                .filter(|p| detected.iter().any(|&e| near(e, p.t_s)))
                .count(),
            detected: detected.len(),
            matching: detected
                .iter()
                .filter(|&&e| truth.iter().any(|p| near(e, p.t_s)))
                .count(),
        }
    }

    /// Found / listed.
    pub fn recall(&self) -> f64 {
        self.found as f64 / self.listed.max(1) as f64
    }

    /// Matching / detected.
    pub fn precision(&self) -> f64 {
        self.matching as f64 / self.detected.max(1) as f64
    }
}

/// Summed distances between the run's positions at the truth footprints over the surveyed
/// distances.
fn stride_ratio(trace: &runner::Trace, truth: &[TruthPoint]) -> f64 {
    let at = |t: f64| {
        let i = trace
            .t_s
            .partition_point(|&x| x < t)
            .min(trace.t_s.len().saturating_sub(1));
        trace.xy_m.get(i).copied().unwrap_or([f64::NAN; 2])
    };
    let (mut est, mut sur) = (0.0, 0.0);
    for w in truth.windows(2) {
        let (a, b) = (at(w[0].t_s), at(w[1].t_s));
        est += (b[0] - a[0]).hypot(b[1] - a[1]);
        sur += (w[1].x_m - w[0].x_m).hypot(w[1].y_m - w[0].y_m);
    }
    est / sur
}

/// What the suite measures on the default run besides the footprint error.
struct DefaultFigures {
    nis: [Option<NisFigure>; 3],
    stride_use: Option<StrideUse>,
    stride_ratio: f64,
    stances_found: Option<StanceMatch>,
}

/// The mean NIS of one update type against its two-sided 95 % χ² band.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct NisFigure {
    /// Mean NIS per degree of freedom.
    pub mean: f64,
    /// Lower bound of the band, per degree of freedom.
    pub lower: f64,
    /// Upper bound of the band, per degree of freedom.
    pub upper: f64,
    /// Updates.
    pub n: usize,
}

impl NisFigure {
    fn of(nis: &[f64], dof: usize) -> Option<Self> {
        let t = crate::stats::nis_consistency(nis, dof, 0.95).ok()?;
        let d = dof as f64;
        Some(Self {
            mean: t.mean / d,
            lower: t.lower / d,
            upper: t.upper / d,
            n: t.n,
        })
    }

    /// Whether the mean lies inside the band.
    pub fn in_band(&self) -> bool {
        (self.lower..=self.upper).contains(&self.mean)
    }
}

/// How the default run used heading information on the strides of a walk whose every
/// footprint is surveyed. A truth stride lies on a *straight stretch* when it and both
/// neighbours point within [`STRAIGHT_DEG`] of one dominant direction; it is a *weave* when it
/// points more than [`WEAVE_DEG`] off the dominant direction that both neighbours follow (within
/// [`WEAVE_DEG`]). Turns are neither.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct StrideUse {
    /// Straight-stretch strides.
    pub straight: usize,
    /// Of them, strides whose stance used a stride-direction or foot-axis observation.
    pub straight_used: usize,
    /// Weave strides.
    pub weave: usize,
    /// Of them, strides whose direction was used as a stride-direction observation.
    pub weave_used: usize,
    /// Of them, strides whose stance used the foot axis (in a side-step the foot may still
    /// point along the corridor: not an error in itself).
    pub weave_foot_used: usize,
}

/// Largest deviation from the dominant direction of a straight-stretch stride, degrees.
pub const STRAIGHT_DEG: f64 = 5.0;
/// Smallest deviation of a weave stride, degrees.
pub const WEAVE_DEG: f64 = 10.0;

impl StrideUse {
    /// Classifies the truth strides (grid spacing `step_rad` from `grid_rad`) and counts the
    /// stances (time, heading information used) of the run that fall in each stride's window
    /// (after the previous footprint, up to its own). `None` unless every stride is surveyed.
    fn of(
        truth: &[TruthPoint],
        grid_rad: f64,
        step_rad: f64,
        stances: &[StanceUse],
    ) -> Option<Self> {
        let every = truth.windows(2).all(|w| match (w[0].stride, w[1].stride) {
            (Some(a), Some(b)) => b == a + 1,
            _ => false,
        });
        if !every || truth.len() < 4 {
            return None;
        }
        let wrap = crate::core::rotation::wrap_pi;
        // (time of the footprint ending the stride, nearest dominant direction index, deviation)
        let strides: Vec<(f64, f64, i64, f64)> = truth
            .windows(2)
            .map(|w| {
                let d = (w[1].y_m - w[0].y_m).atan2(w[1].x_m - w[0].x_m);
                let k = ((d - grid_rad) / step_rad).round();
                let dev = wrap(d - grid_rad - k * step_rad).abs().to_degrees();
                let n = (std::f64::consts::TAU / step_rad).round() as i64;
                (w[0].t_s, w[1].t_s, (k as i64).rem_euclid(n.max(1)), dev)
            })
            .collect();
        let mut u = StrideUse::default();
        for i in 1..strides.len().saturating_sub(1) {
            let (prev, cur, next) = (strides[i - 1], strides[i], strides[i + 1]);
            let straight = [prev, cur, next]
                .iter()
                .all(|s| s.2 == cur.2 && s.3 <= STRAIGHT_DEG);
            let weave = prev.2 == next.2
                && prev.3 <= WEAVE_DEG
                && next.3 <= WEAVE_DEG
                && (cur.2 != prev.2 || cur.3 > WEAVE_DEG);
            if !(straight || weave) {
                continue;
            }
            let inside = |s: &&StanceUse| s.t_s > cur.0 && s.t_s <= cur.1;
            let stride = stances.iter().filter(inside).any(|s| s.stride);
            let foot = stances.iter().filter(inside).any(|s| s.foot_axis);
            if straight {
                u.straight += 1;
                u.straight_used += usize::from(stride || foot);
            } else {
                u.weave += 1;
                u.weave_used += usize::from(stride);
                u.weave_foot_used += usize::from(foot);
            }
        }
        Some(u)
    }
}

/// One stance's use of heading information.
#[derive(Debug, Clone, Copy)]
struct StanceUse {
    t_s: f64,
    stride: bool,
    foot_axis: bool,
}

/// The NIS of one run, by update type, and its stances with the use of heading information.
#[derive(Debug, Default)]
struct NisSeries {
    zupt_first: Vec<f64>,
    stride: Vec<f64>,
    heading: Vec<f64>,
    in_stance: bool,
    stances: Vec<StanceUse>,
    /// Detected stance intervals (start, end), s.
    intervals: Vec<(f64, f64)>,
    detector_stance: Option<f64>,
    last_t_s: f64,
}

impl NisSeries {
    fn push(&mut self, e: &crate::core::Estimate) {
        match (e.stance, self.detector_stance) {
            (true, None) => self.detector_stance = Some(e.t_s),
            (false, Some(start)) => {
                self.intervals.push((start, self.last_t_s));
                self.detector_stance = None;
            }
            _ => {}
        }
        self.last_t_s = e.t_s;
        match &e.zupt {
            Some(z) if !self.in_stance => {
                self.zupt_first.push(z.nis);
                self.in_stance = true;
            }
            Some(_) => {}
            None => self.in_stance = false,
        }
        let mut used = [false; 2];
        for (k, (h, v)) in [
            (&e.stride, &mut self.stride),
            (&e.heading, &mut self.heading),
        ]
        .into_iter()
        .enumerate()
        {
            if let Some(Ok(i)) = h.as_ref().map(|h| h.outcome) {
                v.push(i.nis);
                used[k] = true;
            }
        }
        if e.stride.is_some() || e.heading.is_some() {
            self.stances.push(StanceUse {
                t_s: e.t_s,
                stride: used[0],
                foot_axis: used[1],
            });
        }
    }

    fn figures(&self) -> [Option<NisFigure>; 3] {
        [
            NisFigure::of(&self.zupt_first, 3),
            NisFigure::of(&self.stride, 1),
            NisFigure::of(&self.heading, 1),
        ]
    }
}

/// Reads a suite file.
pub fn read_suite(path: &Path) -> Result<SuiteFile, SuiteError> {
    let text = std::fs::read_to_string(path).map_err(|e| SuiteError::File {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    toml::from_str(&text).map_err(|e| SuiteError::File {
        path: path.to_owned(),
        message: e.to_string(),
    })
}

/// The residual-diagnosis loop on every recording of a suite, starting from the paper's model
/// (the sensor configuration without its `[model]` extensions, `mode = paper`). Writes each
/// report under `out/<recording>/` and returns the summary table (Markdown).
pub fn run_loops(path: &Path, out: &Path) -> Result<String, SuiteError> {
    let suite = read_suite(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let mut md = String::from(
        "| recording | effects added, in order (score = −log₁₀ p) | footprint RMS before → after | heading NIS before → after | left |\n|---|---|---|---|---|\n",
    );
    for r in &suite.recordings {
        let wrap = |source: RunError| SuiteError::Run {
            name: r.name.clone(),
            source: Box::new(source),
        };
        let log = read_imu_csv(&base.join(&r.imu), &ImuCsvOptions::default())
            .map_err(|e| wrap(e.into()))?;
        let truth = read_truth_csv(&base.join(&r.truth)).map_err(|e| wrap(e.into()))?;
        let mut file = ConfigFile::read(&base.join(&r.config)).map_err(|e| wrap(e.into()))?;
        file.model = Default::default();
        file.estimator.mode = Some(Mode::Paper);
        file.heading.start_heading_deg = Some(r.start_heading_deg);
        file.heading.grid_deg = Some(r.grid_deg);
        let crate::diagnose::Diagnosis {
            report,
            before,
            after,
            ..
        } = crate::diagnose::run_diagnosis(&log, &file, Some(&truth), None).map_err(wrap)?;
        let dir = out.join(r.name.replace(' ', "_"));
        std::fs::create_dir_all(&dir).map_err(|e| wrap(crate::runner::io_at(&dir)(e)))?;
        crate::diagnose::write_report(&dir, &report, &before, &after).map_err(wrap)?;
        let added: Vec<String> = report
            .iterations
            .iter()
            .map(|it| {
                format!(
                    "{} ({:.1}){}",
                    it.effect,
                    it.score,
                    if it.kept {
                        ""
                    } else {
                        " — tried, footprint error rose, not kept"
                    }
                )
            })
            .collect();
        let left = report
            .final_effects
            .first()
            .filter(|e| e.score >= crate::diagnose::SIGNIFICANT)
            .map_or("nothing significant".to_string(), |e| {
                format!("{} ({:.1})", e.name, e.score)
            });
        let rms = |c: &crate::diagnose::Consistency| {
            c.gcp_rms_m.map_or("—".into(), |v| format!("{v:.2} m"))
        };
        md.push_str(&format!(
            "| {} | {} | {} → {} | {:.2} → {:.2} | {} |\n",
            r.name,
            if added.is_empty() {
                "none".to_string()
            } else {
                added.join(", ")
            },
            rms(&report.before),
            rms(&report.after),
            report.before.nis_mean,
            report.after.nis_mean,
            left
        ));
    }
    Ok(md)
}

/// Runs the suite (the table's rows).
pub fn run_suite(path: &Path) -> Result<Vec<SuiteRow>, SuiteError> {
    let suite = read_suite(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let inj = suite
        .inject_gyro_bias_rad_s
        .unwrap_or([0.001, 0.001, 0.005]);
    let best_mode = suite.best_mode.unwrap_or(Mode::Eskf);
    suite
        .recordings
        .iter()
        .map(|r| {
            run_recording(base, r, inj, best_mode).map_err(|source| SuiteError::Run {
                name: r.name.clone(),
                source: Box::new(source),
            })
        })
        .collect()
}

/// The recording's configuration with the mode, prior and map knowledge of one suite row.
fn config_for(
    file: &ConfigFile,
    path: &Path,
    r: &SuiteRecording,
    mode: Mode,
    prior: BiasPrior,
) -> Result<Config, RunError> {
    let mut file = file.clone();
    file.estimator.mode = Some(mode);
    file.alignment.gyro_bias_prior = Some(prior);
    file.heading.start_heading_deg = Some(r.start_heading_deg);
    file.heading.grid_deg = Some(r.grid_deg);
    Ok(file
        .validate()
        .map_err(|e| corridor_shared::config::with_path(e, path))?)
}

struct Ctx<'a> {
    base: &'a Path,
    rec: &'a SuiteRecording,
    config: ConfigFile,
    baseline: ConfigFile,
    log: ImuLog,
    truth: Vec<TruthPoint>,
}

impl Ctx<'_> {
    fn run(
        &self,
        mode: Mode,
        prior: BiasPrior,
        inj: BiasInjection,
    ) -> Result<(RunOutcome, Footprint), RunError> {
        self.run_with(&self.config, mode, prior, inj)
    }

    /// A ZUPT baseline run, with the baseline's configuration.
    fn run_baseline(
        &self,
        prior: BiasPrior,
        inj: BiasInjection,
    ) -> Result<(RunOutcome, Footprint), RunError> {
        self.run_with(&self.baseline, Mode::Zupt, prior, inj)
    }

    /// The NIS of the default run (the best mode with the rest-mean prior) and its use of
    /// heading information on the truth strides.
    fn default_figures(&self, mode: Mode) -> Result<DefaultFigures, RunError> {
        let cfg = config_for(
            &self.config,
            &self.base.join(&self.rec.config),
            self.rec,
            mode,
            BiasPrior::RestMean,
        )?;
        let aid = heading_aid(&cfg, None)?;
        let mut nis = NisSeries::default();
        let out = runner::run_log(&self.log, &cfg, &aid, &BiasInjection::default(), |_, e| {
            nis.push(e)
        });
        let grid = &cfg.heading;
        let stride_use = StrideUse::of(
            &self.truth,
            grid.grid_rad,
            grid.grid_step_rad.get(),
            &nis.stances,
        );
        Ok(DefaultFigures {
            nis: nis.figures(),
            stances_found: stride_use.map(|_| StanceMatch::of(&self.truth, &nis.intervals)),
            stride_use,
            stride_ratio: stride_ratio(&out.trace, &self.truth),
        })
    }

    fn run_with(
        &self,
        file: &ConfigFile,
        mode: Mode,
        prior: BiasPrior,
        inj: BiasInjection,
    ) -> Result<(RunOutcome, Footprint), RunError> {
        let cfg = config_for(
            file,
            &self.base.join(&self.rec.config),
            self.rec,
            mode,
            prior,
        )?;
        let aid = heading_aid(&cfg, None)?;
        let out = runner::run_log(&self.log, &cfg, &aid, &inj, |_, _| {});
        let rep = out
            .trace
            .evaluate(&self.truth, &EvalOptions::default())
            .map_err(|source| RunError::Eval {
                truth: self.base.join(&self.rec.truth),
                source,
            })?;
        let fp = Footprint {
            rms_m: rep.rms_error_m.unwrap_or(f64::NAN),
            rms_pct: rep.rms_error_pct_of_path.unwrap_or(f64::NAN),
            final_m: rep.final_gcp_error_m.unwrap_or(f64::NAN),
        };
        Ok((out, fp))
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

fn run_recording(
    base: &Path,
    r: &SuiteRecording,
    inj: [f64; 3],
    best: Mode,
) -> Result<SuiteRow, RunError> {
    let log = read_imu_csv(&base.join(&r.imu), &ImuCsvOptions::default())?;
    let truth = read_truth_csv(&base.join(&r.truth))?;
    let path_m = truth
        .windows(2)
        .map(|w| (w[1].x_m - w[0].x_m).hypot(w[1].y_m - w[0].y_m))
        .sum();
    let ctx = Ctx {
        base,
        rec: r,
        config: ConfigFile::read(&base.join(&r.config))?,
        baseline: ConfigFile::read(&base.join(r.baseline_config.as_ref().unwrap_or(&r.config)))?,
        log,
        truth,
    };
    let none = BiasInjection::default();
    let injected = BiasInjection {
        constant_rad_s: inj,
        ..Default::default()
    };
    let (_, zupt) = ctx.run_baseline(BiasPrior::None, none)?;
    let (_, zupt_rest) = ctx.run_baseline(BiasPrior::RestMean, none)?;
    let (_, zupt_inj) = ctx.run_baseline(BiasPrior::None, injected)?;
    let (paper0, _) = ctx.run(Mode::Paper, BiasPrior::None, none)?;
    let (paper1, paper_inj) = ctx.run(Mode::Paper, BiasPrior::None, injected)?;
    let (best0, best_fp) = ctx.run(best, BiasPrior::None, none)?;
    let (best1, best_inj) = ctx.run(best, BiasPrior::None, injected)?;
    let (best_r0, best_rest) = ctx.run(best, BiasPrior::RestMean, none)?;
    let fig = ctx.default_figures(best)?;
    let c = best_r0.counters;
    let (stances, heading_used, stride_used) = (c.stances, c.heading_used, c.stride_used);
    // The injection starts when the initial rest ends (the alignment instant of the clean run).
    let rest_end = best_r0
        .trace
        .t_s
        .first()
        .copied()
        .unwrap_or(0.0)
        .max(first_motion_s(&best_r0));
    let late = BiasInjection {
        constant_rad_s: inj,
        after_s: rest_end,
        ..Default::default()
    };
    let (best_r1, _) = ctx.run(best, BiasPrior::RestMean, late)?;
    Ok(SuiteRow {
        recording: r.name.clone(),
        gait: r.gait,
        path_m,
        zupt,
        zupt_rest,
        best: best_fp,
        best_rest,
        zupt_inj,
        paper_inj,
        best_inj,
        paper_recovery: recovery(&paper1, &paper0, inj),
        best_recovery: recovery(&best1, &best0, inj),
        best_recovery_prior_late: recovery(&best_r1, &best_r0, inj),
        best_converged_at_s: best1.converged_at_s,
        paper_converged_at_s: paper1.converged_at_s,
        best_settled_at_s: settled_at(&best1, &best0, inj),
        best_settled_prior_late_at_s: settled_at(&best_r1, &best_r0, inj),
        best_reduction_pct: 100.0 * (1.0 - best_inj.rms_m / zupt_inj.rms_m),
        stances,
        heading_used,
        stride_used,
        nis: fig.nis,
        stride_use: fig.stride_use,
        stride_ratio: fig.stride_ratio,
        stances_found: fig.stances_found,
    })
}

/// The end of the initial rest: the first sample whose bias σ is defined (the estimator has
/// aligned and navigates).
fn first_motion_s(o: &RunOutcome) -> f64 {
    o.trace
        .t_s
        .iter()
        .zip(&o.trace.bias_sd_rad_s)
        .find(|(_, sd)| sd[0].is_finite())
        .map_or(0.0, |(t, _)| *t)
}

/// How far the default may be worse than the baseline and still count as "not worse", % of path.
pub const NOT_WORSE_TOLERANCE_PCT: f64 = 0.05;

/// The headline over the normal-gait recordings: the default configuration (best mode with the
/// rest-mean prior) against the ZUPT + rest-mean baseline.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Summary {
    /// Normal-gait recordings.
    pub n: usize,
    /// Median footprint RMS of the baseline, % of path.
    pub baseline_median_pct: f64,
    /// Worst footprint RMS of the baseline, % of path.
    pub baseline_worst_pct: f64,
    /// Median footprint RMS of the default, % of path.
    pub default_median_pct: f64,
    /// Worst footprint RMS of the default, % of path.
    pub default_worst_pct: f64,
    /// Recordings on which the default is better than the baseline.
    pub default_better: usize,
    /// Recordings on which the default is worse than the baseline by more than
    /// [`NOT_WORSE_TOLERANCE_PCT`].
    pub default_worse: usize,
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The summary over the normal-gait rows.
pub fn summary(rows: &[SuiteRow]) -> Summary {
    let normal: Vec<&SuiteRow> = rows.iter().filter(|r| r.gait == Gait::Normal).collect();
    let mut base: Vec<f64> = normal.iter().map(|r| r.zupt_rest.rms_pct).collect();
    let mut def: Vec<f64> = normal.iter().map(|r| r.best_rest.rms_pct).collect();
    let worst = |v: &[f64]| v.iter().copied().fold(f64::NAN, f64::max);
    Summary {
        n: normal.len(),
        baseline_worst_pct: worst(&base),
        default_worst_pct: worst(&def),
        baseline_median_pct: median(&mut base),
        default_median_pct: median(&mut def),
        default_better: normal
            .iter()
            .filter(|r| r.best_rest.rms_pct < r.zupt_rest.rms_pct)
            .count(),
        default_worse: normal
            .iter()
            .filter(|r| r.best_rest.rms_pct > r.zupt_rest.rms_pct + NOT_WORSE_TOLERANCE_PCT)
            .count(),
    }
}

/// The headline table (default against the baseline, per recording) and its summary line.
pub fn headline_markdown(rows: &[SuiteRow]) -> String {
    let mut s = String::from(
        "Default configuration (best mode, rest-mean prior) against the ZUPT + rest-mean baseline: footprint RMS, % of path.\n\n\
         | recording | gait | path | baseline | default | default − baseline | stride directions / foot axes used / stances | stride-length ratio | stances found (recall / precision, ±50 ms) |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {:.1} m | {:.2} % | {:.2} % | {:+.2} | {} / {} / {} | {:.3} | {} |\n",
            r.recording,
            match r.gait {
                Gait::Normal => "normal",
                Gait::Fast => "fast",
            },
            r.path_m,
            r.zupt_rest.rms_pct,
            r.best_rest.rms_pct,
            r.best_rest.rms_pct - r.zupt_rest.rms_pct,
            r.stride_used,
            r.heading_used,
            r.stances,
            r.stride_ratio,
            r.stances_found.map_or("—".to_string(), |m| format!(
                "{} of {} ({:.0} %) / {} of {} ({:.0} %)",
                m.found,
                m.listed,
                100.0 * m.recall(),
                m.matching,
                m.detected,
                100.0 * m.precision()
            )),
        ));
    }
    let m = summary(rows);
    s.push_str(&format!(
        "\nNormal gait ({} recordings): median {:.2} % (baseline {:.2} %), worst {:.2} % (baseline {:.2} %); \
         default better on {} of {}, worse by more than {:.2} % of path on {}.\n",
        m.n,
        m.default_median_pct,
        m.baseline_median_pct,
        m.default_worst_pct,
        m.baseline_worst_pct,
        m.default_better,
        m.n,
        NOT_WORSE_TOLERANCE_PCT,
        m.default_worse
    ));
    s
}

/// The NIS table: mean per degree of freedom of each update type of the default run, and its
/// 95 % band.
pub fn nis_markdown(rows: &[SuiteRow]) -> String {
    let mut s = String::from(
        "Consistency of the default run: mean NIS per degree of freedom [95 % χ² band] (n); ✗ outside the band.\n\n\
         | recording | first ZUPT of each stance | stride direction | foot axis |\n|---|---|---|---|\n",
    );
    let mut inside = [0usize; 3];
    let f = |x: &Option<NisFigure>| {
        x.map_or("—".to_string(), |x| {
            format!(
                "{:.2} [{:.2}, {:.2}] ({}){}",
                x.mean,
                x.lower,
                x.upper,
                x.n,
                if x.in_band() { "" } else { " ✗" }
            )
        })
    };
    for r in rows {
        for (k, x) in r.nis.iter().enumerate() {
            inside[k] += usize::from(x.is_some_and(|x| x.in_band()));
        }
        s.push_str(&format!(
            "| {} | {} | {} | {} |\n",
            r.recording,
            f(&r.nis[0]),
            f(&r.nis[1]),
            f(&r.nis[2])
        ));
    }
    let mut u = StrideUse::default();
    let mut use_rows = String::new();
    for r in rows {
        if let Some(x) = r.stride_use {
            use_rows.push_str(&format!(
                "| {} | {} of {} | {} of {} | {} of {} |\n",
                r.recording,
                x.straight_used,
                x.straight,
                x.weave_used,
                x.weave,
                x.weave_foot_used,
                x.weave
            ));
            if r.gait == Gait::Normal {
                u.straight += x.straight;
                u.straight_used += x.straight_used;
                u.weave += x.weave;
                u.weave_used += x.weave_used;
                u.weave_foot_used += x.weave_foot_used;
            }
        }
    }
    if !use_rows.is_empty() {
        s.push_str(&format!(
            "\nHeading information used on the strides of the walks surveyed at every stride \
             (straight: the stride and both neighbours within {STRAIGHT_DEG}° of one dominant \
             direction; weave: more than {WEAVE_DEG}° off the direction both neighbours follow).\n\n\
             | recording | straight strides with heading information | weave strides whose direction was used | weave strides whose foot axis was used |\n|---|---|---|---|\n{use_rows}\
             | all normal-gait walks | {} of {} ({:.0} %) | {} of {} | {} of {} |\n",
            u.straight_used,
            u.straight,
            100.0 * u.straight_used as f64 / u.straight.max(1) as f64,
            u.weave_used,
            u.weave,
            u.weave_foot_used,
            u.weave
        ));
    }
    s.push_str(&format!(
        "\nInside the band: first ZUPT {} of {}, stride direction {} of {}, foot axis {} of {}.\n",
        inside[0],
        rows.len(),
        inside[1],
        rows.len(),
        inside[2],
        rows.len()
    ));
    s
}

/// The table as Markdown.
pub fn markdown(rows: &[SuiteRow]) -> String {
    let mut s = headline_markdown(rows);
    s.push('\n');
    s.push_str(&nis_markdown(rows));
    s.push('\n');
    s.push_str("Footprint RMS error after first-leg alignment, metres (% of path); final-GCP error in metres.\n\n");
    s.push_str("| recording | path | (1) ZUPT | (1b) ZUPT + rest mean | (2) injected, uncorrected | (3) paper, injected | (4) best, injected | best, no injection | best + rest mean |\n");
    s.push_str("|---|---|---|---|---|---|---|---|---|\n");
    let f = |x: &Footprint| format!("{:.2} ({:.2} %), {:.2}", x.rms_m, x.rms_pct, x.final_m);
    for r in rows {
        s.push_str(&format!(
            "| {} | {:.1} m | {} | {} | {} | {} | {} | {} | {} |\n",
            r.recording,
            r.path_m,
            f(&r.zupt),
            f(&r.zupt_rest),
            f(&r.zupt_inj),
            f(&r.paper_inj),
            f(&r.best_inj),
            f(&r.best),
            f(&r.best_rest)
        ));
    }
    s.push_str("\nInjected-bias recovery ([0.001, 0.001, 0.005] rad/s), per axis x / y / z, % of the injected value; convergence time.\n\n");
    s.push_str("| recording | paper, no prior | best, no prior | best, prior + injection after the rest | paper converged at | best converged at | best settled within ±5 % (hindsight) | best vs uncorrected |\n");
    s.push_str("|---|---|---|---|---|---|---|---|\n");
    let p = |v: &[f64; 3]| {
        format!(
            "{:.0} / {:.0} / {:.0}",
            100.0 * v[0],
            100.0 * v[1],
            100.0 * v[2]
        )
    };
    let t = |v: Option<f64>| v.map_or("never".to_string(), |v| format!("{v:.1} s"));
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} (prior, late: {}) | {:+.0} % |\n",
            r.recording,
            p(&r.paper_recovery),
            p(&r.best_recovery),
            p(&r.best_recovery_prior_late),
            t(r.paper_converged_at_s),
            t(r.best_converged_at_s),
            t(r.best_settled_at_s),
            t(r.best_settled_prior_late_at_s),
            -r.best_reduction_pct
        ));
    }
    s
}
