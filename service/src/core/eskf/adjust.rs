//! The filter's state changed from outside its propagation and its updates, and read out: the
//! map frame fixed (a rotation about z), variances widened after a gap or a fault, the heading
//! turned, a state set again (the gyro bias from a prior or a checkpoint), and the standard
//! deviations the outputs and the health check read.

use super::*;

impl Eskf {
    /// Rotates the navigation frame about z by `angle_rad` (used once the map frame is known).
    pub fn rotate_frame(&mut self, angle_rad: f64) {
        self.settle_covariance();
        let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), angle_rad);
        let m = *r.matrix();
        self.p_m = m * self.p_m;
        self.v_m_s = m * self.v_m_s;
        self.nav_from_body = UnitQuaternion::from_rotation_matrix(&r) * self.nav_from_body;
        let n = self.layout.n;
        let turn =
            |[x, y]: [f64; 2]| [m[(0, 0)] * x + m[(0, 1)] * y, m[(1, 0)] * x + m[(1, 1)] * y];
        self.footprint_xy_m = turn(self.footprint_xy_m);
        self.prev_footprint_xy_m = turn(self.prev_footprint_xy_m);
        // P ← T P Tᵀ with T = blockdiag(R, R, R, I, …, R₂ₓ₂ for each clone), block by block:
        // its rows in every column, then its columns in every row.
        let blocks = self
            .layout
            .clones()
            .map(|k| (k, true))
            .chain([P0, V0, TH].map(|b| (b, false)));
        for (b, horizontal) in blocks {
            let rotate = |x: &mut [f64]| {
                if horizontal {
                    response::rotate_horizontal(x, b, &m);
                } else {
                    response::rotate_block(x, b, &m);
                }
            };
            for c in 0..n {
                rotate(&mut self.p[c * MAX_N..][..MAX_N]);
            }
            for rr in 0..n {
                let mut row: [f64; MAX_N] = std::array::from_fn(|c| self.p[ix(rr, c)]);
                rotate(&mut row);
                for (c, v) in row.iter().enumerate().take(n) {
                    self.p[ix(rr, c)] = *v;
                }
            }
        }
        // The two passes round differently on the two sides of the diagonal: P is kept symmetric
        // to the bit (the propagation computes from one side and mirrors).
        self.mirror_upper();
        self.rotate_bias_response(&m);
    }

    /// After a gap in the data of `gap_s`: nothing is integrated over it; the velocity variance
    /// grows by `vel_var` and the attitude variance by the gyro noise over the gap, up to
    /// [`GAP_MAX_ATTITUDE_SD_RAD`] per axis. The bias's random walk is not added: at the
    /// configured 7e-4 rad/s/√s (a tuning figure, far above this sensor's drift) a 600 s gap
    /// would make its σ 0.017 rad/s, and the bias learnt again from nothing cost more than it
    /// saved (gaps of 600 s at every walk's middle footprint: exp31 1.38 → 4.41 %, exp40 0.40 →
    /// 1.48 % in the map frame).
    pub fn widen_after_gap(&mut self, gap_s: f64, vel_var: f64) {
        self.settle_covariance();
        let att_var = (self.noise.gyro_rad_s.powi(2) * gap_s).min(GAP_MAX_ATTITUDE_SD_RAD.powi(2));
        for i in 0..3 {
            self.p[ix(V0 + i, V0 + i)] += vel_var;
            self.p[ix(TH + i, TH + i)] += att_var;
        }
    }

    /// The attitude turns about the vertical by `angle_rad`, known to `sd_rad`: the nominal
    /// rotates (position, velocity and the other states stay), and the heading variance grows
    /// by `sd_rad²`. Used when a restored state lacks a turn the gyro measured since.
    pub fn turn_heading(&mut self, angle_rad: f64, sd_rad: f64) {
        self.settle_covariance();
        let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), angle_rad);
        self.nav_from_body = UnitQuaternion::from_rotation_matrix(&r) * self.nav_from_body;
        // The attitude error is in the navigation frame: its block turns with the nominal,
        // rows and columns (P ← T P Tᵀ, T = R on the attitude block), and so does its part of
        // the bias-error response.
        let (m, n) = (*r.matrix(), self.layout.n);
        for c in 0..n {
            response::rotate_block(&mut self.p[c * MAX_N..][..MAX_N], TH, &m);
        }
        for rr in 0..n {
            let mut row: [f64; MAX_N] = std::array::from_fn(|c| self.p[ix(rr, c)]);
            response::rotate_block(&mut row, TH, &m);
            for (c, v) in row.iter().enumerate().take(n) {
                self.p[ix(rr, c)] = *v;
            }
        }
        for c in 0..3 {
            response::rotate_block(&mut self.response[c * MAX_N..][..MAX_N], TH, &m);
        }
        self.mirror_upper();
        self.p[ix(TH + 2, TH + 2)] += sd_rad * sd_rad;
    }

    /// The velocity variance grows by `var` on every axis (a bridged gap).
    pub fn widen_velocity(&mut self, var: f64) {
        self.settle_covariance();
        for i in 0..3 {
            self.p[ix(V0 + i, V0 + i)] += var;
        }
    }

    /// A rotation of unknown size about the body axis `axis_body` (unit vector) with variance
    /// `var_rad2` happened: the attitude covariance grows along that axis (in the navigation
    /// frame). Used for the rotation a clipped gyro axis did not measure: process noise, so
    /// while covariance steps wait it is added with theirs at the interval's end.
    pub fn widen_attitude_about(&mut self, axis_body: &Vector3<f64>, var_rad2: f64) {
        let a = self.nav_from_body * axis_body;
        // One product for both sides of the diagonal: the covariance stays symmetric to the bit.
        let var =
            std::array::from_fn(|j| std::array::from_fn(|i| var_rad2 * a[i.min(j)] * a[i.max(j)]));
        self.widen_attitude(&var);
    }

    /// The heading's variance, rad².
    pub fn heading_variance(&self) -> f64 {
        debug_assert!(self.covariance_settled(), "a deferred covariance read");
        self.p[ix(TH + 2, TH + 2)]
    }

    /// Sets the heading variance (after the map frame is fixed, the heading is known).
    pub fn set_heading_variance(&mut self, var_rad2: f64) {
        self.settle_covariance();
        self.clear_state(TH + 2, var_rad2);
    }

    /// Makes state `i`'s error independent of everything before: variance `var`, no
    /// correlations, no part of the bias-error response.
    pub(super) fn clear_state(&mut self, i: usize, var: f64) {
        self.settle_covariance();
        for j in 0..self.layout.n {
            self.p[ix(i, j)] = 0.0;
            self.p[ix(j, i)] = 0.0;
        }
        self.p[ix(i, i)] = var;
        for c in 0..3 {
            self.response[ix(i, c)] = 0.0;
        }
    }

    /// Sets the gyro bias and its covariance block (clearing its correlations), when the filter
    /// owns the bias. The bias-error response starts again from here.
    pub fn set_gyro_bias(&mut self, bias_rad_s: Vector3<f64>, cov: &Matrix3<f64>) {
        self.settle_covariance();
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
        self.reset_bias_response();
    }

    /// Whether the filter estimates the gyro bias (else another estimator owns it).
    pub fn estimates_bias(&self) -> bool {
        self.estimate_bias
    }

    /// Covariance block of the gyro bias.
    /// As of the last covariance step ([`Eskf::covariance_settled`]): between updates it may be
    /// up to [`EskfNoise::covariance_step_s`] old.
    pub fn gyro_bias_cov(&self) -> Matrix3<f64> {
        Matrix3::from_fn(|i, j| self.p[ix(BG + i, BG + j)])
    }

    /// σ of the gyro-bias states.
    /// As of the last covariance step ([`Eskf::covariance_settled`]): between updates it may be
    /// up to [`EskfNoise::covariance_step_s`] old.
    pub fn gyro_bias_sd(&self) -> Vector3<f64> {
        Vector3::from_fn(|i, _| self.p[ix(BG + i, BG + i)].max(0.0).sqrt())
    }

    /// σ of the heading-offset state, when enabled.
    pub fn heading_offset_sd(&self) -> Option<f64> {
        self.layout.offset.map(|i| self.p[ix(i, i)].max(0.0).sqrt())
    }

    /// σ of the reported extension estimates.
    pub fn extension_sd(&self) -> ExtensionSd {
        ExtensionSd {
            scale_factor: self.scale_factor_sd(),
            coupling_z_rad: self.coupling_z_sd(),
            g_sensitivity: self.g_sensitivity_sd(),
        }
    }

    /// σ of the g-sensitivity states, rad/s per m/s², when enabled.
    pub fn g_sensitivity_sd(&self) -> Option<Vector3<f64>> {
        self.layout
            .gsens
            .map(|i| Vector3::from_fn(|k, _| self.p[ix(i + k, i + k)].max(0.0).sqrt()))
    }

    /// σ of the cross-coupling states `[m_zx, m_zy]`, rad, when enabled.
    pub fn coupling_z_sd(&self) -> Option<[f64; 2]> {
        self.layout
            .coupling
            .map(|i| std::array::from_fn(|k| self.p[ix(i + k, i + k)].max(0.0).sqrt()))
    }

    /// σ of the scale-factor states, when enabled.
    pub fn scale_factor_sd(&self) -> Option<Vector3<f64>> {
        self.layout
            .scale
            .map(|i| Vector3::from_fn(|k, _| self.p[ix(i + k, i + k)].max(0.0).sqrt()))
    }
}
