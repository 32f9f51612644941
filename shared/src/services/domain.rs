//! The iceoryx2 namespace of a set of processes, and the functions that open the services.

use super::error::readable;
use super::*;
use iceoryx2::prelude::*;
use iceoryx2::service::builder::event::{EventCreateError, EventOpenError, EventOpenOrCreateError};
use iceoryx2::service::builder::publish_subscribe::{
    PublishSubscribeOpenError, PublishSubscribeOpenOrCreateError,
};
use std::fmt::Debug;

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

    /// [`Domain::check_name`] as a command-line parser (`--domain`): a bad name is a usage
    /// error (exit 2) that names the flag, not a failure after start-up.
    pub fn parse_name(text: &str) -> Result<String, String> {
        Self::check_name(text)
            .map(|()| text.to_owned())
            .map_err(|e| e.to_string())
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
            rd::HoldError::Locked { lock } => ServiceError::daemon_already_running(
                name,
                format!("{} is locked", lock.display()),
                Some(runtime_dir),
            ),
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
        let name: NodeName = node_name.try_into().map_err(|e| err(readable(e)))?;
        super::signals::note_before_first_node();
        let node = NodeBuilder::new()
            .name(&name)
            .config(&self.config)
            .signal_handling_mode(signals)
            .create::<ipc::Service>()
            .map_err(|e| err(readable(e)))?;
        // A process that asks iceoryx2 to handle SIGINT and SIGTERM gets iceoryx2's handlers at
        // that node's first wait: here instead, with ours over them, once. (A process with only
        // `Disabled` nodes, such as a test binary hosting a daemon, keeps the default actions.)
        if signals == SignalHandlingMode::HandleTerminationRequests {
            super::signals::install_after_first_node();
        }
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
        let name: ServiceName = service.try_into().map_err(|e| open_err(readable(e)))?;
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
                    e => open_err(readable(e)),
                }),
            Access::Reader => builder.open().map_err(|e| match e {
                PublishSubscribeOpenError::DoesNotExist => ServiceError::NotFound {
                    service,
                    domain: self.name.clone(),
                },
                e => open_err(readable(e)),
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
        let name: ServiceName = service.try_into().map_err(|e| open_err(readable(e)))?;
        let builder = node
            .service_builder(&name)
            .event()
            .max_notifiers(EVENT_MAX_NOTIFIERS)
            .max_listeners(EVENT_MAX_LISTENERS);
        if create {
            builder
                .open_or_create()
                .map_err(|e: EventOpenOrCreateError| open_err(readable(e)))
        } else {
            builder.open().map_err(|e| match e {
                EventOpenError::DoesNotExist => ServiceError::NotFound {
                    service,
                    domain: self.name.clone(),
                },
                e => open_err(readable(e)),
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
            detail: readable(e),
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
                ServiceError::daemon_already_running(
                    &self.name,
                    format!("service {DAEMON_SERVICE:?} exists"),
                    self.hold.as_deref().map(|h| h.runtime_dir.as_path()),
                )
            }
            e => ServiceError::Open {
                service: DAEMON_SERVICE,
                pattern: "event",
                domain: self.name.clone(),
                detail: readable(e),
            },
        })
    }
}

/// Sleeps `d` on `node` (iceoryx2's `Node::wait`); `false` once SIGINT or SIGTERM was received.
/// A sleep that another signal cut short is not a stop request: after SIGSTOP and SIGCONT
/// (Ctrl-Z, `fg`) Linux ends a `nanosleep` with EINTR even without a handler, and `Node::wait`
/// then reports an interrupt although nobody asked to stop; a zero-length wait tells the two
/// apart (it checks the termination request first).
///
/// A termination request it reads is kept for every thread ([`termination_requested`]).
pub fn node_sleep(node: &Node<ipc::Service>, d: std::time::Duration) -> bool {
    if super::signals::termination_seen() {
        return false;
    }
    let going_on = match node.wait(d) {
        Ok(()) => true,
        Err(iceoryx2::node::NodeWaitFailure::TerminationRequest) => false,
        Err(iceoryx2::node::NodeWaitFailure::Interrupt) => {
            node.wait(std::time::Duration::ZERO).is_ok()
        }
    };
    if !going_on {
        super::signals::record_termination();
    }
    // The latch also sees a request iceoryx2 lost to a later signal (SIGTERM, then SIGCONT).
    going_on && !super::signals::termination_seen()
}

/// The signal (SIGINT or SIGTERM) by which this process was asked to end, once one was seen
/// ([`termination_requested`], [`node_sleep`]; SIGINT when only iceoryx2 reported it); `None`
/// before. For a tool to end as that signal would, with [`end_as_terminated_by`].
pub fn termination_signal() -> Option<libc::c_int> {
    super::signals::termination_signal()
}

/// Ends the process as `signal` would have ended it without a handler: a tool that a Ctrl-C
/// stopped, once it has wound up (its files closed, its nodes dropped, what it got said), so
/// that a shell reads `$?` 130 (143 for SIGTERM) and a script stops, as after any command
/// Ctrl-C stopped. (The tools exited with 0 then, or with 1 and "error: interrupted by a
/// termination request" when it came while they waited for a daemon: a review.)
pub fn end_as_terminated_by(signal: libc::c_int) -> ! {
    super::signals::end_as_terminated_by(signal)
}

/// True once SIGINT or SIGTERM was received by this process, as seen through `node` or through
/// any earlier reader, for every thread. iceoryx2's signal handler clears a signal when it is
/// read (`SignalHandler::last_signal`), so a second thread that also polled (the replay's watch
/// on the daemon's diagnostics, or a subscriber opening, through [`node_sleep`]) took the
/// Ctrl-C from the thread that was to act on it, and the replay could not be stopped (reviews
/// of session 38): whoever sees it first keeps it here. A SIGCONT right after the request
/// (systemd's stop, `timeout(1)`) made iceoryx2 forget it: the latch in `signals.rs` keeps it.
pub fn termination_requested<S: iceoryx2::service::Service>(node: &Node<S>) -> bool {
    if super::signals::termination_seen() {
        return true;
    }
    let seen = node.wait(std::time::Duration::ZERO).is_err();
    if seen {
        super::signals::record_termination();
    }
    seen
}
