//! One sample's navigation once aligned: the strapdown step (the filter and the paper and
//! rotation-aware modes' observers), the stance velocity update, the once-per-stance
//! bookkeeping and observations, and a later rest's zero-rate update.

use super::*;

impl Pipeline {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn navigate(
        &mut self,
        eskf: &mut Box<Eskf>,
        spare: &mut Box<Eskf>,
        t_s: f64,
        dt: f64,
        w_avg: &Vector3<f64>,
        f_avg: &Vector3<f64>,
        f_now: &Vector3<f64>,
        stance: bool,
        stance_age_s: f64,
    ) -> Vector3<f64> {
        // A stance sample's covariance is needed at once (its velocity update); a swing's
        // step may wait for the next ones' (`eskf.covariance_step_s`).
        let covariance = if stance {
            CovarianceStep::Now
        } else {
            CovarianceStep::MayDefer
        };
        let omega = self.propagate(eskf, spare, dt, w_avg, f_avg, covariance);
        self.widen_clipped(eskf, self.clipped_gyro_axes, dt);
        if stance {
            self.out.zupt = self.stance_velocity_update(eskf, &omega, true);
            self.counters.zupts += 1;
        }
        // Once per stance (footfall): a stance event that began since the last one seen here
        // (it may have begun while aligning).
        if stance && self.stances_seen != self.stance_events.count() {
            self.stances_seen = self.stance_events.count();
            self.stance_rest.clear();
            eskf.set_at_rest(false);
            self.stance_obs_done = false;
            self.resumed_look = false;
            self.stance_f_sum = (Vector3::zeros(), 0);
            self.counters.stances += 1;
            self.out.stance_counted = true;
        } else if self.stance_edge == StanceEdge::Resumed {
            // The heading is observed again once the foot has settled after the pause (heel
            // strike, pause, foot flat): observing only in the first part was measured worse
            // (exp40 1.67 -> 3.71 %, 3.2-4.1 % under six perturbations of the noise figures
            // against 1.6-1.8 %; the other walks within 0.03 %). The stride is not observed
            // again (it was, since the previous footfall).
            self.stance_obs_done = false;
            self.resumed_look = true;
        }
        if stance {
            self.stance_f_sum.0 += f_now;
            self.stance_f_sum.1 += 1;
            if self.relevel_next_stance && stance_age_s >= observations::RELEVEL_MIN_STANCE_S {
                self.relevel_if_due(eskf);
            }
            if !self.stance_obs_done && stance_age_s >= self.cfg.heading.obs_delay_s.get() {
                self.stance_obs_done = true;
                self.stance_observation(eskf, t_s);
            }
            if self.cfg.eskf.zero_rate_updates {
                // Its blocks timed on the stamps less the clock's steps (monotonic).
                self.stance_rest
                    .push(t_s - self.clock.offset_s(), f_avg, w_avg);
                // A long rest is fused as it goes: fused only at its end, the yaw integrated
                // the difference between the filter's bias and the rest's rate for the whole
                // rest (a 120 s pause at every walk's middle footprint, at the initial rest's
                // rate: normal-gait median 2.32 %, worst 17.8 %; 0.30 / 0.85 % now).
                let interval_s = self.cfg.eskf.zero_rate_interval_s.get();
                if let Some(rest) = self.stance_rest.settled_means(interval_s) {
                    self.stance_rest.restart_settled();
                    // From here to the end of the stance the foot rests (when its mean rate
                    // was a bias, not a slow turn the gate refused): the attitude's noise is
                    // the sensor's, not a swing's (the yaw σ of `gyro_noise_rad_s` grew by 14°
                    // in a 600 s pause, and exp26's strides after it were associated wrongly:
                    // 13.5 %, 0.29 % at the rest's noise).
                    if self.fuse_rest(eskf, rest) {
                        eskf.set_at_rest(true);
                    }
                }
            }
        } else if self.was_stance {
            // The end of an uninterrupted stance: a rest must be uninterrupted, so each part of
            // a merged stance is tested on its own, at its first pause sample.
            eskf.set_at_rest(false);
            let min_rest_s = self.cfg.alignment.min_rest_s.get();
            if let (true, Some(rest)) = (
                self.cfg.eskf.zero_rate_updates,
                self.stance_rest.settled_means(min_rest_s),
            ) {
                self.fuse_rest(eskf, rest);
            }
            self.stance_rest.clear();
        }
        self.was_stance = stance;
        omega
    }

    /// A gyro reading at or beyond this magnitude is at its rail (probably clipped), rad/s.
    pub(super) fn gyro_rail_rad_s(&self) -> f64 {
        CLIP_FRACTION * self.cfg.sensor.gyro_range_rad_s()
    }

    /// The attitude variance about each gyro axis at its rail grows by the clipped rate's σ
    /// over the step: the rotation the rail cut off.
    pub(super) fn widen_clipped(&self, eskf: &mut Eskf, clipped_axes: [bool; 3], dt: f64) {
        let clip_var = (self.cfg.eskf.clipped_rate_sd_rad_s.get() * dt).powi(2);
        for (k, &c) in clipped_axes.iter().enumerate() {
            if c && clip_var > 0.0 {
                eskf.widen_attitude_about(&Vector3::ith(k, 1.0), clip_var);
            }
        }
    }

    /// The stance velocity update of a sample whose bias-corrected rate is `omega`. A velocity
    /// beyond what the filter allows is reset first when `may_reset` (and reported), else the
    /// update is not made (`None`).
    pub(super) fn stance_velocity_update(
        &mut self,
        eskf: &mut Eskf,
        omega: &Vector3<f64>,
        may_reset: bool,
    ) -> Option<Innovation> {
        // A foot that rolls about its heel or toe moves the sensor at the lever arm times the
        // rotation rate: at the edges of a stance the zero velocity is that much less sure.
        let arm = self.cfg.eskf.zupt_lever_arm_m.get() * omega.norm();
        let sd = self.cfg.eskf.zupt_sd_m_s.get().hypot(arm);
        // ... and, rolling over its heel, its ball or the edge of its sole, at its height
        // above the floor times the horizontal rate (ω × h·ẑ; no mounting yaw needed).
        let h = self.cfg.eskf.zupt_rolling_height_m.get();
        let v = if h > 0.0 {
            rolling_velocity(&eskf.nav_from_body, omega, h)
        } else {
            Vector3::zeros()
        };
        // A velocity far beyond what the filter allows (a burst of garbage samples since the
        // last stance that the health check did not catch) would turn the attitude and the
        // bias by what only the velocity got wrong: it is reset instead, as after a gap.
        if eskf.stance_velocity_implausible(&v, sd, VELOCITY_RESET_Z2) {
            if !may_reset {
                return None;
            }
            let v_max = self.cfg.max_speed_m_s.get();
            eskf.reset_velocity(v_max * v_max);
            // Counted once the step is kept (`step_running`).
            self.out.velocity_reset = true;
        }
        Some(eskf.stance_velocity_update(&v, sd))
    }

    /// One strapdown step of the filter and of the paper and rotation-aware modes' observers,
    /// on the step's mean rate and force; returns the bias-corrected rate. Propagated into the
    /// spare buffer, which becomes the running filter: `spare` is left with the state before.
    /// The covariance's step may wait as `covariance` says ([`CovarianceStep`]).
    pub(super) fn propagate(
        &mut self,
        eskf: &mut Box<Eskf>,
        spare: &mut Box<Eskf>,
        dt: f64,
        w_avg: &Vector3<f64>,
        f_avg: &Vector3<f64>,
        covariance: CovarianceStep,
    ) -> Vector3<f64> {
        let bias = self.bias_only(eskf);
        match &mut self.bias {
            BiasFilter::InEskf => {}
            BiasFilter::Paper { obs, .. } => {
                if let Some(o) = obs {
                    o.propagate(w_avg, dt);
                }
            }
            BiasFilter::RotationAware { obs, .. } => {
                if let Some(o) = obs {
                    o.propagate(w_avg, &bias, dt);
                }
            }
        }
        let omega = eskf.corrected_rate(w_avg, f_avg, &bias);
        eskf.propagate_into(spare, &omega, f_avg, dt, covariance);
        std::mem::swap(eskf, spare);
        omega
    }

    /// At the end of a stance that was a rest (its part before the last `alignment.rest_tail_s`
    /// lasts `alignment.min_rest_s`), and every `eskf.zero_rate_interval_s` of a long one: the
    /// mean rate over that part observes the gyro bias with the σ of the rest-mean prior
    /// (√(floor² + spread²), see `rest.rs`), as the initial rest does. Counted once the health
    /// check has passed (`step_running`). Says whether the update was made (not refused by its
    /// gate: a slow turn).
    fn fuse_rest(&mut self, eskf: &mut Eskf, rest: RestMeans) -> bool {
        let (mean_f, mean_w, sem) = rest;
        let floor = self.cfg.eskf.gyro_bias_prior_sd_rad_s.get();
        let sd = sem.map(|v| v.hypot(floor));
        match eskf.zero_rate_update(&mean_w, &mean_f, &sd) {
            Some(Ok(_)) => {
                self.zero_rate_applied = true;
                return true;
            }
            Some(Err(_)) => self.counters.zero_rate_refused += 1,
            None => {}
        }
        false
    }
}
