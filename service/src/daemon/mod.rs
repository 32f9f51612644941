//! The daemon: the estimator core ([`crate::core::Estimator`], the same as `corridor run`)
//! behind iceoryx2 shared-memory services.
//!
//! Threads (all named, all joined by [`run`]):
//! - `corridor-rx` owns the input subscriber ports ([`ImuSample`], [`AngleObservation`]). It
//!   blocks on the IMU event listener (no busy poll) with [`DaemonConfig::poll_timeout`] so it
//!   sees `shutdown`, checks `seq` (gaps, duplicates, late samples) and the producer's identity
//!   (a restarted producer; one producer at a time, another one's samples refused and counted
//!   while the followed one is live: `producers`; the per-sample bookkeeping, pure and
//!   unit-tested: `intake`), and forwards the samples over a bounded crossbeam channel. Angle
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
//! Loss accounting: the input counters, the position in the current producer's numbering and
//! the output `seq`s live in the domain's accounting file (`state`), a shared file mapping that
//! survives the process however it ends; the next daemon of the domain continues them, so what
//! a restart cost is counted once ([`DaemonReport::missing_at_restart`],
//! [`DaemonReport::lost_in_daemon`]) and consumers see one continuous numbering.
//!
//! One daemon per domain: [`run`] claims the domain ([`Domain::claim_daemon`]) and fails with
//! [`ServiceError::DaemonAlreadyRunning`] when another daemon holds it.
//!
//! Signals: the caller owns SIGINT/SIGTERM and sets `shutdown` (every daemon node is created
//! with `SignalHandlingMode::Disabled`); [`shutdown_on_signal`] is a ready-made watcher.
//!
//! Map of the submodules:
//! - this file: [`DaemonConfig`], [`DaemonReport`], [`DaemonError`], [`run`], [`serve`] and
//!   [`shutdown_on_signal`], the thread plumbing they share.
//! - `receive`: the receive thread (`corridor-rx`), its counters and the channel to the
//!   estimator thread.
//! - `estimator_thread`: the estimator thread (`corridor-estimator`): its state, the end of
//!   stream, the checkpoint saves; its `health_line` the one-line health summary.
//! - `outputs`: the output publishers and the conversion of an estimate into wire messages.
//! - `intake`: the IMU input's bookkeeping, sample by sample (received, repeated, late, another
//!   producer's, missing), for the accounting file.
//! - `producers`: which IMU producer the receive thread follows when several publish.
//! - [`stall`]: a lossless consumer that stops reading does not hold the publishers for longer
//!   than `daemon.stall_timeout_s`.
//! - `latency`: the allocation-free latency histogram behind the diagnostics and health line.
//! - `state`: the accounting file (the receive thread's counters, the output `seq`s).
//!
//! [`Estimator`]: crate::core::Estimator
//! [`Estimator::set_warm_start`]: crate::core::Estimator::set_warm_start
//! [`Estimator::bias_state`]: crate::core::Estimator::bias_state
//! [`ImuSample`]: corridor_shared::wire::ImuSample
//! [`AngleObservation`]: corridor_shared::wire::AngleObservation
//! [`AttitudeSample`]: corridor_shared::wire::AttitudeSample
//! [`BiasSample`]: corridor_shared::wire::BiasSample
//! [`NavSample`]: corridor_shared::wire::NavSample
//! [`FLAG_END_OF_STREAM`]: corridor_shared::wire::FLAG_END_OF_STREAM

mod estimator_thread;
mod intake;
mod latency;
mod outputs;
mod producers;
mod receive;
pub mod stall;
mod state;

pub use state::StateFileError;

use crate::checkpoint::Checkpoint;
use crate::core::heading::HeadingAid;
use corridor_shared::config::{Config, DaemonSettings};
use corridor_shared::services::{Delivery, Domain, ServiceError};
use corridor_shared::wire::Diagnostics;
use estimator_thread::estimator_thread;
use iceoryx2::prelude::*;
use receive::{Msg, ToEstimator, rx_thread};
use state::StateFile;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

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
    /// Longest blocking wait of the receive thread, so it sees `shutdown`, and the most a wake-up
    /// that iceoryx2 0.10 loses can delay the samples behind it (default
    /// [`EVENT_WAIT_SLICE`](corridor_shared::services::EVENT_WAIT_SLICE), as every other wait on
    /// an iceoryx2 event in corridor).
    pub poll_timeout: Duration,
    /// Period of [`BiasSample`](corridor_shared::wire::BiasSample)s besides those at heading observations, s of sensor time.
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
    /// Longest a lossless publish waits on one consumer's full buffer; beyond it the consumer
    /// counts as stalled and loses (counted) what its buffer cannot take.
    pub stall_timeout: Duration,
    /// While the followed IMU producer is connected and has sent within this, another
    /// producer's samples are refused and counted ([`Diagnostics::foreign_samples`]); after it
    /// the other takes over (`daemon.producer_takeover_s`).
    pub producer_takeover: Duration,
}

impl DaemonConfig {
    /// Everything from the configuration: the estimator's settings, and the domain and the rest
    /// of the `[daemon]` section ([`DaemonSettings`]). Fails when the domain name is not usable
    /// by iceoryx2, or its runtime directory (`daemon.runtime_dir`) is not usable or held by
    /// another daemon.
    pub fn from_config(
        estimator: Config,
        daemon: &DaemonSettings,
        aid: HeadingAid,
    ) -> Result<Self, DaemonError> {
        let domain = Domain::serve(&daemon.domain, daemon.runtime_dir.as_deref())?;
        Ok(Self::with_settings(domain, estimator, daemon, aid))
    }

    /// `domain`, and the rest from the built-in `[daemon]` defaults (live delivery, channel of
    /// 4096 samples, bias every 1 s, diagnostics every 1 s, health every 10 s, no checkpoint,
    /// checkpoint every 30 s); the event waits of `EVENT_WAIT_SLICE`.
    pub fn new(domain: Domain, estimator: Config, aid: HeadingAid) -> Self {
        Self::with_settings(domain, estimator, &DaemonSettings::default(), aid)
    }

    /// `domain`, and the rest from `d` (a `[daemon]` section).
    pub fn with_settings(
        domain: Domain,
        estimator: Config,
        d: &DaemonSettings,
        aid: HeadingAid,
    ) -> Self {
        let d = d.clone();
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
            poll_timeout: corridor_shared::services::EVENT_WAIT_SLICE,
            bias_period_s: d.bias_period_s.get(),
            diagnostics_period: Duration::from_secs_f64(d.diagnostics_period_s.get()),
            health_period: Duration::from_secs_f64(d.health_period_s.get()),
            checkpoint: d.checkpoint_path,
            checkpoint_period: Duration::from_secs_f64(d.checkpoint_period_s.get()),
            stall_timeout: Duration::from_secs_f64(d.stall_timeout_s.get()),
            producer_takeover: Duration::from_secs_f64(d.producer_takeover_s.get()),
        }
    }
}

/// What a daemon did, returned by [`run`] after shutdown.
///
/// The input counters (`diagnostics.received`, `seq_gaps`, `late`, `rejected_duplicate_seq`,
/// `dropped_overflow`, `producer_changes`, and the loss counters below), `undelivered` and
/// [`DaemonReport::published`] count over every life of the domain's daemon that used its
/// accounting file ([`Domain::daemon_state_path`]), this one included; the estimator's counts
/// (`accepted`, the rejections, `stances`, `heading_used`) over this life only.
#[derive(Debug, Clone, Default)]
pub struct DaemonReport {
    /// The last diagnostics published (cumulative counters).
    pub diagnostics: Diagnostics,
    /// End-of-stream markers handled (and streams ended by a producer restart).
    pub streams_finished: u64,
    /// The checkpoint the daemon warm-started from, if any.
    pub warm_started_from: Option<Checkpoint>,
    /// Streams after this life's first that started from the gyro bias (and its covariance) an
    /// earlier stream left (a daemon with a checkpoint path carries it from one stream to the
    /// next; the attitude is aligned again): a replay of such a stream equals `corridor run
    /// --checkpoint` with that state, not a cold `corridor run`.
    pub streams_warm_started: u64,
    /// Checkpoints saved.
    pub checkpoints_saved: u64,
    /// Non-fatal problems (a bad checkpoint, a failed save), in order.
    pub warnings: Vec<String>,
    /// Consumers that stalled an output for longer than [`DaemonConfig::stall_timeout`], and the
    /// samples they lost, per output: attitude, bias, nav, diagnostics.
    pub stalls: [stall::StallCounts; 4],
    /// IMU samples of a producer's numbering before the first one a daemon received from it
    /// (sent before any daemon read it, or overwritten in the input buffer before the first
    /// read); the gaps after that are in `diagnostics.seq_gaps` and `missing_at_restart`.
    pub head_missing: u64,
    /// IMU samples of the current producer's numbering between the last one an earlier daemon
    /// life received and the first one the next life received: sent while no daemon was there,
    /// or left unread in the input buffer of a daemon that stopped or was killed.
    pub missing_at_restart: u64,
    /// IMU samples the estimator took (estimated or refused by it, markers included).
    pub estimated: u64,
    /// IMU samples an earlier daemon life received but neither estimated, refused by `seq` nor
    /// dropped (killed with them in its receive thread or channel): `received = estimated +
    /// dropped_overflow + rejected_duplicate_seq + late + foreign_samples + lost_in_daemon`
    /// after a clean stop.
    pub lost_in_daemon: u64,
    /// Angle observations dropped because the estimator's channel was full (live delivery).
    pub angles_dropped: u64,
    /// Messages published per output (attitude, bias, nav, diagnostics): the next `seq` of each,
    /// continued across daemon lives.
    pub published: [u64; 4],
    /// Daemon lives that used the accounting file, this one included.
    pub lives: u64,
    /// Rests or first stances not aligned on because their specific force was no gravity (a
    /// producer's stream in g), over every stream of this life; the first of each stream is in
    /// `warnings` (while they are below their cap).
    pub alignment_not_gravity: u64,
    /// Times a stream's initial rest, or its quiet stances' median, read a specific force beyond
    /// `core::SPECIFIC_FORCE_TOLERANCE` of gravity (an accelerometer scale or units wrong),
    /// over every stream of this life; each is in `warnings` (while they are below their cap).
    pub specific_force_off_gravity: u64,
}

/// A daemon failure.
#[derive(Debug, thiserror::Error)]
pub enum DaemonError {
    /// A service or port could not be set up or used (includes another daemon on the domain).
    #[error(transparent)]
    Service(#[from] ServiceError),
    /// The daemon's accounting file could not be opened.
    #[error(transparent)]
    State(#[from] StateFileError),
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
    // After the claim: one daemon at a time uses the domain's accounting file.
    let counters = Arc::new(StateFile::open(&cfg.domain.daemon_state_path())?);
    tracing::info!(
        path = %counters.path().display(),
        life = counters.lives.load(Ordering::Relaxed),
        "daemon accounting file"
    );

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
/// is set by someone else. The node is made here, so that a daemon whose signals nothing would
/// watch does not start (it was made on the thread, whose failure was only logged, and the
/// daemon ran on with no way to stop it by a signal).
pub fn shutdown_on_signal(
    domain: &Domain,
    shutdown: Arc<AtomicBool>,
) -> Result<JoinHandle<()>, DaemonError> {
    let node = domain.node(
        "corridor-signals",
        SignalHandlingMode::HandleTerminationRequests,
    )?;
    spawn("corridor-signals", move || {
        while !shutdown.load(Ordering::Relaxed) {
            if !corridor_shared::services::node_sleep(&node, Duration::from_millis(100)) {
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
