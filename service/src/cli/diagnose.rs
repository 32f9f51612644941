//! `corridor diagnose`: the residual diagnosis of one log, with its report written and printed.

use super::model::ModelArgs;
use anyhow::{Context, Result};
use clap::Args;
use corridor_shared::imu_csv::ImuCsvOptions;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub(super) struct DiagnoseArgs {
    /// IMU log.
    #[arg(long)]
    pub(super) imu: PathBuf,
    #[command(flatten)]
    pub(super) model: ModelArgs,
    /// Footprint ground truth, to report the footprint error before and after.
    #[arg(long)]
    pub(super) truth: Option<PathBuf>,
    /// Output directory.
    #[arg(long)]
    pub(super) out: PathBuf,
}

/// Diagnoses the log, writes the report and prints its Markdown.
pub(super) fn diagnose(a: &DiagnoseArgs) -> Result<()> {
    let file = a.model.config_file()?;
    let log = corridor_shared::imu_csv::read_imu_csv(&a.imu, &ImuCsvOptions::default())?;
    let truth = a
        .truth
        .as_deref()
        .map(corridor_shared::truth_csv::read_truth_csv)
        .transpose()?;
    let d = corridor_service::diagnose::run_diagnosis(
        &log,
        &file,
        truth.as_deref(),
        a.model.map.as_deref(),
    )?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    corridor_service::diagnose::write_report(&a.out, &d.report, &d.before, &d.after)?;
    print!("{}", std::fs::read_to_string(a.out.join("report.md"))?);
    Ok(())
}
