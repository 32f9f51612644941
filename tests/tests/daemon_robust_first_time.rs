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
//! One daemon test per binary (see `one_daemon_at_a_time`).

mod daemon_common;

use corridor_client::{Delivery, Domain, Subscriber};
use corridor_service::core::{Estimator, ImuInput};
use corridor_service::runner::heading_aid;
use corridor_shared::wire::BiasSample;
use daemon_common::*;

#[test]
fn a_bad_first_time_stamp_costs_two_samples_and_a_glitched_one_costs_one() {
    let _one = one_daemon_at_a_time();
    let name = "test_robust_daemon_first_time";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let dcfg = daemon_config(&domain, Delivery::Lossless);
    let bias_period_s = dcfg.bias_period_s;
    let daemon = Running::start(dcfg);
    let bias = Subscriber::<BiasSample>::open(&domain, "test-first-time-bias", WAIT).unwrap();
    let mut rows = exp36_rows();
    rows.truncate(4000); // 20 s
    rows[0].t_s = 1e9;
    let glitch_t_s = rows[2000].t_s + 0.99;
    rows[2000].t_s = glitch_t_s;
    let producer = produce(
        &domain,
        "test-first-time",
        Delivery::Lossless,
        rows.clone(),
        true,
    );
    let got = until_end(&bias, |b| b.flags);
    producer.join();
    drop(bias);
    let report = daemon.stop();

    // The estimator fed the same samples, in-process.
    let cfg = config();
    let mut est = Estimator::new(cfg.clone(), heading_aid(&cfg, None).unwrap());
    let mut refused = 0;
    for r in &rows {
        let s = ImuInput {
            t_s: r.t_s,
            gyro_rad_s: r.gyro_rad_s,
            accel_m_s2: r.accel_m_s2,
        };
        refused += usize::from(est.step(&s).is_err());
    }
    let c = est.counters();
    // The second sample refused (not increasing), the first and the glitched one dropped after
    // the fact.
    assert_eq!(refused, 1);
    assert_eq!(
        (c.samples, c.rejected_time, c.rejected_time_jump, c.gaps),
        (3997, 1, 2, 0)
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
        .filter(|&t| t < 1e8 && t != glitch_t_s)
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
    assert_eq!((d.accepted, d.rejected_time), (3997, 1), "{d:?}");
    cleanup_domain(name);
}
