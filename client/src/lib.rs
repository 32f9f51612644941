//! corridor-client: talk to the corridor daemon over iceoryx2 shared memory.
//!
//! Map of the modules:
//! - [`csv_rows`]: the CSV rows of the attitude and bias streams (logger tool and demo).
//! - [`producer`]: [`Producer`], publishes [`ImuSample`]s and [`AngleObservation`]s (and the
//!   end-of-stream marker) and wakes the daemon.
//! - [`subscriber`]: [`Subscriber<T>`], receives one of the daemon's outputs
//!   ([`AttitudeSample`], [`BiasSample`], [`NavSample`], [`Diagnostics`]) with a blocking
//!   [`Subscriber::recv_timeout`].
//!
//! Binaries (`src/bin/`): `corridor-replay` (a CSV log as a live IMU), `corridor-log` (the
//! attitude stream to `estimates.csv`), `corridor-pdr` (stride-by-stride positions).
//!
//! Service names, QoS and domains are defined once in [`corridor_shared::services`]; the wire
//! types in [`corridor_shared::wire`].
//!
//! iceoryx2 ports are not `Send`: create a [`Producer`] or [`Subscriber`] on the thread that
//! uses it.
//!
//! [`ImuSample`]: corridor_shared::wire::ImuSample
//! [`AngleObservation`]: corridor_shared::wire::AngleObservation
//! [`AttitudeSample`]: corridor_shared::wire::AttitudeSample
//! [`BiasSample`]: corridor_shared::wire::BiasSample
//! [`NavSample`]: corridor_shared::wire::NavSample
//! [`Diagnostics`]: corridor_shared::wire::Diagnostics

pub mod csv_rows;
pub mod producer;
pub mod subscriber;

pub use corridor_shared::services::{Delivery, Domain, ServiceError};
pub use producer::{Producer, ProducerStats};
pub use subscriber::Subscriber;

use std::time::Duration;

/// A client-side failure.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// A service could not be opened or used.
    #[error(transparent)]
    Service(#[from] ServiceError),
    /// The peer did not show up in time.
    #[error("service {service:?} in domain {domain:?}: no {peer} after {waited:?}")]
    NoPeer {
        /// Service name.
        service: &'static str,
        /// Domain.
        domain: String,
        /// `subscriber` (the daemon, for a producer) or `publisher` (the daemon, for a reader).
        peer: &'static str,
        /// How long it waited.
        waited: Duration,
    },
    /// SIGINT or SIGTERM was received (iceoryx2's signal handler).
    #[error("interrupted by a termination request (SIGINT/SIGTERM)")]
    Interrupted,
}
