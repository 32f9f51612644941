//! The offline runner: a CSV log through the estimator core, to `estimates.csv`,
//! `innovations.csv`, `summary.json` and optional plots. It is an adapter: every line of
//! estimation is in [`crate::core`], shared with the daemon.

use crate::core::heading::HeadingAid;
use crate::core::{Counters, Estimate, Estimator, ImuInput};
use crate::eval::{self, EvalOptions, EvalReport, TruthGcp};
use crate::map_file::{MapError, read_corridor_map};
use corridor_shared::config::{Config, HeadingSource};
use corridor_shared::imu_csv::{ImuCsvError, ImuLog, RejectedRow};
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

/// Runs `log` through a new estimator; `sink` sees every estimate with the input it came from.
pub fn run_log(
    log: &ImuLog,
    cfg: &Config,
    aid: &HeadingAid,
    injection: &BiasInjection,
    mut sink: impl FnMut(&ImuInput, &Estimate),
) -> RunOutcome {
    let mut est = Estimator::new(cfg.clone(), aid.clone());
    let mut trace = Trace::default();
    let mut refused = Vec::new();
    for row in &log.rows {
        let mut gyro = row.gyro_rad_s;
        injection.apply(row.t_s, &mut gyro);
        let input = ImuInput {
            t_s: row.t_s,
            gyro_rad_s: gyro,
            accel_m_s2: row.accel_m_s2,
        };
        match est.step(&input) {
            Ok(e) => {
                if let Some(gap_s) = e.gap_s {
                    tracing::warn!(
                        "{}:{}: gap of {gap_s:.3} s in the data; a new segment starts here",
                        log.path.display(),
                        row.line
                    );
                }
                if let Some(fault) = e.health_fault {
                    tracing::warn!(
                        "{}:{}: estimator state failed the health check ({}); last good state restored",
                        log.path.display(),
                        row.line,
                        fault.name()
                    );
                }
                trace.t_s.push(e.t_s);
                trace.xy_m.push([e.p_m[0], e.p_m[1]]);
                trace.bias_rad_s.push(e.gyro_bias_rad_s);
                trace.bias_sd_rad_s.push(e.gyro_bias_sd_rad_s);
                trace.converged.push(e.converged);
                sink(&input, e);
            }
            Err(err) if refused.len() < MAX_REFUSED_EXAMPLES => {
                refused.push(format!("{}:{}: {err}", log.path.display(), row.line));
            }
            Err(_) => {}
        }
    }
    RunOutcome {
        trace,
        counters: *est.counters(),
        converged_at_s: est.converged_at_s(),
        mount_yaw_rad: est.mount_yaw_rad(),
        extensions: est.extensions(),
        refused,
    }
}

impl Trace {
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
    /// Footprint evaluation (first-leg alignment), when truth was given.
    pub eval: Option<EvalReport>,
}

/// Builds the summary of one run.
pub fn summarize(
    log: &ImuLog,
    cfg: &Config,
    injection: &BiasInjection,
    outcome: &RunOutcome,
    eval: Option<EvalReport>,
) -> Summary {
    let n = outcome.trace.t_s.len();
    let last = |v: &Vec<[f64; 3]>| if n > 0 { v[n - 1] } else { [f64::NAN; 3] };
    let c = &outcome.counters;
    Summary {
        imu: log.path.display().to_string(),
        mode: cfg.mode.name(),
        bias_rad_s: last(&outcome.trace.bias_rad_s),
        bias_sd_rad_s: last(&outcome.trace.bias_sd_rad_s),
        bias_mean_converged_rad_s: outcome
            .converged_at_s
            .and_then(|t| outcome.trace.mean_bias_from(t)),
        converged_at_s: outcome.converged_at_s,
        mount_yaw_deg: outcome.mount_yaw_rad.map(f64::to_degrees),
        injected_gyro_bias_rad_s: injection.constant_rad_s,
        injected_gyro_bias_ramp_rad_s2: injection.ramp_rad_s2,
        injected_after_s: injection.after_s,
        samples_read: log.rows.len() as u64,
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
        input_rows_rejected: log.rejected_counts(),
        input_rows_rejected_examples: log
            .rejected
            .iter()
            .take(10)
            .map(|r: &RejectedRow| r.located(&log.path).to_string())
            .collect(),
        samples_refused_counts: BTreeMap::from([
            ("non_finite", c.rejected_non_finite),
            ("time_not_increasing", c.rejected_time),
            ("implausible", c.rejected_implausible),
            ("time_jump", c.rejected_time_jump),
        ]),
        samples_refused: outcome.refused.clone(),
        clipped_samples: c.clipped_samples,
        health_restores: c.health_restores,
        eval,
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

/// Runs a log and writes `estimates.csv`, `innovations.csv`, `summary.json` (and the figures).
pub fn run(opts: &RunOptions) -> Result<Summary, RunError> {
    let csv = corridor_shared::imu_csv::ImuCsvOptions {
        min_dt_s: opts.config.sensor.min_dt_s(),
        max_dt_s: opts.config.sensor.max_dt_s(),
        ..opts.csv.clone()
    };
    let log = corridor_shared::imu_csv::read_imu_csv(&opts.imu, &csv)?;
    for r in log.rejected.iter().take(20) {
        tracing::warn!("rejected input row: {}", r.located(&log.path));
    }
    if log.rejected.len() > 20 {
        tracing::warn!(
            "{} more rejected rows (counts in summary.json)",
            log.rejected.len() - 20
        );
    }
    let truth = opts
        .truth
        .as_deref()
        .map(corridor_shared::truth_csv::read_truth_csv)
        .transpose()?;
    let aid = heading_aid(&opts.config, opts.map.as_deref())?;
    std::fs::create_dir_all(&opts.out_dir).map_err(io_at(&opts.out_dir))?;
    let est_path = opts.out_dir.join("estimates.csv");
    let inn_path = opts.out_dir.join("innovations.csv");
    let mut est_w = create(&est_path)?;
    let mut inn_w = create(&inn_path)?;
    writeln!(est_w, "{ESTIMATES_HEADER}").map_err(io_at(&est_path))?;
    writeln!(inn_w, "{INNOVATIONS_HEADER}").map_err(io_at(&inn_path))?;
    let mut io_err: Option<RunError> = None;
    let mut progress = Progress::new(log.rows.len());
    let outcome = run_log(&log, &opts.config, &aid, &opts.injection, |input, e| {
        progress.tick();
        if io_err.is_some() {
            return;
        }
        if let Err(err) = write_estimate_row(&mut est_w, e) {
            io_err = Some(io_at(&est_path)(err));
        } else if let Err(err) = write_innovation_rows(&mut inn_w, input, e) {
            io_err = Some(io_at(&inn_path)(err));
        }
    });
    if let Some(e) = io_err {
        return Err(e);
    }
    progress.finish();
    est_w.flush().map_err(io_at(&est_path))?;
    inn_w.flush().map_err(io_at(&inn_path))?;
    if outcome.counters.samples > 0
        && outcome.mount_yaw_rad.is_none()
        && outcome.counters.stances == 0
    {
        return Err(RunError::NeverAligned {
            path: opts.imu.clone(),
            min_rest_s: opts.config.alignment.min_rest_s.get(),
        });
    }
    let eval = match (&truth, &opts.truth) {
        (Some(t), Some(path)) => Some(outcome.trace.evaluate(t, &EvalOptions::default()).map_err(
            |source| RunError::Eval {
                truth: path.clone(),
                source,
            },
        )?),
        _ => None,
    };
    if opts.plots {
        // "Before": the same log through the ZUPT filter alone, without any bias correction.
        let mut base = opts.config.clone();
        base.mode = corridor_shared::config::Mode::Zupt;
        base.alignment.gyro_bias_prior = corridor_shared::config::BiasPrior::None;
        let before = run_log(&log, &base, &HeadingAid::None, &opts.injection, |_, _| {});
        let eval_before = truth
            .as_deref()
            .and_then(|t| before.trace.evaluate(t, &EvalOptions::default()).ok());
        write_figures(
            &opts.out_dir,
            &before.trace,
            &outcome.trace,
            truth.as_deref(),
            (eval_before.as_ref(), eval.as_ref()),
        )?;
    }
    let summary = summarize(&log, &opts.config, &opts.injection, &outcome, eval);
    let sum_path = opts.out_dir.join("summary.json");
    let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
    std::fs::write(&sum_path, json + "\n").map_err(io_at(&sum_path))?;
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
    let f = dir.join("trajectory.svg");
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
    let f = dir.join("bias.svg");
    bias.write_svg(&f).map_err(io_at(&f))?;
    let f = dir.join("covariance.svg");
    cov.write_svg(&f).map_err(io_at(&f))?;
    Ok(())
}

/// A progress bar on stderr, shown only when stderr is a terminal and the log is long.
struct Progress {
    total: usize,
    done: usize,
    shown_pct: usize,
    enabled: bool,
}

impl Progress {
    fn new(total: usize) -> Self {
        use std::io::IsTerminal;
        Self {
            total,
            done: 0,
            shown_pct: 0,
            enabled: total >= 100_000 && std::io::stderr().is_terminal(),
        }
    }

    fn tick(&mut self) {
        self.done += 1;
        if !self.enabled {
            return;
        }
        let pct = self.done * 100 / self.total.max(1);
        if pct > self.shown_pct {
            self.shown_pct = pct;
            let bar = "#".repeat(pct / 2);
            eprint!(
                "\r[{bar:<50}] {pct:3} % ({} / {} samples)",
                self.done, self.total
            );
        }
    }

    fn finish(&self) {
        if self.enabled {
            eprintln!();
        }
    }
}
