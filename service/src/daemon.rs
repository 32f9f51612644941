//! The daemon: the estimator core ([`crate::core::Estimator`], the same as `corridor run`)
//! behind iceoryx2 shared-memory services.
//!
//! Threads (all named, all joined by [`run`]):
//! - `corridor-rx` owns the input subscriber ports ([`ImuSample`], [`AngleObservation`]). It
//!   blocks on the IMU event listener (no busy poll) with [`DaemonConfig::poll_timeout`] so it
//!   sees `shutdown`, checks `seq` (gaps, duplicates, late samples) and the producer's identity
//!   (a restarted producer), and forwards the samples over a bounded crossbeam channel. Angle
//!   observations are drained on every wake-up (an IMU stream wakes it at the sensor rate; an
//!   idle daemon within `poll_timeout`).
//! - `corridor-estimator` owns the [`Estimator`] and the output publisher ports, publishes an
//!   [`AttitudeSample`] per accepted IMU sample, a [`BiasSample`] at each heading observation,
//!   at the end of alignment and every [`DaemonConfig::bias_period_s`] of sensor time, a
//!   [`NavSample`] at each new stance, and [`Diagnostics`] every
//!   [`DaemonConfig::diagnostics_period`] (wall clock), at end of stream and at shutdown. It also
//!   logs a one-line health summary every [`DaemonConfig::health_period`] and saves the
//!   checkpoint every [`DaemonConfig::checkpoint_period`].
//!
//! iceoryx2 ports are `!Send`, so each thread creates its own node and ports. The daemon's code
//! and the estimator core allocate nothing per sample (tested by `tests/tests/daemon_alloc.rs`):
//! the channel is a preallocated array, samples are copied into loaned shared-memory slots, the
//! latency histograms are fixed arrays. The one allocation left per published message is inside
//! iceoryx2 0.10: `Publisher::loan_uninit` boxes a small `Rc` (`ChunkMutSharedState::new`,
//! iceoryx2 `port/details/chunk_mut_shared_state.rs`) that is freed again by `send`. Periodic
//! work (checkpoint, health line) may allocate.
//!
//! Delivery policy ([`Delivery`]): `live` drops the oldest sample of a full IPC buffer (seen as
//! `seq` gaps) and the newest one when the channel is full (`dropped_overflow`); `lossless`
//! blocks instead, back to the producer. With `lossless`, a connected reader that stops reading
//! stalls the daemon.
//!
//! End of stream: an [`ImuSample`] with [`FLAG_END_OF_STREAM`] makes the daemon publish one
//! attitude, nav, bias and diagnostics message carrying the flag (last state, no new data), save
//! the checkpoint and start a new estimator (the next producer starts at `seq` 0 with its own
//! clock). A producer replaced mid-stream (another publisher port, e.g. a restarted driver) is
//! counted in [`Diagnostics::producer_changes`]; its `seq` numbering starts afresh (a `seq`
//! continuing the old one still counts the gap), and when its clock restarted too, the daemon
//! ends the old stream as if it had received the marker.
//!
//! Checkpoint and warm start: with [`DaemonConfig::checkpoint`] set, the daemon loads it at
//! start (a corrupt or incompatible one is moved aside with a warning: cold start) and hands the
//! saved bias and covariance to [`Estimator::set_warm_start`] before the first sample; it saves
//! the estimator's [`Estimator::bias_state`] periodically, at each end of stream and at
//! shutdown. Every new stream warm-starts from the last saved state, as a restarted daemon
//! would. Without a checkpoint every stream starts from the configured prior (bit-identical to
//! `corridor run`).
//!
//! One daemon per domain: [`run`] claims the domain ([`Domain::claim_daemon`]) and fails with
//! [`ServiceError::DaemonAlreadyRunning`] when another daemon holds it.
//!
//! Signals: the caller owns SIGINT/SIGTERM and sets `shutdown` (every daemon node is created
//! with `SignalHandlingMode::Disabled`); [`shutdown_on_signal`] is a ready-made watcher.

use crate::checkpoint::{self, Checkpoint, CheckpointError};
use crate::core::heading::HeadingAid;
use crate::core::{Counters, Estimate, Estimator, ImuInput, Phase, WarmStart};
use corridor_shared::config::Config;
use corridor_shared::services::{Access, Delivery, Domain, ServiceError, Topic};
use corridor_shared::wire::{
    ANGLE_HEADING, AngleObservation, AttitudeSample, BiasSample, Diagnostics, FLAG_BIAS_CORRECTED,
    FLAG_CONVERGED, FLAG_END_OF_STREAM, FLAG_SHUTDOWN, FLAG_STANCE, ImuSample, NavSample,
    monotonic_ns, phase,
};
use crossbeam_channel::{RecvTimeoutError, TryRecvError, TrySendError};
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
    /// Period of the one-line health summary in the log (`info`), wall clock.
    pub health_period: Duration,
    /// Checkpoint file: loaded at start (a bad one is moved aside, with a warning), saved every
    /// [`DaemonConfig::checkpoint_period`], at each end of stream and at shutdown. `None`: no
    /// checkpoint, no warm start.
    pub checkpoint: Option<PathBuf>,
    /// Period of the checkpoint saves, wall clock (only when the state changed).
    pub checkpoint_period: Duration,
}

impl DaemonConfig {
    /// Everything from the configuration: the domain and the rest of its `[daemon]` section
    /// ([`corridor_shared::config::DaemonSettings`]). Fails when the domain name is not usable
    /// by iceoryx2.
    pub fn from_config(estimator: Config, aid: HeadingAid) -> Result<Self, DaemonError> {
        let domain = Domain::new(&estimator.daemon.domain)?;
        Ok(Self::new(domain, estimator, aid))
    }

    /// `domain`, and the rest from the `[daemon]` section of `estimator` (its defaults: live
    /// delivery, channel of 4096 samples, bias every 1 s, diagnostics every 1 s, health every
    /// 10 s, no checkpoint, checkpoint every 30 s); 100 ms poll.
    pub fn new(domain: Domain, estimator: Config, aid: HeadingAid) -> Self {
        let d = estimator.daemon.clone();
        Self {
            domain,
            estimator,
            aid,
            delivery: if d.lossless {
                Delivery::Lossless
            } else {
                Delivery::Live
            },
            channel_capacity: d.channel_capacity,
            poll_timeout: Duration::from_millis(100),
            bias_period_s: d.bias_period_s.get(),
            diagnostics_period: Duration::from_secs_f64(d.diagnostics_period_s.get()),
            health_period: Duration::from_secs_f64(d.health_period_s.get()),
            checkpoint: d.checkpoint_path,
            checkpoint_period: Duration::from_secs_f64(d.checkpoint_period_s.get()),
        }
    }
}

/// What a daemon did, returned by [`run`] after shutdown.
#[derive(Debug, Clone, Default)]
pub struct DaemonReport {
    /// The last diagnostics published (cumulative counters).
    pub diagnostics: Diagnostics,
    /// End-of-stream markers handled (and streams ended by a producer restart).
    pub streams_finished: u64,
    /// The checkpoint the daemon warm-started from, if any.
    pub warm_started_from: Option<Checkpoint>,
    /// Checkpoints saved.
    pub checkpoints_saved: u64,
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
    producer_changes: AtomicU64,
}

/// Receive → estimator messages.
#[derive(Debug, Clone, Copy)]
enum Msg {
    Imu(ImuSample),
    Heading {
        heading_rad: f64,
        sd_rad: f64,
    },
    /// The next IMU sample comes from another producer than the previous one, mid-stream.
    NewProducer,
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
    for (field, d) in [
        ("diagnostics_period", cfg.diagnostics_period),
        ("health_period", cfg.health_period),
        ("checkpoint_period", cfg.checkpoint_period),
        ("poll_timeout", cfg.poll_timeout),
    ] {
        if d.is_zero() {
            return Err(DaemonError::Config {
                field,
                value: format!("{d:?}"),
                rule: "must be > 0",
            });
        }
    }
    let node = cfg
        .domain
        .node("corridor-daemon", SignalHandlingMode::Disabled)?;
    let _claim = cfg.domain.claim_daemon(&node)?;
    tracing::info!(
        domain = cfg.domain.name(),
        delivery = cfg.delivery.name(),
        mode = cfg.estimator.mode.name(),
        checkpoint = ?cfg.checkpoint,
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
        let to_est = ToEstimator {
            tx,
            wake: est_handle.thread().clone(),
        };
        spawn(RX_THREAD, move || {
            rx_thread(&cfg, to_est, &counters, ready, &shutdown, &stop)
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
    // The channel is disconnected now; wake the estimator so it sees it at once.
    est_handle.thread().unpark();
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
        checkpoints_saved = report.checkpoints_saved,
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
    tx: ToEstimator,
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
    let mut last_producer = None;
    // True between the first data sample of a stream and its end-of-stream marker.
    let mut mid_stream = false;
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
            let producer = smp.header().publisher_id();
            drop(smp); // return the shared-memory slot at once
            counters.received.fetch_add(1, Ordering::Relaxed);
            if last_producer.is_some_and(|p| p != producer) && mid_stream {
                // A restarted or replaced producer: its numbering starts afresh unless it
                // continues the old one (then the gap is real and counted below).
                counters.producer_changes.fetch_add(1, Ordering::Relaxed);
                tracing::warn!(
                    seq = s.seq,
                    last_seq = ?last_seq,
                    "IMU producer changed mid-stream"
                );
                if last_seq.is_some_and(|l| s.seq <= l) {
                    last_seq = None;
                }
                // Never dropped: the estimator must see it before the new producer's samples.
                if !forward(
                    Delivery::Lossless,
                    &tx,
                    Msg::NewProducer,
                    counters,
                    &stopping,
                ) {
                    return Ok(());
                }
            }
            last_producer = Some(producer);
            if s.is_end_of_stream() {
                last_seq = None;
                mid_stream = false;
                // The marker is never dropped, whatever the policy.
                if !forward(Delivery::Lossless, &tx, Msg::Imu(s), counters, &stopping) {
                    return Ok(());
                }
                continue;
            }
            mid_stream = true;
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

/// The receive thread's end of the channel, and the estimator thread to wake after a send.
///
/// The estimator thread parks (`std::thread::park_timeout`) when the channel is empty instead
/// of a blocking `recv`: crossbeam's blocking receive spins and calls `sched_yield` several
/// times per sample before it sleeps, which costs more CPU than the estimation at 1 kHz.
struct ToEstimator {
    tx: crossbeam_channel::Sender<Msg>,
    wake: std::thread::Thread,
}

/// Hands `msg` to the estimator thread; false when the estimator thread is gone or the daemon
/// stops while waiting.
fn forward(
    delivery: Delivery,
    to: &ToEstimator,
    msg: Msg,
    counters: &RxCounters,
    stopping: &impl Fn() -> bool,
) -> bool {
    let tx = &to.tx;
    match delivery {
        Delivery::Live => match tx.try_send(msg) {
            Ok(()) => {
                to.wake.unpark();
                true
            }
            Err(TrySendError::Full(_)) => {
                counters.dropped.fetch_add(1, Ordering::Relaxed);
                to.wake.unpark();
                true
            }
            Err(TrySendError::Disconnected(_)) => false,
        },
        Delivery::Lossless => {
            // Polls instead of a blocking `send`: crossbeam's blocking path allocates (a wait
            // context per thread, its waker list) the first time the channel is full, and a
            // full channel means the estimator has `channel_capacity` samples of work queued,
            // so a 50 µs poll costs no throughput.
            let mut msg = msg;
            let mut waited = Duration::ZERO;
            loop {
                match tx.try_send(msg) {
                    Ok(()) => {
                        to.wake.unpark();
                        return true;
                    }
                    Err(TrySendError::Full(m)) => {
                        msg = m;
                        to.wake.unpark();
                        std::thread::sleep(FULL_POLL);
                        waited += FULL_POLL;
                        if waited >= Duration::from_millis(100) {
                            waited = Duration::ZERO;
                            if stopping() {
                                return false;
                            }
                        }
                    }
                    Err(TrySendError::Disconnected(_)) => return false,
                }
            }
        }
    }
}

/// Poll period of the receive thread while the channel is full (lossless policy).
const FULL_POLL: Duration = Duration::from_micros(50);

// ---------------------------------------------------------------------------------------------
// Latency histogram

/// Sub-buckets per octave of the latency histogram (resolution about 9 %).
const SUB_BUCKETS: usize = 8;

/// A fixed-size log-scale histogram of latencies in ns: no allocation when recording.
#[derive(Debug, Clone)]
struct LatencyHistogram {
    counts: [u32; 64 * SUB_BUCKETS],
    n: u64,
}

impl LatencyHistogram {
    fn new() -> Self {
        Self {
            counts: [0; 64 * SUB_BUCKETS],
            n: 0,
        }
    }

    fn bucket(ns: u64) -> usize {
        if ns < SUB_BUCKETS as u64 {
            return ns as usize;
        }
        let octave = 63 - ns.leading_zeros() as usize; // ≥ 3
        let sub = ((ns >> (octave - 3)) & (SUB_BUCKETS as u64 - 1)) as usize;
        (octave - 2) * SUB_BUCKETS + sub
    }

    /// Middle of a bucket, ns.
    fn value(bucket: usize) -> f64 {
        if bucket < SUB_BUCKETS {
            return bucket as f64;
        }
        let octave = bucket / SUB_BUCKETS + 2;
        let sub = bucket % SUB_BUCKETS;
        let low = ((SUB_BUCKETS + sub) as f64) * (1u64 << (octave - 3)) as f64;
        low + 0.5 * (1u64 << (octave - 3)) as f64
    }

    fn record(&mut self, ns: u64) {
        let b = Self::bucket(ns).min(self.counts.len() - 1);
        self.counts[b] = self.counts[b].saturating_add(1);
        self.n += 1;
    }

    /// The `q` quantile (0..=1), s; NaN when empty.
    fn quantile_s(&self, q: f64) -> f64 {
        if self.n == 0 {
            return f64::NAN;
        }
        let rank = ((q * self.n as f64).ceil() as u64).clamp(1, self.n);
        let mut acc = 0u64;
        for (b, &c) in self.counts.iter().enumerate() {
            acc += u64::from(c);
            if acc >= rank {
                return Self::value(b) * 1e-9;
            }
        }
        f64::NAN
    }

    fn clear(&mut self) {
        self.counts.fill(0);
        self.n = 0;
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

/// Cumulative counters at the previous health line.
#[derive(Debug, Clone, Copy)]
struct HealthMark {
    at: Instant,
    received: u64,
    seq_gaps: u64,
    rejected: u64,
    dropped: u64,
}

/// State of the estimator thread.
struct EstState {
    est: Estimator,
    /// Counters of the estimators of finished streams.
    previous: Counters,
    last: Estimate,
    last_imu_seq: u64,
    last_bias_t_s: f64,
    last_phase: Phase,
    last_stances: u64,
    last_nis: f64,
    undelivered: u64,
    streams_finished: u64,
    /// The next sample comes from a new producer (see [`Msg::NewProducer`]).
    producer_changed: bool,
    /// The state each new stream starts from (checkpoint configured only).
    warm: Option<WarmStart>,
    warm_started_from: Option<Checkpoint>,
    /// Accepted samples at the last checkpoint save (no save when nothing changed).
    saved_at_samples: u64,
    checkpoints_saved: u64,
    latency_diag: LatencyHistogram,
    latency_health: LatencyHistogram,
    health: HealthMark,
    warnings: Vec<String>,
}

fn phase_code(p: Phase) -> u32 {
    match p {
        Phase::Aligning => phase::ALIGNING,
        Phase::Calibrating => phase::CALIBRATING,
        Phase::Tracking => phase::TRACKING,
    }
}

fn phase_name(p: Phase) -> &'static str {
    match p {
        Phase::Aligning => "aligning",
        Phase::Calibrating => "calibrating",
        Phase::Tracking => "tracking",
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

fn attitude_of(e: &Estimate, imu_seq: u64, imu_sent_ns: u64) -> AttitudeSample {
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
        imu_sent_ns,
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

/// `[x, y, z]` with 3 significant digits, for the health line.
struct Vec3Fmt([f64; 3]);

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

impl EstState {
    fn new(cfg: &DaemonConfig) -> Self {
        Self {
            est: Estimator::new(cfg.estimator.clone(), cfg.aid.clone()),
            previous: Counters::default(),
            last: Estimate::default(),
            last_imu_seq: 0,
            last_bias_t_s: f64::NEG_INFINITY,
            last_phase: Phase::Aligning,
            last_stances: 0,
            last_nis: f64::NAN,
            undelivered: 0,
            streams_finished: 0,
            producer_changed: false,
            warm: None,
            warm_started_from: None,
            saved_at_samples: 0,
            checkpoints_saved: 0,
            latency_diag: LatencyHistogram::new(),
            latency_health: LatencyHistogram::new(),
            health: HealthMark {
                at: Instant::now(),
                received: 0,
                seq_gaps: 0,
                rejected: 0,
                dropped: 0,
            },
            warnings: Vec::new(),
        }
    }

    fn warn(&mut self, w: String) {
        tracing::warn!("{w}");
        self.warnings.push(w);
    }

    /// Accepted samples over all streams.
    fn accepted(&self) -> u64 {
        self.previous.samples + self.est.counters().samples
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
            producer_changes: rx.producer_changes.load(Ordering::Relaxed),
            latency_p50_s: self.latency_diag.quantile_s(0.5),
            latency_p99_s: self.latency_diag.quantile_s(0.99),
            phase: phase_code(self.est.phase()),
            flags,
        }
    }

    fn publish_diagnostics(&mut self, out: &mut Outputs, rx: &RxCounters, flags: u32) {
        let d = self.diagnostics(rx, flags);
        let ok = out.diagnostics.publish(|v, q| v.seq = q, d);
        self.count(ok);
        self.latency_diag.clear();
    }

    fn count(&mut self, delivered: bool) {
        if !delivered {
            self.undelivered += 1;
        }
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
        if std::mem::take(&mut self.producer_changed)
            && self.est.counters().samples > 0
            && clock_went_back
        {
            // The new producer's clock restarted: end the old stream as a marker would.
            tracing::warn!(
                t_s = s.t_s,
                last_t_s = self.last.t_s,
                "new IMU producer restarted its clock; starting a new stream"
            );
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
        let mut a = attitude_of(&self.last, s.seq, s.sent_ns);
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
        self.publish_diagnostics(out, rx, FLAG_END_OF_STREAM);
        self.save_checkpoint(cfg);
        // A new stream: fresh estimator (warm-started from the state just saved), counters
        // carried over.
        let c = *self.est.counters();
        let p = &mut self.previous;
        p.samples += c.samples;
        p.rejected_non_finite += c.rejected_non_finite;
        p.rejected_time += c.rejected_time;
        p.stances += c.stances;
        p.heading_used += c.heading_used;
        self.est = self.new_estimator(cfg);
        self.last = Estimate::default();
        self.last_bias_t_s = f64::NEG_INFINITY;
        self.last_phase = Phase::Aligning;
        self.last_stances = 0;
        self.streams_finished += 1;
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
                self.warm = Some(state);
                tracing::debug!(path = %path.display(), t_s = cp.t_s, "checkpoint saved");
            }
            Err(e) => {
                // Still the best state for the next stream of this process.
                self.warm = Some(state);
                self.warn(e.to_string());
            }
        }
    }

    /// Logs the one-line health summary and starts a new window.
    fn log_health(&mut self, rx: &RxCounters) {
        let now = Instant::now();
        let d = self.diagnostics(rx, 0);
        let rejected = d.rejected_non_finite + d.rejected_time + d.rejected_duplicate_seq + d.late;
        let h = self.health;
        let secs = now.duration_since(h.at).as_secs_f64().max(1e-9);
        let rate = (d.received - h.received) as f64 / secs;
        tracing::info!(
            "health: input {rate:.1} Hz ({} received), seq gaps +{} ({}), rejected +{} ({}), \
             dropped +{} ({}), producer changes {}, latency p50 {} p99 {}, bias {} rad/s, \
             σ {} rad/s, converged {}, phase {}",
            d.received,
            d.seq_gaps - h.seq_gaps,
            d.seq_gaps,
            rejected - h.rejected,
            rejected,
            d.dropped_overflow - h.dropped,
            d.dropped_overflow,
            d.producer_changes,
            MicrosFmt(self.latency_health.quantile_s(0.5)),
            MicrosFmt(self.latency_health.quantile_s(0.99)),
            Vec3Fmt(self.last.gyro_bias_rad_s),
            Vec3Fmt(self.last.gyro_bias_sd_rad_s),
            if self.last.converged { "yes" } else { "no" },
            phase_name(self.est.phase()),
        );
        self.latency_health.clear();
        self.health = HealthMark {
            at: now,
            received: d.received,
            seq_gaps: d.seq_gaps,
            rejected,
            dropped: d.dropped_overflow,
        };
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
    load_warm_start(cfg, &mut st);
    st.est = st.new_estimator(cfg);
    let start = Instant::now();
    let mut next_diag = start + cfg.diagnostics_period;
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
                st.on_end_of_stream(cfg, &mut out, counters, &s);
                next_diag = Instant::now() + cfg.diagnostics_period;
            }
            Ok(Msg::Imu(s)) => st.on_sample(cfg, &mut out, counters, &s),
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
            Ok(Msg::NewProducer) => st.producer_changed = true,
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => break,
        }
        let now = Instant::now();
        if now >= next_diag {
            st.publish_diagnostics(&mut out, counters, 0);
            next_diag = now + cfg.diagnostics_period;
        }
        if now >= next_health {
            st.log_health(counters);
            next_health = now + cfg.health_period;
        }
        if now >= next_checkpoint {
            st.save_checkpoint(cfg);
            next_checkpoint = Instant::now() + cfg.checkpoint_period;
        }
    }
    st.publish_diagnostics(&mut out, counters, FLAG_SHUTDOWN);
    st.save_checkpoint(cfg);
    let mut diagnostics = st.diagnostics(counters, FLAG_SHUTDOWN);
    diagnostics.seq = out.diagnostics.seq.saturating_sub(1);
    Ok(DaemonReport {
        diagnostics,
        streams_finished: st.streams_finished,
        warm_started_from: st.warm_started_from,
        checkpoints_saved: st.checkpoints_saved,
        warnings: st.warnings,
    })
}

/// Loads the checkpoint into `st.warm`; a bad one becomes a warning and a cold start.
fn load_warm_start(cfg: &DaemonConfig, st: &mut EstState) {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_histogram_quantiles_are_within_a_bucket() {
        let mut h = LatencyHistogram::new();
        assert!(h.quantile_s(0.5).is_nan());
        for ns in 1..=1000u64 {
            h.record(ns * 1000); // 1 µs .. 1 ms, uniform
        }
        let p50 = h.quantile_s(0.5);
        let p99 = h.quantile_s(0.99);
        assert!((p50 - 500e-6).abs() < 0.07 * 500e-6, "{p50}");
        assert!((p99 - 990e-6).abs() < 0.07 * 990e-6, "{p99}");
        h.record(u64::MAX); // clamped into the last bucket, no panic
        h.clear();
        assert!(h.quantile_s(0.99).is_nan());
        for ns in 0..8 {
            assert_eq!(
                LatencyHistogram::value(LatencyHistogram::bucket(ns)),
                ns as f64
            );
        }
    }
}
