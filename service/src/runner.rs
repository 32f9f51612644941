//! The offline runner: a CSV log through the estimator core, to `estimates.csv`,
//! `innovations.csv`, `summary.json` and optional plots. It is an adapter: every line of
//! estimation is in [`crate::core`], shared with the daemon.
//!
//! [`run`] (`corridor run`, the demo) streams: the log is read row by row
//! ([`ImuCsvReader`]), each row goes through the estimator and its estimate straight to
//! `estimates.csv` and `innovations.csv`; what the summary needs is kept as it goes (the last
//! bias, the converged-phase mean, the positions next to the footprint times in a
//! [`GcpSampler`], for `--plots` at most [`PLOT_POINTS`] samples of each trace), so its memory
//! does not depend on the log's length. Every output is written as `NAME.partial` and renamed
//! only when the run succeeded; a run that fails removes its partial files (one killed leaves
//! them named `.partial`), and earlier outputs in the directory stay as they were.
//!
//! [`run_log`] runs a log already in memory and keeps the whole per-sample [`Trace`]: the
//! suite, the diagnosis and the tests use it on the bundled recordings.

use crate::core::heading::HeadingAid;
use crate::core::{Counters, Estimate, Estimator, ImuInput};
use crate::eval::{self, EvalOptions, EvalReport, GcpSampler, TruthGcp};
use crate::map_file::{MapError, read_corridor_map};
use corridor_shared::config::{Config, HeadingSource};
use corridor_shared::imu_csv::{ImuCsvError, ImuCsvReader, ImuLog, ImuRow, RejectedRow};
use corridor_shared::injection::BiasInjection;
use corridor_shared::truth_csv::{TruthCsvError, TruthPoint};
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Anything that stops a run.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The IMU log is unreadable or invalid.
    #[error(transparent)]
    Imu(#[from] ImuCsvError),
    /// The ground truth is unreadable or invalid.
    #[error(transparent)]
    Truth(#[from] TruthCsvError),
    /// The corridor map is unreadable or invalid.
    #[error(transparent)]
    Map(#[from] MapError),
    /// The evaluation failed.
    #[error("evaluation against {truth}: {source}")]
    Eval {
        /// Truth file.
        truth: PathBuf,
        /// Cause.
        source: eval::EvalError,
    },
    /// Writing an output failed.
    #[error("{path}: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// The configuration is unreadable or invalid.
    #[error(transparent)]
    Config(#[from] corridor_shared::config::ConfigError),
    /// The log never left the alignment phase.
    #[error("{path}: no initial rest of at least {min_rest_s} s followed by motion was found")]
    NeverAligned {
        /// The log.
        path: PathBuf,
        /// Required rest.
        min_rest_s: f64,
    },
}

/// Builds the heading source the configuration asks for.
pub fn heading_aid(cfg: &Config, map: Option<&Path>) -> Result<HeadingAid, RunError> {
    Ok(match (cfg.heading.source, map) {
        (_, Some(path)) => HeadingAid::Map(read_corridor_map(path)?),
        (HeadingSource::Map, None) | (HeadingSource::None, None) => HeadingAid::None,
        (HeadingSource::Grid, None) => HeadingAid::Grid {
            grid_rad: cfg.heading.grid_rad,
            step_rad: cfg.heading.grid_step_rad.get(),
        },
    })
}

/// Per-sample trace kept in memory for evaluation and plots.
#[derive(Debug, Clone, Default)]
pub struct Trace {
    /// Sample times.
    pub t_s: Vec<f64>,
    /// Positions, map frame.
    pub xy_m: Vec<[f64; 2]>,
    /// Bias, sensor axes.
    pub bias_rad_s: Vec<[f64; 3]>,
    /// Bias σ.
    pub bias_sd_rad_s: Vec<[f64; 3]>,
    /// Converged flag.
    pub converged: Vec<bool>,
}

/// Result of running a log through the estimator.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    /// The trace.
    pub trace: Trace,
    /// Counters of the estimator.
    pub counters: Counters,
    /// First convergence time.
    pub converged_at_s: Option<f64>,
    /// Sensor yaw on the foot, once calibrated.
    pub mount_yaw_rad: Option<f64>,
    /// The first [`MAX_REFUSED_EXAMPLES`] samples refused by the estimator, with file, line and
    /// reason (the counts are in `counters`).
    pub refused: Vec<String>,
    /// Final extension estimates and the scale factors' σ (see `Estimator::extensions`).
    pub extensions: Option<(
        crate::core::eskf::ExtensionEstimates,
        Option<nalgebra::Vector3<f64>>,
    )>,
}

/// How many refused samples `summary.json` names.
pub const MAX_REFUSED_EXAMPLES: usize = 10;

/// One estimator fed row by row: the injection, the warnings naming file and line, the first
/// refused samples.
struct Feed<'a> {
    est: Estimator,
    injection: &'a BiasInjection,
    path: &'a Path,
    refused: Vec<String>,
}

impl<'a> Feed<'a> {
    fn new(cfg: &Config, aid: &HeadingAid, injection: &'a BiasInjection, path: &'a Path) -> Self {
        Self {
            est: Estimator::new(cfg.clone(), aid.clone()),
            injection,
            path,
            refused: Vec::new(),
        }
    }

    /// The estimate of one row and the first convergence time after it, or `None` when the
    /// estimator refused the row.
    fn step(&mut self, row: &ImuRow) -> Option<(ImuInput, &Estimate, Option<f64>)> {
        let mut gyro = row.gyro_rad_s;
        self.injection.apply(row.t_s, &mut gyro);
        let input = ImuInput {
            t_s: row.t_s,
            gyro_rad_s: gyro,
            accel_m_s2: row.accel_m_s2,
        };
        match self.est.step(&input) {
            Ok(e) => {
                if let Some(gap_s) = e.gap_s {
                    tracing::warn!(
                        "{}:{}: gap of {gap_s:.3} s in the data; a new segment starts here",
                        self.path.display(),
                        row.line
                    );
                }
                if let Some(fault) = e.health_fault {
                    tracing::warn!(
                        "{}:{}: estimator state failed the health check ({}); last good state restored",
                        self.path.display(),
                        row.line,
                        fault.name()
                    );
                }
            }
            Err(err) => {
                if self.refused.len() < MAX_REFUSED_EXAMPLES {
                    self.refused
                        .push(format!("{}:{}: {err}", self.path.display(), row.line));
                }
                return None;
            }
        }
        Some((input, self.est.last_estimate(), self.est.converged_at_s()))
    }

    /// The outcome, with the trace kept by the caller.
    fn outcome(self, trace: Trace) -> RunOutcome {
        RunOutcome {
            trace,
            counters: *self.est.counters(),
            converged_at_s: self.est.converged_at_s(),
            mount_yaw_rad: self.est.mount_yaw_rad(),
            extensions: self.est.extensions(),
            refused: self.refused,
        }
    }
}

/// Runs `log` (in memory) through a new estimator and keeps the whole per-sample trace; `sink`
/// sees every estimate with the input it came from. For a log of any length, [`run`] streams.
pub fn run_log(
    log: &ImuLog,
    cfg: &Config,
    aid: &HeadingAid,
    injection: &BiasInjection,
    mut sink: impl FnMut(&ImuInput, &Estimate),
) -> RunOutcome {
    let mut feed = Feed::new(cfg, aid, injection, &log.path);
    let mut trace = Trace::default();
    for row in &log.rows {
        if let Some((input, e, _)) = feed.step(row) {
            trace.push(e);
            sink(&input, e);
        }
    }
    feed.outcome(trace)
}

impl Trace {
    /// Appends one estimate.
    pub fn push(&mut self, e: &Estimate) {
        self.t_s.push(e.t_s);
        self.xy_m.push([e.p_m[0], e.p_m[1]]);
        self.bias_rad_s.push(e.gyro_bias_rad_s);
        self.bias_sd_rad_s.push(e.gyro_bias_sd_rad_s);
        self.converged.push(e.converged);
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// Whether it holds no sample.
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Keeps every other sample (the first, the third, …).
    fn halve(&mut self) {
        fn keep_even<T: Copy>(v: &mut Vec<T>) {
            let mut i = 0;
            v.retain(|_| {
                i += 1;
                i % 2 == 1
            });
        }
        keep_even(&mut self.t_s);
        keep_even(&mut self.xy_m);
        keep_even(&mut self.bias_rad_s);
        keep_even(&mut self.bias_sd_rad_s);
        keep_even(&mut self.converged);
    }

    /// Mean bias over the samples at or after `from_s`.
    pub fn mean_bias_from(&self, from_s: f64) -> Option<[f64; 3]> {
        let mut sum = [0.0; 3];
        let mut n = 0usize;
        for (t, b) in self.t_s.iter().zip(&self.bias_rad_s) {
            if *t >= from_s {
                for k in 0..3 {
                    sum[k] += b[k];
                }
                n += 1;
            }
        }
        (n > 0).then(|| sum.map(|s| s / n as f64))
    }

    /// Evaluates the trajectory against footprint truth as `eval_traj.py` does by default.
    pub fn evaluate(
        &self,
        truth: &[TruthPoint],
        opts: &EvalOptions,
    ) -> Result<EvalReport, eval::EvalError> {
        let x: Vec<f64> = self.xy_m.iter().map(|p| p[0]).collect();
        let y: Vec<f64> = self.xy_m.iter().map(|p| p[1]).collect();
        let gcps: Vec<TruthGcp> = truth.iter().map(to_gcp).collect();
        eval::evaluate(&self.t_s, &x, &y, &gcps, opts)
    }
}

/// Converts a truth row for the evaluator.
pub fn to_gcp(p: &TruthPoint) -> TruthGcp {
    TruthGcp {
        t_s: p.t_s,
        x_m: p.x_m,
        y_m: p.y_m,
        stride: p.stride,
    }
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// The IMU log.
    pub imu: String,
    /// Estimation mode.
    pub mode: &'static str,
    /// Final bias, rad/s, sensor axes.
    pub bias_rad_s: [f64; 3],
    /// Final bias σ.
    pub bias_sd_rad_s: [f64; 3],
    /// Mean bias over the converged phase (from `converged_at_s` on), or null.
    pub bias_mean_converged_rad_s: Option<[f64; 3]>,
    /// First time every bias σ was below `estimator.converged_sd_rad_s` (a real-time criterion).
    pub converged_at_s: Option<f64>,
    /// Sensor yaw on the foot found by the calibration, degrees.
    pub mount_yaw_deg: Option<f64>,
    /// Injected bias (constant part), rad/s.
    pub injected_gyro_bias_rad_s: [f64; 3],
    /// Injected ramp, rad/s².
    pub injected_gyro_bias_ramp_rad_s2: [f64; 3],
    /// Injection start, s.
    pub injected_after_s: f64,
    /// Input rows in the file (accepted by the reader).
    pub samples_read: u64,
    /// Samples the estimator processed.
    pub samples: u64,
    /// Stances.
    pub stances: u64,
    /// ZUPT updates.
    pub zupts: u64,
    /// Gaps (steps above `estimator.max_dt_s`).
    pub gaps: u64,
    /// Heading observations used.
    pub heading_observations_used: u64,
    /// Heading observations rejected, by reason.
    pub heading_observations_rejected: BTreeMap<&'static str, u64>,
    /// Stride-direction observations used.
    pub stride_observations_used: u64,
    /// Stride-direction observations rejected (too short, outside the gate or unlikely).
    pub stride_observations_rejected: u64,
    /// Input rows rejected by the CSV reader, by reason.
    pub input_rows_rejected: BTreeMap<&'static str, u64>,
    /// The first few rejected rows, with file, line, column and value.
    pub input_rows_rejected_examples: Vec<String>,
    /// Samples refused by the estimator (after the reader), by reason.
    pub samples_refused_counts: BTreeMap<&'static str, u64>,
    /// The first samples refused by the estimator, with file, line and reason.
    pub samples_refused: Vec<String>,
    /// Accepted samples with an axis at the rail of its range (probably clipped).
    pub clipped_samples: u64,
    /// Updates that failed the estimator's health check (the last good state was restored).
    pub health_restores: u64,
    /// Samples integrated on the smoothed clock because the stamps jitter (host arrival times).
    pub jittery_clock_samples: u64,
    /// Alignment came from a short first stance (no initial rest, no rest-mean prior).
    pub started_without_rest: bool,
    /// Zero-rate updates of the bias at rests after the alignment.
    pub zero_rate_updates: u64,
    /// Footprint evaluation (first-leg alignment), when truth was given.
    pub eval: Option<EvalReport>,
}

/// What a streamed run keeps of its estimates: memory independent of the log's length.
struct Kept {
    /// Bias and σ of the last estimate.
    last: Option<([f64; 3], [f64; 3])>,
    /// Sum and count of the bias from the first converged sample on.
    converged_sum: [f64; 3],
    converged_n: usize,
    /// Positions next to the footprint times, when truth was given.
    gcps: Option<GcpSampler>,
    /// The figures' traces, with `--plots`.
    plot: Option<PlotTrace>,
}

impl Kept {
    fn new(truth: Option<&[TruthGcp]>, plots: bool) -> Self {
        Self {
            last: None,
            converged_sum: [0.0; 3],
            converged_n: 0,
            gcps: truth.map(|t| GcpSampler::new(t, &EvalOptions::default())),
            plot: plots.then(PlotTrace::new),
        }
    }

    /// One estimate; `converged_at_s` is the estimator's after it (the same sum as
    /// [`Trace::mean_bias_from`] over the whole trace).
    fn push(&mut self, e: &Estimate, converged_at_s: Option<f64>) {
        self.last = Some((e.gyro_bias_rad_s, e.gyro_bias_sd_rad_s));
        if converged_at_s.is_some_and(|t| e.t_s >= t) {
            for k in 0..3 {
                self.converged_sum[k] += e.gyro_bias_rad_s[k];
            }
            self.converged_n += 1;
        }
        if let Some(g) = &mut self.gcps {
            g.push(e.t_s, e.p_m[0], e.p_m[1]);
        }
        if let Some(p) = &mut self.plot {
            p.push(e);
        }
    }

    fn mean_bias_converged(&self) -> Option<[f64; 3]> {
        let n = self.converged_n;
        (n > 0).then(|| self.converged_sum.map(|s| s / n as f64))
    }
}

/// How many samples of each trace `--plots` keeps at most (about 2.4 MB a trace): a log up to
/// this length is drawn sample by sample, a longer one decimated evenly.
pub const PLOT_POINTS: usize = 1 << 15;

/// A trace of at most [`PLOT_POINTS`] samples: every `stride`-th estimate; when full, every
/// other sample is dropped and the stride doubles.
struct PlotTrace {
    trace: Trace,
    stride: u64,
    seen: u64,
}

impl PlotTrace {
    fn new() -> Self {
        let n = PLOT_POINTS;
        Self {
            trace: Trace {
                t_s: Vec::with_capacity(n),
                xy_m: Vec::with_capacity(n),
                bias_rad_s: Vec::with_capacity(n),
                bias_sd_rad_s: Vec::with_capacity(n),
                converged: Vec::with_capacity(n),
            },
            stride: 1,
            seen: 0,
        }
    }

    fn push(&mut self, e: &Estimate) {
        if self.seen.is_multiple_of(self.stride) {
            if self.trace.len() == PLOT_POINTS {
                self.trace.halve();
                self.stride *= 2;
            }
            if self.seen.is_multiple_of(self.stride) {
                self.trace.push(e);
            }
        }
        self.seen += 1;
    }
}

/// Outputs written as `NAME.partial` and renamed to `NAME` by [`Staged::commit`]; dropped
/// without it (a failed run), the partial files are removed.
struct Staged {
    /// The final paths.
    files: Vec<PathBuf>,
    committed: bool,
}

impl Staged {
    fn new() -> Self {
        Self {
            files: Vec::new(),
            committed: false,
        }
    }

    fn partial(path: &Path) -> PathBuf {
        let mut name = path.as_os_str().to_owned();
        name.push(".partial");
        PathBuf::from(name)
    }

    /// The temporary path to write `path` under.
    fn stage(&mut self, path: PathBuf) -> PathBuf {
        let partial = Self::partial(&path);
        self.files.push(path);
        partial
    }

    /// Creates `path`'s temporary file for buffered writing.
    fn create(
        &mut self,
        path: PathBuf,
    ) -> Result<(std::io::BufWriter<std::fs::File>, PathBuf), RunError> {
        let partial = self.stage(path);
        Ok((create(&partial)?, partial))
    }

    /// Renames every file to its final name.
    fn commit(mut self) -> Result<(), RunError> {
        for f in &self.files {
            std::fs::rename(Self::partial(f), f).map_err(io_at(f))?;
        }
        self.committed = true;
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            for f in &self.files {
                // Files not yet created, or already renamed, are not there: nothing to do.
                let _ = std::fs::remove_file(Self::partial(f));
            }
        }
    }
}

/// CSV header of `estimates.csv`.
pub const ESTIMATES_HEADER: &str = "t_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,roll_rad,pitch_rad,yaw_rad,qw,qx,qy,qz,bias_x_rad_s,bias_y_rad_s,bias_z_rad_s,bias_sd_x_rad_s,bias_sd_y_rad_s,bias_sd_z_rad_s,stance,converged,phase";

/// CSV header of `innovations.csv`.
pub const INNOVATIONS_HEADER: &str = "t_s,kind,accepted,reason,r0,r1,r2,s0,s1,s2,nis,foot_heading_deg,direction_deg,baseline_s,gyro_norm_rad_s,accel_norm_m_s2,gz_rad_s";

/// Writes one `estimates.csv` row.
pub fn write_estimate_row(w: &mut impl Write, e: &Estimate) -> std::io::Result<()> {
    let b = e.gyro_bias_rad_s;
    let s = e.gyro_bias_sd_rad_s;
    let q = e.nav_from_body;
    writeln!(
        w,
        "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
        e.t_s,
        e.p_m[0],
        e.p_m[1],
        e.p_m[2],
        e.v_m_s[0],
        e.v_m_s[1],
        e.v_m_s[2],
        e.roll_rad,
        e.pitch_rad,
        e.yaw_rad,
        q[0],
        q[1],
        q[2],
        q[3],
        b[0],
        b[1],
        b[2],
        s[0],
        s[1],
        s[2],
        u8::from(e.stance),
        u8::from(e.converged),
        e.phase.name()
    )
}

/// Writes the `innovations.csv` rows of one estimate (ZUPT, stride-direction and heading
/// events; for a stride row `foot_heading_deg` is the stride's direction).
pub fn write_innovation_rows(
    w: &mut impl Write,
    input: &ImuInput,
    e: &Estimate,
) -> std::io::Result<()> {
    let g = input.gyro_rad_s;
    let a = input.accel_m_s2;
    let gn = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    let an = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if let Some(z) = &e.zupt {
        writeln!(
            w,
            "{},zupt,1,,{},{},{},{},{},{},{},,,,{gn},{an},{}",
            e.t_s, z.r[0], z.r[1], z.r[2], z.s_diag[0], z.s_diag[1], z.s_diag[2], z.nis, g[2]
        )?;
    }
    for (kind, h) in [("stride", &e.stride), ("heading", &e.heading)] {
        let Some(h) = h else { continue };
        let fh = h.foot_heading_rad.to_degrees();
        let dir = h.direction_rad.to_degrees();
        match &h.outcome {
            Ok(i) => writeln!(
                w,
                "{},{kind},1,,{},{},{},{},{},{},{},{fh},{dir},{},{gn},{an},{}",
                e.t_s,
                i.r[0],
                i.r[1],
                i.r[2],
                i.s_diag[0],
                i.s_diag[1],
                i.s_diag[2],
                i.nis,
                h.baseline_s,
                g[2]
            )?,
            Err(r) => writeln!(
                w,
                "{},{kind},0,{},,,,,,,,{fh},,,{gn},{an},{}",
                e.t_s,
                r.name(),
                g[2]
            )?,
        }
    }
    Ok(())
}

/// Creates a buffered file for writing, naming the path on error.
pub fn create(path: &Path) -> Result<std::io::BufWriter<std::fs::File>, RunError> {
    std::fs::File::create(path)
        .map(|f| std::io::BufWriter::with_capacity(1 << 16, f))
        .map_err(|source| RunError::Io {
            path: path.to_owned(),
            source,
        })
}

/// Maps an IO error to one that names `path`.
pub fn io_at(path: &Path) -> impl Fn(std::io::Error) -> RunError + '_ {
    move |source| RunError::Io {
        path: path.to_owned(),
        source,
    }
}

/// Everything `corridor run` needs.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// IMU log.
    pub imu: PathBuf,
    /// Validated configuration (with command-line overrides applied).
    pub config: Config,
    /// Corridor map file.
    pub map: Option<PathBuf>,
    /// Ground truth.
    pub truth: Option<PathBuf>,
    /// Synthetic bias injection.
    pub injection: BiasInjection,
    /// Write the figures.
    pub plots: bool,
    /// Output directory.
    pub out_dir: PathBuf,
    /// Reader options.
    pub csv: corridor_shared::imu_csv::ImuCsvOptions,
}

/// How many rejected input rows are logged as warnings (all are counted in `summary.json`).
const REJECTED_ROWS_LOGGED: usize = 20;

/// Streams a log through the estimator and writes `estimates.csv`, `innovations.csv`,
/// `summary.json` (and the figures); see the module's documentation for what is kept and what
/// a failed run leaves.
pub fn run(opts: &RunOptions) -> Result<Summary, RunError> {
    let csv = corridor_shared::imu_csv::ImuCsvOptions {
        min_dt_s: opts.config.sensor.min_dt_s(),
        max_dt_s: opts.config.sensor.max_dt_s(),
        ..opts.csv.clone()
    };
    let mut reader = ImuCsvReader::open(&opts.imu, &csv)?;
    let truth = opts
        .truth
        .as_deref()
        .map(corridor_shared::truth_csv::read_truth_csv)
        .transpose()?;
    let gcps: Option<Vec<TruthGcp>> = truth.as_ref().map(|t| t.iter().map(to_gcp).collect());
    let aid = heading_aid(&opts.config, opts.map.as_deref())?;
    std::fs::create_dir_all(&opts.out_dir).map_err(io_at(&opts.out_dir))?;
    let mut staged = Staged::new();
    let (mut est_w, est_path) = staged.create(opts.out_dir.join("estimates.csv"))?;
    let (mut inn_w, inn_path) = staged.create(opts.out_dir.join("innovations.csv"))?;
    writeln!(est_w, "{ESTIMATES_HEADER}").map_err(io_at(&est_path))?;
    writeln!(inn_w, "{INNOVATIONS_HEADER}").map_err(io_at(&inn_path))?;

    let mut feed = Feed::new(&opts.config, &aid, &opts.injection, &opts.imu);
    let mut kept = Kept::new(gcps.as_deref(), opts.plots);
    // "Before" for the figures: the same rows through the ZUPT filter alone, without any bias
    // correction, in the same pass.
    let mut before = opts.plots.then(|| {
        let mut base = opts.config.clone();
        base.mode = corridor_shared::config::Mode::Zupt;
        base.alignment.gyro_bias_prior = corridor_shared::config::BiasPrior::None;
        (
            Feed::new(&base, &HeadingAid::None, &opts.injection, &opts.imu),
            Kept::new(gcps.as_deref(), true),
        )
    });
    let mut progress = Progress::new(reader.progress_bytes().1.unwrap_or(0));
    let mut logged = 0;
    loop {
        let item = reader.next();
        while logged < reader.rejected_rows().len().min(REJECTED_ROWS_LOGGED) {
            tracing::warn!(
                "rejected input row: {}",
                reader.rejected_rows()[logged].located(reader.path())
            );
            logged += 1;
        }
        let Some(row) = item else { break };
        let row = row?;
        progress.show(reader.progress_bytes().0);
        if let Some((input, e, converged_at_s)) = feed.step(&row) {
            write_estimate_row(&mut est_w, e).map_err(io_at(&est_path))?;
            write_innovation_rows(&mut inn_w, &input, e).map_err(io_at(&inn_path))?;
            kept.push(e, converged_at_s);
        }
        if let Some((feed, kept)) = &mut before
            && let Some((_, e, converged_at_s)) = feed.step(&row)
        {
            kept.push(e, converged_at_s);
        }
    }
    if reader.rows_rejected() > logged as u64 {
        tracing::warn!(
            "{} more rejected rows (counts in summary.json)",
            reader.rows_rejected() - logged as u64
        );
    }
    progress.finish();
    est_w.flush().map_err(io_at(&est_path))?;
    inn_w.flush().map_err(io_at(&inn_path))?;
    drop((est_w, inn_w));
    let c = *feed.est.counters();
    if c.samples > 0 && feed.est.mount_yaw_rad().is_none() && c.stances == 0 {
        return Err(RunError::NeverAligned {
            path: opts.imu.clone(),
            min_rest_s: opts.config.alignment.min_rest_s.get(),
        });
    }
    let eval = match (&kept.gcps, &opts.truth) {
        (Some(g), Some(path)) => Some(g.finish().map_err(|source| RunError::Eval {
            truth: path.clone(),
            source,
        })?),
        _ => None,
    };
    if let (Some((_, b)), Some(after)) = (&before, &kept.plot) {
        let eval_before = b.gcps.as_ref().and_then(|g| g.finish().ok());
        let before_trace = &b.plot.as_ref().expect("the before run keeps a trace").trace;
        write_figures_to(
            &mut |name| staged.stage(opts.out_dir.join(name)),
            before_trace,
            &after.trace,
            truth.as_deref(),
            (eval_before.as_ref(), eval.as_ref()),
        )?;
    }
    let summary = Summary {
        imu: opts.imu.display().to_string(),
        mode: opts.config.mode.name(),
        bias_rad_s: kept.last.map_or([f64::NAN; 3], |l| l.0),
        bias_sd_rad_s: kept.last.map_or([f64::NAN; 3], |l| l.1),
        bias_mean_converged_rad_s: kept.mean_bias_converged(),
        converged_at_s: feed.est.converged_at_s(),
        mount_yaw_deg: feed.est.mount_yaw_rad().map(f64::to_degrees),
        injected_gyro_bias_rad_s: opts.injection.constant_rad_s,
        injected_gyro_bias_ramp_rad_s2: opts.injection.ramp_rad_s2,
        injected_after_s: opts.injection.after_s,
        samples_read: reader.rows_accepted(),
        samples: c.samples,
        stances: c.stances,
        zupts: c.zupts,
        gaps: c.gaps,
        heading_observations_used: c.heading_used,
        heading_observations_rejected: BTreeMap::from([
            ("not_straight", c.heading_not_straight),
            ("outside_gate", c.heading_outside_gate),
            ("outside_map", c.heading_outside_map),
            ("unlikely", c.heading_unlikely),
        ]),
        stride_observations_used: c.stride_used,
        stride_observations_rejected: c.stride_rejected,
        input_rows_rejected: reader.rejected_counts(),
        input_rows_rejected_examples: reader
            .rejected_rows()
            .iter()
            .take(10)
            .map(|r: &RejectedRow| r.located(reader.path()).to_string())
            .collect(),
        samples_refused_counts: BTreeMap::from([
            ("non_finite", c.rejected_non_finite),
            ("time_not_increasing", c.rejected_time),
            ("implausible", c.rejected_implausible),
            ("time_jump", c.rejected_time_jump),
        ]),
        samples_refused: feed.refused,
        clipped_samples: c.clipped_samples,
        health_restores: c.health_restores,
        jittery_clock_samples: c.jittery_clock_samples,
        started_without_rest: c.started_without_rest,
        zero_rate_updates: c.zero_rate_updates,
        eval,
    };
    let sum_path = staged.stage(opts.out_dir.join("summary.json"));
    let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
    std::fs::write(&sum_path, json + "\n").map_err(io_at(&sum_path))?;
    staged.commit()?;
    Ok(summary)
}

/// The trajectory aligned to the truth as the evaluation aligns it (first leg), or as is.
fn aligned_xy(
    trace: &Trace,
    truth: Option<&[TruthPoint]>,
    rep: Option<&EvalReport>,
) -> (Vec<f64>, Vec<f64>) {
    let (mut xs, mut ys): (Vec<f64>, Vec<f64>) = trace.xy_m.iter().map(|p| (p[0], p[1])).unzip();
    if let (Some(t), Some(r)) = (truth, rep)
        && let (Some(g0), Some(theta)) = (t.first(), r.rotation_deg)
    {
        let i0 = trace
            .t_s
            .partition_point(|&x| x < g0.t_s)
            .min(trace.t_s.len().saturating_sub(1));
        let (px, py) = (xs[i0], ys[i0]);
        let (s, c) = theta.to_radians().sin_cos();
        for (x, y) in xs.iter_mut().zip(ys.iter_mut()) {
            let (dx, dy) = (*x - px, *y - py);
            *x = c * dx - s * dy + g0.x_m;
            *y = s * dx + c * dy + g0.y_m;
        }
    }
    (xs, ys)
}

/// Writes the paper's figures: trajectory before/after with the footprints, the bias per axis
/// with its ±σ band, and the filter's bias σ against time.
pub fn write_figures(
    dir: &Path,
    before: &Trace,
    after: &Trace,
    truth: Option<&[TruthPoint]>,
    evals: (Option<&EvalReport>, Option<&EvalReport>),
) -> Result<(), RunError> {
    write_figures_to(&mut |name| dir.join(name), before, after, truth, evals)
}

/// [`write_figures`], each figure to `path_of(its name)`.
fn write_figures_to(
    path_of: &mut dyn FnMut(&str) -> PathBuf,
    before: &Trace,
    after: &Trace,
    truth: Option<&[TruthPoint]>,
    evals: (Option<&EvalReport>, Option<&EvalReport>),
) -> Result<(), RunError> {
    use crate::plot::{Figure, Panel, Series};
    let (bx, by) = aligned_xy(before, truth, evals.0);
    let (ax, ay) = aligned_xy(after, truth, evals.1);
    let mut traj = Panel::new("Trajectory (aligned on the first leg)", "x (m)", "y (m)")
        .with_equal_aspect()
        .with_series(Series::dashed("ZUPT filter, no bias correction", bx, by))
        .with_series(Series::line("corrected", ax, ay));
    if let Some(t) = truth {
        traj = traj.with_series(
            Series::markers(
                "surveyed footprints",
                t.iter().map(|p| p.x_m).collect(),
                t.iter().map(|p| p.y_m).collect(),
            )
            .with_point_labels((0..t.len()).map(|i| i.to_string()).collect()),
        );
    }
    let f = path_of("trajectory.svg");
    Figure::new("corridor: trajectory before and after bias correction")
        .with_panel(traj)
        .with_size(900, 700)
        .write_svg(&f)
        .map_err(io_at(&f))?;

    let mut bias = Figure::new("Gyro-bias estimate (sensor axes) with ±1σ").with_shared_x();
    let mut cov = Figure::new("Bias-filter σ against time").with_shared_x();
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let b: Vec<f64> = after.bias_rad_s.iter().map(|v| v[k]).collect();
        let sd: Vec<f64> = after.bias_sd_rad_s.iter().map(|v| v[k]).collect();
        bias = bias.with_panel(
            Panel::new(format!("bias {axis}"), "t (s)", "rad/s").with_series(
                Series::line(format!("b_{axis}"), after.t_s.clone(), b).with_band(sd.clone()),
            ),
        );
        cov = cov.with_panel(
            Panel::new(format!("σ {axis}"), "t (s)", "rad/s").with_series(Series::line(
                format!("σ_{axis}"),
                after.t_s.clone(),
                sd,
            )),
        );
    }
    let f = path_of("bias.svg");
    bias.write_svg(&f).map_err(io_at(&f))?;
    let f = path_of("covariance.svg");
    cov.write_svg(&f).map_err(io_at(&f))?;
    Ok(())
}

/// A progress bar on stderr over the bytes of the log, shown only when stderr is a terminal and
/// the log is long.
struct Progress {
    total_bytes: u64,
    shown_pct: u64,
    enabled: bool,
}

/// Logs shorter than this get no progress bar (about 100 000 rows), bytes.
const PROGRESS_MIN_BYTES: u64 = 8 << 20;

impl Progress {
    fn new(total_bytes: u64) -> Self {
        use std::io::IsTerminal;
        Self {
            total_bytes,
            shown_pct: 0,
            enabled: total_bytes >= PROGRESS_MIN_BYTES && std::io::stderr().is_terminal(),
        }
    }

    fn show(&mut self, done_bytes: u64) {
        if !self.enabled {
            return;
        }
        let pct = done_bytes * 100 / self.total_bytes.max(1);
        if pct > self.shown_pct {
            self.shown_pct = pct;
            let bar = "#".repeat(pct as usize / 2);
            eprint!(
                "\r[{bar:<50}] {pct:3} % ({} / {} MB)",
                done_bytes >> 20,
                self.total_bytes >> 20
            );
        }
    }

    fn finish(&self) {
        if self.enabled {
            eprintln!();
        }
    }
}
