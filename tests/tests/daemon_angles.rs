//! An external heading (`AngleObservation` over `corridor/v4/angles`, e.g. from a map matcher)
//! reaches the estimator end to end: the daemon's attitude stream is the offline run's with the
//! same heading queued (to 1e-12, as the replay test compares), and differs in yaw from the run
//! without it. Its own binary:
//! one daemon per test process (README, known issues).

mod daemon_common;

use corridor_client::{Delivery, Domain, Producer, Subscriber};
use corridor_service::core::{Estimate, Phase};
use corridor_shared::wire::{
    ANGLE_HEADING, ANGLE_ROLL, AngleObservation, AttitudeSample, ImuSample,
};
use daemon_common::*;
use std::time::Instant;

/// The heading the "map matcher" reports: 20° off the corridor the walk starts in, trusted to
/// 0.5°, so that the first tracking stance visibly turns the estimate.
const HEADING_RAD: f64 = 0.349;
const HEADING_SD_RAD: f64 = 0.0087;

/// The offline estimates of exp36, with `queued` heading observation given before the first
/// sample (as the daemon gets it), or none.
fn offline(queued: Option<(f64, f64)>) -> Vec<Estimate> {
    offline_exp36_with(|est| {
        if let Some((h, sd)) = queued {
            est.queue_heading(h, sd).unwrap();
        }
    })
}

#[test]
fn an_external_heading_moves_the_published_yaw_as_offline() {
    let with = offline(Some((HEADING_RAD, HEADING_SD_RAD)));
    let without = offline(None);
    let first_tracking = with
        .iter()
        .position(|e| e.phase == Phase::Tracking)
        .expect("exp36 reaches tracking");
    let differ = with
        .iter()
        .zip(&without)
        .skip(first_tracking)
        .filter(|(a, b)| (a.yaw_rad - b.yaw_rad).abs() > 1e-3)
        .count();
    assert!(
        differ > 1000,
        "the heading changes the yaw offline ({differ} samples)"
    );

    let domain = Domain::new("test_daemon_angles").unwrap();
    cleanup_domain("test_daemon_angles");
    let daemon = Running::start(daemon_config(&domain, Delivery::Lossless));
    let attitude = Subscriber::<AttitudeSample>::open(&domain, "test-attitude", WAIT).unwrap();
    let rows = exp36_rows();
    let d = domain.clone();
    let producer = std::thread::spawn(move || {
        let mut p = Producer::new(&d, "test-angles", Delivery::Lossless).unwrap();
        p.wait_for_daemon(WAIT).unwrap();
        // The heading first: the daemon drains angle observations before IMU samples, so it is
        // queued before the first sample, as offline. Sent again until the daemon's angle
        // subscriber is connected (it is created next to the IMU one).
        let obs = AngleObservation {
            t_s: rows[0].t_s,
            heading_rad: HEADING_RAD,
            heading_sd_rad: HEADING_SD_RAD,
            valid: ANGLE_HEADING,
            ..AngleObservation::default()
        };
        let start = Instant::now();
        while p.send_angles(obs).unwrap() == 0 {
            assert!(start.elapsed() < WAIT, "no angle subscriber");
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        // Roll and pitch are not fused: counted, nothing else happens.
        let tilt = AngleObservation {
            roll_rad: 0.2,
            roll_sd_rad: 0.01,
            valid: ANGLE_ROLL,
            ..obs
        };
        assert_eq!(p.send_angles(tilt).unwrap(), 1);
        for r in &rows {
            p.send_imu(ImuSample::from(r)).unwrap();
        }
        p.finish().unwrap();
        p.stats()
    });
    let got = until_end(&attitude, |a| a.flags);
    let stats = producer.join().unwrap();
    let report = daemon.stop();
    assert_eq!(report.angles_ignored, 1, "the roll observation is counted");
    assert_eq!(
        stats.angles_sent - stats.angles_undelivered,
        2,
        "the heading and the roll observation reached the daemon"
    );
    assert_eq!(got.len(), with.len() + 1, "every sample and the marker");
    for (i, (a, e)) in got.iter().zip(&with).enumerate() {
        let close = |x: f64, y: f64| x == y || (x - y).abs() <= 1e-12;
        assert!(
            close(a.yaw_rad, e.yaw_rad),
            "yaw at {i}: {} vs {}",
            a.yaw_rad,
            e.yaw_rad
        );
    }
}
