//! An external heading (`AngleObservation` over `corridor/v6/angles`, e.g. from a map matcher)
//! reaches the estimator end to end: the daemon's attitude stream is the offline run's with the
//! same heading queued (to 1e-12, as the replay test compares), and differs in yaw from the run
//! without it. Handed in before the first sample and stamped later, it waits for its own time.
//! Its own binary:
//! one daemon per test process (docs/known-issues.md).

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

/// The offline estimates of exp36, with `queued` heading observation (time, heading, σ) given
/// before the first sample (as the daemon gets it), or none.
fn offline(queued: Option<(f64, f64, f64)>) -> Vec<Estimate> {
    offline_exp36_with(|est| {
        if let Some((t, h, sd)) = queued {
            est.queue_heading(t, h, sd).unwrap();
        }
    })
}

#[test]
fn an_external_heading_moves_the_published_yaw_as_offline() {
    let without = offline(None);
    let first_tracking = without
        .iter()
        .position(|e| e.phase == Phase::Tracking)
        .expect("exp36 reaches tracking");
    // Stamped half a second into tracking: the next stance's.
    let t_heading = without[first_tracking].t_s + 0.5;
    let with = offline(Some((t_heading, HEADING_RAD, HEADING_SD_RAD)));
    let used = with
        .iter()
        .filter_map(|e| e.heading)
        .find(|h| h.direction_rad == HEADING_RAD)
        .expect("the heading is used");
    assert!(
        used.observed_t_s >= t_heading - 0.5 && used.observed_t_s <= t_heading + 2.0,
        "used at {} s, stamped {t_heading} s",
        used.observed_t_s
    );
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
        // queued before the first sample, as offline, and waits for its time. Sent again until
        // the daemon's angle subscriber is connected (it is created next to the IMU one).
        let obs = AngleObservation {
            t_s: t_heading,
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
    assert_eq!(
        report.diagnostics.angles_ignored, 1,
        "the roll observation is counted"
    );
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

/// An external heading further than `EXTERNAL_HEADING_MAX_NIS` from the filter's prediction is
/// refused and counted, not fused (one 90° off with σ 1e-6 at 30 s used to throw the bias to
/// 0.03 rad/s); one that agrees with the prediction is fused.
#[test]
fn an_absurd_external_heading_mid_walk_is_refused_at_its_stance() {
    use corridor_service::runner::heading_aid;
    let run = |heading: Option<(f64, f64)>| {
        let cfg = config();
        let aid = heading_aid(&cfg, None).unwrap();
        let mut est = corridor_service::core::Estimator::new(cfg, aid);
        // The heading queued, and whether its stance fused it.
        let (mut queued, mut fused) = (None, None);
        for r in exp36_rows() {
            let e = *est.step(&(&r).into()).unwrap();
            if let (Some(dir), Some(ev)) = (queued, e.heading)
                && ev.direction_rad == dir
            {
                fused = Some(ev.outcome.is_ok());
            }
            if let Some((h, sd)) = heading
                && queued.is_none()
                && r.t_s >= 30.0
            {
                // The foot's heading now, roughly (the sensor's yaw less its yaw on the foot),
                // turned by `h`, with σ `sd`.
                let foot = e.yaw_rad - est.mount_yaw_rad().expect("calibrated by 30 s");
                est.queue_heading(r.t_s, foot + h, sd).unwrap();
                queued = Some(foot + h);
            }
        }
        (*est.counters(), est.last_estimate().gyro_bias_rad_s, fused)
    };
    let (clean, clean_bias, _) = run(None);
    let (absurd, absurd_bias, fused) = run(Some((std::f64::consts::FRAC_PI_2, 1e-6)));
    assert_eq!((absurd.headings_outside_gate, fused), (1, Some(false)));
    let moved = (0..3)
        .map(|k| (absurd_bias[k] - clean_bias[k]).abs())
        .fold(0.0, f64::max);
    assert!(moved < 1e-4, "the bias moved by {moved} rad/s");
    assert_eq!(clean.headings_outside_gate, 0);
    // Not turned, with a σ (10°) that covers the rough foot heading: within the gate, fused.
    let (near, _, fused) = run(Some((0.0, 0.17)));
    assert_eq!((near.headings_outside_gate, fused), (0, Some(true)));
}
