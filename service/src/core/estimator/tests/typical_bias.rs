//! The unit's typical gyro bias (`alignment.typical_gyro_bias_rad_s`): where a start without a
//! rest begins; nothing where a rest measured the bias, or with the prior switched off.

use super::*;
use corridor_shared::config::{BiasPrior, Positive, TypicalGyroBias};

const TYPICAL: [f64; 3] = [0.0013, -0.0022, 0.0049];
const TYPICAL_SD: f64 = 0.004;

fn with_typical(prior: BiasPrior) -> Config {
    let mut cfg = Config::default();
    cfg.alignment.gyro_bias_prior = prior;
    cfg.alignment.typical_gyro_bias = Some(TypicalGyroBias {
        rad_s: TYPICAL,
        sd_rad_s: Positive::new("test", TYPICAL_SD).unwrap(),
    });
    cfg
}

/// 0.2 s of stance (shorter than a rest), then a push: the filter aligns on that stance.
fn start_without_rest(est: &mut Estimator, gyro: [f64; 3]) -> Estimate {
    let t = feed(est, 0.0, 40, gyro, [0.0, 0.0, 9.81]);
    let e = *est
        .step(&ImuInput {
            t_s: t,
            gyro_rad_s: gyro,
            accel_m_s2: [30.0, 0.0, 9.81],
        })
        .unwrap();
    assert!(est.counters().started_without_rest);
    e
}

#[test]
fn a_start_without_a_rest_begins_at_the_typical_bias_with_its_sigma() {
    let mut est = Estimator::new(with_typical(BiasPrior::RestMean), HeadingAid::None);
    let e = start_without_rest(&mut est, [0.004, -0.002, 0.006]);
    assert_eq!(e.gyro_bias_rad_s, TYPICAL);
    let p = est.bias_state().unwrap().gyro_bias_cov;
    // (The bias random walk over the one step since has widened it by a hair.)
    for (k, row) in p.iter().enumerate() {
        assert!(
            (row[k].sqrt() / TYPICAL_SD - 1.0).abs() < 1e-4,
            "axis {k}: {}",
            row[k]
        );
    }
}

/// A rest is the measurement of now: it is fused with the wide prior about zero as without a
/// typical bias, not with the typical bias (which pulled a swaying rest's mean towards this
/// unit's usual value; wrong for another unit, or a bias that moved).
#[test]
fn a_rest_is_not_fused_with_the_typical_bias() {
    let bias = [0.004, -0.002, 0.009];
    let plain = rest_then_move(
        &mut Estimator::new(Config::default(), HeadingAid::None),
        bias,
    );
    let typical = rest_then_move(
        &mut Estimator::new(with_typical(BiasPrior::RestMean), HeadingAid::None),
        bias,
    );
    assert_eq!(typical.gyro_bias_rad_s, plain.gyro_bias_rad_s);
    // (and that is the rest's mean, nearly whole)
    assert!((typical.gyro_bias_rad_s[2] - bias[2]).abs() < 1e-4);
}

#[test]
fn without_the_rest_mean_prior_the_typical_bias_is_not_used() {
    let mut est = Estimator::new(with_typical(BiasPrior::None), HeadingAid::None);
    let e = start_without_rest(&mut est, [0.004, -0.002, 0.006]);
    assert_eq!(e.gyro_bias_rad_s, [0.0; 3]);
    let mut est = Estimator::new(with_typical(BiasPrior::None), HeadingAid::None);
    let e = rest_then_move(&mut est, [0.004, -0.002, 0.006]);
    assert_eq!(e.gyro_bias_rad_s, [0.0; 3]);
}
