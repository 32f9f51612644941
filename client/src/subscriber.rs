//! [`Subscriber<T>`]: one output stream of the daemon.

use crate::ClientError;
use corridor_shared::services::{
    Access, Domain, PubSub, ServiceError, Topic, event_wait_slice, node_sleep,
};
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::prelude::*;
use std::cell::Cell;
use std::time::{Duration, Instant};

/// Receives the messages of type `T` (e.g. [`AttitudeSample`]) that the daemon publishes, with
/// a blocking [`Subscriber::recv_timeout`] (the daemon notifies the paired event service after
/// each send, so waiting costs no CPU).
///
/// It counts what it lost from the `seq` numbers ([`Subscriber::missed`]): with the `live`
/// policy a reader that falls behind by more than the buffer ([`Topic::QOS`]) loses the oldest
/// messages, and iceoryx2 does not tell the publisher, so only the reader can count them. The
/// daemon's numbering continues across its restarts (its accounting file), so what a reader
/// misses around a restart is a gap too. With [`Subscriber::received`] and
/// [`Subscriber::missed_at_start`] (what was published before this reader's first message),
/// the daemon's published count of the output (its next `seq`) is accounted for:
/// `published = missed_at_start + received + missed`, up to the last message received.
///
/// [`AttitudeSample`]: corridor_shared::wire::AttitudeSample
pub struct Subscriber<T: Topic> {
    domain: Domain,
    service: PubSub<T>,
    sub: iceoryx2::port::subscriber::Subscriber<ipc::Service, T, ()>,
    listener: Listener<ipc::Service>,
    last_seq: Cell<Option<u64>>,
    received: Cell<u64>,
    missed: Cell<u64>,
    missed_at_start: Cell<u64>,
    restarts: Cell<u64>,
    // Declared last: dropped after the ports.
    node: Node<ipc::Service>,
}

impl<T: Topic> std::fmt::Debug for Subscriber<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Subscriber")
            .field("service", &T::SERVICE)
            .field("domain", &self.domain.name())
            .finish_non_exhaustive()
    }
}

impl<T: Topic> Subscriber<T> {
    /// Opens the service of `T` in `domain` as a reader on a node called `node_name`, waiting up
    /// to `timeout` for it to exist and to have a publisher (the daemon); then attaches to it so
    /// nothing the daemon sends afterwards is missed. iceoryx2 handles SIGINT/SIGTERM for this
    /// node: waits end with [`ClientError::Interrupted`].
    pub fn open(domain: &Domain, node_name: &str, timeout: Duration) -> Result<Self, ClientError> {
        let node = domain.node(node_name, SignalHandlingMode::HandleTerminationRequests)?;
        let start = Instant::now();
        let no_peer = || ClientError::NoPeer {
            service: T::SERVICE,
            domain: domain.name().to_owned(),
            peer: "publisher",
            waited: timeout,
        };
        // The daemon creates the pub-sub service, then its event service: wait for both.
        let (service, event) = loop {
            let attempt = domain
                .open::<T>(&node, Access::Reader)
                .and_then(|s| Ok((s, domain.open_event(&node, T::SERVICE, false)?)));
            match attempt {
                Ok(x) => break x,
                Err(ServiceError::NotFound { .. }) if start.elapsed() < timeout => {
                    if !node_sleep(&node, Duration::from_millis(10)) {
                        return Err(ClientError::Interrupted);
                    }
                }
                Err(ServiceError::NotFound { .. }) => return Err(no_peer()),
                Err(e) => return Err(e.into()),
            }
        };
        let sub = service
            .subscriber_builder()
            .buffer_size(T::QOS.buffer_size)
            .history_request(T::QOS.history_size)
            .create()
            .map_err(|e| ServiceError::port(domain, T::SERVICE, "subscriber", e))?;
        let listener = event
            .listener_builder()
            .create()
            .map_err(|e| ServiceError::port(domain, T::SERVICE, "listener", e))?;
        while service.dynamic_config().number_of_publishers() == 0 {
            if start.elapsed() >= timeout {
                return Err(no_peer());
            }
            if !node_sleep(&node, Duration::from_millis(5)) {
                return Err(ClientError::Interrupted);
            }
        }
        // Attach the receive side of the publisher's connection now (iceoryx2 attaches it
        // lazily on receive/has_samples), without consuming a sample.
        sub.has_samples()
            .map_err(|e| ServiceError::io(domain, T::SERVICE, "connect", e))?;
        Ok(Self {
            domain: domain.clone(),
            service,
            sub,
            listener,
            last_seq: Cell::new(None),
            received: Cell::new(0),
            missed: Cell::new(0),
            missed_at_start: Cell::new(0),
            restarts: Cell::new(0),
            node,
        })
    }

    /// The next message if one is waiting.
    pub fn try_recv(&self) -> Result<Option<T>, ClientError> {
        match self.sub.receive() {
            Ok(Some(s)) => {
                let v = *s.payload();
                drop(s);
                self.track(v.seq());
                Ok(Some(v))
            }
            Ok(None) => Ok(None),
            Err(e) => Err(ServiceError::io(&self.domain, T::SERVICE, "receive", e).into()),
        }
    }

    /// The next message, waiting up to `timeout` for one; `Ok(None)` on timeout.
    pub fn recv_timeout(&self, timeout: Duration) -> Result<Option<T>, ClientError> {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(x) = self.try_recv()? {
                return Ok(Some(x));
            }
            // In slices: a wake-up the event loses costs one slice, not the whole timeout.
            let Some(slice) = event_wait_slice(Instant::now(), deadline) else {
                return Ok(None);
            };
            match self.listener.timed_wait(|_| {}, slice) {
                Ok(_) => {}
                Err(_) if self.termination_requested() => return Err(ClientError::Interrupted),
                // Another signal interrupted the wait (SIGCONT after Ctrl-Z): wait on.
                Err(ListenerWaitError::InterruptSignal) => {}
                Err(e) => return Err(ServiceError::io(&self.domain, T::SERVICE, "wait", e).into()),
            }
            if self.termination_requested() {
                return Err(ClientError::Interrupted);
            }
        }
    }

    fn track(&self, seq: u64) {
        self.received.set(self.received.get() + 1);
        match self.last_seq.get() {
            Some(l) if seq > l => self.missed.set(self.missed.get() + (seq - l - 1)),
            Some(_) => {
                // A new numbering (a daemon that lost its accounting file): its head is missed.
                self.restarts.set(self.restarts.get() + 1);
                self.missed.set(self.missed.get() + seq);
            }
            None => self.missed_at_start.set(seq),
        }
        self.last_seq.set(Some(seq));
    }

    /// Messages received so far.
    pub fn received(&self) -> u64 {
        self.received.get()
    }

    /// Messages lost so far according to their `seq`, after this reader's first message
    /// (overwritten in its buffer because it fell behind with the `live` policy, discarded for
    /// a stalled reader, or published by a daemon killed before they reached this reader).
    pub fn missed(&self) -> u64 {
        self.missed.get()
    }

    /// Messages the daemon published before this reader's first message (the `seq` of that
    /// message): a reader that started late, or missed the head of the stream.
    pub fn missed_at_start(&self) -> u64 {
        self.missed_at_start.get()
    }

    /// Times the `seq` numbering went back (a restarted daemon without its accounting file).
    pub fn publisher_restarts(&self) -> u64 {
        self.restarts.get()
    }

    /// Number of publishers currently connected (0 once the daemon has gone).
    pub fn publishers(&self) -> usize {
        self.service.dynamic_config().number_of_publishers()
    }

    /// True once SIGINT or SIGTERM was received by this process.
    pub fn termination_requested(&self) -> bool {
        corridor_shared::services::termination_requested(&self.node)
    }
}
