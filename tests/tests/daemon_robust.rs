//! The daemon never publishes or checkpoints garbage (issue 10, finding 2). In its own test
//! binary: a daemon test binary that starts several daemons one after another sometimes leaves a
//! later daemon without the producer's connection (see `one_daemon_at_a_time`).

mod daemon_common;

use corridor_client::record::{RecordOptions, Recorder};
use corridor_client::{Delivery, Domain, Producer, Subscriber};
use corridor_service::checkpoint;
use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::imu_csv::{ImuCsvOptions, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::wire::{AttitudeSample, BiasSample, ImuSample};
use daemon_common::*;
use std::sync::atomic::AtomicBool;

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
    let wide = corridor_shared::sensor::SensorFile {
        max_accel_m_s2: Some(1e301),
        max_gyro_rad_s: Some(1e301),
        ..Default::default()
    }
    .validate()
    .unwrap();
    for (limits, accel, gyro) in [(None, 1e30, 1e300), (Some(wide), 1e4, 0.0)] {
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
        producer.join().unwrap();
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

#[test]
fn a_consumer_that_stops_reading_does_not_stall_the_others() {
    // Before: in lossless mode the daemon's attitude publisher waited forever on the full buffer
    // of a consumer that stopped reading (or was killed): the other consumer froze, and the
    // producer with it.
    let _one = one_daemon_at_a_time();
    let name = "test_robust_daemon_stall";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let mut dcfg = daemon_config(&domain, Delivery::Lossless);
    dcfg.stall_timeout = std::time::Duration::from_millis(200);
    let daemon = Running::start(dcfg);
    let reader = Subscriber::<AttitudeSample>::open(&domain, "test-robust-reader", WAIT).unwrap();
    let stuck = Subscriber::<AttitudeSample>::open(&domain, "test-robust-stuck", WAIT).unwrap();
    // Attach both receiving ends; then `stuck` never reads again while the stream runs.
    assert!(reader.try_recv().unwrap().is_none() && stuck.try_recv().unwrap().is_none());
    let rows = exp36_rows();
    let sent = rows.len();
    let producer = produce(&domain, "test-replay", Delivery::Lossless, rows, true);
    let got = until_end(&reader, |a| a.flags);
    let stats = producer.join().unwrap();
    let mut drained = 0u64;
    while stuck.try_recv().unwrap().is_some() {
        drained += 1;
    }
    let report = daemon.stop();
    // The reader got every sample and the end marker.
    assert_eq!(got.len(), sent + 1);
    assert_eq!(reader.missed(), 0);
    let stalls = report.stalls[0];
    assert_eq!(stalls.stalled_consumers, 1, "{:?}", report.stalls);
    // Every attitude message reached the stuck consumer's buffer or is counted as discarded.
    assert_eq!(
        drained + stalls.discarded,
        got.len() as u64,
        "drained {drained}, discarded {}, producer {stats:?}",
        stalls.discarded
    );
    cleanup_domain(name);
}

#[test]
fn a_logger_follows_the_new_stream_of_a_restarted_producer() {
    // Before: the logger stopped at the first end-of-stream marker and the restarted producer's
    // stream went unlogged.
    let _one = one_daemon_at_a_time();
    let name = "test_robust_daemon_follow";
    cleanup_domain(name);
    let dir = temp_dir("test-robust-daemon-follow");
    let domain = Domain::new(name).unwrap();
    let daemon = Running::start(daemon_config(&domain, Delivery::Lossless));
    let opts = RecordOptions {
        node_name: "test-robust-log".into(),
        wait: WAIT,
        idle_timeout: std::time::Duration::from_secs(2),
        idle_before_first: true,
        poll: std::time::Duration::from_millis(50),
    };
    // iceoryx2 ports are `!Send`: the recorder is opened on its own thread.
    let (ready_tx, ready) = std::sync::mpsc::channel();
    let logger = {
        let (domain, dir) = (domain.clone(), dir.to_path_buf());
        std::thread::spawn(move || {
            let recorder = Recorder::open(&domain, &dir, &opts)
                .unwrap()
                .following_new_streams();
            ready_tx.send(()).unwrap();
            recorder.run(&AtomicBool::new(false)).unwrap()
        })
    };
    ready.recv().unwrap();
    let rows = exp36_rows();
    // Two lives of a producer: each sends its part and its end-of-stream marker.
    let first = produce(
        &domain,
        "test-replay",
        Delivery::Lossless,
        rows[..3000].to_vec(),
        true,
    );
    let s1 = first.join().unwrap();
    let second = produce(
        &domain,
        "test-replay",
        Delivery::Lossless,
        rows[3000..6000].to_vec(),
        true,
    );
    let s2 = second.join().unwrap();
    let got = logger.join().unwrap();
    daemon.stop();
    assert_eq!((s1.imu_sent, s2.imu_sent), (3001, 3001));
    assert_eq!(got.streams_ended, 2);
    assert_eq!(got.attitude_rows, 6000, "{got:?}");
    cleanup_domain(name);
}

#[test]
fn samples_missing_at_the_head_of_a_stream_are_counted() {
    // Before: samples lost before the daemon's first read of a producer (a live replay at full
    // speed lost its first 15 443) or at the head of a later stream were counted nowhere:
    // `seq_gaps` only counted gaps between two received samples.
    let _one = one_daemon_at_a_time();
    let name = "test_robust_daemon_head";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let daemon = Running::start(daemon_config(&domain, Delivery::Lossless));
    let attitude = Subscriber::<AttitudeSample>::open(&domain, "test-robust-att", WAIT).unwrap();
    let rows = exp36_rows();
    let producer = {
        let (domain, rows) = (domain.clone(), rows[..2000].to_vec());
        std::thread::spawn(move || {
            let mut p = Producer::new(&domain, "test-robust-replay", Delivery::Lossless).unwrap();
            p.wait_for_daemon(WAIT).unwrap();
            // Stream 1 starts at seq 300 (0..300 "lost before the daemon read"): 1000 samples,
            // marker at 1300. Stream 2 starts at 1401 (1301..1401 lost at its head).
            let mut seq = 300;
            for (k, r) in rows.iter().enumerate() {
                if k == 1000 {
                    p.finish().unwrap();
                    seq += 101;
                }
                let mut s = ImuSample::from(r);
                s.seq = seq;
                p.send_imu_raw(s).unwrap();
                seq += 1;
            }
            p.finish().unwrap();
            p.stats()
        })
    };
    let _ = until_end(&attitude, |a| a.flags);
    let _ = until_end(&attitude, |a| a.flags);
    let stats = producer.join().unwrap();
    let report = daemon.stop();
    let d = report.diagnostics;
    assert_eq!(report.head_missing, 300);
    assert_eq!(d.seq_gaps, 100);
    // What the producer numbered = what the daemon received + what it counts as missing.
    let numbered = 2000 + 2 + 300 + 100;
    assert_eq!(stats.imu_sent, 2002);
    assert_eq!(d.received + report.head_missing + d.seq_gaps, numbered);
    cleanup_domain(name);
}
