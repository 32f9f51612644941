//! Checkpoint and warm start of the daemon (in-process): a daemon replays exp36 and is
//! stopped; a second daemon with the same checkpoint file publishes, at the end of its
//! alignment, the saved bias with the fresh rest fused into it (not the rest-mean prior a cold
//! start gives), exactly as the offline estimator warm-started from the same state. The corrupt-file case
//! is in `daemon_checkpoint_corrupt.rs`: one test binary a scenario, so that no more than the two
//! daemons this scenario needs ever run in one process (see docs/known-issues.md).

mod daemon_common;

use corridor_client::{Delivery, Domain, Subscriber};
use corridor_service::checkpoint;
use corridor_shared::wire::{BiasSample, FLAG_END_OF_STREAM};
use daemon_common::*;

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
    producer.join();
    drop(bias);
    let report = daemon.stop();
    assert!(report.warm_started_from.is_none(), "first start is cold");
    // ... and its only stream is not one warm-started from an earlier stream's bias.
    assert_eq!(report.streams_warm_started, 0);
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
    // The offline estimator warm-started from the saved state over the same rows: the same
    // bias and σ (the saved state with the fresh rest fused in, so σ below the saved one).
    let warm = offline_exp36_with(|est| {
        est.set_warm_start(corridor_service::core::WarmStart {
            gyro_bias_rad_s: saved.gyro_bias_rad_s,
            gyro_bias_cov: saved.gyro_bias_cov,
        })
        .unwrap();
    })[first_aligned];
    assert!(
        max_abs_diff(first.gyro_bias_rad_s, warm.gyro_bias_rad_s) <= 1e-12,
        "first bias after alignment {:?}, offline warm start {:?}",
        first.gyro_bias_rad_s,
        warm.gyro_bias_rad_s
    );
    assert!(
        max_abs_diff(first.gyro_bias_rad_s, cold) > 1e-6,
        "the saved state counts, not only the rest"
    );
    for k in 0..3 {
        let sd = saved.gyro_bias_cov[k][k].sqrt();
        assert!(
            (first.gyro_bias_sd_rad_s[k] - warm.gyro_bias_sd_rad_s[k]).abs() <= 1e-12,
            "σ[{k}] {} vs offline {}",
            first.gyro_bias_sd_rad_s[k],
            warm.gyro_bias_sd_rad_s[k]
        );
        assert!(
            first.gyro_bias_sd_rad_s[k] < sd,
            "σ[{k}] below the saved {sd}"
        );
    }
    // The second life saved its own state over the first one.
    let resaved = checkpoint::load(&ckpt).unwrap();
    assert_eq!(resaved.t_s, offline[first_aligned + 399].t_s);

    cleanup_domain(name);
}
