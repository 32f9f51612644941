//! Measurement updates: the generic sparse update, the ZUPT, the foot-axis heading and the
//! stride direction on the cloned footprint.

use super::*;

impl Eskf {
    /// A measurement update with an `m × n` Jacobian given by rows of (index, value) pairs over
    /// at most 4 columns each, innovation `r` and noise variances `r_var`. Joseph-free
    /// symmetric form: `P ← P − K·H·P` on one triangle, mirrored.
    fn update<const M: usize>(
        &mut self,
        h: &[[(usize, f64); 4]; M],
        r: [f64; M],
        r_var: [f64; M],
    ) -> Innovation {
        self.gated_update(h, r, r_var, f64::INFINITY)
            .unwrap_or_else(|i| i)
    }

    /// [`Self::update`], unless the innovation's NIS exceeds `gate_nis`: then nothing changes
    /// and the innovation comes back as the error.
    fn gated_update<const M: usize>(
        &mut self,
        h: &[[(usize, f64); 4]; M],
        r: [f64; M],
        r_var: [f64; M],
        gate_nis: f64,
    ) -> Result<Innovation, Innovation> {
        self.settle_covariance();
        let n = self.layout.n;
        // PHᵀ (n × M)
        let mut pht = [[0.0; M]; MAX_N];
        for (i, row) in pht.iter_mut().enumerate().take(n) {
            for (j, hj) in h.iter().enumerate() {
                row[j] = hj.iter().map(|&(c, v)| v * self.p[ix(i, c)]).sum();
            }
        }
        // S = H P Hᵀ + R
        let mut s = nalgebra::SMatrix::<f64, M, M>::zeros();
        for a in 0..M {
            for b in 0..M {
                s[(a, b)] = h[a].iter().map(|&(c, v)| v * pht[c][b]).sum::<f64>();
            }
            s[(a, a)] += r_var[a];
        }
        let Some(s_inv) = s.try_inverse() else {
            return Ok(Innovation::default());
        };
        let rv = nalgebra::SVector::<f64, M>::from(r);
        let s_inv_r = s_inv * rv;
        let mut out = Innovation {
            nis: rv.dot(&s_inv_r),
            dim: M as u8,
            ..Default::default()
        };
        for a in 0..M.min(3) {
            out.r[a] = r[a];
            out.s_diag[a] = s[(a, a)];
        }
        if out.nis.is_nan() || out.nis > gate_nis {
            return Err(out);
        }
        let mut k = [[0.0; M]; MAX_N];
        for (ki, pi) in k.iter_mut().zip(&pht).take(n) {
            for (b, kb) in ki.iter_mut().enumerate() {
                *kb = (0..M).map(|a| pi[a] * s_inv[(a, b)]).sum();
            }
        }
        self.update_bias_response(h, &k);
        for (j, pj) in pht.iter().enumerate().take(n) {
            for (i, ki) in k.iter().enumerate().take(j + 1) {
                let d: f64 = (0..M).map(|a| ki[a] * pj[a]).sum();
                let v = self.p[ix(i, j)] - d;
                self.p[ix(i, j)] = v;
                self.p[ix(j, i)] = v;
            }
        }
        let mut dx = [0.0; MAX_N];
        for (i, d) in dx.iter_mut().enumerate().take(n) {
            *d = (0..M).map(|a| pht[i][a] * s_inv_r[a]).sum();
        }
        self.inject(&dx);
        Ok(out)
    }

    /// Zero-velocity update (H selects the velocity: written out, it runs on every stance
    /// sample).
    pub fn zupt(&mut self) -> Innovation {
        self.zupt_with_sd(self.noise.zupt_m_s)
    }

    /// Zero-velocity update with σ `sd_m_s` instead of the configured one.
    pub fn zupt_with_sd(&mut self, sd_m_s: f64) -> Innovation {
        self.stance_velocity_update(&Vector3::zeros(), sd_m_s)
    }

    /// Stance velocity update: the sensor's velocity is `expected_m_s` (navigation frame; zero
    /// for a flat foot, the rolling motion at the edges of a stance) with σ `sd_m_s` per axis.
    /// While the yaw's σ exceeds [`EskfNoise::stance_yaw_max_sd_rad`] the yaw is a considered
    /// state (Schmidt): its estimate and variance stay as they are, every other state is
    /// updated as usual and its covariance with the yaw as the Joseph form with that gain
    /// gives, which is the usual update's except for the yaw's own variance.
    pub fn stance_velocity_update(
        &mut self,
        expected_m_s: &Vector3<f64>,
        sd_m_s: f64,
    ) -> Innovation {
        self.settle_covariance();
        let n = self.layout.n;
        let rv = sd_m_s * sd_m_s;
        let r = expected_m_s - self.v_m_s;
        let mut pht = [[0.0; 3]; MAX_N];
        for (i, row) in pht.iter_mut().enumerate().take(n) {
            *row = [
                self.p[ix(i, V0)],
                self.p[ix(i, V0 + 1)],
                self.p[ix(i, V0 + 2)],
            ];
        }
        let mut s = Matrix3::from_fn(|a, b| pht[V0 + a][b]);
        for a in 0..3 {
            s[(a, a)] += rv;
        }
        let Some(s_inv) = s.try_inverse() else {
            return Innovation::default();
        };
        // K = PHᵀ·S⁻¹ by columns (one per velocity axis), so that the update below runs down
        // the contiguous columns of P.
        let mut k = [[0.0; MAX_N]; 3];
        for (i, pi) in pht.iter().enumerate().take(n) {
            let v = s_inv.transpose() * Vector3::from(*pi);
            (k[0][i], k[1][i], k[2][i]) = (v.x, v.y, v.z);
        }
        let yaw = TH + 2;
        let yaw_var = self.p[ix(yaw, yaw)];
        let consider_yaw = yaw_var > self.noise.stance_yaw_max_sd_rad.powi(2);
        if consider_yaw {
            // The response to a bias error keeps its yaw row, as the yaw does.
            let mut k_yaw_kept = k;
            for kc in &mut k_yaw_kept {
                kc[yaw] = 0.0;
            }
            self.update_bias_response_velocity(&k_yaw_kept);
        } else {
            self.update_bias_response_velocity(&k);
        }
        // P ← P − K·(PHᵀ)ᵀ on the upper triangle, then mirrored. Each column's part as slices
        // of one length, so that the loop has no bounds checks.
        let [k0, k1, k2] = &k;
        for (j, pj) in pht.iter().enumerate().take(n) {
            let len = j + 1;
            let col = &mut self.p[j * MAX_N..][..len];
            let (k0, k1, k2) = (&k0[..len], &k1[..len], &k2[..len]);
            for i in 0..len {
                col[i] -= k0[i] * pj[0] + k1[i] * pj[1] + k2[i] * pj[2];
            }
        }
        self.mirror_upper();
        let s_inv_r = s_inv * r;
        let mut dx = [0.0; MAX_N];
        for (d, pi) in dx.iter_mut().zip(&pht).take(n) {
            *d = pi[0] * s_inv_r.x + pi[1] * s_inv_r.y + pi[2] * s_inv_r.z;
        }
        if consider_yaw {
            dx[yaw] = 0.0;
            self.p[ix(yaw, yaw)] = yaw_var;
        }
        self.inject(&dx);
        Innovation {
            r: [r.x, r.y, r.z],
            s_diag: [s[(0, 0)], s[(1, 1)], s[(2, 2)]],
            nis: r.dot(&s_inv_r),
            dim: 3,
        }
    }

    /// Whether the stance velocity update's innovation lies beyond `max_z2` times its variance
    /// on some axis: a lower bound of its NIS (`rᵀS⁻¹r ≥ rᵢ²/Sᵢᵢ`), so a cheap test for a
    /// velocity that cannot be what the filter holds. Brings the covariance up to date first
    /// (a replayed sample's step may wait).
    pub fn stance_velocity_implausible(
        &mut self,
        expected_m_s: &Vector3<f64>,
        sd_m_s: f64,
        max_z2: f64,
    ) -> bool {
        self.settle_covariance();
        let r = expected_m_s - self.v_m_s;
        let rv = sd_m_s * sd_m_s;
        (0..3).any(|a| r[a] * r[a] > max_z2 * (self.p[ix(V0 + a, V0 + a)] + rv))
    }

    /// The tilt is levelled again from `up_body` (the direction of the specific force of a
    /// standing foot, body axes): the smallest rotation that takes it to the vertical, the
    /// heading kept. The tilt's error becomes independent with variance `tilt_var`, and the
    /// velocity zero with variance `vel_var` (the foot stands).
    pub fn relevel(&mut self, up_body: &Vector3<f64>, tilt_var: f64, vel_var: f64) {
        self.settle_covariance();
        let up_nav = self.nav_from_body * up_body;
        // Exactly upside down, any horizontal axis will do.
        let turn = UnitQuaternion::rotation_between(&up_nav, &Vector3::z()).unwrap_or_else(|| {
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
        });
        self.nav_from_body = turn * self.nav_from_body;
        for i in 0..2 {
            self.clear_state(TH + i, tilt_var);
        }
        self.v_m_s = Vector3::zeros();
        for i in 0..3 {
            self.clear_state(V0 + i, vel_var);
        }
    }

    /// The velocity is not what the filter holds (garbage samples since the last stance): its
    /// error becomes independent of every other state with variance `var_m2_s2` per axis, so
    /// the next stance update sets it without moving the attitude or the bias.
    pub fn reset_velocity(&mut self, var_m2_s2: f64) {
        self.settle_covariance();
        for a in 0..3 {
            self.clear_state(V0 + a, var_m2_s2);
        }
    }

    /// Zero-rate update: during a rest the gyro reads its bias (plus its g-sensitivity times the
    /// specific force, when that is a state). `mean_rate_rad_s` and `mean_f_m_s2` are the means
    /// over the rest (sensor axes); `sd_rad_s` the σ of the mean rate, per axis. `None` when
    /// the bias is not estimated (the paper's and the rotation-aware modes keep their own).
    /// `Err` (nothing changed) when the mean rate lies beyond the χ² gate [`ZERO_RATE_GATE_NIS`]
    /// of the bias the filter holds: a foot that turned slowly and steadily through a "rest"
    /// passes the stance detector with a small spread, and its mean rate is not the bias.
    pub fn zero_rate_update(
        &mut self,
        mean_rate_rad_s: &Vector3<f64>,
        mean_f_m_s2: &Vector3<f64>,
        sd_rad_s: &Vector3<f64>,
    ) -> Option<Result<Innovation, Innovation>> {
        if !self.estimate_bias {
            return None;
        }
        let mut predicted = self.gyro_bias_rad_s;
        let mut h = [[(BG, 1.0), (0, 0.0), (0, 0.0), (0, 0.0)]; 3];
        for (k, row) in h.iter_mut().enumerate() {
            row[0].0 = BG + k;
            if let Some(g) = self.layout.gsens {
                predicted[k] += self.ext.g_sensitivity[k] * mean_f_m_s2[k];
                row[1] = (g + k, mean_f_m_s2[k]);
            }
        }
        let r = mean_rate_rad_s - predicted;
        let var = sd_rad_s.map(|v| v * v);
        Some(self.gated_update(
            &h,
            [r.x, r.y, r.z],
            [var.x, var.y, var.z],
            ZERO_RATE_GATE_NIS,
        ))
    }

    /// The heading of the body-frame direction `axis_body` (the foot's forward axis) as the
    /// model predicts it: its attitude heading plus the heading-offset state.
    pub fn predicted_heading(&self, axis_body: &Vector3<f64>) -> f64 {
        heading_of_axis(&self.nav_from_body, axis_body) + self.ext.heading_offset_rad
    }

    /// Heading observation of `axis_body`: observed value `heading_obs_rad` with σ `sd_rad`.
    pub fn heading_update(
        &mut self,
        heading_obs_rad: f64,
        sd_rad: f64,
        axis_body: &Vector3<f64>,
    ) -> Innovation {
        let r = wrap_pi(heading_obs_rad - self.predicted_heading(axis_body));
        let h = self.heading_row(axis_body);
        self.update(&[h], [r], [sd_rad * sd_rad])
    }

    /// The sparse Jacobian row of the foot-axis heading (attitude and heading offset).
    fn heading_row(&self, axis_body: &Vector3<f64>) -> SparseRow {
        let j = heading_jacobian(&self.nav_from_body, axis_body);
        let off = self.layout.offset.map_or((0, 0.0), |i| (i, 1.0));
        [(TH, j.x), (TH + 1, j.y), (TH + 2, j.z), off]
    }

    /// `H P Hᵀ` of one sparse row: the predicted variance of a scalar observation.
    fn predicted_variance(&self, h: &SparseRow) -> f64 {
        debug_assert!(self.covariance_settled(), "a deferred covariance read");
        h.iter()
            .map(|&(a, va)| {
                h.iter()
                    .map(|&(b, vb)| va * vb * self.p[ix(a, b)])
                    .sum::<f64>()
            })
            .sum()
    }

    /// The foot-axis heading as the model predicts it and its variance, rad and rad².
    pub fn heading_prediction(&self, axis_body: &Vector3<f64>) -> (f64, f64) {
        (
            wrap_pi(self.predicted_heading(axis_body)),
            self.predicted_variance(&self.heading_row(axis_body)),
        )
    }

    /// Forgets the cloned footprints (their nominal positions become NaN): no stride is
    /// observed until new ones are cloned. For a filter put back to a copy that no longer
    /// matches the footprints its user recorded.
    pub fn forget_footprints(&mut self) {
        self.settle_covariance();
        self.footprint_xy_m = [f64::NAN; 2];
        self.prev_footprint_xy_m = [f64::NAN; 2];
    }

    /// Starts a new stride: the current horizontal position becomes the cloned footprint,
    /// with its covariance (rows and columns of the clone copied from those of x and y).
    /// Without the clone states this does nothing.
    pub fn clone_footprint(&mut self) {
        self.settle_covariance();
        let Some(c) = self.layout.clone else {
            return;
        };
        let n = self.layout.n;
        let prev = self.layout.clone_prev;
        if let Some(a) = prev {
            // With look-ahead the old clone becomes the previous one: its rows and columns
            // move over first.
            self.prev_footprint_xy_m = self.footprint_xy_m;
            for k in 0..2 {
                for j in (0..n).filter(|&j| j != a && j != a + 1) {
                    let v = self.p[ix(c + k, j)];
                    self.p[ix(a + k, j)] = v;
                    self.p[ix(j, a + k)] = v;
                }
            }
            for x in 0..2 {
                for y in 0..2 {
                    self.p[ix(a + x, a + y)] = self.p[ix(c + x, c + y)];
                }
            }
        }
        self.footprint_xy_m = [self.p_m.x, self.p_m.y];
        self.footprints_cloned += 1;
        for k in 0..2 {
            for j in 0..n {
                let v = if j == c || j == c + 1 {
                    0.0
                } else {
                    self.p[ix(P0 + k, j)]
                };
                self.p[ix(c + k, j)] = v;
                self.p[ix(j, c + k)] = v;
            }
        }
        for a in 0..2 {
            for b in 0..2 {
                self.p[ix(c + a, c + b)] = self.p[ix(P0 + a, P0 + b)];
            }
        }
        self.clone_bias_response(c, prev);
    }

    /// The stride observed now: its horizontal length (m), direction (rad) and the direction's
    /// sparse Jacobian row, or `None` without a clone. The stride since the cloned footprint,
    /// or with look-ahead the one between the two clones (the stride before the last).
    fn stride(&self) -> Option<(f64, f64, SparseRow)> {
        let c = self.layout.clone?;
        match self.layout.clone_prev {
            None => stride_between(P0, c, self.footprint_xy_m, [self.p_m.x, self.p_m.y]),
            Some(a) => stride_between(c, a, self.prev_footprint_xy_m, self.footprint_xy_m),
        }
    }

    /// The stride since the cloned footprint: length (m), direction (rad) and the direction's
    /// variance (rad²), or `None` without a clone.
    pub fn stride_prediction(&self) -> Option<(f64, f64, f64)> {
        self.stride()
            .map(|(len, dir, h)| (len, dir, self.predicted_variance(&h)))
    }

    /// The stride walked since the last cloned footprint (also with look-ahead, where the
    /// observed stride is the one before it): horizontal length (m) and direction (rad), or
    /// `None` without a clone.
    pub fn stride_since_footprint(&self) -> Option<(f64, f64)> {
        let c = self.layout.clone?;
        stride_between(P0, c, self.footprint_xy_m, [self.p_m.x, self.p_m.y])
            .map(|(len, dir, _)| (len, dir))
    }

    /// Stride-direction observation: the walking direction since the cloned footprint is
    /// `direction_obs_rad` with σ `sd_rad`. `None` without a clone.
    pub fn stride_direction_update(
        &mut self,
        direction_obs_rad: f64,
        sd_rad: f64,
    ) -> Option<Innovation> {
        let (_, dir, h) = self.stride()?;
        let r = wrap_pi(direction_obs_rad - dir);
        Some(self.update(&[h], [r], [sd_rad * sd_rad]))
    }
}

/// The stride from `[x0, y0]` (state index `from`) to `[x1, y1]` (`to`): horizontal length (m),
/// direction (rad) and the direction's sparse Jacobian row, or `None` for no displacement.
fn stride_between(
    to: usize,
    from: usize,
    [x0, y0]: [f64; 2],
    [x1, y1]: [f64; 2],
) -> Option<(f64, f64, SparseRow)> {
    let (dx, dy) = (x1 - x0, y1 - y0);
    let d2 = dx * dx + dy * dy;
    if !d2.is_finite() || d2 <= 0.0 {
        return None;
    }
    let (hx, hy) = (-dy / d2, dx / d2);
    Some((
        d2.sqrt(),
        dy.atan2(dx),
        [(to, hx), (to + 1, hy), (from, -hx), (from + 1, -hy)],
    ))
}
