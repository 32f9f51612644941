//! The last stride or two of samples, kept to fill a gap in a swing with the same phase of the
//! stride before (`estimator.max_fill_s`).
//!
//! Walking repeats itself: the swing a foot makes now rotates it much as the one before did, at
//! the same time after its footfall. A gap too long to bridge by one step (`max_bridge_s`)
//! loses the motion in it, up to a radian of rotation in a swing; as a new segment nothing is
//! integrated over it. Here the samples one stride earlier stand in for the lost ones: the
//! stride's lag is found by matching the rates before the gap (and the first one after it)
//! against the memory, within ±20 % of the last stride period, and refused when they do not
//! match.

use nalgebra::Vector3;

/// Samples kept: 2048 (10 s at 200 Hz, 5 s at 400 Hz). A lag beyond the memory is not filled.
pub(super) const MEMORY_SAMPLES: usize = 2048;

/// Rate samples before the gap that the stride's lag is matched on.
const MATCH_SAMPLES: usize = 30;

/// The stride lag is searched within this fraction of the last stride period either way.
const LAG_SPAN: f64 = 0.2;

/// One remembered sample: sample-clock time, gyro and specific force (sensor axes) as they
/// came, and the rate a gyro rail cut off it, put back (`rail_peaks.rs`; zero where nothing was).
#[derive(Debug, Clone, Copy)]
pub(super) struct Remembered {
    pub t_s: f64,
    pub gyro_rad_s: Vector3<f64>,
    pub accel_m_s2: Vector3<f64>,
    pub restored_rad_s: Vector3<f64>,
}

impl Remembered {
    /// The rate the filter integrates: the reading and what its rail cut off.
    pub fn rate_rad_s(&self) -> Vector3<f64> {
        self.gyro_rad_s + self.restored_rad_s
    }
}

/// A fixed ring of the last [`MEMORY_SAMPLES`] samples and the last two footfall times.
/// Allocated once, at construction.
#[derive(Debug, Clone)]
pub(super) struct StrideMemory {
    ring: Vec<Remembered>,
    /// Index of the oldest sample.
    head: usize,
    len: usize,
    /// The last two footfalls (stance events begun), sample clock, newest last.
    footfalls_s: [f64; 2],
}

/// Where in the memory the lost samples of a gap are taken from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct StrideLag {
    /// The stride lag, s: a lost sample at t stands for the remembered one at t − lag.
    pub lag_s: f64,
    /// Memory index (0 = oldest) of the first remembered sample inside the gap, and one past
    /// the last.
    pub from: usize,
    pub to: usize,
    /// RMS rate difference between the samples around the gap and their remembered
    /// counterparts, rad/s.
    pub mismatch_rad_s: f64,
    /// The same over the samples before the gap alone.
    pub mismatch_before_rad_s: f64,
}

impl Default for StrideMemory {
    fn default() -> Self {
        let zero = Remembered {
            t_s: f64::NAN,
            gyro_rad_s: Vector3::zeros(),
            accel_m_s2: Vector3::zeros(),
            restored_rad_s: Vector3::zeros(),
        };
        Self {
            ring: vec![zero; MEMORY_SAMPLES],
            head: 0,
            len: 0,
            footfalls_s: [f64::NAN; 2],
        }
    }
}

impl StrideMemory {
    /// Becomes a copy of `src` in its own ring: no allocation (every ring is as long). Every
    /// other field is `Copy` (see `StanceDetector::copy_from`).
    pub fn copy_from(&mut self, src: &Self) {
        let mut ring = std::mem::take(&mut self.ring);
        ring.clone_from(&src.ring);
        *self = Self { ring, ..*src };
    }

    /// Remembers one sample (the oldest is forgotten when the memory is full).
    pub fn push(&mut self, s: Remembered) {
        // Once per sample: no division for the wrap.
        let cap = self.ring.len();
        if self.len < cap {
            let i = self.head + self.len;
            self.ring[if i >= cap { i - cap } else { i }] = s;
            self.len += 1;
        } else {
            self.ring[self.head] = s;
            self.head = if self.head + 1 == cap {
                0
            } else {
                self.head + 1
            };
        }
    }

    /// A footfall (a stance event began) at `t_s`.
    pub fn footfall(&mut self, t_s: f64) {
        self.footfalls_s = [self.footfalls_s[1], t_s];
    }

    /// Forgets everything (a new segment: the walk before it says nothing of the one after).
    pub fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
        self.footfalls_s = [f64::NAN; 2];
    }

    /// The `i`-th remembered sample, 0 = oldest.
    pub fn get(&self, i: usize) -> &Remembered {
        &self.ring[(self.head + i) % self.ring.len()]
    }

    /// The `i`-th remembered sample, 0 = oldest, to put back what a rail cut off.
    pub fn get_mut(&mut self, i: usize) -> &mut Remembered {
        let cap = self.ring.len();
        &mut self.ring[(self.head + i) % cap]
    }

    pub fn len(&self) -> usize {
        self.len
    }

    /// The time between the last two footfalls, s (NaN before two).
    pub fn stride_period_s(&self) -> f64 {
        self.footfalls_s[1] - self.footfalls_s[0]
    }

    /// The stride lag for a gap from the newest remembered sample to a sample at `t_after_s`
    /// with rate `gyro_after`: the lag within ±[`LAG_SPAN`] of the last stride period whose
    /// remembered rates best match the [`MATCH_SAMPLES`] rates before the gap and the one after
    /// it. `None` without two footfalls, when the gap is longer than half a stride, when the
    /// memory does not reach back far enough, or when the remembered samples that would fill
    /// the gap have a gap themselves (a step longer than `max_step_s`).
    pub fn stride_lag(
        &self,
        t_after_s: f64,
        gyro_after: &Vector3<f64>,
        max_step_s: f64,
    ) -> Option<StrideLag> {
        let n = self.len;
        let period = self.stride_period_s();
        // NaN: fewer than two footfalls.
        if n < MATCH_SAMPLES + 2 || period.is_nan() || period <= 0.0 {
            return None;
        }
        let newest = self.get(n - 1);
        let gap_s = t_after_s - newest.t_s;
        // The footfall clock must be recent: a stride period from before a long stop says
        // nothing of the phase now.
        if gap_s.is_nan()
            || gap_s <= 0.0
            || gap_s > 0.5 * period
            || newest.t_s - self.footfalls_s[1] > 2.0 * period
        {
            return None;
        }
        let (lo, hi) = ((1.0 - LAG_SPAN) * period, (1.0 + LAG_SPAN) * period);
        let mut best: Option<(f64, f64, usize)> = None;
        // Shift s: the sample at index i stands for the one at i + s.
        for s in 1..=n - MATCH_SAMPLES {
            let lag = newest.t_s - self.get(n - 1 - s).t_s;
            if lag < lo {
                continue;
            }
            if lag > hi {
                break;
            }
            let before: f64 = (n - MATCH_SAMPLES..n)
                .map(|i| (self.get(i).gyro_rad_s - self.get(i - s).gyro_rad_s).norm_squared())
                .sum();
            let after = (gyro_after - self.at(t_after_s - lag)?.gyro_rad_s).norm_squared();
            let cost = (before + after) / (MATCH_SAMPLES + 1) as f64;
            if best.is_none_or(|(c, ..)| cost < c) {
                best = Some((cost, before, s));
            }
        }
        let (cost, before, s) = best?;
        let lag_s = newest.t_s - self.get(n - 1 - s).t_s;
        let from = n - s;
        let to = (from..n)
            .find(|&i| self.get(i).t_s + lag_s >= t_after_s)
            .unwrap_or(n);
        // From the newest sample's counterpart to the last one that fills, and from there to
        // the sample after the gap: no hole.
        let hole = (from..to).any(|i| self.get(i).t_s - self.get(i - 1).t_s > max_step_s)
            || to > from && t_after_s - (self.get(to - 1).t_s + lag_s) > max_step_s;
        if hole {
            return None;
        }
        Some(StrideLag {
            lag_s,
            from,
            to,
            mismatch_rad_s: cost.sqrt(),
            mismatch_before_rad_s: (before / MATCH_SAMPLES as f64).sqrt(),
        })
    }

    /// Remembers the samples `from..to` again, `lag_s` later: the samples that filled a gap,
    /// so that the memory goes on without a hole. Reads each before the push that may forget
    /// the oldest (every index moves down by one then).
    pub fn push_filled(&mut self, from: usize, to: usize, lag_s: f64) {
        let mut forgotten = 0;
        for i in from..to {
            let s = *self.get(i - forgotten);
            forgotten += usize::from(self.len == self.ring.len());
            self.push(Remembered {
                t_s: s.t_s + lag_s,
                ..s
            });
        }
    }

    /// The remembered sample nearest to `t_s` (binary search on the times).
    pub fn at(&self, t_s: f64) -> Option<&Remembered> {
        if self.len == 0 {
            return None;
        }
        let (mut a, mut b) = (0, self.len);
        while a < b {
            let m = (a + b) / 2;
            if self.get(m).t_s < t_s {
                a = m + 1;
            } else {
                b = m;
            }
        }
        let i = match a {
            0 => 0,
            a if a == self.len => self.len - 1,
            a if t_s - self.get(a - 1).t_s < self.get(a).t_s - t_s => a - 1,
            a => a,
        };
        Some(self.get(i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 0.005;
    const MAX_STEP: f64 = 0.05;

    /// A gait with a period of `period_s`: a swing rotation in the first 60 % of each stride,
    /// still in the rest; a footfall at 60 % of each.
    fn gait(t_s: f64, period_s: f64) -> Vector3<f64> {
        let phase = (t_s / period_s).fract();
        if phase < 0.6 {
            let x = phase / 0.6 * std::f64::consts::TAU;
            Vector3::new(
                0.3 * x.sin(),
                5.0 * x.sin() + 2.0 * (2.0 * x).sin(),
                0.5 * x.cos(),
            )
        } else {
            Vector3::zeros()
        }
    }

    fn walked(period_s: f64, until_s: f64) -> StrideMemory {
        let mut m = StrideMemory::default();
        let mut k = 0;
        loop {
            let t_s = k as f64 * DT;
            if t_s > until_s {
                break m;
            }
            m.push(Remembered {
                t_s,
                gyro_rad_s: gait(t_s, period_s),
                accel_m_s2: Vector3::new(0.0, 0.0, 9.81),
                restored_rad_s: Vector3::zeros(),
            });
            // The sample nearest to 60 % of each stride.
            if ((t_s / period_s).fract() - 0.6).abs() * period_s < 0.5 * DT {
                m.footfall(t_s);
            }
            k += 1;
        }
    }

    #[test]
    fn the_lag_of_a_regular_gait_is_its_period_and_the_gap_is_covered() {
        let period = 1.1;
        let m = walked(period, 10.2);
        assert!(
            (m.stride_period_s() - period).abs() < 1.5 * DT,
            "{}",
            m.stride_period_s()
        );
        // 0.25 s lost in the swing after 10.2 s.
        let t_after = 10.2 + 0.25;
        let lag = m
            .stride_lag(t_after, &gait(t_after, period), MAX_STEP)
            .unwrap();
        assert!((lag.lag_s - period).abs() < 1.5 * DT, "{lag:?}");
        assert!(lag.mismatch_rad_s < 0.1, "{lag:?}");
        // The remembered samples stand for the lost ones: from the one after the newest to
        // the one before the sample after the gap.
        let newest = m.get(m.len() - 1).t_s;
        let first = m.get(lag.from).t_s + lag.lag_s;
        let last = m.get(lag.to - 1).t_s + lag.lag_s;
        assert!((first - (newest + DT)).abs() < 0.5 * DT, "{first} {newest}");
        assert!(last < t_after && last > t_after - 1.5 * DT, "{last}");
    }

    #[test]
    fn a_gait_that_changed_matches_worse_than_one_that_did_not() {
        let m = walked(1.0, 10.2);
        let t_after = 10.45;
        let same = m
            .stride_lag(t_after, &gait(t_after, 1.0), MAX_STEP)
            .unwrap();
        // The rate after the gap from another motion (a turn on the spot).
        let other = m
            .stride_lag(t_after, &Vector3::new(0.0, 0.0, 4.0), MAX_STEP)
            .unwrap();
        assert!(
            other.mismatch_rad_s > 3.0 * same.mismatch_rad_s.max(0.1),
            "{same:?} {other:?}"
        );
    }

    #[test]
    fn no_lag_without_two_footfalls_across_half_a_stride_or_after_a_long_stop() {
        let mut m = StrideMemory::default();
        for k in 0..400 {
            let t_s = k as f64 * DT;
            m.push(Remembered {
                t_s,
                gyro_rad_s: gait(t_s, 1.0),
                accel_m_s2: Vector3::zeros(),
                restored_rad_s: Vector3::zeros(),
            });
        }
        // No footfall yet.
        assert_eq!(m.stride_lag(2.2, &Vector3::zeros(), MAX_STEP), None);
        let m = walked(1.0, 10.2);
        // More than half a stride lost.
        assert_eq!(m.stride_lag(10.2 + 0.55, &Vector3::zeros(), MAX_STEP), None);
        assert!(
            m.stride_lag(10.2 + 0.45, &Vector3::zeros(), MAX_STEP)
                .is_some()
        );
        // The last footfall long ago: the phase is not known any more.
        let mut stopped = walked(1.0, 10.2);
        for k in 1..500 {
            stopped.push(Remembered {
                t_s: 10.2 + k as f64 * DT,
                gyro_rad_s: Vector3::zeros(),
                accel_m_s2: Vector3::zeros(),
                restored_rad_s: Vector3::zeros(),
            });
        }
        assert_eq!(stopped.stride_lag(12.9, &Vector3::zeros(), MAX_STEP), None);
        stopped.clear();
        assert_eq!(stopped.len(), 0);
    }

    #[test]
    fn a_full_memory_finds_the_lag_and_goes_on_after_a_fill_without_a_hole() {
        // 30 s at 200 Hz: the ring has wrapped.
        let period = 1.2;
        let mut m = walked(period, 30.0);
        assert_eq!(m.len(), MEMORY_SAMPLES);
        let t_after = 30.0 + 0.3;
        let lag = m
            .stride_lag(t_after, &gait(t_after, period), MAX_STEP)
            .unwrap();
        assert!((lag.lag_s - period).abs() < 1.5 * DT, "{lag:?}");
        let filled: Vec<Remembered> = (lag.from..lag.to).map(|i| *m.get(i)).collect();
        m.push_filled(lag.from, lag.to, lag.lag_s);
        assert_eq!(m.len(), MEMORY_SAMPLES);
        // The filled samples are the newest, in order, a stride later, each what it stood for.
        let k = filled.len();
        for (j, f) in filled.iter().enumerate() {
            let got = m.get(MEMORY_SAMPLES - k + j);
            assert_eq!(got.t_s, f.t_s + lag.lag_s);
            assert_eq!(got.gyro_rad_s, f.gyro_rad_s);
            assert!(
                (got.gyro_rad_s - gait(got.t_s, period)).norm() < 1e-9,
                "{j}"
            );
        }
        // A hole in the samples that would fill a gap: refused.
        let walk = walked(period, 10.2);
        let mut holed = StrideMemory::default();
        for i in 0..walk.len() {
            let s = *walk.get(i);
            // 0.1 s missing one stride before the gap after 10.2 s.
            if !(9.1..9.2).contains(&s.t_s) {
                holed.push(s);
            }
        }
        holed.footfalls_s = walk.footfalls_s;
        let t_after = 10.2 + 0.2;
        assert_eq!(
            holed.stride_lag(t_after, &gait(t_after, period), MAX_STEP),
            None
        );
        assert!(
            holed
                .stride_lag(t_after, &gait(t_after, period), 0.2)
                .is_some()
        );
    }

    #[test]
    fn filled_samples_are_remembered_in_order_whether_or_not_the_ring_fills_up_meanwhile() {
        let period = 1.0;
        // Not full before or after; full only part of the way through the fill.
        for until_s in [5.0, (MEMORY_SAMPLES - 20) as f64 * DT] {
            let mut m = walked(period, until_s);
            let t_after = until_s + 0.3;
            let lag = m
                .stride_lag(t_after, &gait(t_after, period), MAX_STEP)
                .unwrap();
            let filled: Vec<Remembered> = (lag.from..lag.to).map(|i| *m.get(i)).collect();
            let (len, k) = (m.len(), filled.len());
            m.push_filled(lag.from, lag.to, lag.lag_s);
            assert_eq!(m.len(), (len + k).min(MEMORY_SAMPLES), "{until_s}");
            for (j, f) in filled.iter().enumerate() {
                let got = m.get(m.len() - k + j);
                assert_eq!(got.t_s, f.t_s + lag.lag_s, "{until_s} {j}");
                assert_eq!(got.gyro_rad_s, f.gyro_rad_s, "{until_s} {j}");
            }
        }
    }

    #[test]
    fn the_memory_keeps_the_newest_samples() {
        let mut m = StrideMemory::default();
        let n = MEMORY_SAMPLES + 952;
        for k in 0..n {
            m.push(Remembered {
                t_s: k as f64,
                gyro_rad_s: Vector3::zeros(),
                accel_m_s2: Vector3::zeros(),
                restored_rad_s: Vector3::zeros(),
            });
        }
        assert_eq!(m.len(), MEMORY_SAMPLES);
        assert_eq!(m.get(0).t_s, 952.0);
        assert_eq!(m.get(MEMORY_SAMPLES - 1).t_s, (n - 1) as f64);
        assert_eq!(m.at(1000.4).unwrap().t_s, 1000.0);
        assert_eq!(m.at(1000.6).unwrap().t_s, 1001.0);
        assert_eq!(m.at(-5.0).unwrap().t_s, 952.0);
    }
}
