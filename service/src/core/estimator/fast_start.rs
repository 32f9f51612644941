//! A start in fast gait, taken back to the first stance it could have started on.
//!
//! Without a rest, a stance as short as fast gait's (`alignment.fast_gait_start_stance_s`) may
//! start the filter only once the stance detector has raised its threshold over a whole
//! look-back (`InitialRest::min_start_s`): in normal gait a stance that short is a split or a
//! shuffle. So the gait is known to be fast a look-back (`detector.adaptive_window_s`, 1.5 s)
//! after the walk is first seen, and a start then had lost what the foot did since: exp34 and
//! exp38 cut mid-walk started 1.7–2.1 s after the cut, 0.85–23.9 % of path off. While it aligns
//! the estimator keeps its last samples as the step saw them ([`RecentSamples`]); a start in
//! fast gait goes back over the last `alignment.fast_gait_replay_s` of them to the first stance
//! the fast-gait rule takes now that the gait is known, aligns there, and runs the filter over
//! the samples since ([`Pipeline::start_earlier`]), as if it had started there. What those
//! samples observed is counted; their estimates are not given again (each was given as
//! "aligning" when it came): the first estimate after the start holds what the foot did since
//! that stance.

use super::*;

/// Samples kept while aligning: 1024 (5.1 s at 200 Hz, 2.6 s at 400 Hz). A replay reaches back
/// at most this far, whatever `alignment.fast_gait_replay_s` says.
pub(super) const REPLAY_SAMPLES: usize = 1024;

/// One sample as the step saw it while aligning: what [`Pipeline::step_running`] takes.
#[derive(Debug, Clone, Copy)]
pub(super) struct Recorded {
    /// Sample-clock time, s.
    t_clock: f64,
    /// The sample's stamp, s.
    t_s: f64,
    w: Vector3<f64>,
    f: Vector3<f64>,
    decision: StanceDecision,
    edge: StanceEdge,
    /// The stance events after this sample's edge (the running step counts a stance when
    /// their count moves).
    stance_events: StanceEvents,
    clipped: bool,
    clipped_gyro_axes: [bool; 3],
    /// `Counters::alignment_restarts` before this sample.
    alignment_restarts: u64,
    /// `Counters::alignment_not_gravity` before this sample.
    alignment_not_gravity: u64,
}

impl Recorded {
    /// Time, rate and specific force, as the step keeps the last sample (`Pipeline::last`).
    fn sample(&self) -> (f64, Vector3<f64>, Vector3<f64>) {
        (self.t_clock, self.w, self.f)
    }
}

/// How the filter started on the current sample.
pub(super) enum Start {
    /// On the current sample's stance: the step runs the sample.
    Here(Box<Eskf>),
    /// On an earlier stance, and it has run over every sample since, the current one included.
    Earlier(Box<Eskf>),
}

/// The samples since the last step longer than `estimator.max_dt_s`, the newest
/// [`REPLAY_SAMPLES`] of them; none when the replay is off. Fixed capacity, kept by its copies
/// (`Clone` by hand, as `RestSums`: the estimator's copy before a gap, `gap_copy.rs`, may
/// become the live one).
#[derive(Debug, Default)]
pub(super) struct RecentSamples {
    ring: std::collections::VecDeque<Recorded>,
    capacity: usize,
}

impl Clone for RecentSamples {
    fn clone(&self) -> Self {
        let mut copy = Self::new(self.capacity);
        copy.ring.extend(self.ring.iter().copied());
        copy
    }

    fn clone_from(&mut self, src: &Self) {
        self.copy_from(src);
    }
}

impl RecentSamples {
    pub(super) fn new(capacity: usize) -> Self {
        Self {
            ring: std::collections::VecDeque::with_capacity(capacity),
            capacity,
        }
    }

    /// Becomes a copy of `src` in its own ring: no allocation (every ring of one
    /// configuration is as long).
    pub(super) fn copy_from(&mut self, src: &Self) {
        self.ring.clone_from(&src.ring);
        self.capacity = src.capacity;
    }

    /// Keeps one sample (the oldest is forgotten when full); after a step longer than
    /// `max_dt_s`, the samples before it are forgotten first: a replay never crosses a gap.
    fn push(&mut self, r: Recorded, max_dt_s: f64) {
        if self.capacity == 0 {
            return;
        }
        if self
            .ring
            .back()
            .is_some_and(|b| r.t_clock - b.t_clock > max_dt_s)
        {
            self.ring.clear();
        }
        if self.ring.len() == self.capacity {
            self.ring.pop_front();
        }
        self.ring.push_back(r);
    }
}

impl Pipeline {
    /// Keeps the sample the step is aligning on (`align_sample`), with what the step made of
    /// it.
    pub(super) fn record(
        &self,
        recent: &mut RecentSamples,
        (t_clock, t_s): (f64, f64),
        (w, f): (&Vector3<f64>, &Vector3<f64>),
        decision: &StanceDecision,
    ) {
        let r = Recorded {
            t_clock,
            t_s,
            w: *w,
            f: *f,
            decision: *decision,
            edge: self.stance_edge,
            stance_events: self.stance_events,
            clipped: self.out.clipped,
            clipped_gyro_axes: self.clipped_gyro_axes,
            alignment_restarts: self.counters.alignment_restarts,
            alignment_not_gravity: self.counters.alignment_not_gravity,
        };
        recent.push(r, self.cfg.max_dt_s.get());
    }

    /// The filter `live` has just aligned on the current sample (the newest in `recent`), on
    /// a stance taken by the fast-gait rule. Goes back over the last
    /// `alignment.fast_gait_replay_s` of `recent` (the current sample left out of the search)
    /// with the gait known to be fast: the first stance the alignment takes there starts a filter,
    /// which then runs over every sample from it to the current one, as it would have had it
    /// started there (the same estimates from here on, bit for bit: test
    /// `a_replayed_start_is_a_live_start_on_the_same_stance`). What the live alignment counted
    /// is not counted again; the output is the current sample's. A heading handed in while
    /// aligning is observed from the current sample on, as without the replay. `Here(live)`
    /// when no earlier stance is taken.
    #[inline(never)]
    pub(super) fn start_earlier(&mut self, recent: &RecentSamples, live: Box<Eskf>) -> Start {
        // Nothing kept when the replay is off (`alignment.fast_gait_replay_s` 0: a ring of none).
        let Some(now) = recent.ring.back() else {
            return Start::Here(live);
        };
        let a = &self.cfg.alignment;
        let from = recent
            .ring
            .partition_point(|r| r.t_clock < now.t_clock - a.fast_gait_replay_s.get());
        let mut rest = InitialRest::new(a.rest_tail_s.get(), a.rest_max_rate_change_rad_s.get(), 0);
        let (out, restarts) = (self.out, self.counters.alignment_restarts);
        let not_gravity = self.counters.alignment_not_gravity;
        // The restarts and the rests refused as no gravity are counted as the live start on
        // that stance would have counted them: those before the window, and the replay's own
        // (a stance refused after the one the replay starts on is run through, not refused).
        self.counters.alignment_restarts = recent.ring[from].alignment_restarts;
        self.counters.alignment_not_gravity = recent.ring[from].alignment_not_gravity;
        let current = recent.ring.len() - 1;
        let start = (from..current).find_map(|k| {
            let r = &recent.ring[k];
            let xs = (&r.w, &r.f);
            self.align_on(&mut rest, r.t_s, xs, &r.decision, true)
                .map(|e| (k, e))
        });
        let Some((first, mut eskf)) = start else {
            (self.out, self.counters.alignment_restarts) = (out, restarts);
            self.counters.alignment_not_gravity = not_gravity;
            return Start::Here(live);
        };
        let pending_heading = self.pending_heading.take();
        // Each sample as the step gave it to the running step. The stride memory keeps the
        // footfalls the step gave it while aligning: they are read only across a gap, and the
        // ring holds none.
        self.last = first.checked_sub(1).map(|k| recent.ring[k].sample());
        for k in first..=current {
            let r = &recent.ring[k];
            // After a failed health check the step integrates from the sample before
            // (`step_running` takes `last` back), as here.
            let prev = self.last;
            self.last = Some(r.sample());
            self.stance_edge = r.edge;
            self.stance_events = r.stance_events;
            self.clipped_gyro_axes = r.clipped_gyro_axes;
            if k == current {
                self.out = out;
                self.pending_heading = pending_heading;
            } else {
                self.out.begin_sample(r.t_s, &r.decision, r.edge, r.clipped);
            }
            self.step_running(&mut eskf, r.t_s, prev, (&r.w, &r.f), &r.decision);
        }
        self.counters.start_replayed_ms = ((now.t_clock - recent.ring[first].t_clock) * 1e3) as u64;
        Start::Earlier(eskf)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t_clock: f64) -> Recorded {
        Recorded {
            t_clock,
            t_s: t_clock,
            w: Vector3::zeros(),
            f: Vector3::zeros(),
            decision: StanceDecision {
                statistic: 0.0,
                raw: false,
                stance: false,
                moving: true,
                stance_age_s: 0.0,
            },
            edge: StanceEdge::None,
            stance_events: StanceEvents::new(0.3, 0.05),
            clipped: false,
            clipped_gyro_axes: [false; 3],
            alignment_restarts: 0,
            alignment_not_gravity: 0,
        }
    }

    fn times(r: &RecentSamples) -> Vec<f64> {
        r.ring.iter().map(|s| s.t_clock).collect()
    }

    #[test]
    fn the_ring_keeps_the_newest_samples_since_the_last_gap() {
        let mut r = RecentSamples::new(3);
        for k in 0..5 {
            r.push(sample(k as f64 * 0.01), 0.05);
        }
        assert_eq!(times(&r), [0.02, 0.03, 0.04]);
        // A copy has the ring's room, and goes on as the ring does.
        let mut copy = RecentSamples::new(3);
        copy.clone_from(&r);
        assert_eq!(copy.ring.capacity(), r.ring.capacity());
        // A step longer than `max_dt_s`: nothing before it is kept.
        r.push(sample(0.2), 0.05);
        assert_eq!(times(&r), [0.2]);
        copy.push(sample(0.05), 0.05);
        assert_eq!(times(&copy), [0.03, 0.04, 0.05]);
        // Off: nothing kept.
        let mut off = RecentSamples::new(0);
        off.push(sample(0.0), 0.05);
        assert!(off.ring.is_empty());
    }
}
