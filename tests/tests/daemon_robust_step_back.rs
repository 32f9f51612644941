//! A stream whose clock is set back by 0.3 s mid-stream and runs on from there (a host clock
//! stepped back by NTP). Before, the daemon refused the 60 samples up to the old time (and
//! published nothing for them), then integrated one step across the motion they carried. Now
//! the sample after the step is refused, the next one runs on from it, and the rates running on
//! across the step make it the new time base: one sample refused, the bias bit-identical to the
//! estimator fed the same samples, and the periodic bias output (paced by sensor time, which
//! went back) without a pause.
//!
//! One daemon test per binary (see `one_daemon_at_a_time`).

mod daemon_common;

use corridor_client::{Delivery, Domain, Subscriber};
use corridor_service::core::{Estimator, ImuInput};
use corridor_service::runner::heading_aid;
use corridor_shared::wire::BiasSample;
use daemon_common::*;

#[test]
fn a_clock_set_back_mid_stream_costs_one_sample() {
    let _one = one_daemon_at_a_time();
    let name = "test_robust_daemon_step_back";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let dcfg = daemon_config(&domain, Delivery::Lossless);
    let bias_period_s = dcfg.bias_period_s;
    let daemon = Running::start(dcfg);
    let bias = Subscriber::<BiasSample>::open(&domain, "test-step-back-bias", WAIT).unwrap();
    let mut rows = exp36_rows();
    rows.truncate(4000); // 20 s
    for r in &mut rows[2500..] {
        r.t_s -= 0.3;
    }
    let producer = produce(
        &domain,
        "test-step-back",
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
    for r in &rows {
        let _ = est.step(&ImuInput {
            t_s: r.t_s,
            gyro_rad_s: r.gyro_rad_s,
            accel_m_s2: r.accel_m_s2,
        });
    }
    let c = est.counters();
    assert_eq!(
        (c.samples, c.rejected_time, c.clock_steps_back),
        (3999, 1, 1)
    );
    let last = got.last().expect("bias samples");
    assert_eq!(last.gyro_bias_rad_s, est.last_estimate().gyro_bias_rad_s);
    let d = report.diagnostics;
    assert_eq!((d.accepted, d.rejected_time), (3999, 1), "{d:?}");
    // The bias output goes back with the stamps once, and runs on without a pause: counted in
    // IMU samples (the stamps cannot show a pause that spans the step).
    let steps: Vec<f64> = got.windows(2).map(|w| w[1].t_s - w[0].t_s).collect();
    assert_eq!(steps.iter().filter(|&&dt| dt < 0.0).count(), 1, "{steps:?}");
    let longest = got
        .windows(2)
        .map(|w| w[1].imu_seq.saturating_sub(w[0].imu_seq))
        .max()
        .unwrap();
    let period = (bias_period_s * 200.0).round() as u64;
    assert!(
        longest <= period + 2,
        "{longest} IMU samples without a bias sample at a period of {period}"
    );
    cleanup_domain(name);
}
