//! [`Producer`]: feeds the daemon.

use crate::ClientError;
use corridor_shared::services::{
    ANGLES_SERVICE, Delivery, Domain, IMU_ACK_SERVICE, IMU_SERVICE, PubSub, ServiceError,
    ack_event_id, event_wait_slice,
};
use corridor_shared::wire::{AngleObservation, FLAG_END_OF_STREAM, ImuSample, monotonic_ns};
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use std::time::{Duration, Instant};

/// How long a lossless send keeps retrying a sample that reached no subscriber although one is
/// connected (its receive side not attached yet, see the iceoryx2 notes).
const LOSSLESS_RETRY: Duration = Duration::from_secs(2);

/// After the daemon's subscriber appears, the time the producer waits before its first send.
/// Without it, about one in six in-process test daemons never received a sample although every
/// send reported one receiver (iceoryx2 0.10; the subscriber's side of the new connection not yet
/// in place, cause not found; a delay in the first send made it disappear).
pub const SETTLE: Duration = Duration::from_millis(100);

/// How long [`Producer::close`] waits for the daemon to acknowledge this producer's samples.
pub const END_ACK_WAIT: Duration = Duration::from_secs(5);

/// What a [`Producer`] has sent so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ProducerStats {
    /// IMU messages sent (end-of-stream markers included).
    pub imu_sent: u64,
    /// IMU messages that reached no subscriber.
    pub imu_undelivered: u64,
    /// Angle observations sent.
    pub angles_sent: u64,
    /// Angle observations that reached no subscriber.
    pub angles_undelivered: u64,
    /// Sends repeated because a connected subscriber was not attached yet (lossless only).
    pub retries: u64,
    /// Closes at which the daemon had not confirmed within [`END_ACK_WAIT`] that it took this
    /// producer's samples although a subscriber received some: what was still queued may be
    /// lost.
    pub closes_unconfirmed: u64,
}

/// Publishes IMU samples and angle observations to the daemon of a domain and notifies it.
///
/// Sequence numbers are assigned by [`Producer::send_imu`] (0, 1, 2, …);
/// [`Producer::send_imu_raw`] sends a sample as given (for bridges and tests).
pub struct Producer {
    domain: Domain,
    delivery: Delivery,
    imu_service: PubSub<ImuSample>,
    imu: Publisher<ipc::Service, ImuSample, ()>,
    imu_notifier: Notifier<ipc::Service>,
    angles: Publisher<ipc::Service, AngleObservation, ()>,
    angles_notifier: Notifier<ipc::Service>,
    /// The daemon's acknowledgements (see [`IMU_ACK_SERVICE`]).
    ack: Listener<ipc::Service>,
    /// This producer's event id on [`IMU_ACK_SERVICE`].
    ack_id: usize,
    /// The daemon acknowledged this producer (or it was closed already).
    taken: bool,
    next_imu_seq: u64,
    next_angles_seq: u64,
    stats: ProducerStats,
    // Declared last: dropped after the ports.
    node: Node<ipc::Service>,
}

impl std::fmt::Debug for Producer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Producer")
            .field("domain", &self.domain.name())
            .field("delivery", &self.delivery)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl Producer {
    /// [`Producer::open`] asserting `delivery`: fails when the daemon uses the other policy.
    pub fn new(domain: &Domain, node_name: &str, delivery: Delivery) -> Result<Self, ClientError> {
        Self::open(domain, node_name, Some(delivery))
    }

    /// Opens (or creates) the input services of `domain` and creates the publishers on a node
    /// called `node_name`. The delivery policy is the daemon's (the one the services exist
    /// with); `delivery`, when given, is an assertion: another policy is an error
    /// ([`ServiceError::DeliveryAssertion`]). Services that do not exist yet are created with
    /// `delivery` or [`Delivery::Live`]. iceoryx2 handles SIGINT/SIGTERM for this node: see
    /// [`Producer::termination_requested`].
    pub fn open(
        domain: &Domain,
        node_name: &str,
        delivery: Option<Delivery>,
    ) -> Result<Self, ClientError> {
        let node = domain.node(node_name, SignalHandlingMode::HandleTerminationRequests)?;
        let (imu_service, delivery) = domain.open_input::<ImuSample>(&node, delivery)?;
        let imu = imu_service
            .publisher_builder()
            .backpressure_strategy(delivery.backpressure())
            .max_loaned_samples(2)
            .create()
            .map_err(|e| ServiceError::port(domain, IMU_SERVICE, "publisher", e))?;
        let imu_notifier = domain
            .open_event(&node, IMU_SERVICE, true)?
            .notifier_builder()
            .create()
            .map_err(|e| ServiceError::port(domain, IMU_SERVICE, "notifier", e))?;
        let (angles_service, _) = domain.open_input::<AngleObservation>(&node, Some(delivery))?;
        let angles = angles_service
            .publisher_builder()
            .backpressure_strategy(delivery.backpressure())
            .max_loaned_samples(2)
            .create()
            .map_err(|e| ServiceError::port(domain, ANGLES_SERVICE, "publisher", e))?;
        let angles_notifier = domain
            .open_event(&node, ANGLES_SERVICE, true)?
            .notifier_builder()
            .create()
            .map_err(|e| ServiceError::port(domain, ANGLES_SERVICE, "notifier", e))?;
        let ack_id = ack_event_id(imu.id().value());
        let ack = domain
            .open_event(&node, IMU_ACK_SERVICE, true)?
            .listener_builder()
            .create()
            .map_err(|e| ServiceError::port(domain, IMU_ACK_SERVICE, "listener", e))?;
        Ok(Self {
            domain: domain.clone(),
            delivery,
            imu_service,
            imu,
            imu_notifier,
            angles,
            angles_notifier,
            ack,
            ack_id,
            taken: false,
            next_imu_seq: 0,
            next_angles_seq: 0,
            stats: ProducerStats::default(),
            node,
        })
    }

    /// Waits until at least one subscriber (the daemon) reads the IMU service, up to `timeout`,
    /// then [`SETTLE`] more.
    pub fn wait_for_daemon(&self, timeout: Duration) -> Result<(), ClientError> {
        let start = Instant::now();
        while self.imu_service.dynamic_config().number_of_subscribers() == 0 {
            if self.termination_requested() {
                return Err(ClientError::Interrupted);
            }
            if start.elapsed() >= timeout {
                return Err(ClientError::NoPeer {
                    service: IMU_SERVICE,
                    domain: self.domain.name().to_owned(),
                    peer: "subscriber",
                    waited: timeout,
                });
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        self.imu
            .update_connections()
            .map_err(|e| ServiceError::io(&self.domain, IMU_SERVICE, "update connections", e))?;
        std::thread::sleep(SETTLE);
        self.imu
            .update_connections()
            .map_err(|e| ServiceError::io(&self.domain, IMU_SERVICE, "update connections", e))?;
        // The daemon opens its angle subscriber next to the IMU one: connected now too.
        self.angles
            .update_connections()
            .map_err(|e| ServiceError::io(&self.domain, ANGLES_SERVICE, "update connections", e))?;
        Ok(())
    }

    /// Sends one IMU sample with the next sequence number (its `seq` is overwritten); returns the
    /// number of subscribers that received it.
    pub fn send_imu(&mut self, mut sample: ImuSample) -> Result<usize, ClientError> {
        sample.seq = self.next_imu_seq;
        self.send_imu_raw(sample)
    }

    /// Sends one IMU sample as given, `seq` included; the automatic sequence continues after it.
    /// A `sent_ns` of 0 is stamped with [`monotonic_ns`] now (the daemon's latency figures).
    pub fn send_imu_raw(&mut self, mut sample: ImuSample) -> Result<usize, ClientError> {
        self.next_imu_seq = sample.seq.wrapping_add(1);
        if sample.sent_ns == 0 {
            sample.sent_ns = monotonic_ns();
        }
        let n = send(
            &self.imu,
            &self.imu_service,
            self.delivery,
            sample,
            &mut self.stats.retries,
        )
        .map_err(|e| ServiceError::io(&self.domain, IMU_SERVICE, "send", e))?;
        self.stats.imu_sent += 1;
        if n == 0 {
            self.stats.imu_undelivered += 1;
        }
        self.imu_notifier
            .notify()
            .map_err(|e| ServiceError::io(&self.domain, IMU_SERVICE, "notify", e))?;
        Ok(n)
    }

    /// Sends the end-of-stream marker (a data-less [`ImuSample`] with [`FLAG_END_OF_STREAM`]):
    /// the daemon answers with end-of-stream outputs and resets its estimator.
    pub fn finish(&mut self) -> Result<usize, ClientError> {
        self.send_imu(ImuSample {
            t_s: f64::NAN,
            temp_c: f64::NAN,
            flags: FLAG_END_OF_STREAM,
            ..ImuSample::default()
        })
    }

    /// Lets the producer go once the daemon has taken its samples, and returns the final stats.
    /// iceoryx2 0.10 attaches the daemon's side of a connection only when the daemon next
    /// receives, and a publisher dropped before that takes the samples still queued with it; so
    /// when a sample reached a subscriber and the daemon has not yet acknowledged this producer
    /// on [`IMU_ACK_SERVICE`] (it does at the first sample it takes from it), this waits up to
    /// [`END_ACK_WAIT`] for that (none in time: [`ProducerStats::closes_unconfirmed`]).
    /// Usually the acknowledgement came long before and this returns at once. Dropping the
    /// producer waits the same way, and logs a missing acknowledgement.
    pub fn close(mut self) -> Result<ProducerStats, ClientError> {
        self.settle()?;
        Ok(self.stats)
    }

    /// The wait of [`Producer::close`].
    fn settle(&mut self) -> Result<(), ClientError> {
        if self.stats.imu_sent > self.stats.imu_undelivered
            && !self.taken
            && !self.wait_for_ack(END_ACK_WAIT)?
        {
            self.stats.closes_unconfirmed += 1;
        }
        // Once per producer: a second close (the drop after `close`) does not wait again.
        self.taken = true;
        Ok(())
    }

    /// Waits up to `timeout` for this producer's acknowledgement (at once when it is pending).
    fn wait_for_ack(&mut self, timeout: Duration) -> Result<bool, ClientError> {
        let mine = EventId::new(self.ack_id);
        let deadline = Instant::now() + timeout;
        loop {
            // In slices (see `EVENT_WAIT_SLICE`): a timed-out slice still drains the event ids
            // that were set, so an acknowledgement whose wake-up was lost is seen at its end.
            let Some(slice) = event_wait_slice(Instant::now(), deadline) else {
                return Ok(false);
            };
            let mut seen = false;
            match self.ack.timed_wait(|a| seen |= a.id == mine, slice) {
                Ok(_) if seen => {
                    self.taken = true;
                    return Ok(true);
                }
                Ok(_) => {}
                Err(_) if self.termination_requested() => return Err(ClientError::Interrupted),
                // Another signal interrupted the wait (SIGCONT after Ctrl-Z): wait on.
                Err(ListenerWaitError::InterruptSignal) => {}
                Err(e) => {
                    return Err(ServiceError::io(&self.domain, IMU_ACK_SERVICE, "wait", e).into());
                }
            }
        }
    }

    /// Sends one angle observation with the next sequence number. Its `t_s` is on the IMU
    /// samples' clock: the daemon uses its heading at the stance that time falls in or the next
    /// one, within 2 s; one 2 s behind the latest sample when it arrives (`t_s` left at 0) is
    /// refused and counted ([`AngleObservation`]).
    pub fn send_angles(&mut self, mut obs: AngleObservation) -> Result<usize, ClientError> {
        obs.seq = self.next_angles_seq;
        self.next_angles_seq += 1;
        let n = self
            .angles
            .send_copy(obs)
            .map_err(|e| ServiceError::io(&self.domain, ANGLES_SERVICE, "send", e))?;
        self.stats.angles_sent += 1;
        if n == 0 {
            self.stats.angles_undelivered += 1;
        }
        self.angles_notifier
            .notify()
            .map_err(|e| ServiceError::io(&self.domain, ANGLES_SERVICE, "notify", e))?;
        Ok(n)
    }

    /// What was sent so far.
    pub fn stats(&self) -> ProducerStats {
        self.stats
    }

    /// The delivery policy.
    pub fn delivery(&self) -> Delivery {
        self.delivery
    }

    /// True once SIGINT or SIGTERM was received by this process.
    pub fn termination_requested(&self) -> bool {
        corridor_shared::services::termination_requested(&self.node)
    }
}

impl Drop for Producer {
    fn drop(&mut self) {
        let before = self.stats.closes_unconfirmed;
        match self.settle() {
            Ok(()) if self.stats.closes_unconfirmed > before => tracing::warn!(
                domain = self.domain.name(),
                "the daemon did not confirm within {END_ACK_WAIT:?} that it took this \
                 producer's samples: samples still queued may be lost"
            ),
            Ok(()) => {}
            Err(e) => tracing::warn!(domain = self.domain.name(), "closing the producer: {e}"),
        }
    }
}

/// Sends `sample`; in lossless mode retries while a connected subscriber was not reached.
fn send(
    publisher: &Publisher<ipc::Service, ImuSample, ()>,
    service: &PubSub<ImuSample>,
    delivery: Delivery,
    sample: ImuSample,
    retries: &mut u64,
) -> Result<usize, iceoryx2::port::SendError> {
    let mut n = publisher.send_copy(sample)?;
    if n > 0 || delivery == Delivery::Live {
        return Ok(n);
    }
    let start = Instant::now();
    while n == 0
        && service.dynamic_config().number_of_subscribers() > 0
        && start.elapsed() < LOSSLESS_RETRY
    {
        std::thread::sleep(Duration::from_micros(200));
        *retries += 1;
        n = publisher.send_copy(sample)?;
    }
    Ok(n)
}
