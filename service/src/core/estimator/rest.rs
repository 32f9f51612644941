//! A rest's means of specific force and rate, without its last part, without its first part
//! when it begins with a landing, and without the blocks in which the foot moved.

use super::fast_start::RecentSamples;
use crate::core::stance::StanceDecision;
#[cfg(doc)]
use crate::core::stance::StanceDetector;
use nalgebra::Vector3;

/// Sums of specific force and rate over part of the rest.
#[derive(Debug, Clone, Copy, Default)]
struct Sums {
    n: u64,
    /// Blocks summed (settled part only).
    blocks: u64,
    f: Vector3<f64>,
    w: Vector3<f64>,
    /// Sum of the squared rates, per axis.
    w2: Vector3<f64>,
    /// The block moved: its mean rate left the rest's (see [`RestSums::push`]); not summed.
    moving: bool,
}

impl Sums {
    fn add(&mut self, o: &Sums) {
        self.n += o.n;
        self.blocks += 1;
        self.f += o.f;
        self.w += o.w;
        self.w2 += o.w2;
    }
}

/// A rest's mean specific force (m/s²) and mean rate (rad/s), and the standard error of the mean
/// rate (rad/s), sensor axes.
pub(super) type RestMeans = (Vector3<f64>, Vector3<f64>, Vector3<f64>);

/// A rest, in blocks, so that its last `tail_s` (the foot already starting to move while the
/// detector still says "stance") can be left out of the means, and so can any block whose mean
/// rate lies further than `max_rate_change_rad_s` (when given: the initial rest's) from the
/// mean of the rest's still blocks so far (a foot that rocks or shifts its weight before its
/// first step: exp40 rocks at 0.05–0.2 rad/s for 0.7 s after 0.6 s of quiet, all of it
/// "stance"). A later rest begins with the foot's landing (rolling to flat at up to the stance
/// detector's threshold), which the motion test, anchored on the first block, would take for
/// the reference: its first `head_s` are left out instead ([`RestSums::leaving_out_head`]).
/// Fixed capacity, kept by its copies (`Clone` by hand: a derived one gives a copy only as
/// much room as it holds, and the copy before a gap, `gap_copy.rs`, becomes the live one).
#[derive(Debug)]
pub(super) struct RestSums {
    pub(super) t_first_s: f64,
    settled: Sums,
    /// The settled part with its moving blocks too.
    settled_all: Sums,
    recent: std::collections::VecDeque<Sums>,
    current: Sums,
    current_start_s: f64,
    capacity: usize,
    max_rate_change_rad_s: Option<f64>,
    /// Settled blocks left out because the foot moved in them.
    settled_moving: u64,
    /// The first part of the rest left out of every mean, s.
    head_s: f64,
}

/// Block length of the rest accumulator, s.
pub const REST_BLOCK_S: f64 = 0.05;

impl Clone for RestSums {
    fn clone(&self) -> Self {
        let mut recent = std::collections::VecDeque::with_capacity(self.capacity + 1);
        recent.extend(self.recent.iter().copied());
        Self { recent, ..*self }
    }

    fn clone_from(&mut self, src: &Self) {
        self.copy_from(src);
    }
}

impl RestSums {
    /// Becomes a copy of `src` in its own blocks: no allocation (every `RestSums` of one
    /// configuration has room for as many). Every other field is `Copy` (see
    /// `StanceDetector::copy_from`).
    pub(super) fn copy_from(&mut self, src: &Self) {
        let mut recent = std::mem::take(&mut self.recent);
        recent.clone_from(&src.recent);
        *self = Self { recent, ..*src };
    }

    pub(super) fn new(tail_s: f64, max_rate_change_rad_s: Option<f64>) -> Self {
        let capacity = (tail_s / REST_BLOCK_S).ceil() as usize + 1;
        Self {
            t_first_s: f64::NAN,
            settled: Sums::default(),
            settled_all: Sums::default(),
            recent: std::collections::VecDeque::with_capacity(capacity + 1),
            current: Sums::default(),
            current_start_s: f64::NAN,
            capacity,
            max_rate_change_rad_s,
            settled_moving: 0,
            head_s: 0.0,
        }
    }

    /// The same, leaving the rest's first `head_s` out of every mean.
    pub(super) fn leaving_out_head(self, head_s: f64) -> Self {
        Self { head_s, ..self }
    }

    pub(super) fn clear(&mut self) {
        self.t_first_s = f64::NAN;
        self.settled = Sums::default();
        self.settled_all = Sums::default();
        self.recent.clear();
        self.current = Sums::default();
        self.settled_moving = 0;
    }

    /// Forgets the settled part (fused already) and goes on with the rest: the blocks still in
    /// its tail, the current one and the head left out stay as they are.
    pub(super) fn restart_settled(&mut self) {
        self.settled = Sums::default();
        self.settled_all = Sums::default();
        self.settled_moving = 0;
    }

    pub(super) fn is_empty(&self) -> bool {
        self.t_first_s.is_nan()
    }

    pub(super) fn push(&mut self, t_s: f64, f: &Vector3<f64>, w: &Vector3<f64>) {
        if self.is_empty() {
            self.t_first_s = t_s;
            self.current_start_s = t_s;
        }
        if t_s - self.current_start_s >= REST_BLOCK_S {
            if self.recent.len() == self.capacity
                && let Some(old) = self.recent.pop_front()
            {
                self.settled_all.add(&old);
                if old.moving {
                    self.settled_moving += 1;
                } else {
                    self.settled.add(&old);
                }
            }
            if let Some(max) = self.max_rate_change_rad_s
                && self.current.n > 0
                && let still = self.still_blocks()
                && still.n > 0
            {
                let change = self.current.w / self.current.n as f64 - still.w / still.n as f64;
                self.current.moving = change.norm() > max;
            }
            if self.current_start_s - self.t_first_s >= self.head_s {
                self.recent.push_back(self.current);
            }
            self.current = Sums::default();
            self.current_start_s = t_s;
        }
        self.current.n += 1;
        self.current.f += f;
        self.current.w += w;
        self.current.w2 += w.component_mul(w);
    }

    /// Means of specific force and rate over the settled part (the rest without its tail), when
    /// that part lasts at least `min_s`.
    /// With the standard error of the mean rate ([`RestSums::rate_sd_of_mean`]).
    pub(super) fn settled_means(&self, min_s: f64) -> Option<RestMeans> {
        let s = &self.settled;
        (s.n > 0 && s.blocks as f64 * REST_BLOCK_S >= min_s)
            .then(|| (s.f / s.n as f64, s.w / s.n as f64, self.rate_sd_of_mean()))
    }

    /// Means over the settled part, or over everything when the rest was too short for that.
    pub(super) fn means(&self) -> (Vector3<f64>, Vector3<f64>) {
        let s = self.used();
        let n = s.n.max(1) as f64;
        (s.f / n, s.w / n)
    }

    /// Means over every sample pushed, the blocks in which the foot moved included: a first
    /// stance that aligns a walk without a rest begins with its landing, which the motion test
    /// (anchored on the first block) would take for the reference.
    pub(super) fn means_all(&self) -> (Vector3<f64>, Vector3<f64>) {
        let mut s = self.settled_all;
        for b in &self.recent {
            s.add(b);
        }
        s.add(&self.current);
        let n = s.n.max(1) as f64;
        (s.f / n, s.w / n)
    }

    /// A conservative standard error of the mean rate of [`RestSums::means`], per axis: the
    /// rate's per-sample spread over the square root of the number of 50 ms blocks, not of
    /// samples (samples within a block are not independent when the foot sways; for white noise
    /// alone this overstates the error by √(samples per block)). A rest that is not one (a foot that still moves) gives
    /// a mean rate far from the bias, and says so here.
    pub(super) fn rate_sd_of_mean(&self) -> Vector3<f64> {
        let s = self.used();
        let n = s.n.max(1) as f64;
        let mean = s.w / n;
        let var = (s.w2 / n - mean.component_mul(&mean)).map(|v| v.max(0.0));
        var.map(|v| (v / s.blocks.max(1) as f64).sqrt())
    }

    /// Blocks left out of [`RestSums::means`] because the foot moved in them (not those of the
    /// tail, which is left out anyway).
    pub(super) fn moving_blocks(&self) -> u64 {
        if self.settled.n > 0 {
            self.settled_moving
        } else {
            self.recent.iter().filter(|b| b.moving).count() as u64
        }
    }

    /// How long the blocks the means use last, s ([`REST_BLOCK_S`] each; the block still
    /// being summed not counted).
    pub(super) fn still_s(&self) -> f64 {
        let s = if self.settled.n > 0 {
            self.settled
        } else {
            self.still_blocks()
        };
        s.blocks as f64 * REST_BLOCK_S
    }

    /// Every closed block in which the foot did not move, the settled ones and the recent.
    fn still_blocks(&self) -> Sums {
        let mut s = self.settled;
        for b in self.recent.iter().filter(|b| !b.moving) {
            s.add(b);
        }
        s
    }

    /// The part the means use: the settled part, or everything still when that is empty.
    fn used(&self) -> Sums {
        if self.settled.n > 0 {
            return self.settled;
        }
        let mut s = self.still_blocks();
        s.add(&self.current);
        s
    }
}

/// The initial rest, and its part since a loss that came after less than
/// `alignment.min_rest_s` of it (see `Estimator::step`): which of the two aligns is decided
/// when the rest ends.
#[derive(Debug, Clone)]
pub(super) struct InitialRest {
    pub(super) whole: RestSums,
    since_loss: RestSums,
    /// Such a loss, and the rest has not ended since: how long the rest had lasted before it,
    /// s (on the sample stamps), and its mean specific force and rate then.
    lost: Option<(f64, Vector3<f64>, Vector3<f64>)>,
    /// The last stamp pushed, s.
    last_t_s: f64,
    /// The largest change of mean rate between two parts of one rest, rad/s
    /// (`alignment.rest_max_rate_change_rad_s`).
    max_rate_change_rad_s: f64,
    /// The foot was seen moving since the log began or since the last loss, on a detector
    /// window of samples all after it ([`InitialRest::observe`]).
    moved: bool,
    /// Samples since the log began or since the last loss.
    samples_since_loss: usize,
    /// The current stance began after such a motion: the detector saw its landing, so it is
    /// a stance, not the end of one.
    stance_seen_whole: bool,
    /// The stance detector's threshold was raised by the gait (fast or varying gait) on a
    /// sample of the current stance.
    stance_raised: bool,
    /// The last samples, for a start in fast gait to go back over (`fast_start.rs`).
    pub(super) recent: RecentSamples,
}

/// Two parts of a rest split by a loss are one rest when their mean forces lie within this
/// angle (1°, in rad: exp37's parts around a loss in its last 0.95 s of rest lie 0.4° apart)
/// and their mean rates within `alignment.rest_max_rate_change_rad_s`. The rate is the test
/// that tells a walking stance after a loss: a foot flat in mid-stance has a rest's tilt (a
/// review found 95 of 744 such stances within the angle), but its rate differs by 0.12 rad/s
/// or more.
const REST_PARTS_MAX_ANGLE_RAD: f64 = 0.017_453_292_519_943_295;

impl InitialRest {
    /// `replay_samples`: how many of the last samples it keeps (0: none).
    pub(super) fn new(tail_s: f64, max_rate_change_rad_s: f64, replay_samples: usize) -> Self {
        let rest = RestSums::new(tail_s, Some(max_rate_change_rad_s));
        Self {
            since_loss: rest.clone(),
            whole: rest,
            lost: None,
            last_t_s: f64::NAN,
            max_rate_change_rad_s,
            moved: false,
            samples_since_loss: 0,
            stance_seen_whole: false,
            stance_raised: false,
            recent: RecentSamples::new(replay_samples),
        }
    }

    /// Becomes a copy of `src` in its own blocks: no allocation.
    pub(super) fn copy_from(&mut self, src: &Self) {
        self.whole.copy_from(&src.whole);
        self.since_loss.copy_from(&src.since_loss);
        self.lost = src.lost;
        self.last_t_s = src.last_t_s;
        self.max_rate_change_rad_s = src.max_rate_change_rad_s;
        self.moved = src.moved;
        self.samples_since_loss = src.samples_since_loss;
        self.stance_seen_whole = src.stance_seen_whole;
        self.stance_raised = src.stance_raised;
        self.recent.copy_from(&src.recent);
    }

    /// What the stance detector said about a sample (before [`InitialRest::push`] or
    /// [`InitialRest::end`]): whether the stance that begins here is seen whole. A stance is
    /// seen whole when the foot was seen moving before it, on a full detector window
    /// (`window` samples) of samples after the last loss. A stance that is not may be the end
    /// of one: a log that starts as the foot rolls onto its toes, or a loss that ends in a
    /// swing while the detector's window still holds the rest before it, whose "stance" is
    /// the swing's first samples.
    /// `raised`: the detector's threshold was raised by the gait ([`StanceDetector::raised`]).
    pub(super) fn observe(&mut self, decision: &StanceDecision, raised: bool, window: usize) {
        self.samples_since_loss = self.samples_since_loss.saturating_add(1);
        if decision.moving && self.samples_since_loss >= window {
            self.moved = true;
        }
        if decision.stance && self.whole.is_empty() {
            self.stance_seen_whole = self.moved;
            self.stance_raised = false;
        }
        self.stance_raised |= decision.stance && raised;
    }

    /// The shortest stance that may start the filter without a rest (`alignment.min_rest_s`)
    /// now: `min_start_stance_s`, or `fast_gait_s` for a stance seen whole in which the
    /// stance detector's threshold was raised by the gait. A short stance is mostly its
    /// landing and its push-off (the tilt of the walking stances of 0.03–0.1 s lies 3–5° off
    /// the filter's, of those of 0.1–0.2 s 1.4°); in normal gait the next stance is longer,
    /// and a short one is a split or a shuffle. In fast gait (exp34's, exp38's stances last
    /// 0.03–0.1 s) none is longer, and the filter waited for a rare longer one (exp38 cut at
    /// 30 % of its walk: 14.8 s). A "stance" not seen whole needs `min_start_stance_s` whatever
    /// the gait: the end of a stance as the log begins, or a swing's first samples after a
    /// loss, which the detector's window still takes for the rest before it (30 ms of that
    /// aligned the filter on a moving foot's tilt: health restores in 274 of 5,824 starts
    /// after a loss).
    pub(super) fn min_start_s(&self, min_start_stance_s: f64, fast_gait_s: f64) -> f64 {
        if self.fast_gait() {
            fast_gait_s.min(min_start_stance_s)
        } else {
            min_start_stance_s
        }
    }

    /// The current stance was seen whole, in fast gait: the fast-gait rule applies to it.
    pub(super) fn fast_gait(&self) -> bool {
        self.stance_seen_whole && self.stance_raised
    }

    /// A loss in the rest (the samples come back after more than a bridgeable gap):
    /// remembered when less than `min_rest_s` of rest came before it. Whatever came before
    /// it, the stance going on is no longer seen whole, and the foot not seen moving since.
    pub(super) fn lose(&mut self, min_rest_s: f64) {
        self.moved = false;
        self.samples_since_loss = 0;
        self.stance_seen_whole = false;
        self.stance_raised = false;
        let before_s = self.last_t_s - self.whole.t_first_s;
        if !self.whole.is_empty() && before_s < min_rest_s {
            let (f, w) = self.whole.means();
            self.since_loss.clear();
            self.lost = Some((before_s, f, w));
        }
    }

    /// One sample of the rest: the whole rest takes it in the alignment, the part since a loss
    /// here.
    pub(super) fn push(&mut self, t_s: f64, f: &Vector3<f64>, w: &Vector3<f64>) {
        self.last_t_s = t_s;
        if self.lost.is_some() {
            self.since_loss.push(t_s, f, w);
        }
    }

    /// The rest ends at `t_s`. After such a loss, when less than `min_rest_s` of rest came
    /// after it as well, only that part is kept (the alignment starts again from the loss;
    /// true then), unless the two parts last `min_rest_s` together and are one rest: the same
    /// mean force within [`REST_PARTS_MAX_ANGLE_RAD`] and the same mean rate within
    /// `alignment.rest_max_rate_change_rad_s`, over their still blocks (a stream that paused,
    /// or lost a few tenths of a second, in a short rest).
    pub(super) fn end(&mut self, t_s: f64, min_rest_s: f64) -> bool {
        let restart = self.lost.take().is_some_and(|(before_s, f, w)| {
            if self.since_loss.is_empty() {
                return true;
            }
            let after_s = t_s - self.since_loss.t_first_s;
            if after_s >= min_rest_s {
                return false;
            }
            // The parts' still blocks: the part after the loss is mostly the rest's tail,
            // where the foot may already be starting its first step.
            let (f_after, w_after) = self.since_loss.means();
            let one_rest = before_s + after_s >= min_rest_s
                && f.angle(&f_after) <= REST_PARTS_MAX_ANGLE_RAD
                && (w - w_after).norm() <= self.max_rate_change_rad_s;
            !one_rest
        });
        if restart {
            std::mem::swap(&mut self.whole, &mut self.since_loss);
        }
        self.since_loss.clear();
        restart
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 0.6 s of quiet at the bias `b`, then 1.2 s in which the foot rocks (as exp40's does
    /// before its first step, all of it "stance" to the detector), at 200 Hz.
    fn rocking_rest(max_rate_change_rad_s: Option<f64>) -> RestSums {
        let b = Vector3::new(0.001, -0.005, 0.008);
        let g = Vector3::new(0.0, 0.0, 9.81);
        let mut rest = RestSums::new(0.5, max_rate_change_rad_s);
        for i in 0..360 {
            let t = i as f64 * 0.005;
            // A little sway while quiet, ±0.15 rad/s of rocking about y at 1 Hz after 0.6 s (whose
            // mean over the rocking part is not zero: it stops mid-swing).
            let sway = 0.003 * (40.0 * t).sin();
            let rock = if t < 0.6 {
                0.0
            } else {
                0.15 * (std::f64::consts::TAU * (t - 0.6)).sin()
            };
            rest.push(t, &g, &(b + Vector3::new(sway, sway + rock, -sway)));
        }
        rest
    }

    /// What the detector says of one sample: stance, moving (a full window above its
    /// threshold), or neither (its first window).
    fn said(stance: bool, moving: bool, raised: bool) -> (StanceDecision, bool) {
        let decision = StanceDecision {
            statistic: 0.0,
            raw: stance,
            stance,
            moving,
            stance_age_s: 0.0,
        };
        (decision, raised)
    }

    #[test]
    fn a_short_start_stance_must_be_seen_whole_and_in_fast_gait() {
        let (min_s, fast_s, window) = (0.1, 0.03, 5);
        let g = Vector3::new(0.0, 0.0, 9.81);
        let mut rest = InitialRest::new(0.5, 0.05, 0);
        let mut t_s = 0.0;
        let mut feed = |rest: &mut InitialRest, (d, raised): (StanceDecision, bool), n: usize| {
            for _ in 0..n {
                rest.observe(&d, raised, window);
                if d.stance {
                    rest.push(t_s, &g, &Vector3::zeros());
                    rest.whole.push(t_s, &g, &Vector3::zeros());
                } else {
                    rest.end(t_s, 0.5);
                    rest.whole.clear();
                }
                t_s += 0.005;
            }
        };
        // The log begins in a stance (the end of one: its landing was not seen), in fast gait.
        feed(&mut rest, said(false, false, false), 4);
        feed(&mut rest, said(true, false, true), 10);
        assert_eq!(rest.min_start_s(min_s, fast_s), min_s);
        // The foot moves, then lands: a stance seen whole, in fast gait.
        feed(&mut rest, said(false, true, true), 40);
        feed(&mut rest, said(true, false, true), 3);
        assert_eq!(rest.min_start_s(min_s, fast_s), fast_s);
        // The same stance in normal gait (the threshold not raised): a split or a shuffle.
        feed(&mut rest, said(false, true, false), 40);
        feed(&mut rest, said(true, false, false), 3);
        assert_eq!(rest.min_start_s(min_s, fast_s), min_s);
        // A loss: the stance going on is no longer seen whole, and the foot must be seen
        // moving on a whole window of samples after the loss before the next one is.
        feed(&mut rest, said(false, true, true), 40);
        feed(&mut rest, said(true, false, true), 3);
        rest.lose(0.5);
        assert_eq!(rest.min_start_s(min_s, fast_s), min_s);
        // Motion whose detector windows still hold samples from before the loss.
        feed(&mut rest, said(false, true, true), window - 1);
        feed(&mut rest, said(true, false, true), 3);
        assert_eq!(rest.min_start_s(min_s, fast_s), min_s);
        rest.lose(0.5);
        feed(&mut rest, said(false, true, true), window);
        feed(&mut rest, said(true, false, true), 3);
        assert_eq!(rest.min_start_s(min_s, fast_s), fast_s);
    }

    #[test]
    fn blocks_in_which_the_foot_rocks_are_left_out_of_the_rest_means() {
        let b = Vector3::new(0.001, -0.005, 0.008);
        let rest = rocking_rest(Some(0.05));
        let (_, w, sem) = rest.settled_means(0.5).expect("0.6 s of quiet settles");
        assert!((w - b).norm() < 1e-3, "{w}");
        assert!(sem.norm() < 3e-3, "{sem}");
        assert!(rest.moving_blocks() >= 8, "{}", rest.moving_blocks());
        // Every block counted, the rocking ones included, the mean is the rocking's.
        let all = rocking_rest(None);
        let (_, w_all) = all.means();
        assert!((w_all - b).norm() > 5e-3, "{w_all}");
        assert_eq!(all.moving_blocks(), 0);
    }
}
