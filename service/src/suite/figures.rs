//! What the suite measures on the default run besides the footprint error: the NIS of each
//! update type against its band, the use of heading information on straight and weave strides,
//! the stances found against the footprint list, and the stride-length ratio.

use crate::runner;
use corridor_shared::truth_csv::TruthPoint;
use serde::Serialize;

/// Detected stances against the footprint list: a listed footprint (the end of its stance)
/// is found when a detected stance ends within [`STANCE_MATCH_S`] of it.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct StanceMatch {
    /// Listed footprints.
    pub listed: usize,
    /// Of them, found.
    pub found: usize,
    /// Detected stances within the listed span.
    pub detected: usize,
    /// Of them, matching a listed footprint.
    pub matching: usize,
    /// Listed footprints not found whose footfall was still detected: a detected stance ends
    /// more than [`STANCE_MATCH_S`] from it but nearer than half the way to a neighbouring
    /// footprint (the end placed differently, not a missed footfall).
    pub timing: usize,
    /// Detected stances that are no listed footprint's nearest (within the same limits): extra
    /// stances, not a footfall's stance with its end placed differently.
    pub extra: usize,
    /// Median of (detected − listed) stance end over the found footprints, s (NaN: none).
    pub median_end_offset_s: f64,
    /// Listed footprints whose stance end the data set's authors placed by hand (the
    /// recording's `hand_placed_strides`).
    pub hand_placed: usize,
    /// Of the hand-placed ones, found.
    pub hand_placed_found: usize,
}

/// Largest distance between a detected and a listed stance end, s.
pub const STANCE_MATCH_S: f64 = 0.05;

impl StanceMatch {
    /// `truth` against the `stances` (first, last sample, s); `hand_placed`: the strides (the
    /// truth's `stride` column) whose listed end was placed by hand.
    pub(super) fn of(truth: &[TruthPoint], stances: &[(f64, f64)], hand_placed: &[u32]) -> Self {
        let (t0, t1) = match (truth.first(), truth.last()) {
            (Some(a), Some(b)) => (a.t_s - STANCE_MATCH_S, b.t_s + STANCE_MATCH_S),
            _ => return Self::default(),
        };
        let near = |a: f64, b: f64| (a - b).abs() <= STANCE_MATCH_S;
        let detected: Vec<f64> = stances
            .iter()
            .map(|s| s.1)
            .filter(|&e| e >= t0 && e <= t1)
            .collect();
        // Each listed footprint takes the detected stance end nearest to it, if that lies
        // closer than half the way to a neighbouring footprint (the same footfall).
        let assigned: Vec<Option<(usize, f64)>> = truth
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let half_gap = [i.checked_sub(1), Some(i + 1)]
                    .into_iter()
                    .flatten()
                    .filter_map(|j| truth.get(j))
                    .map(|q| 0.5 * (q.t_s - p.t_s).abs())
                    .fold(f64::INFINITY, f64::min);
                detected
                    .iter()
                    .enumerate()
                    .map(|(k, &e)| (k, e - p.t_s))
                    .min_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
                    .filter(|&(_, d)| d.abs() < half_gap || d.abs() <= STANCE_MATCH_S)
            })
            .collect();
        let mut offsets: Vec<f64> = assigned
            .iter()
            .flatten()
            .map(|&(_, d)| d)
            .filter(|d| d.abs() <= STANCE_MATCH_S)
            .collect();
        let timing = assigned.iter().flatten().count() - offsets.len();
        let by_hand = |p: &TruthPoint| {
            p.stride
                .is_some_and(|s| hand_placed.iter().any(|&h| i64::from(h) == s))
        };
        let hand: Vec<bool> = truth
            .iter()
            .zip(&assigned)
            .filter(|(p, _)| by_hand(p))
            .map(|(_, a)| a.is_some_and(|(_, d)| d.abs() <= STANCE_MATCH_S))
            .collect();
        let mut owners: Vec<usize> = assigned.iter().flatten().map(|&(k, _)| k).collect();
        owners.sort_unstable();
        owners.dedup();
        Self {
            listed: truth.len(),
            found: offsets.len(),
            detected: detected.len(),
            matching: detected
                .iter()
                .filter(|&&e| truth.iter().any(|p| near(e, p.t_s)))
                .count(),
            timing,
            extra: detected.len() - owners.len(),
            median_end_offset_s: super::tables::median(&mut offsets),
            hand_placed: hand.len(),
            hand_placed_found: hand.iter().filter(|&&f| f).count(),
        }
    }

    /// Listed footprints with no detected stance ending nearer than half the way to a
    /// neighbouring footprint: footfalls missed.
    pub fn missed(&self) -> usize {
        self.listed - self.found - self.timing
    }

    /// Found / listed.
    pub fn recall(&self) -> f64 {
        self.found as f64 / self.listed.max(1) as f64
    }

    /// Matching / detected.
    pub fn precision(&self) -> f64 {
        self.matching as f64 / self.detected.max(1) as f64
    }
}

/// Stances as (first, last stance sample) intervals, s, from each sample's "a new stance
/// begins" and "stance" flags; the last one may still be open. A footfall the detector missed
/// and the estimator updated late is one too, at its quietest sample (it lies after the last
/// stance: none within `detector.merge_gap_s` of it).
#[derive(Debug, Default)]
pub(super) struct StanceIntervals(Vec<(f64, f64)>);

impl StanceIntervals {
    pub(super) fn push(&mut self, t_s: f64, began: bool, stance: bool, late: Option<f64>) {
        if let Some(t) = late {
            self.0.push((t, t));
        }
        if began {
            self.0.push((t_s, t_s));
        }
        if let (true, Some(last)) = (stance, self.0.last_mut()) {
            last.1 = t_s;
        }
    }

    pub(super) fn get(&self) -> &[(f64, f64)] {
        &self.0
    }
}

/// Summed distances between the run's positions at the truth footprints over the surveyed
/// distances.
pub(super) fn stride_ratio(trace: &runner::Trace, truth: &[TruthPoint]) -> f64 {
    let at = |t: f64| {
        let i = trace
            .t_s
            .partition_point(|&x| x < t)
            .min(trace.t_s.len().saturating_sub(1));
        trace.xy_m.get(i).copied().unwrap_or([f64::NAN; 2])
    };
    let (mut est, mut sur) = (0.0, 0.0);
    for w in truth.windows(2) {
        let (a, b) = (at(w[0].t_s), at(w[1].t_s));
        est += (b[0] - a[0]).hypot(b[1] - a[1]);
        sur += (w[1].x_m - w[0].x_m).hypot(w[1].y_m - w[0].y_m);
    }
    est / sur
}

/// What the suite measures on the default run besides the footprint error.
pub(super) struct DefaultFigures {
    pub(super) nis: [Option<NisFigure>; 3],
    pub(super) stride_use: Option<StrideUse>,
    pub(super) stride_ratio: f64,
    pub(super) stances_found: Option<StanceMatch>,
}

/// The mean NIS of one update type against its two-sided 95 % χ² band.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct NisFigure {
    /// Mean NIS per degree of freedom.
    pub mean: f64,
    /// Lower bound of the band, per degree of freedom.
    pub lower: f64,
    /// Upper bound of the band, per degree of freedom.
    pub upper: f64,
    /// Updates.
    pub n: usize,
}

impl NisFigure {
    fn of(nis: &[f64], dof: usize) -> Option<Self> {
        let t = crate::stats::nis_consistency(nis, dof, 0.95).ok()?;
        let d = dof as f64;
        Some(Self {
            mean: t.mean / d,
            lower: t.lower / d,
            upper: t.upper / d,
            n: t.n,
        })
    }

    /// Whether the mean lies inside the band.
    pub fn in_band(&self) -> bool {
        (self.lower..=self.upper).contains(&self.mean)
    }
}

/// How the default run used heading information on the strides of a walk whose every
/// footprint is surveyed. A truth stride lies on a *straight stretch* when it and both
/// neighbours point within [`STRAIGHT_DEG`] of one dominant direction; it is a *weave* when it
/// points more than [`WEAVE_DEG`] off the dominant direction that both neighbours follow (within
/// [`WEAVE_DEG`]). Turns are neither.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct StrideUse {
    /// Straight-stretch strides.
    pub straight: usize,
    /// Of them, strides whose stance used a stride-direction or foot-axis observation.
    pub straight_used: usize,
    /// Weave strides.
    pub weave: usize,
    /// Of them, strides whose direction was used as a stride-direction observation.
    pub weave_used: usize,
    /// Of them, strides whose stance used the foot axis (in a side-step the foot may still
    /// point along the corridor: not an error in itself).
    pub weave_foot_used: usize,
}

/// Largest deviation from the dominant direction of a straight-stretch stride, degrees.
pub const STRAIGHT_DEG: f64 = 5.0;
/// Smallest deviation of a weave stride, degrees.
pub const WEAVE_DEG: f64 = 10.0;

impl StrideUse {
    /// Classifies the truth strides (grid spacing `step_rad` from `grid_rad`) and counts the
    /// stances (time, heading information used) of the run that fall in each stride's window
    /// (after the previous footprint, up to its own). `None` unless every stride is surveyed.
    pub(super) fn of(
        truth: &[TruthPoint],
        grid_rad: f64,
        step_rad: f64,
        stances: &[StanceUse],
    ) -> Option<Self> {
        let every = truth.windows(2).all(|w| match (w[0].stride, w[1].stride) {
            (Some(a), Some(b)) => b == a + 1,
            _ => false,
        });
        if !every || truth.len() < 4 {
            return None;
        }
        let wrap = crate::core::rotation::wrap_pi;
        // (time of the footprint ending the stride, nearest dominant direction index, deviation)
        let strides: Vec<(f64, f64, i64, f64)> = truth
            .windows(2)
            .map(|w| {
                let d = (w[1].y_m - w[0].y_m).atan2(w[1].x_m - w[0].x_m);
                let k = ((d - grid_rad) / step_rad).round();
                let dev = wrap(d - grid_rad - k * step_rad).abs().to_degrees();
                let n = (std::f64::consts::TAU / step_rad).round() as i64;
                (w[0].t_s, w[1].t_s, (k as i64).rem_euclid(n.max(1)), dev)
            })
            .collect();
        let mut u = StrideUse::default();
        for i in 1..strides.len().saturating_sub(1) {
            let (prev, cur, next) = (strides[i - 1], strides[i], strides[i + 1]);
            let straight = [prev, cur, next]
                .iter()
                .all(|s| s.2 == cur.2 && s.3 <= STRAIGHT_DEG);
            let weave = prev.2 == next.2
                && prev.3 <= WEAVE_DEG
                && next.3 <= WEAVE_DEG
                && (cur.2 != prev.2 || cur.3 > WEAVE_DEG);
            if !(straight || weave) {
                continue;
            }
            let inside = |t_s: f64| t_s > cur.0 && t_s <= cur.1;
            let stride = stances.iter().any(|s| s.stride && inside(s.stride_t_s));
            let foot = stances.iter().any(|s| s.foot_axis && inside(s.t_s));
            if straight {
                u.straight += 1;
                u.straight_used += usize::from(stride || foot);
            } else {
                u.weave += 1;
                u.weave_used += usize::from(stride);
                u.weave_foot_used += usize::from(foot);
            }
        }
        Some(u)
    }
}

/// One stance's use of heading information.
#[derive(Debug, Clone, Copy)]
pub(super) struct StanceUse {
    t_s: f64,
    /// The end of the stride observed (earlier than `t_s` for a stride observed one stance
    /// late).
    stride_t_s: f64,
    stride: bool,
    foot_axis: bool,
}

/// The NIS of one run, by update type, and its stances with the use of heading information.
#[derive(Debug, Default)]
pub(super) struct NisSeries {
    zupt_first: Vec<f64>,
    stride: Vec<f64>,
    heading: Vec<f64>,
    in_stance: bool,
    pub(super) stances: Vec<StanceUse>,
    /// The stances the estimator found.
    intervals: StanceIntervals,
}

impl NisSeries {
    pub(super) fn push(&mut self, e: &crate::core::Estimate) {
        self.intervals
            .push(e.t_s, e.stance_began, e.stance, e.late_footfall_t_s);
        match &e.zupt {
            Some(z) if !self.in_stance => {
                self.zupt_first.push(z.nis);
                self.in_stance = true;
            }
            Some(_) => {}
            None => self.in_stance = false,
        }
        let mut used = [false; 2];
        for (k, (h, v)) in [
            (&e.stride, &mut self.stride),
            (&e.heading, &mut self.heading),
        ]
        .into_iter()
        .enumerate()
        {
            if let Some(Ok(i)) = h.as_ref().map(|h| h.outcome) {
                v.push(i.nis);
                used[k] = true;
            }
        }
        if e.stride.is_some() || e.heading.is_some() {
            self.stances.push(StanceUse {
                t_s: e.t_s,
                stride_t_s: e.stride.as_ref().map_or(e.t_s, |s| s.observed_t_s),
                stride: used[0],
                foot_axis: used[1],
            });
        }
    }

    /// The stances the estimator found: (first, last stance sample), s.
    pub(super) fn intervals(&self) -> &[(f64, f64)] {
        self.intervals.get()
    }

    pub(super) fn figures(&self) -> [Option<NisFigure>; 3] {
        [
            NisFigure::of(&self.zupt_first, 3),
            NisFigure::of(&self.stride, 1),
            NisFigure::of(&self.heading, 1),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn footprints(times: &[f64]) -> Vec<TruthPoint> {
        times
            .iter()
            .zip(0..)
            .map(|(&t_s, stride)| TruthPoint {
                t_s,
                x_m: 0.0,
                y_m: 0.0,
                z_m: 0.0,
                stride: Some(stride),
                sample_index: None,
            })
            .collect()
    }

    #[test]
    fn misses_are_told_apart_from_late_stance_ends() {
        // Footprints at 1, 2, 3, 4 s. Stances: ending 20 ms late at 1 s, 30 ms early at 2 s,
        // one around 3 s that ends 200 ms late (its footfall found, its end not), none near
        // 4 s (missed), and an extra one ending at 3.45 s.
        let truth = footprints(&[1.0, 2.0, 3.0, 4.0]);
        let stances = [(0.7, 1.02), (1.6, 1.97), (2.8, 3.2), (3.4, 3.45)];
        let m = StanceMatch::of(&truth, &stances, &[]);
        assert_eq!((m.listed, m.found, m.timing, m.missed()), (4, 2, 1, 1));
        assert_eq!((m.hand_placed, m.hand_placed_found), (0, 0));
        // Strides 1 and 2 (at 2 and 3 s) placed by hand: the first found, the second not (its
        // end 200 ms off); stride 3 (missed) is not among them.
        let m = StanceMatch::of(&truth, &stances, &[1, 2]);
        assert_eq!((m.hand_placed, m.hand_placed_found), (2, 1));
        assert_eq!((m.listed, m.found), (4, 2));
        assert_eq!((m.detected, m.matching, m.extra), (4, 2, 1));
        // Median of +20 and −30 ms.
        assert!(
            (m.median_end_offset_s + 0.005).abs() < 1e-12,
            "{}",
            m.median_end_offset_s
        );
        assert!((m.recall() - 0.5).abs() < 1e-12 && (m.precision() - 0.5).abs() < 1e-12);
    }
}
