//! Samples missing at the head of a stream are counted (issue 10, finding 4).
//!
//! One daemon test per binary: a test binary that starts several daemons one after another
//! sometimes leaves a later daemon without the producer's connection (see
//! `one_daemon_at_a_time`; iceoryx2 0.10, seen on the unmodified `daemon_checkpoint` too).

mod daemon_common;

use corridor_client::{Delivery, Domain, Producer, Subscriber};
use corridor_shared::wire::{AttitudeSample, ImuSample};
use daemon_common::*;

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
    // The producer stays alive until both streams were taken (see `Produced`).
    let (release, released) = std::sync::mpsc::channel::<()>();
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
            // Stream 3 is its end marker alone, at 2452 (2402..2452, its data, all lost): the
            // marker at a stream's head counts what was numbered before it too (a review: it
            // was counted nowhere).
            p.send_imu_raw(ImuSample {
                seq: 2452,
                flags: corridor_shared::wire::FLAG_END_OF_STREAM,
                t_s: f64::NAN,
                temp_c: f64::NAN,
                ..ImuSample::default()
            })
            .unwrap();
            let _ = released.recv_timeout(WAIT);
            p.stats()
        })
    };
    for _ in 0..3 {
        let _ = until_end(&attitude, |a| a.flags);
    }
    let _ = release.send(());
    let stats = producer.join().unwrap();
    let report = daemon.stop();
    let d = report.diagnostics;
    assert_eq!(report.head_missing, 300);
    // The diagnostics on the wire carry the same count.
    assert_eq!(d.head_missing, 300);
    assert_eq!(d.seq_gaps, 100 + 50);
    // What the producer numbered = what the daemon received + what it counts as missing.
    let numbered = 2000 + 3 + 300 + 100 + 50;
    assert_eq!(stats.imu_sent, 2003);
    assert_eq!(d.received + report.head_missing + d.seq_gaps, numbered);
    cleanup_domain(name);
}
