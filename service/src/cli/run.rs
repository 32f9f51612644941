//! `corridor run`: the offline runner over one CSV log.

use super::model::ModelArgs;
use anyhow::Result;
use clap::Args;
use corridor_service::checkpoint;
use corridor_service::runner::{self, RunOptions};
use corridor_shared::imu_csv::ImuCsvOptions;
use corridor_shared::injection::{
    BiasInjection, parse_injected_bias_rad_s, parse_injected_ramp_rad_s2, parse_time_s,
};
use std::path::PathBuf;

#[derive(Args, Debug)]
#[command(group = clap::ArgGroup::new("injected").multiple(true))]
pub(super) struct RunArgs {
    /// IMU log (CSV: t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2,...).
    #[arg(long)]
    pub(super) imu: PathBuf,
    #[command(flatten)]
    pub(super) model: ModelArgs,
    /// Footprint ground truth (ground_truth.csv) to evaluate against.
    #[arg(long)]
    pub(super) truth: Option<PathBuf>,
    /// Constant gyro bias to add, X,Y,Z in rad/s (each within ±0.2).
    #[arg(long, value_parser = parse_injected_bias_rad_s, allow_hyphen_values = true, group = "injected")]
    pub(super) inject_gyro_bias: Option<[f64; 3]>,
    /// Linearly growing gyro bias to add, X,Y,Z in rad/s² (each within ±0.01).
    #[arg(long, value_parser = parse_injected_ramp_rad_s2, allow_hyphen_values = true, group = "injected")]
    pub(super) inject_gyro_bias_ramp: Option<[f64; 3]>,
    /// Start the injection this long after the log's first sample instead of at it, s (with
    /// --inject-gyro-bias or --inject-gyro-bias-ramp: alone it injected nothing, silently).
    #[arg(
        long,
        requires = "injected",
        default_value_t = 0.0,
        allow_negative_numbers = true,
        value_parser = parse_time_s
    )]
    pub(super) inject_after_s: f64,
    /// Start from the bias state of a daemon's checkpoint file, as the daemon does after a
    /// restart (one of another mode is refused: the daemon would start cold).
    #[arg(long)]
    pub(super) checkpoint: Option<PathBuf>,
    /// Write the figures (SVG).
    #[arg(long)]
    pub(super) plots: bool,
    /// Output directory.
    #[arg(long)]
    pub(super) out: PathBuf,
}

/// Runs the estimator over the log and prints the brief summary.
pub(super) fn run(a: &RunArgs) -> Result<()> {
    let config = a.model.config()?;
    let checkpoint = a.checkpoint.as_deref().map(checkpoint::read).transpose()?;
    // The daemon starts cold from a checkpoint of another mode; this run used it as it was.
    if let (Some(cp), Some(path)) = (&checkpoint, &a.checkpoint)
        && cp.mode != config.mode.name()
    {
        anyhow::bail!(
            "{}: the checkpoint is for mode {:?}, this run's is {} (--mode or estimator.mode): \
             the daemon would start cold from it",
            path.display(),
            cp.mode,
            config.mode.name()
        );
    }
    let opts = RunOptions {
        imu: a.imu.clone(),
        config,
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
        warm_start: checkpoint.map(|cp| cp.warm_start()),
    };
    let s = runner::run(&opts)?;
    corridor_client::say!("{}", serde_json::to_string_pretty(&brief(&s))?);
    Ok(())
}

/// The summary fields printed by `corridor run` and `corridor demo`.
pub(super) fn brief(s: &runner::Summary) -> serde_json::Value {
    let e = s.eval.as_ref();
    let mut brief = serde_json::json!({
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
        "notes": s.notes,
    });
    // A closed truth's figure (the x-io walk's start and end at one place), when it has one:
    // it was only in summary.json, and the brief said null for the footprints alone.
    if let Some(m) = e.and_then(|e| e.loop_closure_error_m) {
        brief["loop_closure_m"] = m.into();
        // A percentage only where the evaluation gives one (a loop-closure-only truth; a
        // closed footprint truth has its footprint RMS instead).
        if let Some(pct) = e.and_then(|e| e.loop_closure_pct.flatten()) {
            brief["loop_closure_pct"] = pct.into();
        }
    }
    brief
}
