//! A logger follows a restarted producer's new stream (issue 10, finding 4).
//!
//! One daemon test per binary: a test binary that starts several daemons one after another
//! sometimes leaves a later daemon without the producer's connection (see
//! `one_daemon_at_a_time`; iceoryx2 0.10, seen on the unmodified `daemon_checkpoint` too).

mod daemon_common;

use corridor_client::record::{RecordOptions, Recorder};
use corridor_client::{Delivery, Domain, Subscriber};
use corridor_shared::wire::AttitudeSample;
use daemon_common::*;
use std::sync::atomic::AtomicBool;

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
        // The recording ends on this idle time after the second stream (2 s was short for a new
        // stream's first attitude on a loaded machine).
        idle_timeout: std::time::Duration::from_secs(5),
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
    let watch = Subscriber::<AttitudeSample>::open(&domain, "test-robust-watch", WAIT).unwrap();
    let rows = exp36_rows();
    // Two lives of a producer: each sends its part and its end-of-stream marker.
    let first = produce(
        &domain,
        "test-replay",
        Delivery::Lossless,
        rows[..3000].to_vec(),
        true,
    );
    // Each producer stays alive until the daemon has taken its stream (see `Produced`).
    until_end(&watch, |a| a.flags);
    let s1 = first.join();
    let second = produce(
        &domain,
        "test-replay",
        Delivery::Lossless,
        rows[3000..6000].to_vec(),
        true,
    );
    until_end(&watch, |a| a.flags);
    let s2 = second.join();
    let got = logger.join().unwrap();
    daemon.stop();
    assert_eq!((s1.imu_sent, s2.imu_sent), (3001, 3001));
    assert_eq!(got.streams_ended, 2);
    assert_eq!(got.attitude_rows, 6000, "{got:?}");
    cleanup_domain(name);
}
