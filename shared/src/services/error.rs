//! The error of a service that could not be opened or used.

use super::{Delivery, Domain, RUNTIME_DIR_ENV};
use std::fmt::Display;

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
    /// Another daemon already serves this domain (said with what to do: it said only that the
    /// service existed), and the `corridor status` command that reaches it (a secured domain's
    /// needs its runtime directory: the plain command answered "no corridor daemon answers").
    #[error(
        "another corridor daemon already serves domain {domain:?} ({found}): stop it first, or \
         serve another domain (--domain); `{status}` shows it"
    )]
    DaemonAlreadyRunning {
        /// Domain.
        domain: String,
        /// What showed it: the daemon's service exists, or the secured domain's lock is held.
        found: String,
        /// The `corridor status` command that reaches that daemon.
        status: String,
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
    /// [`ServiceError::DaemonAlreadyRunning`] for `domain`, secured under `runtime_dir` if given.
    pub(crate) fn daemon_already_running(
        domain: &str,
        found: String,
        runtime_dir: Option<&std::path::Path>,
    ) -> Self {
        // The directory shell-quoted, so that the command pastes as it is (a path with a space
        // was cut in two by the shell: a review). A domain name needs no quotes (its rule).
        let status = match runtime_dir {
            Some(dir) => format!(
                "{RUNTIME_DIR_ENV}={} corridor status --domain {domain}",
                shell_quoted(&dir.display().to_string())
            ),
            None => format!("corridor status --domain {domain}"),
        };
        ServiceError::DaemonAlreadyRunning {
            domain: domain.to_owned(),
            found,
            status,
        }
    }

    /// A failed send, receive, notify or wait ([`ServiceError::Io`]) on `service` in `domain`.
    pub fn io(
        domain: &Domain,
        service: &'static str,
        operation: &'static str,
        detail: impl Display,
    ) -> Self {
        ServiceError::Io {
            service,
            operation,
            domain: domain.name().to_owned(),
            detail: readable(detail),
        }
    }

    /// A port of `service` in `domain` that could not be created ([`ServiceError::Port`]).
    pub fn port(
        domain: &Domain,
        service: &'static str,
        port: &'static str,
        detail: impl Display,
    ) -> Self {
        ServiceError::Port {
            service,
            port,
            domain: domain.name().to_owned(),
            detail: readable(detail),
        }
    }
}

/// An iceoryx2 error in words: `loan error: out of memory` for `SendError::LoanError(OutOfMemory)`.
/// iceoryx2 0.10 displays its errors as `Type::{self:?}`, the Rust names of the type and its
/// variants (a user saw `ExceedsMaxSupportedSubscribers`); every word of them is kept, each
/// name split at its capitals and lower-cased, a variant's fields after a colon. The type that
/// leads the text is left out: the message says what was attempted.
pub(crate) fn readable(detail: impl Display) -> String {
    let text = detail.to_string();
    // `SendError::LoanError(OutOfMemory)`: the variant after the type's name.
    let text = match text.split_once("::") {
        Some((ty, rest)) if !ty.is_empty() && ty.chars().all(|c| c.is_ascii_alphanumeric()) => rest,
        _ => text.as_str(),
    };
    let mut out = String::with_capacity(text.len() + 8);
    let mut chars = text.chars().peekable();
    // The previous character written was a letter or digit of the current name.
    let mut prev: Option<char> = None;
    while let Some(c) = chars.next() {
        if c.is_ascii_uppercase() {
            // A capital starts a word, but inside a run of capitals (`IPC`), unless it starts
            // the last word of the run (`IPCPort`: `ipc port`).
            let next_lower = chars.peek().is_some_and(|n| n.is_ascii_lowercase());
            let starts_word = match prev {
                Some(p) if p.is_ascii_lowercase() || p.is_ascii_digit() => true,
                Some(p) if p.is_ascii_uppercase() => next_lower,
                _ => false,
            };
            if starts_word {
                out.push(' ');
            }
            out.push(c.to_ascii_lowercase());
        } else if c == '(' {
            out.push_str(": ");
        } else if c == ')' {
        } else {
            out.push(c);
        }
        prev = c.is_ascii_alphanumeric().then_some(c);
    }
    out
}

/// `text` as one word for a POSIX shell: as it is when it holds only characters no shell
/// treats specially, else in single quotes (a `'` in it written `'\''`).
fn shell_quoted(text: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "/._-+,:@%=".contains(c);
    if !text.is_empty() && text.chars().all(plain) {
        text.to_owned()
    } else {
        format!("'{}'", text.replace('\'', "'\\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use iceoryx2::port::notifier::NotifierCreateError;
    use iceoryx2::port::{LoanError, SendError};

    #[test]
    fn an_iceoryx2_error_is_said_in_words_not_rust_names() {
        // It showed `LoanError(OutOfMemory)` and `ExceedsMaxSupportedNotifiers` (a review).
        let domain = Domain::unsecured("readable-errors").unwrap();
        let e = ServiceError::io(
            &domain,
            "imu",
            "send",
            SendError::LoanError(LoanError::OutOfMemory),
        );
        assert_eq!(
            e.to_string(),
            "service \"imu\" in domain \"readable-errors\": send failed: loan error: out of memory"
        );
        let e = ServiceError::port(
            &domain,
            "imu",
            "notifier",
            NotifierCreateError::ExceedsMaxSupportedNotifiers,
        );
        assert_eq!(
            e.to_string(),
            "service \"imu\" in domain \"readable-errors\": cannot create notifier: exceeds max \
             supported notifiers"
        );
        assert_eq!(
            readable("X::UnableToGenerateUniqueNotifierId"),
            "unable to generate unique notifier id"
        );
        assert_eq!(readable("IPCPortFailed2Open"), "ipc port failed2 open");
        assert_eq!(readable("a plain message"), "a plain message");
    }
}
