//! The daemon never publishes or checkpoints garbage (issue 10, finding 2).
//!
//! One daemon test per binary: a test binary that starts several daemons one after another
//! sometimes leaves a later daemon without the producer's connection (see
//! `one_daemon_at_a_time`; iceoryx2 0.10, seen on the unmodified `daemon_checkpoint` too).

mod daemon_common;

use corridor_client::{Delivery, Domain, Subscriber};
use corridor_service::checkpoint;
use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::imu_csv::{ImuCsvOptions, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::wire::BiasSample;
use daemon_common::*;

/// The final bias of the clean offline run of exp36.
fn clean_final_bias() -> [f64; 3] {
    let cfg = config();
    let aid = heading_aid(&cfg, None).unwrap();
    let path = manifest().join("data/gdins_exp36_corridor_out_and_back/imu.csv");
    let log = read_imu_csv(&path, &ImuCsvOptions::default()).unwrap();
    let out = run_log(&log, &cfg, &aid, &BiasInjection::default(), |_, _| {});
    *out.trace.bias_rad_s.last().unwrap()
}

fn max_abs_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max)
}

#[test]
fn absurd_samples_never_reach_the_published_bias_or_the_checkpoint() {
    // Before: one az = 1e30 through the daemon checkpointed a garbage bias (0.43, 1.30,
    // 0.05 rad/s) that warm-started the next stream. Case 1: the samples, refused by the
    // plausibility check. Case 2: limits opened so wide that the samples pass it: the health
    // check after the update must catch the state.
    let _one = one_daemon_at_a_time();
    let name = "test_robust_daemon_garbage";
    let clean = clean_final_bias();
    use corridor_shared::sensor::{MAX_ACCEL_RANGE_M_S2, MAX_GYRO_RANGE_RAD_S, MAX_NORM_FACTOR};
    let wide = corridor_shared::sensor::SensorFile {
        // The widest the configuration takes (1e300 was taken before the ranges were
        // bounded): a single axis passes up to twice the range.
        max_accel_m_s2: Some(MAX_NORM_FACTOR * MAX_ACCEL_RANGE_M_S2),
        max_gyro_rad_s: Some(MAX_NORM_FACTOR * MAX_GYRO_RANGE_RAD_S),
        accel_range_m_s2: Some(MAX_ACCEL_RANGE_M_S2),
        gyro_range_rad_s: Some(MAX_GYRO_RANGE_RAD_S),
        ..Default::default()
    }
    .validate()
    .unwrap();
    for (limits, accel, gyro) in [(None, 1e30, 1e300), (Some(wide), 7.9e3, 0.0)] {
        cleanup_domain(name);
        let dir = temp_dir("test-robust-daemon-garbage");
        let ckpt = dir.join("checkpoint.bin");
        let domain = Domain::new(name).unwrap();
        let mut dcfg = daemon_config(&domain, Delivery::Lossless);
        if let Some(l) = limits {
            dcfg.estimator.sensor = l;
        }
        dcfg.checkpoint = Some(ckpt.clone());
        let daemon = Running::start(dcfg);
        let bias = Subscriber::<BiasSample>::open(&domain, "test-bias", WAIT).unwrap();
        let mut rows = exp36_rows();
        rows[5000].accel_m_s2[2] = accel;
        rows[9000].accel_m_s2[0] = -accel;
        rows[9500].gyro_rad_s[1] += gyro;
        let producer = produce(&domain, "test-replay", Delivery::Lossless, rows, true);
        let got = until_end(&bias, |b| b.flags);
        producer.join();
        drop(bias);
        let report = daemon.stop();
        for b in &got {
            assert!(
                b.gyro_bias_rad_s
                    .iter()
                    .all(|v| v.is_finite() && v.abs() < 0.2),
                "published {:?}",
                b.gyro_bias_rad_s
            );
        }
        assert!(report.checkpoints_saved >= 1);
        let saved = checkpoint::load(&ckpt).expect("a valid checkpoint");
        assert!(
            max_abs_diff(saved.gyro_bias_rad_s, clean) < 5e-4,
            "accel {accel}: saved {:?} vs clean run {clean:?}",
            saved.gyro_bias_rad_s
        );
    }
    cleanup_domain(name);
}
