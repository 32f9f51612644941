//! `corridor serve`: the daemon until SIGINT/SIGTERM, with its report printed as JSON.

use super::model::ModelArgs;
use anyhow::Result;
use clap::Args;
use corridor_service::runner;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub(super) struct ServeArgs {
    #[command(flatten)]
    pub(super) model: ModelArgs,
    /// iceoryx2 domain to serve (overrides `daemon.domain`); processes on other domains never
    /// see this daemon.
    #[arg(long, value_parser = corridor_shared::services::Domain::parse_name)]
    pub(super) domain: Option<String>,
    /// live (a lagging reader loses the oldest samples, counted) or lossless (the producer
    /// waits); overrides `daemon.delivery`.
    #[arg(long)]
    pub(super) delivery: Option<corridor_shared::services::Delivery>,
    /// Serve a secured domain from this runtime directory (overrides `daemon.runtime_dir`):
    /// only this user can connect, with CORRIDOR_RUNTIME_DIR set to the same directory.
    #[arg(long, value_parser = absolute_path())]
    pub(super) runtime_dir: Option<PathBuf>,
    /// Checkpoint file (overrides `daemon.checkpoint_path`): loaded at start (a bad one is
    /// moved aside, cold start), saved periodically, at each end of stream and at shutdown.
    #[arg(long)]
    pub(super) checkpoint: Option<PathBuf>,
}

/// Serves until a termination request, then prints the daemon's report.
pub(super) fn serve(a: &ServeArgs) -> Result<()> {
    use corridor_service::daemon::{self, DaemonConfig};
    let config = a.model.config()?;
    let mut settings = a.model.daemon_settings()?;
    if let Some(dir) = &a.runtime_dir {
        settings.runtime_dir = Some(dir.clone());
    }
    let aid = runner::heading_aid(&config, a.model.map.as_deref())?;
    // The flags override the `[daemon]` section of the file.
    let mut cfg = match &a.domain {
        Some(d) => DaemonConfig::with_settings(
            corridor_shared::services::Domain::serve(d, settings.runtime_dir.as_deref())?,
            config,
            &settings,
            aid,
        ),
        None => DaemonConfig::from_config(config, &settings, aid)?,
    };
    if let Some(d) = a.delivery {
        cfg.delivery = d;
    }
    if let Some(p) = &a.checkpoint {
        cfg.checkpoint = Some(p.clone());
    }
    let report = daemon::serve(cfg)?;
    corridor_client::say!("{}", serde_json::to_string_pretty(&report_json(&report))?);
    Ok(())
}

/// The daemon's report as `corridor serve` prints it at shutdown: every count the last
/// diagnostics carry, and the per-output counts of the report.
fn report_json(report: &corridor_service::daemon::DaemonReport) -> serde_json::Value {
    let d = &report.diagnostics;
    serde_json::json!({
        "streams_finished": report.streams_finished,
        "received": d.received,
        "accepted": d.accepted,
        "seq_gaps": d.seq_gaps,
        "rejected_non_finite": d.rejected_non_finite,
        "rejected_time": d.rejected_time,
        "rejected_implausible": d.rejected_implausible,
        "rejected_time_jump": d.rejected_time_jump,
        "rejected_duplicate_seq": d.rejected_duplicate_seq,
        "late": d.late,
        "dropped_overflow": d.dropped_overflow,
        "undelivered": d.undelivered,
        "producer_changes": d.producer_changes,
        "foreign_samples": d.foreign_samples,
        "head_missing": report.head_missing,
        "missing_at_restart": report.missing_at_restart,
        "estimated": report.estimated,
        "lost_in_daemon": report.lost_in_daemon,
        "angles_dropped": report.angles_dropped,
        "angles_ignored": d.angles_ignored,
        "headings_refused": d.headings_refused,
        "headings_superseded": d.headings_superseded,
        "headings_outside_gate": d.headings_outside_gate,
        "headings_expired": d.headings_expired,
        "headings_undone": d.headings_undone,
        "clipped_samples": d.clipped_samples,
        "clipped_peaks_restored": d.clipped_peaks_restored,
        "clipped_peaks_not_restored": d.clipped_peaks_not_restored,
        "published": {
            "attitude": report.published[0],
            "bias": report.published[1],
            "nav": report.published[2],
            "diagnostics": report.published[3],
        },
        "stalled_consumers": {
            "attitude": report.stalls[0].stalled_consumers,
            "bias": report.stalls[1].stalled_consumers,
            "nav": report.stalls[2].stalled_consumers,
            "diagnostics": report.stalls[3].stalled_consumers,
        },
        "stalled_discarded": {
            "attitude": report.stalls[0].discarded,
            "bias": report.stalls[1].discarded,
            "nav": report.stalls[2].discarded,
            "diagnostics": report.stalls[3].discarded,
        },
        "daemon_lives": report.lives,
        "checkpoints_saved": report.checkpoints_saved,
        "warm_started": report.warm_started_from.is_some(),
        "streams_warm_started": report.streams_warm_started,
        "alignment_not_gravity": report.alignment_not_gravity,
        "specific_force_off_gravity": report.specific_force_off_gravity,
        "warnings": report.warnings,
    })
}

/// `--runtime-dir`: an absolute path, any bytes (a usage error otherwise, exit code 2).
fn absolute_path() -> impl clap::builder::TypedValueParser<Value = PathBuf> {
    use clap::builder::TypedValueParser;
    clap::builder::PathBufValueParser::new().try_map(|dir| {
        if dir.is_absolute() {
            Ok(dir)
        } else {
            Err(format!("{}: must be an absolute path", dir.display()))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_report_says_the_clipping_counts_and_the_stalled_consumers() {
        // The report left out the v6 counts the diagnostics carry (the samples at a rail, the
        // gyro peaks put back or not) and the stalled consumers themselves (only what was
        // discarded for them), though the DaemonReport holds them.
        let mut report = corridor_service::daemon::DaemonReport::default();
        let d = &mut report.diagnostics;
        (d.clipped_samples, d.clipped_peaks_restored) = (144, 30);
        d.clipped_peaks_not_restored = 2;
        report.stalls[0].stalled_consumers = 1;
        report.stalls[2].stalled_consumers = 3;
        report.stalls[2].discarded = 40;
        let j = report_json(&report);
        assert_eq!(j["clipped_samples"], 144, "{j}");
        assert_eq!(j["clipped_peaks_restored"], 30, "{j}");
        assert_eq!(j["clipped_peaks_not_restored"], 2, "{j}");
        assert_eq!(j["stalled_consumers"]["attitude"], 1, "{j}");
        assert_eq!(j["stalled_consumers"]["nav"], 3, "{j}");
        assert_eq!(j["stalled_discarded"]["nav"], 40, "{j}");
    }
}
