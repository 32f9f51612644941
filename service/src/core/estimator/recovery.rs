//! When the state or the input goes bad: the health check after each update (undo it, or go
//! back to the last healthy stance with the turn since added back), the velocity reset of a
//! stance update that finds a velocity far beyond what the filter allows, the restart when the
//! stream's first time stamp turns out to be an outlier, and the undoing of a sample whose time
//! after a gap turns out to be a glitch.

use super::*;

/// Failed health checks in a row that undo the update; beyond, the stance copy is restored.
const MAX_UNDONE_UPDATES: u32 = 3;

/// A stance update whose innovation on some velocity axis exceeds this many times its variance
/// (20σ) finds a velocity the filter cannot hold: the velocity is reset. The largest NIS of a
/// stance update over the 16 gdins walks is 55 (the fast exp38; 1.7–10 on the others).
pub(super) const VELOCITY_RESET_Z2: f64 = 400.0;

/// Restores of the last healthy stance this close together (s) say that state itself goes bad
/// again: from the [`RESTORE_LOOP_COUNT`]-th in a row the bias starts again from zero with its
/// initial σ and the tilt is levelled again at the next stance. Without it a state whose tilt or
/// bias prior was wrong (a long loss, samples at the rails, a walking stance taken for a rest)
/// was restored again and again for the rest of the walk (7 of 40,000 torture cases: up to
/// 1,409 restores in 6,594 samples).
const RESTORE_LOOP_S: f64 = 5.0;

/// See [`RESTORE_LOOP_S`].
const RESTORE_LOOP_COUNT: u32 = 3;

/// σ of the turn added back to a state restored from the last healthy stance, as a fraction of
/// that turn: the gyro over less than a stride measures it to a scale error or a clipped peak
/// (a few %), rounded up.
const RESTORED_TURN_SD: f64 = 0.1;

impl BiasFilter {
    /// The filter of `saved` (a copy from the last healthy stance) with this one's observer,
    /// which integrates the raw gyro from its epoch and so already holds the rotation since.
    pub(super) fn restore_keeping_observer(&mut self, saved: &BiasFilter) {
        match (self, saved) {
            (BiasFilter::Paper { kf, obs }, BiasFilter::Paper { kf: k, obs: o }) => {
                kf.clone_from(k);
                if obs.is_none() {
                    obs.clone_from(o);
                }
            }
            (
                BiasFilter::RotationAware { kf, obs },
                BiasFilter::RotationAware { kf: k, obs: o },
            ) => {
                kf.clone_from(k);
                if obs.is_none() {
                    obs.clone_from(o);
                }
            }
            (this, saved) => this.clone_from(saved),
        }
    }
}

impl Estimator {
    /// The stream's first sample carried a time that the next two samples contradict (see
    /// [`corridor_shared::sensor::TimeVerdict::Rebase`]): it is dropped after the fact, counted
    /// as a refused time jump, and the estimator starts again from the current sample. Only the
    /// first sample can be such an outlier (every later time was judged against one that a
    /// sample had followed), so nothing but that sample is lost. Kept: the counters, the time
    /// rule's state (which accepted the current time), a warm start and an external heading not
    /// yet used. Allocates (a new estimator), once at most per stream.
    /// Out of line: its copies of the filter stay out of the per-sample step's frame (see
    /// `Pipeline::save_good`).
    #[inline(never)]
    pub(super) fn restart_after_time_outlier(&mut self) {
        let mut fresh = Estimator::new(self.p.cfg.clone(), (*self.p.aid).clone());
        fresh.p.plausibility = self.p.plausibility.clone();
        fresh.p.counters = self.p.counters;
        fresh.p.counters.samples = fresh.p.counters.samples.saturating_sub(1);
        // Only that sample was counted so far: a rail it was at goes with it.
        fresh.p.counters.clipped_samples = 0;
        fresh.p.counters.rejected_time_jump += 1;
        fresh.p.warm_start = self.p.warm_start.take();
        fresh.p.pending_heading = self.p.pending_heading.take();
        *self = fresh;
    }

    /// The previous sample's time had jumped forward by a gap, and the current sample goes back
    /// and follows the time before it ([`corridor_shared::sensor::TimeVerdict::Glitch`]): that
    /// sample is dropped after the fact, counted as a refused time jump, and the estimator goes
    /// back to the copy taken before it. The same for every sample since a confirmed jump whose
    /// run the current sample shows to be glitched stamps
    /// ([`corridor_shared::sensor::TimeVerdict::GlitchRun`]; the jumped sample itself was
    /// refused and counted then). Kept from now: the time rule (which accepted the current
    /// time), the refusals counted since, an external heading handed in since (one handed in
    /// before and used by a dropped sample is pending again), and a warm start handed in since
    /// (applied again to the restored filter when it was running), and whether the stances'
    /// specific force was said off gravity. Returns the number of samples dropped.
    /// Out of line: its copies of the filter stay out of the per-sample step's frame (see
    /// `Pipeline::save_good`).
    #[inline(never)]
    pub(super) fn drop_glitched_samples(&mut self) -> u64 {
        // `now`: the pipeline that took the dropped samples; `self.p` the copy from before them.
        let Some(now) = self.before_gap.swap_in(&mut self.stage, &mut self.p) else {
            return 0; // not reached: every provisional sample leaves its copy
        };
        let p = &mut self.p;
        let dropped = now.counters.samples - p.counters.samples;
        std::mem::swap(&mut p.plausibility, &mut now.plausibility);
        let c = &mut p.counters;
        c.rejected_non_finite = now.counters.rejected_non_finite;
        c.rejected_time = now.counters.rejected_time;
        c.rejected_implausible = now.counters.rejected_implausible;
        c.rejected_time_jump = now.counters.rejected_time_jump + dropped;
        c.headings_refused = now.counters.headings_refused;
        // (`headings_expired` stays the copy's: a heading a dropped sample's stance found too
        // old is pending again, as one it used is. The stream's end, which also expires one,
        // is never followed by a drop: the daemon starts a new estimator there.)
        // A specific force said off gravity on a dropped sample was said (its estimate went
        // out): the stance that ended there ends again on a later sample and is not said
        // twice (a review: two warnings in the daemon's report, one counted).
        c.specific_force_off_gravity = now.counters.specific_force_off_gravity;
        p.stance_force.keep_said(&now.stance_force);
        // (`headings_undone` stays the copy's: an undo in a dropped sample is dropped with it,
        // as its uses and gate refusals are; a review found it counted with the heading
        // pending again.)
        // The newest heading handed in since the copy is pending (a dropped sample may have
        // used it: a review found it lost), or else the copy's (used by a dropped sample, it
        // is pending again). Every heading pending at the copy or handed in since is now
        // pending, superseded or refused at arrival: the others were replaced by a newer one
        // and are counted as superseded (they went uncounted: a review).
        let in_play =
            u64::from(p.pending_heading.is_some()) + now.headings_queued - p.headings_queued;
        let superseded_since = now.counters.headings_superseded - c.headings_superseded;
        // Its time on the copy's clock: a dropped sample taken as a clock step moved the
        // offset it was converted with (a review).
        let last_queued = now.last_queued.map(|h| h.on_clock(p.clock.offset_s()));
        if now.headings_queued > p.headings_queued {
            p.pending_heading = last_queued;
        }
        p.headings_queued = now.headings_queued;
        p.last_queued = last_queued;
        let pending = u64::from(p.pending_heading.is_some());
        let c = &mut p.counters;
        c.headings_superseded =
            now.counters.headings_superseded + in_play.saturating_sub(superseded_since + pending);
        let warm_start_since = now.warm_start.filter(|_| self.warm_start_since_copy);
        p.warm_start = now.warm_start.or(p.warm_start);
        if let (Some(ws), Stage::Running(eskf)) = (warm_start_since, &mut self.stage) {
            self.p.apply_warm_start(eskf, &ws);
        }
        dropped
    }
}

impl Pipeline {
    /// The bounds of a healthy state.
    fn health_limits(&self) -> HealthLimits {
        HealthLimits {
            max_speed_m_s: self.cfg.max_speed_m_s.get(),
            max_gyro_bias_rad_s: self.cfg.sensor.max_gyro_bias_rad_s(),
        }
    }

    /// Whether `eskf` (with the bias filter) passes the health check (see `guard_health`).
    pub(super) fn healthy(&self, eskf: &Eskf) -> bool {
        health::check(eskf, &self.bias_only(eskf), &self.health_limits()).is_ok()
    }

    /// Keeps the filter and the bias filter as the last healthy state.
    ///
    /// Out of line, as every copy of the filter on this path: a copy built in the per-sample
    /// step's own frame made that frame 70 KB (each an `Eskf` of 7 KB on the stack), whose
    /// pages the step touched at every sample (`Estimator::step` 3.5 % of the instructions but
    /// 12 % of the time).
    #[cold]
    #[inline(never)]
    pub(super) fn save_good(&mut self, eskf: &Eskf) {
        self.good.save(&(eskf.clone(), self.bias.clone()));
    }

    /// The health check after an update; `true` when it failed. The first
    /// [`MAX_UNDONE_UPDATES`] failures in a row undo the update (the state before it was
    /// healthy, and unlike the stance copy it holds the foot's rotation since the stance);
    /// further ones restore the state of the last healthy stance. Keeps a copy of the state at
    /// the first sample of each healthy stance.
    pub(super) fn guard_health(
        &mut self,
        eskf: &mut Eskf,
        before: &Eskf,
        stance: bool,
        t_s: f64,
    ) -> bool {
        let bias = self.bias_only(eskf);
        let failed = match health::check(eskf, &bias, &self.health_limits()) {
            Ok(()) => {
                self.consecutive_faults = 0;
                if stance && !self.good_saved_this_stance {
                    self.save_good(eskf);
                    self.good_saved_this_stance = true;
                }
                false
            }
            Err(fault) => {
                self.consecutive_faults += 1;
                let cloned = eskf.footprints_cloned;
                if self.consecutive_faults <= MAX_UNDONE_UPDATES {
                    eskf.copy_state_from(before);
                    if let Some(b) = self.before_bias.get() {
                        self.bias.clone_from(b);
                    }
                } else if let Some((e, b)) = self.good.get() {
                    // The turn since that stance, as the gyro integrated it (the state before
                    // this sample): the stance's attitude alone left the heading where it was
                    // there, and after a turn outside the gate for the rest of the walk.
                    let fwd = self.forward_body;
                    let turn = wrap_pi(
                        heading_of_axis(&before.nav_from_body, &fwd)
                            - heading_of_axis(&e.nav_from_body, &fwd),
                    );
                    eskf.copy_state_from(e);
                    if turn.is_finite() {
                        eskf.turn_heading(turn, RESTORED_TURN_SD * turn.abs());
                    }
                    // The observer as it was before this sample (the next step integrates the
                    // sample's interval again), with the stance's filter.
                    if let Some(bb) = self.before_bias.get() {
                        self.bias.clone_from(bb);
                    }
                    self.bias.restore_keeping_observer(b);
                    self.heading_suspect = true;
                    // On the sample clock (monotonic across a step back of the stamps).
                    let t_clock = self.last.map_or(t_s, |l| l.0);
                    let (last_s, count) = self.restores_in_a_row;
                    let count = if t_clock - last_s < RESTORE_LOOP_S {
                        count + 1
                    } else {
                        1
                    };
                    self.restores_in_a_row = (t_clock, count);
                    if count >= RESTORE_LOOP_COUNT {
                        let (bias, sd) = self.bias_before_rest();
                        let p = Matrix3::from_diagonal_element(sd * sd);
                        self.set_bias(eskf, bias, &p);
                        self.relevel_next_stance = true;
                        self.restores_in_a_row = (f64::NEG_INFINITY, 0);
                    }
                }
                if eskf.footprints_cloned != cloned {
                    self.forget_footprints(eskf);
                }
                // Either copy may hold the bias filter from before the mounting-yaw
                // calibration (without its observer) while the phase stays tracking.
                if self.phase == Phase::Tracking {
                    self.calibrate_bias_filter(eskf.nav_from_body, t_s);
                }
                self.counters.health_restores += 1;
                self.out.health_fault = Some(fault);
                true
            }
        };
        if !stance {
            self.good_saved_this_stance = false;
        }
        failed
    }
}

/// The spare filter buffer (`Pipeline::before`), a copy of `eskf` the first time.
#[inline]
pub(super) fn take_spare(before: &mut Option<Box<Eskf>>, eskf: &Eskf) -> Box<Eskf> {
    match before.take() {
        Some(b) => b,
        None => boxed_copy(eskf),
    }
}

/// A boxed copy of the filter, built out of line (see [`Pipeline::save_good`]).
#[cold]
#[inline(never)]
fn boxed_copy(eskf: &Eskf) -> Box<Eskf> {
    Box::new(eskf.clone())
}
