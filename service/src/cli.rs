//! Command-line flags of `corridor` and their dispatch to the library.

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use corridor_client::csv_rows::{ATTITUDE_HEADER, BIAS_HEADER, write_attitude_row, write_bias_row};
use corridor_service::runner::{self, RunOptions};
use corridor_shared::config::{BiasPrior, Config, ConfigFile, Mode};
use corridor_shared::imu_csv::ImuCsvOptions;
use corridor_shared::injection::{BiasInjection, parse_vec3};
use corridor_shared::wire::{AttitudeSample, BiasSample, FLAG_END_OF_STREAM, ImuSample, NavSample};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

#[derive(Parser, Debug)]
#[command(
    name = "corridor",
    version,
    about = "Gyro-bias and attitude estimation for foot-mounted IMUs from map headings"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run the estimator over a CSV log and write estimates, innovations and a summary.
    Run(Box<RunArgs>),
    /// Run a suite of recordings through the baselines and the bias modes; print the table.
    Eval(EvalArgs),
    /// The demo on the bundled measured recordings: the results table, the residual-diagnosis
    /// loop, one recording with the paper's injected bias (summary and figures), the second
    /// sensor, and the same injected run replayed through the daemon to a logger and a PDR
    /// consumer.
    Demo(DemoArgs),
    /// Run the estimator as a daemon behind iceoryx2 services until SIGINT/SIGTERM.
    Serve(ServeArgs),
    /// Diagnose the model on a log: rank the effects its residuals show, add the top one, and
    /// report the error before and after (report.json, report.md, residuals.svg).
    Diagnose(DiagnoseArgs),
}

#[derive(Args, Debug)]
struct DiagnoseArgs {
    /// IMU log.
    #[arg(long)]
    imu: PathBuf,
    #[command(flatten)]
    model: ModelArgs,
    /// Footprint ground truth, to report the footprint error before and after.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
}

#[derive(Args, Debug)]
struct ServeArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// iceoryx2 domain to serve (overrides `daemon.domain`); processes on other domains never
    /// see this daemon.
    #[arg(long)]
    domain: Option<String>,
    /// live (a lagging reader loses the oldest samples, counted) or lossless (the producer
    /// waits); overrides `daemon.delivery`.
    #[arg(long)]
    delivery: Option<corridor_shared::services::Delivery>,
    /// Checkpoint file (overrides `daemon.checkpoint_path`): loaded at start (a bad one is
    /// moved aside, cold start), saved periodically, at each end of stream and at shutdown.
    #[arg(long)]
    checkpoint: Option<PathBuf>,
}

#[derive(Args, Debug)]
struct DemoArgs {
    /// Repository root (where configs/ and tests/data/ are).
    #[arg(long, default_value = ".")]
    root: PathBuf,
    /// Output directory.
    #[arg(long, default_value = "out/demo")]
    out: PathBuf,
}

#[derive(Args, Debug)]
struct EvalArgs {
    /// Suite file (TOML with [[recording]] tables).
    #[arg(long)]
    suite: PathBuf,
    /// Also write the table (Markdown) and the rows (JSON) into this directory.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Configuration flags shared by every command that runs the estimator.
#[derive(Args, Debug, Clone)]
pub struct ModelArgs {
    /// Configuration file (TOML); built-in defaults when absent.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Corridor map (TOML with [[corridor]] tables); switches the heading source to the map.
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Walking direction at the start, degrees in the map frame (overrides the config).
    #[arg(long)]
    pub start_heading_deg: Option<f64>,
    /// Orientation of the building's dominant directions, degrees (overrides the config).
    #[arg(long)]
    pub grid_deg: Option<f64>,
    /// Estimation mode: zupt, paper, rotation_aware or eskf (overrides the config).
    #[arg(long)]
    pub mode: Option<String>,
    /// Gyro-bias prior: none or rest_mean (overrides the config).
    #[arg(long)]
    pub prior: Option<String>,
}

impl ModelArgs {
    /// Reads the config file and applies the overrides; errors name the key and the value.
    pub fn config(&self) -> Result<Config> {
        let file = self.config_file()?;
        let path = self
            .config
            .clone()
            .unwrap_or_else(|| PathBuf::from("<built-in defaults>"));
        Ok(file
            .validate()
            .map_err(|e| corridor_shared::config::with_path(e, &path))?)
    }

    /// The config file with the overrides applied, not yet validated.
    pub fn config_file(&self) -> Result<ConfigFile> {
        let mut file = match &self.config {
            Some(p) => ConfigFile::read(p)?,
            None => ConfigFile::default(),
        };
        if let Some(v) = self.start_heading_deg {
            file.heading.start_heading_deg = Some(v);
        }
        if let Some(v) = self.grid_deg {
            file.heading.grid_deg = Some(v);
        }
        if let Some(m) = &self.mode {
            file.estimator.mode = Some(
                toml::Value::String(m.clone())
                    .try_into::<Mode>()
                    .with_context(|| {
                        format!("--mode {m:?}: expected zupt, paper, rotation_aware or eskf")
                    })?,
            );
        }
        if let Some(p) = &self.prior {
            file.alignment.gyro_bias_prior = Some(
                toml::Value::String(p.clone())
                    .try_into::<BiasPrior>()
                    .with_context(|| format!("--prior {p:?}: expected none or rest_mean"))?,
            );
        }
        Ok(file)
    }
}

#[derive(Args, Debug)]
struct RunArgs {
    /// IMU log (CSV: t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2,...).
    #[arg(long)]
    imu: PathBuf,
    #[command(flatten)]
    model: ModelArgs,
    /// Footprint ground truth (ground_truth.csv) to evaluate against.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// Constant gyro bias to add, X,Y,Z in rad/s.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    inject_gyro_bias: Option<[f64; 3]>,
    /// Linearly growing gyro bias to add, X,Y,Z in rad/s².
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    inject_gyro_bias_ramp: Option<[f64; 3]>,
    /// Start the injection at this time instead of 0, s.
    #[arg(long, default_value_t = 0.0)]
    inject_after_s: f64,
    /// Write the figures (SVG).
    #[arg(long)]
    plots: bool,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
}

pub fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info")),
        )
        .with_writer(std::io::stderr)
        .init();
    let cli = Cli::parse();
    match dispatch(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn dispatch(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Run(a) => {
            let opts = RunOptions {
                imu: a.imu.clone(),
                config: a.model.config()?,
                map: a.model.map.clone(),
                truth: a.truth.clone(),
                injection: BiasInjection {
                    constant_rad_s: a.inject_gyro_bias.unwrap_or_default(),
                    ramp_rad_s2: a.inject_gyro_bias_ramp.unwrap_or_default(),
                    after_s: a.inject_after_s,
                },
                plots: a.plots,
                out_dir: a.out.clone(),
                csv: ImuCsvOptions::default(),
            };
            let s = runner::run(&opts)?;
            println!("{}", serde_json::to_string_pretty(&brief(&s))?);
            Ok(())
        }
        Command::Demo(a) => {
            let suite = a.root.join("configs/eval/gdins.toml");
            let rows = corridor_service::suite::run_suite(&suite)?;
            let md = corridor_service::suite::markdown(&rows);
            println!(
                "# Results on the bundled recordings ({})\n",
                suite.display()
            );
            print!("{md}");
            std::fs::create_dir_all(&a.out)
                .with_context(|| format!("creating {}", a.out.display()))?;
            let loops = corridor_service::suite::run_loops(&suite, &a.out.join("diagnose"))?;
            println!(
                "\n# The loop: residual diagnosis from the paper's model (reports in {})\n\n{loops}",
                a.out.join("diagnose").display()
            );
            std::fs::write(a.out.join("results.md"), format!("{md}\n{loops}"))?;
            let data = a.root.join("tests/data/gdins_exp25_multi_corridor");
            let run_dir = a.out.join("exp25_injected");
            // The paper's injected bias; the daemon section below replays the same log with it.
            let injection = BiasInjection {
                constant_rad_s: [0.001, 0.001, 0.005],
                ..Default::default()
            };
            let opts = RunOptions {
                imu: data.join("imu.csv"),
                config: demo_exp25_config(&a.root)?,
                map: None,
                truth: Some(data.join("ground_truth.csv")),
                injection,
                plots: true,
                out_dir: run_dir.clone(),
                csv: ImuCsvOptions::default(),
            };
            let s = runner::run(&opts)?;
            println!(
                "\n# exp25 with the injected bias [0.001, 0.001, 0.005] rad/s, no prior, mode {}\n",
                s.mode
            );
            println!("{}", serde_json::to_string_pretty(&brief(&s))?);
            println!("\nFigures and CSV files: {}", run_dir.display());
            let exp25 = opts;
            let offline = s;

            // A second sensor, irregular timing, loop-closure truth only.
            let data = a.root.join("tests/data/xio_ngimu_long_walk");
            let opts = RunOptions {
                imu: data.join("imu.csv"),
                config: Config::from_file(&a.root.join("configs/ngimu.toml"))?,
                map: None,
                truth: Some(data.join("ground_truth.csv")),
                injection: BiasInjection::default(),
                plots: false,
                out_dir: a.out.join("xio"),
                csv: ImuCsvOptions::default(),
            };
            let s = runner::run(&opts)?;
            let e = s.eval.as_ref();
            println!(
                "\n# xio NGIMU long walk (~400 Hz, irregular timing, {} gaps > {} s): loop-closure error {:.3} m over {:.1} m walked (x-io's own ZUPT: 0.421 m)",
                s.gaps,
                opts.config.max_dt_s.get(),
                e.and_then(|e| e.loop_closure_error_m).unwrap_or(f64::NAN),
                e.map_or(f64::NAN, |e| e.traj_path_length_m),
            );

            // The same injected exp25 run through the daemon over iceoryx2.
            demo_daemon(&a.out, &exp25, &offline)
        }
        Command::Serve(a) => {
            use corridor_service::daemon::{self, DaemonConfig};
            let config = a.model.config()?;
            let aid = runner::heading_aid(&config, a.model.map.as_deref())?;
            // The flags override the `[daemon]` section of the file.
            let mut cfg = match &a.domain {
                Some(d) => {
                    DaemonConfig::new(corridor_shared::services::Domain::new(d)?, config, aid)
                }
                None => DaemonConfig::from_config(config, aid)?,
            };
            if let Some(d) = a.delivery {
                cfg.delivery = d;
            }
            if let Some(p) = &a.checkpoint {
                cfg.checkpoint = Some(p.clone());
            }
            let report = daemon::serve(cfg)?;
            let d = &report.diagnostics;
            println!(
                "{}",
                serde_json::to_string_pretty(&serde_json::json!({
                    "streams_finished": report.streams_finished,
                    "received": d.received,
                    "accepted": d.accepted,
                    "seq_gaps": d.seq_gaps,
                    "rejected_non_finite": d.rejected_non_finite,
                    "rejected_time": d.rejected_time,
                    "rejected_duplicate_seq": d.rejected_duplicate_seq,
                    "late": d.late,
                    "dropped_overflow": d.dropped_overflow,
                    "undelivered": d.undelivered,
                    "producer_changes": d.producer_changes,
                    "checkpoints_saved": report.checkpoints_saved,
                    "warm_started": report.warm_started_from.is_some(),
                    "warnings": report.warnings,
                }))?
            );
            Ok(())
        }
        Command::Diagnose(a) => {
            let file = a.model.config_file()?;
            let log = corridor_shared::imu_csv::read_imu_csv(&a.imu, &ImuCsvOptions::default())?;
            let truth = a
                .truth
                .as_deref()
                .map(corridor_shared::truth_csv::read_truth_csv)
                .transpose()?;
            let (report, before, after, _) = corridor_service::diagnose::diagnose(
                &log,
                &file,
                truth.as_deref(),
                a.model.map.as_deref(),
            )?;
            std::fs::create_dir_all(&a.out)
                .with_context(|| format!("creating {}", a.out.display()))?;
            corridor_service::diagnose::write_report(&a.out, &report, &before, &after)?;
            print!("{}", std::fs::read_to_string(a.out.join("report.md"))?);
            Ok(())
        }
        Command::Eval(a) => {
            let rows = corridor_service::suite::run_suite(&a.suite)?;
            let md = corridor_service::suite::markdown(&rows);
            print!("{md}");
            if let Some(dir) = a.out {
                std::fs::create_dir_all(&dir)
                    .with_context(|| format!("creating {}", dir.display()))?;
                std::fs::write(dir.join("results.md"), &md)?;
                std::fs::write(
                    dir.join("results.json"),
                    serde_json::to_string_pretty(&rows)? + "\n",
                )?;
            }
            Ok(())
        }
    }
}

fn brief(s: &runner::Summary) -> serde_json::Value {
    let e = s.eval.as_ref();
    serde_json::json!({
        "mode": s.mode,
        "bias_rad_s": s.bias_rad_s,
        "bias_sd_rad_s": s.bias_sd_rad_s,
        "converged_at_s": s.converged_at_s,
        "mount_yaw_deg": s.mount_yaw_deg,
        "stances": s.stances,
        "heading_used": s.heading_observations_used,
        "heading_rejected": s.heading_observations_rejected,
        "gcp_rms_m": e.and_then(|e| e.rms_error_m),
        "gcp_rms_pct": e.and_then(|e| e.rms_error_pct_of_path),
        "final_gcp_error_m": e.and_then(|e| e.final_gcp_error_m),
    })
}

// ---------------------------------------------------------------------------------------------
// `corridor demo`: the injected exp25 run through the daemon.

/// How long the demo's daemon section waits for a peer or for the next message.
const DEMO_WAIT: Duration = Duration::from_secs(10);
/// Longest single wait of the demo's consumers, so they see an abort.
const DEMO_POLL: Duration = Duration::from_millis(50);
/// Largest accepted difference between the daemon's final bias and the offline run's, rad/s.
const DEMO_BIAS_TOLERANCE_RAD_S: f64 = 1e-12;

/// The configuration of the demo's exp25 runs (offline and through the daemon):
/// `configs/gdins.toml` without a gyro-bias prior, walking off at heading 0°.
fn demo_exp25_config(root: &Path) -> Result<Config> {
    let path = root.join("configs/gdins.toml");
    let mut file = ConfigFile::read(&path)?;
    file.alignment.gyro_bias_prior = Some(BiasPrior::None);
    file.heading.start_heading_deg = Some(0.0);
    Ok(file
        .validate()
        .map_err(|e| corridor_shared::config::with_path(e, &path))?)
}

/// What the demo's logger consumer received.
#[derive(Debug, Default)]
struct DemoLogged {
    attitude_rows: u64,
    bias_rows: u64,
    /// Attitude and bias messages missing from the `seq` numbering.
    missed: u64,
    /// The bias of the last attitude row.
    last_attitude_bias_rad_s: [f64; 3],
    /// The bias of the end-of-stream bias message (the daemon's final bias).
    final_bias_rad_s: [f64; 3],
}

/// What the demo's PDR consumer received.
#[derive(Debug, Default)]
struct DemoTracked {
    /// One nav sample per stance.
    strides: Vec<NavSample>,
    /// The stance count carried by the end-of-stream nav sample.
    end_stances: u64,
    /// Nav messages missing from the `seq` numbering.
    missed: u64,
}

/// Runs the daemon in-process on a domain of this process, opens a logger and a PDR consumer,
/// replays `exp25` (its log, configuration and injection) through the client [`Producer`] at
/// full speed with lossless delivery, and checks the daemon's final bias against `offline`
/// (the `corridor run` of the same options). Fails when anything was lost or the biases differ.
///
/// [`Producer`]: corridor_client::Producer
fn demo_daemon(out: &Path, exp25: &RunOptions, offline: &runner::Summary) -> Result<()> {
    use corridor_client::{Delivery, Domain};
    use corridor_service::daemon::{self, DaemonConfig};

    let started = Instant::now();
    let log = corridor_shared::imu_csv::read_imu_csv(&exp25.imu, &exp25.csv)?;
    let domain = Domain::new(&format!("demo_{}", std::process::id()))?;
    let aid = runner::heading_aid(&exp25.config, exp25.map.as_deref())?;
    let mut cfg = DaemonConfig::new(domain.clone(), exp25.config.clone(), aid);
    cfg.delivery = Delivery::Lossless;
    cfg.checkpoint = None;
    let dir = out.join("daemon");
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;

    let shutdown = Arc::new(AtomicBool::new(false));
    let daemon = {
        let flag = Arc::clone(&shutdown);
        std::thread::Builder::new()
            .name("corridor-demo-daemon".into())
            .spawn(move || daemon::run(cfg, flag))
            .context("starting the daemon thread")?
    };
    // The consumers open their ports on their own threads (iceoryx2 ports are !Send) and say
    // when they are attached; the replay starts after both.
    let abort = Arc::new(AtomicBool::new(false));
    let (ready_tx, ready_rx) = std::sync::mpsc::channel::<()>();
    let logger = {
        let (domain, dir, ready, abort) = (
            domain.clone(),
            dir.clone(),
            ready_tx.clone(),
            Arc::clone(&abort),
        );
        std::thread::Builder::new()
            .name("corridor-demo-log".into())
            .spawn(move || demo_logger(&domain, &dir, &ready, &abort))
            .context("starting the logger thread")?
    };
    let pdr = {
        let (domain, ready, abort) = (domain.clone(), ready_tx, Arc::clone(&abort));
        std::thread::Builder::new()
            .name("corridor-demo-pdr".into())
            .spawn(move || demo_pdr(&domain, &ready, &abort))
            .context("starting the PDR thread")?
    };
    let replay_started = Instant::now();
    let replay = (|| -> Result<corridor_client::ProducerStats> {
        let mut ready = 0;
        let waiting = Instant::now();
        while ready < 2 {
            match ready_rx.recv_timeout(DEMO_POLL) {
                Ok(()) => ready += 1,
                Err(_) if daemon.is_finished() => bail!("the daemon stopped before the replay"),
                Err(_) if logger.is_finished() || pdr.is_finished() => {
                    bail!("a consumer stopped before the replay")
                }
                Err(_) if waiting.elapsed() >= DEMO_WAIT => {
                    bail!("the consumers did not attach within {DEMO_WAIT:?}")
                }
                Err(_) => {}
            }
        }
        demo_replay(&domain, &log, &exp25.injection)
    })();
    let replay_s = replay_started.elapsed().as_secs_f64();
    if replay.is_err() {
        abort.store(true, Ordering::Relaxed);
    }
    let joined = |name: &str| anyhow::anyhow!("the {name} thread panicked");
    let logged = logger.join().map_err(|_| joined("logger"))?;
    let tracked = pdr.join().map_err(|_| joined("PDR"))?;
    shutdown.store(true, Ordering::Relaxed);
    let report = daemon.join().map_err(|_| joined("daemon"))?;
    // The daemon's clean shutdown removed its services; what is left of the domain is the
    // node counter iceoryx2 keeps across runs (`<prefix>…node.<version>.global_mgmt`), which a
    // domain of one process does not need.
    // SAFETY: no other process uses this domain (it is named after this process's id) and
    // every thread of this process that used it has ended, its ports and nodes dropped.
    let removed = unsafe {
        iceoryx2::testing::remove_global_mgmt_segment::<iceoryx2::prelude::ipc::Service>(
            domain.config(),
        )
    };
    let stats = replay.context("replaying through the daemon")?;
    let logged = logged.context("logger consumer")?;
    let tracked = tracked.context("PDR consumer")?;
    let report = report.context("daemon")?;
    removed.map_err(|e| anyhow::anyhow!("removing the iceoryx2 node counter: {e:?}"))?;
    let left = demo_leftovers(&domain);

    let d = &report.diagnostics;
    let sent = stats.imu_sent.saturating_sub(1);
    let lost_daemon = stats.imu_undelivered
        + stats.imu_sent.saturating_sub(d.received)
        + d.seq_gaps
        + d.dropped_overflow;
    let lost_logger = d.accepted.saturating_sub(logged.attitude_rows) + logged.missed;
    let lost_pdr = tracked
        .end_stances
        .saturating_sub(tracked.strides.len() as u64)
        + tracked.missed;
    let lost = lost_daemon + lost_logger + lost_pdr;
    let rejected = d.rejected_non_finite + d.rejected_time + d.rejected_duplicate_seq + d.late;
    let last = tracked.strides.last().copied().unwrap_or_default();
    let path_m: f64 = tracked
        .strides
        .windows(2)
        .map(|w| (w[1].p_m[0] - w[0].p_m[0]).hypot(w[1].p_m[1] - w[0].p_m[1]))
        .sum();
    let daemon_bias = logged.final_bias_rad_s;
    let diff: [f64; 3] = std::array::from_fn(|k| (daemon_bias[k] - offline.bias_rad_s[k]).abs());
    let max_diff = diff
        .iter()
        .copied()
        .fold(0.0, |m: f64, d| if d > m || d.is_nan() { d } else { m });

    println!(
        "\n# The same run through the daemon: iceoryx2 domain {:?}, lossless, replay at full speed with the injected bias, logger and PDR consumers\n",
        domain.name()
    );
    println!(
        "replay: {sent} samples sent (+1 end-of-stream marker) in {replay_s:.2} s ({:.0} samples/s), {} reached no subscriber",
        sent as f64 / replay_s.max(1e-9),
        stats.imu_undelivered
    );
    println!(
        "daemon: received {} (marker included), accepted {}, rejected {rejected}, sequence gaps {}, overflow drops {}",
        d.received, d.accepted, d.seq_gaps, d.dropped_overflow
    );
    println!(
        "logger: {} attitude rows, {} bias rows, {} missed ({}, {})",
        logged.attitude_rows,
        logged.bias_rows,
        logged.missed,
        dir.join("attitude.csv").display(),
        dir.join("bias.csv").display()
    );
    println!(
        "pdr: {} strides ({} stances offline), {} missed; last at t = {:.2} s: x = {:.3} m, y = {:.3} m, z = {:.3} m, yaw = {:.1}°; path {:.2} m",
        tracked.strides.len(),
        offline.stances,
        tracked.missed,
        last.t_s,
        last.p_m[0],
        last.p_m[1],
        last.p_m[2],
        last.yaw_rad.to_degrees(),
        path_m
    );
    println!("lost: {lost} (daemon {lost_daemon}, logger {lost_logger}, pdr {lost_pdr})");
    println!(
        "\nfinal gyro bias, rad/s   {:>22} {:>22} {:>22}",
        "x", "y", "z"
    );
    let row = |name: &str, v: [f64; 3]| {
        println!(
            "{name:<24} {:>22.15e} {:>22.15e} {:>22.15e}",
            v[0], v[1], v[2]
        );
    };
    row("daemon", daemon_bias);
    row("corridor run (offline)", offline.bias_rad_s);
    row("|difference|", diff);
    for w in &report.warnings {
        println!("daemon warning: {w}");
    }
    println!(
        "iceoryx2 files left for the domain: {}",
        if left.is_empty() {
            "none".to_owned()
        } else {
            left.join(", ")
        }
    );
    println!(
        "daemon section: {:.2} s wall time",
        started.elapsed().as_secs_f64()
    );

    if lost > 0 {
        bail!("{lost} samples lost with lossless delivery");
    }
    if logged.last_attitude_bias_rad_s != daemon_bias {
        bail!(
            "the daemon's end-of-stream bias {daemon_bias:?} is not the bias of its last attitude {:?}",
            logged.last_attitude_bias_rad_s
        );
    }
    // NaN never compares below the tolerance.
    if !diff.iter().all(|&d| d <= DEMO_BIAS_TOLERANCE_RAD_S) {
        bail!(
            "the daemon's final bias differs from the offline run's by {max_diff:e} rad/s on its worst axis (tolerance {DEMO_BIAS_TOLERANCE_RAD_S:e})"
        );
    }
    if tracked.strides.len() as u64 != offline.stances {
        bail!(
            "the PDR consumer saw {} strides, the offline run {} stances",
            tracked.strides.len(),
            offline.stances
        );
    }
    if !left.is_empty() {
        bail!("iceoryx2 files left behind: {}", left.join(", "));
    }
    Ok(())
}

/// Sends `log` with `injection` added to the gyro through a lossless [`Producer`], as fast as
/// the daemon takes it, then the end-of-stream marker.
///
/// [`Producer`]: corridor_client::Producer
fn demo_replay(
    domain: &corridor_client::Domain,
    log: &corridor_shared::imu_csv::ImuLog,
    injection: &BiasInjection,
) -> Result<corridor_client::ProducerStats> {
    use corridor_client::{Delivery, Producer};
    let mut p = Producer::new(domain, "corridor-demo-replay", Delivery::Lossless)?;
    p.wait_for_daemon(DEMO_WAIT)?;
    for r in &log.rows {
        let mut gyro = r.gyro_rad_s;
        injection.apply(r.t_s, &mut gyro);
        p.send_imu(ImuSample {
            t_s: r.t_s,
            gyro_rad_s: gyro,
            accel_m_s2: r.accel_m_s2,
            temp_c: r.temp_c.unwrap_or(f64::NAN),
            ..ImuSample::default()
        })?;
    }
    p.finish()?;
    Ok(p.stats())
}

/// The demo's logger: writes the attitude and bias streams to `dir/attitude.csv` and
/// `dir/bias.csv` (the columns of `corridor-log`) until the end-of-stream attitude and bias.
fn demo_logger(
    domain: &corridor_client::Domain,
    dir: &Path,
    ready: &std::sync::mpsc::Sender<()>,
    abort: &AtomicBool,
) -> Result<DemoLogged> {
    use corridor_client::Subscriber;
    let attitude =
        Subscriber::<AttitudeSample>::open(domain, "corridor-demo-log-attitude", DEMO_WAIT)?;
    let bias = Subscriber::<BiasSample>::open(domain, "corridor-demo-log-bias", DEMO_WAIT)?;
    let att_path = dir.join("attitude.csv");
    let bias_path = dir.join("bias.csv");
    let mut att_w = runner::create(&att_path)?;
    let mut bias_w = runner::create(&bias_path)?;
    writeln!(att_w, "{ATTITUDE_HEADER}").map_err(runner::io_at(&att_path))?;
    writeln!(bias_w, "{BIAS_HEADER}").map_err(runner::io_at(&bias_path))?;
    let _ = ready.send(());

    let mut got = DemoLogged::default();
    let (mut attitude_done, mut bias_done) = (false, false);
    let mut last_rx = Instant::now();
    while !(attitude_done && bias_done) {
        if abort.load(Ordering::Relaxed) {
            bail!("stopped: the replay failed");
        }
        // The bias stream first, without waiting while attitudes still come.
        let b = if attitude_done {
            bias.recv_timeout(DEMO_POLL)?
        } else {
            bias.try_recv()?
        };
        if let Some(b) = b {
            last_rx = Instant::now();
            if b.flags & FLAG_END_OF_STREAM != 0 {
                got.final_bias_rad_s = b.gyro_bias_rad_s;
                bias_done = true;
            } else {
                write_bias_row(&mut bias_w, &b).map_err(runner::io_at(&bias_path))?;
                got.bias_rows += 1;
            }
            continue;
        }
        if !attitude_done && let Some(x) = attitude.recv_timeout(DEMO_POLL)? {
            last_rx = Instant::now();
            if x.flags & FLAG_END_OF_STREAM != 0 {
                attitude_done = true;
                continue;
            }
            write_attitude_row(&mut att_w, &x).map_err(runner::io_at(&att_path))?;
            got.attitude_rows += 1;
            got.last_attitude_bias_rad_s = x.gyro_bias_rad_s;
            continue;
        }
        if last_rx.elapsed() >= DEMO_WAIT {
            bail!("nothing from the daemon for {DEMO_WAIT:?}");
        }
    }
    att_w.flush().map_err(runner::io_at(&att_path))?;
    bias_w.flush().map_err(runner::io_at(&bias_path))?;
    got.missed = attitude.missed() + bias.missed();
    Ok(got)
}

/// The demo's PDR consumer: collects the nav sample of every stance until the end of stream.
fn demo_pdr(
    domain: &corridor_client::Domain,
    ready: &std::sync::mpsc::Sender<()>,
    abort: &AtomicBool,
) -> Result<DemoTracked> {
    let nav =
        corridor_client::Subscriber::<NavSample>::open(domain, "corridor-demo-pdr", DEMO_WAIT)?;
    let _ = ready.send(());
    let mut got = DemoTracked::default();
    let mut last_rx = Instant::now();
    loop {
        if abort.load(Ordering::Relaxed) {
            bail!("stopped: the replay failed");
        }
        let Some(n) = nav.recv_timeout(DEMO_POLL)? else {
            if last_rx.elapsed() >= DEMO_WAIT {
                bail!("nothing from the daemon for {DEMO_WAIT:?}");
            }
            continue;
        };
        last_rx = Instant::now();
        if n.flags & FLAG_END_OF_STREAM != 0 {
            got.end_stances = n.stance;
            break;
        }
        got.strides.push(n);
    }
    got.missed = nav.missed();
    Ok(got)
}

/// Files of `domain` still in the iceoryx2 locations: shared memory (`/dev/shm`) and the
/// iceoryx2 root directory (services, nodes), two levels deep.
fn demo_leftovers(domain: &corridor_client::Domain) -> Vec<String> {
    fn scan(dir: &Path, tag: &str, depth: u32, left: &mut Vec<String>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().contains(tag) {
                left.push(e.path().display().to_string());
            } else if depth > 0 && e.file_type().is_ok_and(|t| t.is_dir()) {
                scan(&e.path(), tag, depth - 1, left);
            }
        }
    }
    let tag = format!("{}_", domain.name());
    let mut left = Vec::new();
    scan(Path::new("/dev/shm"), &tag, 0, &mut left);
    let root = PathBuf::from(domain.config().global.root_path().to_string());
    scan(&root, &tag, 2, &mut left);
    left
}
