//! Tests of the bias-error response (`response.rs`): against a finite difference of two
//! filters, and its restart when the bias is set.

use super::tests::{extension_sets, filter_with, level_filter};
use super::*;
use crate::core::rotation::log_rotvec;

/// The error state of `b` against the exact filter `a`, `b − a` (the attitude as the rotation
/// vector of `q_b·q_a⁻¹`), in the layout of the error state.
fn estimate_difference(b: &Eskf, a: &Eskf) -> [f64; MAX_N] {
    let mut d = [0.0; MAX_N];
    let mut put = |i: usize, v: &[f64]| d[i..i + v.len()].copy_from_slice(v);
    put(P0, (b.p_m - a.p_m).as_slice());
    put(V0, (b.v_m_s - a.v_m_s).as_slice());
    put(
        TH,
        log_rotvec(&(b.nav_from_body * a.nav_from_body.inverse())).as_slice(),
    );
    put(BG, (b.gyro_bias_rad_s - a.gyro_bias_rad_s).as_slice());
    let (eb, ea) = (&b.ext, &a.ext);
    let lay = a.layout;
    if let Some(i) = lay.rate {
        put(i, (eb.bias_rate_rad_s2 - ea.bias_rate_rad_s2).as_slice());
    }
    if let Some(i) = lay.scale {
        put(i, (eb.scale_factor - ea.scale_factor).as_slice());
    }
    if let Some(i) = lay.offset {
        put(i, &[eb.heading_offset_rad - ea.heading_offset_rad]);
    }
    if let Some(i) = lay.gsens {
        put(i, (eb.g_sensitivity - ea.g_sensitivity).as_slice());
    }
    if let Some(i) = lay.coupling {
        put(
            i,
            &[
                eb.coupling_z_rad[0] - ea.coupling_z_rad[0],
                eb.coupling_z_rad[1] - ea.coupling_z_rad[1],
            ],
        );
    }
    for (i, xb, xa) in [
        (lay.clone, b.footprint_xy_m, a.footprint_xy_m),
        (lay.clone_prev, b.prev_footprint_xy_m, a.prev_footprint_xy_m),
    ] {
        if let Some(i) = i {
            put(i, &[xb[0] - xa[0], xb[1] - xa[1]]);
        }
    }
    d
}

#[test]
fn the_bias_error_response_is_what_a_start_error_becomes() {
    // Two filters see the same body walking at a constant velocity while it turns and rocks,
    // with velocity updates for 0.2 s of every second (its "stances"), foot-axis headings,
    // stride directions on footprint clones and a frame fix that turns the navigation frame by
    // 0.5 rad; one starts with its bias estimate off by δ on one axis. The other is exact (its innovations are zero, so the gains' own
    // dependence on the state adds nothing at first order), and their difference over δ is the
    // response's column, on every error state. Each steps as the estimator does, into a spare
    // that holds the state of two samples before.
    let delta = 1e-6;
    let dt = 0.005;
    let g = Vector3::new(0.0, 0.0, 9.81);
    for ext in extension_sets() {
        for axis in 0..3 {
            let mut a = level_filter(0.01, ext);
            let v0 = Vector3::new(1.0, 0.3, 0.0);
            a.v_m_s = v0;
            let mut b = a.clone();
            b.gyro_bias_rad_s[axis] += delta;
            let (mut spare_a, mut spare_b) = (a.clone(), b.clone());
            // The truth in the first navigation frame, and that frame in the current one.
            let mut truth = UnitQuaternion::identity();
            let mut frame = UnitQuaternion::identity();
            let mut fraction_mid = f64::NAN;
            let mut position_slack = 0.0;
            // Up to the end of a stance, where the velocity has just been observed.
            for k in 0..5_840 {
                let t = k as f64 * dt;
                let w = Vector3::new(
                    3.0 * (2.0 * t).sin(),
                    2.0 * (3.1 * t).cos(),
                    if (k / 400) % 2 == 0 { 1.0 } else { -0.5 },
                );
                // The specific force at the middle of the step, where the filter takes it.
                let mid = truth * exp_rotvec(&(w * (0.5 * dt)));
                let f_body = mid.inverse() * g;
                truth *= exp_rotvec(&(w * dt));
                if k == 1_000 {
                    frame = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.5);
                }
                let nav_truth = frame * truth;
                let v_nav = frame * v0;
                for (f, spare) in [(&mut a, &mut spare_a), (&mut b, &mut spare_b)] {
                    let omega = f.corrected_rate(&w, &f_body, &f.gyro_bias_rad_s.clone());
                    f.propagate_into(spare, &omega, &f_body, dt, CovarianceStep::Now);
                    std::mem::swap(f, spare);
                    if k == 1_000 {
                        // The frame turned by 0.5 rad, then the heading defined anew (as at the
                        // map-frame fix): the filter's own heading error taken out of its
                        // attitude alone, and its variance set.
                        f.rotate_frame(0.5);
                        let err = log_rotvec(&(nav_truth * f.nav_from_body.inverse()));
                        f.nav_from_body =
                            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), err.z)
                                * f.nav_from_body;
                        f.set_heading_variance(1e-4);
                    }
                    if k % 200 < 40 {
                        f.stance_velocity_update(&v_nav, 0.01);
                    }
                    if k % 200 == 199 {
                        f.heading_update(
                            heading_of_axis(&nav_truth, &Vector3::x()),
                            0.005,
                            &Vector3::x(),
                        );
                        if k > 200 {
                            f.stride_direction_update(v_nav.y.atan2(v_nav.x), 0.01);
                        }
                        f.clone_footprint();
                    }
                }
                if k == 3_000 {
                    fraction_mid = max_row_sum(&a.unabsorbed_bias_error());
                }
                // What the nominal integration adds to the positions and the transition leaves
                // out (of P as of the response): ½·dt²·(f × δθ) a step.
                let th = Vector3::new(
                    a.response[ix(TH, axis)],
                    a.response[ix(TH + 1, axis)],
                    a.response[ix(TH + 2, axis)],
                );
                position_slack += 0.5 * dt * dt * (frame * truth * f_body).cross(&th).norm();
            }
            let want = estimate_difference(&b, &a);
            // The transition is first order in dt (the attitude at the start of a step stands for
            // its value across it: about 1 % of the velocity error a swing builds, observed
            // away at the stance): 0.5 % is left for that, and the positions (and the clone of
            // one) may differ by the term summed above.
            let positions = |i: usize| i < V0 || a.layout.clone.is_some_and(|c| i >= c);
            for (i, w) in want.iter().enumerate().take(a.layout.n) {
                let (w, got) = (w / delta, a.response[ix(i, axis)]);
                let slack = if positions(i) { position_slack } else { 0.0 };
                assert!(
                    (w - got).abs() <= 1e-4 + 5e-3 * w.abs() + slack,
                    "{ext:?} bias axis {axis}, error state {i}: finite difference {w} against response {got}"
                );
            }
            // The walk observes the bias: most of the start error is gone, and more of it by the
            // end than half-way.
            let end = max_row_sum(&a.unabsorbed_bias_error());
            assert!(end < 0.5 && end <= fraction_mid, "{end} {fraction_mid}");
        }
    }
}

#[test]
fn setting_the_bias_starts_the_response_again() {
    let mut f = level_filter(0.01, Extensions::default());
    let g = Vector3::new(0.0, 0.0, 9.81);
    for k in 0..2_000 {
        f.propagate(&Vector3::new(0.0, 0.0, 0.5), &g, 0.005);
        f.zupt();
        if k % 200 == 199 {
            f.heading_update(0.0, 0.005, &Vector3::x());
        }
    }
    assert!(f.unabsorbed_bias_error()[(2, 2)] < 0.9);
    f.set_gyro_bias(Vector3::zeros(), &(Matrix3::identity() * 1e-6));
    assert_eq!(f.unabsorbed_bias_error(), Matrix3::identity());
    // A filter that does not own the bias has no response.
    let frozen = filter_with(
        BiasStates::Frozen,
        UnitQuaternion::identity(),
        Vector3::zeros(),
        0.01,
        0.01,
        Extensions::default(),
    );
    assert_eq!(frozen.unabsorbed_bias_error(), Matrix3::zeros());
}
