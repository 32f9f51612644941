//! Peaks a gyro rail cut off, put back (`eskf.restore_clipped_peaks`).
//!
//! A gyro axis at its rail reads the rail while the foot turns faster: the rotation beyond it
//! is lost to the attitude, and through the tilt to the velocity and the stride. At the
//! 3DM-GX5-25's ±8.7 rad/s that is little (110 runs in the 16 gdins walks, a median 1.2 mrad
//! each by the parabola below); a sensor set to a smaller range loses radians per walk (the
//! same walks clipped at ±5 rad/s: 3,200 runs, 190 rad).
//!
//! A peak opens at a swing sample with a gyro axis at its rail: the filter before that sample
//! is kept (one copy, its buffer reused). It closes when [`OFF_RAIL_AFTER`] samples in a row
//! have no axis at the rail. Then, on each axis, each run of samples at the rail gets the
//! parabola (least squares) through the two samples before it and the two after it, the
//! continuation of the rate's own curve over the top; what the parabola has beyond a
//! sample's reading, at most [`MAX_EXCESS_OF_RAIL`] of the rail, is the rate the rail cut off.
//! It is remembered beside the reading (`Remembered::restored_rad_s`), and the filter goes
//! back to the kept copy and propagates again through the peak's samples with it, as a late
//! footfall does (`late_footfall.rs`); later replays from the stride memory integrate it too,
//! and a late footfall's anchor kept inside the peak is kept again on the way (an overdue
//! footfall's search keeps one 0.3 s after a stance, often mid-swing; none was used from inside
//! a peak on the 16 walks at the sensor's rail nor at 6 or 5 rad/s, where the suite's results are
//! the same with and without keeping them again).
//! The samples stay clipped samples: the attitude variance about the axis still grows by
//! `eskf.clipped_rate_sd_rad_s` (what the parabola cannot know). What the estimator output in
//! between stays as it was: the peak is put back two samples (10 ms at 200 Hz) after its end.
//!
//! The parabola was checked on peaks the rail did not cut, without footprints: the 16 walks'
//! rates clipped at 7, 5 and 4 rad/s (`docs/experiments/rail-peaks.py`). It takes the RMS
//! error of a run's lost rotation from 22 to 10 mrad at 7 rad/s, 89 to 48 at 5, 154 to 59 at 4,
//! and puts back 81, 104 and 96 % of the rotation lost; the cap at half the rail keeps a fit
//! over a long run from running away (without it 61 and 100 mrad at 5 and 4 rad/s).
//!
//! Not put back, and counted (`Counters::clipped_peaks_not_restored`): a peak with a stance, a
//! gap, a health fault, a late footfall or a warm start before its end, one that begins at a
//! stance's end (counted if it goes on past that sample and has no other run put back: see
//! `follow_rail_peaks`), one longer than [`MAX_PEAK_SAMPLES`], one none of whose runs has two
//! samples off the rail either side (remembered), one whose filter propagated again fails the
//! health check, and one still open when the stream ends (`Estimator::end_stream`). A peak
//! whose parabolas all lie under their readings lost nothing and is in neither count. The
//! paper's and the rotation-aware modes keep their bias outside the filter and are left as they
//! were.

use super::late_footfall::{Anchor, keep, restore};
use super::stride_memory::StrideMemory;
use super::*;

/// Samples in a row with no gyro axis at its rail that close a peak: the parabola's two after
/// each run.
const OFF_RAIL_AFTER: usize = 2;

/// A peak's samples at most, after the one before its first up to its end (0.5 s at 200 Hz;
/// the longest run of the 16 walks clipped at 4 rad/s is 58 samples, but a peak spans the runs
/// of every axis until two samples are off the rail: offline, without the stances that drop
/// one, the longest such peak there is 99 samples, just under the limit).
pub(super) const MAX_PEAK_SAMPLES: usize = 100;

/// The rate put back at most, as a fraction of the rail.
const MAX_EXCESS_OF_RAIL: f64 = 0.5;

/// The open peak.
#[derive(Debug, Clone, Copy)]
struct Peak {
    /// The sample before its first, sample clock: the filter kept is the one at it.
    anchor_t_s: f64,
    /// Samples since that one.
    samples: usize,
    /// Samples in a row with no axis at the rail, at its end.
    off_rail: usize,
}

/// The clipped peaks: the open one and the filter before it.
#[derive(Debug, Clone, Default)]
pub(super) struct RailPeaks {
    open: Option<Peak>,
    anchor: LastGood<Anchor>,
    /// The late-footfall anchors kept inside a peak, kept again while it is propagated again
    /// (swapped with the late-footfall tracker's when the replay is kept; buffers reused).
    late_anchors: [LastGood<Anchor>; 2],
    /// A peak longer than [`MAX_PEAK_SAMPLES`] was dropped: none opens until a sample is off
    /// the rail (it would be the same peak, counted twice).
    wait_off_rail: bool,
}

impl Pipeline {
    /// Follows the clipped peaks after a navigated sample whose health check passed and which
    /// is remembered: opens a peak at a swing sample with a gyro axis at its rail (the filter
    /// `before` it kept, at `t_prev_s`), drops it at a stance or a gap, and puts it back when
    /// [`OFF_RAIL_AFTER`] samples in a row are off the rail. `stance_ended`: the sample ended a
    /// stance, and no peak opens at it: the filter before it still has the stance's rest noise,
    /// and the rest fused at the stance's end (`navigate`) is only in the filter after it.
    /// Propagated again from before it, both were lost, the update counted as made (a knock
    /// at the rail ending a rest took the z bias 0.006 -> 0 rad/s). Such a run is not put back:
    /// if it goes on, a peak opens at its next sample, which has no two samples off the rail
    /// before it (the peak counted as not put back, unless another of its runs is put back).
    pub(super) fn follow_rail_peaks(
        &mut self,
        eskf: &mut Box<Eskf>,
        t_prev_s: f64,
        (stance, stance_ended): (bool, bool),
    ) {
        if !self.cfg.eskf.restore_clipped_peaks || !matches!(self.bias, BiasFilter::InEskf) {
            return;
        }
        let clipped = self.clipped_gyro_axes.contains(&true);
        let interrupted = stance || stance_ended || self.out.gap_s.is_some();
        if self.rails.wait_off_rail {
            self.rails.wait_off_rail = clipped;
            return;
        }
        let Some(peak) = &mut self.rails.open else {
            if clipped
                && !interrupted
                && let Some(before) = self.before.as_deref()
            {
                keep(&mut self.rails.anchor, before, &self.bias, t_prev_s);
                self.rails.open = Some(Peak {
                    anchor_t_s: t_prev_s,
                    samples: 1,
                    off_rail: 0,
                });
            }
            return;
        };
        peak.samples += 1;
        peak.off_rail = if clipped { 0 } else { peak.off_rail + 1 };
        if interrupted || peak.samples > MAX_PEAK_SAMPLES {
            self.rails.wait_off_rail = !interrupted && clipped;
            self.drop_rail_peak();
        } else if peak.off_rail == OFF_RAIL_AFTER {
            let anchor_t_s = peak.anchor_t_s;
            self.rails.open = None;
            self.restore_rail_peak(eskf, anchor_t_s);
        }
    }

    /// The open peak is not put back (something came between it and its end), and counted.
    pub(super) fn drop_rail_peak(&mut self) {
        if self.rails.open.take().is_some() {
            self.counters.clipped_peaks_not_restored += 1;
        }
    }

    /// Puts back the peak after the remembered sample at `anchor_t_s` (the newest remembered
    /// sample ends it) and propagates the filter kept there again through it.
    fn restore_rail_peak(&mut self, eskf: &mut Box<Eskf>, anchor_t_s: f64) {
        let n = self.memory.len();
        let rail_rad_s = self.gyro_rail_rad_s();
        let from = (0..n).rev().find(|&i| self.memory.get(i).t_s == anchor_t_s);
        let put_back = from.map(|from| put_back_runs(&mut self.memory, from, rail_rad_s));
        let (Some(PutBack::Some), Some(from)) = (put_back, from) else {
            // Not put back, and counted; but a peak whose parabolas all lie under their
            // readings lost nothing (readings within 2 % of the range, not at it): in neither
            // count. No propagation again either way.
            if put_back != Some(PutBack::NothingAbove) {
                self.counters.clipped_peaks_not_restored += 1;
            }
            return;
        };
        // The late-footfall anchors kept inside the peak (after its first sample, before the
        // newest, at which the tracker keeps its own after this) hold the filter without what
        // is put back: a late update from one would lose it. Kept again on the way.
        let newest_s = self.memory.get(n - 1).t_s;
        let stops = self.late.anchors_mut().map(|slot| {
            let t_s = slot.get().map(|a| a.t_s)?;
            let inside = t_s > anchor_t_s && t_s < newest_s;
            inside.then(|| (from + 1..n - 1).find(|&i| self.memory.get(i).t_s == t_s))?
        });
        let order = if stops[1] < stops[0] { [1, 0] } else { [0, 1] };
        // The filter as it is, to go back to (this sample's health check is made already).
        keep(&mut self.undo, eskf, &self.bias, f64::NAN);
        let mut replay = take_spare(&mut self.before, eskf);
        restore(&self.rails.anchor, &mut replay, &mut self.bias);
        let mut spare = std::mem::replace(eskf, replay);
        let mut at = from;
        for slot in order {
            if let Some(i) = stops[slot] {
                self.propagate_remembered(eskf, &mut spare, at, i);
                let t_s = self.memory.get(i).t_s;
                keep(&mut self.rails.late_anchors[slot], eskf, &self.bias, t_s);
                at = i;
            }
        }
        self.propagate_remembered(eskf, &mut spare, at, n - 1);
        self.before = Some(spare);
        if !self.healthy(eskf) {
            restore(&self.undo, eskf, &mut self.bias);
            for i in from..n {
                self.memory.get_mut(i).restored_rad_s = Vector3::zeros();
            }
            self.counters.clipped_peaks_not_restored += 1;
            return;
        }
        for (slot, kept) in self.late.anchors_mut().into_iter().enumerate() {
            if stops[slot].is_some() {
                std::mem::swap(kept, &mut self.rails.late_anchors[slot]);
            }
        }
        self.counters.clipped_peaks_restored += 1;
    }
}

/// What a peak's runs at the rail allowed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PutBack {
    /// No run had two samples off the rail either side: nothing could be put back.
    NoFit,
    /// Every parabola lay under its readings: nothing was cut off.
    NothingAbove,
    /// A rate was put back.
    Some,
}

/// Puts back, in the remembered samples after `from`, the rate cut off each run of samples at
/// the rail (`rail_rad_s`) on each axis.
fn put_back_runs(memory: &mut StrideMemory, from: usize, rail_rad_s: f64) -> PutBack {
    let n = memory.len();
    let mut result = PutBack::NoFit;
    for axis in 0..3 {
        let mut i = from + 1;
        while i < n {
            let sign = memory.get(i).gyro_rad_s[axis].signum();
            if memory.get(i).gyro_rad_s[axis].abs() < rail_rad_s {
                i += 1;
                continue;
            }
            let start = i;
            while i < n && memory.get(i).gyro_rad_s[axis] * sign >= rail_rad_s {
                i += 1;
            }
            result = match (
                put_back_run(memory, axis, (start, i), rail_rad_s, sign),
                result,
            ) {
                (Some(true), _) | (_, PutBack::Some) => PutBack::Some,
                (Some(false), _) | (None, PutBack::NothingAbove) => PutBack::NothingAbove,
                (None, PutBack::NoFit) => PutBack::NoFit,
            };
        }
    }
    result
}

/// The parabola (least squares) through the two samples before the run `start..end` on `axis`
/// and the two after it; what it has beyond each run sample's reading (towards `sign`), at most
/// [`MAX_EXCESS_OF_RAIL`] of the rail (`rail_rad_s`), put back. `None` (nothing put back)
/// without two samples off the rail either side; else whether the parabola rose above any
/// reading.
fn put_back_run(
    memory: &mut StrideMemory,
    axis: usize,
    (start, end): (usize, usize),
    rail_rad_s: f64,
    sign: f64,
) -> Option<bool> {
    if start < 2 || end + 2 > memory.len() {
        return None;
    }
    let around = [start - 2, start - 1, end, end + 1];
    if around
        .iter()
        .any(|&i| memory.get(i).gyro_rad_s[axis].abs() >= rail_rad_s)
    {
        return None;
    }
    // Time from the run's first sample, in units of the span the four samples cover (the
    // normal equations stay well conditioned at any sample rate).
    let t0_s = memory.get(start).t_s;
    let span_s = memory.get(end + 1).t_s - memory.get(start - 2).t_s;
    if span_s <= 0.0 {
        return None;
    }
    let x_of = |t_s: f64| (t_s - t0_s) / span_s;
    let (mut ata, mut aty) = (Matrix3::zeros(), Vector3::zeros());
    for &i in &around {
        let m = memory.get(i);
        let x = x_of(m.t_s);
        let row = Vector3::new(1.0, x, x * x);
        ata += row * row.transpose();
        aty += row * m.gyro_rad_s[axis];
    }
    let c = ata.lu().solve(&aty)?;
    let max_excess_rad_s = MAX_EXCESS_OF_RAIL * rail_rad_s;
    let mut any = false;
    for i in start..end {
        let m = memory.get_mut(i);
        let x = x_of(m.t_s);
        let fit_rad_s = c[0] + c[1] * x + c[2] * x * x;
        let excess_rad_s = (sign * (fit_rad_s - m.gyro_rad_s[axis])).clamp(0.0, max_excess_rad_s);
        m.restored_rad_s[axis] = sign * excess_rad_s;
        any |= excess_rad_s > 0.0;
    }
    Some(any)
}

#[cfg(test)]
mod tests {
    use super::super::stride_memory::Remembered;
    use super::*;
    use corridor_shared::config::{Config, ConfigFile};

    const DT_S: f64 = 0.005;

    /// A memory of `n` samples of the rate `w(t)` on axis y, read through a `rail`.
    fn clipped_memory(n: usize, rail: f64, w: impl Fn(f64) -> f64) -> StrideMemory {
        let mut m = StrideMemory::default();
        for k in 0..n {
            let t_s = k as f64 * DT_S;
            m.push(Remembered {
                t_s,
                gyro_rad_s: Vector3::new(0.0, w(t_s).min(rail), 0.0),
                accel_m_s2: Vector3::new(0.0, 0.0, 9.81),
                restored_rad_s: Vector3::zeros(),
            });
        }
        m
    }

    #[test]
    fn a_parabolic_peak_is_put_back_exactly_and_a_runaway_fit_is_capped() {
        let peak = |t_s: f64| 10.0 - 2000.0 * (t_s - 0.1).powi(2);
        let rail = 8.5;
        let mut m = clipped_memory(41, rail, peak);
        assert_eq!(put_back_runs(&mut m, 0, rail), PutBack::Some);
        let mut clipped = 0;
        for i in 0..m.len() {
            let s = m.get(i);
            let truth = peak(s.t_s);
            if truth >= rail {
                clipped += 1;
                assert!((s.rate_rad_s()[1] - truth).abs() < 1e-9, "{i}: {s:?}");
            } else {
                assert_eq!(s.restored_rad_s, Vector3::zeros(), "{i}");
            }
        }
        assert_eq!(
            clipped, 11,
            "the peak lies up to 1.5 rad/s over the rail for 55 ms"
        );
        // At a rail of 3 rad/s the peak lies 7 rad/s over it: put back up to half the rail.
        let mut m = clipped_memory(41, 3.0, peak);
        assert_eq!(put_back_runs(&mut m, 0, 3.0), PutBack::Some);
        let top = (0..m.len()).map(|i| m.get(i).rate_rad_s()[1]);
        assert_eq!(top.fold(f64::MIN, f64::max), 4.5);
    }

    #[test]
    fn a_run_without_two_samples_off_the_rail_on_either_side_is_left_as_read() {
        let rail = 8.5;
        // The peak's top at the memory's second sample: one sample before it.
        let early = |t_s: f64| 10.0 - 2000.0 * (t_s - 0.005).powi(2);
        let mut m = clipped_memory(12, rail, early);
        assert_eq!(put_back_runs(&mut m, 0, rail), PutBack::NoFit);
        // Ends one sample before the memory does.
        let late = |t_s: f64| 10.0 - 2000.0 * (t_s - 0.05).powi(2);
        let mut m = clipped_memory(13, rail, late);
        assert_eq!(put_back_runs(&mut m, 0, rail), PutBack::NoFit);
        assert!((0..m.len()).all(|i| m.get(i).restored_rad_s == Vector3::zeros()));
        // A plateau at the rail whose neighbours fall away steeply enough that the parabola
        // through them lies under it: nothing to put back.
        let plateau = |t_s: f64| {
            if (t_s - 0.05).abs() < 0.006 {
                rail
            } else {
                0.0
            }
        };
        let mut m = clipped_memory(21, rail, plateau);
        assert_eq!(put_back_runs(&mut m, 0, rail), PutBack::NothingAbove);
    }

    #[test]
    fn a_peak_longer_than_the_limit_is_counted_once_as_not_put_back() {
        let mut est = Estimator::new(gdins_range(), HeadingAid::None);
        let rail = est.config().sensor.gyro_range_rad_s();
        let mut t_s = 0.0;
        let mut step = |est: &mut Estimator, w_y: f64| {
            est.step(&ImuInput {
                t_s,
                gyro_rad_s: [0.0, w_y, 0.0],
                accel_m_s2: [0.0, 0.0, 9.81],
            })
            .unwrap();
            t_s += DT_S;
        };
        for _ in 0..600 {
            step(&mut est, 0.0);
        }
        for _ in 0..5 {
            step(&mut est, 0.5);
        }
        // Twice the limit at the rail, then off it.
        for _ in 0..2 * MAX_PEAK_SAMPLES {
            step(&mut est, rail);
        }
        for _ in 0..5 {
            step(&mut est, 0.5);
        }
        let c = est.counters();
        assert_eq!(c.clipped_samples, 2 * MAX_PEAK_SAMPLES as u64);
        assert_eq!(
            (c.clipped_peaks_restored, c.clipped_peaks_not_restored),
            (0, 1)
        );
    }

    /// The defaults with the gdins gyro's range (±8.727 rad/s).
    fn gdins_range() -> Config {
        let mut f = ConfigFile::default();
        f.sensor.gyro_range_rad_s = Some(8.727);
        f.validate().unwrap()
    }

    /// The attitude's rotation over a half-sine lobe about y of peak `peak_rad_s` lasting
    /// 0.2 s (after an aligning rest), and the estimator's counters.
    fn lobe(restore: bool, peak_rad_s: f64) -> (f64, Counters) {
        let mut cfg = gdins_range();
        cfg.eskf.restore_clipped_peaks = restore;
        let rail = cfg.sensor.gyro_range_rad_s();
        let mut est = Estimator::new(cfg, HeadingAid::None);
        let level = [0.0, 0.0, 9.81];
        let mut t_s = 0.0;
        let mut step = |est: &mut Estimator, w_y: f64| {
            let s = ImuInput {
                t_s,
                gyro_rad_s: [0.0, w_y.clamp(-rail, rail), 0.0],
                accel_m_s2: level,
            };
            t_s += DT_S;
            *est.step(&s).unwrap()
        };
        for _ in 0..600 {
            step(&mut est, 0.0);
        }
        // Moving: the filter aligns, and runs from here.
        step(&mut est, 0.5);
        let before = step(&mut est, 0.5).nav_from_body;
        for k in 1..40 {
            step(
                &mut est,
                peak_rad_s * (std::f64::consts::PI * k as f64 / 40.0).sin(),
            );
        }
        // Back to the lobe's start rate: closes the peak (two samples off the rail).
        for _ in 0..3 {
            step(&mut est, 0.5);
        }
        let after = est.last_estimate().nav_from_body;
        let q = |a: [f64; 4]| {
            UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(a[0], a[1], a[2], a[3]))
        };
        ((q(before).inverse() * q(after)).angle(), *est.counters())
    }

    #[test]
    fn a_peak_cut_off_by_the_rail_is_put_back_into_the_attitude() {
        let range = gdins_range().sensor.gyro_range_rad_s();
        let peak = 1.25 * range;
        // The rotation the lobe and the samples around it make, and the part the range cuts.
        let rate = |k: usize| peak * (std::f64::consts::PI * k as f64 / 40.0).sin();
        let truth: f64 = (0..=40).map(|k| rate(k) * DT_S).sum::<f64>() + 3.0 * 0.5 * DT_S;
        let lost: f64 = (1..40).map(|k| (rate(k) - range).max(0.0) * DT_S).sum();
        assert!(lost > 0.03, "{lost}");
        let (off, c_off) = lobe(false, peak);
        let (on, c_on) = lobe(true, peak);
        assert!(c_on.clipped_samples > 5 && c_on.clipped_samples == c_off.clipped_samples);
        assert_eq!(
            (c_on.clipped_peaks_restored, c_on.clipped_peaks_not_restored),
            (1, 0)
        );
        assert_eq!(
            (
                c_off.clipped_peaks_restored,
                c_off.clipped_peaks_not_restored
            ),
            (0, 0)
        );
        // Without: the rotation the rail cut is missing (the trapezoid's ends aside).
        assert!(
            (truth - off - lost).abs() < 0.1 * lost,
            "{truth} {off} {lost}"
        );
        // With: within a tenth of it (a sine is no parabola).
        assert!((truth - on).abs() < 0.1 * lost, "{truth} {on} {lost}");
        // Under the rail, nothing to put back.
        let (_, c) = lobe(true, 0.9 * CLIP_FRACTION * range);
        assert_eq!((c.clipped_samples, c.clipped_peaks_restored), (0, 0));
    }

    /// `n` samples of `gyro` and `accel` from `t0_s`; the time after them.
    fn feed(est: &mut Estimator, t0_s: f64, n: usize, gyro: [f64; 3], accel: [f64; 3]) -> f64 {
        for k in 0..n {
            let t_s = t0_s + k as f64 * DT_S;
            est.step(&ImuInput {
                t_s,
                gyro_rad_s: gyro,
                accel_m_s2: accel,
            })
            .unwrap();
        }
        t0_s + n as f64 * DT_S
    }

    /// After an aligning rest, a swing (the foot spinning about x at 2 rad/s) and a stance,
    /// a swing whose y rate runs through a half-sine lobe of `peak_rad_s` (0.2 s) from 0.2 s
    /// after the stance's end, read through the rail, and on (or, `end`, its first half only);
    /// the estimator then.
    fn stance_then_lobe(restore: bool, peak_rad_s: f64, end: bool) -> Estimator {
        let mut cfg = gdins_range();
        cfg.eskf.restore_clipped_peaks = restore;
        cfg.detector.overdue_stride_factor = Some(Positive::new("test", 1.5).unwrap());
        let rail = cfg.sensor.gyro_range_rad_s();
        let mut est = Estimator::new(cfg, HeadingAid::None);
        let (level, spin) = ([0.0, 0.0, 9.81], [2.0, 0.0, 0.0]);
        let mut t = feed(&mut est, 0.0, 200, [0.0; 3], level);
        t = feed(&mut est, t, 100, spin, level);
        t = feed(&mut est, t, 60, [0.0; 3], level);
        t = feed(&mut est, t, 40, spin, level);
        let lobe = |k: usize| peak_rad_s * (std::f64::consts::PI * k as f64 / 40.0).sin();
        let last = if end { 20 } else { 40 };
        for k in 1..last {
            t = feed(
                &mut est,
                t,
                1,
                [2.0, lobe(k).clamp(-rail, rail), 0.0],
                level,
            );
        }
        if !end {
            feed(&mut est, t, 3, spin, level);
        }
        est
    }

    #[test]
    fn a_late_footfall_anchor_kept_inside_a_peak_is_kept_again_with_it_put_back() {
        // The overdue-footfall search keeps the filter at its first sample, 0.3 s after the
        // stance (`detector.merge_gap_s`), here inside the peak: a late update from it would
        // lose the rotation put back between the peak's first sample and it.
        let range = gdins_range().sensor.gyro_range_rad_s();
        let peak = 1.25 * range;
        let mut runs = [false, true].map(|restore| stance_then_lobe(restore, peak, false));
        let kept = |est: &mut Estimator| {
            let [_, cycle] = est.p.late.anchors_mut();
            let a = cycle.get().expect("kept");
            (a.t_s, a.eskf.nav_from_body)
        };
        let [off, on] = &mut runs;
        let [(t_off, q_off), (t_on, q_on)] = [kept(off), kept(on)];
        let c = runs[1].counters();
        assert_eq!((c.clipped_peaks_restored, c.stances), (1, 1), "{c:?}");
        assert_eq!(t_on, t_off);
        // The anchor lies in the lobe's clipped part, which spans its samples 12 to 28.
        let lobe_k = ((t_on - 2.0) / DT_S).round() + 1.0;
        assert!((13.0..28.0).contains(&lobe_k), "{t_on} {lobe_k}");
        // What the rail cut between the lobe's start and the anchor, put back into it (the
        // samples' trapezoid and the parabola's error aside: 66 against 65 mrad). Without
        // keeping it again, the anchors of both runs were the same.
        let rate = |k: f64| peak * (std::f64::consts::PI * k / 40.0).sin();
        let lost: f64 = (1..lobe_k as usize)
            .map(|k| (rate(k as f64) - range).max(0.0) * DT_S)
            .sum();
        let moved = (q_off.inverse() * q_on).angle();
        assert!(lost > 0.005, "{lost}");
        assert!((moved - lost).abs() < 0.1 * lost, "{moved} {lost}");
    }

    #[test]
    fn a_peak_open_when_the_stream_ends_is_counted_as_not_put_back() {
        let range = gdins_range().sensor.gyro_range_rad_s();
        let mut est = stance_then_lobe(true, 1.25 * range, true);
        let c = *est.counters();
        assert!(c.clipped_samples > 5, "{c:?}");
        assert_eq!(
            (c.clipped_peaks_restored, c.clipped_peaks_not_restored),
            (0, 0)
        );
        est.end_stream();
        let c = *est.counters();
        assert_eq!(
            (c.clipped_peaks_restored, c.clipped_peaks_not_restored),
            (0, 1)
        );
        est.end_stream();
        assert_eq!(est.counters().clipped_peaks_not_restored, 1, "counted once");
    }

    #[test]
    fn a_rest_fused_where_a_peak_begins_is_not_undone_by_putting_the_peak_back() {
        // A 2 s rest ends at a sample with the y axis at its rail (a knock): that sample fuses
        // the rest (the zero-rate update at a stance's end) and ends its rest noise. The x axis
        // swings over its rail from the next sample on. A peak opened at the knock kept the filter before it, and
        // putting the x peak back propagated again from there: the update was lost (counted
        // as made) and the rest noise ran on into the swing.
        let bias = [0.004, -0.002, 0.006];
        let (level, pushed) = ([0.0, 0.0, 9.81], [30.0, 0.0, 9.81]);
        let mut runs = Vec::new();
        for restore in [false, true] {
            let mut cfg = gdins_range();
            cfg.alignment.gyro_bias_prior = BiasPrior::None;
            cfg.eskf.zero_rate_updates = true;
            cfg.eskf.restore_clipped_peaks = restore;
            let range = cfg.sensor.gyro_range_rad_s();
            let mut est = Estimator::new(cfg, HeadingAid::None);
            let t = feed(&mut est, 0.0, 200, bias, level);
            let t = feed(&mut est, t, 10, bias, pushed);
            let mut t = feed(&mut est, t, 400, bias, level);
            let zero_rate = est.counters().zero_rate_updates;
            // x: a parabola through 0.6 × the range at the knock, up to 1.3 × it three samples
            // later and down, read through the range (at the rail from the next sample on, so
            // that one peak holds the knock and x's run).
            let x = |j: f64| (1.3 - 0.7 / 9.0 * (j - 3.0).powi(2)).max(0.0) * range;
            t = feed(&mut est, t, 1, [x(0.0), range, bias[2]], level);
            assert_eq!(
                est.counters().zero_rate_updates,
                zero_rate + 1,
                "fused there"
            );
            for j in 1..=8 {
                let x_rad_s = x(f64::from(j)).min(range);
                t = feed(&mut est, t, 1, [x_rad_s, bias[1], bias[2]], pushed);
            }
            feed(&mut est, t, 3, bias, pushed);
            runs.push((*est.last_estimate(), *est.counters()));
        }
        let [(off, c_off), (on, c_on)] = runs.try_into().unwrap();
        assert_eq!(c_on.zero_rate_updates, c_off.zero_rate_updates);
        assert_eq!(
            (c_off.clipped_peaks_restored, c_on.clipped_peaks_restored),
            (0, 1)
        );
        // The x peak was put back from the filter after the rest was fused: its bias is the
        // rest's (nothing but the zero-rate update moved it since), as without the peaks.
        assert_eq!(on.gyro_bias_rad_s, off.gyro_bias_rad_s);
        for (b, want) in on.gyro_bias_rad_s.iter().zip(bias) {
            assert!((b - want).abs() < 5e-4, "{:?}", on.gyro_bias_rad_s);
        }
        assert_ne!(
            on.nav_from_body, off.nav_from_body,
            "the x peak was put back"
        );
    }
}
