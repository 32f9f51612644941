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
//! - gyro cross-coupling into the body z axis (2 states: the z gyro also reads
//!   `m_zx·ω_x + m_zy·ω_y`; an axis misalignment as it reaches the heading when z is the axis
//!   nearest the vertical);
//! - the previous footprint (2 states: a stochastic clone of the horizontal position at the
//!   last stance, so that the direction of the stride since then can be observed), and with
//!   look-ahead the one before it (2 more: the stride between the two clones is observed one
//!   stance late, once the footprint after it shows whether it lay on a straight stretch).
//!
//! Error state: δp, δv, δθ (navigation frame, applied as `exp(δθ)·q`), δb, then the extensions
//! in that order. The covariance lives in a fixed array sized for every extension, is propagated
//! block by block (the transition matrix is sparse), and nothing here allocates.
//!
//! Files: this one holds the filter's state and its strapdown step; `adjust.rs` what changes the
//! state from outside the filter's own steps (the map frame fixed, variances widened after a gap,
//! the bias set) and the σ readouts; `covariance.rs` the block
//! propagation of the covariance; `updates.rs` the measurement updates (ZUPT, foot-axis heading,
//! stride direction with its footprint clone); `response.rs` the closed-loop response to a bias
//! error, on which the convergence flag rises; `tests.rs`, `clone_tests.rs` (the footprint
//! clones) and `response_tests.rs` the unit tests.

use super::rotation::{exp_rotvec, heading_jacobian, heading_of_axis, skew, wrap_pi};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// Largest error-state dimension (12 base states and 16 extension states).
pub const MAX_N: usize = 28;

/// χ² gate of a zero-rate update (3 degrees of freedom, p = 10⁻³): a rest's mean rate further
/// from the bias the filter holds is not fused.
pub const ZERO_RATE_GATE_NIS: f64 = 16.27;
const P0: usize = 0;
const V0: usize = 3;
const TH: usize = 6;
const BG: usize = 9;

/// Noise figures of the filter.
#[derive(Debug, Clone, Copy)]
pub struct EskfNoise {
    /// Accelerometer white-noise density, m/s²/√Hz: the velocity's variance grows by σ²·dt.
    pub accel_m_s2: f64,
    /// Gyro white-noise density, rad/s/√Hz: the attitude's variance grows by σ²·dt.
    pub gyro_rad_s: f64,
    /// The same while the foot rests ([`Eskf::set_at_rest`]): the sensor's own noise, without
    /// the errors a swing builds, rad/s/√Hz.
    pub rest_gyro_rad_s: f64,
    /// Gyro-bias random walk σ, rad/s/√s (0 freezes the bias states).
    pub gyro_bias_rw_rad_s_sqrt_s: f64,
    /// ZUPT σ, m/s.
    pub zupt_m_s: f64,
    /// Above this yaw σ the stance velocity updates leave the yaw alone (a Schmidt update),
    /// rad; infinite: never.
    pub stance_yaw_max_sd_rad: f64,
    /// Between updates the covariance is propagated once per interval of about this length, s,
    /// on the samples' summed transition (0: on every sample; see
    /// [`CovarianceStep::MayDefer`]).
    pub covariance_step_s: f64,
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
    /// Cross-coupling states into the body z axis (from x and from y): initial σ, rad
    /// (`None`: off).
    pub coupling_sd: Option<f64>,
    /// Footprint-clone states for stride-direction observations.
    pub footprint_clone: bool,
    /// A second footprint clone (the footprint before the last), for stride observations made
    /// one stance late (only with `footprint_clone`).
    pub stride_look_ahead: bool,
}

/// Indices of the extension states in the error state.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Layout {
    n: usize,
    rate: Option<usize>,
    scale: Option<usize>,
    offset: Option<usize>,
    gsens: Option<usize>,
    coupling: Option<usize>,
    clone: Option<usize>,
    /// The clone of the footprint before the last (look-ahead), right after `clone`.
    clone_prev: Option<usize>,
}

impl Layout {
    /// First indices of the footprint clones (each a horizontal pair).
    fn clones(&self) -> impl Iterator<Item = usize> + use<> {
        self.clone.into_iter().chain(self.clone_prev)
    }

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
        let coupling = take(ext.coupling_sd.is_some(), 2);
        let clone = take(ext.footprint_clone, 2);
        let clone_prev = take(ext.footprint_clone && ext.stride_look_ahead, 2);
        // The covariance's storage, and loops bounded by it (`n.min(MAX_N)`), hold every state:
        // a new extension must raise `MAX_N`.
        assert!(n <= MAX_N, "{n} error states, storage for {MAX_N}");
        Self {
            n,
            rate,
            scale,
            offset,
            gsens,
            coupling,
            clone,
            clone_prev,
        }
    }

    /// Whether every extension state is constant between updates (F = I, no noise): the
    /// heading offset and the footprint clone. Then the base block propagation serves.
    fn static_extensions_only(&self) -> bool {
        self.rate.is_none()
            && self.scale.is_none()
            && self.gsens.is_none()
            && self.coupling.is_none()
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
    /// Cross-coupling into the body z axis, rad: `[m_zx, m_zy]` (the z gyro reads
    /// `m_zx·ω_x + m_zy·ω_y` too much).
    pub coupling_z_rad: [f64; 2],
}

/// σ of the extension estimates that are reported, when their states are on.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ExtensionSd {
    /// Gyro scale factor per body axis.
    pub scale_factor: Option<Vector3<f64>>,
    /// Cross-coupling into the body z axis `[m_zx, m_zy]`, rad.
    pub coupling_z_rad: Option<[f64; 2]>,
    /// g-sensitivity per body axis, rad/s per m/s².
    pub g_sensitivity: Option<Vector3<f64>>,
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
    /// The footprint cloned before it (look-ahead only), m; NaN before the second clone.
    pub prev_footprint_xy_m: [f64; 2],
    /// Footprints cloned so far: a copy of the filter from before a clone has fewer.
    pub footprints_cloned: u64,
    /// Error covariance, column-major with stride `MAX_N`; only the leading `n × n` is used.
    p: [f64; MAX_N * MAX_N],
    /// The closed-loop response to a bias error present when the bias was set
    /// (`response.rs`).
    response: response::Response,
    /// The covariance steps deferred since `p` and `response` were last propagated
    /// (`covariance.rs`): those two are as of `pending`'s samples ago.
    pending: covariance::Pending,
    layout: Layout,
    gravity_m_s2: f64,
    noise: EskfNoise,
    ext_cfg: Extensions,
    estimate_bias: bool,
    /// The foot rests: the attitude's process noise is [`EskfNoise::rest_gyro_rad_s`].
    at_rest: bool,
}

/// One row of a sparse measurement Jacobian: (state index, value) pairs.
type SparseRow = [(usize, f64); 4];

#[inline]
fn ix(r: usize, c: usize) -> usize {
    c * MAX_N + r
}

/// The most a gap widens the attitude's σ about each axis, rad (10°). The gyro noise over a gap
/// of minutes would make it tens of degrees, where the error-state filter's small-angle model no
/// longer holds: gaps of 600 s / 3600 s at every walk's middle footprint (the foot at rest)
/// lost the walk after them (normal gait, median / worst: 0.343 / 16.6 % and 1.65 / 25.9 %; 0.350
/// / 13.7 % with the cap, exp26 the one still lost). A heading really lost in a gap is found
/// again from the strides (the re-acquisition).
pub const GAP_MAX_ATTITUDE_SD_RAD: f64 = 10.0 * (std::f64::consts::PI / 180.0);

/// Dimension without extensions.
const BASE_N: usize = 12;

mod adjust;
mod covariance;
mod response;
mod updates;

pub use covariance::CovarianceStep;
pub use response::max_row_sum;

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
            prev_footprint_xy_m: [f64::NAN; 2],
            footprints_cloned: 0,
            p: [0.0; MAX_N * MAX_N],
            response: [0.0; MAX_N * 3],
            pending: Default::default(),
            layout,
            gravity_m_s2,
            noise,
            at_rest: false,
            ext_cfg: ext,
            estimate_bias,
        };
        f.reset_bias_response();
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
        if let (Some(i), Some(sd)) = (layout.coupling, ext.coupling_sd) {
            for k in 0..2 {
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
        self.response = src.response;
        self.pending = src.pending;
    }

    /// Copies everything of `src` but the covariance.
    fn copy_nominal_from(&mut self, src: &Eskf) {
        self.p_m = src.p_m;
        self.v_m_s = src.v_m_s;
        self.nav_from_body = src.nav_from_body;
        self.gyro_bias_rad_s = src.gyro_bias_rad_s;
        self.ext = src.ext;
        self.footprint_xy_m = src.footprint_xy_m;
        self.prev_footprint_xy_m = src.prev_footprint_xy_m;
        self.footprints_cloned = src.footprints_cloned;
        self.layout = src.layout;
        self.gravity_m_s2 = src.gravity_m_s2;
        self.noise = src.noise;
        self.ext_cfg = src.ext_cfg;
        self.estimate_bias = src.estimate_bias;
        self.at_rest = src.at_rest;
    }

    /// The foot rests (a rest the estimator has observed as one) or walks again: while it
    /// rests, the attitude's process noise is the sensor's own ([`EskfNoise::rest_gyro_rad_s`]).
    pub fn set_at_rest(&mut self, at_rest: bool) {
        self.at_rest = at_rest;
    }

    /// Copies the upper triangle of the covariance onto the lower one.
    fn mirror_upper(&mut self) {
        // Bounded by `MAX_N` (which `n` never exceeds) so that the indexing needs no checks.
        for j in 0..self.layout.n.min(MAX_N) {
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
        debug_assert!(self.covariance_settled(), "a deferred covariance read");
        self.p[ix(r, c)]
    }

    /// The diagonal of the covariance in use (`n` elements).
    /// As of the last covariance step ([`Eskf::covariance_settled`]): between updates it may be
    /// up to [`EskfNoise::covariance_step_s`] old. The health check reads it so, without
    /// settling: a fault the waiting steps would make in it shows at the sample that applies
    /// them (the step of finite inputs that could make one is beyond what the input checks let
    /// through; the updates, which can, settle first).
    pub fn cov_diagonal(&self) -> impl Iterator<Item = &f64> {
        // Indexed rather than `step_by`: this runs on every sample (the health check), and
        // `StepBy`'s fold did not inline (6 % of the eskf mode's time in a profile). The bound
        // `n ≤ MAX_N`, said to the compiler, drops a compare per element (0.4 % of the core's
        // instructions).
        let n = self.layout.n.min(MAX_N);
        (0..n).map(move |i| &self.p[i * (MAX_N + 1)])
    }

    /// The body rate corrected for the filter's own error model (scale factor, g-sensitivity
    /// and the cross-coupling into z) and for `bias_rad_s` (the filter's own bias, or an
    /// external one).
    #[inline]
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
        if self.layout.coupling.is_some() {
            // x and y are already the true rates; z read (1 + s_z)·ω_z + m_zx·ω_x + m_zy·ω_y.
            let [mx, my] = self.ext.coupling_z_rad;
            w.z -= (mx * w.x + my * w.y) / (1.0 + self.ext.scale_factor.z);
        }
        w
    }

    /// Strapdown step over `dt_s` with the corrected body rate `omega_rad_s` (see
    /// [`Eskf::corrected_rate`], already averaged over the step) and the specific force
    /// `f_m_s2`, then covariance propagation. In place, through a copy of the filter: the
    /// per-sample path uses [`Eskf::propagate_into`].
    pub fn propagate(&mut self, omega_rad_s: &Vector3<f64>, f_m_s2: &Vector3<f64>, dt_s: f64) {
        let before = self.clone();
        before.propagate_into(self, omega_rad_s, f_m_s2, dt_s, CovarianceStep::Now);
    }

    /// [`Eskf::propagate`] written into `next` (a copy of this filter, whatever state it holds
    /// now: the configuration must be the same), leaving `self` as it was: the estimator keeps the state before each
    /// sample for its health check this way, without copying it (the copy of the covariance is
    /// part of the propagation's first pass).
    /// `covariance` says whether the covariance's step may wait for the next ones
    /// ([`CovarianceStep`]).
    pub fn propagate_into(
        &self,
        next: &mut Eskf,
        omega_rad_s: &Vector3<f64>,
        f_m_s2: &Vector3<f64>,
        dt_s: f64,
        covariance: CovarianceStep,
    ) {
        // `next` has this filter's configuration (it is a copy of it; nothing changes the
        // configuration after `new`): only the state is copied, what the step changes is
        // written below.
        debug_assert!(next.layout == self.layout && next.ext_cfg == self.ext_cfg);
        next.gyro_bias_rad_s = self.gyro_bias_rad_s;
        next.ext = self.ext;
        next.footprint_xy_m = self.footprint_xy_m;
        next.prev_footprint_xy_m = self.prev_footprint_xy_m;
        next.footprints_cloned = self.footprints_cloned;
        next.at_rest = self.at_rest;
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
            self,
            &(-skew(&f_nav) * dt_s),
            &(-c * dt_s),
            omega_rad_s,
            f_m_s2,
            dt_s,
            covariance,
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
        if let Some(i) = self.layout.coupling {
            self.ext.coupling_z_rad[0] += dx[i];
            self.ext.coupling_z_rad[1] += dx[i + 1];
        }
        if let Some(i) = self.layout.clone {
            self.footprint_xy_m[0] += dx[i];
            self.footprint_xy_m[1] += dx[i + 1];
        }
        if let Some(i) = self.layout.clone_prev {
            self.prev_footprint_xy_m[0] += dx[i];
            self.prev_footprint_xy_m[1] += dx[i + 1];
        }
    }
}

#[cfg(test)]
mod clone_tests;
#[cfg(test)]
mod deferral_tests;
#[cfg(test)]
mod response_tests;
#[cfg(test)]
mod tests;
