//! A checkpoint the daemon cannot write (its directory is a file): the daemon goes on, tries
//! again at every period, and says the failure once, not once a period (a review of long runs
//! found 2,880 copies a day in its report). One test binary a scenario (see
//! `daemon_checkpoint.rs`).

mod daemon_common;

use corridor_client::{Delivery, Domain, Subscriber};
use corridor_shared::wire::BiasSample;
use daemon_common::*;
use std::time::Duration;

#[test]
fn an_unwritable_checkpoint_is_said_once() {
    let _one = one_daemon_at_a_time();
    let name = "test_daemon_ckpt_unwritable";
    cleanup_domain(name);
    let dir = temp_dir("test-daemon-ckpt-unwritable");
    let not_a_dir = dir.join("a-file");
    std::fs::write(&not_a_dir, "").unwrap();
    let domain = Domain::new(name).unwrap();
    let mut dcfg = daemon_config(&domain, Delivery::Lossless);
    dcfg.checkpoint = Some(not_a_dir.join("checkpoint.bin"));
    dcfg.checkpoint_period = Duration::from_millis(2);
    let daemon = Running::start(dcfg);
    let bias = Subscriber::<BiasSample>::open(&domain, "test-bias", WAIT).unwrap();
    let producer = produce(
        &domain,
        "test-replay",
        Delivery::Lossless,
        exp36_rows(),
        true,
    );
    let _ = until_end(&bias, |b| b.flags);
    producer.join();
    drop(bias);
    let report = daemon.stop();
    assert_eq!(report.checkpoints_saved, 0);
    // The cold start's unreadable file, and the failed save once (hundreds of tries).
    let saves = report
        .warnings
        .iter()
        .filter(|w| w.contains("cannot create checkpoint"))
        .count();
    assert_eq!(
        (report.warnings.len(), saves),
        (2, 1),
        "{:?}",
        report.warnings
    );
    // A directory that is not there is said at start, before any stream (it was said after the
    // first stream had ended: `corridor serve --config configs/service.toml` on a machine
    // without /var/lib/corridor, a review).
    let mut dcfg = daemon_config(&domain, Delivery::Lossless);
    dcfg.checkpoint = Some(dir.join("not-there").join("checkpoint.bin"));
    let report = Running::start(dcfg).stop();
    assert_eq!(report.checkpoints_saved, 0);
    assert!(
        report.warnings.len() == 1
            && report.warnings[0].contains("not-there/checkpoint.bin: cannot create checkpoint"),
        "{:?}",
        report.warnings
    );
}
