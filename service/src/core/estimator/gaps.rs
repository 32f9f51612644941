//! Gaps in the data: a step longer than `estimator.max_dt_s` is bridged by one step when it is
//! short (a few lost samples), filled with the same phase of the stride before when it is
//! longer but within half a stride (`estimator.max_fill_s`) and the rates around it match that
//! stride's, else it starts a new segment. A step up to that fill range across which the rates
//! run on as if no time had passed, where the stride before says time passing would have changed
//! them, is the clock stepping forward with nothing lost: one sample step is integrated. A
//! clock that steps back and runs on from there (`TimeVerdict::StepBack`) is taken as a new
//! time base when the rates run on across the step as if it had not happened.

use super::late_footfall::{keep, restore};
use super::stride_memory::{Remembered, StrideMemory};
use super::*;
use crate::core::plausibility::StepBack;

/// Largest RMS difference between the rates around a gap and those one stride earlier for the
/// stride before to stand in for the lost samples, rad/s. Measured without footprints
/// (`docs/experiments/stride-template.py`: 0.2 and 0.4 s taken out of the 16 gdins walks at 40
/// places each, the rotation over the gap against the remembered stride's): in each 0.5 rad/s
/// band of the mismatch up to 2.5 rad/s the stride before turns the foot closer to the real
/// rotation than no rotation at all (what a new segment integrates) on 76–95 % of the cuts, from
/// 2.5 to 3.5 on 53–73 %, beyond on 52–62 %.
const FILL_MAX_MISMATCH_RAD_S: f64 = 2.5;

/// The rotation and the velocity change of a filled gap are taken as known to this fraction:
/// the attitude and velocity variances grow by its square times theirs. The same measurement:
/// the remembered stride's rotation is off by a median 0.20 of the real one.
const FILL_RELATIVE_SD: f64 = 0.2;

/// The first rate after a clock step lies on the straight continuation of the last two before
/// it within this many times the larger of the last step's change of the rate and the RMS
/// second difference over the last [`CONTINUATION_SAMPLES`] ...
const CONTINUATION_TOLERANCE: f64 = 1.5;
/// ... or within this, rad/s (the rate's own noise on a still foot).
const CONTINUATION_FLOOR_RAD_S: f64 = 0.05;
/// Samples before a gap whose second differences widen the continuation's tolerance.
const CONTINUATION_SAMPLES: usize = 30;
/// And the rate after the step must lie so close to that continuation that a real loss would
/// have put it there with at most this probability: the rate at a loss's far side taken as the
/// stride before's rate there, with its RMS mismatch on the samples before the gap as an
/// isotropic spread. Where the stride before expects there what the continuation does (a foot
/// still on both sides), continuity says nothing and the stamps are believed.
const STEP_LOSS_PROBABILITY: f64 = 1e-3;

/// The two samples after a step back of the clock run on within this many times the
/// continuation's tolerance. Measured without footprints (`docs/experiments/step-back.py`, every
/// 7th sample of the 16 gdins walks): a step back with nothing lost passes at 1×, 1.5×, 2×, 3× on
/// 97.6, 99.3, 99.8, 99.9 % of the places; samples re-sent from 0.02 / 0.05 / 0.1 / 0.3 s
/// earlier that are not exact copies (exact ones are caught as such) pass on 37 / 14 / 5 / 3 % at
/// 2×, 89 / 28 / 13 / 6 % at 3×. A step back refused costs what a loss of its length costs, so
/// the knee.
const STEP_BACK_TOLERANCE: f64 = 2.0;

/// On jittery (host arrival) stamps, a step of up to this many periods is a regular one for a
/// step back: stamps handed over in groups of up to four are normally within it, a swap of
/// packets of five samples or more leaves a hole beyond it.
const JITTERY_REGULAR_PERIODS: f64 = 5.0;

/// What [`Pipeline::cross_gap`] did with the step before the current sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Gap {
    /// A regular step, or a gap bridged: integrate it as usual.
    Integrate,
    /// A new segment: nothing is integrated over the step.
    NewSegment,
    /// Filled with the stride before up to this (sample-clock time, rate, force), from which
    /// the step to the current sample is integrated as usual.
    Filled((f64, Vector3<f64>, Vector3<f64>)),
}

/// The straight continuation of the newest two remembered rates, and how far from it a rate
/// one sample step later may lie ([`CONTINUATION_TOLERANCE`]).
struct Continuation {
    newest: Vector3<f64>,
    change: Vector3<f64>,
    tolerance: f64,
    /// The newest sample step, s.
    step_s: f64,
}

impl Continuation {
    /// From the memory, which must end at the filter's last sample (`t_prev_s`), after a regular
    /// step (at most `regular_dt_s`, `estimator.max_dt_s`), with [`CONTINUATION_SAMPLES`] before
    /// it.
    fn of(memory: &StrideMemory, t_prev_s: f64, regular_dt_s: f64) -> Option<Self> {
        let n = memory.len();
        if n < CONTINUATION_SAMPLES + 2 {
            return None;
        }
        let newest = *memory.get(n - 1);
        let before = *memory.get(n - 2);
        let step_s = newest.t_s - before.t_s;
        if newest.t_s != t_prev_s || !(step_s > 0.0 && step_s <= regular_dt_s) {
            return None;
        }
        let change = newest.gyro_rad_s - before.gyro_rad_s;
        let second_differences: f64 = (n - CONTINUATION_SAMPLES..n)
            .map(|i| {
                let (a, b, c) = (memory.get(i - 2), memory.get(i - 1), memory.get(i));
                (c.gyro_rad_s - b.gyro_rad_s * 2.0 + a.gyro_rad_s).norm_squared()
            })
            .sum();
        let spread = change
            .norm()
            .max((second_differences / CONTINUATION_SAMPLES as f64).sqrt());
        Some(Self {
            newest: newest.gyro_rad_s,
            change,
            tolerance: (CONTINUATION_TOLERANCE * spread).max(CONTINUATION_FLOOR_RAD_S),
            step_s,
        })
    }
}

/// Whether the clock stepped back with nothing lost: `back.first` (refused, its time behind the
/// last accepted one) and `now` (which follows it) run on from the filter's last sample (sample
/// clock `t_prev_s`, the memory's newest) as the next two samples would, each within the
/// continuation's tolerance of the straight line through the two before it, and they are not
/// samples the memory already holds (a driver re-sending what it sent: the same values, two in a
/// row). Nothing is asked of the stride before, as for a forward step: how long a loss would
/// have been is not known here, and a foot still on both sides of a step back passes (a device
/// that reset while the foot stood still, losing samples, is taken for a clock set back).
///
/// And the stamps must look like a clock set back (reviews found these taken for steps, costing
/// up to 3.7 % of path): `now` one regular sample step after `back.first` (at most 1.5 periods
/// on a device clock, [`JITTERY_REGULAR_PERIODS`] on jittery stamps), else two bad stamps in a
/// row would become a gap; `back.first` among dense accepted times (the step around it as
/// regular), not in the hole that packets delivered out of order leave; and the step longer
/// than `regular_dt_s` (`estimator.max_dt_s`, as a forward clock step), where a hole of a few
/// periods is within a host clock's scatter. Such deliveries are refused as before: their rows
/// are dropped.
#[cold]
#[inline(never)]
pub(super) fn clock_stepped_back(
    memory: &StrideMemory,
    (t_prev_s, clock): (Option<f64>, &SampleClock),
    back: &StepBack,
    now: (f64, &Vector3<f64>, &Vector3<f64>),
    (accel_correction, regular_dt_s): (f64, f64),
) -> bool {
    let (now_t_s, gyro_now, accel_now) = now;
    let period_s = clock.period_s();
    let regular = period_s
        * if clock.jittery() {
            JITTERY_REGULAR_PERIODS
        } else {
            1.5
        };
    let next_s = now_t_s - back.first.t_s;
    let step_s = StepBack::shift_s(back.last_t_s, back.first.t_s, period_s);
    let in_a_hole = back.around_first_s.is_some_and(|around| around > regular);
    if !(next_s <= regular && step_s > regular_dt_s) || in_a_hole {
        return false;
    }
    let Some(run) = t_prev_s.and_then(|t| Continuation::of(memory, t, regular_dt_s)) else {
        return false;
    };
    let gyro_first = Vector3::from(back.first.gyro_rad_s);
    let accel_first = Vector3::from(back.first.accel_m_s2) * accel_correction;
    let tolerance = STEP_BACK_TOLERANCE * run.tolerance;
    let first_runs_on = (gyro_first - (run.newest + run.change)).norm() <= tolerance;
    let now_runs_on = (gyro_now - (gyro_first * 2.0 - run.newest)).norm() <= tolerance;
    let seen = |i: usize, g: &Vector3<f64>, a: &Vector3<f64>| {
        let m = memory.get(i);
        m.gyro_rad_s == *g && m.accel_m_s2 == *a
    };
    let replayed = (1..memory.len())
        .any(|i| seen(i - 1, &gyro_first, &accel_first) && seen(i, gyro_now, accel_now));
    first_runs_on && now_runs_on && !replayed
}

impl Pipeline {
    /// Remembers the sample just navigated for [`Self::fill_gap`] (the footfalls are
    /// remembered in `step`, whatever the filter makes of their sample).
    pub(super) fn remember(&mut self, t_clock: f64, w: &Vector3<f64>, f: &Vector3<f64>) {
        self.memory.push(Remembered {
            t_s: t_clock,
            gyro_rad_s: *w,
            accel_m_s2: *f,
            restored_rad_s: Vector3::zeros(),
        });
    }

    /// Whether a step from `t_prev_s` (the newest remembered sample) to a sample at `t_after_s`
    /// with rate `gyro_after`, longer than `max_dt_s` and within a fill, is the sample clock
    /// stepping forward with no sample lost (or, on host stamps, a driver's stall: the samples
    /// held come late and together). Two things must hold: the rate after it lies on the
    /// straight continuation of the last two before it (within [`CONTINUATION_TOLERANCE`] of
    /// how fast the rate was changing), and a real loss would have put it that close to the
    /// continuation with a probability of at most [`STEP_LOSS_PROBABILITY`], judged by the
    /// stride before (matched as for a fill): what it expects at the gap's far side, and how
    /// well it matched the samples before the gap. Returns the time the clock stepped by beyond
    /// one sample step (what [`SampleClock::take_back`] then takes off every later stamp).
    ///
    /// The continuation alone is no test: it passed 4–11 % of real losses of 0.06–0.4 s cut at
    /// every 7th sample of the 16 walks, and on 7–20 % of those the lost samples had turned
    /// the foot by more than 0.3 rad (at a rate's peak, or from a still foot to a still foot,
    /// the rate runs on across a loss too; `docs/experiments/rate-continuation.py`). With the
    /// stride before, no real loss of 0.06–0.3 s and 1 of 80 of 0.4 s (on a still foot) was
    /// taken for a step at `docs/experiments/clock-steps.py`'s places; cut at every 23rd sample
    /// of exp22 and exp38, 15 of 3102 of 0.06–0.15 s (0.5 %, `loss-scan.py`): the stride
    /// before's spread is optimistic, and a rate that rises and falls within the lost samples
    /// can run on across them. Beyond a fill a new segment integrates nothing over the step,
    /// which is what a clock step needs.
    #[cold]
    #[inline(never)]
    pub(super) fn clock_step(
        &self,
        t_prev_s: f64,
        t_after_s: f64,
        gyro_after: &Vector3<f64>,
    ) -> Option<f64> {
        let dt = t_after_s - t_prev_s;
        if dt <= self.cfg.max_dt_s.get() || dt > self.cfg.max_fill_s.get() {
            return None;
        }
        let run = Continuation::of(&self.memory, t_prev_s, self.cfg.max_dt_s.get())?;
        let continued = run.newest + run.change;
        let run_on = (gyro_after - continued).norm();
        if run_on > run.tolerance {
            return None;
        }
        let step_s = run.step_s;
        let lag = self
            .memory
            .stride_lag(t_after_s, gyro_after, self.cfg.max_dt_s.get())?;
        let expected = self.memory.at(t_after_s - lag.lag_s)?.gyro_rad_s;
        // The stride before's mismatch on the samples before the gap (the one after it is what
        // a clock step puts off, the thing tested here).
        let mismatch_sq = lag
            .mismatch_before_rad_s
            .powi(2)
            .max(CONTINUATION_FLOOR_RAD_S * CONTINUATION_FLOOR_RAD_S);
        // The probability that a real loss's far-side rate, N(expected, mismatch²/3 per axis),
        // lies within `run_on` (at least the floor) of the continuation, bounded above by the
        // ball's volume times the largest density inside it.
        let radius = run_on.max(CONTINUATION_FLOOR_RAD_S);
        let var = mismatch_sq / 3.0;
        let nearest = ((expected - continued).norm() - radius).max(0.0);
        let ln_p = (4.0 / 3.0 * std::f64::consts::PI * radius.powi(3)).ln()
            - 1.5 * (std::f64::consts::TAU * var).ln()
            - nearest * nearest / (2.0 * var);
        (ln_p <= STEP_LOSS_PROBABILITY.ln()).then_some(dt - step_s)
    }

    /// Judges the step from the previous sample (time `t_prev`, rate `w_prev`, force `f.0`) to
    /// this one (time `t_clock`, rate `w_now`, force `f.1`); bridges, fills or widens the
    /// covariance of a gap, and counts and reports it.
    pub(super) fn cross_gap(
        &mut self,
        eskf: &mut Box<Eskf>,
        t_clock: f64,
        (t_prev, w_prev, w_now): (f64, &Vector3<f64>, &Vector3<f64>),
        f: (&Vector3<f64>, &Vector3<f64>),
    ) -> Gap {
        let dt = t_clock - t_prev;
        let w = (w_prev, w_now);
        if dt <= self.cfg.max_dt_s.get() {
            return Gap::Integrate;
        }
        self.counters.gaps += 1;
        self.out.gap_s = Some(dt);
        self.out.gap_crossing = Some(GapCrossing::Bridged);
        if dt <= self.cfg.max_bridge_s.get() {
            // A short gap (a few lost samples) is bridged: one step on the mean of the rates and
            // forces on both sides of it, as every step is integrated. What that interpolation
            // misses is at most half the change of the rate (force) across the gap times its
            // length: the attitude variance grows by that about the axis of the change, the
            // velocity variance by its square. Dropping the gap instead lost the rotation of a
            // swing (0.3 rad in 55 ms) with an attitude σ of a few mrad.
            self.counters.gaps_bridged += 1;
            let dw = (w.1 - w.0) * (0.5 * dt);
            let dv = ((f.1 - f.0) * (0.5 * dt)).norm();
            eskf.widen_velocity(dv * dv);
            if let Some(axis) = dw.try_normalize(0.0) {
                eskf.widen_attitude_about(&axis, dw.norm().min(std::f64::consts::PI).powi(2));
            }
            return Gap::Integrate;
        }
        if dt <= self.cfg.max_fill_s.get()
            && let Some(last) = self.fill_gap(eskf, t_prev, t_clock, w_now)
        {
            self.counters.gaps_filled += 1;
            self.out.gap_crossing = Some(GapCrossing::Filled);
            return Gap::Filled(last);
        }
        self.out.gap_crossing = Some(GapCrossing::NewSegment);
        // A new segment. Extrapolating two samples over the gap is meaningless (a 10 s gap once
        // gave a vertical velocity of −286 m/s), so nothing is integrated over it. The velocity
        // is kept (the best guess for a short gap; the next ZUPT settles it) but its variance
        // grows by the largest plausible speed, so that ZUPT moves nothing else; the attitude
        // variance grows by the gyro noise over the gap. A reset to zero would be wrong when the
        // gap falls in a swing and the data go on with the same stride. (Widening the attitude
        // by the rate times the gap as well, about the rate's axis, made gaps of 0.3–1 s cut out
        // of the suite's walks worse: worst +32 % of path at 1 s against +21 %. Bridging them
        // too: worse from 0.2 s on, see `max_bridge_s`.)
        let v_max = self.cfg.max_speed_m_s.get();
        eskf.widen_after_gap(dt, v_max * v_max);
        Gap::NewSegment
    }

    /// Fills a gap from `t_prev_s` to `t_after_s` (rate `gyro_after`) with the remembered
    /// samples one stride earlier, when the rates around the gap match them: propagates the
    /// filter through them and widens its attitude and velocity variance by
    /// [`FILL_RELATIVE_SD`] of the rotation and velocity change they made; the filled samples
    /// are remembered in turn. Returns the last filled sample, on the current clock; `None`
    /// (nothing changed) when the memory cannot fill it, or when the filled state fails the
    /// health check (the stride before held samples at the rails: a review's case drove the
    /// speed to 18.7 m/s, output for three samples, whose updates were undone back to it): the
    /// gap is then a new segment.
    fn fill_gap(
        &mut self,
        eskf: &mut Box<Eskf>,
        t_prev_s: f64,
        t_after_s: f64,
        gyro_after: &Vector3<f64>,
    ) -> Option<(f64, Vector3<f64>, Vector3<f64>)> {
        let newest = *self.memory.get(self.memory.len().checked_sub(1)?);
        // The memory must end where the filter is (not so after a failed health check that
        // left a remembered sample out).
        if newest.t_s != t_prev_s {
            return None;
        }
        let lag = self
            .memory
            .stride_lag(t_after_s, gyro_after, self.cfg.max_dt_s.get())?;
        if lag.mismatch_rad_s > FILL_MAX_MISMATCH_RAD_S || lag.from >= lag.to {
            return None;
        }
        keep(&mut self.undo, eskf, &self.bias, t_prev_s);
        let mut spare = take_spare(&mut self.before, eskf);
        let v_before = eskf.v_m_s;
        let mut turned = UnitQuaternion::identity();
        // The rates as integrated: with what a rail cut off put back (`rail_peaks.rs`).
        let (mut t, mut w, mut f) = (newest.t_s, newest.rate_rad_s(), newest.accel_m_s2);
        for i in lag.from..lag.to {
            let s = *self.memory.get(i);
            let t_s = s.t_s + lag.lag_s;
            let (w_avg, f_avg) = ((w + s.rate_rad_s()) * 0.5, (f + s.accel_m_s2) * 0.5);
            let omega = self.propagate(
                eskf,
                &mut spare,
                t_s - t,
                &w_avg,
                &f_avg,
                CovarianceStep::MayDefer,
            );
            turned *= UnitQuaternion::from_scaled_axis(omega * (t_s - t));
            (t, w, f) = (t_s, s.rate_rad_s(), s.accel_m_s2);
        }
        self.before = Some(spare);
        if !self.healthy(eskf) {
            restore(&self.undo, eskf, &mut self.bias);
            return None;
        }
        self.memory.push_filled(lag.from, lag.to, lag.lag_s);
        let var = (FILL_RELATIVE_SD * turned.angle()).powi(2);
        for k in 0..3 {
            eskf.widen_attitude_about(&Vector3::ith(k, 1.0), var);
        }
        eskf.widen_velocity((FILL_RELATIVE_SD * (eskf.v_m_s - v_before).norm()).powi(2));
        Some((t, w, f))
    }
}
