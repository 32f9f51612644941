use super::*;
use crate::core::rotation::from_euler_zyx;

fn noise() -> EskfNoise {
    EskfNoise {
        accel_m_s2: 0.5,
        gyro_rad_s: 0.01,
        rest_gyro_rad_s: 1e-3,
        gyro_bias_rw_rad_s_sqrt_s: 1e-4,
        zupt_m_s: 0.01,
        stance_yaw_max_sd_rad: f64::INFINITY,
        covariance_step_s: 0.0,
    }
}

pub(super) fn all_ext() -> Extensions {
    Extensions {
        bias_rate_rw: Some(1e-5),
        bias_rate_sd: 1e-4,
        scale_factor_sd: Some(0.01),
        heading_offset_sd: Some(0.05),
        g_sensitivity_sd: Some(1e-3),
        coupling_sd: Some(0.02),
        footprint_clone: true,
        stride_look_ahead: true,
    }
}

/// No extension; only the static ones (the base block propagation's fast path, one footprint
/// clone); all (two footprint clones).
pub(super) fn extension_sets() -> [Extensions; 3] {
    let static_only = Extensions {
        heading_offset_sd: Some(0.05),
        footprint_clone: true,
        ..Default::default()
    };
    [Extensions::default(), static_only, all_ext()]
}

/// A filter estimating its bias, with the test noise and 9.81 m/s² of gravity.
fn filter(
    nav_from_body: UnitQuaternion<f64>,
    gyro_bias_rad_s: Vector3<f64>,
    tilt_sd_rad: f64,
    bias_sd_rad_s: f64,
    ext: Extensions,
) -> Eskf {
    filter_with(
        BiasStates::Estimated,
        nav_from_body,
        gyro_bias_rad_s,
        tilt_sd_rad,
        bias_sd_rad_s,
        ext,
    )
}

/// [`filter`] with its bias states estimated or frozen.
pub(super) fn filter_with(
    bias: BiasStates,
    nav_from_body: UnitQuaternion<f64>,
    gyro_bias_rad_s: Vector3<f64>,
    tilt_sd_rad: f64,
    bias_sd_rad_s: f64,
    ext: Extensions,
) -> Eskf {
    Eskf::new(
        EskfInit {
            nav_from_body,
            gyro_bias_rad_s,
            tilt_sd_rad,
            bias_sd_rad_s,
            gravity_m_s2: 9.81,
            bias,
        },
        noise(),
        ext,
    )
}

/// A level filter at the origin with no bias, tilt σ 0.01 rad and bias σ `bias_sd_rad_s`.
pub(super) fn level_filter(bias_sd_rad_s: f64, ext: Extensions) -> Eskf {
    filter(
        UnitQuaternion::identity(),
        Vector3::zeros(),
        0.01,
        bias_sd_rad_s,
        ext,
    )
}

pub(super) fn dense(f: &Eskf) -> nalgebra::DMatrix<f64> {
    let n = f.dim();
    nalgebra::DMatrix::from_fn(n, n, |r, c| f.cov(r, c))
}

#[test]
fn a_state_copy_equals_a_clone_where_it_is_used() {
    let mut a = filter(
        from_euler_zyx(0.1, 0.2, 0.3),
        Vector3::new(0.01, 0.0, -0.01),
        0.01,
        0.01,
        all_ext(),
    );
    let mut b = a.clone();
    for _ in 0..5 {
        a.propagate(
            &Vector3::new(1.0, -2.0, 0.5),
            &Vector3::new(1.0, 2.0, 9.0),
            0.005,
        );
        a.zupt();
        a.clone_footprint();
    }
    b.copy_state_from(&a);
    let n = a.dim();
    assert_eq!(dense(&a), dense(&b));
    assert_eq!(
        (a.p_m, a.v_m_s, a.nav_from_body),
        (b.p_m, b.v_m_s, b.nav_from_body)
    );
    assert_eq!((a.gyro_bias_rad_s, a.ext), (b.gyro_bias_rad_s, b.ext));
    assert_eq!(a.footprint_xy_m, b.footprint_xy_m);
    assert_eq!(a.prev_footprint_xy_m, b.prev_footprint_xy_m);
    // The next steps agree to the bit.
    for f in [&mut a, &mut b] {
        f.propagate(
            &Vector3::new(0.3, 0.1, -0.2),
            &Vector3::new(0.5, 0.0, 9.8),
            0.005,
        );
        f.stride_direction_update(0.2, 0.05);
    }
    assert_eq!(dense(&a), dense(&b));
    assert_eq!(n, b.dim());
}

#[test]
fn propagating_into_a_spare_equals_propagating_in_place() {
    for ext in extension_sets() {
        let mut a = filter(
            from_euler_zyx(0.1, 0.2, 0.3),
            Vector3::new(0.01, 0.0, -0.01),
            0.01,
            0.01,
            ext,
        );
        // The spare holds another state of the same configuration (as the estimator's
        // does: the state of two samples ago).
        let mut spare = a.clone();
        for k in 0..4 {
            a.propagate(
                &Vector3::new(1.0, -2.0, 0.5),
                &Vector3::new(1.0, 2.0, 9.0),
                0.005,
            );
            a.zupt();
            a.heading_update(0.3, 0.05, &Vector3::x());
            a.clone_footprint();
            if k == 1 {
                spare.copy_state_from(&a);
            }
        }
        let before = a.clone();
        let (omega, acc) = (Vector3::new(0.5, 3.0, -1.0), Vector3::new(2.0, -1.0, 10.0));
        a.propagate_into(&mut spare, &omega, &acc, 0.005, CovarianceStep::Now);
        let mut in_place = a.clone();
        in_place.propagate(&omega, &acc, 0.005);
        // `a` is left as it was; the spare is the in-place result, to the bit (the footprint
        // compared by its bits: NaN before the first clone).
        assert_eq!(dense(&a), dense(&before));
        assert_eq!(
            (a.p_m, a.v_m_s, a.nav_from_body),
            (before.p_m, before.v_m_s, before.nav_from_body)
        );
        assert_eq!(dense(&spare), dense(&in_place));
        assert_eq!(
            (spare.p_m, spare.v_m_s, spare.nav_from_body),
            (in_place.p_m, in_place.v_m_s, in_place.nav_from_body)
        );
        assert_eq!(
            (
                spare.gyro_bias_rad_s,
                spare.ext,
                spare.footprint_xy_m.map(f64::to_bits)
            ),
            (
                in_place.gyro_bias_rad_s,
                in_place.ext,
                in_place.footprint_xy_m.map(f64::to_bits)
            )
        );
    }
}

#[test]
fn block_propagation_equals_dense_formula_with_every_extension() {
    for ext in extension_sets() {
        let mut f = tilted(Vector3::zeros(), ext);
        for _ in 0..3 {
            f.propagate(
                &Vector3::new(1.0, -2.0, 0.5),
                &Vector3::new(1.0, 2.0, 9.0),
                0.005,
            );
            f.zupt();
            f.heading_update(0.3, 0.05, &Vector3::x());
            f.stride_direction_update(0.2, 0.05);
            f.clone_footprint();
        }
        let n = f.dim();
        let lay = Layout::new(&ext);
        let p_before = dense(&f);
        let q_before = f.nav_from_body;
        let omega = Vector3::new(0.5, 3.0, -1.0);
        let acc = Vector3::new(2.0, -1.0, 10.0);
        let dt = 0.005;
        f.propagate(&omega, &acc, dt);
        let half = q_before * exp_rotvec(&(omega * (0.5 * dt)));
        let c = half.to_rotation_matrix().into_inner();
        let mut big_f = nalgebra::DMatrix::<f64>::identity(n, n);
        let mut put =
            |r: usize, cc: usize, m: &Matrix3<f64>| big_f.view_mut((r, cc), (3, 3)).copy_from(m);
        put(P0, V0, &(Matrix3::identity() * dt));
        put(V0, TH, &(-skew(&(half * acc)) * dt));
        put(TH, BG, &(-c * dt));
        if let Some(i) = lay.scale {
            put(TH, i, &(-c * Matrix3::from_diagonal(&omega) * dt));
        }
        if let Some(i) = lay.gsens {
            put(TH, i, &(-c * Matrix3::from_diagonal(&acc) * dt));
        }
        if let Some(i) = lay.rate {
            put(BG, i, &(Matrix3::identity() * dt));
        }
        if let Some(i) = lay.coupling {
            // ∂(rate error)/∂(m_zx, m_zy) = e_z·(ω_x, ω_y)
            let mut g = nalgebra::Matrix3x2::<f64>::zeros();
            g[(2, 0)] = omega.x;
            g[(2, 1)] = omega.y;
            big_f.view_mut((TH, i), (3, 2)).copy_from(&(-c * g * dt));
        }
        let mut q = nalgebra::DMatrix::<f64>::zeros(n, n);
        for i in 0..3 {
            q[(V0 + i, V0 + i)] = 0.25 * dt;
            q[(TH + i, TH + i)] = 1e-4 * dt;
            q[(BG + i, BG + i)] = 1e-8 * dt;
            if let Some(r) = lay.rate {
                q[(r + i, r + i)] = 1e-10 * dt;
            }
        }
        let want = &big_f * p_before * big_f.transpose() + q;
        let err = (want - dense(&f)).abs().max();
        assert!(err < 1e-15, "n = {n}: {err}");
    }
}

#[test]
fn the_fast_propagation_and_the_zupt_keep_the_covariance_exactly_symmetric() {
    // Without extensions and with the static ones (the default filter's), propagation works on
    // one triangle and mirrors it: P is symmetric to the bit after every step, update and
    // adjustment, so that no asymmetry builds up over a long run.
    for ext in &extension_sets()[..2] {
        let mut f = tilted(Vector3::new(0.01, -0.02, 0.005), *ext);
        for k in 0..200 {
            let t = f64::from(k) * 0.01;
            f.propagate(
                &Vector3::new(3.0 * t.sin(), -2.0, 0.5 * t.cos()),
                &Vector3::new(1.0, 2.0 * t.cos(), 9.0),
                0.005,
            );
            if k % 3 == 0 {
                f.zupt();
            }
            if k % 50 == 10 {
                f.clone_footprint();
            }
            // The changes from outside the filter (the map frame fixed, a restored turn, the
            // rotation a clipped axis lost) keep it too: the propagation computes from one side
            // of P and mirrors, so an asymmetry left here would be carried on one-sided.
            match k {
                60 => f.rotate_frame(0.7),
                90 => f.turn_heading(-0.4, 0.02),
                _ if k % 40 == 20 => f.widen_attitude_about(&Vector3::new(0.6, -0.48, 0.64), 1e-3),
                _ => {}
            }
            let p = dense(&f);
            assert_eq!(p, p.transpose(), "step {k}");
        }
    }
}

/// A filter at a tilted attitude and an arbitrary heading (roll 0.2, pitch −0.3, yaw 1 rad),
/// with the given bias and extensions.
fn tilted(gyro_bias_rad_s: Vector3<f64>, ext: Extensions) -> Eskf {
    filter(
        from_euler_zyx(0.2, -0.3, 1.0),
        gyro_bias_rad_s,
        0.01,
        0.01,
        ext,
    )
}

/// The stance update's H: it selects the velocity of an `n`-state filter.
fn velocity_h(n: usize) -> nalgebra::DMatrix<f64> {
    nalgebra::DMatrix::from_fn(3, n, |i, j| f64::from(u8::from(j == V0 + i)))
}

#[test]
fn update_matches_the_textbook_kalman_formulas() {
    let mut f = tilted(Vector3::zeros(), all_ext());
    for _ in 0..5 {
        f.propagate(
            &Vector3::new(1.0, -2.0, 0.5),
            &Vector3::new(1.0, 2.0, 9.0),
            0.005,
        );
    }
    let n = f.dim();
    let p = dense(&f);
    let axis = Vector3::new(0.2, 0.9, -0.3).normalize();
    let j = heading_jacobian(&f.nav_from_body, &axis);
    let mut h = nalgebra::DMatrix::<f64>::zeros(1, n);
    h[(0, TH)] = j.x;
    h[(0, TH + 1)] = j.y;
    h[(0, TH + 2)] = j.z;
    h[(0, Layout::new(&all_ext()).offset.unwrap())] = 1.0;
    let s = (&h * &p * h.transpose())[(0, 0)] + 0.05f64.powi(2);
    let k = &p * h.transpose() / s;
    let want = &p - &k * &h * &p;
    let inn = f.heading_update(0.7, 0.05, &axis);
    assert!((inn.s_diag[0] - s).abs() < 1e-15);
    assert!((want - dense(&f)).abs().max() < 1e-15);

    // ZUPT: H selects the velocity.
    let p = dense(&f);
    let h = velocity_h(n);
    let s = &h * &p * h.transpose() + nalgebra::DMatrix::<f64>::identity(3, 3) * 1e-4;
    let k = &p * h.transpose() * s.clone().try_inverse().unwrap();
    let want = &p - &k * &h * &p;
    let v_before = f.v_m_s;
    let dx = &k * nalgebra::DVector::from_column_slice(&[-v_before.x, -v_before.y, -v_before.z]);
    f.zupt();
    assert!((want - dense(&f)).abs().max() < 1e-15);
    assert!((f.v_m_s - (v_before + Vector3::new(dx[V0], dx[V0 + 1], dx[V0 + 2]))).norm() < 1e-14);
}

#[test]
fn a_stance_update_leaves_a_wide_yaw_alone_in_the_schmidt_joseph_form() {
    let mut f = tilted(Vector3::zeros(), all_ext());
    f.noise.stance_yaw_max_sd_rad = 5f64.to_radians();
    // A gap widens the yaw to 10°; a horizontal force then ties it to the velocity.
    f.widen_after_gap(600.0, 0.0);
    for _ in 0..20 {
        f.propagate(
            &Vector3::new(1.0, -2.0, 0.5),
            &Vector3::new(3.0, 2.0, 9.0),
            0.005,
        );
    }
    let n = f.dim();
    let yaw = TH + 2;
    let p = dense(&f);
    assert!(p[(yaw, yaw)].sqrt() > 5f64.to_radians());
    assert!(p[(yaw, V0)].abs() > 1e-4, "the yaw is tied to the velocity");
    let h = velocity_h(n);
    let r_var = 0.01f64.powi(2);
    let s = &h * &p * h.transpose() + nalgebra::DMatrix::<f64>::identity(3, 3) * r_var;
    let mut k = &p * h.transpose() * s.try_inverse().unwrap();
    k.row_mut(yaw).fill(0.0);
    let i_kh = nalgebra::DMatrix::<f64>::identity(n, n) - &k * &h;
    let want = &i_kh * &p * i_kh.transpose() + &k * k.transpose() * r_var;
    let v_before = f.v_m_s;
    let dx = &k * nalgebra::DVector::from_column_slice(&[-v_before.x, -v_before.y, -v_before.z]);
    f.zupt();
    let got = dense(&f);
    let scale = p.abs().max();
    assert!(
        (&want - &got).abs().max() < 1e-12 * scale,
        "{}",
        (&want - &got).abs().max()
    );
    assert_eq!(got[(yaw, yaw)], p[(yaw, yaw)], "the yaw's variance stays");
    assert!((f.v_m_s - (v_before + Vector3::new(dx[V0], dx[V0 + 1], dx[V0 + 2]))).norm() < 1e-12);
    // Below the bound it is the usual update (the textbook test above), and the yaw narrows.
    let mut f = level_filter(0.01, Extensions::default());
    f.noise.stance_yaw_max_sd_rad = 5f64.to_radians();
    for _ in 0..20 {
        f.propagate(&Vector3::zeros(), &Vector3::new(3.0, 2.0, 9.0), 0.005);
    }
    let before = f.cov(yaw, yaw);
    f.zupt();
    assert!(f.cov(yaw, yaw) < before);
}

#[test]
fn heading_updates_make_z_bias_observable() {
    // Static sensor, level, with a z bias of 0.01 rad/s the filter does not know.
    let mut f = level_filter(0.02, Extensions::default());
    let true_bias = Vector3::new(0.0, 0.0, 0.01);
    let g = Vector3::new(0.0, 0.0, 9.81);
    let dt = 0.005;
    for k in 0..4000 {
        let omega = f.corrected_rate(&true_bias, &g, &f.gyro_bias_rad_s.clone());
        f.propagate(&omega, &g, dt);
        f.zupt();
        if k % 200 == 199 {
            f.heading_update(0.0, 0.02, &Vector3::x());
        }
    }
    assert!(
        (f.gyro_bias_rad_s.z - 0.01).abs() < 5e-4,
        "{}",
        f.gyro_bias_rad_s.z
    );
    assert!(
        f.gyro_bias_sd().z < 0.25 * 0.02,
        "σ did not shrink: {}",
        f.gyro_bias_sd().z
    );
}

#[test]
fn scale_factor_state_converges_on_a_turning_body() {
    // Turns about z at ±2 rad/s with a 2 % z scale error; heading observed every second.
    let ext = Extensions {
        scale_factor_sd: Some(0.05),
        ..Default::default()
    };
    let mut f = level_filter(1e-4, ext);
    let g = Vector3::new(0.0, 0.0, 9.81);
    let dt = 0.005;
    let mut true_yaw: f64 = 0.0;
    for k in 0..20_000 {
        let rate = if (k / 400) % 2 == 0 { 2.0 } else { -1.0 };
        true_yaw += rate * dt;
        let meas = Vector3::new(0.0, 0.0, rate * 1.02);
        let omega = f.corrected_rate(&meas, &g, &f.gyro_bias_rad_s.clone());
        f.propagate(&omega, &g, dt);
        f.zupt();
        if k % 200 == 199 {
            f.heading_update(wrap_pi(true_yaw), 0.01, &Vector3::x());
        }
    }
    assert!(
        (f.ext.scale_factor.z - 0.02).abs() < 1e-3,
        "{}",
        f.ext.scale_factor.z
    );
}

#[test]
fn the_corrected_rate_inverts_the_whole_rate_model() {
    // ω_meas = (1 + s)∘ω + M·ω + b + k∘f, with the coupling M = e_z·(m_zx, m_zy, 0)
    let mut f = level_filter(1e-4, all_ext());
    f.ext.scale_factor = Vector3::new(0.01, -0.02, 0.03);
    f.ext.coupling_z_rad = [0.02, -0.015];
    f.ext.g_sensitivity = Vector3::new(1e-3, -2e-3, 5e-4);
    let b = Vector3::new(0.004, -0.002, 0.006);
    let (w, force) = (Vector3::new(1.5, -3.0, 0.7), Vector3::new(0.5, 2.0, 9.5));
    let [mx, my] = f.ext.coupling_z_rad;
    let mut meas = (Vector3::repeat(1.0) + f.ext.scale_factor).component_mul(&w)
        + b
        + f.ext.g_sensitivity.component_mul(&force);
    meas.z += mx * w.x + my * w.y;
    let back = f.corrected_rate(&meas, &force, &b);
    assert!((back - w).norm() < 1e-12, "{back} against {w}");
}

#[test]
fn coupling_states_converge_on_a_body_that_pitches_and_turns() {
    // The z gyro also reads 3 % of the x rate and −2 % of the y rate; the body turns about z and
    // rocks about x and y (a foot's swing), and the heading is observed every second.
    let ext = Extensions {
        coupling_sd: Some(0.05),
        ..Default::default()
    };
    let mut f = level_filter(1e-4, ext);
    let (m_zx, m_zy) = (0.03, -0.02);
    let dt = 0.005;
    let mut truth = UnitQuaternion::identity();
    for k in 0..40_000 {
        let t = k as f64 * dt;
        let w = Vector3::new(
            3.0 * (2.0 * t).sin(),
            2.0 * (3.1 * t).cos(),
            if (k / 400) % 2 == 0 { 1.0 } else { -0.5 },
        );
        truth *= exp_rotvec(&(w * dt));
        let g_body = truth.inverse() * Vector3::new(0.0, 0.0, 9.81);
        let meas = Vector3::new(w.x, w.y, w.z + m_zx * w.x + m_zy * w.y);
        let omega = f.corrected_rate(&meas, &g_body, &f.gyro_bias_rad_s.clone());
        f.propagate(&omega, &g_body, dt);
        f.zupt();
        if k % 200 == 199 {
            let yaw = heading_of_axis(&truth, &Vector3::x());
            f.heading_update(yaw, 0.005, &Vector3::x());
        }
    }
    let [mx, my] = f.ext.coupling_z_rad;
    assert!(
        (mx - m_zx).abs() < 3e-3 && (my - m_zy).abs() < 3e-3,
        "{mx} {my}"
    );
    let sd = f.coupling_z_sd().unwrap();
    assert!(sd[0] < 0.01 && sd[1] < 0.01, "{sd:?}");
    // The corrected rate takes the coupling out of z.
    let w = Vector3::new(1.0, -2.0, 0.5);
    let meas = Vector3::new(w.x, w.y, w.z + mx * w.x + my * w.y);
    let back = f.corrected_rate(&meas, &Vector3::zeros(), &Vector3::zeros());
    assert!((back - w).norm() < 1e-12, "{back}");
}

#[test]
fn bias_rate_state_follows_a_ramp() {
    let ext = Extensions {
        bias_rate_rw: Some(1e-7),
        bias_rate_sd: 3e-4,
        ..Default::default()
    };
    let mut f = Eskf::new(
        EskfInit {
            nav_from_body: UnitQuaternion::identity(),
            gyro_bias_rad_s: Vector3::zeros(),
            tilt_sd_rad: 0.01,
            bias_sd_rad_s: 1e-3,
            gravity_m_s2: 9.81,
            bias: BiasStates::Estimated,
        },
        EskfNoise {
            gyro_bias_rw_rad_s_sqrt_s: 1e-6,
            ..noise()
        },
        ext,
    );
    let g = Vector3::new(0.0, 0.0, 9.81);
    let dt = 0.005;
    let ramp = 1e-4; // rad/s²
    for k in 0..40_000 {
        let t = k as f64 * dt;
        let meas = Vector3::new(0.0, 0.0, ramp * t);
        let omega = f.corrected_rate(&meas, &g, &f.gyro_bias_rad_s.clone());
        f.propagate(&omega, &g, dt);
        f.zupt();
        if k % 200 == 199 {
            f.heading_update(0.0, 0.01, &Vector3::x());
        }
    }
    assert!(
        (f.ext.bias_rate_rad_s2.z - ramp).abs() < 0.2 * ramp,
        "{}",
        f.ext.bias_rate_rad_s2.z
    );
    assert!(
        (f.gyro_bias_rad_s.z - ramp * 200.0).abs() < 2e-3,
        "{}",
        f.gyro_bias_rad_s.z
    );
}

#[test]
fn g_sensitivity_state_converges_on_a_tumbling_body() {
    // A body rolling in place about its x axis: gravity sweeps through y and z, and the z
    // gyro reads k_z·f_z on top of the rate. ZUPTs and heading observations of the x axis.
    let k_true = Vector3::new(0.0, 0.0, 2e-3);
    let ext = Extensions {
        g_sensitivity_sd: Some(5e-3),
        ..Default::default()
    };
    let mut f = level_filter(1e-4, ext);
    let dt = 0.005;
    let w_true = Vector3::new(0.5, 0.0, 0.0);
    let mut q_true = UnitQuaternion::identity();
    for k in 0..40_000 {
        q_true *= exp_rotvec(&(w_true * dt));
        let f_body = q_true.inverse() * Vector3::new(0.0, 0.0, 9.81);
        let meas = w_true + k_true.component_mul(&f_body);
        let omega = f.corrected_rate(&meas, &f_body, &f.gyro_bias_rad_s.clone());
        f.propagate(&omega, &f_body, dt);
        f.zupt();
        if k % 200 == 199 {
            f.heading_update(0.0, 0.01, &Vector3::x());
        }
    }
    assert!(
        (f.ext.g_sensitivity.z - k_true.z).abs() < 0.2 * k_true.z,
        "{}",
        f.ext.g_sensitivity
    );
    // its σ is reported with it (the diagnosis's final estimates), as the other states' are
    let sd = f.extension_sd().g_sensitivity.expect("the states are on");
    assert!(sd.z > 0.0 && sd.z < 0.2 * k_true.z, "{sd}");
    let plain = level_filter(1e-4, Extensions::default());
    assert_eq!(plain.extension_sd().g_sensitivity, None);
}

#[test]
fn a_stance_velocity_update_pulls_the_velocity_to_the_expected_one() {
    let mut f = level_filter(0.01, Extensions::default());
    f.v_m_s = Vector3::new(0.3, 0.0, 0.0);
    f.widen_after_gap(0.0, 1.0); // the velocity is unknown to 1 m/s
    let expected = Vector3::new(0.1, 0.0, 0.0);
    let i = f.stance_velocity_update(&expected, 0.01);
    assert!(
        (i.r[0] + 0.2).abs() < 1e-12,
        "residual is expected − v: {:?}",
        i.r
    );
    for _ in 0..50 {
        f.stance_velocity_update(&expected, 0.01);
    }
    assert!((f.v_m_s - expected).norm() < 0.01, "{}", f.v_m_s);
}

#[test]
fn unmeasured_rotation_widens_the_attitude_about_its_axis_in_the_nav_frame() {
    // Yawed by 90°: the body x axis is the nav y axis.
    let q = UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2);
    let mut f = filter(q, Vector3::zeros(), 0.01, 0.01, Extensions::default());
    let before = dense(&f);
    f.widen_attitude_about(&Vector3::x(), 4e-4);
    let d = dense(&f) - before;
    assert!((d[(TH + 1, TH + 1)] - 4e-4).abs() < 1e-12, "{d}");
    let rest: f64 = d.iter().map(|v| v.abs()).sum::<f64>() - d[(TH + 1, TH + 1)].abs();
    assert!(rest < 1e-12, "only the nav-y attitude variance grows: {d}");
}

#[test]
fn heading_offset_state_absorbs_a_constant_offset() {
    // A foot that walks along the map direction but points 3° off it: with the attitude's
    // heading known (tight initial σ), the offset state takes the difference.
    let ext = Extensions {
        heading_offset_sd: Some(0.1),
        ..Default::default()
    };
    let mut f = level_filter(1e-5, ext);
    let g = Vector3::new(0.0, 0.0, 9.81);
    for _ in 0..20 {
        f.propagate(&Vector3::zeros(), &g, 0.005);
        f.heading_update(3f64.to_radians(), 0.02, &Vector3::x());
    }
    assert!(
        (f.ext.heading_offset_rad.to_degrees() - 3.0).abs() < 0.5,
        "{}",
        f.ext.heading_offset_rad.to_degrees()
    );
}

#[test]
fn a_heading_turn_rotates_the_attitude_and_its_covariance_with_it() {
    // A filter with correlations (a few propagation and update steps in a swing-like motion).
    let mut f = filter(
        UnitQuaternion::from_euler_angles(0.1, -0.2, 0.3),
        Vector3::zeros(),
        0.01,
        0.01,
        all_ext(),
    );
    for k in 0..40 {
        let w = Vector3::new(0.5, 2.0 * (k as f64 * 0.1).sin(), 0.3);
        f.propagate(&w, &Vector3::new(1.0, 0.5, 9.81), 0.005);
    }
    f.zupt();
    let (q0, p0) = (f.nav_from_body, dense(&f));
    let a = 0.7;
    f.turn_heading(a, 0.0);
    let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), a);
    assert!(
        f.nav_from_body
            .angle_to(&(UnitQuaternion::from_rotation_matrix(&r) * q0))
            < 1e-12
    );
    // P ← T P Tᵀ with T the identity but R on the attitude block.
    let n = p0.nrows();
    let mut t = nalgebra::DMatrix::<f64>::identity(n, n);
    t.view_mut((TH, TH), (3, 3)).copy_from(r.matrix());
    let want = &t * &p0 * t.transpose();
    let err = (dense(&f) - want).abs().max();
    assert!(err < 1e-15, "{err}");
    // The σ given is added to the heading variance.
    let before = dense(&f)[(TH + 2, TH + 2)];
    f.turn_heading(0.0, 0.1);
    assert!((dense(&f)[(TH + 2, TH + 2)] - before - 0.01).abs() < 1e-15);
}
