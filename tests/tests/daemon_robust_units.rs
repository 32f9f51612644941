//! A producer's stream in g instead of m/s² (no CSV reader and its units check in front of the
//! daemon): never aligned on, said, and counted in the report; the next stream, in m/s² but with
//! its accelerometer's scale 20 % low, aligns, and the scale is said once and counted.
//!
//! One daemon test per binary (see `daemon_robust_garbage.rs`).

mod daemon_common;

use corridor_client::{Delivery, Domain};
use corridor_shared::wire::{FLAG_END_OF_STREAM, phase};
use daemon_common::*;

#[test]
fn a_stream_in_g_is_never_aligned_on_and_the_report_says_so() {
    // Before: the daemon took the rest's 1 m/s² for gravity and estimated the walk an eighth
    // as long, with nothing said.
    let _one = one_daemon_at_a_time();
    let name = "test_robust_daemon_units";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let daemon = Running::start(daemon_config(&domain, Delivery::Lossless));
    let reader = AttitudeReader::start(&domain, 2);
    let in_g: Vec<_> = exp36_rows()
        .into_iter()
        .map(|mut r| {
            r.accel_m_s2 = r.accel_m_s2.map(|a| a / 9.80665);
            r
        })
        .collect();
    let n_g = in_g.len();
    let first = produce(&domain, "test-in-g", Delivery::Lossless, in_g, true);
    reader.wait_for_ends(1);
    first.join();
    // A scale error aligns (it reads gravity within the alignment's ±50 %), and is said at the
    // end of the rest it aligns on, once (`core/estimator/stance_force.rs`).
    let scaled: Vec<_> = exp36_rows()
        .into_iter()
        .map(|mut r| {
            r.accel_m_s2 = r.accel_m_s2.map(|a| a * 0.8);
            r
        })
        .collect();
    let second = produce(&domain, "test-scaled", Delivery::Lossless, scaled, true);
    let att = reader.join();
    second.join();
    let report = daemon.stop();
    let end = att
        .iter()
        .position(|a| a.flags & FLAG_END_OF_STREAM != 0)
        .unwrap();
    // Every sample of the stream in g published, then its end-of-stream message.
    assert_eq!(end, n_g);
    assert!(
        att[..=end].iter().all(|a| a.phase == phase::ALIGNING),
        "a stream in g was aligned on"
    );
    assert!(
        att[end + 1..].iter().any(|a| a.phase == phase::TRACKING),
        "the stream in m/s² after it did not align"
    );
    assert_eq!(report.specific_force_off_gravity, 1, "{report:?}");
    let scale: Vec<&String> = report
        .warnings
        .iter()
        .filter(|w| w.contains("scale or units look wrong"))
        .collect();
    assert_eq!(scale.len(), 1, "{:?}", report.warnings);
    assert!(
        scale[0].starts_with("stream 2 ")
            && scale[0].contains("the initial rest read a mean specific force of 7.860 m/s²")
            && scale[0].contains("wrong by -19.8 %"),
        "{}",
        scale[0]
    );
    // Every stance of the walk was a candidate first stance and was refused (exp36: 58).
    assert!(report.alignment_not_gravity > 20, "{report:?}");
    let said: Vec<&String> = report
        .warnings
        .iter()
        .filter(|w| w.contains("Not aligned on it"))
        .collect();
    assert_eq!(said.len(), 1, "{:?}", report.warnings);
    assert!(
        said[0].contains("a mean specific force of 1.00"),
        "{}",
        said[0]
    );
    cleanup_domain(name);
}
