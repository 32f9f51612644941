//! The paper's 3-state gyro-bias Kalman filter and the two observers that feed it.
//!
//! State: the gyro bias (constant plus an optional random walk: F = I, Q = q²·Δt·I).
//! - [`PaperObserver`] integrates the raw gyro into a quaternion from an epoch at which the
//!   attitude was known; at a stance with a "true" attitude it takes the logarithm of the
//!   quaternion between the two (the accumulated `Σ Ts·(bias + noise)`) and divides by the
//!   elapsed time: an observation of the bias with H = I, which assumes (as the paper does) that
//!   the bias rotation commutes with the body rotation.
//! - [`RotationAwareObserver`] integrates the bias-corrected gyro and keeps `H = Σ C·Δt`, the
//!   body-to-navigation rotation integrated over time, so that `log(q_gyro·q_true⁻¹) + Σ C·b̂·Δt
//!   = H·b` holds to first order for a foot that turns hundreds of degrees per second.

use super::eskf::Innovation;
use super::rotation::{exp_rotvec, log_rotvec};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// The bias filter.
#[derive(Debug, Clone)]
pub struct BiasKf {
    /// Bias estimate, rad/s (frame chosen by the caller).
    pub b_rad_s: Vector3<f64>,
    /// Covariance, (rad/s)².
    pub p: Matrix3<f64>,
    /// The part of a bias error present at the start that the estimate still carries:
    /// `Π (I − K·H)` over the updates (F = I), as the full filter's response (`eskf/response.rs`).
    pub unabsorbed: Matrix3<f64>,
    rw_rad_s_sqrt_s: f64,
    last_t_s: f64,
}

impl BiasKf {
    /// A filter starting at `b0` with σ `sd0` on each axis at time `t_s`.
    pub fn new(b0: Vector3<f64>, sd0: f64, rw_rad_s_sqrt_s: f64, t_s: f64) -> Self {
        Self {
            b_rad_s: b0,
            p: Matrix3::identity() * (sd0 * sd0),
            unabsorbed: Matrix3::identity(),
            rw_rad_s_sqrt_s,
            last_t_s: t_s,
        }
    }

    /// Sets the bias and its covariance (a prior, a saved state): the unabsorbed part starts again.
    pub fn set(&mut self, b_rad_s: Vector3<f64>, p: Matrix3<f64>) {
        self.b_rad_s = b_rad_s;
        self.p = p;
        self.unabsorbed = Matrix3::identity();
    }

    /// Re-expresses the filter in axes turned by `r` (new = r·old).
    pub fn rotate(&mut self, r: &Matrix3<f64>) {
        self.b_rad_s = r * self.b_rad_s;
        self.p = r * self.p * r.transpose();
        self.unabsorbed = r * self.unabsorbed * r.transpose();
    }

    /// Time update to `t_s` (F = I).
    pub fn predict(&mut self, t_s: f64) {
        let dt = (t_s - self.last_t_s).max(0.0);
        self.p += Matrix3::identity() * (self.rw_rad_s_sqrt_s.powi(2) * dt);
        self.last_t_s = t_s;
    }

    /// Measurement update `y = H·b + e`, `e ~ N(0, diag(r_diag))`.
    pub fn update(
        &mut self,
        y: &Vector3<f64>,
        h: &Matrix3<f64>,
        r_diag: &Vector3<f64>,
    ) -> Innovation {
        let r = y - h * self.b_rad_s;
        let s = h * self.p * h.transpose() + Matrix3::from_diagonal(r_diag);
        let Some(s_inv) = s.try_inverse() else {
            return Innovation::default();
        };
        let k = self.p * h.transpose() * s_inv;
        self.b_rad_s += k * r;
        let ikh = Matrix3::identity() - k * h;
        self.unabsorbed = ikh * self.unabsorbed;
        // Joseph form: stays symmetric and positive with the tiny R of long baselines.
        self.p =
            ikh * self.p * ikh.transpose() + k * Matrix3::from_diagonal(r_diag) * k.transpose();
        Innovation {
            r: [r.x, r.y, r.z],
            s_diag: [s[(0, 0)], s[(1, 1)], s[(2, 2)]],
            nis: r.dot(&(s_inv * r)),
            dim: 3,
        }
    }

    /// σ per axis.
    pub fn sd(&self) -> Vector3<f64> {
        self.p.diagonal().map(|v| v.max(0.0).sqrt())
    }
}

/// The paper's observer: raw gyro attitude against the true attitude, H = I.
#[derive(Debug, Clone)]
pub struct PaperObserver {
    q_raw: UnitQuaternion<f64>,
    t0_s: f64,
}

impl PaperObserver {
    /// Starts at epoch `t0_s` with the known attitude `q0`.
    pub fn new(q0: UnitQuaternion<f64>, t0_s: f64) -> Self {
        Self { q_raw: q0, t0_s }
    }

    /// Integrates the raw (uncorrected) body rate over `dt_s`.
    pub fn propagate(&mut self, omega_raw_rad_s: &Vector3<f64>, dt_s: f64) {
        self.q_raw *= exp_rotvec(&(omega_raw_rad_s * dt_s));
    }

    /// The raw gyro attitude.
    pub fn attitude(&self) -> UnitQuaternion<f64> {
        self.q_raw
    }

    /// Starts a new epoch at `t_s` from `q_true` when the raw gyro attitude has drifted more
    /// than `max_angle_rad` from it (the bias integrated since the epoch): the logarithm of
    /// [`PaperObserver::observe`] wraps at π. Says whether it did.
    pub fn restart_if_far(
        &mut self,
        q_true: &UnitQuaternion<f64>,
        t_s: f64,
        max_angle_rad: f64,
    ) -> bool {
        let far = (self.q_raw * q_true.inverse()).angle() > max_angle_rad;
        if far {
            *self = Self::new(*q_true, t_s);
        }
        far
    }

    /// The bias observation at `t_s` given the true attitude: `(y, elapsed_s)` with
    /// `y = log(q_raw·q_true⁻¹)/elapsed` (the rotation vector over the elapsed time).
    pub fn observe(&self, q_true: &UnitQuaternion<f64>, t_s: f64) -> Option<(Vector3<f64>, f64)> {
        let elapsed = t_s - self.t0_s;
        (elapsed > 0.0).then(|| {
            (
                log_rotvec(&(self.q_raw * q_true.inverse())) / elapsed,
                elapsed,
            )
        })
    }
}

/// The rotation-aware observer: bias-corrected gyro attitude and `H = Σ C·Δt`.
#[derive(Debug, Clone)]
pub struct RotationAwareObserver {
    q: UnitQuaternion<f64>,
    h: Matrix3<f64>,
    g: Vector3<f64>,
}

impl RotationAwareObserver {
    /// Starts with the known attitude `q0`.
    pub fn new(q0: UnitQuaternion<f64>) -> Self {
        Self {
            q: q0,
            h: Matrix3::zeros(),
            g: Vector3::zeros(),
        }
    }

    /// Integrates `omega_raw − bias` over `dt_s`, accumulating `H` and `Σ C·b̂·Δt`.
    pub fn propagate(
        &mut self,
        omega_raw_rad_s: &Vector3<f64>,
        bias_rad_s: &Vector3<f64>,
        dt_s: f64,
    ) {
        let w = omega_raw_rad_s - bias_rad_s;
        let mid = self.q * exp_rotvec(&(w * (0.5 * dt_s)));
        let c = mid.to_rotation_matrix().into_inner();
        self.h += c * dt_s;
        self.g += c * bias_rad_s * dt_s;
        self.q = mid * exp_rotvec(&(w * (0.5 * dt_s)));
    }

    /// The observation `(y, H)` with `y = H·b + noise`, given the true attitude.
    pub fn observe(&self, q_true: &UnitQuaternion<f64>) -> (Vector3<f64>, Matrix3<f64>) {
        (log_rotvec(&(self.q * q_true.inverse())) + self.g, self.h)
    }

    /// The corrected gyro attitude.
    pub fn attitude(&self) -> UnitQuaternion<f64> {
        self.q
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rotation::from_euler_zyx;

    /// A body tumbling like a foot (pitch swings and turns) with a constant bias in body axes.
    fn tumble(t: f64) -> Vector3<f64> {
        Vector3::new(
            0.5 * (3.0 * t).sin(),
            4.0 * (6.0 * t).cos(),
            0.8 * (0.7 * t).sin(),
        )
    }

    #[test]
    fn rotation_aware_observer_recovers_bias_of_a_tumbling_body() {
        let b_true = Vector3::new(0.001, 0.001, 0.005);
        let dt = 0.005;
        let q0 = from_euler_zyx(0.3, -0.2, 0.1);
        let mut q_true = q0;
        let mut obs = RotationAwareObserver::new(q0);
        let mut kf = BiasKf::new(Vector3::zeros(), 0.02, 0.0, 0.0);
        let mut paper = PaperObserver::new(q0, 0.0);
        let mut paper_kf = BiasKf::new(Vector3::zeros(), 0.02, 0.0, 0.0);
        for k in 1..=12_000 {
            let t = k as f64 * dt;
            let w = tumble(t);
            q_true *= exp_rotvec(&(w * dt));
            let meas = w + b_true;
            obs.propagate(&meas, &kf.b_rad_s, dt);
            paper.propagate(&meas, dt);
            if k % 200 == 0 {
                let (y, h) = obs.observe(&q_true);
                let r = Vector3::repeat(1e-6);
                kf.update(&y, &h, &r);
                let (yp, el) = paper.observe(&q_true, t).unwrap();
                paper_kf.update(&yp, &Matrix3::identity(), &(r / (el * el)));
            }
        }
        let err = (kf.b_rad_s - b_true).abs();
        assert!(err.max() < 2e-5, "rotation-aware error {err}");
        // The paper's commuting assumption does not hold for a tumbling body: it is far off.
        let perr = (paper_kf.b_rad_s - b_true).abs();
        assert!(perr.max() > 5e-4, "paper error unexpectedly small: {perr}");
    }

    #[test]
    fn the_paper_observer_restarts_its_epoch_before_its_logarithm_wraps() {
        // A daemon's half hour at this sensor's bias (6.5e-3 rad/s), observed once a second
        // with a 1° attitude error: at π of drift (8 minutes) the logarithm turns round.
        let b_true = Vector3::new(3.0e-3, -2.6e-3, 5.2e-3);
        let q0 = from_euler_zyx(0.1, -0.3, 0.7);
        let (dt, sd) = (0.01, 1f64.to_radians());
        for restart in [false, true] {
            let mut p = PaperObserver::new(q0, 0.0);
            let mut kf = BiasKf::new(Vector3::zeros(), 0.02, 0.0, 0.0);
            let mut wrong_at_10_min = false;
            for k in 1..=180_000 {
                p.propagate(&b_true, dt);
                let t = k as f64 * dt;
                if k % 100 == 0 {
                    let (y, el) = p.observe(&q0, t).unwrap();
                    wrong_at_10_min |= k == 60_000 && (y - q0 * b_true).norm() > 1e-3;
                    kf.update(
                        &y,
                        &Matrix3::identity(),
                        &Vector3::repeat((sd / el).powi(2)),
                    );
                    if restart {
                        p.restart_if_far(&q0, t, 2.0);
                    }
                }
            }
            let err = (kf.b_rad_s - q0 * b_true).norm();
            if restart {
                assert!(!wrong_at_10_min && err < 1e-4, "restarted: error {err}");
            } else {
                assert!(
                    wrong_at_10_min && err > 1e-3,
                    "never restarted: error {err}"
                );
            }
        }
    }

    #[test]
    fn paper_observer_is_exact_without_rotation() {
        let b_true = Vector3::new(0.002, -0.001, 0.004);
        let q0 = from_euler_zyx(0.0, 0.0, 0.7);
        let mut p = PaperObserver::new(q0, 1.0);
        for _ in 0..1000 {
            p.propagate(&b_true, 0.01);
        }
        let (y, el) = p.observe(&q0, 11.0).unwrap();
        assert!((el - 10.0).abs() < 1e-12);
        // nav-frame error of a body bias rotated by the constant attitude
        assert!((y - q0 * b_true).norm() < 1e-9, "{y} vs {}", q0 * b_true);
    }
}
