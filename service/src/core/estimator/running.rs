//! The estimator's step once the filter runs ([`Pipeline::step_running`]: the segment check,
//! navigation and the stance observations, the health check) and the estimate it gives
//! ([`Pipeline::fill_output`]: attitude, bias in sensor axes, the convergence flag).

use super::*;

impl Pipeline {
    /// The rest of [`Estimator::step`] once aligned: the segment check, navigation and the
    /// stance observations, the health check, the output.
    pub(super) fn step_running(
        &mut self,
        eskf: &mut Box<Eskf>,
        t_s: f64,
        prev: Option<(f64, Vector3<f64>, Vector3<f64>)>,
        (w, f): (&Vector3<f64>, &Vector3<f64>),
        decision: &StanceDecision,
    ) {
        let (stance, stance_age_s) = (decision.stance, decision.stance_age_s);
        if self.good.get().is_none() {
            self.save_good(eskf);
        }
        let Some((t_prev, w_prev, f_prev)) = prev else {
            return;
        };
        // `prev` and `last` hold the sample clock's times (see `step`).
        let t_clock = self.last.map_or(t_s, |l| l.0);
        let gap = self.cross_gap(eskf, t_clock, (t_prev, &w_prev, w), (&f_prev, f));
        if self.out.gap_s.is_some() {
            // Bridged, filled or a new segment: no late footfall reaches back across it.
            self.late.drop_pending();
        }
        let (t_prev, w_prev, f_prev) = match gap {
            Gap::NewSegment => {
                self.memory.clear();
                self.drop_rail_peak();
                if self.stance_edge == StanceEdge::Began {
                    self.memory.footfall(t_clock);
                }
                self.remember(t_clock, w, f);
                self.fill_output(eskf);
                return;
            }
            Gap::Integrate => (t_prev, w_prev, f_prev),
            // The gap was filled up to its last remembered sample: the step from there.
            Gap::Filled(last) => last,
        };
        let dt = t_clock - t_prev;
        let w_avg = (w + w_prev) * 0.5;
        let f_avg = (f + f_prev) * 0.5;
        // The state before the sample: the bias filter is copied; the filter's buffer is the
        // one `navigate` propagates into and then swaps with the running one (allocated once).
        match (&self.bias, self.before_bias.get()) {
            // Nothing to copy when the filter owns the bias (and the copy of the whole enum was
            // measurable at every sample).
            (BiasFilter::InEskf, Some(BiasFilter::InEskf)) => {}
            _ => self.before_bias.save(&self.bias),
        }
        let mut before = take_spare(&mut self.before, eskf);
        // A stance ends at this sample: `navigate` ends its rest noise and may fuse the rest.
        let stance_ended = self.was_stance && !stance;
        let used_before = (self.counters.heading_used, self.counters.stride_used);
        let external_pending = self.pending_heading.is_some();
        let expired_before = self.counters.headings_expired;
        let omega = self.navigate(
            eskf,
            &mut before,
            t_s,
            dt,
            &w_avg,
            &f_avg,
            f,
            stance,
            stance_age_s,
        );
        let applied = std::mem::take(&mut self.zero_rate_applied);
        let failed = self.guard_health(eskf, &before, stance, t_s);
        self.before = Some(before);
        if failed {
            // The update was undone: the next step integrates from the previous sample. A
            // zero-rate update made in it is undone too, and not made again (it used to be, at
            // every sample, and a rest that itself broke the state froze the estimator): the
            // rest is refused, the next one observes the bias.
            // After a filled gap, from its last filled sample: the fill stays (the filter went
            // back to the state after it), it is not made again.
            self.last = Some((t_prev, w_prev, f_prev));
            self.counters.zero_rate_refused += u64::from(applied);
            // A velocity reset in it is undone as well; the next stance update judges again.
            // So is a heading taken as lost (its widened variance): the run starts over.
            self.out.velocity_reset = false;
            self.out.heading_reacquired = None;
            // So is a frame the start heading set in it (the filter went back to the frame
            // before): it is set at a later stance (a review).
            self.out.frame_set = false;
            // A stance observation made in it was not used (it was counted as used, and an
            // external heading it took was lost uncounted: a review); the stance is not
            // observed again, as the zero-rate update is not made again.
            let c = &mut self.counters;
            let external_used = external_pending
                && self.pending_heading.is_none()
                && c.headings_expired == expired_before
                && c.heading_used > used_before.0;
            c.headings_undone += u64::from(external_used);
            (c.heading_used, c.stride_used) = used_before;
        } else if applied {
            self.counters.zero_rate_updates += 1;
        }
        if failed {
            self.late.drop_pending();
            self.drop_rail_peak();
        } else {
            self.check_specific_force(dt, stance, w, f);
            self.remember(t_clock, w, f);
            self.follow_rail_peaks(eskf, t_prev, (stance, stance_ended));
            let began = self.stance_edge == StanceEdge::Began;
            let flags = (decision.raw, stance, began, decision.statistic);
            self.follow_footfalls(eskf, t_clock, flags, &omega);
            if self.out.late_footfall_t_s.is_some() {
                // Propagated again from before the late footfall's update, an open peak
                // would lose it.
                self.drop_rail_peak();
            }
        }
        self.counters.velocity_resets += u64::from(self.out.velocity_reset);
        self.counters.heading_reacquisitions += u64::from(self.out.heading_reacquired.is_some());
        self.fill_output(eskf);
    }

    /// The quiet stances' specific force against gravity (`stance_force.rs`): said once when
    /// its median leaves the tolerance.
    #[inline]
    fn check_specific_force(
        &mut self,
        dt_s: f64,
        stance: bool,
        w: &Vector3<f64>,
        f: &Vector3<f64>,
    ) {
        let configured = self.cfg.alignment.gravity_m_s2;
        let gravity = || expected_gravity_m_s2(configured);
        if let Some(said) = self.stance_force.sample(dt_s, stance, w, f, gravity) {
            self.counters.specific_force_off_gravity += 1;
            self.out.specific_force_off_gravity = Some(said);
        }
    }

    /// The gravity the accelerometer should read at rest, m/s² ([`expected_gravity_m_s2`]).
    pub(super) fn expected_gravity_m_s2(&self) -> f64 {
        expected_gravity_m_s2(self.cfg.alignment.gravity_m_s2)
    }

    /// Foot-from-sensor rotation: `R_z(mount_yaw)·tilt0`.
    pub(super) fn foot_from_sensor(&self) -> UnitQuaternion<f64> {
        rot_z(self.mount_yaw_rad) * self.tilt0
    }

    /// The foot's forward axis in sensor axes. Its horizontal heading is the foot heading at
    /// any foot pitch or roll, unlike the sensor's ZYX yaw minus the mounting yaw, which is only
    /// right while the foot is flat.
    pub(super) fn foot_forward_body(&self) -> Vector3<f64> {
        self.forward_body
    }

    /// Recomputes [`Self::foot_forward_body`] after the tilt or the mounting yaw changed.
    pub(super) fn update_forward_body(&mut self) {
        self.forward_body = self.foot_from_sensor().inverse() * Vector3::x();
    }

    /// The gyro bias in sensor axes, without its σ (the per-sample paths need only this).
    pub(super) fn bias_only(&self, eskf: &Eskf) -> Vector3<f64> {
        match &self.bias {
            BiasFilter::InEskf => eskf.gyro_bias_rad_s,
            BiasFilter::Paper { kf, .. } => {
                let c = self.foot_from_sensor().to_rotation_matrix().into_inner();
                c.transpose() * kf.b_rad_s
            }
            BiasFilter::RotationAware { kf, .. } => kf.b_rad_s,
        }
    }

    /// The bias, its σ and the part of a bias error present when it was set that it still
    /// carries (`None` when no filter estimates it), in sensor axes.
    pub(super) fn bias_sensor(
        &self,
        eskf: &Eskf,
    ) -> (Vector3<f64>, Vector3<f64>, Option<Matrix3<f64>>) {
        match &self.bias {
            BiasFilter::InEskf => (
                eskf.gyro_bias_rad_s,
                eskf.gyro_bias_sd(),
                eskf.estimates_bias().then(|| eskf.unabsorbed_bias_error()),
            ),
            BiasFilter::Paper { kf, .. } => {
                let c = self.foot_from_sensor().to_rotation_matrix().into_inner();
                let p = c.transpose() * kf.p * c;
                (
                    c.transpose() * kf.b_rad_s,
                    p.diagonal().map(|v| v.max(0.0).sqrt()),
                    Some(c.transpose() * kf.unabsorbed * c),
                )
            }
            BiasFilter::RotationAware { kf, .. } => (kf.b_rad_s, kf.sd(), Some(kf.unabsorbed)),
        }
    }

    /// The estimate of the sample just processed, from the filter `e`.
    pub(super) fn fill_output(&mut self, e: &Eskf) {
        let (b, sd, unabsorbed) = self.bias_sensor(e);
        let q = e.nav_from_body;
        let (roll, pitch, yaw) = euler_zyx(&q);
        let out = &mut self.out;
        out.phase = self.phase;
        out.p_m = e.p_m.into();
        out.v_m_s = e.v_m_s.into();
        out.nav_from_body = [q.w, q.i, q.j, q.k];
        out.roll_rad = roll;
        out.pitch_rad = pitch;
        out.yaw_rad = yaw;
        out.gyro_bias_rad_s = b.into();
        out.gyro_bias_sd_rad_s = sd.into();
        out.bias_unabsorbed = unabsorbed.map_or(f64::NAN, |m| max_row_sum(&m));
        out.converged = self.phase == Phase::Tracking
            && out.bias_unabsorbed < self.cfg.converged_unabsorbed.get();
        if out.converged && self.converged_at_s.is_none() {
            self.converged_at_s = Some(out.t_s);
        }
    }
}

/// The gravity the accelerometer should read at rest, m/s²: `alignment.gravity_m_s2` as
/// `configured`, or standard gravity (the filter's own may come from a rest, and scale with the
/// sensor).
fn expected_gravity_m_s2(configured: Option<Positive>) -> f64 {
    configured.map_or(STANDARD_GRAVITY_M_S2, |g| g.get())
}
