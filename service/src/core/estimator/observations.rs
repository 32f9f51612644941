//! Once per stance: the calibration of the map frame and the mounting yaw, then the heading
//! observations of the configured mode.

use super::association::weighted_association;
use super::*;

/// The paper mode's observer starts a new epoch when its raw attitude is this far from the
/// observed one, rad (its logarithm wraps at π).
const PAPER_EPOCH_MAX_ANGLE_RAD: f64 = 2.0;

/// A stance is levelled again (after restores that did not hold, `recovery.rs`) once it has
/// lasted this long, s: its mean force is then the standing foot's more than the landing's ...
pub(super) const RELEVEL_MIN_STANCE_S: f64 = 0.1;

/// ... and when that mean force lies within this fraction of gravity.
const RELEVEL_FORCE_TOLERANCE: f64 = 0.1;

/// The tilt's σ after it is levelled again, rad (3°): the mean force of a stance's first tenth
/// of a second carries its landing, and lies 0.8–2.8° (median per walk; at most 5.4°) off the
/// vertical of a healthy filter on the bundled walks (a review's measurement).
const RELEVEL_TILT_SD_RAD: f64 = 0.05;

impl Pipeline {
    /// Levels the tilt again from the stance's mean specific force, when restores that did not
    /// hold asked for it (`relevel_next_stance`): the heading kept, the bias started again from
    /// zero with its initial σ. From [`RELEVEL_MIN_STANCE_S`] into a stance, at the first sample
    /// at which the stance's mean force is a standing foot's. True when it did.
    pub(super) fn relevel_if_due(&mut self, eskf: &mut Eskf) -> bool {
        let (sum, n) = self.stance_f_sum;
        let f = sum / n.max(1) as f64;
        let g = eskf.gravity_m_s2();
        if !self.relevel_next_stance || n == 0 || (f.norm() - g).abs() > RELEVEL_FORCE_TOLERANCE * g
        {
            return false;
        }
        self.relevel_next_stance = false;
        let up = f.normalize();
        let e = &self.cfg.eskf;
        let (bias, bias_sd) = self.bias_before_rest();
        eskf.relevel(
            &up,
            RELEVEL_TILT_SD_RAD.powi(2),
            e.zupt_sd_m_s.get().powi(2),
        );
        // What the filter made of a wrong tilt went into the bias, whichever filter owns it.
        let p = Matrix3::from_diagonal_element(bias_sd * bias_sd);
        self.set_bias(eskf, bias, &p);
        self.counters.relevels += 1;
        true
    }

    /// Once per stance: calibration or a heading observation.
    pub(super) fn stance_observation(&mut self, eskf: &mut Eskf, t_s: f64) {
        let h = self.cfg.heading.clone();
        let forward = self.foot_forward_body();
        if self.phase == Phase::Calibrating {
            let stride_dir = match self.last_footprint {
                None => {
                    let d = eskf.p_m;
                    if d.x.hypot(d.y) < 0.2 {
                        return; // not a stride yet (a shuffle in place)
                    }
                    eskf.rotate_frame(h.start_heading_rad.get() - d.y.atan2(d.x));
                    eskf.set_heading_variance(h.start_heading_sd_rad.get().powi(2));
                    self.out.frame_set = true;
                    h.start_heading_rad.get()
                }
                Some((xy, _)) => {
                    let (dx, dy) = (eskf.p_m.x - xy[0], eskf.p_m.y - xy[1]);
                    if dx.hypot(dy) < h.min_stride_m.get() {
                        return; // a shuffle: wait for a real stride
                    }
                    dy.atan2(dx)
                }
            };
            // The sensor's yaw on the foot is learnt on straight strides only (this stride in
            // the direction of the previous one): in a turn the foot at touchdown does not
            // point along the stride that brought it there.
            let straight = self
                .last_footprint
                .and_then(|(_, prev)| prev)
                .is_none_or(|prev| {
                    wrap_pi(stride_dir - prev).abs() <= h.straight_max_change_rad.get()
                });
            self.last_footprint = Some(([eskf.p_m.x, eskf.p_m.y], Some(stride_dir)));
            self.new_footprint(eskf, t_s);
            if !straight {
                return;
            }
            // The sensor's yaw on the foot: the one that gives the foot's forward axis the
            // stride's direction as its heading at this stance. Not the ZYX yaw of the attitude
            // less the rest's tilt, less the stride's direction: the two agree only where the
            // stance's tilt is the rest's, and differ by an angle that depends on how the
            // sensor sits on the shoe.
            let m = self.mount_yaw_of_stride(eskf, stride_dir);
            self.mount_sum.0 += m.cos();
            self.mount_sum.1 += m.sin();
            self.mount_sum.2 += 1;
            self.straight.push(stride_dir);
            if self.mount_sum.2 >= h.calibration_strides {
                self.mount_yaw_rad = self.mount_sum.1.atan2(self.mount_sum.0);
                self.update_forward_body();
                self.phase = Phase::Tracking;
                self.calibrate_bias_filter(eskf.nav_from_body, t_s);
                // The stance copy the health check restores is taken again, now calibrated.
                self.good_saved_this_stance = false;
            }
            return;
        }
        let due = self.due_heading(t_s);
        if self.cfg.mode == Mode::Eskf && due.is_none() {
            self.eskf_observations(eskf, &forward, t_s);
            return;
        }
        let foot_heading = wrap_pi(eskf.predicted_heading(&forward));
        let straight = self.straight.push(foot_heading);
        let xy = [eskf.p_m.x, eskf.p_m.y];
        let external = due.is_some();
        let (direction, sd) = match due {
            Some(h) => (Ok(h.heading_rad), h.sd_rad),
            None if self.cfg.mode == Mode::Zupt => (Err(Rejection::NoSource), h.sigma_rad.get()),
            None if !straight => (Err(Rejection::NotStraight), h.sigma_rad.get()),
            None => (
                self.aid.associate(xy, foot_heading, h.gate_rad.get()),
                h.sigma_rad.get(),
            ),
        };
        let mut event = HeadingEvent {
            foot_heading_rad: foot_heading,
            direction_rad: f64::NAN,
            outcome: Err(Rejection::NoSource),
            baseline_s: 0.0,
            observed_t_s: t_s,
        };
        match direction {
            Err(r) => {
                self.count_rejection(r);
                event.outcome = Err(r);
            }
            Ok(dir) => {
                event.direction_rad = dir;
                let sensor_yaw = dir + self.mount_yaw_rad; // flat foot at heading `dir`
                let tilt_sd = self.cfg.bias_kf.tilt_sd_rad.get();
                // The bias filters' time runs on the stamps less the clock's steps, as the
                // rotation they compare does (`SampleClock::take_back`).
                let t_s = t_s - self.clock.offset_s();
                // An external heading far from the filter's prediction is refused in every
                // mode: the attitude filter runs in each, whichever filter owns the bias (the
                // gate was the eskf mode's alone, and one absurd heading moved the paper
                // filter's bias by 0.05 rad/s: a review).
                let gated = external && outside_gate(eskf, dir, sd, &forward);
                if gated {
                    self.counters.headings_outside_gate += 1;
                    event.outcome = Err(Rejection::OutsideGate);
                }
                let innovation = match &mut self.bias {
                    _ if gated => None,
                    BiasFilter::InEskf => Some(eskf.heading_update(dir, sd, &forward)),
                    BiasFilter::Paper { kf, obs } => {
                        let q_true = rot_z(sensor_yaw) * self.tilt0;
                        let innovation =
                            obs.as_ref()
                                .and_then(|o| o.observe(&q_true, t_s))
                                .map(|(y, el)| {
                                    event.baseline_s = el;
                                    kf.predict(t_s);
                                    let r = Vector3::new(tilt_sd / el, tilt_sd / el, sd / el)
                                        .map(|v| v * v);
                                    kf.update(&y, &Matrix3::identity(), &r)
                                });
                        // The raw attitude drifts from the true one by the bias times the time
                        // since the epoch; past π the logarithm wraps and the observation turns
                        // round (a long-running daemon at this sensor's 6.5e-3 rad/s: after 8
                        // minutes). The epoch restarts at this observation well before that;
                        // the bundled walks (at most 1.5 rad) never reach it.
                        if let Some(o) = obs.as_mut() {
                            o.restart_if_far(&q_true, t_s, PAPER_EPOCH_MAX_ANGLE_RAD);
                        }
                        innovation
                    }
                    BiasFilter::RotationAware { kf, obs } => {
                        let (sum, n) = self.stance_f_sum;
                        let (roll, pitch) = tilt_from_specific_force(&(sum / n.max(1) as f64));
                        // The accelerometer's tilt, turned about z until the foot axis points at `dir`.
                        let tilt = from_euler_zyx(roll, pitch, 0.0);
                        let q_true = rot_z(dir - heading_of_axis(&tilt, &forward)) * tilt;
                        obs.as_ref().map(|o| {
                            let (y, hm) = o.observe(&q_true);
                            kf.predict(t_s);
                            let r = Vector3::new(tilt_sd, tilt_sd, sd).map(|v| v * v);
                            kf.update(&y, &hm, &r)
                        })
                    }
                };
                if let Some(i) = innovation {
                    self.counters.heading_used += 1;
                    event.outcome = Ok(i);
                }
            }
        }
        self.out.heading = Some(event);
    }

    /// The external heading this stance, observed at `t_s` (stamped), uses: the pending one if
    /// its time has come ([`EXTERNAL_HEADING_LEAD_S`]), taken; one whose time is more than
    /// [`EXTERNAL_HEADING_MAX_AGE_S`] past is taken and counted as expired; one whose time is
    /// to come stays pending.
    fn due_heading(&mut self, t_s: f64) -> Option<QueuedHeading> {
        let h = self.pending_heading?;
        let t_s = t_s - self.clock.offset_s();
        if h.t_s - t_s > EXTERNAL_HEADING_LEAD_S {
            return None;
        }
        self.pending_heading = None;
        if t_s - h.t_s > EXTERNAL_HEADING_MAX_AGE_S {
            self.counters.headings_expired += 1;
            return None;
        }
        Some(h)
    }

    /// The `eskf` mode's observations at a stance: the stride direction since the previous
    /// footprint (with `heading.stride_look_ahead`, the stride before it, one stance late) and
    /// the foot axis, each associated with the nearest dominant direction and fused with the
    /// weight of that association (see [`association_weight`]).
    fn eskf_observations(&mut self, eskf: &mut Eskf, forward: &Vector3<f64>, t_s: f64) {
        // The foot axis is associated where the stance began, before the stride update.
        let xy = [eskf.p_m.x, eskf.p_m.y];
        // The stride that brought the foot here (before it is observed or cloned).
        let stride_dir = eskf
            .stride_since_footprint()
            .filter(|&(len, _)| len >= self.cfg.heading.min_stride_m.get())
            .map(|(_, dir)| dir);
        if self.cfg.heading.observations.stride() && !self.resumed_look {
            self.out.stride = self.stride_observation(eskf, t_s);
            self.new_footprint(eskf, t_s);
        }
        let h = &self.cfg.heading;
        let (foot_heading, var) = eskf.heading_prediction(forward);
        let straight = self.straight.push(foot_heading);
        let mut event = HeadingEvent {
            foot_heading_rad: foot_heading,
            direction_rad: f64::NAN,
            outcome: Err(Rejection::NoSource),
            baseline_s: 0.0,
            observed_t_s: t_s,
        };
        if h.observations.foot_axis() {
            let sd = h.sigma_rad.get();
            let assoc = if straight {
                let s2 = var + sd * sd;
                weighted_association(&self.aid, h, xy, foot_heading, s2, self.reacquiring)
            } else {
                Err(Rejection::NotStraight)
            };
            let assoc = assoc.and_then(|dw| self.stride_test(dw, stride_dir));
            match assoc {
                Ok((d, w)) => {
                    event.direction_rad = d;
                    let i = eskf.heading_update(d, sd / w.sqrt(), forward);
                    self.counters.heading_used += 1;
                    self.reacquiring = false;
                    event.outcome = Ok(i);
                }
                Err(r) => {
                    self.count_rejection(r);
                    event.outcome = Err(r);
                }
            }
        }
        self.out.heading = Some(event);
    }

    /// The foot axis associated with direction `d` (weight `w`) is evidence of the walking
    /// direction only when the stride that brought the foot there (`stride_dir`) runs along the
    /// same corridor, within `heading.foot_axis_stride_max_deg`: in a weave the foot turns back
    /// towards the corridor before the walk does. After a fault put the state back to the last
    /// healthy stance, the heading carries what the faulty samples did to it, by more than its
    /// variance says: the strides then run off the corridor with the foot, and the foot axis is
    /// the way back, so the test waits until a stride runs along its corridor again.
    fn stride_test(
        &mut self,
        (d, w): (f64, f64),
        stride_dir: Option<f64>,
    ) -> Result<(f64, f64), Rejection> {
        let Some(max) = self.cfg.heading.foot_axis_stride_max_rad else {
            return Ok((d, w));
        };
        let off = stride_dir.is_some_and(|s| wrap_pi(s - d).abs() > max.get());
        if !off {
            self.heading_suspect = false;
        }
        if off && !self.heading_suspect {
            Err(Rejection::OffStride)
        } else {
            Ok((d, w))
        }
    }

    /// Once the mounting yaw is known: the paper's filter re-expresses its prior in the foot
    /// frame and gets its observer, the rotation-aware filter its observer. Also after a health
    /// fault restored a bias filter from before the calibration (its observer is missing while
    /// the phase is tracking): without it no heading would be observed again.
    pub(super) fn calibrate_bias_filter(&mut self, nav_from_body: UnitQuaternion<f64>, t_s: f64) {
        // The observer's epoch on the stamps less the clock's steps, as its later times.
        let t_s = t_s - self.clock.offset_s();
        match &mut self.bias {
            BiasFilter::InEskf => {}
            BiasFilter::Paper { kf, obs } => {
                if obs.is_none() {
                    kf.rotate(&rot_z(self.mount_yaw_rad).to_rotation_matrix().into_inner());
                    *obs = Some(PaperObserver::new(nav_from_body, t_s));
                }
            }
            BiasFilter::RotationAware { obs, .. } => {
                if obs.is_none() {
                    *obs = Some(RotationAwareObserver::new(nav_from_body));
                }
            }
        }
    }

    /// The stride direction observation at a new footprint (before the footprint is cloned):
    /// the stride since the previous footprint or, with `heading.stride_look_ahead`, the one
    /// before it, judged straight once the footprint after it is known.
    fn stride_observation(&mut self, eskf: &mut Eskf, t_s: f64) -> Option<HeadingEvent> {
        let h = &self.cfg.heading;
        let xy = [eskf.p_m.x, eskf.p_m.y];
        let look_ahead = h.stride_look_ahead;
        // With look-ahead the line test sees every footprint, and the stride before the
        // last is straight when the line held both at its own footprint and at this one.
        let ahead = look_ahead.then(|| {
            let now = self.line.as_mut().and_then(|l| l.push(xy));
            let both = self.line_before.zip(now).map(|(a, b)| a && b);
            self.line_before = now;
            both
        });
        // The foot's turn over the observed stride (the gyro's over one stride: a bias
        // error adds a fraction of a degree); with look-ahead, also over the stride after it.
        let now = self.levelled_yaw(eskf);
        let turn = if look_ahead {
            self.footprint_yaw_rad
                .zip(self.prev_footprint_yaw_rad)
                .map(|(b, a)| wrap_pi(b - a).abs().max(wrap_pi(now - b).abs()))
        } else {
            self.footprint_yaw_rad.map(|prev| wrap_pi(now - prev))
        };
        let observed_t_s = if look_ahead { self.footprint_t_s } else { t_s };
        match eskf.stride_prediction() {
            Some((len, dir, var)) if len >= h.min_stride_m.get() => {
                let sd = h.stride_sigma_rad.get();
                let mut event = HeadingEvent {
                    foot_heading_rad: dir,
                    direction_rad: f64::NAN,
                    outcome: Err(Rejection::NoSource),
                    baseline_s: 0.0,
                    observed_t_s,
                };
                // Straight walking: the footprint line decides once it holds enough
                // footprints; until then (the first strides of tracking) a stride over
                // which the foot turned is no straight stride. Without the line test
                // (`line_footprints = 0`) every stride is associated, as before it.
                let verdict = match (self.line.as_mut(), ahead) {
                    (None, _) => None,
                    (Some(_), Some(both)) => Some(both),
                    (Some(l), None) => Some(l.push(xy)),
                };
                let straight = match verdict {
                    None => true,
                    Some(Some(on_line)) => on_line,
                    Some(None) => turn.is_none_or(|t| t.abs() <= h.straight_max_change_rad.get()),
                };
                // The map is asked at the stride's own end.
                let at = if look_ahead { eskf.footprint_xy_m } else { xy };
                let assoc = if !straight {
                    Err(Rejection::NotStraight)
                } else {
                    weighted_association(&self.aid, h, at, dir, var + sd * sd, self.reacquiring)
                };
                self.track_off_direction(eskf, at, dir, &assoc);
                match assoc {
                    Ok((d, w)) => {
                        event.direction_rad = d;
                        if let Some(i) = eskf.stride_direction_update(d, sd / w.sqrt()) {
                            self.counters.stride_used += 1;
                            self.reacquiring = false;
                            event.outcome = Ok(i);
                        }
                    }
                    Err(r) => {
                        self.counters.stride_rejected += 1;
                        event.outcome = Err(r);
                    }
                }
                Some(event)
            }
            Some(_) => {
                self.counters.stride_rejected += 1;
                None
            }
            None => None,
        }
    }

    /// A straight stride that no direction took (outside the gate, or unlikely) extends the run
    /// of strides off the nearest direction; anything else ends it. A run of
    /// `heading.reacquire_strides` at one angle: the heading is taken as lost (`reacquire.rs`).
    fn track_off_direction(
        &mut self,
        eskf: &mut Eskf,
        at: [f64; 2],
        dir: f64,
        assoc: &Result<(f64, f64), Rejection>,
    ) {
        let Some(strides) = self.cfg.heading.reacquire_strides else {
            return;
        };
        let missed = matches!(assoc, Err(Rejection::OutsideGate | Rejection::Unlikely));
        let nearest = missed
            .then(|| self.aid.associate(at, dir, std::f64::consts::PI).ok())
            .flatten();
        let Some(nearest) = nearest else {
            self.off_direction.clear();
            return;
        };
        let spread = self.cfg.heading.straight_max_change_rad.get();
        if let Some(off) = self
            .off_direction
            .push(wrap_pi(nearest - dir), spread, strides)
        {
            let sd = self.cfg.heading.stride_sigma_rad.get();
            eskf.set_heading_variance(eskf.heading_variance().max(off * off + sd * sd));
            self.reacquiring = true;
            // the foot axis waits for a stride along its corridor, as after a restore
            self.heading_suspect = true;
            self.out.heading_reacquired = Some(off);
        }
    }

    /// The current position becomes the cloned footprint (the previous one, with look-ahead,
    /// the footprint before it), with the foot's yaw and the time there.
    fn new_footprint(&mut self, eskf: &mut Eskf, t_s: f64) {
        eskf.clone_footprint();
        self.prev_footprint_yaw_rad = self.footprint_yaw_rad;
        self.footprint_yaw_rad = Some(self.levelled_yaw(eskf));
        self.footprint_t_s = t_s;
    }

    /// After a health fault put the filter back to a copy from before a footprint was cloned
    /// (an undone update at a stance observation, or a restored stance): the filter's clones
    /// and the footprints, yaws, times and line verdicts recorded here no longer match, so all
    /// of them are forgotten, and strides are observed again from the next new footprints.
    pub(super) fn forget_footprints(&mut self, eskf: &mut Eskf) {
        eskf.forget_footprints();
        self.counters.footprints_forgotten += 1;
        self.last_footprint = None;
        self.footprint_yaw_rad = None;
        self.prev_footprint_yaw_rad = None;
        self.footprint_t_s = f64::NAN;
        self.line_before = None;
        if let Some(l) = self.line.as_mut() {
            l.clear();
        }
    }

    /// Yaw of the sensor's levelled x axis (the attitude with the initial tilt taken out).
    fn levelled_yaw(&self, eskf: &Eskf) -> f64 {
        yaw(&(eskf.nav_from_body * self.tilt0.inverse()))
    }

    /// The sensor's yaw on the foot from one stride, rad: the `m` for which the foot's forward
    /// axis ([`Self::foot_forward_body`], `(R_z(m)·tilt0)⁻¹·x̂`: `(cos m, −sin m, 0)` in the
    /// levelled sensor frame) has the stride's direction `stride_dir_rad` for its heading in
    /// this stance's attitude, as the foot-axis observation measures the heading.
    pub(super) fn mount_yaw_of_stride(&self, eskf: &Eskf, stride_dir_rad: f64) -> f64 {
        yaw_of_axis_with_heading(&(eskf.nav_from_body * self.tilt0.inverse()), stride_dir_rad)
    }

    fn count_rejection(&mut self, r: Rejection) {
        match r {
            Rejection::NotStraight => self.counters.heading_not_straight += 1,
            Rejection::OutsideGate => self.counters.heading_outside_gate += 1,
            Rejection::OutsideMap => self.counters.heading_outside_map += 1,
            Rejection::Unlikely => self.counters.heading_unlikely += 1,
            Rejection::OffStride => self.counters.heading_off_stride += 1,
            Rejection::NoSource => {}
        }
    }
}

/// Whether the external heading `dir` (σ `sd`) lies further than [`EXTERNAL_HEADING_MAX_NIS`]
/// from the filter's prediction of the foot axis's heading.
fn outside_gate(eskf: &Eskf, dir: f64, sd: f64, forward: &Vector3<f64>) -> bool {
    let (predicted, var) = eskf.heading_prediction(forward);
    let r = wrap_pi(dir - predicted);
    r * r / (var + sd * sd) > EXTERNAL_HEADING_MAX_NIS
}
