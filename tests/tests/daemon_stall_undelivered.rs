//! A lossless consumer that stops reading, alone on its output: what the daemon discards for it
//! is counted once, as discarded for a stalled consumer, not as undelivered as well.
//!
//! One daemon test per binary (see `daemon_robust_stall.rs`).

mod daemon_common;

use corridor_client::{Delivery, Domain, Subscriber};
use corridor_shared::wire::{AttitudeSample, BiasSample};
use daemon_common::*;

#[test]
fn a_sample_discarded_for_the_only_consumer_is_not_also_undelivered() {
    // iceoryx2 0.10 reports no receiver for a sample whose only receiver's buffer was full and
    // had it discarded (the stall guard's decision): the daemon counted it in `undelivered` too,
    // which `corridor status` shows as outputs published while none was subscribed (a review).
    let _one = one_daemon_at_a_time();
    let name = "test_stall_undelivered";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let mut dcfg = daemon_config(&domain, Delivery::Lossless);
    dcfg.stall_timeout = std::time::Duration::from_millis(200);
    let daemon = Running::start(dcfg);
    // The end of the stream is read on the bias output; the attitude output has one consumer,
    // which never reads after attaching; nav and diagnostics have none.
    let bias = Subscriber::<BiasSample>::open(&domain, "test-bias-reader", WAIT).unwrap();
    let stuck = Subscriber::<AttitudeSample>::open(&domain, "test-stuck", WAIT).unwrap();
    assert!(bias.try_recv().unwrap().is_none() && stuck.try_recv().unwrap().is_none());
    let producer = produce(
        &domain,
        "test-replay",
        Delivery::Lossless,
        exp36_rows(),
        true,
    );
    until_end(&bias, |b| b.flags);
    producer.join();
    let report = daemon.stop();
    let stalls = report.stalls[0];
    assert_eq!(stalls.stalled_consumers, 1, "{:?}", report.stalls);
    assert!(stalls.discarded > 1000, "{:?}", report.stalls);
    // What reached nobody is the nav and diagnostics outputs' (no subscriber), not the
    // attitude samples discarded for the stuck consumer.
    let [_, _, nav, diagnostics] = report.published;
    assert!(
        report.diagnostics.undelivered <= nav + diagnostics,
        "undelivered {}, nav {nav}, diagnostics {diagnostics}, attitude discarded {}",
        report.diagnostics.undelivered,
        stalls.discarded
    );
    drop((bias, stuck));
    cleanup_domain(name);
}
