//! [`RunOutcome`]: what [`super::run_log`] returns, and what the input cost it in one line.

use super::Trace;
use crate::core::Counters;
use corridor_shared::imu_csv::ImuLog;

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
    /// The first [`super::MAX_REFUSED_EXAMPLES`] samples refused by the estimator, with file, line and
    /// reason (the counts are in `counters`).
    pub refused: Vec<String>,
    /// Final extension estimates and the σ of the reported ones (see `Estimator::extensions`).
    pub extensions: Option<(
        crate::core::eskf::ExtensionEstimates,
        crate::core::eskf::ExtensionSd,
    )>,
}

impl RunOutcome {
    /// What the input cost this run of `log`, in one line, when it cost anything: rows the CSV
    /// reader rejected (by reason), samples the estimator refused (by reason, with the first
    /// one's place), gaps and how they were crossed, clock steps, restores of the health check,
    /// and the other events `corridor run` warns of (velocity resets, a heading reacquired).
    /// `None` for a clean log.
    pub fn input_report(&self, log: &ImuLog) -> Option<String> {
        let c = &self.counters;
        let mut parts = Vec::new();
        if !log.rejected.is_empty() {
            let reasons = log
                .rejected_counts()
                .into_iter()
                .filter(|&(_, n)| n > 0)
                .map(|(why, n)| format!("{why} {n}"))
                .collect::<Vec<_>>()
                .join(", ");
            parts.push(format!(
                "{} rejected by the CSV reader ({reasons})",
                count(log.rejected.len() as u64, "row")
            ));
        }
        if c.refused() > 0 {
            let reasons = [
                (c.rejected_non_finite, "not finite"),
                (c.rejected_time, "time"),
                (c.rejected_implausible, "implausible"),
                (c.rejected_time_jump, "time jump"),
            ]
            .iter()
            .filter(|(n, _)| *n > 0)
            .map(|(n, why)| format!("{why} {n}"))
            .collect::<Vec<_>>()
            .join(", ");
            let first = self
                .refused
                .first()
                .map_or(String::new(), |f| format!("; the first: {f}"));
            parts.push(format!(
                "{} refused ({reasons}{first})",
                count(c.refused(), "sample")
            ));
        }
        if c.gaps > 0 {
            parts.push(format!(
                "{} ({} bridged, {} filled, {} taken for clock steps)",
                count(c.gaps, "gap"),
                c.gaps_bridged,
                c.gaps_filled,
                c.gaps_clock_steps
            ));
        }
        if c.clock_steps_back > 0 {
            parts.push(count(c.clock_steps_back, "clock step back"));
        }
        if c.health_restores > 0 {
            parts.push(count(c.health_restores, "health-check restore"));
        }
        // Not the input's doing, but what `corridor run` warns of besides: said too.
        if c.velocity_resets > 0 {
            parts.push(count(c.velocity_resets, "velocity reset"));
        }
        if c.heading_reacquisitions > 0 {
            parts.push(count(c.heading_reacquisitions, "heading reacquisition"));
        }
        (!parts.is_empty()).then(|| parts.join("; "))
    }
}

/// "1 gap", "2 gaps".
pub(crate) fn count(n: u64, what: &str) -> String {
    format!("{n} {what}{}", if n == 1 { "" } else { "s" })
}
