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
//! | [`IMU_SERVICE`] | [`ImuSample`](crate::wire::ImuSample) | producers | yes (daemon waits on it) |
//! | [`ANGLES_SERVICE`] | [`AngleObservation`](crate::wire::AngleObservation) | producers | yes |
//! | [`ATTITUDE_SERVICE`] | [`AttitudeSample`](crate::wire::AttitudeSample) | daemon | yes |
//! | [`BIAS_SERVICE`] | [`BiasSample`](crate::wire::BiasSample) | daemon | yes |
//! | [`NAV_SERVICE`] | [`NavSample`](crate::wire::NavSample) | daemon | yes |
//! | [`DIAGNOSTICS_SERVICE`] | [`Diagnostics`](crate::wire::Diagnostics) | daemon | yes |
//! | [`DAEMON_SERVICE`] | (event only) | daemon, created exclusively | lock only |
//!
//! A blocking wait on a publish-subscribe port is not possible in iceoryx2; each pub-sub service
//! has an event service of the same name: the publisher notifies after sending, the reader waits
//! on a listener.
//!
//! [`Domain`] gives every independent set of processes (a sensor, a test) its own iceoryx2
//! namespace (`global.prefix`), so they never see each other's services.
//!
//! Files: this one holds the service names; `error.rs` [`ServiceError`]; `qos.rs` the delivery
//! policy, the quality of service and the [`Topic`] of each wire type; `domain.rs` the
//! [`Domain`] namespace and the functions that open the services; `signals.rs` the latch of
//! SIGINT and SIGTERM that [`termination_requested`] and [`node_sleep`] read.

mod domain;
mod error;
mod qos;
mod signals;

pub use domain::*;
pub use error::ServiceError;
pub use qos::{Delivery, Qos, Topic};

/// Version of the wire layout; part of every service name. Bump it with any change to
/// [`crate::wire`].
pub const SERVICE_VERSION: &str = "v6";
/// IMU samples, producers → daemon.
pub const IMU_SERVICE: &str = "corridor/v6/imu";
/// External angle observations, producers → daemon.
pub const ANGLES_SERVICE: &str = "corridor/v6/angles";
/// Attitude after every IMU sample, daemon → clients.
pub const ATTITUDE_SERVICE: &str = "corridor/v6/attitude";
/// Gyro-bias estimates, daemon → clients.
pub const BIAS_SERVICE: &str = "corridor/v6/bias";
/// Position and velocity at each stance, daemon → clients.
pub const NAV_SERVICE: &str = "corridor/v6/nav";
/// Daemon counters, daemon → clients.
pub const DIAGNOSTICS_SERVICE: &str = "corridor/v6/diagnostics";
/// Event, daemon → producers: notified with [`ack_event_id`] of a producer's IMU publisher when
/// the daemon has read that producer's first sample (in this daemon life; taken, or refused
/// because another producer is followed). A producer waits for it before it lets its publisher go: iceoryx2 0.10
/// attaches the daemon's side of a new connection only when the daemon next receives, and a
/// publisher dropped before that takes the samples still queued with it.
pub const IMU_ACK_SERVICE: &str = "corridor/v6/imu_ack";

/// The event id of [`IMU_ACK_SERVICE`] that acknowledges the IMU publisher with this port id
/// (`UniquePublisherId::value`): one of 256, iceoryx2's default id range (0–255). Two producers
/// of one domain share an id with probability 1/256.
pub fn ack_event_id(publisher_id: u128) -> usize {
    (publisher_id % 256) as usize
}
/// Event service created exclusively by the running daemon: a second daemon on the same domain
/// fails to create it. Clients must not open it (an open handle would keep it alive after the
/// daemon exits).
pub const DAEMON_SERVICE: &str = "corridor/v6/daemon";

/// Longest single wait on an event listener. iceoryx2 0.10's event can lose a wake-up: a
/// listener that has just reset its state to idle empties its socket, swallowing the datagram
/// of a notifier that set the state to pending and was then preempted before marking it
/// notified; the listener's next wait finds "pending", blocks on the empty socket, and once the
/// notifier marks "notified" every later `notify` sends nothing (it sees "notified"). Only the
/// listener's timeout ends that sleep (`iceoryx2-cal` 0.10 `event/common.rs`, `notify` and
/// `drain_events`; reproduced with two delays added at those points,
/// `docs/experiments/iceoryx2-lost-wakeup/`). So a long wait is made of waits of at most this
/// length, each followed by a look at the data: a lost wake-up costs at most this much.
pub const EVENT_WAIT_SLICE: std::time::Duration = std::time::Duration::from_millis(50);

/// The next single listener wait of a wait that ends at `deadline`: at most
/// [`EVENT_WAIT_SLICE`], `None` once the deadline is reached.
pub fn event_wait_slice(
    now: std::time::Instant,
    deadline: std::time::Instant,
) -> Option<std::time::Duration> {
    (now < deadline).then(|| (deadline - now).min(EVENT_WAIT_SLICE))
}

/// The default domain name.
pub const DEFAULT_DOMAIN: &str = "default";

/// Longest domain name, characters.
pub const MAX_DOMAIN_LEN: usize = 48;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::{
        AngleObservation, AttitudeSample, BiasSample, Diagnostics, ImuSample, NavSample,
    };

    #[test]
    fn a_long_wait_is_cut_into_slices_that_end_at_the_deadline() {
        use std::time::{Duration, Instant};
        let t0 = Instant::now();
        let deadline = t0 + Duration::from_secs(60);
        // Far from the deadline: one slice, not the remaining minute.
        assert_eq!(event_wait_slice(t0, deadline), Some(EVENT_WAIT_SLICE));
        // Close to it: what is left.
        let near = deadline - Duration::from_millis(7);
        assert_eq!(
            event_wait_slice(near, deadline),
            Some(Duration::from_millis(7))
        );
        // At or past it: no wait.
        assert_eq!(event_wait_slice(deadline, deadline), None);
        assert_eq!(
            event_wait_slice(deadline + Duration::from_millis(1), deadline),
            None
        );
        // Walking the slices covers the whole wait, each at most a slice long.
        let (mut now, mut n) = (t0, 0);
        while let Some(d) = event_wait_slice(now, deadline) {
            assert!(d <= EVENT_WAIT_SLICE && d > Duration::ZERO);
            now += d;
            n += 1;
        }
        assert_eq!(now, deadline);
        assert_eq!(n, 1200);
    }

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
    fn a_second_daemon_on_a_secured_domain_is_told_how_to_reach_the_first() {
        // The refusal said `corridor status --domain lab`, which finds no daemon on a secured
        // domain without CORRIDOR_RUNTIME_DIR (exit code 3).
        let dir = std::path::PathBuf::from(format!("/tmp/crs{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let first = Domain::serve("lab", Some(&dir)).unwrap();
        let e = Domain::serve("lab", Some(&dir)).unwrap_err().to_string();
        drop(first);
        let _ = std::fs::remove_dir_all(&dir);
        let status = format!(
            "`{RUNTIME_DIR_ENV}={} corridor status --domain lab`",
            dir.display()
        );
        assert!(e.contains(&status), "{e}");
        assert!(e.contains("daemon.lock is locked"), "{e}");
    }

    #[test]
    fn the_status_command_of_a_second_daemon_pastes_into_a_shell_as_it_is() {
        // A runtime directory with a space (and a quote) was written as it is, and the shell
        // cut the pasted command in two at the space (a review).
        let dir = std::path::PathBuf::from(format!("/tmp/crs it's {}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let first = Domain::serve("lab", Some(&dir)).unwrap();
        let e = Domain::serve("lab", Some(&dir)).unwrap_err().to_string();
        drop(first);
        let _ = std::fs::remove_dir_all(&dir);
        let command = e.split('`').nth(1).unwrap_or_default();
        let command = command
            .strip_suffix(" corridor status --domain lab")
            .expect(&e);
        // What the shell gives the command in its environment.
        let shell = std::process::Command::new("sh")
            .arg("-c")
            .arg(format!(
                "{command} sh -c 'printf %s \"${RUNTIME_DIR_ENV}\"'"
            ))
            .output()
            .unwrap();
        assert_eq!(
            String::from_utf8_lossy(&shell.stdout),
            dir.to_str().unwrap(),
            "{e}"
        );
    }

    #[test]
    fn every_service_name_carries_the_wire_version() {
        let prefix = format!("corridor/{SERVICE_VERSION}/");
        for name in [
            IMU_SERVICE,
            ANGLES_SERVICE,
            ATTITUDE_SERVICE,
            BIAS_SERVICE,
            NAV_SERVICE,
            DIAGNOSTICS_SERVICE,
            IMU_ACK_SERVICE,
            DAEMON_SERVICE,
        ] {
            assert!(name.starts_with(&prefix), "{name}");
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
