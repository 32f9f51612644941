//! A footfall the detector missed, updated late (`detector.late_stance_min_s`).
//!
//! In fast gait the foot never stops rotating: the statistic of some stances dips below the
//! threshold for less than `detector.min_stance_s`, and the stride runs on to the next footfall
//! without a zero-velocity update. A dip that short also comes before many ordinary stances
//! (heel strike, then foot flat), so it cannot be told from one when it happens; what tells it
//! is that no stance follows: between footfalls the foot swings for at least 0.65 s even in fast
//! gait, while the parts of one footfall lie within `detector.merge_gap_s` (0.3 s) of each other
//! (see `DETECTOR_MERGE_GAP_S`). So a dip of at least `late_stance_min_s`, with no stance within
//! `merge_gap_s` before it and none in the `merge_gap_s` after it, is taken as a footfall, and
//! its quietest sample gets the stance velocity update then, `merge_gap_s` late: the filter as
//! it was at that sample (kept while the dip lasted) is updated and propagated again through
//! the samples since, from the stride memory. What the estimator output in between stays as it
//! was; the state from then on is as if the update had been made on time.
//!
//! It adds no heading observation and no footfall to the stride bookkeeping (the stride that
//! ends there runs on to the next stance, as before); it is counted
//! (`Counters::late_footfalls`). A gap, a health fault or a new segment in between drops it.

use super::*;

/// The filter at the quietest sample of the current dip, and what its update needs.
#[derive(Debug, Clone)]
pub(super) struct Quietest {
    eskf: Eskf,
    bias: BiasFilter,
    /// The bias-corrected rate of that sample (the rolling model's edge velocity).
    omega: Vector3<f64>,
    /// Its time on the sample clock (as the stride memory holds it).
    t_s: f64,
    statistic: f64,
}

/// The late-footfall tracker: the current dip and the one waiting for its `merge_gap_s`.
#[derive(Debug, Clone)]
pub(super) struct LateFootfall {
    min_dip_s: Option<f64>,
    wait_s: f64,
    /// The last sample that was a stance (sample clock).
    last_stance_s: f64,
    /// Start of the current dip (raw below the threshold, not yet a stance), and its last sample.
    dip: Option<(f64, f64)>,
    /// The current dip's quietest sample (kept without allocating after the first).
    quietest: LastGood<Quietest>,
    /// A finished dip waiting for `wait_s` without a stance: the time its wait ends.
    pending_until_s: Option<f64>,
}

impl LateFootfall {
    pub(super) fn new(cfg: &DetectorConfig) -> Self {
        Self {
            min_dip_s: cfg.late_stance_min_s.map(Positive::get),
            wait_s: cfg.merge_gap_s,
            last_stance_s: f64::NEG_INFINITY,
            dip: None,
            quietest: LastGood::default(),
            pending_until_s: None,
        }
    }

    /// Forgets the dip and any footfall waiting (a gap, a fault, a new segment).
    pub(super) fn drop_pending(&mut self) {
        self.dip = None;
        self.pending_until_s = None;
    }
}

impl Pipeline {
    /// Follows the dips of the detector's statistic after a kept sample (`raw`: below the
    /// threshold; `stance`: a stance sample); when a dip's wait ends without a stance, updates
    /// it late. `omega` is the sample's bias-corrected rate.
    pub(super) fn follow_dips(
        &mut self,
        eskf: &mut Box<Eskf>,
        t_clock: f64,
        (raw, stance, statistic): (bool, bool, f64),
        omega: &Vector3<f64>,
    ) {
        let Some(min_dip_s) = self.late.min_dip_s else {
            return;
        };
        let late = &mut self.late;
        if stance {
            late.last_stance_s = t_clock;
            late.drop_pending();
            return;
        }
        if raw {
            let (start, _) = *late.dip.get_or_insert((t_clock, t_clock));
            late.dip = Some((start, t_clock));
            // Two dips within the wait are parts of one footfall: the quieter sample of both.
            let waiting = late.pending_until_s.is_some();
            let quieter = late
                .quietest
                .get()
                .is_none_or(|q| (!waiting && q.t_s < start) || statistic < q.statistic);
            if quieter {
                match late.quietest.get_mut() {
                    Some(q) => {
                        q.eskf.copy_state_from(eskf);
                        q.bias.clone_from(&self.bias);
                        (q.omega, q.t_s, q.statistic) = (*omega, t_clock, statistic);
                    }
                    None => late.quietest.save(&Quietest {
                        eskf: (**eskf).clone(),
                        bias: self.bias.clone(),
                        omega: *omega,
                        t_s: t_clock,
                        statistic,
                    }),
                }
            }
        } else if let Some((start, end)) = late.dip.take() {
            // A dip of `n` samples spans about `n` sample periods.
            let long_enough = t_clock - start >= min_dip_s;
            if long_enough && start - late.last_stance_s > late.wait_s {
                late.pending_until_s = Some(end + late.wait_s);
            }
        }
        if late.pending_until_s.is_some_and(|until| t_clock >= until) {
            late.pending_until_s = None;
            self.update_late(eskf);
        }
    }

    /// The late update: the filter at the dip's quietest sample, its stance velocity update, and
    /// the samples since propagated again from the stride memory.
    fn update_late(&mut self, eskf: &mut Box<Eskf>) {
        let Some(q) = self.late.quietest.get() else {
            return;
        };
        let n = self.memory.len();
        // The memory holds every kept sample since the quietest one, the current one last.
        let Some(from) = (0..n).rev().find(|&i| self.memory.get(i).t_s == q.t_s) else {
            self.counters.late_footfalls_dropped += 1;
            return;
        };
        let mut replay = self.before.take().unwrap_or_else(|| eskf.clone());
        replay.copy_state_from(&q.eskf);
        let (omega, bias_then, t_quiet_s) = (q.omega, q.bias.clone(), q.t_s);
        if self
            .stance_velocity_update(&mut replay, &omega, false)
            .is_none()
        {
            // Too far from a standing foot for the filter: not a footfall after all.
            self.before = Some(replay);
            self.counters.late_footfalls_dropped += 1;
            return;
        }
        self.bias = bias_then;
        std::mem::swap(eskf, &mut replay);
        let mut spare = replay;
        let rail = CLIP_FRACTION * self.cfg.sensor.gyro_range_rad_s();
        for i in from + 1..n {
            let (a, b) = (*self.memory.get(i - 1), *self.memory.get(i));
            let dt = b.t_s - a.t_s;
            let w_avg = (a.gyro_rad_s + b.gyro_rad_s) * 0.5;
            let f_avg = (a.accel_m_s2 + b.accel_m_s2) * 0.5;
            self.propagate(eskf, &mut spare, dt, &w_avg, &f_avg);
            // As `navigate` does after each sample with an axis at its rail.
            self.widen_clipped(eskf, b.gyro_rad_s.map(|v| v.abs() >= rail).into(), dt);
        }
        self.before = Some(spare);
        self.counters.late_footfalls += 1;
        self.out.late_footfall_t_s = Some(t_quiet_s);
    }
}
