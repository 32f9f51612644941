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
//! both runs' convergence flags have risen (else over the last quarter of the log), no prior;
//! and separately with the rest-mean prior and the injection starting when the initial rest
//! ends. The flag of each injected run is compared with the hindsight time its recovery
//! settles within ±5 % (`recovery.rs`).
//!
//! Map of the module:
//! - this file: the rows, and running one recording;
//! - [`run`]: running every recording of a suite (each on its own, or the first failure
//!   failing it);
//! - [`file`]: the suite file, read and checked (start headings, suspect legs);
//! - [`figures`]: what is measured on the default run besides the footprint error (NIS by
//!   update type, heading use on straight and weave strides, stances found, stride lengths);
//! - [`front_end`]: the front end's figures (the stance detectors against the footprint lists,
//!   the start without a rest and from a checkpoint, the clipping model);
//! - [`recovery`]: injected-bias recovery and its hindsight settling time;
//! - [`tables`]: the summary and the Markdown tables;
//! - [`loops`]: the residual-diagnosis loop on every recording;
//! - [`detection`]: the diagnosis's detection matrix (injected sensor errors × recordings);
//! - [`detection_tables`]: its Markdown tables;
//! - [`mde_scan`]: the diagnosis's predicted detectable sizes checked by injection at multiples
//!   of them;
//! - [`sweep`]: the leave-one-walk-out check of the configuration's choices;
//! - [`ensemble`]: every walk's default run under small start-heading offsets (how stable
//!   each figure is).

mod detection;
mod detection_tables;
mod ensemble;
mod figures;
mod file;
mod front_end;
mod loops;
mod mde_scan;
mod recovery;
mod run;
mod sweep;
mod tables;

pub use detection::{
    CaseInjection, DetectionMatrix, FailedRecording, MatrixCase, MatrixCell, StrideFigure,
    detection_matrix, diagnosis_model, matrix_cases,
};
pub use detection_tables::{matrix_markdown, prediction_markdown};
pub use ensemble::{
    EnsembleRow, EnsembleSummary, START_OFFSETS_DEG, ensemble_markdown, ensemble_summary,
    run_ensemble,
};
use figures::{DefaultFigures, NisSeries, stride_ratio};
pub use figures::{NisFigure, STANCE_MATCH_S, STRAIGHT_DEG, StanceMatch, StrideUse, WEAVE_DEG};
pub use file::{
    FIRST_STRIDE_MIN_M, FLAGGED_LEGS_KEY, Gait, StartHeading, SuiteFile, SuiteRecording,
    read_suite, start_heading_from_truth,
};
pub use front_end::{DETECTORS, FrontEnd, KEPT_REST_S, detector_label, front_end_markdown};
pub use loops::{loops_markdown, run_loops};
pub use mde_scan::{MDE_FACTORS, ScanPoint, ScanRow, already_modelled, detected_from, scan_walk};
pub use recovery::{Convergence, SETTLED_TOLERANCE, convergence, recovery, settled_at};
pub use run::{SuiteRun, run_suite, run_suite_each};
pub use sweep::{
    HeldOut, SweepFile, SweepParameter, SweepResult, held_out, run_sweep, sweep_markdown,
};
pub use tables::{
    NOT_WORSE_TOLERANCE_PCT, Summary, headline_markdown, markdown, nis_markdown, summary,
};

use crate::eval::{Align, EvalOptions, EvalReport};
use crate::runner::{self, RunError, RunOutcome, heading_aid};
use corridor_shared::config::{BiasPrior, Config, ConfigFile, Mode};
use corridor_shared::imu_csv::ImuLog;
use corridor_shared::injection::BiasInjection;
use corridor_shared::truth_csv::{TruthPoint, read_truth_csv};
use serde::Serialize;
use std::path::{Path, PathBuf};

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

impl SuiteError {
    /// The recording whose run failed (`None` for the suite file's own errors).
    pub fn recording(&self) -> Option<&str> {
        match self {
            SuiteError::Run { name, .. } => Some(name),
            SuiteError::File { .. } => None,
        }
    }
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

/// The default and the baseline in the map frame: translated onto the first footprint, each
/// with its own heading (both start from the map's start heading), not turned by the first leg
/// ([`Align::Translation`]).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct MapFrame {
    /// The ZUPT + rest-mean baseline.
    pub baseline: Footprint,
    /// The default (best mode, rest-mean prior).
    pub default: Footprint,
}

/// The default and the baseline scored on the footprints before the first leg the data set's
/// own check flags ([`SuiteRecording::suspect_legs`]).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct BeforeSuspect {
    /// The first flagged leg: footprints 0 to `first_leg − 1` are scored.
    pub first_leg: usize,
    /// The recording's footprints.
    pub footprints: usize,
    /// The ZUPT + rest-mean baseline.
    pub baseline: Footprint,
    /// The default (best mode, rest-mean prior).
    pub default: Footprint,
}

/// One row of the results table.
#[derive(Debug, Clone, Serialize)]
pub struct SuiteRow {
    /// Recording.
    pub recording: String,
    /// Its gait.
    pub gait: Gait,
    /// The start heading it was run with, degrees.
    pub start_heading_deg: f64,
    /// Given in the suite file or taken from the first surveyed stride.
    pub start_heading: StartHeading,
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
    /// The paper mode's convergence flag against hindsight, no prior, injection from the start.
    pub paper_convergence: Convergence,
    /// The best mode's convergence flag against hindsight, no prior, injection from the start.
    pub best_convergence: Convergence,
    /// The same with the prior and the injection after the rest.
    pub best_convergence_prior_late: Convergence,
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
    /// Front end: detectors compared, start without rest, clipping model off.
    pub front_end: FrontEnd,
    /// The bias the default run ended with, sensor axes, rad/s.
    pub final_bias_rad_s: [f64; 3],
    /// What the input cost: the rows the reader rejected and what the default run refused,
    /// crossed or restored (every other run reads the same rows; the suite logs this once).
    pub input: InputCounts,
    /// The footprint figures before the first leg the data set flags (recordings with one).
    pub before_suspect: Option<BeforeSuspect>,
    /// The footprint figures in the map frame (no first-leg rotation).
    pub map_frame: MapFrame,
    /// What the footprint evaluation of the default run had to do (footprints outside the
    /// log's time span clamped to its ends), as `corridor run` and `eval_traj.py` say it.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub eval_warnings: Vec<String>,
}

/// The input a recording's default run did not take as it came (see [`SuiteRow::input`]).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct InputCounts {
    /// Rows the CSV reader rejected (malformed, not finite, time).
    pub rows_rejected: u64,
    /// Samples the estimator refused (implausible, time).
    pub samples_refused: u64,
    /// Gaps (longer than `estimator.max_dt_s`), however crossed.
    pub gaps: u64,
    /// Clock steps back taken.
    pub clock_steps_back: u64,
    /// Restores of the health check.
    pub health_restores: u64,
}

impl InputCounts {
    fn of(log: &ImuLog, run: &RunOutcome) -> Self {
        let c = &run.counters;
        Self {
            rows_rejected: log.rejected_counts().values().sum(),
            samples_refused: c.refused(),
            gaps: c.gaps,
            clock_steps_back: c.clock_steps_back,
            health_restores: c.health_restores,
        }
    }

    /// Nothing rejected, refused, crossed or restored.
    pub fn is_clean(&self) -> bool {
        self.rows_rejected == 0
            && self.samples_refused == 0
            && self.gaps == 0
            && self.clock_steps_back == 0
            && self.health_restores == 0
    }
}

/// The recording's configuration with the mode, prior and map knowledge of one suite row.
fn config_for(
    file: &ConfigFile,
    path: &Path,
    r: &SuiteRecording,
    mode: Mode,
    prior: BiasPrior,
) -> Result<Config, RunError> {
    Ok(r.overrides(mode, Some(prior)).validate(file, path)?)
}

struct Ctx<'a> {
    base: &'a Path,
    rec: &'a SuiteRecording,
    config: ConfigFile,
    baseline: ConfigFile,
    log: ImuLog,
    truth: Vec<TruthPoint>,
}

/// Whether a reading of a recording's log says the rows it rejected: the first reading in a
/// command does, a later pass over the same log does not.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum RejectedRows {
    Say,
    AlreadySaid,
}

/// A recording's log, read with its configuration's time-step limits and gap threshold (its
/// rejected rows said unless `said` is [`RejectedRows::AlreadySaid`], see
/// [`crate::runner::read_log`]), and its truth.
pub(crate) fn read_recording(
    base: &Path,
    r: &SuiteRecording,
    said: RejectedRows,
) -> Result<(ImuLog, Vec<TruthPoint>), RunError> {
    let config_path = base.join(&r.config);
    // The file named in a validation error (it printed an empty path, `recording X: : key`).
    let config = ConfigFile::read(&config_path)?
        .validate()
        .map_err(|e| corridor_shared::config::with_path(e, &config_path))?;
    let path = base.join(&r.imu);
    let log = match said {
        RejectedRows::Say => crate::runner::read_log(&path, &config)?,
        RejectedRows::AlreadySaid => crate::runner::read_log_counted(&path, &config)?,
    };
    Ok((log, read_truth_csv(&base.join(&r.truth))?))
}

impl<'a> Ctx<'a> {
    /// Reads a recording's log, truth and configurations.
    fn open(base: &'a Path, r: &'a SuiteRecording, said: RejectedRows) -> Result<Self, RunError> {
        let (log, truth) = read_recording(base, r, said)?;
        Ok(Ctx {
            base,
            rec: r,
            config: ConfigFile::read(&base.join(&r.config))?,
            baseline: ConfigFile::read(
                &base.join(r.baseline_config.as_ref().unwrap_or(&r.config)),
            )?,
            log,
            truth,
        })
    }

    /// The recording cut [`KEPT_REST_S`] before its first footprint ([`front_end::without_rest`]).
    fn without_rest(&self) -> Option<Ctx<'a>> {
        let rows = front_end::without_rest(&self.log.rows, &self.truth)?;
        Some(Ctx {
            log: ImuLog {
                path: self.log.path.clone(),
                rows: rows.to_vec(),
                rejected: Vec::new(),
                has_temperature: self.log.has_temperature,
                temperature_missing: 0,
                extra_columns: self.log.extra_columns.clone(),
            },
            config: self.config.clone(),
            baseline: self.baseline.clone(),
            truth: self.truth.clone(),
            ..*self
        })
    }

    /// The footprint figures of a run without injection at configuration `cfg`; with `say`,
    /// what the input cost that run is logged (once per recording: the runs log nothing per
    /// sample, see [`runner::run_log`]).
    fn footprint_at(&self, cfg: &Config, say: Option<&str>) -> Result<Footprint, RunError> {
        let aid = heading_aid(cfg, None)?;
        let run = runner::run_log(&self.log, cfg, &aid, &BiasInjection::default(), |_, _| {});
        if let Some(which) = say {
            self.say_input(&run, which);
        }
        self.footprint(&run)
    }

    /// Logs what the input cost `run` ([`RunOutcome::input_report`]), when it cost anything.
    fn say_input(&self, run: &RunOutcome, which: &str) {
        if let Some(report) = run.input_report(&self.log) {
            tracing::warn!("{}: {report} ({which})", self.rec.name);
        }
    }

    /// The footprint figures of a run against the recording's truth.
    fn footprint(&self, out: &RunOutcome) -> Result<Footprint, RunError> {
        self.footprint_against(out, &self.truth)
    }

    /// The footprint figures of a run against the recording's footprints before leg `leg`.
    fn footprint_before_leg(&self, out: &RunOutcome, leg: usize) -> Result<Footprint, RunError> {
        self.footprint_against(out, &self.truth[..leg.min(self.truth.len())])
    }

    fn footprint_against(
        &self,
        out: &RunOutcome,
        truth: &[TruthPoint],
    ) -> Result<Footprint, RunError> {
        self.footprint_aligned(out, truth, Align::FirstLeg)
    }

    /// The footprint figures of a run in the map frame ([`MapFrame`]).
    fn footprint_map_frame(&self, out: &RunOutcome) -> Result<Footprint, RunError> {
        self.footprint_aligned(out, &self.truth, Align::Translation)
    }

    /// The warnings of a run's footprint evaluation against the recording's truth.
    fn eval_warnings(&self, out: &RunOutcome) -> Result<Vec<String>, RunError> {
        Ok(self
            .eval_report(out, &self.truth, Align::FirstLeg)?
            .warnings)
    }

    fn eval_report(
        &self,
        out: &RunOutcome,
        truth: &[TruthPoint],
        align: Align,
    ) -> Result<EvalReport, RunError> {
        let opts = EvalOptions {
            align,
            ..EvalOptions::default()
        };
        out.trace
            .evaluate(truth, &opts)
            .map_err(|source| RunError::Eval {
                truth: self.base.join(&self.rec.truth),
                source,
            })
    }

    fn footprint_aligned(
        &self,
        out: &RunOutcome,
        truth: &[TruthPoint],
        align: Align,
    ) -> Result<Footprint, RunError> {
        let rep = self.eval_report(out, truth, align)?;
        let (Some(rms_m), Some(rms_pct)) = (rep.rms_error_m, rep.rms_error_pct_of_path) else {
            return Err(RunError::NotScorable {
                truth: self.base.join(&self.rec.truth),
                why: rep.alignment,
            });
        };
        Ok(Footprint {
            rms_m,
            rms_pct,
            final_m: rep.final_gcp_error_m.unwrap_or(f64::NAN),
        })
    }

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

    /// The default run's configuration: `mode` with the rest-mean prior.
    fn default_config(&self, mode: Mode) -> Result<Config, RunError> {
        self.default_config_turned(mode, 0.0)
    }

    /// [`Ctx::default_config`] with the start heading moved by `offset_deg`.
    fn default_config_turned(&self, mode: Mode, offset_deg: f64) -> Result<Config, RunError> {
        let mut rec = self.rec.clone();
        rec.start_heading_deg += offset_deg;
        config_for(
            &self.config,
            &self.base.join(&self.rec.config),
            &rec,
            mode,
            BiasPrior::RestMean,
        )
    }

    /// The NIS of the default run (the best mode with the rest-mean prior) and its use of
    /// heading information on the truth strides.
    fn default_figures(&self, mode: Mode) -> Result<DefaultFigures, RunError> {
        let cfg = self.default_config(mode)?;
        let aid = heading_aid(&cfg, None)?;
        let mut nis = NisSeries::default();
        let out = runner::run_log(&self.log, &cfg, &aid, &BiasInjection::default(), |_, e| {
            nis.push(e)
        });
        let grid = &cfg.heading;
        let stride_use = StrideUse::of(
            &self.truth,
            grid.grid_rad.get(),
            grid.grid_step_rad.get(),
            &nis.stances,
        );
        Ok(DefaultFigures {
            nis: nis.figures(),
            stances_found: stride_use.map(|_| {
                StanceMatch::of(&self.truth, nis.intervals(), &self.rec.hand_placed_strides)
            }),
            stride_use,
            stride_ratio: stride_ratio(&out.trace, &self.truth),
        })
    }

    /// The front-end figures: the default without its initial rest and without the clipping
    /// model, and (walks surveyed at every stride) the stance detectors compared.
    fn front_end(
        &self,
        mode: Mode,
        clipped_samples: u64,
        every_stride: bool,
    ) -> Result<FrontEnd, RunError> {
        // The clipping model off: neither the attitude variance nor the peaks put back; then
        // the variance alone (the model before the peaks were put back).
        let mut off = self.config.clone();
        off.eskf.restore_clipped_peaks = Some(false);
        let (_, peaks_not_restored) =
            self.run_with(&off, mode, BiasPrior::RestMean, BiasInjection::default())?;
        off.eskf.clipped_rate_sd_rad_s = Some(0.0);
        let (_, clipping_off) =
            self.run_with(&off, mode, BiasPrior::RestMean, BiasInjection::default())?;
        let (without_rest, without_rest_map_frame) = match self.without_rest() {
            Some(cut) => {
                let (out, first_leg) =
                    cut.run(mode, BiasPrior::RestMean, BiasInjection::default())?;
                (Some(first_leg), Some(cut.footprint_map_frame(&out)?))
            }
            None => (None, None),
        };
        let cfg = self.default_config(mode)?;
        Ok(FrontEnd {
            clipped_samples,
            clipping_off,
            peaks_not_restored,
            without_rest,
            without_rest_map_frame,
            without_rest_checkpoint: None,
            detectors: every_stride
                .then(|| front_end::compare_detectors(&self.log.rows, &self.truth, &cfg)),
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
        let fp = self.footprint(&out)?;
        Ok((out, fp))
    }
}

fn run_recording(
    base: &Path,
    r: &SuiteRecording,
    inj: [f64; 3],
    best: Mode,
) -> Result<SuiteRow, RunError> {
    let ctx = Ctx::open(base, r, RejectedRows::Say)?;
    let path_m = ctx
        .truth
        .windows(2)
        .map(|w| (w[1].x_m - w[0].x_m).hypot(w[1].y_m - w[0].y_m))
        .sum();
    let none = BiasInjection::default();
    let injected = BiasInjection {
        constant_rad_s: inj,
        ..Default::default()
    };
    let (_, zupt) = ctx.run_baseline(BiasPrior::None, none)?;
    let (zupt_rest_run, zupt_rest) = ctx.run_baseline(BiasPrior::RestMean, none)?;
    let (_, zupt_inj) = ctx.run_baseline(BiasPrior::None, injected)?;
    let (paper0, _) = ctx.run(Mode::Paper, BiasPrior::None, none)?;
    let (paper1, paper_inj) = ctx.run(Mode::Paper, BiasPrior::None, injected)?;
    let (best0, best_fp) = ctx.run(best, BiasPrior::None, none)?;
    let (best1, best_inj) = ctx.run(best, BiasPrior::None, injected)?;
    let (best_r0, best_rest) = ctx.run(best, BiasPrior::RestMean, none)?;
    let fig = ctx.default_figures(best)?;
    // The runs log nothing per sample (`runner::run_log`): what the input cost is said once,
    // and so is what the footprint evaluation had to do.
    ctx.say_input(&best_r0, "the default run");
    let eval_warnings = ctx.eval_warnings(&best_r0)?;
    for w in &eval_warnings {
        tracing::warn!("{}: {w} (the default run's footprint evaluation)", r.name);
    }
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
    let log_from_s = ctx.log.rows.first().map_or(0.0, |r| r.t_s);
    let late = BiasInjection {
        constant_rad_s: inj,
        after_s: rest_end - log_from_s,
        ..Default::default()
    };
    let (best_r1, _) = ctx.run(best, BiasPrior::RestMean, late)?;
    let before_suspect = match r.suspect_legs.iter().min() {
        Some(&leg) => Some(BeforeSuspect {
            first_leg: leg,
            footprints: ctx.truth.len(),
            baseline: ctx.footprint_before_leg(&zupt_rest_run, leg)?,
            default: ctx.footprint_before_leg(&best_r0, leg)?,
        }),
        None => None,
    };
    let map_frame = MapFrame {
        baseline: ctx.footprint_map_frame(&zupt_rest_run)?,
        default: ctx.footprint_map_frame(&best_r0)?,
    };
    let front_end = ctx.front_end(
        best,
        best_r0.counters.clipped_samples,
        fig.stances_found.is_some(),
    )?;
    Ok(SuiteRow {
        recording: r.name.clone(),
        gait: r.gait,
        start_heading_deg: r.start_heading_deg,
        start_heading: r.start_heading,
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
        paper_convergence: convergence(&paper1, &paper0, inj, rest_end, log_from_s),
        best_convergence: convergence(&best1, &best0, inj, rest_end, log_from_s),
        best_convergence_prior_late: convergence(&best_r1, &best_r0, inj, rest_end, log_from_s),
        best_reduction_pct: 100.0 * (1.0 - best_inj.rms_m / zupt_inj.rms_m),
        stances,
        heading_used,
        stride_used,
        nis: fig.nis,
        stride_use: fig.stride_use,
        stride_ratio: fig.stride_ratio,
        stances_found: fig.stances_found,
        front_end,
        final_bias_rad_s: best_r0
            .trace
            .bias_rad_s
            .last()
            .copied()
            .unwrap_or([f64::NAN; 3]),
        input: InputCounts::of(&ctx.log, &best_r0),
        eval_warnings,
        before_suspect,
        map_frame,
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
