//! The receive thread (`corridor-rx`): input subscribers, `seq` and producer checks (one
//! producer at a time: [`super::producers`]), and the bounded channel to the estimator thread.

use super::producers::{Admit, Missing, OtherNumbering, ProducerLock, TakeOverReason};
use super::state::{load_opt, store_opt};
use super::{DaemonConfig, DaemonError};
use corridor_shared::services::{
    Access, Delivery, IMU_ACK_SERVICE, ServiceError, Topic, ack_event_id,
};
use corridor_shared::wire::{ANGLE_HEADING, ANGLE_PITCH, ANGLE_ROLL, AngleObservation, ImuSample};
use crossbeam_channel::TrySendError;
use iceoryx2::port::listener::ListenerWaitError;
use iceoryx2::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Producer changes per stream that are logged as warnings (the rest at debug level; all
/// counted in `producer_changes`).
const PRODUCER_CHANGE_WARNINGS_PER_STREAM: u64 = 3;

/// Producers refused per stream (another producer while the followed one is live) that are
/// logged as warnings, at their first refused sample (the rest at debug level; every sample
/// counted in `foreign`).
const FOREIGN_WARNINGS_PER_STREAM: u64 = 3;

/// Counters of the receive thread, read by the estimator thread: the daemon's accounting file
/// ([`super::state::Record`]), so they continue across daemon lives.
pub(super) type RxCounters = super::state::Record;

/// Receive → estimator messages.
#[derive(Debug, Clone, Copy)]
pub(super) enum Msg {
    Imu(ImuSample),
    Heading {
        heading_rad: f64,
        sd_rad: f64,
    },
    /// The next IMU sample comes from another producer than the previous one, mid-stream.
    NewProducer,
}

pub(super) fn rx_thread(
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
        let imu_service = d.open::<ImuSample>(&node, access)?;
        let imu = imu_service
            .subscriber_builder()
            .buffer_size(ImuSample::QOS.buffer_size)
            .create()
            .map_err(|e| ServiceError::port(d, ImuSample::SERVICE, "subscriber", e))?;
        let listener = d
            .open_event(&node, ImuSample::SERVICE, true)?
            .listener_builder()
            .create()
            .map_err(|e| ServiceError::port(d, ImuSample::SERVICE, "listener", e))?;
        let angles = d
            .open::<AngleObservation>(&node, access)?
            .subscriber_builder()
            .buffer_size(AngleObservation::QOS.buffer_size)
            .create()
            .map_err(|e| ServiceError::port(d, AngleObservation::SERVICE, "subscriber", e))?;
        // The producers notify this one too; creating it lets them open it before we wait.
        let _angles_event = d.open_event(&node, AngleObservation::SERVICE, true)?;
        let ack = d
            .open_event(&node, IMU_ACK_SERVICE, true)?
            .notifier_builder()
            .create()
            .map_err(|e| ServiceError::port(d, IMU_ACK_SERVICE, "notifier", e))?;
        Ok((imu_service, imu, listener, angles, _angles_event, ack, node))
    };
    let (imu_service, imu, listener, angles, _angles_event, ack, _node) = match setup() {
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
    // The position in the current producer's numbering, continued from the daemon's
    // accounting file (an earlier life of the daemon, see `super::state`).
    let mut last_seq: Option<u64> = load_opt(&counters.last_seq_plus1);
    // The producer followed (see `super::producers`), from an earlier life too.
    let mut lock = ProducerLock::new(counters.producer(), cfg.producer_takeover, Instant::now());
    // Whether a producer's publisher is still on the IMU service (asked only when another
    // producer's sample comes mid-stream, and at a take-over).
    let connected = |producer: u128| {
        let mut found = false;
        imu_service.dynamic_config().list_publishers(|p| {
            found = p.publisher_id.value() == producer;
            if found {
                CallbackProgression::Stop
            } else {
                CallbackProgression::Continue
            }
        });
        found
    };
    // The numbering of the producer not followed (refused, or followed before), from an
    // earlier life too.
    let mut other: Option<OtherNumbering> = counters.other();
    // Refused producers warned of in the current stream, and the last one.
    let mut foreign_warned = 0u64;
    let mut warned_of: Option<u128> = None;
    let count_missing = |m: Missing| {
        for (n, c) in [
            (m.head, &counters.head_missing),
            (m.gap, &counters.seq_gaps),
            (m.at_restart, &counters.missing_at_restart),
        ] {
            if n > 0 {
                c.fetch_add(n, Ordering::Relaxed);
            }
        }
    };
    // The seq the next stream of the current producer starts with (after its end marker).
    let mut next_stream_seq: Option<u64> = load_opt(&counters.next_stream_seq_plus1);
    // True between the first data sample of a stream and its end-of-stream marker.
    let mut mid_stream = counters.mid_stream.load(Ordering::Relaxed) != 0;
    // The time stamp of the followed producer's last data sample taken (this life), for
    // telling a replacement that continues its numbering and clock.
    let mut last_t_s: Option<f64> = None;
    // True until this life's first sample: a gap before it, in the numbering of the producer an
    // earlier life was receiving, is counted in `missing_at_restart`.
    let mut first_of_life = true;
    // Producer changes warned of in the current stream (the rest at debug level; all counted).
    let mut changes_warned = 0u64;
    // Tells a producer that its samples were taken (see `IMU_ACK_SERVICE`); a producer that
    // misses it waits its timeout and counts it.
    let acknowledge = |producer: u128| {
        if let Err(e) = ack.notify_with_custom_event_id(EventId::new(ack_event_id(producer))) {
            tracing::warn!("{}", ServiceError::io(d, IMU_ACK_SERVICE, "notify", e));
        }
    };
    while !stopping() {
        match listener.timed_wait(|_| {}, cfg.poll_timeout) {
            // A signal interrupted the wait (SIGCONT after a SIGSTOP, Ctrl-Z then `fg`): a
            // stop request is in `stopping()`, anything else just continues.
            Ok(_) | Err(ListenerWaitError::InterruptSignal) => {}
            Err(e) => return Err(ServiceError::io(d, ImuSample::SERVICE, "wait", e).into()),
        }
        while let Some(obs) = angles
            .receive()
            .map_err(|e| ServiceError::io(d, AngleObservation::SERVICE, "receive", e))?
        {
            let o: AngleObservation = *obs.payload();
            drop(obs);
            // Roll and pitch come from gravity at every stance; an external one is not fused
            // (counted, and said once).
            if o.valid & (ANGLE_ROLL | ANGLE_PITCH) != 0
                && counters.angles_ignored.fetch_add(1, Ordering::Relaxed) == 0
            {
                tracing::warn!(
                    seq = o.seq,
                    "angle observation with roll or pitch: not fused (the filter's tilt comes \
                     from gravity at every stance); its heading, if any, is used; counted in \
                     angles_ignored"
                );
            }
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
            .map_err(|e| ServiceError::io(d, ImuSample::SERVICE, "receive", e))?
        {
            let s: ImuSample = *smp.payload();
            let producer = smp.header().publisher_id().value();
            drop(smp); // return the shared-memory slot at once
            let last_producer = lock.followed();
            let admit = lock.admit(producer, mid_stream, Instant::now, connected);
            if admit == Admit::Foreign {
                counters.received.fetch_add(1, Ordering::Relaxed);
                counters.foreign.fetch_add(1, Ordering::Relaxed);
                let o = match other.as_mut() {
                    Some(o) if o.producer == producer => o,
                    _ => other.insert(OtherNumbering::new(producer)),
                };
                if !o.seen_this_life {
                    // Its samples were read: its close need not wait for the daemon.
                    acknowledge(producer);
                }
                count_missing(o.read(s.seq));
                counters.set_other(o);
                if warned_of != Some(producer) {
                    warned_of = Some(producer);
                    foreign_warned += 1;
                    if foreign_warned <= FOREIGN_WARNINGS_PER_STREAM {
                        tracing::warn!(
                            seq = s.seq,
                            "IMU samples from a second producer while the followed one sends: \
                             refused, counted in foreign_samples (one producer at a time; \
                             another takes over after daemon.producer_takeover_s of silence, \
                             an end of stream or a close)"
                        );
                    } else {
                        tracing::debug!(seq = s.seq, "IMU samples from a second producer refused");
                    }
                }
                continue;
            }
            if let Admit::TakeOver(reason) = admit {
                let known = other.is_some_and(|o| o.producer == producer);
                if mid_stream {
                    tracing::warn!(
                        seq = s.seq,
                        "IMU producer taken over mid-stream: the followed one {}",
                        reason.said()
                    );
                } else if known && reason == TakeOverReason::StreamEnded {
                    tracing::info!(
                        seq = s.seq,
                        "IMU producer whose samples were refused (or that was followed before) \
                         takes over: the followed one had ended its stream"
                    );
                }
            }
            // `received` is counted next to the store of the position (`last_seq_plus1`), so a
            // SIGKILL can misplace at most the one sample between the two stores.
            let new_producer = last_producer != Some(producer);
            if new_producer || first_of_life {
                // The daemon's side of this producer's connection is attached now: its queued
                // samples survive the producer (`Producer::close` waits for this).
                acknowledge(producer);
            }
            // Gaps in the numbering of the producer an earlier daemon life was receiving, up to
            // this life's first sample of it, are the restart's.
            let first_taken_of_life = std::mem::take(&mut first_of_life);
            let gaps = if first_taken_of_life && !new_producer {
                &counters.missing_at_restart
            } else {
                &counters.seq_gaps
            };
            // Where the numbering of the producer taken over from stood.
            let (last_seq_before, next_stream_seq_before) = (last_seq, next_stream_seq);
            if new_producer {
                next_stream_seq = None;
            }
            if last_producer.is_some_and(|p| p != producer) && mid_stream {
                // A restarted or replaced producer: its numbering starts afresh unless it
                // continues the old one (then the gap is real and counted below).
                counters.producer_changes.fetch_add(1, Ordering::Relaxed);
                // Two producers at once change at every sample: a warning each flooded the log
                // (a review: one per sample); the count is `producer_changes`.
                changes_warned += 1;
                if changes_warned <= PRODUCER_CHANGE_WARNINGS_PER_STREAM {
                    tracing::warn!(
                        seq = s.seq,
                        last_seq = ?last_seq,
                        "IMU producer changed mid-stream{}",
                        if changes_warned == PRODUCER_CHANGE_WARNINGS_PER_STREAM {
                            " (further changes in this stream are counted in producer_changes, \
                             not logged: two producers at once?)"
                        } else {
                            ""
                        }
                    );
                } else {
                    tracing::debug!(seq = s.seq, "IMU producer changed mid-stream");
                }
                // The new producer continues the old numbering only when the old one is gone
                // (not silent: still connected, it is a second producer) and both its `seq` and
                // its clock run on from the old one's: a restarted driver that keeps its
                // counter and its sensor's clock. Otherwise its numbering is its own, and its
                // head is counted as such (reviews: a producer at seq 100,000 after 2,000 had
                // its head counted as gaps in the old numbering, 2,000 short in the sum).
                // After an end of stream (not mid-stream) a new producer always starts its own.
                let continues = admit != Admit::TakeOver(TakeOverReason::Silent)
                    && last_seq.is_some_and(|l| s.seq > l)
                    && last_t_s.is_some_and(|t| s.t_s >= t);
                if !continues {
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
            if new_producer {
                counters.set_producer(producer);
                // The producer taken over from becomes the other one, with where its numbering
                // stands; one whose samples were read before (refused, or followed before) goes
                // on from its own numbering: its head was counted when it was first read.
                let taken_over = last_producer.map(|p| OtherNumbering {
                    producer: p,
                    next_seq: if mid_stream {
                        last_seq_before.map(|l| l.wrapping_add(1))
                    } else {
                        next_stream_seq_before
                    },
                    // Not when this life's first sample is the new one's: the producer taken over
                    // from is an earlier life's.
                    seen_this_life: !first_taken_of_life,
                });
                if let Some(o) = other.filter(|o| o.producer == producer) {
                    let (missing, from) = o.take_over(s.seq);
                    count_missing(missing);
                    last_seq = from;
                    next_stream_seq = None;
                    other = None;
                }
                // One slot (the service takes two publishers): a producer refused while still
                // connected keeps it over the one taken over from, which then is gone (a
                // review: a driver restarted after its end of stream next to a refused producer
                // overwrote the refused one's numbering, and its head was counted again).
                let keep = other.is_some_and(|o| connected(o.producer));
                if !keep {
                    other = taken_over;
                }
                if let Some(o) = &other {
                    counters.set_other(o);
                }
                // Where the new producer's numbering stands, at once (the sample may still be
                // refused as repeated or late below, before the store at the end).
                store_opt(&counters.last_seq_plus1, last_seq);
                store_opt(&counters.next_stream_seq_plus1, next_stream_seq);
            }
            if s.is_end_of_stream() {
                changes_warned = 0;
                foreign_warned = 0;
                warned_of = None;
                match (last_seq, next_stream_seq) {
                    (Some(l), _) if s.seq > l => {
                        gaps.fetch_add(s.seq - l - 1, Ordering::Relaxed);
                    }
                    (Some(_), _) => {}
                    // A marker at the head of a stream (all its data lost, or sent while no
                    // daemon ran): what was numbered before it is missing, as before a stream's
                    // first sample (a review: it was counted nowhere).
                    (None, Some(first)) => {
                        gaps.fetch_add(s.seq.saturating_sub(first), Ordering::Relaxed);
                    }
                    (None, None) => {
                        counters.head_missing.fetch_add(s.seq, Ordering::Relaxed);
                    }
                }
                next_stream_seq = Some(s.seq.wrapping_add(1));
                last_seq = None;
                mid_stream = false;
                store_opt(&counters.next_stream_seq_plus1, next_stream_seq);
                counters.mid_stream.store(0, Ordering::Relaxed);
                store_opt(&counters.last_seq_plus1, None);
                counters.received.fetch_add(1, Ordering::Relaxed);
                // The marker is never dropped, whatever the policy.
                if !forward(Delivery::Lossless, &tx, Msg::Imu(s), counters, &stopping) {
                    return Ok(());
                }
                continue;
            }
            if !mid_stream {
                mid_stream = true;
                counters.mid_stream.store(1, Ordering::Relaxed);
            }
            if last_seq.is_none() {
                // The head of a stream: what the producer numbered before this sample.
                match next_stream_seq.take() {
                    Some(first) => {
                        gaps.fetch_add(s.seq.saturating_sub(first), Ordering::Relaxed);
                    }
                    None => {
                        counters.head_missing.fetch_add(s.seq, Ordering::Relaxed);
                    }
                }
                store_opt(&counters.next_stream_seq_plus1, None);
            }
            if let Some(l) = last_seq {
                if s.seq == l {
                    counters.received.fetch_add(1, Ordering::Relaxed);
                    counters.duplicate.fetch_add(1, Ordering::Relaxed);
                    continue;
                }
                if s.seq < l {
                    counters.received.fetch_add(1, Ordering::Relaxed);
                    counters.late.fetch_add(1, Ordering::Relaxed);
                    continue;
                }
                gaps.fetch_add(s.seq - l - 1, Ordering::Relaxed);
            }
            last_seq = Some(s.seq);
            last_t_s = Some(s.t_s);
            store_opt(&counters.last_seq_plus1, last_seq);
            counters.received.fetch_add(1, Ordering::Relaxed);
            if !forward(cfg.delivery, &tx, Msg::Imu(s), counters, &stopping) {
                return Ok(());
            }
        }
        // The input is empty: from here the followed producer is silent until its next sample
        // (a review: this was marked after every forwarded sample instead, so a producer whose
        // last sample before it hung was a repeated one never went silent).
        lock.drained(Instant::now());
    }
    Ok(())
}

/// The receive thread's end of the channel, and the estimator thread to wake after a send.
///
/// The estimator thread parks (`std::thread::park_timeout`) when the channel is empty instead
/// of a blocking `recv`: crossbeam's blocking receive spins and calls `sched_yield` several
/// times per sample before it sleeps, which costs more CPU than the estimation at 1 kHz.
pub(super) struct ToEstimator {
    pub(super) tx: crossbeam_channel::Sender<Msg>,
    pub(super) wake: std::thread::Thread,
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
    let is_imu = matches!(msg, Msg::Imu(_));
    match delivery {
        Delivery::Live => match tx.try_send(msg) {
            Ok(()) => {
                if is_imu {
                    counters.forwarded.fetch_add(1, Ordering::Relaxed);
                }
                to.wake.unpark();
                true
            }
            Err(TrySendError::Full(_)) => {
                match msg {
                    Msg::Imu(_) => counters.dropped.fetch_add(1, Ordering::Relaxed),
                    _ => counters.angles_dropped.fetch_add(1, Ordering::Relaxed),
                };
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
                        if is_imu {
                            counters.forwarded.fetch_add(1, Ordering::Relaxed);
                        }
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
                                if is_imu {
                                    counters.dropped.fetch_add(1, Ordering::Relaxed);
                                }
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
