//! Rotation helpers: the quaternion exponential and logarithm (closed form and the paper's
//! Newton iteration), ZYX Euler angles, heading of a body axis and its Jacobian, angle wrapping.
//!
//! Conventions: `nav_from_body` quaternions rotate body-frame vectors into the navigation frame
//! (ENU-like local level, z up). The "half-angle vector" `x` of the paper is the vector with
//! `q = exp(x) = [cos|x|, sin|x|·x/|x|]`; the rotation vector is `2x`.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use std::f64::consts::{PI, TAU};

/// Wraps an angle to [-π, π).
pub fn wrap_pi(a: f64) -> f64 {
    (a + PI).rem_euclid(TAU) - PI
}

/// The skew-symmetric (cross-product) matrix of `v`.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Below this squared angle (rad², an angle of 0.1 rad) [`exp_rotvec`] uses its series: their
/// first left-out terms are then below 3e-19 of the result's (the gyro's step rotations are
/// at most 0.05 rad: 8.7 rad/s over a 5 ms half step at 100 Hz).
const EXP_SERIES_MAX_ANGLE2: f64 = 0.01;

/// The rotation by the rotation vector `rotvec_rad` (axis × angle). Small rotations (every
/// per-sample step) through the series of cos(θ/2) and sin(θ/2)/θ in θ², with no square root
/// and no sine or cosine: the strapdown step's largest cost before, about 200 instructions.
#[inline]
pub fn exp_rotvec(rotvec_rad: &Vector3<f64>) -> UnitQuaternion<f64> {
    let x = rotvec_rad.norm_squared();
    if x >= EXP_SERIES_MAX_ANGLE2 {
        return UnitQuaternion::from_scaled_axis(*rotvec_rad);
    }
    // cos(θ/2) = Σ (−x/4)ᵏ/(2k)!, sin(θ/2)/θ = ½·Σ (−x/4)ᵏ/(2k+1)!, x = θ², to k = 4.
    let y = -0.25 * x;
    let w = 1.0 + y * (1.0 / 2.0 + y * (1.0 / 24.0 + y * (1.0 / 720.0 + y * (1.0 / 40320.0))));
    let s = 0.5
        * (1.0 + y * (1.0 / 6.0 + y * (1.0 / 120.0 + y * (1.0 / 5040.0 + y * (1.0 / 362880.0)))));
    UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(
        w,
        s * rotvec_rad.x,
        s * rotvec_rad.y,
        s * rotvec_rad.z,
    ))
}

/// Closed-form logarithm: the half-angle vector `x` with `q = exp(x)`, taking the
/// representative with a non-negative scalar part (|x| ≤ π/2).
pub fn log_half_closed_form(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let q = canonical(q);
    let v = q.imag();
    let n = v.norm();
    if n < 1e-300 {
        return Vector3::zeros();
    }
    v * (n.atan2(q.w) / n)
}

/// The paper's logarithm: Newton iteration on `vec(exp(x)) = vec(q)` starting from `x = vec(q)`.
/// Returns the half-angle vector and the number of iterations used. Agrees with
/// [`log_half_closed_form`] to `tol` for rotations up to π (|x| < π/2).
pub fn log_half_newton(
    q: &UnitQuaternion<f64>,
    tol: f64,
    max_iter: usize,
) -> (Vector3<f64>, usize) {
    let q = canonical(q);
    let target = q.imag();
    let mut x = target;
    for it in 0..max_iter {
        let a = x.norm();
        let (s, ds) = sinc_and_derivative(a);
        let f = x * s - target;
        if f.norm() <= tol {
            return (x, it);
        }
        // d/dx [s(|x|) x] = s I + s'(a) x xᵀ / a
        let mut j = Matrix3::identity() * s;
        if a > 1e-12 {
            j += x * x.transpose() * (ds / a);
        }
        match j.try_inverse() {
            Some(ji) => x -= ji * f,
            None => break,
        }
    }
    (x, max_iter)
}

/// sin(a)/a and its derivative, with series near 0.
fn sinc_and_derivative(a: f64) -> (f64, f64) {
    if a < 1e-4 {
        (1.0 - a * a / 6.0, -a / 3.0)
    } else {
        let (s, c) = a.sin_cos();
        (s / a, (a * c - s) / (a * a))
    }
}

/// The representative with a non-negative scalar part (q and -q are the same rotation).
pub fn canonical(q: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    if q.w < 0.0 {
        UnitQuaternion::new_unchecked(-q.into_inner())
    } else {
        *q
    }
}

/// The rotation vector (axis × angle, rad) of `q`, angle in [0, π].
pub fn log_rotvec(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    log_half_closed_form(q) * 2.0
}

/// ZYX Euler angles (roll, pitch, yaw) of `nav_from_body`: nalgebra's `euler_angles` (the same
/// branches and angles) from the five rotation-matrix entries it needs, without its division of
/// both atan2 arguments by cos(pitch) > 0, which leaves the angle as it is. Per sample output:
/// this saves a cos, four divisions and four matrix entries.
pub fn euler_zyx(q: &UnitQuaternion<f64>) -> (f64, f64, f64) {
    let (w, i, j, k) = (q.w, q.i, q.j, q.k);
    let (ww, ii, jj, kk) = (w * w, i * i, j * j, k * k);
    // Row 2 and the first column of the rotation matrix.
    let r20 = 2.0 * (i * k - w * j);
    if r20.abs() < 1.0 {
        let r21 = 2.0 * (w * i + j * k);
        let r22 = ww - ii - jj + kk;
        let r10 = 2.0 * (w * k + i * j);
        let r00 = ww + ii - jj - kk;
        (r21.atan2(r22), -r20.asin(), r10.atan2(r00))
    } else {
        // Gimbal lock: nalgebra's convention (yaw 0, the rotation in roll).
        let r01 = 2.0 * (i * j - w * k);
        let r02 = 2.0 * (w * j + i * k);
        if r20 <= -1.0 {
            (r01.atan2(r02), std::f64::consts::FRAC_PI_2, 0.0)
        } else {
            (-r01.atan2(-r02), -std::f64::consts::FRAC_PI_2, 0.0)
        }
    }
}

/// `nav_from_body` from ZYX Euler angles.
pub fn from_euler_zyx(roll: f64, pitch: f64, yaw: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(roll, pitch, yaw)
}

/// A rotation about the navigation z axis.
pub fn rot_z(angle_rad: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), angle_rad)
}

/// ZYX yaw of `nav_from_body`: the heading of the body x axis projected on the horizontal.
pub fn yaw(q: &UnitQuaternion<f64>) -> f64 {
    heading_of_axis(q, &Vector3::x())
}

/// Heading (angle from the navigation x axis, counter-clockwise about z) of the body-frame
/// direction `axis_body` projected on the horizontal.
pub fn heading_of_axis(q: &UnitQuaternion<f64>, axis_body: &Vector3<f64>) -> f64 {
    let c = q * axis_body;
    c.y.atan2(c.x)
}

/// The yaw `m` of the horizontal axis `(cos m, −sin m, 0)` of frame `b` whose
/// [`heading_of_axis`] under `nav_from_b` is `heading_rad`: the axis lies at right angles to
/// the horizontal normal of that heading, and of the two such axes it is the one that points
/// along it. Where `nav_from_b` is a pure yaw ψ, `m = ψ − heading_rad`; unlike that difference
/// of yaws it holds for any tilt of `nav_from_b`.
pub fn yaw_of_axis_with_heading(nav_from_b: &UnitQuaternion<f64>, heading_rad: f64) -> f64 {
    let (sin_h, cos_h) = heading_rad.sin_cos();
    let w = nav_from_b.inverse() * Vector3::new(-sin_h, cos_h, 0.0);
    let m = w.x.atan2(w.y);
    let axis_nav = nav_from_b * Vector3::new(m.cos(), -m.sin(), 0.0);
    if axis_nav.x * cos_h + axis_nav.y * sin_h < 0.0 {
        wrap_pi(m + PI)
    } else {
        m
    }
}

/// Jacobian of [`heading_of_axis`] with respect to a small navigation-frame rotation `δθ`
/// applied as `exp(δθ)·q`.
pub fn heading_jacobian(q: &UnitQuaternion<f64>, axis_body: &Vector3<f64>) -> Vector3<f64> {
    let c = q * axis_body;
    let n2 = (c.x * c.x + c.y * c.y).max(1e-12);
    Vector3::new(
        -c.x * c.z / n2,
        -c.y * c.z / n2,
        (c.x * c.x + c.y * c.y) / n2,
    )
}

/// The horizontal velocity (navigation frame) of a sensor `height_m` above the floor contact of a
/// foot that rolls over that contact, as it does from heel strike to foot flat (about the heel),
/// at heel-off (about the ball) and sideways over the edge of the sole: a point at height h above
/// a contact point on the floor moves horizontally at ω × h·ẑ, whatever the contact's place
/// along the foot, so only the height matters (its vertical speed depends on that place: left
/// at zero, within the lever-arm σ). Both horizontal components of the rate count: a turn about
/// the vertical moves nothing, and neither the foot's forward axis nor the mounting yaw is
/// needed.
pub fn rolling_velocity(
    q: &UnitQuaternion<f64>,
    omega_body_rad_s: &Vector3<f64>,
    height_m: f64,
) -> Vector3<f64> {
    let w = q * omega_body_rad_s;
    // ω × h·ẑ = h·(ω_y, −ω_x, 0).
    Vector3::new(height_m * w.y, -height_m * w.x, 0.0)
}

/// Roll and pitch (ZYX) of a body frame whose measured specific force (pointing up at rest)
/// is `f_body`.
pub fn tilt_from_specific_force(f_body: &Vector3<f64>) -> (f64, f64) {
    let roll = f_body.y.atan2(f_body.z);
    let pitch = (-f_body.x).atan2((f_body.y * f_body.y + f_body.z * f_body.z).sqrt());
    (roll, pitch)
}

#[cfg(test)]
mod tests {

    #[test]
    fn the_axis_with_a_heading_has_that_heading_at_any_tilt() {
        // Frames rolled and pitched up to 25° each (tilted up to 35°) and turned every way,
        // headings all round: the axis found has the heading asked for (as the foot-axis
        // observation measures it), and where the frame is a pure yaw it is the difference of
        // yaws the calibration took before.
        let mut worst: f64 = 0.0;
        for k in 0..2000 {
            let t = f64::from(k);
            let roll = 0.44 * (0.37 * t).sin();
            let pitch = 0.44 * (0.91 * t + 1.0).cos();
            let psi = (2.3 * t).sin() * PI;
            let heading = wrap_pi(1.7 * t);
            for q in [from_euler_zyx(roll, pitch, psi), rot_z(psi)] {
                let m = super::yaw_of_axis_with_heading(&q, heading);
                let axis = Vector3::new(m.cos(), -m.sin(), 0.0);
                worst = worst.max(wrap_pi(heading_of_axis(&q, &axis) - heading).abs());
            }
            let m = super::yaw_of_axis_with_heading(&rot_z(psi), heading);
            assert!(wrap_pi(m - (psi - heading)).abs() < 1e-12, "{m} at ψ {psi}");
        }
        assert!(worst < 1e-12, "{worst}");
    }

    #[test]
    fn the_small_angle_series_is_the_exponential_to_rounding() {
        // Angles from 1e-12 rad to just past the series' limit, about axes in every octant:
        // the series and nalgebra's closed form agree to a few units in the last place, and
        // the result is a unit quaternion to rounding.
        let mut worst: f64 = 0.0;
        for k in 0..=400 {
            let angle = 1e-12 * (0.11f64 / 1e-12).powf(f64::from(k) / 400.0);
            for axis in [
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::new(0.3, -0.8, 0.52),
                Vector3::new(-0.6, -0.6, -0.53),
            ] {
                let v = axis.normalize() * angle;
                let got = exp_rotvec(&v);
                let want = UnitQuaternion::from_scaled_axis(v);
                let d = (got.coords - want.coords).amax();
                worst = worst.max(d);
                assert!(d < 4.0 * f64::EPSILON, "angle {angle}: {d:e}");
                assert!((got.coords.norm() - 1.0).abs() < 4.0 * f64::EPSILON);
            }
        }
        assert!(worst > 0.0, "the series was not used");
    }

    #[test]
    fn a_foot_rolling_over_its_contact_moves_a_sensor_above_the_floor() {
        // Foot along nav x; its lateral (left) axis is nav y. A nose-down roll is a positive
        // rotation about y (it takes x towards −z); the top of the foot then moves forward.
        let q = UnitQuaternion::identity();
        let v = rolling_velocity(&q, &Vector3::new(0.0, 2.0, 0.0), 0.08);
        assert!((v - Vector3::new(0.16, 0.0, 0.0)).norm() < 1e-12, "{v}");
        // Rolling over the sole's outer (right) edge, a positive rotation about the forward
        // axis, takes the top of the foot to the right (−y); a twist about the vertical
        // moves nothing.
        let v = rolling_velocity(&q, &Vector3::new(3.0, 0.0, 0.0), 0.08);
        assert!((v - Vector3::new(0.0, -0.24, 0.0)).norm() < 1e-12, "{v}");
        let v = rolling_velocity(&q, &Vector3::new(0.0, 0.0, 1.0), 0.08);
        assert!(v.norm() < 1e-12, "{v}");
        // The same foot walking along nav y (yawed by 90°): the nose-down roll now moves the
        // sensor along nav y, whatever the sensor's axes are called.
        let q = rot_z(std::f64::consts::FRAC_PI_2);
        let v = rolling_velocity(&q, &Vector3::new(0.0, 2.0, 0.0), 0.08);
        assert!((v - Vector3::new(0.0, 0.16, 0.0)).norm() < 1e-12, "{v}");
    }

    use super::*;

    #[test]
    fn newton_and_closed_form_logarithms_agree() {
        let mut worst: f64 = 0.0;
        for i in 0..200 {
            let f = i as f64;
            let axis =
                Vector3::new((f * 0.37).sin(), (f * 0.73).cos(), (f * 1.1).sin() + 0.1).normalize();
            let angle = (f / 200.0) * 3.1; // up to ~178°
            let q = UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle);
            let a = log_half_closed_form(&q);
            let (b, iters) = log_half_newton(&q, 1e-14, 50);
            assert!(iters < 50, "no convergence at angle {angle}");
            worst = worst.max((a - b).norm());
            assert!(((a * 2.0).norm() - angle).abs() < 1e-9);
        }
        assert!(worst < 1e-12, "worst disagreement {worst}");
    }

    #[test]
    fn euler_angles_equal_nalgebras_to_round_off() {
        let mut worst: f64 = 0.0;
        for n in 0..2000 {
            let f = n as f64;
            let v = Vector3::new((f * 0.37).sin(), (f * 0.73).cos(), (f * 1.1).sin() + 0.1);
            let q = exp_rotvec(&(v * (f * 0.013)));
            let (a, b) = (euler_zyx(&q), q.euler_angles());
            let d = [a.0 - b.0, a.1 - b.1, a.2 - b.2];
            worst = worst.max(d.iter().map(|x| wrap_pi(*x).abs()).fold(0.0, f64::max));
        }
        assert!(worst < 1e-14, "worst {worst}");
        // At gimbal lock, nalgebra's branches.
        for pitch in [std::f64::consts::FRAC_PI_2, -std::f64::consts::FRAC_PI_2] {
            let q = from_euler_zyx(0.3, pitch, 0.0);
            let (a, b) = (euler_zyx(&q), q.euler_angles());
            assert!(
                (a.1 - b.1).abs() < 1e-7 && (a.0 - b.0).abs() < 1e-6,
                "{a:?} {b:?}"
            );
        }
    }

    #[test]
    fn exp_log_round_trip() {
        let v = Vector3::new(0.3, -1.2, 0.7);
        assert!((log_rotvec(&exp_rotvec(&v)) - v).norm() < 1e-12);
    }

    #[test]
    fn heading_jacobian_matches_finite_difference() {
        let q = from_euler_zyx(0.4, -0.6, 1.0);
        for axis in [Vector3::x(), Vector3::new(0.3, -0.8, 0.5).normalize()] {
            let j = heading_jacobian(&q, &axis);
            for k in 0..3 {
                let mut d = Vector3::zeros();
                d[k] = 1e-7;
                let num = wrap_pi(
                    heading_of_axis(&(exp_rotvec(&d) * q), &axis) - heading_of_axis(&q, &axis),
                ) / 1e-7;
                assert!((num - j[k]).abs() < 1e-5, "axis {k}: {num} vs {}", j[k]);
            }
        }
        let (_, _, y) = euler_zyx(&q);
        assert!((y - yaw(&q)).abs() < 1e-12);
    }

    #[test]
    fn tilt_from_gravity_recovers_roll_pitch() {
        let q = from_euler_zyx(0.3, -0.4, 2.0);
        let f_body = q.inverse() * Vector3::new(0.0, 0.0, 9.81);
        let (r, p) = tilt_from_specific_force(&f_body);
        assert!((r - 0.3).abs() < 1e-12 && (p + 0.4).abs() < 1e-12);
    }

    #[test]
    fn wrap_is_in_range() {
        assert!((wrap_pi(3.0 * PI) + PI).abs() < 1e-12);
        assert!((wrap_pi(-0.5) + 0.5).abs() < 1e-15);
        assert!((wrap_pi(7.0) - (7.0 - TAU)).abs() < 1e-12);
    }
}
