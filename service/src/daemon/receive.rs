//! The receive thread (`corridor-rx`): the input subscribers, the acknowledgements, and the
//! bounded channel to the estimator thread. What each IMU sample counts, and whether it is
//! taken (its `seq`, its producer: one at a time), is [`super::intake`]'s.

use super::intake::{Intake, Take};
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

/// Counters of the receive thread, read by the estimator thread: the daemon's accounting file
/// ([`super::state::Record`]), so they continue across daemon lives.
pub(super) type RxCounters = super::state::Record;

/// Receive → estimator messages.
#[derive(Debug, Clone, Copy)]
pub(super) enum Msg {
    Imu(ImuSample),
    Heading {
        t_s: f64,
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
    // Where the producers' numberings stand and which one is followed, continued from the
    // daemon's accounting file (an earlier life of the daemon, see `super::state`).
    let mut intake = Intake::resume(counters, cfg.producer_takeover, Instant::now());
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
                    t_s: o.t_s,
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
            let verdict = intake.take(&s, producer, Instant::now, connected);
            if verdict.ack {
                acknowledge(producer);
            }
            // Never dropped: the estimator must see it before the new producer's samples. (If
            // the daemon stops here, the sample counted received is the next life's
            // `lost_in_daemon`.)
            if verdict.new_producer
                && !forward(
                    Delivery::Lossless,
                    &tx,
                    Msg::NewProducer,
                    counters,
                    &stopping,
                )
            {
                return Ok(());
            }
            let delivery = match verdict.take {
                Take::Refused => continue,
                Take::Data => cfg.delivery,
                // The marker is never dropped, whatever the policy.
                Take::EndOfStream => Delivery::Lossless,
            };
            if !forward(delivery, &tx, Msg::Imu(s), counters, &stopping) {
                return Ok(());
            }
        }
        // The input is empty: from here the followed producer is silent until its next sample.
        intake.drained(Instant::now());
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
