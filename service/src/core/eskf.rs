//! The ZUPT-aided error-state Kalman filter of a foot-mounted INS: the standard filter every
//! corridor result is compared with.
//!
//! Nominal state: position and velocity in the navigation frame (local level, z up),
//! attitude `nav_from_body`, gyro bias in body axes. Error state (12): δp, δv, δθ (navigation
//! frame, applied as `exp(δθ)·q`), δb_g. The covariance is propagated block by block because the
//! transition matrix is sparse; nothing here allocates.

use super::rotation::{exp_rotvec, heading_jacobian, heading_of_axis, skew, wrap_pi};
use nalgebra::{Matrix3, SMatrix, SVector, UnitQuaternion, Vector3};

/// Error-state dimension.
pub const N: usize = 12;
const P0: usize = 0;
const V0: usize = 3;
const TH: usize = 6;
const BG: usize = 9;

type Mat = SMatrix<f64, N, N>;
type Vecn = SVector<f64, N>;

/// Noise figures of the filter.
#[derive(Debug, Clone, Copy)]
pub struct EskfNoise {
    /// Accelerometer white noise σ, m/s².
    pub accel_m_s2: f64,
    /// Gyro white noise σ, rad/s.
    pub gyro_rad_s: f64,
    /// Gyro-bias random walk σ, rad/s/√s (0 freezes the bias states).
    pub gyro_bias_rw: f64,
    /// ZUPT σ, m/s.
    pub zupt_m_s: f64,
}

/// Result of one scalar or vector measurement update.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Innovation {
    /// Innovation components (only the first `dim` are used).
    pub r: [f64; 3],
    /// Diagonal of the innovation covariance S.
    pub s_diag: [f64; 3],
    /// Normalised innovation squared rᵀS⁻¹r.
    pub nis: f64,
    /// Number of components.
    pub dim: u8,
}

/// The filter.
#[derive(Debug, Clone)]
pub struct Eskf {
    /// Position, m, navigation frame.
    pub p_m: Vector3<f64>,
    /// Velocity, m/s, navigation frame.
    pub v_m_s: Vector3<f64>,
    /// Attitude.
    pub nav_from_body: UnitQuaternion<f64>,
    /// Gyro bias, rad/s, body frame.
    pub gyro_bias_rad_s: Vector3<f64>,
    /// Error covariance.
    pub p: Mat,
    gravity_m_s2: f64,
    noise: EskfNoise,
    estimate_bias: bool,
}

impl Eskf {
    /// A filter at rest at the origin with the given attitude, bias and initial σ.
    /// With `estimate_bias == false` the bias states are frozen (zero covariance, no noise):
    /// another estimator then owns the bias.
    pub fn new(
        nav_from_body: UnitQuaternion<f64>,
        gyro_bias_rad_s: Vector3<f64>,
        tilt_sd_rad: f64,
        bias_sd_rad_s: f64,
        gravity_m_s2: f64,
        noise: EskfNoise,
        estimate_bias: bool,
    ) -> Self {
        let mut p = Mat::zeros();
        for i in 0..3 {
            p[(P0 + i, P0 + i)] = 1e-6;
            p[(V0 + i, V0 + i)] = 1e-6;
            if estimate_bias {
                p[(BG + i, BG + i)] = bias_sd_rad_s * bias_sd_rad_s;
            }
        }
        p[(TH, TH)] = tilt_sd_rad * tilt_sd_rad;
        p[(TH + 1, TH + 1)] = tilt_sd_rad * tilt_sd_rad;
        p[(TH + 2, TH + 2)] = 1e-6; // heading is defined by the alignment
        Self {
            p_m: Vector3::zeros(),
            v_m_s: Vector3::zeros(),
            nav_from_body,
            gyro_bias_rad_s,
            p,
            gravity_m_s2,
            noise,
            estimate_bias,
        }
    }

    /// Whether the filter owns the gyro bias.
    pub fn estimates_bias(&self) -> bool {
        self.estimate_bias
    }

    /// Gravity magnitude in use.
    pub fn gravity_m_s2(&self) -> f64 {
        self.gravity_m_s2
    }

    /// Strapdown step over `dt_s` with the bias-corrected body rate `omega_rad_s` (already
    /// averaged over the step) and the specific force `f_m_s2`, then covariance propagation.
    pub fn propagate(&mut self, omega_rad_s: &Vector3<f64>, f_m_s2: &Vector3<f64>, dt_s: f64) {
        let step_half = exp_rotvec(&(omega_rad_s * (0.5 * dt_s)));
        let half = self.nav_from_body * step_half;
        let f_nav = half * f_m_s2;
        let a = f_nav - Vector3::new(0.0, 0.0, self.gravity_m_s2);
        self.p_m += self.v_m_s * dt_s + a * (0.5 * dt_s * dt_s);
        self.v_m_s += a * dt_s;
        self.nav_from_body = half * step_half;
        let c = half.to_rotation_matrix().into_inner();
        self.propagate_covariance(&(-skew(&f_nav) * dt_s), &(-c * dt_s), dt_s);
    }

    /// P ← F P Fᵀ + Q for F = [[I, dt, 0, 0], [0, I, Fvθ, 0], [0, 0, I, Fθb], [0, 0, 0, I]].
    /// Written out by blocks on the column-major storage: F is sparse, so this is about 500
    /// multiply-adds instead of the 3,500 of a dense product (the hot path of the core).
    fn propagate_covariance(&mut self, f_vth: &Matrix3<f64>, f_thb: &Matrix3<f64>, dt: f64) {
        let fvt: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|k| f_vth[(i, k)]));
        let ftb: [[f64; 3]; 3] = if self.estimate_bias {
            std::array::from_fn(|i| std::array::from_fn(|k| f_thb[(i, k)]))
        } else {
            [[0.0; 3]; 3]
        };
        let a = self.p.as_mut_slice(); // column-major: a[col * N + row]
        // M = F P: for each column, rows p, v, θ read the old rows v, θ, b.
        for col in a.chunks_exact_mut(N) {
            let v = [col[V0], col[V0 + 1], col[V0 + 2]];
            let th = [col[TH], col[TH + 1], col[TH + 2]];
            let b = [col[BG], col[BG + 1], col[BG + 2]];
            for i in 0..3 {
                col[P0 + i] += dt * v[i];
                col[V0 + i] += fvt[i][0] * th[0] + fvt[i][1] * th[1] + fvt[i][2] * th[2];
                col[TH + i] += ftb[i][0] * b[0] + ftb[i][1] * b[1] + ftb[i][2] * b[2];
            }
        }
        // P' = M Fᵀ: columns p, v, θ read the old columns v, θ, b.
        for row in 0..N {
            let v = [
                a[V0 * N + row],
                a[(V0 + 1) * N + row],
                a[(V0 + 2) * N + row],
            ];
            let th = [
                a[TH * N + row],
                a[(TH + 1) * N + row],
                a[(TH + 2) * N + row],
            ];
            let b = [
                a[BG * N + row],
                a[(BG + 1) * N + row],
                a[(BG + 2) * N + row],
            ];
            for k in 0..3 {
                a[(P0 + k) * N + row] += dt * v[k];
                a[(V0 + k) * N + row] += th[0] * fvt[k][0] + th[1] * fvt[k][1] + th[2] * fvt[k][2];
                a[(TH + k) * N + row] += b[0] * ftb[k][0] + b[1] * ftb[k][1] + b[2] * ftb[k][2];
            }
        }
        let qa = self.noise.accel_m_s2.powi(2) * dt;
        let qg = self.noise.gyro_rad_s.powi(2) * dt;
        let qb = if self.estimate_bias {
            self.noise.gyro_bias_rw.powi(2) * dt
        } else {
            0.0
        };
        for i in 0..3 {
            a[(V0 + i) * N + V0 + i] += qa;
            a[(TH + i) * N + TH + i] += qg;
            a[(BG + i) * N + BG + i] += qb;
        }
    }

    /// Zero-velocity update.
    pub fn zupt(&mut self) -> Innovation {
        let r = -self.v_m_s;
        let mut s = self.p.fixed_view::<3, 3>(V0, V0).into_owned();
        let rv = self.noise.zupt_m_s.powi(2);
        for i in 0..3 {
            s[(i, i)] += rv;
        }
        let Some(s_inv) = s.try_inverse() else {
            return Innovation::default();
        };
        let pht = self.p.fixed_view::<N, 3>(0, V0).into_owned();
        let k = pht * s_inv;
        let dx = k * r;
        // P ← P − K·P_v: (the product is symmetric) computed on one triangle and mirrored.
        for j in 0..N {
            for i in 0..=j {
                let d = k[(i, 0)] * pht[(j, 0)] + k[(i, 1)] * pht[(j, 1)] + k[(i, 2)] * pht[(j, 2)];
                let v = self.p[(i, j)] - d;
                self.p[(i, j)] = v;
                self.p[(j, i)] = v;
            }
        }
        self.inject(&dx);
        Innovation {
            r: [r.x, r.y, r.z],
            s_diag: [s[(0, 0)], s[(1, 1)], s[(2, 2)]],
            nis: r.dot(&(s_inv * r)),
            dim: 3,
        }
    }

    /// Heading of the body-frame direction `axis_body` (e.g. the foot's forward axis):
    /// observed value `heading_obs_rad` with σ `sd_rad`.
    pub fn heading_update(
        &mut self,
        heading_obs_rad: f64,
        sd_rad: f64,
        axis_body: &Vector3<f64>,
    ) -> Innovation {
        let r = wrap_pi(heading_obs_rad - heading_of_axis(&self.nav_from_body, axis_body));
        let h = heading_jacobian(&self.nav_from_body, axis_body);
        let pht: SVector<f64, N> = self.p.fixed_view::<N, 3>(0, TH) * h;
        let s = h.dot(&pht.fixed_rows::<3>(TH)) + sd_rad * sd_rad;
        let k = pht / s;
        let dx = k * r;
        let hp = pht.transpose();
        self.p -= k * hp;
        self.symmetrize();
        self.inject(&dx);
        Innovation {
            r: [r, 0.0, 0.0],
            s_diag: [s, 0.0, 0.0],
            nis: r * r / s,
            dim: 1,
        }
    }

    fn inject(&mut self, dx: &Vecn) {
        self.p_m += dx.fixed_rows::<3>(P0);
        self.v_m_s += dx.fixed_rows::<3>(V0);
        self.nav_from_body = exp_rotvec(&dx.fixed_rows::<3>(TH).into_owned()) * self.nav_from_body;
        if self.estimate_bias {
            self.gyro_bias_rad_s += dx.fixed_rows::<3>(BG);
        }
    }

    fn symmetrize(&mut self) {
        let t = self.p.transpose();
        self.p = (self.p + t) * 0.5;
    }

    /// Rotates the navigation frame about z by `angle_rad` (used once the map frame is known).
    pub fn rotate_frame(&mut self, angle_rad: f64) {
        let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), angle_rad);
        let m = *r.matrix();
        self.p_m = m * self.p_m;
        self.v_m_s = m * self.v_m_s;
        self.nav_from_body = UnitQuaternion::from_rotation_matrix(&r) * self.nav_from_body;
        let mut t = Mat::identity();
        for b in [P0, V0, TH] {
            t.fixed_view_mut::<3, 3>(b, b).copy_from(&m);
        }
        self.p = t * self.p * t.transpose();
    }

    /// Sets the heading variance (after the map frame is fixed, the heading is known).
    pub fn set_heading_variance(&mut self, var_rad2: f64) {
        for j in 0..N {
            self.p[(TH + 2, j)] = 0.0;
            self.p[(j, TH + 2)] = 0.0;
        }
        self.p[(TH + 2, TH + 2)] = var_rad2;
    }

    /// Sets the gyro bias and its covariance block (clearing its correlations), when the filter
    /// owns the bias.
    pub fn set_gyro_bias(&mut self, bias_rad_s: Vector3<f64>, cov: &Matrix3<f64>) {
        if !self.estimate_bias {
            return;
        }
        self.gyro_bias_rad_s = bias_rad_s;
        for j in 0..N {
            for i in 0..3 {
                self.p[(BG + i, j)] = 0.0;
                self.p[(j, BG + i)] = 0.0;
            }
        }
        self.p.fixed_view_mut::<3, 3>(BG, BG).copy_from(cov);
    }

    /// Covariance block of the gyro bias.
    pub fn gyro_bias_cov(&self) -> Matrix3<f64> {
        self.p.fixed_view::<3, 3>(BG, BG).into_owned()
    }

    /// σ of the gyro-bias states.
    pub fn gyro_bias_sd(&self) -> Vector3<f64> {
        Vector3::new(
            self.p[(BG, BG)].max(0.0).sqrt(),
            self.p[(BG + 1, BG + 1)].max(0.0).sqrt(),
            self.p[(BG + 2, BG + 2)].max(0.0).sqrt(),
        )
    }

    /// σ of the attitude error (navigation frame).
    pub fn attitude_sd(&self) -> Vector3<f64> {
        Vector3::new(
            self.p[(TH, TH)].max(0.0).sqrt(),
            self.p[(TH + 1, TH + 1)].max(0.0).sqrt(),
            self.p[(TH + 2, TH + 2)].max(0.0).sqrt(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn noise() -> EskfNoise {
        EskfNoise {
            accel_m_s2: 0.5,
            gyro_rad_s: 0.01,
            gyro_bias_rw: 1e-4,
            zupt_m_s: 0.01,
        }
    }

    #[test]
    fn block_propagation_equals_dense_formula() {
        let mut f = Eskf::new(
            crate::core::rotation::from_euler_zyx(0.2, -0.3, 1.0),
            Vector3::zeros(),
            0.01,
            0.01,
            9.81,
            noise(),
            true,
        );
        // give P some structure
        for _ in 0..3 {
            f.propagate(
                &Vector3::new(1.0, -2.0, 0.5),
                &Vector3::new(1.0, 2.0, 9.0),
                0.005,
            );
            f.zupt();
        }
        let p_before = f.p;
        let q_before = f.nav_from_body;
        let omega = Vector3::new(0.5, 3.0, -1.0);
        let acc = Vector3::new(2.0, -1.0, 10.0);
        let dt = 0.005;
        f.propagate(&omega, &acc, dt);
        let half = q_before * exp_rotvec(&(omega * (0.5 * dt)));
        let c = half.to_rotation_matrix().into_inner();
        let mut big_f = Mat::identity();
        big_f
            .fixed_view_mut::<3, 3>(P0, V0)
            .copy_from(&(Matrix3::identity() * dt));
        big_f
            .fixed_view_mut::<3, 3>(V0, TH)
            .copy_from(&(-skew(&(half * acc)) * dt));
        big_f.fixed_view_mut::<3, 3>(TH, BG).copy_from(&(-c * dt));
        let mut q = Mat::zeros();
        for i in 0..3 {
            q[(V0 + i, V0 + i)] = 0.25 * dt;
            q[(TH + i, TH + i)] = 1e-4 * dt;
            q[(BG + i, BG + i)] = 1e-8 * dt;
        }
        let dense = big_f * p_before * big_f.transpose() + q;
        assert!(
            (dense - f.p).abs().max() < 1e-15,
            "{}",
            (dense - f.p).abs().max()
        );
    }

    #[test]
    fn heading_updates_make_z_bias_observable() {
        // Static sensor, level, with a z bias of 0.01 rad/s the filter does not know.
        let mut f = Eskf::new(
            UnitQuaternion::identity(),
            Vector3::zeros(),
            0.01,
            0.02,
            9.81,
            noise(),
            true,
        );
        let true_bias = Vector3::new(0.0, 0.0, 0.01);
        let g = Vector3::new(0.0, 0.0, 9.81);
        let dt = 0.005;
        for k in 0..4000 {
            let omega = true_bias - f.gyro_bias_rad_s;
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
}
