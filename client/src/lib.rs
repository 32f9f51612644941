//! corridor-client: talk to the corridor daemon over iceoryx2 shared memory.
//!
//! Map of the modules:
//! - [`csv_rows`]: the CSV rows of the attitude and bias streams (logger tool and demo).
//! - [`record`]: [`Recorder`], the attitude and bias streams to `attitude.csv` and `bias.csv`.
//! - [`replay`](mod@replay): [`replay()`], a recorded IMU log sent as a live sensor (paced, looped, with an
//!   injected gyro bias).
//! - [`track`]: [`Tracker`], the stride-by-stride positions of the nav stream.
//! - [`producer`]: [`Producer`], publishes [`ImuSample`]s and [`AngleObservation`]s (and the
//!   end-of-stream marker) and wakes the daemon.
//! - [`status`]: [`StatusReader`](status::StatusReader), the daemon's health from its
//!   diagnostics and bias streams (`corridor status`).
//! - [`subscriber`]: [`Subscriber<T>`], receives one of the daemon's outputs
//!   ([`AttitudeSample`], [`BiasSample`], [`NavSample`], [`Diagnostics`]) with a blocking
//!   [`Subscriber::recv_timeout`].
//!
//! Binaries (`src/bin/`), thin wrappers around the three tool modules (which `corridor demo`
//! uses too): `corridor-replay` ([`replay`](mod@replay)), `corridor-log` ([`record`]), `corridor-pdr`
//! ([`track`]); and `corridor-wire`, the wire types' layout for C and Python clients
//! ([`corridor_shared::wire_layout`]). [`init_tracing`] is the log setup of every corridor binary.
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
pub mod record;
pub mod replay;
pub mod status;
pub mod subscriber;
pub mod track;

pub use corridor_shared::services::{Delivery, Domain, ServiceError};
pub use producer::{END_ACK_WAIT, Producer, ProducerStats};
pub use record::Recorder;
pub use replay::replay;
pub use subscriber::Subscriber;
pub use track::Tracker;

use std::process::ExitCode;
use std::time::Duration;

/// A client-side failure.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// A service could not be opened or used.
    #[error(transparent)]
    Service(#[from] ServiceError),
    /// The peer did not show up in time: no daemon serves the domain (said as `corridor
    /// status` says it, with the runtime directory's hint: the tools gave the raw service
    /// text, a review).
    #[error(
        "no corridor daemon answers on domain {domain:?}: service {service:?} has no {peer} after {waited:?}{}",
        runtime_dir_hint()
    )]
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
    /// An output file could not be created or written.
    #[error("{}: {source}", path.display())]
    File {
        /// The file (or directory).
        path: std::path::PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
}

/// What to add to "no corridor daemon answers": a daemon serving a secured domain
/// (`--runtime-dir`) is found only through its runtime directory, and without it the domain
/// looks empty (a review). Empty when the variable is set.
pub fn runtime_dir_hint() -> String {
    if std::env::var_os(corridor_shared::services::RUNTIME_DIR_ENV).is_none() {
        format!(
            " (a daemon started with --runtime-dir DIR is found only with {}=DIR)",
            corridor_shared::services::RUNTIME_DIR_ENV
        )
    } else {
        String::new()
    }
}

/// Logs to stderr, filtered by `RUST_LOG`, or by `default_filter` (e.g. `warn`) when it is
/// unset or invalid. Call once, at the start of a binary.
pub fn init_tracing(default_filter: &str) {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(default_filter)),
        )
        .with_writer(std::io::stderr)
        // Colour codes only on a terminal: a log file or the journal gets plain text.
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        // A log line that cannot be written (stderr a pipe whose reader left) is dropped: the
        // subscriber's own report of it went to that same stderr and panicked, which killed a
        // daemon, or its signal thread so that it never stopped (a review, session 38).
        .log_internal_errors(false)
        .init();
}

/// Prints a line to standard output; a line that cannot be written (a pipe whose reader left,
/// `| head`) is dropped instead of panicking as `println!` does, so that a tool that must
/// finish its work (a replay's end-of-stream marker) does.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// Prints `text` to standard output as it is (a table that ends its own lines); like [`say!`],
/// a text that cannot be written is dropped.
pub fn say_text(text: &str) {
    use std::io::Write as _;
    let _ = std::io::stdout().write_all(text.as_bytes());
}

/// [`say!`] for standard error.
#[macro_export]
macro_rules! say_err {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

/// True once SIGINT or SIGTERM was received by this process, for every thread (the latch is
/// `corridor_shared::services::termination_requested`'s). `Producer` and `Subscriber` ask
/// through it; so should anything else that polls.
pub use corridor_shared::services::termination_requested;

/// The error and its causes on one line (`a: b: c`), each cause once: a cause whose text the
/// message already contains (many errors repeat their source in their own text) is left out.
/// No backtrace, whatever `RUST_BACKTRACE` says: these are user errors, not crashes.
pub fn error_message(e: &anyhow::Error) -> String {
    let mut msg = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if msg.contains(&text) {
            continue;
        }
        if !msg.is_empty() {
            msg.push_str(": ");
        }
        msg.push_str(&text);
    }
    msg
}

/// Exit code of every corridor binary for a usage error: the argument parser's own, and a
/// flag's value outside the range of the key it sets.
pub const EXIT_USAGE: u8 = 2;

/// Exit code of every corridor binary when no daemon answered on the domain within its wait
/// ([`ClientError::NoPeer`]; `corridor status` also when the daemon is shutting down). Not
/// [`EXIT_USAGE`]: `corridor status` gave 2 for both, so a script could not tell a mistyped
/// flag from a daemon that is down, and the tools gave 1, as for any other error.
pub const EXIT_NO_DAEMON: u8 = 3;

/// The exit code of a tool stopped by Ctrl-C, as a shell gives it (128 + SIGINT's number),
/// where the tool cannot end by the signal itself.
pub const EXIT_INTERRUPTED: u8 = 130;

/// A tool stopped by SIGINT or SIGTERM, once it has wound up and said what it got: it ends as
/// that signal would end it ([`corridor_shared::services::end_as_terminated_by`]: `$?` 130
/// after Ctrl-C, 143 after SIGTERM); nothing happens without such a request.
pub fn end_if_interrupted() {
    if let Some(signal) = corridor_shared::services::termination_signal() {
        corridor_shared::services::end_as_terminated_by(signal);
    }
}

/// The exit of every corridor client tool: success, or `error: ...` ([`error_message`]) once
/// on stderr and a failure code: [`EXIT_NO_DAEMON`] when the cause is that no daemon answered,
/// 1 otherwise. A tool that SIGINT or SIGTERM stopped ([`ClientError::Interrupted`], or a
/// success after one) ends as that signal would ([`end_if_interrupted`]), with `interrupted`
/// on stderr if it had not got to say so.
pub fn exit(result: anyhow::Result<()>) -> ExitCode {
    match result {
        Ok(()) => {
            end_if_interrupted();
            ExitCode::SUCCESS
        }
        Err(e)
            if e.chain()
                .any(|c| matches!(c.downcast_ref(), Some(ClientError::Interrupted))) =>
        {
            say_err!("interrupted");
            end_if_interrupted();
            // (A request only iceoryx2 saw, and lost: as Ctrl-C.)
            ExitCode::from(EXIT_INTERRUPTED)
        }
        Err(e) => {
            say_err!("error: {}", error_message(&e));
            let no_daemon = e
                .chain()
                .any(|c| matches!(c.downcast_ref(), Some(ClientError::NoPeer { .. })));
            if no_daemon {
                ExitCode::from(EXIT_NO_DAEMON)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_message_names_each_cause_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let inner = anyhow::Error::from(io).context("x.csv: cannot read: no such file");
        let e = inner.context("reading x.csv");
        assert_eq!(
            error_message(&e),
            "reading x.csv: x.csv: cannot read: no such file"
        );
    }
}
