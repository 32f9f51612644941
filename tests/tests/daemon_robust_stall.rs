//! Lossless without stalls (issue 10, finding 1).
//!
//! One daemon test per binary: a test binary that starts several daemons one after another
//! sometimes leaves a later daemon without the producer's connection (see
//! `one_daemon_at_a_time`; iceoryx2 0.10, seen on the unmodified `daemon_checkpoint` too).

mod daemon_common;

use corridor_client::{Delivery, Domain, Subscriber};
use corridor_shared::wire::AttitudeSample;
use daemon_common::*;

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
    // Long enough that the reading consumer (this thread) is never taken for stalled when the
    // machine is loaded; the stuck one costs this wait once.
    dcfg.stall_timeout = std::time::Duration::from_secs(3);
    let daemon = Running::start(dcfg);
    let reader = Subscriber::<AttitudeSample>::open(&domain, "test-robust-reader", WAIT).unwrap();
    let stuck = Subscriber::<AttitudeSample>::open(&domain, "test-robust-stuck", WAIT).unwrap();
    // Attach both receiving ends; then `stuck` never reads again while the stream runs.
    assert!(reader.try_recv().unwrap().is_none() && stuck.try_recv().unwrap().is_none());
    let rows = exp36_rows();
    let sent = rows.len();
    let producer = produce(&domain, "test-replay", Delivery::Lossless, rows, true);
    let got = until_end(&reader, |a| a.flags);
    let stats = producer.join();
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
