//! Checkpoint and warm start of the daemon (in-process, each test on its own domain).
//!
//! - `restart_warm_starts_from_the_saved_bias`: a daemon replays exp36 and is stopped; a second
//!   daemon with the same checkpoint file publishes, at the end of its alignment, the saved bias
//!   (not the rest-mean prior a cold start gives).
//! - `corrupt_checkpoint_is_moved_aside_and_the_daemon_cold_starts`: a damaged file becomes a
//!   warning, is renamed `<file>.corrupt-1`, and the daemon starts from the configured prior.

mod daemon_common;

use corridor_client::{Delivery, Domain, Subscriber};
use corridor_service::checkpoint;
use corridor_service::core::{Estimate, Phase};
use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::imu_csv::{ImuCsvOptions, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::wire::{BiasSample, FLAG_END_OF_STREAM};
use daemon_common::*;

/// The offline estimates of exp36 and the index of the first aligned sample.
fn offline_exp36() -> (Vec<Estimate>, usize) {
    let cfg = config();
    let aid = heading_aid(&cfg, None).unwrap();
    let path = manifest().join("data/gdins_exp36_corridor_out_and_back/imu.csv");
    let log = read_imu_csv(&path, &ImuCsvOptions::default()).unwrap();
    let mut est = Vec::with_capacity(log.rows.len());
    run_log(&log, &cfg, &aid, &BiasInjection::default(), |_, e| {
        est.push(*e)
    });
    let first = est
        .iter()
        .position(|e| e.phase != Phase::Aligning)
        .expect("exp36 aligns");
    (est, first)
}

/// Replays the first `n` rows of exp36 (then the end-of-stream marker) and returns the first
/// bias sample with a finite σ (published at the end of alignment) and the report.
fn first_aligned_bias(
    domain: &Domain,
    ckpt: &std::path::Path,
    n: usize,
) -> (BiasSample, corridor_service::daemon::DaemonReport) {
    let mut dcfg = daemon_config(domain, Delivery::Lossless);
    dcfg.checkpoint = Some(ckpt.to_owned());
    let daemon = Running::start(dcfg);
    let bias = Subscriber::<BiasSample>::open(domain, "test-bias", WAIT).unwrap();
    let rows = exp36_rows()[..n].to_vec();
    let producer = produce(domain, "test-replay", Delivery::Lossless, rows, true);
    let got = until_end(&bias, |b| b.flags);
    producer.join().unwrap();
    let report = daemon.stop();
    let first = *got
        .iter()
        .find(|b| b.gyro_bias_sd_rad_s[0].is_finite())
        .expect("a bias sample after alignment");
    (first, report)
}

fn max_abs_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max)
}

#[test]
fn restart_warm_starts_from_the_saved_bias() {
    let _one = one_daemon_at_a_time();
    let name = "test_daemon_warm";
    cleanup_domain(name);
    let dir = temp_dir("test-daemon-warm");
    let ckpt = dir.join("checkpoint.bin");
    let domain = Domain::new(name).unwrap();
    let (offline, first_aligned) = offline_exp36();

    // First life: the whole log, then stop.
    let mut dcfg = daemon_config(&domain, Delivery::Lossless);
    dcfg.checkpoint = Some(ckpt.clone());
    let daemon = Running::start(dcfg);
    let bias = Subscriber::<BiasSample>::open(&domain, "test-bias", WAIT).unwrap();
    let producer = produce(
        &domain,
        "test-replay",
        Delivery::Lossless,
        exp36_rows(),
        true,
    );
    let got = until_end(&bias, |b| b.flags);
    producer.join().unwrap();
    drop(bias);
    let report = daemon.stop();
    assert!(report.warm_started_from.is_none(), "first start is cold");
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    assert!(report.checkpoints_saved >= 1);
    let end = got.last().unwrap();
    assert!(end.flags & FLAG_END_OF_STREAM != 0);

    let saved = checkpoint::load(&ckpt).expect("checkpoint saved at end of stream");
    assert_eq!(saved.mode, "eskf");
    assert_eq!(
        saved.t_s,
        offline.last().unwrap().t_s,
        "state of the last sample"
    );
    assert!(
        max_abs_diff(saved.gyro_bias_rad_s, end.gyro_bias_rad_s) <= 1e-15,
        "checkpoint {:?} vs last published {:?}",
        saved.gyro_bias_rad_s,
        end.gyro_bias_rad_s
    );
    // The full covariance: off-diagonal terms are there, and it matches the published σ.
    let cov = saved.gyro_bias_cov;
    assert!(cov[0][1] != 0.0 && cov[0][1] == cov[1][0], "{cov:?}");
    for (k, published) in end.gyro_bias_sd_rad_s.iter().enumerate() {
        let sd = cov[k][k].sqrt();
        assert!(
            (sd - published).abs() <= 1e-12 * sd.max(1.0),
            "σ[{k}] {sd} vs {published}"
        );
    }

    // The cold start's bias right after alignment (rest-mean prior) must differ from the saved
    // one, or this test could not tell a warm start from a cold one.
    let cold = offline[first_aligned].gyro_bias_rad_s;
    assert!(
        max_abs_diff(cold, saved.gyro_bias_rad_s) > 1e-4,
        "cold {cold:?} vs saved {:?}",
        saved.gyro_bias_rad_s
    );

    // Second life: same checkpoint file, the start of the log.
    let (first, report) = first_aligned_bias(&domain, &ckpt, first_aligned + 400);
    assert_eq!(
        report.warm_started_from.as_ref(),
        Some(&saved),
        "warm start from the file"
    );
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    assert_eq!(
        first.imu_seq, first_aligned as u64,
        "published at alignment"
    );
    assert!(
        max_abs_diff(first.gyro_bias_rad_s, saved.gyro_bias_rad_s) <= 1e-12,
        "first bias after alignment {:?}, saved {:?}",
        first.gyro_bias_rad_s,
        saved.gyro_bias_rad_s
    );
    for k in 0..3 {
        let sd = saved.gyro_bias_cov[k][k].sqrt();
        assert!(
            (first.gyro_bias_sd_rad_s[k] - sd).abs() <= 1e-3 * sd,
            "σ[{k}] {} vs saved {sd}",
            first.gyro_bias_sd_rad_s[k]
        );
    }
    // The second life saved its own state over the first one.
    let resaved = checkpoint::load(&ckpt).unwrap();
    assert_eq!(resaved.t_s, offline[first_aligned + 399].t_s);

    cleanup_domain(name);
}

#[test]
fn corrupt_checkpoint_is_moved_aside_and_the_daemon_cold_starts() {
    let _one = one_daemon_at_a_time();
    let name = "test_daemon_corrupt";
    cleanup_domain(name);
    let dir = temp_dir("test-daemon-corrupt");
    let ckpt = dir.join("checkpoint.bin");
    let garbage = b"CORRCKPT\x02\x00\x00\x00 this is not bincode".to_vec();
    std::fs::write(&ckpt, &garbage).unwrap();
    let domain = Domain::new(name).unwrap();
    let (offline, first_aligned) = offline_exp36();

    let (first, report) = first_aligned_bias(&domain, &ckpt, first_aligned + 50);
    assert!(report.warm_started_from.is_none());
    assert_eq!(report.warnings.len(), 1, "{:?}", report.warnings);
    let w = &report.warnings[0];
    assert!(
        w.contains("corrupt checkpoint") && w.contains("cold start"),
        "{w}"
    );
    let aside = dir.join("checkpoint.bin.corrupt-1");
    assert!(w.contains(&aside.display().to_string()), "{w}");
    assert_eq!(std::fs::read(&aside).unwrap(), garbage, "kept aside as is");

    // Cold start: exactly the offline run's bias at alignment (configured rest-mean prior).
    let cold = offline[first_aligned];
    assert_eq!(first.imu_seq, first_aligned as u64);
    assert_eq!(first.gyro_bias_rad_s, cold.gyro_bias_rad_s);
    assert_eq!(first.gyro_bias_sd_rad_s, cold.gyro_bias_sd_rad_s);
    // And a valid checkpoint replaced the corrupt one.
    let cp = checkpoint::load(&ckpt).expect("new checkpoint");
    assert_eq!(cp.t_s, offline[first_aligned + 49].t_s);

    cleanup_domain(name);
}
