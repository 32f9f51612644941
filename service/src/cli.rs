//! Command-line flags of `corridor` and their dispatch to the library.

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};
use corridor_service::runner::{self, RunOptions};
use corridor_shared::config::{BiasPrior, Config, ConfigFile, Mode};
use corridor_shared::imu_csv::ImuCsvOptions;
use corridor_shared::injection::{BiasInjection, parse_vec3};
use std::path::PathBuf;
use std::process::ExitCode;

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
    /// The demo on the bundled measured recordings: the results table, then one recording with
    /// the paper's injected bias, its summary and its figures.
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
            let mut file = ConfigFile::read(&a.root.join("configs/gdins.toml"))?;
            file.alignment.gyro_bias_prior = Some(BiasPrior::None);
            let opts = RunOptions {
                imu: data.join("imu.csv"),
                config: file.validate()?,
                map: None,
                truth: Some(data.join("ground_truth.csv")),
                injection: BiasInjection {
                    constant_rad_s: [0.001, 0.001, 0.005],
                    ..Default::default()
                },
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
            Ok(())
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
