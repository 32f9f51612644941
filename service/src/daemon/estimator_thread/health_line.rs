//! The daemon's one-line health summary in the log (`daemon.health_period_s`): rates and
//! counts since the previous line, the bias and the estimator's robustness counters.

use super::super::receive::RxCounters;
use super::super::stall::StallCounts;
use super::EstState;
use crate::core::{ForceWitness, Phase};
use std::sync::atomic::Ordering;
use std::time::Instant;

/// Cumulative counters at the previous health line.
#[derive(Debug, Clone, Copy)]
pub(super) struct HealthMark {
    at: Instant,
    /// Received from the followed producer (`received` less `foreign_samples`).
    received: u64,
    seq_gaps: u64,
    rejected: u64,
    dropped: u64,
}

impl HealthMark {
    /// The mark at the start of a daemon life: from the accounting file's counters, which
    /// continue an earlier life's (the first health line of a restarted daemon counted them as
    /// this life's input).
    pub(super) fn now(rec: &RxCounters) -> Self {
        let load = |a: &std::sync::atomic::AtomicU64| a.load(Ordering::Relaxed);
        Self {
            at: Instant::now(),
            received: load(&rec.received).saturating_sub(load(&rec.foreign)),
            seq_gaps: load(&rec.seq_gaps),
            rejected: load(&rec.duplicate) + load(&rec.late),
            dropped: load(&rec.dropped),
        }
    }
}

/// `[x, y, z]` with 3 significant digits, for the health line.
pub(super) struct Vec3Fmt(pub(super) [f64; 3]);

impl std::fmt::Display for Vec3Fmt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [x, y, z] = self.0;
        write!(f, "[{x:.3e}, {y:.3e}, {z:.3e}]")
    }
}

/// A latency in s as µs, or `-` when unknown.
struct MicrosFmt(f64);

impl std::fmt::Display for MicrosFmt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.0.is_finite() {
            write!(f, "{:.0} µs", self.0 * 1e6)
        } else {
            f.write_str("-")
        }
    }
}

impl EstState<'_> {
    /// Logs the one-line health summary and starts a new window; `stalls`: the publishers'
    /// stalled consumers (attitude, bias, nav, diagnostics).
    pub(super) fn log_health(&mut self, rx: &RxCounters, stalls: [StallCounts; 4]) {
        let line = self.health_line(rx, stalls);
        tracing::info!("{line}");
    }

    /// The health line ([`Self::log_health`]), and a new window.
    fn health_line(&mut self, rx: &RxCounters, stalls: [StallCounts; 4]) -> String {
        let now = Instant::now();
        let d = self.diagnostics(rx, stalls, 0);
        let c = self.est.counters();
        let rejected = d.rejected_non_finite
            + d.rejected_time
            + d.rejected_duplicate_seq
            + d.late
            + self.previous.rejected_implausible
            + c.rejected_implausible
            + self.previous.rejected_time_jump
            + c.rejected_time_jump;
        let h = self.health;
        let secs = now.duration_since(h.at).as_secs_f64().max(1e-9);
        // The followed producer's input: a second producer's refused samples are not it.
        let received = d.received.saturating_sub(d.foreign_samples);
        let rate = received.saturating_sub(h.received) as f64 / secs;
        // (Each with its unit, or none: "none rad/s" read oddly, a review.)
        let (bias, sd) = if self.between_streams {
            ("none (between streams)".to_string(), "none".to_string())
        } else if self.est.bias_state().is_none() {
            // Before the first stream's alignment there is no estimate: the fresh estimator's
            // zero bias with σ NaN was printed as one (a review, session 38).
            ("none before the alignment".to_string(), "none".to_string())
        } else {
            (
                format!("{} rad/s", Vec3Fmt(self.last.gyro_bias_rad_s)),
                format!("{} rad/s", Vec3Fmt(self.last.gyro_bias_sd_rad_s)),
            )
        };
        let line = format!(
            "health: input {rate:.1} Hz ({} received), seq gaps +{} ({}), rejected +{} ({}), \
             dropped +{} ({}), producer changes {}, foreign samples {}, latency p50 {} p99 {}, bias {}, \
             σ {}, converged {}, phase {}{}, stances {} (map headings used: foot axis {}, strides {}), implausible {}, time jumps {}, clipped {} \
             (gyro peaks put back {}, not put back {}), health restores {} (footprints forgotten {}), velocity resets {}, tilts levelled again {}, headings taken as lost {}, time gaps {} (filled from the stride before {}, clock steps {}), clock steps back {}, IMU head missing {}, missing at restart {}, \
             lost in a killed daemon {}, external headings refused {} (superseded {}, outside the gate {}, expired (too old, or at a stream's end) {}, undone by the health check {}), \
             lossless consumers stalled {} (samples they lost {})",
            d.received,
            d.seq_gaps - h.seq_gaps,
            d.seq_gaps,
            rejected - h.rejected,
            rejected,
            d.dropped_overflow - h.dropped,
            d.dropped_overflow,
            d.producer_changes,
            d.foreign_samples,
            MicrosFmt(self.latency_health.quantile_s(0.5)),
            MicrosFmt(self.latency_health.quantile_s(0.99)),
            bias,
            sd,
            if self.last.converged { "yes" } else { "no" },
            if self.between_streams {
                "between streams"
            } else {
                self.est.phase().name()
            },
            match (c.alignment_not_gravity, self.est.phase()) {
                (0, _) | (_, Phase::Calibrating | Phase::Tracking) => {
                    // What said it: the rest's reading, or the stances' median (the median
                    // may lie within the tolerance while the rest's episode lasts).
                    let (what, reading) = match self.est.specific_force_off_gravity_said_by() {
                        Some(ForceWitness::InitialRest) => {
                            ("initial rest", self.est.rest_specific_force_m_s2())
                        }
                        Some(ForceWitness::QuietStances) => {
                            ("quiet stances", self.est.stance_specific_force_m_s2())
                        }
                        None => ("", None),
                    };
                    reading.map_or_else(String::new, |f| {
                        format!(" (accelerometer scale? its {what} read {f:.2} m/s², not gravity)")
                    })
                }
                (1, Phase::Aligning) => {
                    " (1 rest or stance refused: its specific force is no gravity)".into()
                }
                (n, Phase::Aligning) => {
                    format!(" ({n} rests or stances refused: their specific force is no gravity)")
                }
            },
            self.previous.stances + c.stances,
            self.previous.heading_used + c.heading_used,
            self.previous.stride_used + c.stride_used,
            self.previous.rejected_implausible + self.est.counters().rejected_implausible,
            self.previous.rejected_time_jump + self.est.counters().rejected_time_jump,
            d.clipped_samples,
            d.clipped_peaks_restored,
            d.clipped_peaks_not_restored,
            self.previous.health_restores + self.est.counters().health_restores,
            self.previous.footprints_forgotten + self.est.counters().footprints_forgotten,
            self.previous.velocity_resets + self.est.counters().velocity_resets,
            self.previous.relevels + self.est.counters().relevels,
            self.previous.heading_reacquisitions + self.est.counters().heading_reacquisitions,
            self.previous.gaps + self.est.counters().gaps,
            self.previous.gaps_filled + self.est.counters().gaps_filled,
            self.previous.gaps_clock_steps + self.est.counters().gaps_clock_steps,
            self.previous.clock_steps_back + self.est.counters().clock_steps_back,
            rx.head_missing.load(Ordering::Relaxed),
            rx.missing_at_restart.load(Ordering::Relaxed),
            rx.lost_in_daemon.load(Ordering::Relaxed),
            d.headings_refused,
            d.headings_superseded,
            d.headings_outside_gate,
            d.headings_expired,
            d.headings_undone,
            d.stalled_consumers,
            d.discarded_for_stalled,
        );
        self.latency_health.clear();
        self.health = HealthMark {
            at: now,
            received,
            seq_gaps: d.seq_gaps,
            rejected,
            dropped: d.dropped_overflow,
        };
        line
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::DaemonConfig;
    use super::*;
    use crate::core::heading::HeadingAid;
    use corridor_shared::config::Config;
    use corridor_shared::services::Domain;

    #[test]
    fn the_health_line_says_the_clipped_peaks_and_the_stalled_consumers() {
        // The daemon carried both peak counts over its streams and showed neither (they were
        // in `corridor run`'s summary only); the publishers' stall losses were in the report
        // at shutdown only.
        let rec = RxCounters::default();
        let domain = Domain::unsecured("test_health_line").unwrap();
        let cfg = DaemonConfig::new(domain, Config::default(), HeadingAid::None);
        let mut st = EstState::new(&cfg, &rec);
        // A finished stream's counts, as the daemon carries them over.
        st.previous.clipped_samples = 40;
        st.previous.clipped_peaks_restored = 7;
        st.previous.clipped_peaks_not_restored = 2;
        let stalled = |stalled_consumers, discarded| StallCounts {
            stalled_consumers,
            discarded,
        };
        let stalls = [stalled(1, 30), stalled(0, 0), stalled(2, 5), stalled(0, 0)];
        let line = st.health_line(&rec, stalls);
        assert!(
            line.contains("clipped 40 (gyro peaks put back 7, not put back 2)"),
            "{line}"
        );
        assert!(
            line.contains("lossless consumers stalled 3 (samples they lost 35)"),
            "{line}"
        );
    }
}
