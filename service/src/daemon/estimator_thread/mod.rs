//! The estimator thread (`corridor-estimator`): owns the [`Estimator`] and the output ports,
//! publishes per sample, handles the end of stream, saves the checkpoint and logs the health
//! line.

mod health_line;

use super::latency::LatencyHistogram;
use super::outputs::{Out, Outputs, attitude_of, bias_of, flags_of, phase_code};
use super::receive::{Msg, RxCounters};
use super::stall::StallCounts;
use super::state::{OUT_ATTITUDE, OUT_BIAS, OUT_DIAGNOSTICS, OUT_NAV, StateFile};
use super::{DaemonConfig, DaemonError, DaemonReport};
use crate::checkpoint::{self, Checkpoint, CheckpointError};
use crate::core::{Counters, Estimate, Estimator, ImuInput, Notice, Phase, SampleError, WarmStart};
use corridor_shared::wire::{
    Diagnostics, FLAG_END_OF_STREAM, FLAG_SHUTDOWN, ImuSample, NavSample, monotonic_ns,
};
use crossbeam_channel::{RecvTimeoutError, TryRecvError};
use health_line::{HealthMark, Vec3Fmt};
use iceoryx2::prelude::*;
use std::sync::Arc;
use std::sync::atomic::Ordering;

/// A clock that went back and runs on regularly for this long (its own time, s) has restarted:
/// the stream ends and a new one begins, as for a restarted producer. Shorter runs of earlier
/// times (a stray stamp, a replayed burst) are refused and counted as `rejected_time`; every
/// sample of the run before the restart is too.
const CLOCK_RESTART_S: f64 = 1.0;

/// Warnings kept for the daemon's report (all of them are logged).
const MAX_REPORTED_WARNINGS: usize = 64;
use std::time::Instant;

/// Refused samples per stream that are logged as warnings, rests or stances refused as no
/// gravity, and external headings refused on arrival (the rest at debug level; all counted).
const REFUSED_WARNINGS_PER_STREAM: u64 = 10;

/// State of the estimator thread.
struct EstState<'a> {
    /// The accounting file (input counters, `undelivered`).
    rec: &'a RxCounters,
    est: Estimator,
    /// Counters of the estimators of finished streams.
    previous: Counters,
    last: Estimate,
    last_imu_seq: u64,
    last_bias_t_s: f64,
    last_phase: Phase,
    last_nis: f64,
    streams_finished: u64,
    /// The next sample comes from a new producer (see [`Msg::NewProducer`]).
    producer_changed: bool,
    /// A stream ended and the next one has not sent a sample yet: the periodic diagnostics
    /// carry `FLAG_END_OF_STREAM` (the estimator is already the next stream's, aligning), and
    /// the health line says "between streams" instead of that estimator's zero bias.
    between_streams: bool,
    /// The run of samples refused in a row because their time went back, each following the
    /// one before it (a driver whose clock restarted): its first time and its last.
    went_back: Option<(f64, f64)>,
    /// The state each new stream starts from (checkpoint configured only).
    warm: Option<WarmStart>,
    warm_started_from: Option<Checkpoint>,
    /// Streams after the first of this daemon life that started from the gyro bias an earlier
    /// one left.
    streams_warm_started: u64,
    /// Accepted samples at the last checkpoint save (no save when nothing changed).
    saved_at_samples: u64,
    checkpoints_saved: u64,
    latency_diag: LatencyHistogram,
    latency_health: LatencyHistogram,
    health: HealthMark,
    warnings: Vec<String>,
    /// This stream's first rest or stance refused as no gravity went into `warnings`.
    not_gravity_reported: bool,
    /// The last checkpoint save's error, while saves keep failing with it.
    last_save_error: Option<String>,
}

impl<'a> EstState<'a> {
    fn new(cfg: &DaemonConfig, rec: &'a RxCounters) -> Self {
        Self {
            rec,
            est: Estimator::new(cfg.estimator.clone(), cfg.aid.clone()),
            previous: Counters::default(),
            last: Estimate::default(),
            last_imu_seq: 0,
            last_bias_t_s: f64::NEG_INFINITY,
            last_phase: Phase::Aligning,
            last_nis: f64::NAN,
            streams_finished: 0,
            producer_changed: false,
            between_streams: false,
            went_back: None,
            warm: None,
            warm_started_from: None,
            streams_warm_started: 0,
            saved_at_samples: 0,
            checkpoints_saved: 0,
            latency_diag: LatencyHistogram::new(),
            latency_health: LatencyHistogram::new(),
            health: HealthMark::now(rec),
            warnings: Vec::new(),
            not_gravity_reported: false,
            last_save_error: None,
        }
    }

    fn warn(&mut self, w: String) {
        tracing::warn!("{w}");
        // Bounded: a daemon that runs for weeks keeps the first ones for its report.
        match self.warnings.len() {
            n if n < MAX_REPORTED_WARNINGS => self.warnings.push(w),
            MAX_REPORTED_WARNINGS => self
                .warnings
                .push("further warnings are in the log only".to_owned()),
            _ => {}
        }
    }

    /// Accepted samples over all streams.
    fn accepted(&self) -> u64 {
        self.previous.samples + self.est.counters().samples
    }

    /// The counters as published; `stalls`: the publishers' stalled consumers (attitude, bias,
    /// nav, diagnostics).
    fn diagnostics(&self, rx: &RxCounters, stalls: [StallCounts; 4], flags: u32) -> Diagnostics {
        let c = self.est.counters();
        let p = &self.previous;
        Diagnostics {
            seq: 0,
            t_s: self.last.t_s,
            received: rx.received.load(Ordering::Relaxed),
            seq_gaps: rx.seq_gaps.load(Ordering::Relaxed),
            rejected_duplicate_seq: rx.duplicate.load(Ordering::Relaxed),
            late: rx.late.load(Ordering::Relaxed),
            rejected_non_finite: p.rejected_non_finite + c.rejected_non_finite,
            rejected_time: p.rejected_time + c.rejected_time,
            rejected_implausible: p.rejected_implausible + c.rejected_implausible,
            rejected_time_jump: p.rejected_time_jump + c.rejected_time_jump,
            dropped_overflow: rx.dropped.load(Ordering::Relaxed),
            accepted: p.samples + c.samples,
            undelivered: self.rec.undelivered.load(Ordering::Relaxed),
            stances: p.stances + c.stances,
            heading_used: p.heading_used + c.heading_used,
            last_nis: self.last_nis,
            producer_changes: rx.producer_changes.load(Ordering::Relaxed),
            latency_p50_s: self.latency_diag.quantile_s(0.5),
            latency_p99_s: self.latency_diag.quantile_s(0.99),
            head_missing: rx.head_missing.load(Ordering::Relaxed),
            missing_at_restart: rx.missing_at_restart.load(Ordering::Relaxed),
            lost_in_daemon: rx.lost_in_daemon.load(Ordering::Relaxed),
            angles_dropped: rx.angles_dropped.load(Ordering::Relaxed),
            lives: rx.lives.load(Ordering::Relaxed),
            foreign_samples: rx.foreign.load(Ordering::Relaxed),
            angles_ignored: rx.angles_ignored.load(Ordering::Relaxed),
            headings_refused: p.headings_refused + c.headings_refused,
            headings_superseded: p.headings_superseded + c.headings_superseded,
            headings_outside_gate: p.headings_outside_gate + c.headings_outside_gate,
            headings_expired: p.headings_expired + c.headings_expired,
            headings_undone: p.headings_undone + c.headings_undone,
            clipped_samples: p.clipped_samples + c.clipped_samples,
            clipped_peaks_restored: p.clipped_peaks_restored + c.clipped_peaks_restored,
            clipped_peaks_not_restored: p.clipped_peaks_not_restored + c.clipped_peaks_not_restored,
            stalled_consumers: stalls.iter().map(|s| s.stalled_consumers).sum(),
            discarded_for_stalled: stalls.iter().map(|s| s.discarded).sum(),
            phase: phase_code(self.est.phase()),
            flags,
        }
    }

    fn publish_diagnostics(&mut self, out: &mut Outputs, rx: &RxCounters, flags: u32) {
        let d = self.diagnostics(rx, out.stall_counts(), flags);
        let ok = out.diagnostics.publish(|v, q| v.seq = q, d);
        self.count(ok);
        // Late readers of the bias and nav streams get their latest value even while idle.
        out.bias.refresh();
        out.nav.refresh();
        self.latency_diag.clear();
    }

    fn count(&mut self, delivered: bool) {
        if !delivered {
            self.rec.undelivered.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// A sample refused because its time went back: counts it into the run of such samples
    /// that follow each other.
    fn note_went_back(&mut self, cfg: &DaemonConfig, t_s: f64) {
        let first = match self.went_back {
            Some((first, last)) if cfg.estimator.sensor.follows(last, t_s) => first,
            _ => t_s,
        };
        self.went_back = Some((first, t_s));
    }

    /// The clock went back and has run on regularly from there for [`CLOCK_RESTART_S`] of its
    /// own time, this sample included: a restarted device clock, not a stray stamp or a
    /// replayed burst.
    fn clock_restarted(&self, cfg: &DaemonConfig, t_s: f64) -> bool {
        self.went_back.is_some_and(|(first, last)| {
            cfg.estimator.sensor.follows(last, t_s) && t_s - first >= CLOCK_RESTART_S
        })
    }

    /// A fresh estimator for a new stream, warm-started from the last saved state if any.
    fn new_estimator(&mut self, cfg: &DaemonConfig) -> Estimator {
        let mut est = Estimator::new(cfg.estimator.clone(), cfg.aid.clone());
        if let Some(ws) = self.warm
            && let Err(e) = est.set_warm_start(ws)
        {
            self.warm = None;
            self.warn(format!("{e}; cold start"));
        }
        est
    }

    fn on_sample(&mut self, cfg: &DaemonConfig, out: &mut Outputs, rx: &RxCounters, s: &ImuSample) {
        let clock_went_back =
            s.t_s.partial_cmp(&self.last.t_s) != Some(std::cmp::Ordering::Greater);
        let producer_changed = std::mem::take(&mut self.producer_changed);
        if self.est.counters().samples > 0
            && clock_went_back
            && (producer_changed || self.clock_restarted(cfg, s.t_s))
        {
            // The producer's clock restarted: end the old stream as a marker would.
            tracing::warn!(
                t_s = s.t_s,
                last_t_s = self.last.t_s,
                "{}",
                if producer_changed {
                    "new IMU producer restarted its clock; starting a new stream"
                } else {
                    "the IMU clock went back and runs on from there; starting a new stream"
                }
            );
            self.went_back = None;
            let marker = ImuSample {
                seq: self.last_imu_seq,
                flags: FLAG_END_OF_STREAM,
                ..ImuSample::default()
            };
            self.on_end_of_stream(cfg, out, rx, &marker);
        }
        let input = ImuInput {
            t_s: s.t_s,
            gyro_rad_s: s.gyro_rad_s,
            accel_m_s2: s.accel_m_s2,
        };
        // (Between streams `warm` is what the estimator prepared for this one started from:
        // `new_estimator` drops a state it refused, and nothing is saved before a sample.)
        if self.between_streams && self.warm.is_some() {
            self.streams_warm_started += 1;
            tracing::info!(
                "this stream starts from the gyro bias an earlier one left (the daemon carries \
                 it across streams; `corridor run --checkpoint` with the saved state reproduces \
                 this stream, a cold `corridor run` does not)"
            );
        }
        self.between_streams = false;
        let e = match self.est.step(&input) {
            Ok(e) => {
                self.went_back = None;
                *e
            }
            Err(err) => {
                if let SampleError::TimeNotIncreasing { .. } = err {
                    self.note_went_back(cfg, s.t_s);
                }
                // Counted by the estimator (Diagnostics and the health line); the first few of
                // each stream are named with their sequence number.
                let refused = self.est.counters().refused();
                if refused <= REFUSED_WARNINGS_PER_STREAM {
                    tracing::warn!(seq = s.seq, reason = err.reason(), "sample refused: {err}");
                } else {
                    tracing::debug!(seq = s.seq, reason = err.reason(), "sample refused: {err}");
                }
                return;
            }
        };
        for n in e.notices() {
            // A stream in g refuses every stance as a rest: the first few are named. Into the
            // report's warnings: the first refusal as not gravity of each stream (a
            // flag, not the count: a copy restored after a glitch takes the count back), and
            // every time the specific force (the initial rest's or the stances' median) is said
            // off gravity (once each time).
            let to_report = match n {
                Notice::NotGravity(..) => !std::mem::replace(&mut self.not_gravity_reported, true),
                Notice::SpecificForceOffGravity(..) => true,
                _ => false,
            };
            let not_gravity_beyond_cap = matches!(n, Notice::NotGravity(..))
                && self.est.counters().alignment_not_gravity > REFUSED_WARNINGS_PER_STREAM;
            if to_report {
                self.warn(format!(
                    "stream {} (IMU seq {}): {n}",
                    self.streams_finished + 1,
                    s.seq
                ));
            } else if not_gravity_beyond_cap {
                tracing::debug!(seq = s.seq, "{n}");
            } else {
                tracing::warn!(seq = s.seq, "{n}");
            }
        }
        if e.replaced_first_t_s.is_some()
            || e.glitch_t_s.is_some()
            || e.clock_stepped_back_s.is_some()
        {
            // Its time paced the periodic bias output (a first time in the future stopped it, a
            // glitched stamp paused it for as long as the stamp was ahead, a clock set back
            // paused it for as long as it stepped); the attitude published for it stays
            // published.
            self.last_bias_t_s = f64::NEG_INFINITY;
        }
        self.last = e;
        self.last_imu_seq = s.seq;
        let ok = out
            .attitude
            .publish(|v, q| v.seq = q, attitude_of(&e, s.seq, s.sent_ns));
        self.count(ok);
        if s.sent_ns != 0 {
            let now = monotonic_ns();
            if now >= s.sent_ns {
                self.latency_diag.record(now - s.sent_ns);
                self.latency_health.record(now - s.sent_ns);
            }
        }
        if let Some(h) = &e.heading
            && let Ok(i) = &h.outcome
        {
            self.last_nis = i.nis;
        }
        let aligned_now = e.phase != self.last_phase && self.last_phase == Phase::Aligning;
        self.last_phase = e.phase;
        if aligned_now || e.heading.is_some() || e.t_s - self.last_bias_t_s >= cfg.bias_period_s {
            self.last_bias_t_s = e.t_s;
            let ok = out.bias.publish(|v, q| v.seq = q, bias_of(&e, s.seq));
            self.count(ok);
        }
        // A nav sample per stance counted. A glitched sample dropped after the fact took the
        // stance it counted with it (its nav sample stays published): the real footfall counts
        // it again, and is published with the same stance number and the later `imu_seq`. The
        // start heading that sets the map frame during the stance published last publishes
        // that stance again, in the frame (`FLAG_FRAME_SET`): its first nav sample was in the
        // frame before, its footfall 1.2-1.8 m and up to 180° off on the bundled walks (a
        // review).
        let stances = self.est.counters().stances;
        if e.stance_counted || (e.frame_set && stances > 0) {
            let nav = NavSample {
                seq: 0,
                t_s: e.t_s,
                imu_seq: s.seq,
                stance: stances,
                p_m: e.p_m,
                v_m_s: e.v_m_s,
                yaw_rad: e.yaw_rad,
                flags: flags_of(&e),
                reserved: 0,
            };
            let ok = out.nav.publish(|v, q| v.seq = q, nav);
            self.count(ok);
        }
    }

    /// An external heading, handed to the estimator, which refuses and counts one that is
    /// absurd or can no longer be used. A refusal is said with why; beyond the first
    /// [`REFUSED_WARNINGS_PER_STREAM`] of a stream at debug level (a producer that leaves `t_s`
    /// at 0 has every heading refused, each one warned of). Returns whether it was warned of.
    fn on_heading(&mut self, t_s: f64, heading_rad: f64, sd_rad: f64) -> bool {
        let Err(e) = self.est.queue_heading(t_s, heading_rad, sd_rad) else {
            return false;
        };
        let warn = self.est.counters().headings_refused <= REFUSED_WARNINGS_PER_STREAM;
        if warn {
            tracing::warn!("{e}");
        } else {
            tracing::debug!("{e}");
        }
        warn
    }

    fn on_end_of_stream(
        &mut self,
        cfg: &DaemonConfig,
        out: &mut Outputs,
        rx: &RxCounters,
        s: &ImuSample,
    ) {
        let mut a = attitude_of(&self.last, s.seq, s.sent_ns);
        a.flags |= FLAG_END_OF_STREAM;
        let ok = out.attitude.publish(|v, q| v.seq = q, a);
        self.count(ok);
        let nav = NavSample {
            t_s: self.last.t_s,
            imu_seq: s.seq,
            stance: self.est.counters().stances,
            p_m: self.last.p_m,
            v_m_s: self.last.v_m_s,
            yaw_rad: self.last.yaw_rad,
            flags: FLAG_END_OF_STREAM,
            ..NavSample::default()
        };
        let ok = out.nav.publish(|v, q| v.seq = q, nav);
        self.count(ok);
        let mut b = bias_of(&self.last, self.last_imu_seq);
        b.flags |= FLAG_END_OF_STREAM;
        let ok = out.bias.publish(|v, q| v.seq = q, b);
        self.count(ok);
        // What waited for samples that will not come, counted before the stream's last
        // diagnostics say the counts.
        self.est.end_stream();
        self.publish_diagnostics(out, rx, FLAG_END_OF_STREAM);
        self.save_checkpoint(cfg);
        // A new stream: fresh estimator (warm-started from the state just saved), counters
        // carried over.
        let c = *self.est.counters();
        let p = &mut self.previous;
        p.samples += c.samples;
        p.rejected_non_finite += c.rejected_non_finite;
        p.rejected_time += c.rejected_time;
        p.rejected_implausible += c.rejected_implausible;
        p.rejected_time_jump += c.rejected_time_jump;
        p.clipped_samples += c.clipped_samples;
        p.clipped_peaks_restored += c.clipped_peaks_restored;
        p.clipped_peaks_not_restored += c.clipped_peaks_not_restored;
        p.health_restores += c.health_restores;
        p.footprints_forgotten += c.footprints_forgotten;
        p.velocity_resets += c.velocity_resets;
        p.relevels += c.relevels;
        p.heading_reacquisitions += c.heading_reacquisitions;
        p.gaps += c.gaps;
        p.gaps_filled += c.gaps_filled;
        p.gaps_clock_steps += c.gaps_clock_steps;
        p.clock_steps_back += c.clock_steps_back;
        p.stances += c.stances;
        p.heading_used += c.heading_used;
        p.stride_used += c.stride_used;
        p.headings_refused += c.headings_refused;
        p.headings_superseded += c.headings_superseded;
        p.headings_outside_gate += c.headings_outside_gate;
        p.headings_expired += c.headings_expired;
        p.headings_undone += c.headings_undone;
        p.alignment_not_gravity += c.alignment_not_gravity;
        p.specific_force_off_gravity += c.specific_force_off_gravity;
        self.not_gravity_reported = false;
        self.est = self.new_estimator(cfg);
        self.last = Estimate::default();
        self.last_bias_t_s = f64::NEG_INFINITY;
        self.last_phase = Phase::Aligning;
        self.streams_finished += 1;
        self.between_streams = true;
    }

    /// Saves the estimator's bias state (once aligned, and only if it changed since the last
    /// save); it also becomes the warm start of the next stream.
    fn save_checkpoint(&mut self, cfg: &DaemonConfig) {
        let Some(path) = &cfg.checkpoint else { return };
        let Some(state) = self.est.bias_state() else {
            return;
        };
        let accepted = self.accepted();
        if accepted == self.saved_at_samples {
            return;
        }
        let cp = Checkpoint {
            mode: cfg.estimator.mode.name().to_owned(),
            t_s: self.last.t_s,
            saved_unix_ms: checkpoint::unix_now_ms(),
            gyro_bias_rad_s: state.gyro_bias_rad_s,
            gyro_bias_cov: state.gyro_bias_cov,
            nav_from_body_wxyz: self.last.nav_from_body,
        };
        match checkpoint::save(path, &cp) {
            Ok(()) => {
                self.saved_at_samples = accepted;
                self.checkpoints_saved += 1;
                self.last_save_error = None;
                self.warm = Some(state);
                tracing::debug!(path = %path.display(), t_s = cp.t_s, "checkpoint saved");
            }
            Err(e) => {
                // Still the best state for the next stream of this process.
                self.warm = Some(state);
                // Tried again at the next period (the directory may come back); the same
                // failure is said once, not every 30 s.
                let text = e.to_string();
                if self.last_save_error.as_deref() == Some(text.as_str()) {
                    tracing::debug!("{text} (again)");
                } else {
                    self.warn(text.clone());
                    self.last_save_error = Some(text);
                }
            }
        }
    }
}

pub(super) fn estimator_thread(
    cfg: &DaemonConfig,
    rx: crossbeam_channel::Receiver<Msg>,
    state: &Arc<StateFile>,
    ready: crossbeam_channel::Sender<Result<(), DaemonError>>,
) -> Result<DaemonReport, DaemonError> {
    let counters: &RxCounters = state;
    let setup = || -> Result<_, DaemonError> {
        let node = cfg
            .domain
            .node("corridor-daemon-estimator", SignalHandlingMode::Disabled)?;
        let out = Outputs {
            attitude: Out::new(cfg, &node, state, OUT_ATTITUDE)?,
            bias: Out::new(cfg, &node, state, OUT_BIAS)?,
            nav: Out::new(cfg, &node, state, OUT_NAV)?,
            diagnostics: Out::new(cfg, &node, state, OUT_DIAGNOSTICS)?,
        };
        Ok((out, node))
    };
    let (mut out, _node) = match setup() {
        Ok(x) => {
            let _ = ready.send(Ok(()));
            x
        }
        Err(e) => {
            let _ = ready.send(Err(e));
            return Ok(DaemonReport::default());
        }
    };
    drop(ready);
    let mut st = EstState::new(cfg, counters);
    load_warm_start(cfg, &mut st);
    st.est = st.new_estimator(cfg);
    let start = Instant::now();
    // The first diagnostics at once: a reader that attaches now gets the counters before any
    // sample of this life from the history (`corridor-replay`'s account of a replay started
    // right after the daemon, `corridor status`), not one period into a stream.
    let mut next_diag = start;
    let mut next_health = start + cfg.health_period;
    let mut next_checkpoint = start + cfg.checkpoint_period;
    loop {
        let deadline = next_diag.min(next_health).min(next_checkpoint);
        let msg = match rx.try_recv() {
            Ok(m) => Ok(m),
            Err(TryRecvError::Empty) => {
                // Woken by the receive thread's unpark after each send (no lost wake-up:
                // an unpark before the park makes it return at once).
                let now = Instant::now();
                if deadline > now {
                    std::thread::park_timeout(deadline - now);
                }
                Err(RecvTimeoutError::Timeout)
            }
            Err(TryRecvError::Disconnected) => Err(RecvTimeoutError::Disconnected),
        };
        match msg {
            Ok(Msg::Imu(s)) if s.is_end_of_stream() => {
                counters.taken.fetch_add(1, Ordering::Relaxed);
                st.on_end_of_stream(cfg, &mut out, counters, &s);
                next_diag = Instant::now() + cfg.diagnostics_period;
            }
            Ok(Msg::Imu(s)) => {
                counters.taken.fetch_add(1, Ordering::Relaxed);
                st.on_sample(cfg, &mut out, counters, &s);
            }
            Ok(Msg::Heading {
                t_s,
                heading_rad,
                sd_rad,
            }) => {
                st.on_heading(t_s, heading_rad, sd_rad);
            }
            Ok(Msg::NewProducer) => st.producer_changed = true,
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => break,
        }
        let now = Instant::now();
        if now >= next_diag {
            let flags = if st.between_streams {
                FLAG_END_OF_STREAM
            } else {
                0
            };
            st.publish_diagnostics(&mut out, counters, flags);
            next_diag = now + cfg.diagnostics_period;
        }
        if now >= next_health {
            st.log_health(counters, out.stall_counts());
            next_health = now + cfg.health_period;
        }
        if now >= next_checkpoint {
            st.save_checkpoint(cfg);
            next_checkpoint = Instant::now() + cfg.checkpoint_period;
        }
    }
    // A heading still waiting for a stance will not be used, nor a clipped peak still open put
    // back: both counted.
    st.est.end_stream();
    st.publish_diagnostics(&mut out, counters, FLAG_SHUTDOWN);
    st.save_checkpoint(cfg);
    let mut diagnostics = st.diagnostics(counters, out.stall_counts(), FLAG_SHUTDOWN);
    diagnostics.seq = out.diagnostics.seq.saturating_sub(1);
    Ok(DaemonReport {
        diagnostics,
        streams_finished: st.streams_finished,
        warm_started_from: st.warm_started_from,
        streams_warm_started: st.streams_warm_started,
        checkpoints_saved: st.checkpoints_saved,
        warnings: st.warnings,
        stalls: out.stall_counts(),
        head_missing: counters.head_missing.load(Ordering::Relaxed),
        missing_at_restart: counters.missing_at_restart.load(Ordering::Relaxed),
        estimated: counters.taken.load(Ordering::Relaxed),
        lost_in_daemon: counters.lost_in_daemon.load(Ordering::Relaxed),
        angles_dropped: counters.angles_dropped.load(Ordering::Relaxed),
        published: [
            out.attitude.seq,
            out.bias.seq,
            out.nav.seq,
            out.diagnostics.seq,
        ],
        lives: counters.lives.load(Ordering::Relaxed),
        alignment_not_gravity: st.previous.alignment_not_gravity
            + st.est.counters().alignment_not_gravity,
        specific_force_off_gravity: st.previous.specific_force_off_gravity
            + st.est.counters().specific_force_off_gravity,
    })
}

/// Loads the checkpoint into `st.warm`; a bad one becomes a warning and a cold start.
fn load_warm_start(cfg: &DaemonConfig, st: &mut EstState<'_>) {
    let Some(path) = &cfg.checkpoint else { return };
    match checkpoint::load(path) {
        Ok(cp) if cp.mode != cfg.estimator.mode.name() => {
            st.warn(format!(
                "{}: checkpoint is for mode {}, the daemon runs {}; cold start",
                path.display(),
                cp.mode,
                cfg.estimator.mode.name()
            ));
        }
        Ok(cp) => {
            tracing::info!(
                path = %path.display(),
                t_s = cp.t_s,
                age_s = cp.age().map(|a| a.as_secs_f64()),
                bias_rad_s = %Vec3Fmt(cp.gyro_bias_rad_s),
                "warm start from the checkpoint"
            );
            st.warm = Some(cp.warm_start());
            st.warm_started_from = Some(cp);
        }
        Err(CheckpointError::NotFound { .. }) => {
            tracing::info!(path = %path.display(), "no checkpoint; cold start");
        }
        Err(e) => st.warn(format!("{e}; cold start")),
    }
    // Whether it can be saved there: said now, and not again by the saves that fail alike.
    if let Err(e) = checkpoint::probe(path) {
        let text = e.to_string();
        st.warn(format!(
            "{text} (the daemon tries again at each save; the bias is carried across streams in memory meanwhile)"
        ));
        st.last_save_error = Some(text);
    }
}

#[cfg(test)]
mod tests {
    use super::super::DaemonConfig;
    use super::*;
    use crate::core::heading::HeadingAid;
    use corridor_shared::config::Config;
    use corridor_shared::services::Domain;

    #[test]
    fn refused_external_headings_are_warned_of_up_to_a_cap_per_stream_and_all_counted() {
        // Each one was a warning: a producer that leaves `t_s` at 0 has every heading refused
        // (2 s or more behind the latest sample), at its heading rate, for as long as it runs.
        let rx = RxCounters::default();
        let domain = Domain::unsecured("test_heading_warnings").unwrap();
        let cfg = DaemonConfig::new(domain, Config::default(), HeadingAid::None);
        let mut st = EstState::new(&cfg, &rx);
        assert!(!st.on_heading(0.0, 0.1, 0.05), "taken: nothing to warn of");
        let warned: Vec<bool> = (0..15)
            .map(|_| st.on_heading(f64::NAN, 0.1, 0.05))
            .collect();
        let cap = REFUSED_WARNINGS_PER_STREAM as usize;
        assert!(warned[..cap].iter().all(|&w| w), "{warned:?}");
        assert!(warned[cap..].iter().all(|&w| !w), "{warned:?}");
        assert_eq!(st.est.counters().headings_refused, 15);
    }
}
