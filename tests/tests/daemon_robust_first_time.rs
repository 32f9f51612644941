//! A stream whose very first sample carries a bad time stamp (a driver that sends garbage
//! first). Before, that time became the time base and the daemon refused every later sample as
//! "not increasing", for the life of the stream. Now the two samples after it, which follow each
//! other, replace it: the daemon drops the first sample after the fact, counts it, and runs as
//! on the stream without it (bias bit-identical to the estimator fed the same samples), with
//! its periodic bias output (paced by sensor time, which the dropped 1e9 s had stopped).
//!
//! The same stream carries a stamp glitched 0.99 s ahead mid-stream (within `sensor.max_dt_s`,
//! so it looks like a gap). Before, the 180 good samples after it were refused as "not
//! increasing" and the gap started a new segment; now the next sample, which goes back and
//! follows the time before it, shows it to be a glitch, and the daemon drops it after the fact.
//!
//! A second stamp, glitched 0.1 s ahead (a bridged gap), lies on a footfall: the daemon
//! publishes that footfall's nav sample for the glitched sample, and, once it is dropped, again
//! for the real footfall (before, the dropped sample's stance count was taken for the real one
//! and the real footfall was never published).
//!
//! And three stamps 975 s ahead in a row (a jump that the second confirms): the next good time
//! drops all three after the fact. The outputs of each sample that drops glitched ones carry
//! `FLAG_RETRACTS`.
//!
//! One daemon test per binary (see `one_daemon_at_a_time`).

mod daemon_common;

use corridor_client::{Delivery, Domain, Subscriber};
use corridor_service::core::{Estimator, ImuInput};
use corridor_service::runner::heading_aid;
use corridor_shared::imu_csv::ImuRow;
use corridor_shared::wire::{BiasSample, FLAG_RETRACTS, NavSample};
use daemon_common::*;

#[test]
fn a_bad_first_time_stamp_costs_two_samples_and_each_glitched_one_costs_one() {
    let _one = one_daemon_at_a_time();
    let name = "test_robust_daemon_first_time";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let dcfg = daemon_config(&domain, Delivery::Lossless);
    let bias_period_s = dcfg.bias_period_s;
    let daemon = Running::start(dcfg);
    let bias = Subscriber::<BiasSample>::open(&domain, "test-first-time-bias", WAIT).unwrap();
    let nav = Subscriber::<NavSample>::open(&domain, "test-first-time-nav", WAIT).unwrap();
    let mut rows = exp36_rows();
    rows.truncate(4000); // 20 s
    rows[0].t_s = 1e9;
    let glitch_t_s = rows[2000].t_s + 0.99;
    rows[2000].t_s = glitch_t_s;
    // Three stamps 975 s ahead (a jump the second confirms): the next good time drops them.
    for r in &mut rows[2500..2503] {
        r.t_s += 975.0;
    }
    let cfg = config();
    let run = |rows: &[ImuRow]| {
        let mut est = Estimator::new(cfg.clone(), heading_aid(&cfg, None).unwrap());
        let stances: Vec<u64> = rows
            .iter()
            .map(|r| {
                let s = ImuInput {
                    t_s: r.t_s,
                    gyro_rad_s: r.gyro_rad_s,
                    accel_m_s2: r.accel_m_s2,
                };
                let _ = est.step(&s);
                est.counters().stances
            })
            .collect();
        (est, stances)
    };
    // The first footfall after 15 s, glitched 0.1 s ahead.
    let (_, stances) = run(&rows);
    let footfall = (3000..rows.len())
        .find(|&k| stances[k] > stances[k - 1])
        .expect("a footfall after 15 s");
    let footfall_stance = stances[footfall];
    let footfall_glitch_t_s = rows[footfall].t_s + 0.1;
    rows[footfall].t_s = footfall_glitch_t_s;
    let producer = produce(
        &domain,
        "test-first-time",
        Delivery::Lossless,
        rows.clone(),
        true,
    );
    let got = until_end(&bias, |b| b.flags);
    let navs = until_end(&nav, |n| n.flags);
    producer.join();
    drop((bias, nav));
    let report = daemon.stop();

    // The estimator fed the same samples, in-process.
    let (est, _) = run(&rows);
    let c = est.counters();
    // The second sample refused (not increasing), the first and the two glitched ones dropped
    // after the fact, and the run of three (the first refused as a jump, two dropped).
    assert_eq!(
        (c.samples, c.rejected_time, c.rejected_time_jump, c.gaps),
        (3993, 1, 6, 0)
    );
    // The outputs of the samples that dropped glitched ones say so (`FLAG_RETRACTS`): the bias
    // is published at each (its pacing starts again there).
    let retracting: Vec<f64> = got
        .iter()
        .filter(|b| b.flags & FLAG_RETRACTS != 0)
        .map(|b| b.t_s)
        .collect();
    assert_eq!(
        retracting,
        [rows[2001].t_s, rows[2503].t_s, rows[footfall + 1].t_s],
        "{retracting:?}"
    );
    // What they retract: the outputs before them with a later time.
    assert!(got.iter().any(|b| b.t_s > 975.0));
    // The footfall's nav sample: the glitched sample's (it began the stance too), then the real
    // one's.
    let at_footfall: Vec<f64> = navs
        .iter()
        .filter(|n| n.stance == footfall_stance)
        .map(|n| n.t_s)
        .collect();
    assert_eq!(
        at_footfall.first(),
        Some(&footfall_glitch_t_s),
        "{at_footfall:?}"
    );
    assert!(
        at_footfall.iter().any(|&t| t < footfall_glitch_t_s),
        "the real footfall was not published: {at_footfall:?}"
    );
    let last = got.last().expect("bias samples");
    assert_eq!(last.gyro_bias_rad_s, est.last_estimate().gyro_bias_rad_s);
    // The periodic bias output runs from the start of the stream, the first one within a period
    // of it (before: after the one published for the dropped sample at 1e9 s, nothing until
    // the alignment, then only at heading observations), and on after the glitch (a bias sample
    // was published for it; paced by its time, the output would pause for a period).
    // Its pacing starts again at the sample that dropped it.
    assert!(got.iter().any(|b| b.t_s == glitch_t_s));
    assert!(got.iter().any(|b| b.t_s == rows[2001].t_s));
    let times: Vec<f64> = got
        .iter()
        .map(|b| b.t_s)
        .filter(|&t| t < 900.0 && t != glitch_t_s) // not the dropped ones
        .collect();
    let longest = times
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(times[0], f64::max);
    assert!(
        longest <= bias_period_s + 0.01,
        "{longest} s without a bias sample at a period of {bias_period_s} s"
    );
    let d = report.diagnostics;
    assert_eq!((d.accepted, d.rejected_time), (3993, 1), "{d:?}");
    cleanup_domain(name);
}
