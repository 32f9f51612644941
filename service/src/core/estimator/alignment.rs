//! The alignment: the initial rest (or, without one, the first stance) that gives roll, pitch,
//! gravity and the bias prior and starts the filter; a saved bias state for a warm start.

use super::*;

#[cfg(test)]
thread_local! {
    /// Tests only: the gait taken as fast from the first sample on, as a start in fast gait
    /// that goes back takes it over its window: a live start on the stance such a start goes
    /// back to (`tests.rs`).
    pub(super) static GAIT_TAKEN_AS_FAST: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

#[cfg(test)]
fn gait_taken_as_fast() -> bool {
    GAIT_TAKEN_AS_FAST.with(std::cell::Cell::get)
}

#[cfg(not(test))]
fn gait_taken_as_fast() -> bool {
    false
}

impl Pipeline {
    /// One sample while aligning (`Estimator::step`): the initial rest's bookkeeping of
    /// losses, then [`Pipeline::align_step`]. `t_prev` and `t_clock` are the sample clock's
    /// times of the previous sample and this one; the filter when the alignment ends here,
    /// and whether it has run this sample already (a start in fast gait that went back).
    pub(super) fn align_sample(
        &mut self,
        rest: &mut InitialRest,
        t_prev: Option<f64>,
        t_clock: f64,
        t_s: f64,
        (w, f): (&Vector3<f64>, &Vector3<f64>),
        decision: &StanceDecision,
    ) -> Option<Start> {
        // A loss longer than a bridgeable gap (`estimator.max_bridge_s`, at least `max_dt_s`:
        // a few lost samples or a driver's stall stay within the rest) after less than
        // `alignment.min_rest_s` of rest is remembered, and the rest since it kept apart.
        // When the rest ends with less than `min_rest_s` of it after the loss as well, the
        // alignment starts again from the loss: what the foot did in it is unknown, and
        // neither side is a rest by itself, unless the two together are one rest
        // (`InitialRest::end`: a short rest with a pause in it). Timed across a loss into
        // the walk, such a rest took the first stance after it for its last seconds, and
        // that stance's rate for the bias prior (exp17 with 2.25 s lost from 0.4 s: a prior
        // of 0.08 rad/s, the health check failing for the rest of the walk). A rest that
        // goes on after its loss is kept whole: started again at the loss, a loss or a
        // stall of 0.2–0.3 s 0.43 s into exp40's rest (then 0.8 s of it rocking) cost up to
        // 9.5 % of path; started again at any loss, 58 of a review's 288 runs were worse by
        // more than 0.3 % of path.
        let bridgeable_s = self.cfg.max_bridge_s.get().max(self.cfg.max_dt_s.get());
        let min_rest_s = self.cfg.alignment.min_rest_s.get();
        if let Some(t_prev) = t_prev
            && t_clock - t_prev > bridgeable_s
        {
            rest.lose(min_rest_s);
        }
        self.record(&mut rest.recent, (t_clock, t_s), (w, f), decision);
        let raised = self.detector.raised(t_clock) || gait_taken_as_fast();
        let aligned = self.align_on(rest, t_s, (w, f), decision, raised);
        if aligned.is_none() {
            // A gap the rest spans is counted here; one the alignment ends at, where the
            // filter crosses it (as a new segment).
            if let Some(t_prev) = t_prev
                && t_clock - t_prev > self.cfg.max_dt_s.get()
                && self.out.gap_s.is_none()
            {
                self.counters.gaps += 1;
                self.out.gap_s = Some(t_clock - t_prev);
                self.out.gap_crossing = Some(GapCrossing::InRest);
            }
        }
        aligned.map(|live| {
            if self.counters.started_without_rest && rest.fast_gait() {
                // The gait was known to be fast only now: the start goes back to the first
                // stance the fast-gait rule takes (`fast_start.rs`).
                self.start_earlier(&rest.recent, live)
            } else {
                Start::Here(live)
            }
        })
    }

    /// One sample of the rest or of a stance that may align: the filter when the alignment
    /// ends with it. `raised`: the stance detector's threshold was raised by the gait on this
    /// sample (a replay in fast gait takes it as raised: `fast_start.rs`).
    pub(super) fn align_on(
        &mut self,
        rest: &mut InitialRest,
        t_s: f64,
        (w, f): (&Vector3<f64>, &Vector3<f64>),
        decision: &StanceDecision,
        raised: bool,
    ) -> Option<Box<Eskf>> {
        let stance = decision.stance;
        let min_rest_s = self.cfg.alignment.min_rest_s.get();
        rest.observe(decision, raised, self.cfg.detector.window);
        let mut restarted = false;
        if stance {
            rest.push(t_s, f, w);
        } else {
            restarted = rest.end(t_s, min_rest_s);
        }
        // One restart, counted once: the alignment counts it as well when what is left
        // after the loss is too short to start from.
        let restarts = self.counters.alignment_restarts;
        let a = &self.cfg.alignment;
        let min_start_s =
            rest.min_start_s(a.min_start_stance_s.get(), a.fast_gait_start_stance_s.get());
        let aligned = self.align_step(&mut rest.whole, t_s, (w, f), stance, min_start_s);
        if restarted && self.counters.alignment_restarts == restarts {
            self.counters.alignment_restarts += 1;
        }
        aligned
    }

    /// One sample of the initial rest; the filter when the alignment ends with it (boxed here,
    /// out of line: an `Eskf` returned by value took 7 KB of the per-sample step's frame).
    /// `min_start_s`: the shortest stance that may start the filter without a rest here
    /// ([`InitialRest::min_start_s`]).
    #[inline(never)]
    pub(super) fn align_step(
        &mut self,
        rest: &mut RestSums,
        t_s: f64,
        (w, f): (&Vector3<f64>, &Vector3<f64>),
        stance: bool,
        min_start_s: f64,
    ) -> Option<Box<Eskf>> {
        if stance {
            rest.push(t_s, f, w);
            let (mean_f, _) = rest.means();
            let (roll, pitch) = tilt_from_specific_force(&mean_f);
            let q = from_euler_zyx(roll, pitch, 0.0);
            self.out.nav_from_body = [q.w, q.i, q.j, q.k];
            self.out.roll_rad = roll;
            self.out.pitch_rad = pitch;
            return None;
        }
        let rest_s = if rest.is_empty() {
            0.0
        } else {
            t_s - rest.t_first_s
        };
        let a = &self.cfg.alignment;
        // Without a rest, the first stance of at least `min_start_s` aligns: roll and pitch
        // from its mean specific force, known to `alignment.start_stance_tilt_sd_rad` (the
        // ZUPTs refine them), no bias prior (the later rests' zero-rate updates and the
        // heading observations give the bias).
        let short_start = rest_s < a.min_rest_s.get();
        if short_start && (a.min_start_stance_s.get() <= 0.0 || rest_s < min_start_s) {
            if !rest.is_empty() {
                self.counters.alignment_restarts += 1;
            }
            rest.clear();
            return None;
        }
        // A rest's blocks in which the foot moved are left out; a walking stance's (no rest)
        // are not: it begins with its landing, which the motion test would take as reference.
        let (mean_f, mean_w) = if short_start {
            rest.means_all()
        } else {
            rest.means()
        };
        // A "rest" whose specific force is no gravity (a stream in g) aligns nothing.
        let g_expected = self.expected_gravity_m_s2();
        let f_norm = mean_f.norm();
        if (f_norm - g_expected).abs() > GRAVITY_TOLERANCE * g_expected || !f_norm.is_finite() {
            self.counters.alignment_not_gravity += 1;
            self.out.not_gravity_m_s2 = Some((f_norm, g_expected));
            rest.clear();
            return None;
        }
        self.counters.started_without_rest = short_start;
        if !short_start {
            self.counters.initial_rest_moving_blocks = rest.moving_blocks();
            // Standing still, the foot reads gravity to the accelerometer's scale error (the
            // aligning rests of the 16 gdins walks 9.809–9.825 m/s²): beyond the stances' own
            // tolerance the scale or units are wrong, said now rather than after fifteen quiet
            // stances. Only a rest that was still for `min_rest_s` and moved in no more blocks
            // than it stood still: one that is mostly motion anchors its motion test on a
            // moving block (exp40 from 0.705 s, 10 of 13 blocks moving, read +5.0 %: a
            // review). A walking stance reads its landing and push-off too: not held to it.
            let still_s = rest.still_s();
            let still = still_s >= a.min_rest_s.get()
                && rest.moving_blocks() as f64 * REST_BLOCK_S <= still_s;
            if still && self.stance_force.rest(f_norm, g_expected) {
                self.counters.specific_force_off_gravity += 1;
                self.out.specific_force_off_gravity = Some(OffGravity {
                    force_m_s2: f_norm,
                    gravity_m_s2: g_expected,
                    witness: ForceWitness::InitialRest,
                });
            }
        }
        // The prior's σ: √(floor² + spread²), the bias instability floor and the rest's rate
        // spread over √(number of 50 ms blocks) (a rest during which the foot still sways).
        let rest_sd = rest
            .rate_sd_of_mean()
            .map(|v| v.hypot(self.cfg.eskf.gyro_bias_prior_sd_rad_s.get()));
        // Gravity from the rest's mean specific force, but not from a walking stance (its
        // push-off would bias it): standard gravity then, unless configured.
        let g = self.cfg.alignment.gravity_m_s2.map_or(
            if short_start {
                STANDARD_GRAVITY_M_S2
            } else {
                mean_f.norm()
            },
            |g| g.get(),
        );
        self.detector.set_gravity(g);
        let (roll, pitch) = tilt_from_specific_force(&mean_f);
        self.tilt0 = from_euler_zyx(roll, pitch, 0.0);
        self.update_forward_body();
        // A "rest" that turned faster than any bias of this sensor can be is no measurement of
        // the bias (a foot pivoting on its heel, a log that starts mid-walk): its mean rate would
        // start the filter in a state the health check refuses, and every later state with it.
        // The same for a rest turning faster than `alignment.max_prior_rate_rad_s` (its rate's
        // magnitude), where a sensor's biases are known to be smaller.
        let bound = self.cfg.sensor.max_gyro_bias_rad_s();
        let turning = !short_start
            && (mean_w.iter().any(|v| v.abs() > bound)
                || self
                    .cfg
                    .alignment
                    .max_prior_rate_rad_s
                    .is_some_and(|m| mean_w.norm() > m.get()));
        let wants_prior = self.cfg.alignment.gyro_bias_prior == BiasPrior::RestMean;
        self.counters.rest_prior_refused = wants_prior && turning;
        let rest_prior = wants_prior && !short_start && !turning;
        // The rest's mean rate is a measurement of the bias with the σ above; the sensor's own
        // spread of biases (`eskf.gyro_bias_initial_sd_rad_s` about zero) is what is known
        // before it, and the two are fused per axis. A quiet rest's σ (5e-4–2.5e-3 rad/s) is
        // far below 0.01 and its mean is taken nearly whole; a "rest" that is mostly motion (a
        // foot that shifts before its first step, a rest cut short by a loss so that only its
        // moving tail is left) has a wide σ and its mean, tens of mrad/s off, no longer starts
        // the filter there. Without a rest (or with one refused as turning) the start is the
        // unit's typical bias when configured (`alignment.typical_gyro_bias_rad_s`). It is not
        // fused with a rest: fused, its σ of 4 mrad/s pulled a swaying rest's mean by up to 28 %
        // of the difference, which is right only for this unit and a bias that did not
        // move (a g-sensitivity injected into the diagnosis's matrix was named first on 8 of 13
        // walks instead of 10, and the late injection lost an axis: session 38).
        let (b0, prior_sd, sd0) = if rest_prior {
            let initial_sd = self.cfg.eskf.gyro_bias_initial_sd_rad_s.get();
            let (b0, prior_sd) = fuse_with_zero_prior(&mean_w, &rest_sd, initial_sd);
            (b0, prior_sd, self.cfg.eskf.gyro_bias_prior_sd_rad_s.get())
        } else {
            let (before_rest, before_rest_sd) = self.bias_before_rest();
            (before_rest, Vector3::repeat(before_rest_sd), before_rest_sd)
        };
        let e = &self.cfg.eskf;
        let own_bias = matches!(self.cfg.mode, Mode::Zupt | Mode::Eskf);
        let noise = EskfNoise {
            accel_m_s2: e.accel_noise_m_s2.get(),
            gyro_rad_s: e.gyro_noise_rad_s.get(),
            rest_gyro_rad_s: e.rest_gyro_noise_rad_s.get(),
            gyro_bias_rw_rad_s_sqrt_s: e.gyro_bias_rw_rad_s_sqrt_s.get(),
            zupt_m_s: e.zupt_sd_m_s.get(),
            stance_yaw_max_sd_rad: match e.stance_yaw_max_sd_rad.get() {
                0.0 => f64::INFINITY,
                sd => sd,
            },
            covariance_step_s: e.covariance_step_s.get(),
        };
        let m = &self.cfg.model;
        let ext = if own_bias {
            Extensions {
                bias_rate_rw: m.bias_rate_rw_rad_s2_sqrt_s.map(|v| v.get()),
                bias_rate_sd: m.bias_rate_initial_sd_rad_s2.get(),
                scale_factor_sd: m.scale_factor_sd.map(|v| v.get()),
                heading_offset_sd: m.heading_offset_sd_rad.map(|v| v.get()),
                g_sensitivity_sd: m.g_sensitivity_sd.map(|v| v.get()),
                coupling_sd: m.gyro_coupling_z_sd_rad.map(|v| v.get()),
                footprint_clone: self.cfg.mode == Mode::Eskf
                    && self.cfg.heading.observations.stride(),
                stride_look_ahead: self.cfg.heading.stride_look_ahead,
            }
        } else {
            // The extensions are observed through the filter's own heading updates, which the
            // bias-filter modes do not make.
            Extensions::default()
        };
        let mut eskf = Eskf::new(
            EskfInit {
                nav_from_body: self.tilt0,
                gyro_bias_rad_s: if own_bias { b0 } else { Vector3::zeros() },
                // A walking stance's mean force holds what the foot still accelerates: its
                // tilt is known to `alignment.start_stance_tilt_sd_rad`, and the ZUPTs of the
                // next stances refine it. Trusted as a rest's, the tilt error goes into the
                // horizontal bias instead. The bias-filter modes' filter has no bias states
                // for it to go to, and keeps the rest's σ (the wider one made 12 and 13 of a
                // review's 400 starts worse by more than 0.3 % of path there, and no restores
                // either way).
                tilt_sd_rad: if short_start && own_bias {
                    self.cfg.alignment.start_stance_tilt_sd_rad.get()
                } else {
                    e.initial_tilt_sd_rad.get()
                },
                bias_sd_rad_s: sd0,
                gravity_m_s2: g,
                bias: if own_bias {
                    BiasStates::Estimated
                } else {
                    BiasStates::Frozen
                },
            },
            noise,
            ext,
        );
        let rw = self.cfg.bias_kf.bias_rw_rad_s_sqrt_s.get();
        self.bias = match self.cfg.mode {
            Mode::Zupt | Mode::Eskf => BiasFilter::InEskf,
            // The paper's filter works on a foot-frame bias; the foot frame is the sensor frame
            // rotated by the mounting, fixed later. Start from the prior expressed in the foot
            // frame with the tilt only (the mounting yaw is applied when known).
            Mode::Paper => BiasFilter::Paper {
                kf: BiasKf::new(self.tilt0 * b0, sd0, rw, t_s),
                obs: None,
            },
            Mode::RotationAware => BiasFilter::RotationAware {
                kf: BiasKf::new(b0, sd0, rw, t_s),
                obs: None,
            },
        };
        // The rest-mean prior's covariance per axis (fused as above), in each filter's axes.
        let prior_cov = Matrix3::from_diagonal(&prior_sd.map(|v| v * v));
        match &mut self.bias {
            BiasFilter::Paper { kf, .. } if rest_prior => {
                let c = self.tilt0.to_rotation_matrix().into_inner();
                kf.p = c * prior_cov * c.transpose();
            }
            BiasFilter::RotationAware { kf, .. } if rest_prior => kf.p = prior_cov,
            _ => {}
        }
        if own_bias && rest_prior {
            eskf.set_gyro_bias(b0, &prior_cov);
        }
        if let Some(ws) = self.warm_start {
            self.apply_warm_start(&mut eskf, &ws);
            // A saved state (hours old, perhaps) and a fresh rest are two observations of the
            // same bias: the rest is fused into the saved state rather than thrown away.
            // A rest beyond the gate of the saved bias: the bias moved while the estimator was
            // down (hours, another temperature), and the rest is the measurement of now.
            if own_bias
                && rest_prior
                && let Some(Err(_)) = eskf.zero_rate_update(&mean_w, &mean_f, &rest_sd)
            {
                self.counters.zero_rate_refused += 1;
                eskf.set_gyro_bias(b0, &prior_cov);
            }
        }
        self.phase = Phase::Calibrating;
        Some(Box::new(eskf))
    }

    /// What is known of the bias before any rest or stance measured it (sensor axes; σ per
    /// axis): the unit's typical bias with the rest-mean prior, when configured
    /// (`alignment.typical_gyro_bias_rad_s`), else zero with the sensor's spread of biases
    /// (`eskf.gyro_bias_initial_sd_rad_s`). Also where a bias thrown away (a restore loop, a
    /// relevel) starts again.
    pub(super) fn bias_before_rest(&self) -> (Vector3<f64>, f64) {
        match self.cfg.alignment.typical_gyro_bias {
            Some(t) if self.cfg.alignment.gyro_bias_prior == BiasPrior::RestMean => {
                (Vector3::from(t.rad_s), t.sd_rad_s.get())
            }
            _ => (
                Vector3::zeros(),
                self.cfg.eskf.gyro_bias_initial_sd_rad_s.get(),
            ),
        }
    }

    /// Replaces the bias prior by a saved state (bias and covariance in sensor axes).
    pub(super) fn apply_warm_start(&mut self, eskf: &mut Eskf, ws: &WarmStart) {
        let b = Vector3::from(ws.gyro_bias_rad_s);
        let p = Matrix3::from_fn(|i, j| ws.gyro_bias_cov[i][j]);
        self.set_bias(eskf, b, &p);
    }

    /// Sets the bias and its covariance (sensor axes) in whichever filter owns it.
    pub(super) fn set_bias(&mut self, eskf: &mut Eskf, b: Vector3<f64>, p: &Matrix3<f64>) {
        let c = self.foot_from_sensor().to_rotation_matrix().into_inner();
        match &mut self.bias {
            BiasFilter::InEskf => eskf.set_gyro_bias(b, p),
            BiasFilter::Paper { kf, .. } => kf.set(c * b, c * p * c.transpose()),
            BiasFilter::RotationAware { kf, .. } => kf.set(b, *p),
        }
    }
}

/// The bias measured as `mean` with σ `sd` (per axis), fused with a prior of zero and σ
/// `prior_sd`: the posterior mean and σ, per axis.
fn fuse_with_zero_prior(
    mean: &Vector3<f64>,
    sd: &Vector3<f64>,
    prior_sd: f64,
) -> (Vector3<f64>, Vector3<f64>) {
    let p2 = prior_sd * prior_sd;
    let gain = sd.map(|s| p2 / (p2 + s * s));
    let post_sd = sd.map(|s| (p2 * s * s / (p2 + s * s)).sqrt());
    (mean.component_mul(&gain), post_sd)
}
