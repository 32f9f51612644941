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
    #[arg(long, value_parser = parse_injected_bias_rad_s, allow_hyphen_values = true)]
    pub(super) inject_gyro_bias: Option<[f64; 3]>,
    /// Linearly growing gyro bias to add, X,Y,Z in rad/s² (each within ±0.01).
    #[arg(long, value_parser = parse_injected_ramp_rad_s2, allow_hyphen_values = true)]
    pub(super) inject_gyro_bias_ramp: Option<[f64; 3]>,
    /// Start the injection at this time instead of 0, s.
    #[arg(
        long,
        default_value_t = 0.0,
        allow_negative_numbers = true,
        value_parser = parse_time_s
    )]
    pub(super) inject_after_s: f64,
    /// Start from the bias state of a daemon's checkpoint file, as the daemon does after a
    /// restart.
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
        warm_start: a
            .checkpoint
            .as_deref()
            .map(checkpoint::read)
            .transpose()?
            .map(|cp| cp.warm_start()),
    };
    let s = runner::run(&opts)?;
    corridor_client::say!("{}", serde_json::to_string_pretty(&brief(&s))?);
    Ok(())
}

/// The summary fields printed by `corridor run` and `corridor demo`.
pub(super) fn brief(s: &runner::Summary) -> serde_json::Value {
    let e = s.eval.as_ref();
    // What the input did that a user should know about, said once in words.
    let mut notes = Vec::new();
    if s.jittery_clock_samples > 0 {
        notes.push(format!(
            "the time stamps jitter (host arrival times?): {} samples integrated on a smoothed clock",
            s.jittery_clock_samples
        ));
    }
    if s.started_without_rest {
        notes.push(
            "no initial rest: aligned on a short first stance, without a rest-mean bias prior"
                .into(),
        );
    }
    if s.start_replayed_ms > 0 {
        notes.push(format!(
            "fast gait: the start went back {:.2} s, to the first stance the fast-gait rule takes (alignment.fast_gait_replay_s)",
            s.start_replayed_ms as f64 * 1e-3
        ));
    }
    if s.rest_prior_refused {
        notes.push(
            "the initial rest turned faster than a bias of this sensor can be (alignment.max_prior_rate_rad_s, sensor.max_gyro_bias_rad_s): a pivoting foot, no rest-mean bias prior"
                .into(),
        );
    }
    if s.initial_rest_moving_blocks > 0 {
        notes.push(format!(
            "the foot moved in {:.2} s of the initial rest (rocking, a weight shift): left out of the bias prior and the tilt",
            s.initial_rest_moving_blocks as f64 * corridor_service::core::estimator::REST_BLOCK_S
        ));
    }
    if s.clipped_samples > 0 {
        notes.push(format!(
            "{} samples at a sensor rail (clipped)",
            s.clipped_samples
        ));
    }
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
        "notes": notes,
    })
}
