//! Footfalls the detector missed, updated late (`detector.late_stance_min_s`,
//! `detector.overdue_stride_factor`).
//!
//! In fast gait the foot never stops rotating: the statistic of some footfalls dips below the
//! threshold for less than `detector.min_stance_s`, or not at all, and the stride runs on to the
//! next footfall without a zero-velocity update. Two kinds are recognised, both only once it is
//! clear that no stance follows: between footfalls the foot swings for at least 0.65 s even in
//! fast gait, while the parts of one footfall lie within `detector.merge_gap_s` (0.3 s) of each
//! other (see `DETECTOR_MERGE_GAP_S`).
//! - *A short dip*: at least `late_stance_min_s` below the threshold, with no stance within
//!   `merge_gap_s` before it and none in the `merge_gap_s` after it. (A dip that short also
//!   comes before many ordinary stances, heel strike then foot flat, so it cannot be told from
//!   one when it happens.)
//! - *An overdue footfall*: `overdue_stride_factor` times the stride period (the median of the
//!   last three intervals between footfalls) after the last footfall, no stance has begun: the
//!   quietest sample since the last stance (plus `merge_gap_s`) whose statistic is below the
//!   adaptive threshold's cap is the footfall, if no stance begins within `merge_gap_s` after
//!   it. Not twice in a row: a stance or a short dip must come between.
//!
//! The footfall's quietest sample gets the stance velocity update then: the filter as it was at
//! that sample (propagated to, from a copy kept at the dip's or the cycle's first sample) is
//! updated and propagated again through the samples since, from the stride memory. What the estimator output in between stays as it was;
//! the state from then on is as if the update had been made on time. It adds no heading
//! observation and no footfall to the stride bookkeeping (the stride that ends there runs on to
//! the next stance, as before); it is counted (`Counters::late_footfalls`) and marked on the
//! estimate (`Estimate::late_footfall_t_s`). A gap, a health fault or a new segment in between
//! drops it.

use super::*;

/// The filter at the first sample of a candidate's search (a dip's first sample, a cycle's
/// first searched one): a late update propagates from here to the quietest sample. One copy per
/// dip or cycle, not one per quieter sample.
#[derive(Debug, Clone)]
pub(super) struct Anchor {
    pub(super) eskf: Eskf,
    bias: BiasFilter,
    /// Its time on the sample clock (as the stride memory holds it).
    pub(super) t_s: f64,
}

/// A candidate's quietest sample so far: time (sample clock), statistic, bias-corrected rate
/// (the rolling model's edge velocity).
type Quiet = (f64, f64, Vector3<f64>);

/// Which candidate a waiting footfall is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Candidate {
    /// The quietest sample of a short dip.
    Dip,
    /// The quietest sample of a stride cycle without a footfall.
    Overdue,
}

/// The late-footfall tracker: the current dip, the current cycle's quietest sample, and the
/// candidate waiting for its `merge_gap_s`.
#[derive(Debug, Clone)]
pub(super) struct LateFootfall {
    min_dip_s: Option<f64>,
    overdue_factor: Option<f64>,
    /// A cycle's quietest sample must lie below this statistic (the adaptive threshold's cap).
    quiet_max: f64,
    wait_s: f64,
    /// The last sample that was a stance (sample clock).
    last_stance_s: f64,
    /// The last four footfalls (stances' first samples and late footfalls), the newest last.
    footfalls_s: [f64; 4],
    /// The stride period: the median of the three intervals between them (NaN until known).
    period_s: f64,
    /// An overdue footfall may be looked for (a stance or a short dip since the last one).
    armed: bool,
    /// Overdue candidates only after this time (the last stance or late footfall plus the wait).
    search_from_s: f64,
    /// Start of the current dip (raw below the threshold, not yet a stance), and its last sample.
    dip: Option<(f64, f64)>,
    /// The filter at the current dip's first sample (kept without allocating after the first),
    /// and the dip's quietest sample.
    dip_anchor: LastGood<Anchor>,
    dip_quiet: Option<Quiet>,
    /// The filter at the first sample of the current cycle's search (one copy per stride: an
    /// overdue footfall is propagated to from here).
    anchor: LastGood<Anchor>,
    /// The current cycle's quietest sample below `quiet_max`.
    cycle_quiet: Option<Quiet>,
    /// A candidate waiting: the time its wait ends.
    pending: Option<(f64, Candidate)>,
}

impl LateFootfall {
    pub(super) fn new(cfg: &DetectorConfig) -> Self {
        Self {
            min_dip_s: cfg.late_stance_min_s.map(Positive::get),
            overdue_factor: cfg.overdue_stride_factor.map(Positive::get),
            quiet_max: match cfg.adaptive_factor {
                Some(_) => cfg.adaptive_max_threshold.get(),
                None => cfg.threshold.get(),
            },
            wait_s: cfg.merge_gap_s.get(),
            last_stance_s: f64::NEG_INFINITY,
            footfalls_s: [f64::NAN; 4],
            period_s: f64::NAN,
            armed: false,
            search_from_s: f64::INFINITY,
            dip: None,
            dip_anchor: LastGood::default(),
            dip_quiet: None,
            anchor: LastGood::default(),
            cycle_quiet: None,
            pending: None,
        }
    }

    /// Forgets the dip, the cycle and any footfall waiting (a gap, a fault, a new segment).
    pub(super) fn drop_pending(&mut self) {
        self.dip = None;
        self.pending = None;
        self.armed = false;
    }

    /// The two filters kept for a late update (the dip's and the cycle's, in that order): a
    /// clipped peak put back before they are used keeps them again (`rail_peaks.rs`).
    pub(super) fn anchors_mut(&mut self) -> [&mut LastGood<Anchor>; 2] {
        [&mut self.dip_anchor, &mut self.anchor]
    }

    fn footfall(&mut self, t_s: f64) {
        let f = [
            self.footfalls_s[1],
            self.footfalls_s[2],
            self.footfalls_s[3],
            t_s,
        ];
        let mut d = [f[1] - f[0], f[2] - f[1], f[3] - f[2]];
        d.sort_by(f64::total_cmp);
        (self.footfalls_s, self.period_s) = (f, d[1]);
        self.search_from_s = t_s + self.wait_s;
    }
}

/// Keeps the filter at the sample at `t_s` in `slot`.
/// Out of line: its copies of the filter stay out of the per-sample step's frame (see
/// `Pipeline::save_good`).
#[inline(never)]
pub(super) fn keep(slot: &mut LastGood<Anchor>, eskf: &Eskf, bias: &BiasFilter, t_s: f64) {
    match slot.get_mut() {
        Some(a) => {
            a.eskf.copy_state_from(eskf);
            a.bias.clone_from(bias);
            a.t_s = t_s;
        }
        None => slot.save(&Anchor {
            eskf: eskf.clone(),
            bias: bias.clone(),
            t_s,
        }),
    }
}

/// The filter and bias filter kept in `slot` put back into `eskf` and `bias`.
#[inline(never)]
pub(super) fn restore(slot: &LastGood<Anchor>, eskf: &mut Eskf, bias: &mut BiasFilter) {
    if let Some(a) = slot.get() {
        eskf.copy_state_from(&a.eskf);
        bias.clone_from(&a.bias);
    }
}

impl Pipeline {
    /// Follows the footfalls after a kept sample (`raw`: its statistic below the threshold;
    /// `stance`: a stance sample; `began`: a stance event's first); when a candidate's wait ends
    /// without a stance, updates it late. `omega` is the sample's bias-corrected rate.
    pub(super) fn follow_footfalls(
        &mut self,
        eskf: &mut Box<Eskf>,
        t_clock: f64,
        (raw, stance, began, statistic): (bool, bool, bool, f64),
        omega: &Vector3<f64>,
    ) {
        let late = &mut self.late;
        if late.min_dip_s.is_none() && late.overdue_factor.is_none() {
            return;
        }
        if stance {
            late.last_stance_s = t_clock;
            if began {
                late.footfall(t_clock);
            }
            late.search_from_s = t_clock + late.wait_s;
            late.armed = true;
            late.dip = None;
            late.pending = None;
            return;
        }
        let at = (t_clock, statistic, *omega);
        if let Some(min_dip_s) = late.min_dip_s {
            if raw {
                // Two dips within the wait are parts of one footfall: the quieter of both, from
                // the first one's anchor.
                let waiting = late.pending.is_some_and(|p| p.1 == Candidate::Dip);
                match late.dip {
                    None if !waiting => {
                        keep(&mut late.dip_anchor, eskf, &self.bias, t_clock);
                        late.dip_quiet = Some(at);
                    }
                    _ if late.dip_quiet.is_none_or(|q| statistic < q.1) => {
                        late.dip_quiet = Some(at);
                    }
                    _ => {}
                }
                let start = late.dip.map_or(t_clock, |d| d.0);
                late.dip = Some((start, t_clock));
            } else if let Some((start, end)) = late.dip.take() {
                // A dip of `n` samples spans about `n` sample periods.
                let long_enough = t_clock - start >= min_dip_s;
                if long_enough && start - late.last_stance_s > late.wait_s {
                    late.pending = Some((end + late.wait_s, Candidate::Dip));
                }
            }
        }
        if let (Some(factor), true) = (late.overdue_factor, late.armed) {
            if t_clock >= late.search_from_s {
                if late.anchor.get().is_none_or(|a| a.t_s < late.search_from_s) {
                    keep(&mut late.anchor, eskf, &self.bias, t_clock);
                }
                let quieter = late
                    .cycle_quiet
                    .is_none_or(|q| q.0 < late.search_from_s || statistic < q.1);
                if statistic < late.quiet_max && quieter {
                    late.cycle_quiet = Some(at);
                }
            }
            // NaN until four footfalls: never due.
            let due = t_clock - late.footfalls_s[3] >= factor * late.period_s;
            if due && late.pending.is_none() {
                late.armed = false;
                if let Some((t_s, ..)) = late.cycle_quiet
                    && t_s >= late.search_from_s
                {
                    late.pending = Some((t_s + late.wait_s, Candidate::Overdue));
                }
            }
        }
        if let Some((until, candidate)) = late.pending
            && t_clock >= until
        {
            late.pending = None;
            self.update_late(eskf, candidate);
        }
    }

    /// The late update: the filter at the candidate's quietest sample (propagated to from its
    /// anchor), its stance velocity update, and the samples since propagated again from the
    /// stride memory.
    fn update_late(&mut self, eskf: &mut Box<Eskf>, candidate: Candidate) {
        let (start, quiet) = match candidate {
            Candidate::Dip => (self.late.dip_anchor.get(), self.late.dip_quiet),
            Candidate::Overdue => (self.late.anchor.get(), self.late.cycle_quiet),
        };
        let (Some(start), Some((t_quiet_s, _, omega))) = (start, quiet) else {
            return;
        };
        // The memory holds every kept sample since the start, the current one last.
        let n = self.memory.len();
        let index_of = |t_s: f64| (0..n).rev().find(|&i| self.memory.get(i).t_s == t_s);
        let (Some(from), Some(quiet_at)) = (index_of(start.t_s), index_of(t_quiet_s)) else {
            self.counters.late_footfalls_dropped += 1;
            return;
        };
        // The filter as it is, to go back to: this sample's health check is made already.
        keep(&mut self.undo, eskf, &self.bias, f64::NAN);
        let mut replay = take_spare(&mut self.before, eskf);
        replay.copy_state_from(&start.eskf);
        self.bias = start.bias.clone();
        let mut spare = std::mem::replace(eskf, replay);
        self.propagate_remembered(eskf, &mut spare, from, quiet_at);
        // Too far from a standing foot for the filter: not a footfall after all. Propagated on
        // without the update, the filter is again what it was.
        let updated = self.stance_velocity_update(eskf, &omega, false).is_some();
        self.propagate_remembered(eskf, &mut spare, quiet_at, n - 1);
        self.before = Some(spare);
        // A replay that breaks the state (through samples at the rails, or times that are not
        // the foot's) is not kept: it was output as it was, with no fault, for a sample and
        // then undone back to itself (a review's case: a z bias of −1.93 rad/s).
        if !updated || !self.healthy(eskf) {
            restore(&self.undo, eskf, &mut self.bias);
            self.counters.late_footfalls_dropped += 1;
            return;
        }
        self.counters.late_footfalls += 1;
        // An estimate's times are stamps: the sample clock's plus what it took back.
        self.out.late_footfall_t_s = Some(t_quiet_s + self.clock.offset_s());
        self.late.footfall(t_quiet_s);
        // A short dip is a footfall as a stance is; an overdue one is not looked for twice in a
        // row.
        self.late.armed = candidate == Candidate::Dip;
    }

    /// Propagates the filter through the remembered samples after index `from` up to `to`, as
    /// `navigate` did when they came (no stance among them), with what a rail cut off them put
    /// back (`rail_peaks.rs`).
    pub(super) fn propagate_remembered(
        &mut self,
        eskf: &mut Box<Eskf>,
        spare: &mut Box<Eskf>,
        from: usize,
        to: usize,
    ) {
        let rail = self.gyro_rail_rad_s();
        for i in from + 1..=to {
            let (a, b) = (*self.memory.get(i - 1), *self.memory.get(i));
            let dt = b.t_s - a.t_s;
            let w_avg = (a.rate_rad_s() + b.rate_rad_s()) * 0.5;
            let f_avg = (a.accel_m_s2 + b.accel_m_s2) * 0.5;
            self.propagate(eskf, spare, dt, &w_avg, &f_avg, CovarianceStep::MayDefer);
            // As `navigate` does after each sample with an axis at its rail.
            self.widen_clipped(eskf, b.gyro_rad_s.map(|v| v.abs() >= rail).into(), dt);
        }
    }
}
