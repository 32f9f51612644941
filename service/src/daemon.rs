//! The daemon: the estimator core ([`crate::core::Estimator`], the same as `corridor run`)
//! behind iceoryx2 shared-memory services.
//!
//! Threads (all named, all joined by [`run`]):
//! - `corridor-rx` owns the input subscriber ports ([`ImuSample`], [`AngleObservation`]). It
//!   blocks on the IMU event listener (no busy poll) with [`DaemonConfig::poll_timeout`] so it
//!   sees `shutdown`, checks `seq` (gaps, duplicates, late samples) and forwards the samples over
//!   a bounded crossbeam channel. Angle observations are drained on every wake-up (an IMU stream
//!   wakes it at the sensor rate; an idle daemon within `poll_timeout`).
//! - `corridor-estimator` owns the [`Estimator`] and the output publisher ports, publishes an
//!   [`AttitudeSample`] per accepted IMU sample, a [`BiasSample`] at each heading observation and
//!   every [`DaemonConfig::bias_period_s`] of sensor time, a [`NavSample`] at each new stance,
//!   and [`Diagnostics`] every [`DaemonConfig::diagnostics_period`] (wall clock), at end of
//!   stream and at shutdown.
//!
//! iceoryx2 ports are `!Send`, so each thread creates its own node and ports. Neither thread
//! allocates per sample: the channel is a preallocated array, samples are copied into loaned
//! shared-memory slots.
//!
//! Delivery policy ([`Delivery`]): `live` drops the oldest sample of a full IPC buffer (seen as
//! `seq` gaps) and the newest one when the channel is full (`dropped_overflow`); `lossless`
//! blocks instead, back to the producer. With `lossless`, a connected reader that stops reading
//! stalls the daemon.
//!
//! End of stream: an [`ImuSample`] with [`FLAG_END_OF_STREAM`] makes the daemon publish one
//! attitude, nav, bias and diagnostics message carrying the flag (last state, no new data), save the checkpoint and start a
//! new estimator (the next producer starts at `seq` 0 with its own clock).
//!
//! One daemon per domain: [`run`] claims the domain ([`Domain::claim_daemon`]) and fails with
//! [`ServiceError::DaemonAlreadyRunning`] when another daemon holds it.
//!
//! Signals: the caller owns SIGINT/SIGTERM and sets `shutdown` (every daemon node is created
//! with `SignalHandlingMode::Disabled`); [`shutdown_on_signal`] is a ready-made watcher.

use crate::checkpoint::{self, Checkpoint, CheckpointError};
use crate::core::heading::HeadingAid;
use crate::core::{Counters, Estimate, Estimator, ImuInput, Phase};
use corridor_shared::config::Config;
use corridor_shared::services::{Access, Delivery, Domain, ServiceError, Topic};
use corridor_shared::wire::{
    ANGLE_HEADING, AngleObservation, AttitudeSample, BiasSample, Diagnostics, FLAG_BIAS_CORRECTED,
    FLAG_CONVERGED, FLAG_END_OF_STREAM, FLAG_SHUTDOWN, FLAG_STANCE, ImuSample, NavSample, phase,
};
use crossbeam_channel::{RecvTimeoutError, SendTimeoutError, TrySendError};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Name of the receive thread.
pub const RX_THREAD: &str = "corridor-rx";
/// Name of the estimator thread.
pub const ESTIMATOR_THREAD: &str = "corridor-estimator";

/// Everything the daemon needs.
#[derive(Debug, Clone)]
pub struct DaemonConfig {
    /// The iceoryx2 namespace to serve.
    pub domain: Domain,
    /// Validated estimator configuration.
    pub estimator: Config,
    /// Heading source (see [`crate::runner::heading_aid`]).
    pub aid: HeadingAid,
    /// Delivery policy; producers must use the same.
    pub delivery: Delivery,
    /// Capacity of the receive → estimator channel, samples.
    pub channel_capacity: usize,
    /// Longest blocking wait of the receive thread, so it sees `shutdown`.
    pub poll_timeout: Duration,
    /// Period of [`BiasSample`]s besides those at heading observations, s of sensor time.
    pub bias_period_s: f64,
    /// Period of [`Diagnostics`], wall clock.
    pub diagnostics_period: Duration,
    /// Checkpoint file: loaded at start (a bad one is moved aside, with a warning), saved at
    /// each end of stream and at shutdown. `None`: no checkpoint.
    pub checkpoint: Option<PathBuf>,
}

impl DaemonConfig {
    /// Defaults: live delivery, channel of 4096 samples, 100 ms poll, bias every 1 s, diagnostics
    /// every 1 s, no checkpoint.
    pub fn new(domain: Domain, estimator: Config, aid: HeadingAid) -> Self {
        Self {
            domain,
            estimator,
            aid,
            delivery: Delivery::Live,
            channel_capacity: 4096,
            poll_timeout: Duration::from_millis(100),
            bias_period_s: 1.0,
            diagnostics_period: Duration::from_secs(1),
            checkpoint: None,
        }
    }
}

/// What a daemon did, returned by [`run`] after shutdown.
#[derive(Debug, Clone, Default)]
pub struct DaemonReport {
    /// The last diagnostics published (cumulative counters).
    pub diagnostics: Diagnostics,
    /// End-of-stream markers handled.
    pub streams_finished: u64,
    /// Non-fatal problems (a bad checkpoint, a failed save), in order.
    pub warnings: Vec<String>,
}

/// A daemon failure.
#[derive(Debug, thiserror::Error)]
pub enum DaemonError {
    /// A service or port could not be set up or used (includes another daemon on the domain).
    #[error(transparent)]
    Service(#[from] ServiceError),
    /// A thread could not be started.
    #[error("cannot start thread {thread}: {source}")]
    Spawn {
        /// Thread name.
        thread: &'static str,
        /// The OS error.
        source: std::io::Error,
    },
    /// A thread panicked.
    #[error("thread {thread} panicked: {message}")]
    Panicked {
        /// Thread name.
        thread: &'static str,
        /// The panic message.
        message: String,
    },
    /// The configuration is not usable.
    #[error("daemon configuration: {field} = {value}: {rule}")]
    Config {
        /// Field.
        field: &'static str,
        /// Value found.
        value: String,
        /// What it must satisfy.
        rule: &'static str,
    },
}

/// Counters of the receive thread, read by the estimator thread.
#[derive(Debug, Default)]
struct RxCounters {
    received: AtomicU64,
    seq_gaps: AtomicU64,
    duplicate: AtomicU64,
    late: AtomicU64,
    dropped: AtomicU64,
}

/// Receive → estimator messages.
#[derive(Debug, Clone, Copy)]
enum Msg {
    Imu(ImuSample),
    Heading { heading_rad: f64, sd_rad: f64 },
}

/// Runs the daemon until `shutdown` is set (or a thread fails), then returns its report.
pub fn run(cfg: DaemonConfig, shutdown: Arc<AtomicBool>) -> Result<DaemonReport, DaemonError> {
    if cfg.channel_capacity == 0 {
        return Err(DaemonError::Config {
            field: "channel_capacity",
            value: "0".into(),
            rule: "must be at least 1",
        });
    }
    if !(cfg.bias_period_s.is_finite() && cfg.bias_period_s > 0.0) {
        return Err(DaemonError::Config {
            field: "bias_period_s",
            value: cfg.bias_period_s.to_string(),
            rule: "must be a finite number > 0",
        });
    }
    let node = cfg
        .domain
        .node("corridor-daemon", SignalHandlingMode::Disabled)?;
    let _claim = cfg.domain.claim_daemon(&node)?;
    tracing::info!(
        domain = cfg.domain.name(),
        delivery = cfg.delivery.name(),
        mode = cfg.estimator.mode.name(),
        "corridor daemon starting"
    );

    let (tx, rx) = crossbeam_channel::bounded::<Msg>(cfg.channel_capacity);
    let (ready_tx, ready_rx) = crossbeam_channel::bounded::<Result<(), DaemonError>>(2);
    let stop = Arc::new(AtomicBool::new(false));
    let counters = Arc::new(RxCounters::default());

    let est_handle = {
        let cfg = cfg.clone();
        let counters = Arc::clone(&counters);
        let ready = ready_tx.clone();
        spawn(ESTIMATOR_THREAD, move || {
            estimator_thread(&cfg, rx, &counters, ready)
        })?
    };
    let rx_handle = {
        let cfg = cfg.clone();
        let counters = Arc::clone(&counters);
        let stop = Arc::clone(&stop);
        let shutdown = Arc::clone(&shutdown);
        let ready = ready_tx;
        spawn(RX_THREAD, move || {
            rx_thread(&cfg, tx, &counters, ready, &shutdown, &stop)
        })
    };
    let rx_handle = match rx_handle {
        Ok(h) => h,
        Err(e) => {
            // The estimator thread ends when the channel's sender (moved into the failed
            // closure) is dropped.
            let _ = join(ESTIMATOR_THREAD, est_handle);
            return Err(e);
        }
    };

    // Both threads report their setup; the first failure stops the other one.
    let mut setup_err = None;
    for _ in 0..2 {
        match ready_rx.recv() {
            Ok(Ok(())) => {}
            Ok(Err(e)) => {
                setup_err.get_or_insert(e);
                stop.store(true, Ordering::Relaxed);
            }
            Err(_) => break, // a thread ended without reporting: its join says why
        }
    }
    if setup_err.is_none() {
        tracing::info!(domain = cfg.domain.name(), "corridor daemon ready");
    }
    let rx_result = join(RX_THREAD, rx_handle);
    let est_result = join(ESTIMATOR_THREAD, est_handle);
    if let Some(e) = setup_err {
        return Err(e);
    }
    rx_result?;
    let report = est_result?;
    tracing::info!(
        domain = cfg.domain.name(),
        received = report.diagnostics.received,
        accepted = report.diagnostics.accepted,
        "corridor daemon stopped"
    );
    Ok(report)
}

/// `corridor serve`: [`run`] until SIGINT or SIGTERM (watched by [`shutdown_on_signal`]).
/// Warnings are logged as they occur and kept in the report.
pub fn serve(cfg: DaemonConfig) -> Result<DaemonReport, DaemonError> {
    let shutdown = Arc::new(AtomicBool::new(false));
    let watcher = shutdown_on_signal(&cfg.domain, Arc::clone(&shutdown))?;
    let result = run(cfg, Arc::clone(&shutdown));
    shutdown.store(true, Ordering::Relaxed);
    let _ = watcher.join();
    result
}

/// Watches SIGINT/SIGTERM (through iceoryx2's handler, on a node of `domain`) on a thread named
/// `corridor-signals` and sets `shutdown` when one arrives. The thread also ends once `shutdown`
/// is set by someone else.
pub fn shutdown_on_signal(
    domain: &Domain,
    shutdown: Arc<AtomicBool>,
) -> Result<JoinHandle<()>, DaemonError> {
    let domain = domain.clone();
    spawn("corridor-signals", move || {
        let node = match domain.node(
            "corridor-signals",
            SignalHandlingMode::HandleTerminationRequests,
        ) {
            Ok(n) => n,
            Err(e) => {
                tracing::error!("signal watcher: {e}; SIGINT/SIGTERM will not stop the daemon");
                return;
            }
        };
        while !shutdown.load(Ordering::Relaxed) {
            if node.wait(Duration::from_millis(100)).is_err() {
                tracing::info!("termination requested");
                shutdown.store(true, Ordering::Relaxed);
            }
        }
    })
}

fn spawn<T: Send + 'static>(
    thread: &'static str,
    f: impl FnOnce() -> T + Send + 'static,
) -> Result<JoinHandle<T>, DaemonError> {
    std::thread::Builder::new()
        .name(thread.to_owned())
        .spawn(f)
        .map_err(|source| DaemonError::Spawn { thread, source })
}

fn join<T>(thread: &'static str, h: JoinHandle<Result<T, DaemonError>>) -> Result<T, DaemonError> {
    h.join().unwrap_or_else(|p| {
        let message = p
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "<non-string panic>".into());
        Err(DaemonError::Panicked { thread, message })
    })
}

fn port_err(
    domain: &Domain,
    service: &'static str,
    port: &'static str,
    e: impl std::fmt::Debug,
) -> DaemonError {
    DaemonError::Service(ServiceError::Port {
        service,
        port,
        domain: domain.name().to_owned(),
        detail: format!("{e:?}"),
    })
}

fn io_err(
    domain: &Domain,
    service: &'static str,
    operation: &'static str,
    e: impl std::fmt::Debug,
) -> DaemonError {
    DaemonError::Service(ServiceError::Io {
        service,
        operation,
        domain: domain.name().to_owned(),
        detail: format!("{e:?}"),
    })
}

// ---------------------------------------------------------------------------------------------
// Receive thread

fn rx_thread(
    cfg: &DaemonConfig,
    tx: crossbeam_channel::Sender<Msg>,
    counters: &RxCounters,
    ready: crossbeam_channel::Sender<Result<(), DaemonError>>,
    shutdown: &AtomicBool,
    stop: &AtomicBool,
) -> Result<(), DaemonError> {
    let setup = || -> Result<_, DaemonError> {
        let d = &cfg.domain;
        let node = d.node("corridor-daemon-rx", SignalHandlingMode::Disabled)?;
        let access = Access::Owner(cfg.delivery);
        let imu = d
            .open::<ImuSample>(&node, access)?
            .subscriber_builder()
            .buffer_size(ImuSample::QOS.buffer_size)
            .create()
            .map_err(|e| port_err(d, ImuSample::SERVICE, "subscriber", e))?;
        let listener = d
            .open_event(&node, ImuSample::SERVICE, true)?
            .listener_builder()
            .create()
            .map_err(|e| port_err(d, ImuSample::SERVICE, "listener", e))?;
        let angles = d
            .open::<AngleObservation>(&node, access)?
            .subscriber_builder()
            .buffer_size(AngleObservation::QOS.buffer_size)
            .create()
            .map_err(|e| port_err(d, AngleObservation::SERVICE, "subscriber", e))?;
        // The producers notify this one too; creating it lets them open it before we wait.
        let _angles_event = d.open_event(&node, AngleObservation::SERVICE, true)?;
        Ok((imu, listener, angles, _angles_event, node))
    };
    let (imu, listener, angles, _angles_event, _node) = match setup() {
        Ok(x) => {
            let _ = ready.send(Ok(()));
            x
        }
        Err(e) => {
            let _ = ready.send(Err(e));
            return Ok(());
        }
    };
    drop(ready);
    let d = &cfg.domain;
    let stopping = || shutdown.load(Ordering::Relaxed) || stop.load(Ordering::Relaxed);
    let mut last_seq: Option<u64> = None;
    while !stopping() {
        listener
            .timed_wait(|_| {}, cfg.poll_timeout)
            .map_err(|e| io_err(d, ImuSample::SERVICE, "wait", e))?;
        while let Some(obs) = angles
            .receive()
            .map_err(|e| io_err(d, AngleObservation::SERVICE, "receive", e))?
        {
            let o: AngleObservation = *obs.payload();
            drop(obs);
            if o.valid & ANGLE_HEADING != 0 {
                let msg = Msg::Heading {
                    heading_rad: o.heading_rad,
                    sd_rad: o.heading_sd_rad,
                };
                if !forward(cfg.delivery, &tx, msg, counters, &stopping) {
                    return Ok(());
                }
            }
        }
        while let Some(smp) = imu
            .receive()
            .map_err(|e| io_err(d, ImuSample::SERVICE, "receive", e))?
        {
            let s: ImuSample = *smp.payload();
            drop(smp); // return the shared-memory slot at once
            counters.received.fetch_add(1, Ordering::Relaxed);
            if s.is_end_of_stream() {
                last_seq = None;
                // The marker is never dropped, whatever the policy.
                if !forward(Delivery::Lossless, &tx, Msg::Imu(s), counters, &stopping) {
                    return Ok(());
                }
                continue;
            }
            if let Some(l) = last_seq {
                if s.seq == l {
                    counters.duplicate.fetch_add(1, Ordering::Relaxed);
                    continue;
                }
                if s.seq < l {
                    counters.late.fetch_add(1, Ordering::Relaxed);
                    continue;
                }
                counters
                    .seq_gaps
                    .fetch_add(s.seq - l - 1, Ordering::Relaxed);
            }
            last_seq = Some(s.seq);
            if !forward(cfg.delivery, &tx, Msg::Imu(s), counters, &stopping) {
                return Ok(());
            }
        }
    }
    Ok(())
}

/// Hands `msg` to the estimator thread; false when the estimator thread is gone or the daemon
/// stops while waiting.
fn forward(
    delivery: Delivery,
    tx: &crossbeam_channel::Sender<Msg>,
    msg: Msg,
    counters: &RxCounters,
    stopping: &impl Fn() -> bool,
) -> bool {
    match delivery {
        Delivery::Live => match tx.try_send(msg) {
            Ok(()) => true,
            Err(TrySendError::Full(_)) => {
                counters.dropped.fetch_add(1, Ordering::Relaxed);
                true
            }
            Err(TrySendError::Disconnected(_)) => false,
        },
        Delivery::Lossless => {
            let mut msg = msg;
            loop {
                match tx.send_timeout(msg, Duration::from_millis(100)) {
                    Ok(()) => return true,
                    Err(SendTimeoutError::Timeout(m)) => {
                        if stopping() {
                            return false;
                        }
                        msg = m;
                    }
                    Err(SendTimeoutError::Disconnected(_)) => return false,
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Estimator thread

/// A publisher with its paired notifier.
struct Out<T: Topic> {
    publisher: Publisher<ipc::Service, T, ()>,
    notifier: Notifier<ipc::Service>,
    seq: u64,
    failed_once: bool,
}

impl<T: Topic> Out<T> {
    fn new(cfg: &DaemonConfig, node: &Node<ipc::Service>) -> Result<Self, DaemonError> {
        let d = &cfg.domain;
        let publisher = d
            .open::<T>(node, Access::Owner(cfg.delivery))?
            .publisher_builder()
            .backpressure_strategy(cfg.delivery.backpressure())
            .max_loaned_samples(2)
            .create()
            .map_err(|e| port_err(d, T::SERVICE, "publisher", e))?;
        let notifier = d
            .open_event(node, T::SERVICE, true)?
            .notifier_builder()
            .create()
            .map_err(|e| port_err(d, T::SERVICE, "notifier", e))?;
        Ok(Self {
            publisher,
            notifier,
            seq: 0,
            failed_once: false,
        })
    }

    /// Publishes `value` with the next `seq`; returns false when nobody received it.
    fn publish(&mut self, set_seq: impl FnOnce(&mut T, u64), mut value: T) -> bool {
        set_seq(&mut value, self.seq);
        self.seq += 1;
        let delivered = match self.publisher.loan_uninit() {
            Ok(slot) => slot.write_payload(value).send(),
            Err(e) => Err(e.into()),
        };
        let _ = self.notifier.notify();
        match delivered {
            Ok(n) => n > 0,
            Err(e) => {
                if !self.failed_once {
                    self.failed_once = true;
                    tracing::warn!(
                        service = T::SERVICE,
                        "publishing failed: {e:?} (reported once)"
                    );
                }
                false
            }
        }
    }
}

struct Outputs {
    attitude: Out<AttitudeSample>,
    bias: Out<BiasSample>,
    nav: Out<NavSample>,
    diagnostics: Out<Diagnostics>,
}

/// State of the estimator thread.
struct EstState {
    est: Estimator,
    /// Counters of the estimators of finished streams.
    previous: Counters,
    last: Estimate,
    last_imu_seq: u64,
    last_bias_t_s: f64,
    last_stances: u64,
    last_nis: f64,
    undelivered: u64,
    streams_finished: u64,
    warnings: Vec<String>,
}

fn phase_code(p: Phase) -> u32 {
    match p {
        Phase::Aligning => phase::ALIGNING,
        Phase::Calibrating => phase::CALIBRATING,
        Phase::Tracking => phase::TRACKING,
    }
}

fn flags_of(e: &Estimate) -> u32 {
    let mut f = 0;
    if e.phase != Phase::Aligning {
        f |= FLAG_BIAS_CORRECTED;
    }
    if e.stance {
        f |= FLAG_STANCE;
    }
    if e.converged {
        f |= FLAG_CONVERGED;
    }
    f
}

fn attitude_of(e: &Estimate, imu_seq: u64) -> AttitudeSample {
    AttitudeSample {
        seq: 0,
        t_s: e.t_s,
        imu_seq,
        nav_from_body_wxyz: e.nav_from_body,
        roll_rad: e.roll_rad,
        pitch_rad: e.pitch_rad,
        yaw_rad: e.yaw_rad,
        gyro_bias_rad_s: e.gyro_bias_rad_s,
        gyro_bias_sd_rad_s: e.gyro_bias_sd_rad_s,
        phase: phase_code(e.phase),
        flags: flags_of(e),
    }
}

fn bias_of(e: &Estimate, imu_seq: u64) -> BiasSample {
    BiasSample {
        seq: 0,
        t_s: e.t_s,
        imu_seq,
        gyro_bias_rad_s: e.gyro_bias_rad_s,
        gyro_bias_sd_rad_s: e.gyro_bias_sd_rad_s,
        converged: u32::from(e.converged),
        flags: flags_of(e) & FLAG_CONVERGED,
    }
}

impl EstState {
    fn new(cfg: &DaemonConfig) -> Self {
        Self {
            est: Estimator::new(cfg.estimator.clone(), cfg.aid.clone()),
            previous: Counters::default(),
            last: Estimate::default(),
            last_imu_seq: 0,
            last_bias_t_s: f64::NEG_INFINITY,
            last_stances: 0,
            last_nis: f64::NAN,
            undelivered: 0,
            streams_finished: 0,
            warnings: Vec::new(),
        }
    }

    fn diagnostics(&self, rx: &RxCounters, flags: u32) -> Diagnostics {
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
            dropped_overflow: rx.dropped.load(Ordering::Relaxed),
            accepted: p.samples + c.samples,
            undelivered: self.undelivered,
            stances: p.stances + c.stances,
            heading_used: p.heading_used + c.heading_used,
            last_nis: self.last_nis,
            phase: phase_code(self.est.phase()),
            flags,
        }
    }

    fn count(&mut self, delivered: bool) {
        if !delivered {
            self.undelivered += 1;
        }
    }

    fn on_sample(&mut self, cfg: &DaemonConfig, out: &mut Outputs, s: &ImuSample) {
        let input = ImuInput {
            t_s: s.t_s,
            gyro_rad_s: s.gyro_rad_s,
            accel_m_s2: s.accel_m_s2,
        };
        let e = match self.est.step(&input) {
            Ok(e) => *e,
            Err(err) => {
                // Counted by the estimator, published in Diagnostics.
                tracing::debug!(seq = s.seq, "sample refused: {err}");
                return;
            }
        };
        self.last = e;
        self.last_imu_seq = s.seq;
        let ok = out
            .attitude
            .publish(|v, q| v.seq = q, attitude_of(&e, s.seq));
        self.count(ok);
        if let Some(h) = &e.heading
            && let Ok(i) = &h.outcome
        {
            self.last_nis = i.nis;
        }
        if e.heading.is_some() || e.t_s - self.last_bias_t_s >= cfg.bias_period_s {
            self.last_bias_t_s = e.t_s;
            let ok = out.bias.publish(|v, q| v.seq = q, bias_of(&e, s.seq));
            self.count(ok);
        }
        let stances = self.est.counters().stances;
        if stances > self.last_stances {
            self.last_stances = stances;
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

    fn on_end_of_stream(
        &mut self,
        cfg: &DaemonConfig,
        out: &mut Outputs,
        rx: &RxCounters,
        s: &ImuSample,
    ) {
        let mut a = attitude_of(&self.last, s.seq);
        a.flags |= FLAG_END_OF_STREAM;
        let ok = out.attitude.publish(|v, q| v.seq = q, a);
        self.count(ok);
        let nav = NavSample {
            t_s: self.last.t_s,
            imu_seq: s.seq,
            stance: self.last_stances,
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
        let d = self.diagnostics(rx, FLAG_END_OF_STREAM);
        let ok = out.diagnostics.publish(|v, q| v.seq = q, d);
        self.count(ok);
        self.save_checkpoint(cfg);
        // A new stream: fresh estimator, counters carried over.
        let c = *self.est.counters();
        let p = &mut self.previous;
        p.samples += c.samples;
        p.rejected_non_finite += c.rejected_non_finite;
        p.rejected_time += c.rejected_time;
        p.stances += c.stances;
        p.heading_used += c.heading_used;
        self.est = Estimator::new(cfg.estimator.clone(), cfg.aid.clone());
        self.last = Estimate::default();
        self.last_bias_t_s = f64::NEG_INFINITY;
        self.last_stances = 0;
        self.streams_finished += 1;
    }

    /// Saves bias, covariance and attitude once the estimator has aligned.
    fn save_checkpoint(&mut self, cfg: &DaemonConfig) {
        let Some(path) = &cfg.checkpoint else { return };
        if self.last.phase == Phase::Aligning {
            return;
        }
        let sd = self.last.gyro_bias_sd_rad_s;
        // TODO(core): the estimator exposes only the σ of the bias; store its full covariance
        // once `Estimator::gyro_bias_covariance()` exists. Until then the diagonal.
        let mut cov = [[0.0; 3]; 3];
        for i in 0..3 {
            cov[i][i] = sd[i] * sd[i];
        }
        let cp = Checkpoint {
            mode: cfg.estimator.mode.name().to_owned(),
            t_s: self.last.t_s,
            gyro_bias_rad_s: self.last.gyro_bias_rad_s,
            gyro_bias_cov: cov,
            nav_from_body_wxyz: self.last.nav_from_body,
        };
        if let Err(e) = checkpoint::save(path, &cp) {
            tracing::warn!("{e}");
            self.warnings.push(e.to_string());
        }
    }
}

fn estimator_thread(
    cfg: &DaemonConfig,
    rx: crossbeam_channel::Receiver<Msg>,
    counters: &RxCounters,
    ready: crossbeam_channel::Sender<Result<(), DaemonError>>,
) -> Result<DaemonReport, DaemonError> {
    let setup = || -> Result<_, DaemonError> {
        let node = cfg
            .domain
            .node("corridor-daemon-estimator", SignalHandlingMode::Disabled)?;
        let out = Outputs {
            attitude: Out::new(cfg, &node)?,
            bias: Out::new(cfg, &node)?,
            nav: Out::new(cfg, &node)?,
            diagnostics: Out::new(cfg, &node)?,
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
    let mut st = EstState::new(cfg);
    warm_start(cfg, &mut st);
    let mut next_diag = Instant::now() + cfg.diagnostics_period;
    loop {
        let wait = next_diag.saturating_duration_since(Instant::now());
        match rx.recv_timeout(wait) {
            Ok(Msg::Imu(s)) if s.is_end_of_stream() => {
                st.on_end_of_stream(cfg, &mut out, counters, &s);
                next_diag = Instant::now() + cfg.diagnostics_period;
            }
            Ok(Msg::Imu(s)) => st.on_sample(cfg, &mut out, &s),
            Ok(Msg::Heading {
                heading_rad,
                sd_rad,
            }) => {
                if heading_rad.is_finite() && sd_rad.is_finite() && sd_rad > 0.0 {
                    st.est.queue_heading(heading_rad, sd_rad);
                } else {
                    tracing::debug!(heading_rad, sd_rad, "angle observation refused");
                }
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => break,
        }
        if Instant::now() >= next_diag {
            let d = st.diagnostics(counters, 0);
            let ok = out.diagnostics.publish(|v, q| v.seq = q, d);
            st.count(ok);
            next_diag = Instant::now() + cfg.diagnostics_period;
        }
    }
    let d = st.diagnostics(counters, FLAG_SHUTDOWN);
    let ok = out.diagnostics.publish(|v, q| v.seq = q, d);
    st.count(ok);
    st.save_checkpoint(cfg);
    let mut diagnostics = st.diagnostics(counters, FLAG_SHUTDOWN);
    diagnostics.seq = out.diagnostics.seq.saturating_sub(1);
    Ok(DaemonReport {
        diagnostics,
        streams_finished: st.streams_finished,
        warnings: st.warnings,
    })
}

/// Loads the checkpoint; a bad one becomes a warning and a cold start.
fn warm_start(cfg: &DaemonConfig, st: &mut EstState) {
    let Some(path) = &cfg.checkpoint else { return };
    match checkpoint::load(path) {
        Ok(cp) if cp.mode != cfg.estimator.mode.name() => {
            let w = format!(
                "{}: checkpoint is for mode {}, the daemon runs {}; cold start",
                path.display(),
                cp.mode,
                cfg.estimator.mode.name()
            );
            tracing::warn!("{w}");
            st.warnings.push(w);
        }
        Ok(cp) => {
            // TODO(core): warm start needs `Estimator::warm_start(bias, bias_cov, nav_from_body)`
            // (a prior used at the end of alignment instead of the configured one). Until it
            // exists the checkpoint is only loaded and validated.
            tracing::info!(
                path = %path.display(),
                t_s = cp.t_s,
                "checkpoint loaded; warm start is not wired into the estimator yet, cold start"
            );
        }
        Err(CheckpointError::NotFound { .. }) => {
            tracing::info!(path = %path.display(), "no checkpoint; cold start");
        }
        Err(e) => {
            let w = format!("{e}; cold start");
            tracing::warn!("{w}");
            st.warnings.push(w);
        }
    }
}
