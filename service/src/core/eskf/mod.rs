//! The ZUPT-aided error-state Kalman filter of a foot-mounted INS: the standard filter every
//! corridor result is compared with, with switchable model extensions.
//!
//! Nominal state: position and velocity in the navigation frame (local level, z up),
//! attitude `nav_from_body`, gyro bias in body axes, and the enabled extensions:
//! - gyro-bias rate (3 states: the bias drifts linearly, with a random walk on the rate);
//! - gyro scale factor per body axis (3 states: `ω_meas = (1 + s)·ω + b`);
//! - foot-heading offset (1 state: the foot points `offset` away from the walking direction
//!   the map gives, e.g. a toe-out that differs from the one calibrated at the start);
//! - g-sensitivity, diagonal (3 states: `ω_meas = ω + b + k∘f`);
//! - the previous footprint (2 states: a stochastic clone of the horizontal position at the
//!   last stance, so that the direction of the stride since then can be observed).
//!
//! Error state: δp, δv, δθ (navigation frame, applied as `exp(δθ)·q`), δb, then the extensions
//! in that order. The covariance lives in a fixed array sized for every extension, is propagated
//! block by block (the transition matrix is sparse), and nothing here allocates.
//!
//! Files: this one holds the filter's state and its strapdown step; `covariance.rs` the block
//! propagation of the covariance; `updates.rs` the measurement updates (ZUPT, foot-axis heading,
//! stride direction with its footprint clone).

use super::rotation::{exp_rotvec, heading_jacobian, heading_of_axis, skew, wrap_pi};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// Largest error-state dimension (12 base states and 12 extension states).
pub const MAX_N: usize = 24;
const P0: usize = 0;
const V0: usize = 3;
const TH: usize = 6;
const BG: usize = 9;

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

/// Whether the filter estimates the gyro bias.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BiasStates {
    /// The bias states are estimated (`zupt`, `eskf`).
    Estimated,
    /// The bias states are frozen (zero covariance, no noise): another estimator owns the bias.
    Frozen,
}

/// The filter's starting point.
#[derive(Debug, Clone, Copy)]
pub struct EskfInit {
    /// Attitude `nav_from_body`.
    pub nav_from_body: UnitQuaternion<f64>,
    /// Gyro bias, rad/s, body axes.
    pub gyro_bias_rad_s: Vector3<f64>,
    /// Initial roll and pitch σ, rad.
    pub tilt_sd_rad: f64,
    /// Initial gyro-bias σ, rad/s (unused when the bias states are frozen).
    pub bias_sd_rad_s: f64,
    /// Gravity magnitude, m/s².
    pub gravity_m_s2: f64,
    /// Whether the bias states are estimated.
    pub bias: BiasStates,
}

/// Which extension states the filter carries, with their initial σ and noise.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Extensions {
    /// Bias-rate states: random walk of the rate, rad/s²/√s (`None`: off).
    pub bias_rate_rw: Option<f64>,
    /// Initial σ of the bias rate, rad/s² (used when the bias-rate states are on).
    pub bias_rate_sd: f64,
    /// Scale-factor states: initial σ, dimensionless (`None`: off).
    pub scale_factor_sd: Option<f64>,
    /// Heading-offset state: initial σ, rad (`None`: off).
    pub heading_offset_sd: Option<f64>,
    /// g-sensitivity states: initial σ, rad/s per m/s² (`None`: off).
    pub g_sensitivity_sd: Option<f64>,
    /// Footprint-clone states for stride-direction observations.
    pub footprint_clone: bool,
}

/// Indices of the extension states in the error state.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Layout {
    n: usize,
    rate: Option<usize>,
    scale: Option<usize>,
    offset: Option<usize>,
    gsens: Option<usize>,
    clone: Option<usize>,
}

impl Layout {
    fn new(ext: &Extensions) -> Self {
        let mut n = 12;
        let mut take = |on: bool, k: usize| {
            on.then(|| {
                n += k;
                n - k
            })
        };
        let rate = take(ext.bias_rate_rw.is_some(), 3);
        let scale = take(ext.scale_factor_sd.is_some(), 3);
        let offset = take(ext.heading_offset_sd.is_some(), 1);
        let gsens = take(ext.g_sensitivity_sd.is_some(), 3);
        let clone = take(ext.footprint_clone, 2);
        Self {
            n,
            rate,
            scale,
            offset,
            gsens,
            clone,
        }
    }

    /// Whether every extension state is constant between updates (F = I, no noise): the
    /// heading offset and the footprint clone. Then the base block propagation serves.
    fn static_extensions_only(&self) -> bool {
        self.rate.is_none() && self.scale.is_none() && self.gsens.is_none()
    }
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

/// The extension estimates.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ExtensionEstimates {
    /// Gyro-bias rate, rad/s², body axes.
    pub bias_rate_rad_s2: Vector3<f64>,
    /// Gyro scale factor per body axis (0 = nominal).
    pub scale_factor: Vector3<f64>,
    /// Foot-heading offset, rad.
    pub heading_offset_rad: f64,
    /// g-sensitivity, rad/s per m/s², body axes.
    pub g_sensitivity: Vector3<f64>,
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
    /// Extension estimates (zero when an extension is off).
    pub ext: ExtensionEstimates,
    /// The cloned footprint (horizontal position at the last clone), m; NaN before the first.
    pub footprint_xy_m: [f64; 2],
    /// Error covariance, column-major with stride `MAX_N`; only the leading `n × n` is used.
    p: [f64; MAX_N * MAX_N],
    layout: Layout,
    gravity_m_s2: f64,
    noise: EskfNoise,
    ext_cfg: Extensions,
    estimate_bias: bool,
}

/// One row of a sparse measurement Jacobian: (state index, value) pairs.
type SparseRow = [(usize, f64); 4];

#[inline]
fn ix(r: usize, c: usize) -> usize {
    c * MAX_N + r
}

/// Dimension without extensions.
const BASE_N: usize = 12;

mod covariance;
mod updates;

impl Eskf {
    /// A filter at rest at the origin with the given attitude, bias and initial σ.
    pub fn new(init: EskfInit, noise: EskfNoise, ext: Extensions) -> Self {
        let EskfInit {
            nav_from_body,
            gyro_bias_rad_s,
            tilt_sd_rad,
            bias_sd_rad_s,
            gravity_m_s2,
            bias,
        } = init;
        let estimate_bias = bias == BiasStates::Estimated;
        let layout = Layout::new(&ext);
        let mut f = Self {
            p_m: Vector3::zeros(),
            v_m_s: Vector3::zeros(),
            nav_from_body,
            gyro_bias_rad_s,
            ext: ExtensionEstimates::default(),
            footprint_xy_m: [f64::NAN; 2],
            p: [0.0; MAX_N * MAX_N],
            layout,
            gravity_m_s2,
            noise,
            ext_cfg: ext,
            estimate_bias,
        };
        let mut set = |i: usize, var: f64| f.p[ix(i, i)] = var;
        for i in 0..3 {
            set(P0 + i, 1e-6);
            set(V0 + i, 1e-6);
            if estimate_bias {
                set(BG + i, bias_sd_rad_s * bias_sd_rad_s);
            }
        }
        set(TH, tilt_sd_rad * tilt_sd_rad);
        set(TH + 1, tilt_sd_rad * tilt_sd_rad);
        set(TH + 2, 1e-6); // heading is defined by the alignment
        if let Some(i) = layout.rate.filter(|_| estimate_bias) {
            for k in 0..3 {
                set(i + k, ext.bias_rate_sd * ext.bias_rate_sd);
            }
        }
        if let (Some(i), Some(sd)) = (layout.scale, ext.scale_factor_sd) {
            for k in 0..3 {
                set(i + k, sd * sd);
            }
        }
        if let (Some(i), Some(sd)) = (layout.offset, ext.heading_offset_sd) {
            set(i, sd * sd);
        }
        if let (Some(i), Some(sd)) = (layout.gsens, ext.g_sensitivity_sd) {
            for k in 0..3 {
                set(i + k, sd * sd);
            }
        }
        f
    }

    /// Copies `src`'s state into `self` (same configuration): the nominal state and the
    /// leading `n × n` of the covariance only, a fraction of a full clone. For the restores of
    /// the health check.
    pub fn copy_state_from(&mut self, src: &Eskf) {
        self.copy_nominal_from(src);
        let n = src.layout.n;
        for c in 0..n {
            let col = c * MAX_N;
            self.p[col..col + n].copy_from_slice(&src.p[col..col + n]);
        }
    }

    /// Copies everything of `src` but the covariance.
    fn copy_nominal_from(&mut self, src: &Eskf) {
        self.p_m = src.p_m;
        self.v_m_s = src.v_m_s;
        self.nav_from_body = src.nav_from_body;
        self.gyro_bias_rad_s = src.gyro_bias_rad_s;
        self.ext = src.ext;
        self.footprint_xy_m = src.footprint_xy_m;
        self.layout = src.layout;
        self.gravity_m_s2 = src.gravity_m_s2;
        self.noise = src.noise;
        self.ext_cfg = src.ext_cfg;
        self.estimate_bias = src.estimate_bias;
    }

    /// Copies the upper triangle of the covariance onto the lower one.
    fn mirror_upper(&mut self) {
        for j in 0..self.layout.n {
            for i in 0..j {
                self.p[ix(j, i)] = self.p[ix(i, j)];
            }
        }
    }

    /// Error-state dimension in use.
    pub fn dim(&self) -> usize {
        self.layout.n
    }

    /// Gravity magnitude in use.
    pub fn gravity_m_s2(&self) -> f64 {
        self.gravity_m_s2
    }

    /// Covariance element.
    pub fn cov(&self, r: usize, c: usize) -> f64 {
        self.p[ix(r, c)]
    }

    /// The diagonal of the covariance in use (`n` elements).
    pub fn cov_diagonal(&self) -> impl Iterator<Item = &f64> {
        // Indexed rather than `step_by`: this runs on every sample (the health check), and
        // `StepBy`'s fold did not inline (6 % of the eskf mode's time in a profile).
        (0..self.layout.n).map(move |i| &self.p[i * (MAX_N + 1)])
    }

    /// The body rate corrected for the filter's own error model (scale factor and
    /// g-sensitivity) and for `bias_rad_s` (the filter's own bias, or an external one).
    pub fn corrected_rate(
        &self,
        omega_meas_rad_s: &Vector3<f64>,
        f_m_s2: &Vector3<f64>,
        bias_rad_s: &Vector3<f64>,
    ) -> Vector3<f64> {
        let mut w = omega_meas_rad_s - bias_rad_s;
        if self.layout.gsens.is_some() {
            w -= self.ext.g_sensitivity.component_mul(f_m_s2);
        }
        if self.layout.scale.is_some() {
            w = w.component_div(&(Vector3::repeat(1.0) + self.ext.scale_factor));
        }
        w
    }

    /// Strapdown step over `dt_s` with the corrected body rate `omega_rad_s` (see
    /// [`Eskf::corrected_rate`], already averaged over the step) and the specific force
    /// `f_m_s2`, then covariance propagation. In place, through a copy of the filter: the
    /// per-sample path uses [`Eskf::propagate_into`].
    pub fn propagate(&mut self, omega_rad_s: &Vector3<f64>, f_m_s2: &Vector3<f64>, dt_s: f64) {
        let before = self.clone();
        before.propagate_into(self, omega_rad_s, f_m_s2, dt_s);
    }

    /// [`Eskf::propagate`] written into `next` (a copy of this filter, whatever state it holds
    /// now: the configuration must be the same), leaving `self` as it was: the estimator keeps the state before each
    /// sample for its health check this way, without copying it (the copy of the covariance is
    /// part of the propagation's first pass).
    pub fn propagate_into(
        &self,
        next: &mut Eskf,
        omega_rad_s: &Vector3<f64>,
        f_m_s2: &Vector3<f64>,
        dt_s: f64,
    ) {
        // `next` has this filter's configuration (it is a copy of it; nothing changes the
        // configuration after `new`): only the state is copied, what the step changes is
        // written below.
        debug_assert!(next.layout == self.layout && next.ext_cfg == self.ext_cfg);
        next.gyro_bias_rad_s = self.gyro_bias_rad_s;
        next.ext = self.ext;
        next.footprint_xy_m = self.footprint_xy_m;
        let step_half = exp_rotvec(&(omega_rad_s * (0.5 * dt_s)));
        let half = self.nav_from_body * step_half;
        let f_nav = half * f_m_s2;
        let a = f_nav - Vector3::new(0.0, 0.0, self.gravity_m_s2);
        next.p_m = self.p_m + (self.v_m_s * dt_s + a * (0.5 * dt_s * dt_s));
        next.v_m_s = self.v_m_s + a * dt_s;
        next.nav_from_body = half * step_half;
        if self.layout.rate.is_some() {
            next.gyro_bias_rad_s = self.gyro_bias_rad_s + self.ext.bias_rate_rad_s2 * dt_s;
        }
        let c = half.to_rotation_matrix().into_inner();
        next.propagate_covariance_from(
            &self.p,
            &(-skew(&f_nav) * dt_s),
            &(-c * dt_s),
            omega_rad_s,
            f_m_s2,
            dt_s,
        );
    }

    fn inject(&mut self, dx: &[f64; MAX_N]) {
        let v3 = |i: usize| Vector3::new(dx[i], dx[i + 1], dx[i + 2]);
        self.p_m += v3(P0);
        self.v_m_s += v3(V0);
        self.nav_from_body = exp_rotvec(&v3(TH)) * self.nav_from_body;
        if self.estimate_bias {
            self.gyro_bias_rad_s += v3(BG);
            if let Some(i) = self.layout.rate {
                self.ext.bias_rate_rad_s2 += v3(i);
            }
        }
        if let Some(i) = self.layout.scale {
            self.ext.scale_factor += v3(i);
        }
        if let Some(i) = self.layout.offset {
            self.ext.heading_offset_rad += dx[i];
        }
        if let Some(i) = self.layout.gsens {
            self.ext.g_sensitivity += v3(i);
        }
        if let Some(i) = self.layout.clone {
            self.footprint_xy_m[0] += dx[i];
            self.footprint_xy_m[1] += dx[i + 1];
        }
    }

    /// Rotates the navigation frame about z by `angle_rad` (used once the map frame is known).
    pub fn rotate_frame(&mut self, angle_rad: f64) {
        let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), angle_rad);
        let m = *r.matrix();
        self.p_m = m * self.p_m;
        self.v_m_s = m * self.v_m_s;
        self.nav_from_body = UnitQuaternion::from_rotation_matrix(&r) * self.nav_from_body;
        // P ← T P Tᵀ with T = blockdiag(R, R, R, I, …): rows then columns of the p, v, θ blocks.
        let n = self.layout.n;
        if let Some(c) = self.layout.clone {
            let [x, y] = self.footprint_xy_m;
            self.footprint_xy_m = [m[(0, 0)] * x + m[(0, 1)] * y, m[(1, 0)] * x + m[(1, 1)] * y];
            // The clone is horizontal: T acts on it with the upper-left 2 × 2 of R.
            for c2 in 0..n {
                let x = [self.p[ix(c, c2)], self.p[ix(c + 1, c2)]];
                for i in 0..2 {
                    self.p[ix(c + i, c2)] = m[(i, 0)] * x[0] + m[(i, 1)] * x[1];
                }
            }
            for rr in 0..n {
                let x = [self.p[ix(rr, c)], self.p[ix(rr, c + 1)]];
                for i in 0..2 {
                    self.p[ix(rr, c + i)] = m[(i, 0)] * x[0] + m[(i, 1)] * x[1];
                }
            }
        }
        for b in [P0, V0, TH] {
            for c in 0..n {
                let x = [self.p[ix(b, c)], self.p[ix(b + 1, c)], self.p[ix(b + 2, c)]];
                for i in 0..3 {
                    self.p[ix(b + i, c)] = m[(i, 0)] * x[0] + m[(i, 1)] * x[1] + m[(i, 2)] * x[2];
                }
            }
            for rr in 0..n {
                let x = [
                    self.p[ix(rr, b)],
                    self.p[ix(rr, b + 1)],
                    self.p[ix(rr, b + 2)],
                ];
                for i in 0..3 {
                    self.p[ix(rr, b + i)] = m[(i, 0)] * x[0] + m[(i, 1)] * x[1] + m[(i, 2)] * x[2];
                }
            }
        }
    }

    /// After a gap in the data of `gap_s`: nothing is integrated over it; the velocity variance
    /// grows by `vel_var` and the attitude variance by the gyro noise over the gap.
    pub fn widen_after_gap(&mut self, gap_s: f64, vel_var: f64) {
        let att_var = self.noise.gyro_rad_s.powi(2) * gap_s;
        for i in 0..3 {
            self.p[ix(V0 + i, V0 + i)] += vel_var;
            self.p[ix(TH + i, TH + i)] += att_var;
        }
    }

    /// A rotation of unknown size about the body axis `axis_body` (unit vector) with variance
    /// `var_rad2` happened: the attitude covariance grows along that axis (in the navigation
    /// frame). Used for the rotation a clipped gyro axis did not measure.
    pub fn widen_attitude_about(&mut self, axis_body: &Vector3<f64>, var_rad2: f64) {
        let a = self.nav_from_body * axis_body;
        for i in 0..3 {
            for j in 0..3 {
                self.p[ix(TH + i, TH + j)] += var_rad2 * a[i] * a[j];
            }
        }
    }

    /// Sets the heading variance (after the map frame is fixed, the heading is known).
    pub fn set_heading_variance(&mut self, var_rad2: f64) {
        self.clear_state(TH + 2, var_rad2);
    }

    fn clear_state(&mut self, i: usize, var: f64) {
        for j in 0..self.layout.n {
            self.p[ix(i, j)] = 0.0;
            self.p[ix(j, i)] = 0.0;
        }
        self.p[ix(i, i)] = var;
    }

    /// Sets the gyro bias and its covariance block (clearing its correlations), when the filter
    /// owns the bias.
    pub fn set_gyro_bias(&mut self, bias_rad_s: Vector3<f64>, cov: &Matrix3<f64>) {
        if !self.estimate_bias {
            return;
        }
        self.gyro_bias_rad_s = bias_rad_s;
        for i in 0..3 {
            self.clear_state(BG + i, 0.0);
        }
        for i in 0..3 {
            for j in 0..3 {
                self.p[ix(BG + i, BG + j)] = cov[(i, j)];
            }
        }
    }

    /// Covariance block of the gyro bias.
    pub fn gyro_bias_cov(&self) -> Matrix3<f64> {
        Matrix3::from_fn(|i, j| self.p[ix(BG + i, BG + j)])
    }

    /// σ of the gyro-bias states.
    pub fn gyro_bias_sd(&self) -> Vector3<f64> {
        Vector3::from_fn(|i, _| self.p[ix(BG + i, BG + i)].max(0.0).sqrt())
    }

    /// σ of the heading-offset state, when enabled.
    pub fn heading_offset_sd(&self) -> Option<f64> {
        self.layout.offset.map(|i| self.p[ix(i, i)].max(0.0).sqrt())
    }

    /// σ of the scale-factor states, when enabled.
    pub fn scale_factor_sd(&self) -> Option<Vector3<f64>> {
        self.layout
            .scale
            .map(|i| Vector3::from_fn(|k, _| self.p[ix(i + k, i + k)].max(0.0).sqrt()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rotation::from_euler_zyx;

    fn noise() -> EskfNoise {
        EskfNoise {
            accel_m_s2: 0.5,
            gyro_rad_s: 0.01,
            gyro_bias_rw: 1e-4,
            zupt_m_s: 0.01,
        }
    }

    fn all_ext() -> Extensions {
        Extensions {
            bias_rate_rw: Some(1e-5),
            bias_rate_sd: 1e-4,
            scale_factor_sd: Some(0.01),
            heading_offset_sd: Some(0.05),
            g_sensitivity_sd: Some(1e-3),
            footprint_clone: true,
        }
    }

    /// No extension; only the static ones (the base block propagation's fast path); all.
    fn extension_sets() -> [Extensions; 3] {
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
        Eskf::new(
            EskfInit {
                nav_from_body,
                gyro_bias_rad_s,
                tilt_sd_rad,
                bias_sd_rad_s,
                gravity_m_s2: 9.81,
                bias: BiasStates::Estimated,
            },
            noise(),
            ext,
        )
    }

    fn dense(f: &Eskf) -> nalgebra::DMatrix<f64> {
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
            a.propagate_into(&mut spare, &omega, &acc, 0.005);
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
            let mut f = filter(
                from_euler_zyx(0.2, -0.3, 1.0),
                Vector3::zeros(),
                0.01,
                0.01,
                ext,
            );
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
            let mut put = |r: usize, cc: usize, m: &Matrix3<f64>| {
                big_f.view_mut((r, cc), (3, 3)).copy_from(m)
            };
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
    fn update_matches_the_textbook_kalman_formulas() {
        let mut f = filter(
            from_euler_zyx(0.2, -0.3, 1.0),
            Vector3::zeros(),
            0.01,
            0.01,
            all_ext(),
        );
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
        let mut h = nalgebra::DMatrix::<f64>::zeros(3, n);
        for i in 0..3 {
            h[(i, V0 + i)] = 1.0;
        }
        let s = &h * &p * h.transpose() + nalgebra::DMatrix::<f64>::identity(3, 3) * 1e-4;
        let k = &p * h.transpose() * s.clone().try_inverse().unwrap();
        let want = &p - &k * &h * &p;
        let v_before = f.v_m_s;
        let dx =
            &k * nalgebra::DVector::from_column_slice(&[-v_before.x, -v_before.y, -v_before.z]);
        f.zupt();
        assert!((want - dense(&f)).abs().max() < 1e-15);
        assert!(
            (f.v_m_s - (v_before + Vector3::new(dx[V0], dx[V0 + 1], dx[V0 + 2]))).norm() < 1e-14
        );
    }

    #[test]
    fn heading_updates_make_z_bias_observable() {
        // Static sensor, level, with a z bias of 0.01 rad/s the filter does not know.
        let mut f = filter(
            UnitQuaternion::identity(),
            Vector3::zeros(),
            0.01,
            0.02,
            Extensions::default(),
        );
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
        let mut f = filter(
            UnitQuaternion::identity(),
            Vector3::zeros(),
            0.01,
            1e-4,
            ext,
        );
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
                gyro_bias_rw: 1e-6,
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
        let mut f = filter(
            UnitQuaternion::identity(),
            Vector3::zeros(),
            0.01,
            1e-4,
            ext,
        );
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
    }

    #[test]
    fn a_stance_velocity_update_pulls_the_velocity_to_the_expected_one() {
        let mut f = filter(
            UnitQuaternion::identity(),
            Vector3::zeros(),
            0.01,
            0.01,
            Extensions::default(),
        );
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
        let mut f = filter(
            UnitQuaternion::identity(),
            Vector3::zeros(),
            0.01,
            1e-5,
            ext,
        );
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
}
