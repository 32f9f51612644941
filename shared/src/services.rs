//! The iceoryx2 services of corridor: names, quality of service, and the one place both sides
//! open them.
//!
//! Every service is opened through a function of this module by the daemon and by the clients
//! alike, so the QoS (buffer sizes, history, port counts, overflow behaviour) is identical on both
//! sides: iceoryx2 refuses an opener whose requirements exceed the creator's, so a mismatch would
//! otherwise depend on which process started first.
//!
//! | service | payload | publisher | paired event |
//! | --- | --- | --- | --- |
//! | [`IMU_SERVICE`] | [`ImuSample`] | producers | yes (daemon waits on it) |
//! | [`ANGLES_SERVICE`] | [`AngleObservation`] | producers | yes |
//! | [`ATTITUDE_SERVICE`] | [`AttitudeSample`] | daemon | yes |
//! | [`BIAS_SERVICE`] | [`BiasSample`] | daemon | yes |
//! | [`NAV_SERVICE`] | [`NavSample`] | daemon | yes |
//! | [`DIAGNOSTICS_SERVICE`] | [`Diagnostics`] | daemon | yes |
//! | [`DAEMON_SERVICE`] | (event only) | daemon, created exclusively | lock only |
//!
//! A blocking wait on a publish-subscribe port is not possible in iceoryx2; each pub-sub service
//! has an event service of the same name: the publisher notifies after sending, the reader waits
//! on a listener.
//!
//! [`Domain`] gives every independent set of processes (a sensor, a test) its own iceoryx2
//! namespace (`global.prefix`), so they never see each other's services.

use crate::wire::{
    AngleObservation, AttitudeSample, BiasSample, Diagnostics, ImuSample, NavSample,
};
use iceoryx2::prelude::*;
use iceoryx2::service::builder::event::{EventCreateError, EventOpenError, EventOpenOrCreateError};
use iceoryx2::service::builder::publish_subscribe::{
    PublishSubscribeOpenError, PublishSubscribeOpenOrCreateError,
};
use std::fmt::Debug;
use std::str::FromStr;

/// Version of the wire layout; part of every service name. Bump it with any change to
/// [`crate::wire`].
pub const SERVICE_VERSION: &str = "v2";
/// IMU samples, producers → daemon.
pub const IMU_SERVICE: &str = "corridor/v2/imu";
/// External angle observations, producers → daemon.
pub const ANGLES_SERVICE: &str = "corridor/v2/angles";
/// Attitude after every IMU sample, daemon → clients.
pub const ATTITUDE_SERVICE: &str = "corridor/v2/attitude";
/// Gyro-bias estimates, daemon → clients.
pub const BIAS_SERVICE: &str = "corridor/v2/bias";
/// Position and velocity at each stance, daemon → clients.
pub const NAV_SERVICE: &str = "corridor/v2/nav";
/// Daemon counters, daemon → clients.
pub const DIAGNOSTICS_SERVICE: &str = "corridor/v2/diagnostics";
/// Event service created exclusively by the running daemon: a second daemon on the same domain
/// fails to create it. Clients must not open it (an open handle would keep it alive after the
/// daemon exits).
pub const DAEMON_SERVICE: &str = "corridor/v2/daemon";

/// The default domain name.
pub const DEFAULT_DOMAIN: &str = "default";

/// Longest domain name, characters.
pub const MAX_DOMAIN_LEN: usize = 48;

/// A service that could not be opened or used. Every variant names the service and the domain.
#[derive(Debug, thiserror::Error)]
pub enum ServiceError {
    /// The domain name is not usable.
    #[error("domain {name:?}: {rule}")]
    InvalidDomain {
        /// The name given.
        name: String,
        /// What a domain name must satisfy.
        rule: &'static str,
    },
    /// The iceoryx2 node could not be created.
    #[error("domain {domain:?}: cannot create iceoryx2 node {node:?}: {detail}")]
    Node {
        /// Domain.
        domain: String,
        /// Node name.
        node: String,
        /// The iceoryx2 error.
        detail: String,
    },
    /// The service exists with the other delivery policy.
    #[error(
        "service {service:?} in domain {domain:?} exists with the other delivery policy; \
         this process asked for {requested:?} (use the same --delivery on every process)"
    )]
    DeliveryMismatch {
        /// Service name.
        service: &'static str,
        /// Domain.
        domain: String,
        /// Policy asked for.
        requested: Delivery,
    },
    /// The service exists with another delivery policy than the one this process asserted.
    #[error(
        "service {service:?} in domain {domain:?} uses {} delivery, but {} was asked for \
         (leave --delivery out to take the daemon's policy)", actual.name(), requested.name()
    )]
    DeliveryAssertion {
        /// Service name.
        service: &'static str,
        /// Domain.
        domain: String,
        /// Policy asked for.
        requested: Delivery,
        /// Policy of the existing service.
        actual: Delivery,
    },
    /// The service does not exist (yet): the daemon is not running on this domain.
    #[error(
        "service {service:?} does not exist in domain {domain:?} (is `corridor serve --domain {domain}` running?)"
    )]
    NotFound {
        /// Service name.
        service: &'static str,
        /// Domain.
        domain: String,
    },
    /// The runtime directory of a secured domain is unusable, or this user may not use it.
    #[error("domain {domain:?}: {detail}")]
    RuntimeDir {
        /// Domain.
        domain: String,
        /// The path and what is wrong.
        detail: String,
    },
    /// Another daemon already serves this domain.
    #[error(
        "another corridor daemon already serves domain {domain:?} (service {DAEMON_SERVICE:?} exists)"
    )]
    DaemonAlreadyRunning {
        /// Domain.
        domain: String,
    },
    /// Opening or creating the service failed.
    #[error("service {service:?} ({pattern}) in domain {domain:?}: cannot open: {detail}")]
    Open {
        /// Service name.
        service: &'static str,
        /// `publish-subscribe` or `event`.
        pattern: &'static str,
        /// Domain.
        domain: String,
        /// The iceoryx2 error.
        detail: String,
    },
    /// Creating a port (publisher, subscriber, notifier, listener) failed.
    #[error("service {service:?} in domain {domain:?}: cannot create {port}: {detail}")]
    Port {
        /// Service name.
        service: &'static str,
        /// Port kind.
        port: &'static str,
        /// Domain.
        domain: String,
        /// The iceoryx2 error.
        detail: String,
    },
    /// Sending, receiving, notifying or waiting failed.
    #[error("service {service:?} in domain {domain:?}: {operation} failed: {detail}")]
    Io {
        /// Service name.
        service: &'static str,
        /// What was attempted.
        operation: &'static str,
        /// Domain.
        domain: String,
        /// The iceoryx2 error.
        detail: String,
    },
}

impl ServiceError {
    /// A failed send, receive, notify or wait ([`ServiceError::Io`]) on `service` in `domain`.
    pub fn io(
        domain: &Domain,
        service: &'static str,
        operation: &'static str,
        detail: impl Debug,
    ) -> Self {
        ServiceError::Io {
            service,
            operation,
            domain: domain.name().to_owned(),
            detail: format!("{detail:?}"),
        }
    }

    /// A port of `service` in `domain` that could not be created ([`ServiceError::Port`]).
    pub fn port(
        domain: &Domain,
        service: &'static str,
        port: &'static str,
        detail: impl Debug,
    ) -> Self {
        ServiceError::Port {
            service,
            port,
            domain: domain.name().to_owned(),
            detail: format!("{detail:?}"),
        }
    }
}

/// What happens when a reader falls behind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Delivery {
    /// A full receive buffer drops its oldest sample (iceoryx2 safe overflow); the publisher never
    /// waits. For live sensors: the freshest data wins, losses show up as `seq` gaps.
    #[default]
    Live,
    /// A full receive buffer makes the publisher wait until the reader has taken a sample
    /// (`RetryUntilDelivered`). For replays and recordings: nothing is lost, a slow reader slows
    /// the producer down.
    Lossless,
}

impl Delivery {
    /// `live` or `lossless`.
    pub fn name(self) -> &'static str {
        match self {
            Delivery::Live => "live",
            Delivery::Lossless => "lossless",
        }
    }

    /// The iceoryx2 `enable_safe_overflow` setting of the services.
    pub fn safe_overflow(self) -> bool {
        self == Delivery::Live
    }

    /// The backpressure strategy of the publishers.
    pub fn backpressure(self) -> BackpressureStrategy {
        match self {
            Delivery::Live => BackpressureStrategy::DiscardData,
            Delivery::Lossless => BackpressureStrategy::RetryUntilDelivered,
        }
    }
}

impl FromStr for Delivery {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "live" => Ok(Delivery::Live),
            "lossless" => Ok(Delivery::Lossless),
            _ => Err(format!("delivery {s:?}: expected live or lossless")),
        }
    }
}

/// Quality of service of one publish-subscribe service.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Qos {
    /// Maximum publishers.
    pub max_publishers: usize,
    /// Maximum subscribers.
    pub max_subscribers: usize,
    /// Receive buffer of each subscriber, samples.
    pub buffer_size: usize,
    /// Samples a late subscriber receives on connecting.
    pub history_size: usize,
    /// Samples a subscriber may hold at once.
    pub max_borrowed: usize,
}

/// A wire type bound to its service.
pub trait Topic: Debug + Copy + ZeroCopySend + 'static {
    /// Service name.
    const SERVICE: &'static str;
    /// Quality of service.
    const QOS: Qos;
    /// The message's sequence number (every wire type has one; gaps mean lost messages).
    fn seq(&self) -> u64;
}

impl Topic for ImuSample {
    const SERVICE: &'static str = IMU_SERVICE;
    /// 4096 samples: about 4 s of a 1 kHz IMU.
    const QOS: Qos = Qos {
        max_publishers: 2,
        max_subscribers: 4,
        buffer_size: 4096,
        history_size: 0,
        max_borrowed: 2,
    };
    fn seq(&self) -> u64 {
        self.seq
    }
}

impl Topic for AngleObservation {
    const SERVICE: &'static str = ANGLES_SERVICE;
    const QOS: Qos = Qos {
        max_publishers: 4,
        max_subscribers: 4,
        buffer_size: 64,
        history_size: 0,
        max_borrowed: 2,
    };
    fn seq(&self) -> u64 {
        self.seq
    }
}

impl Topic for AttitudeSample {
    const SERVICE: &'static str = ATTITUDE_SERVICE;
    const QOS: Qos = Qos {
        max_publishers: 1,
        max_subscribers: 8,
        buffer_size: 4096,
        history_size: 0,
        max_borrowed: 2,
    };
    fn seq(&self) -> u64 {
        self.seq
    }
}

impl Topic for BiasSample {
    const SERVICE: &'static str = BIAS_SERVICE;
    /// History 1: a late subscriber gets the latest bias at once.
    const QOS: Qos = Qos {
        max_publishers: 1,
        max_subscribers: 8,
        buffer_size: 256,
        history_size: 1,
        max_borrowed: 2,
    };
    fn seq(&self) -> u64 {
        self.seq
    }
}

impl Topic for NavSample {
    const SERVICE: &'static str = NAV_SERVICE;
    const QOS: Qos = Qos {
        max_publishers: 1,
        max_subscribers: 8,
        buffer_size: 256,
        history_size: 1,
        max_borrowed: 2,
    };
    fn seq(&self) -> u64 {
        self.seq
    }
}

impl Topic for Diagnostics {
    const SERVICE: &'static str = DIAGNOSTICS_SERVICE;
    const QOS: Qos = Qos {
        max_publishers: 1,
        max_subscribers: 8,
        buffer_size: 64,
        history_size: 1,
        max_borrowed: 2,
    };
    fn seq(&self) -> u64 {
        self.seq
    }
}

/// Longest wait, at daemon start, for the cleanup of a killed daemon's claim.
const CLAIM_CLEANUP_WAIT: std::time::Duration = std::time::Duration::from_secs(5);

/// Maximum notifiers on a paired event service.
pub const EVENT_MAX_NOTIFIERS: usize = 4;
/// Maximum listeners on a paired event service.
pub const EVENT_MAX_LISTENERS: usize = 8;

/// How a process opens a service.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// Opens or creates the service with the given delivery policy, and refuses a service that
    /// exists with the other one. For the daemon (all services) and the producers (inputs).
    Owner(Delivery),
    /// Opens an existing service whatever its delivery policy; fails with
    /// [`ServiceError::NotFound`] when it does not exist. For readers of the daemon's outputs.
    Reader,
}

/// A publish-subscribe service handle.
pub type PubSub<T> =
    iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>;
/// An event service handle.
pub type Event = iceoryx2::service::port_factory::event::PortFactory<ipc::Service>;

/// Environment variable naming the runtime directory of secured domains: when it is set,
/// [`Domain::new`] joins the domain the daemon serves there (see [`crate::runtime_dir`]).
pub const RUNTIME_DIR_ENV: &str = "CORRIDOR_RUNTIME_DIR";

/// An isolated iceoryx2 namespace: processes on different domains never see each other.
///
/// An open domain (`global.prefix = corridor_<name>_`, root `/tmp/iceoryx2`) is what tests and
/// development use. A secured domain lives in a runtime directory only the daemon's user can
/// enter, under a prefix other users cannot read ([`crate::runtime_dir`]): the daemon takes it
/// with [`Domain::serve`] and `daemon.runtime_dir`, clients join it with [`Domain::join`] (or
/// [`Domain::new`] with [`RUNTIME_DIR_ENV`] set).
#[derive(Debug, Clone)]
pub struct Domain {
    name: String,
    config: Config,
    /// The daemon's hold on a secured domain (its lock), shared by the clones.
    hold: Option<std::sync::Arc<crate::runtime_dir::DaemonHold>>,
    /// The prefix of a secured domain, whose `global_mgmt` each new node restricts.
    secured_prefix: Option<String>,
}

impl Domain {
    /// Checks a domain name: 1–48 characters out of `a-z A-Z 0-9 _ -`.
    pub fn check_name(name: &str) -> Result<(), ServiceError> {
        let invalid = |rule| ServiceError::InvalidDomain {
            name: name.to_owned(),
            rule,
        };
        if name.is_empty() || name.len() > MAX_DOMAIN_LEN {
            return Err(invalid("must have 1 to 48 characters"));
        }
        if !name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
        {
            return Err(invalid("may only contain a-z, A-Z, 0-9, '_' and '-'"));
        }
        Ok(())
    }

    /// The domain `name` for a client: the secured domain of the runtime directory in
    /// [`RUNTIME_DIR_ENV`] when it is set, else the open one ([`Domain::unsecured`]).
    pub fn new(name: &str) -> Result<Self, ServiceError> {
        match std::env::var_os(RUNTIME_DIR_ENV) {
            Some(dir) if !dir.is_empty() => Self::join(name, std::path::Path::new(&dir)),
            _ => Self::unsecured(name),
        }
    }

    /// The open domain `name`: the iceoryx2 config whose `global.prefix` is `corridor_<name>_`.
    pub fn unsecured(name: &str) -> Result<Self, ServiceError> {
        Self::with_prefix(name, &format!("corridor_{name}_"), None)
    }

    fn with_prefix(
        name: &str,
        prefix: &str,
        root: Option<&std::path::Path>,
    ) -> Result<Self, ServiceError> {
        Self::check_name(name)?;
        let invalid = |rule| ServiceError::InvalidDomain {
            name: name.to_owned(),
            rule,
        };
        let mut config = Config::default();
        config.global.prefix = FileName::new(prefix.as_bytes())
            .map_err(|_| invalid("is not usable in a file name"))?;
        if let Some(root) = root {
            let path = iceoryx2::prelude::Path::new(root.as_os_str().as_encoded_bytes())
                .map_err(|_| invalid("gives a runtime path iceoryx2 cannot use"))?;
            config.global.set_root_path(&path);
        }
        Ok(Self {
            name: name.to_owned(),
            config,
            hold: None,
            secured_prefix: root.map(|_| prefix.to_owned()),
        })
    }

    /// Joins the secured domain `name` that a daemon serves under `runtime_dir` (as the daemon's
    /// user: nobody else can read its prefix).
    pub fn join(name: &str, runtime_dir: &std::path::Path) -> Result<Self, ServiceError> {
        use crate::runtime_dir as rd;
        Self::check_name(name)?;
        let token = rd::read_token(runtime_dir, name).map_err(|e| ServiceError::RuntimeDir {
            domain: name.to_owned(),
            detail: e.to_string(),
        })?;
        Self::with_prefix(
            name,
            &rd::prefix(&token),
            Some(&rd::iox2_root(runtime_dir, &token)),
        )
    }

    /// The domain `name` for its daemon: secured under `runtime_dir` when given (the directory
    /// checked or created, the daemon lock taken, a new prefix when the old one was planted or
    /// corrupted, the dead nodes of earlier runs cleaned up), else open.
    pub fn serve(name: &str, runtime_dir: Option<&std::path::Path>) -> Result<Self, ServiceError> {
        use crate::runtime_dir as rd;
        let Some(runtime_dir) = runtime_dir else {
            return Self::unsecured(name);
        };
        Self::check_name(name)?;
        let dir_err = |detail: String| ServiceError::RuntimeDir {
            domain: name.to_owned(),
            detail,
        };
        let mut hold = rd::hold(runtime_dir, name).map_err(|e| match e {
            rd::HoldError::Locked { .. } => ServiceError::DaemonAlreadyRunning {
                domain: name.to_owned(),
            },
            rd::HoldError::Dir(e) => dir_err(e.to_string()),
        })?;
        let make = |hold: &rd::DaemonHold| {
            Self::with_prefix(name, &rd::prefix(&hold.token), Some(&hold.iox2_root()))
        };
        // A first node cleans up dead nodes and shows whether the segments are usable.
        let probe = |d: &Self| {
            d.node("corridor-start", SignalHandlingMode::Disabled)
                .map(drop)
        };
        let mut domain = make(&hold)?;
        if let Err(e) = probe(&domain) {
            tracing::warn!("domain {name:?}: {e}; new prefix");
            let old = hold.token.clone();
            hold.rotate(name, Some(&old))
                .map_err(|e| dir_err(e.to_string()))?;
            domain = make(&hold)?;
            probe(&domain)?;
        }
        domain.hold = Some(std::sync::Arc::new(hold));
        Ok(domain)
    }

    /// The daemon's accounting file of this domain (its input counters, the position in the
    /// current producer's numbering and the output sequence numbers, kept across daemon
    /// restarts): `DIR/<domain>/daemon.state` for a secured domain served by this process,
    /// else `/dev/shm/<prefix>daemon.state` (removed at reboot, like the domain's segments).
    pub fn daemon_state_path(&self) -> std::path::PathBuf {
        match &self.hold {
            Some(h) => h.dir.join("daemon.state"),
            None => {
                let prefix = match &self.secured_prefix {
                    Some(p) => p.clone(),
                    None => format!("corridor_{}_", self.name),
                };
                std::path::Path::new("/dev/shm").join(format!("{prefix}daemon.state"))
            }
        }
    }

    /// Whether this domain is secured (lives in a runtime directory).
    pub fn is_secured(&self) -> bool {
        self.secured_prefix.is_some()
    }

    /// The domain name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The iceoryx2 configuration of the domain.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// A node in this domain. `signals`: `Disabled` when the caller handles SIGINT/SIGTERM itself
    /// (the daemon), `HandleTerminationRequests` for tools that rely on iceoryx2's handler.
    pub fn node(
        &self,
        node_name: &str,
        signals: SignalHandlingMode,
    ) -> Result<Node<ipc::Service>, ServiceError> {
        let err = |detail: String| ServiceError::Node {
            domain: self.name.clone(),
            node: node_name.to_owned(),
            detail,
        };
        let name: NodeName = node_name.try_into().map_err(|e| err(format!("{e:?}")))?;
        let node = NodeBuilder::new()
            .name(&name)
            .config(&self.config)
            .signal_handling_mode(signals)
            .create::<ipc::Service>()
            .map_err(|e| err(format!("{e:?}")))?;
        if let Some(prefix) = &self.secured_prefix {
            crate::runtime_dir::restrict_global_mgmt(prefix).map_err(|e| err(e.to_string()))?;
        }
        Ok(node)
    }

    /// Opens the publish-subscribe service of `T` with its [`Topic::QOS`].
    pub fn open<T: Topic>(
        &self,
        node: &Node<ipc::Service>,
        access: Access,
    ) -> Result<PubSub<T>, ServiceError> {
        let service = T::SERVICE;
        let q = T::QOS;
        let open_err = |detail: String| ServiceError::Open {
            service,
            pattern: "publish-subscribe",
            domain: self.name.clone(),
            detail,
        };
        let name: ServiceName = service.try_into().map_err(|e| open_err(format!("{e:?}")))?;
        let builder = node
            .service_builder(&name)
            .publish_subscribe::<T>()
            .max_publishers(q.max_publishers)
            .max_subscribers(q.max_subscribers)
            .subscriber_max_buffer_size(q.buffer_size)
            .history_size(q.history_size)
            .subscriber_max_borrowed_samples(q.max_borrowed);
        match access {
            Access::Owner(delivery) => builder
                .enable_safe_overflow(delivery.safe_overflow())
                .open_or_create()
                .map_err(|e| match e {
                    PublishSubscribeOpenOrCreateError::PublishSubscribeOpenError(
                        PublishSubscribeOpenError::IncompatibleOverflowBehavior,
                    ) => ServiceError::DeliveryMismatch {
                        service,
                        domain: self.name.clone(),
                        requested: delivery,
                    },
                    e => open_err(format!("{e:?}")),
                }),
            Access::Reader => builder.open().map_err(|e| match e {
                PublishSubscribeOpenError::DoesNotExist => ServiceError::NotFound {
                    service,
                    domain: self.name.clone(),
                },
                e => open_err(format!("{e:?}")),
            }),
        }
    }

    /// Opens the input service of `T` for a producer and returns it with its delivery policy.
    /// An existing service (the daemon's) is taken with the policy it was created with;
    /// `requested`, when given, is an assertion: another policy fails with
    /// [`ServiceError::DeliveryAssertion`]. A missing one is created with `requested` (or the
    /// default, [`Delivery::Live`]).
    pub fn open_input<T: Topic>(
        &self,
        node: &Node<ipc::Service>,
        requested: Option<Delivery>,
    ) -> Result<(PubSub<T>, Delivery), ServiceError> {
        // Creating can race with the daemon creating it with the other policy: open again.
        for _ in 0..3 {
            match self.open::<T>(node, Access::Reader) {
                Ok(service) => {
                    let actual = if service.static_config().has_safe_overflow() {
                        Delivery::Live
                    } else {
                        Delivery::Lossless
                    };
                    return match requested {
                        Some(r) if r != actual => Err(ServiceError::DeliveryAssertion {
                            service: T::SERVICE,
                            domain: self.name.clone(),
                            requested: r,
                            actual,
                        }),
                        _ => Ok((service, actual)),
                    };
                }
                Err(ServiceError::NotFound { .. }) => {
                    let delivery = requested.unwrap_or_default();
                    match self.open::<T>(node, Access::Owner(delivery)) {
                        Ok(service) => return Ok((service, delivery)),
                        Err(ServiceError::DeliveryMismatch { .. }) => continue,
                        Err(e) => return Err(e),
                    }
                }
                Err(e) => return Err(e),
            }
        }
        self.open::<T>(node, Access::Owner(requested.unwrap_or_default()))
            .map(|s| (s, requested.unwrap_or_default()))
    }

    /// Opens the event service paired with `service` (same name). `create`: open or create
    /// (owners); otherwise open only.
    pub fn open_event(
        &self,
        node: &Node<ipc::Service>,
        service: &'static str,
        create: bool,
    ) -> Result<Event, ServiceError> {
        let open_err = |detail: String| ServiceError::Open {
            service,
            pattern: "event",
            domain: self.name.clone(),
            detail,
        };
        let name: ServiceName = service.try_into().map_err(|e| open_err(format!("{e:?}")))?;
        let builder = node
            .service_builder(&name)
            .event()
            .max_notifiers(EVENT_MAX_NOTIFIERS)
            .max_listeners(EVENT_MAX_LISTENERS);
        if create {
            builder
                .open_or_create()
                .map_err(|e: EventOpenOrCreateError| open_err(format!("{e:?}")))
        } else {
            builder.open().map_err(|e| match e {
                EventOpenError::DoesNotExist => ServiceError::NotFound {
                    service,
                    domain: self.name.clone(),
                },
                e => open_err(format!("{e:?}")),
            })
        }
    }

    /// Claims the domain for one daemon by creating [`DAEMON_SERVICE`] exclusively. Keep the
    /// returned handle alive for the daemon's life; dropping it releases the claim. A daemon
    /// that crashed is cleaned up by the next node creation (iceoryx2 removes dead nodes'
    /// services), so its claim does not block a restart.
    pub fn claim_daemon(&self, node: &Node<ipc::Service>) -> Result<Event, ServiceError> {
        let name: ServiceName = DAEMON_SERVICE.try_into().map_err(|e| ServiceError::Open {
            service: DAEMON_SERVICE,
            pattern: "event",
            domain: self.name.clone(),
            detail: format!("{e:?}"),
        })?;
        let create = || {
            node.service_builder(&name)
                .event()
                .max_notifiers(1)
                .max_listeners(EVENT_MAX_LISTENERS)
                .create()
        };
        let claim = match create() {
            // The claim of a daemon that was killed: the node creation's cleanup of dead nodes
            // does not wait for a cleanup another process (a client) is doing at that moment,
            // so the dead daemon's service can still be there (2 of 9 restarts after SIGKILL
            // in tests/tests/loss_accounting.rs). Wait for the cleanup, then try again.
            Err(EventCreateError::AlreadyExists) => {
                node.blocking_cleanup_dead_nodes(CLAIM_CLEANUP_WAIT);
                create()
            }
            r => r,
        };
        claim.map_err(|e| match e {
            EventCreateError::AlreadyExists | EventCreateError::IsBeingCreatedByAnotherInstance => {
                ServiceError::DaemonAlreadyRunning {
                    domain: self.name.clone(),
                }
            }
            e => ServiceError::Open {
                service: DAEMON_SERVICE,
                pattern: "event",
                domain: self.name.clone(),
                detail: format!("{e:?}"),
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn domain_names_are_validated() {
        assert!(Domain::new("lab-1_a").is_ok());
        assert!(Domain::new(&"x".repeat(MAX_DOMAIN_LEN)).is_ok());
        for bad in ["", "a/b", "a b", &"x".repeat(MAX_DOMAIN_LEN + 1)] {
            let e = Domain::new(bad).unwrap_err();
            assert!(matches!(e, ServiceError::InvalidDomain { .. }), "{bad:?}");
        }
    }

    #[test]
    fn delivery_parses() {
        assert_eq!("live".parse::<Delivery>(), Ok(Delivery::Live));
        assert_eq!("lossless".parse::<Delivery>(), Ok(Delivery::Lossless));
        assert!("fast".parse::<Delivery>().is_err());
        assert!(Delivery::Live.safe_overflow());
        assert!(!Delivery::Lossless.safe_overflow());
    }

    #[test]
    fn lossless_history_fits_the_buffer() {
        // iceoryx2 refuses history > buffer without safe overflow.
        for q in [
            ImuSample::QOS,
            AngleObservation::QOS,
            AttitudeSample::QOS,
            BiasSample::QOS,
            NavSample::QOS,
            Diagnostics::QOS,
        ] {
            assert!(q.history_size <= q.buffer_size);
        }
    }
}
