//! The deferred covariance step ([`EskfNoise::covariance_step_s`]): when a sample's step waits,
//! that whatever changes or reads the covariance brings it up to date first, and that the
//! summed transition gives the per-sample propagation's covariance to first order.

use super::tests::{dense, extension_sets, filter_with};
use super::*;
use crate::core::rotation::from_euler_zyx;

const DT_S: f64 = 0.005;

/// A tilted filter estimating its bias, with its covariance step set to `step_s`.
fn filter(ext: Extensions, step_s: f64) -> Eskf {
    let mut f = filter_with(
        BiasStates::Estimated,
        from_euler_zyx(0.1, 0.2, 0.3),
        Vector3::new(0.01, 0.0, -0.01),
        0.01,
        0.01,
        ext,
    );
    f.noise.covariance_step_s = step_s;
    f
}

/// Sample `k` of a swing: the foot pitching at up to 6 rad/s and accelerating.
fn swing(k: usize) -> (Vector3<f64>, Vector3<f64>) {
    let t = k as f64 * DT_S;
    (
        Vector3::new(1.5 * (7.0 * t).sin(), 6.0 * (5.0 * t).cos(), 0.8),
        Vector3::new(8.0 * (6.0 * t).sin(), 1.0, 9.8 + 5.0 * (4.0 * t).cos()),
    )
}

/// One sample, as the estimator runs it: into the spare buffer, which becomes the filter.
fn step(f: &mut Eskf, spare: &mut Eskf, k: usize, covariance: CovarianceStep) {
    let (w, a) = swing(k);
    f.propagate_into(spare, &w, &a, DT_S, covariance);
    std::mem::swap(f, spare);
}

#[test]
fn a_swing_steps_its_covariance_once_per_interval() {
    // 0.02 s at 200 Hz: every fourth sample, whatever came before; `Now` at once.
    let mut f = filter(extension_sets()[1], 0.02);
    let mut spare = f.clone();
    let mut settled = Vec::new();
    for k in 0..10 {
        let c = if k == 5 {
            CovarianceStep::Now
        } else {
            CovarianceStep::MayDefer
        };
        step(&mut f, &mut spare, k, c);
        settled.push(f.covariance_settled());
    }
    let expected = [
        false, false, false, true, false, true, false, false, false, true,
    ];
    assert_eq!(settled, expected);
}

#[test]
fn a_zero_step_propagates_every_sample_to_the_bit() {
    for ext in extension_sets() {
        let (mut a, mut b) = (filter(ext, 0.0), filter(ext, 0.0));
        let (mut sa, mut sb) = (a.clone(), b.clone());
        for k in 0..7 {
            step(&mut a, &mut sa, k, CovarianceStep::MayDefer);
            step(&mut b, &mut sb, k, CovarianceStep::Now);
            assert!(a.covariance_settled());
        }
        assert_eq!(dense(&a), dense(&b));
    }
}

/// Each way of changing or reading the covariance, after three deferred samples, gives to the
/// bit what it gives after the same three samples propagated at once (the third with `Now`,
/// which applies the same summed transition to the same covariance).
#[test]
fn what_changes_the_covariance_brings_it_up_to_date_first() {
    type Op = fn(&mut Eskf);
    let ops: [(&str, Op); 15] = [
        ("zupt", |f| {
            f.zupt();
        }),
        ("implausible velocity", |f| {
            // A decision from the velocity's variance (the late footfall's replay).
            f.stance_velocity_implausible(&Vector3::zeros(), 0.01, 9.0);
        }),
        ("zero-rate update", |f| {
            let _ = f.zero_rate_update(
                &Vector3::new(0.01, 0.0, -0.01),
                &Vector3::new(0.0, 0.0, 9.81),
                &Vector3::repeat(1e-3),
            );
        }),
        ("relevel", |f| f.relevel(&Vector3::z(), 1e-4, 1e-4)),
        ("set heading variance", |f| f.set_heading_variance(0.01)),
        ("forget footprints", |f| f.forget_footprints()),
        ("stride direction", |f| {
            f.clone_footprint();
            f.p_m.x += 0.7;
            let _ = f.stride_direction_update(0.1, 0.05);
        }),
        ("heading update", |f| {
            f.heading_update(0.3, 0.05, &Vector3::x());
        }),
        ("clone footprint", |f| f.clone_footprint()),
        ("widen velocity", |f| f.widen_velocity(0.1)),
        ("rotate frame", |f| f.rotate_frame(0.4)),
        ("turn heading", |f| f.turn_heading(0.4, 0.1)),
        ("reset velocity", |f| f.reset_velocity(1.0)),
        ("gap", |f| f.widen_after_gap(2.0, 1.0)),
        ("set bias", |f| {
            f.set_gyro_bias(Vector3::zeros(), &Matrix3::identity())
        }),
    ];
    for ext in extension_sets() {
        for (name, op) in ops {
            let (mut a, mut b) = (filter(ext, 0.02), filter(ext, 0.02));
            let (mut sa, mut sb) = (a.clone(), b.clone());
            for k in 0..3 {
                step(&mut a, &mut sa, k, CovarianceStep::MayDefer);
                let c = if k == 2 {
                    CovarianceStep::Now
                } else {
                    CovarianceStep::MayDefer
                };
                step(&mut b, &mut sb, k, c);
            }
            assert!(!a.covariance_settled() && b.covariance_settled(), "{name}");
            op(&mut a);
            op(&mut b);
            assert!(a.covariance_settled(), "{name}");
            assert_eq!(dense(&a), dense(&b), "{name}");
            assert_eq!(a.nav_from_body, b.nav_from_body, "{name}");
            assert_eq!(a.gyro_bias_sd(), b.gyro_bias_sd(), "{name}");
            // The bias-error response waits and comes up to date with the covariance.
            assert_eq!(
                a.unabsorbed_bias_error(),
                b.unabsorbed_bias_error(),
                "{name}"
            );
        }
    }
}

/// The rotation a clipped gyro axis did not measure is process noise: while steps wait it is
/// added with theirs at the interval's end (onto the covariance the interval ends with), and
/// nothing is propagated early for it.
#[test]
fn a_clipped_rotation_waits_with_the_interval_s_noise() {
    for ext in extension_sets() {
        let (mut a, mut b, mut c) = (filter(ext, 0.02), filter(ext, 0.02), filter(ext, 0.02));
        let (mut sa, mut sb, mut sc) = (a.clone(), b.clone(), c.clone());
        let mut axis_nav = Vector3::zeros();
        for k in 0..4 {
            step(&mut a, &mut sa, k, CovarianceStep::MayDefer);
            step(&mut b, &mut sb, k, CovarianceStep::MayDefer);
            step(&mut c, &mut sc, k, CovarianceStep::MayDefer);
            if k == 1 {
                axis_nav = a.nav_from_body * Vector3::y();
                a.widen_attitude_about(&Vector3::y(), 1e-4);
                assert!(!a.covariance_settled());
            }
        }
        assert!(a.covariance_settled() && b.covariance_settled());
        // The same axis in the navigation frame, onto the interval's end.
        b.widen_attitude_about(&(b.nav_from_body.inverse() * axis_nav), 1e-4);
        let (pa, pb, pc) = (dense(&a), dense(&b), dense(&c));
        assert!((&pa - &pb).abs().max() <= 1e-18, "{pa} against {pb}");
        // Without it: the attitude's variance is the rotation's less (its trace, |axis| = 1).
        let added: f64 = (TH..TH + 3).map(|i| pa[(i, i)] - pc[(i, i)]).sum();
        assert!((added - 1e-4).abs() <= 1e-12, "{added}");
        // After a single waiting sample, the update that settles it has the rotation too.
        let (mut a, mut b) = (filter(ext, 0.02), filter(ext, 0.02));
        let (mut sa, mut sb) = (a.clone(), b.clone());
        step(&mut a, &mut sa, 0, CovarianceStep::MayDefer);
        step(&mut b, &mut sb, 0, CovarianceStep::Now);
        for f in [&mut a, &mut b] {
            f.widen_attitude_about(&Vector3::y(), 1e-4);
            f.zupt();
        }
        assert_eq!(dense(&a), dense(&b));
    }
}

#[test]
fn a_state_copy_carries_the_deferred_steps() {
    let mut a = filter(extension_sets()[2], 0.02);
    let mut spare = a.clone();
    for k in 0..2 {
        step(&mut a, &mut spare, k, CovarianceStep::MayDefer);
    }
    let mut b = filter(extension_sets()[2], 0.02);
    b.copy_state_from(&a);
    a.zupt();
    b.zupt();
    assert_eq!(dense(&a), dense(&b));
}

/// The summed transition against one step per sample over a swing of 0.5 s (25 intervals
/// of four samples), then a stance's velocity update. Measured: every variance within 0.37 %,
/// every correlation coefficient within 0.010 (of correlations up to 0.24): what the sum leaves
/// out, the products of two samples' blocks within an interval (`p←θ` and `v←b`, of order
/// dt²), as a step of 20 ms instead of 5 would. The bounds are about twice those; a block or
/// a noise term summed wrongly is off by far more (the velocity noise's share in the position
/// left out: the position variance 4.5 % low).
#[test]
fn the_deferred_covariance_is_the_per_sample_one_to_first_order() {
    for ext in extension_sets() {
        let (mut a, mut b) = (filter(ext, 0.02), filter(ext, 0.0));
        let (mut sa, mut sb) = (a.clone(), b.clone());
        for k in 0..100 {
            step(&mut a, &mut sa, k, CovarianceStep::MayDefer);
            step(&mut b, &mut sb, k, CovarianceStep::MayDefer);
        }
        assert!(a.covariance_settled(), "100 samples are 25 whole intervals");
        let (pa, pb) = (dense(&a), dense(&b));
        let n = a.dim();
        for i in 0..n {
            let (va, vb) = (pa[(i, i)], pb[(i, i)]);
            assert!((va - vb).abs() <= 5e-3 * vb, "state {i}: {va} against {vb}");
        }
        // Correlations too: each element against the σ of its two states.
        for i in 0..n {
            for j in 0..i {
                let scale = (pb[(i, i)] * pb[(j, j)]).sqrt();
                let d = (pa[(i, j)] - pb[(i, j)]).abs();
                assert!(
                    d <= 2e-2 * scale,
                    "({i}, {j}): {} against {}",
                    pa[(i, j)],
                    pb[(i, j)]
                );
            }
        }
        // Not the same computation: the sum differs from the product in the last digits.
        assert_ne!(pa, pb);
        a.zupt();
        b.zupt();
        let (ba, bb) = (a.gyro_bias_sd(), b.gyro_bias_sd());
        assert!((ba - bb).norm() <= 1e-3 * bb.norm(), "{ba} against {bb}");
    }
}

/// With no specific force the transition's blocks have no products (p←v and θ←b are all that
/// moves, and neither feeds the other), so the summed transition is the product of the
/// samples': the position, velocity and bias covariance and the bias-error response come out
/// as the per-sample ones to rounding, which checks the noise terms of a summed interval (the
/// velocity noise's share in the position, the bias random walk) exactly, for intervals of
/// two, three and four samples. (The attitude's is not exact even so: the bias random walk's
/// share in it, through the later samples' θ←b, is left out, as the gyro noise's share in the
/// velocity is; both of order dt².)
#[test]
fn without_specific_force_the_summed_step_is_exact() {
    // Static extensions only: the bias-rate states' b←d would feed θ←b.
    for ext in &extension_sets()[..2] {
        let (mut a, mut b) = (filter(*ext, 0.02), filter(*ext, 0.0));
        let (mut sa, mut sb) = (a.clone(), b.clone());
        // Some velocity and position variance to carry, and correlations.
        for f in [&mut a, &mut b] {
            f.widen_velocity(0.01);
            f.zupt();
        }
        for k in 0..40 {
            let (w, _) = swing(k);
            // Settled after 2, 3 and 4 samples in turn.
            let c = if k % 9 == 1 || k % 9 == 4 {
                CovarianceStep::Now
            } else {
                CovarianceStep::MayDefer
            };
            for (f, spare) in [(&mut a, &mut sa), (&mut b, &mut sb)] {
                f.propagate_into(spare, &w, &Vector3::zeros(), DT_S, c);
                std::mem::swap(f, spare);
            }
        }
        a.settle_covariance();
        let (pa, pb) = (dense(&a), dense(&b));
        let pvb = [P0, P0 + 1, P0 + 2, V0, V0 + 1, V0 + 2, BG, BG + 1, BG + 2];
        for i in pvb {
            for j in pvb {
                let scale = (pb[(i, i)] * pb[(j, j)]).sqrt();
                assert!(
                    (pa[(i, j)] - pb[(i, j)]).abs() <= 1e-12 * scale,
                    "({i}, {j}): {} against {}",
                    pa[(i, j)],
                    pb[(i, j)]
                );
            }
        }
        let (ra, rb) = (a.unabsorbed_bias_error(), b.unabsorbed_bias_error());
        assert!((ra - rb).abs().max() <= 1e-12, "{ra} against {rb}");
        let (ra, rb) = (a.response, b.response);
        for (x, y) in ra.iter().zip(&rb) {
            assert!((x - y).abs() <= 1e-12, "{x} against {y}");
        }
    }
}
