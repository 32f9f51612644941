//! Zero-velocity (stance) detection: the SHOE, ARE and MV statistics of Skog et al. (2010,
//! "Zero-velocity detection — an algorithm evaluation") over a trailing window, and stance
//! intervals with a minimum length.
//!
//! The window is causal (the last `window` samples), so the decision for a sample never waits
//! for later samples. A stance only counts once it has lasted `min_stance_s`; shorter dips of the
//! statistic are ignored. [`StanceEvents`] joins the stances of one footfall that a short pause
//! of the detector splits (heel strike, then foot flat): the zero-velocity updates stay per
//! sample, the footfall counts once.

use corridor_shared::config::{DetectorConfig, DetectorKind};
use nalgebra::Vector3;

/// Samples between exact recomputations of the window sums.
const RESUM_EVERY: usize = 4096;

/// Blocks of the adaptive threshold's look-back (each `adaptive_window_s / MIN_BLOCKS` long).
const MIN_BLOCKS: usize = 6;

/// The quietest statistic over the last few seconds, in blocks: fixed size, no allocation.
#[derive(Debug, Clone, Copy)]
struct RecentMinimum {
    block_s: f64,
    minima: [f64; MIN_BLOCKS],
    current: usize,
    current_start_s: f64,
    /// The first sample of the look-back's continuous history: since it began, or since the
    /// last step of more than half a block (a loss or a stall: the look-back no longer holds
    /// the whole stride cycle before it, though its blocks still hold what came before).
    since_s: f64,
    /// The last sample's time.
    last_s: f64,
}

impl RecentMinimum {
    fn new(window_s: f64) -> Self {
        Self {
            block_s: window_s / MIN_BLOCKS as f64,
            minima: [f64::INFINITY; MIN_BLOCKS],
            current: 0,
            current_start_s: f64::NAN,
            since_s: f64::NAN,
            last_s: f64::NAN,
        }
    }

    /// The look-back holds a whole window of continuous samples (a stride cycle at least).
    fn full(&self, t_s: f64) -> bool {
        t_s - self.since_s >= self.block_s * MIN_BLOCKS as f64
    }

    fn push(&mut self, t_s: f64, statistic: f64) -> f64 {
        if self.current_start_s.is_nan() {
            self.current_start_s = t_s;
            self.since_s = t_s;
        }
        if t_s - self.last_s > 0.5 * self.block_s {
            self.since_s = t_s;
        }
        self.last_s = t_s;
        // A gap longer than the look-back clears it.
        if t_s - self.current_start_s >= self.block_s * MIN_BLOCKS as f64 {
            self.minima = [f64::INFINITY; MIN_BLOCKS];
            self.current_start_s = t_s;
            self.since_s = t_s;
        }
        while t_s - self.current_start_s >= self.block_s {
            self.current = (self.current + 1) % MIN_BLOCKS;
            self.minima[self.current] = f64::INFINITY;
            self.current_start_s += self.block_s;
        }
        let m = &mut self.minima[self.current];
        *m = m.min(statistic);
        self.minima.iter().copied().fold(f64::INFINITY, f64::min)
    }
}

/// Stance detector state. Allocates its window once, at construction.
#[derive(Debug, Clone)]
pub struct StanceDetector {
    kind: DetectorKind,
    threshold: f64,
    inv_var_a: f64,
    inv_var_g: f64,
    min_stance_s: f64,
    gravity_m_s2: f64,
    gyro: Vec<Vector3<f64>>,
    accel: Vec<Vector3<f64>>,
    next: usize,
    filled: usize,
    /// Running sums over the window: Σa, Σ|a|², Σ|ω|² (recomputed exactly every
    /// `RESUM_EVERY` samples so rounding cannot accumulate).
    sum_a: Vector3<f64>,
    sum_a2: f64,
    sum_w2: f64,
    since_resum: usize,
    raw_since_s: Option<f64>,
    last_statistic: f64,
    /// The threshold the last sample was compared with.
    last_threshold: f64,
    adaptive: Option<(f64, f64, RecentMinimum)>,
}

/// What the detector says about one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StanceDecision {
    /// The statistic (dimensionless, compared with the threshold).
    pub statistic: f64,
    /// The statistic is below the threshold on this sample.
    pub raw: bool,
    /// A stance that has lasted at least the minimum length.
    pub stance: bool,
    /// The foot moves on this sample: a full window whose statistic is at or above the
    /// threshold (not a sample of the first window, of which the detector can say nothing).
    pub moving: bool,
    /// Seconds since the stance began (0 when not in stance).
    pub stance_age_s: f64,
}

impl StanceDetector {
    /// Becomes a copy of `src` in its own windows: no allocation when they are as long (the
    /// estimator's copy before a gap, `before_gap`). Every other field is `Copy`: a new one
    /// that is not must be copied here, or this does not compile.
    pub fn copy_from(&mut self, src: &Self) {
        let (mut gyro, mut accel) = (
            std::mem::take(&mut self.gyro),
            std::mem::take(&mut self.accel),
        );
        gyro.clone_from(&src.gyro);
        accel.clone_from(&src.accel);
        *self = Self {
            gyro,
            accel,
            ..*src
        };
    }

    /// A detector with the given configuration; `gravity_m_s2` is refined by
    /// [`StanceDetector::set_gravity`] after alignment.
    pub fn new(cfg: &DetectorConfig, gravity_m_s2: f64) -> Self {
        let w = cfg.window;
        Self {
            kind: cfg.kind,
            threshold: cfg.threshold.get(),
            inv_var_a: 1.0 / cfg.sigma_accel_m_s2.get().powi(2),
            inv_var_g: 1.0 / cfg.sigma_gyro_rad_s.get().powi(2),
            min_stance_s: cfg.min_stance_s.get(),
            gravity_m_s2,
            gyro: vec![Vector3::zeros(); w],
            accel: vec![Vector3::zeros(); w],
            next: 0,
            filled: 0,
            sum_a: Vector3::zeros(),
            sum_a2: 0.0,
            sum_w2: 0.0,
            since_resum: 0,
            raw_since_s: None,
            last_statistic: f64::INFINITY,
            last_threshold: cfg.threshold.get(),
            adaptive: cfg.adaptive_factor.map(|k| {
                (
                    k.get(),
                    cfg.adaptive_max_threshold.get(),
                    RecentMinimum::new(cfg.adaptive_window_s.get()),
                )
            }),
        }
    }

    /// Recomputes the running sums from the window.
    fn resum(&mut self) {
        let (g, a) = (&self.gyro[..self.filled], &self.accel[..self.filled]);
        self.sum_a = a.iter().sum();
        self.sum_a2 = a.iter().map(|v| v.norm_squared()).sum();
        self.sum_w2 = g.iter().map(|v| v.norm_squared()).sum();
        self.since_resum = 0;
    }

    /// Sets the gravity magnitude used by SHOE.
    pub fn set_gravity(&mut self, gravity_m_s2: f64) {
        self.gravity_m_s2 = gravity_m_s2;
    }

    /// The statistic of the last sample.
    pub fn last_statistic(&self) -> f64 {
        self.last_statistic
    }

    /// The threshold.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// The adaptive threshold lay above the fixed one on the last sample (at `t_s`), over a
    /// whole look-back (not in the first `adaptive_window_s` of a log or after a gap): the
    /// quietest moment of the last stride cycle was not quiet, the gait is fast or varying.
    pub fn raised(&self, t_s: f64) -> bool {
        self.last_threshold > self.threshold
            && self
                .adaptive
                .as_ref()
                .is_some_and(|(_, _, recent)| recent.full(t_s))
    }

    /// Adds one sample and decides.
    pub fn push(
        &mut self,
        t_s: f64,
        gyro_rad_s: &Vector3<f64>,
        accel_m_s2: &Vector3<f64>,
    ) -> StanceDecision {
        let w = self.gyro.len();
        if self.filled == w {
            let (og, oa) = (self.gyro[self.next], self.accel[self.next]);
            self.sum_a -= oa;
            self.sum_a2 -= oa.norm_squared();
            self.sum_w2 -= og.norm_squared();
        }
        self.gyro[self.next] = *gyro_rad_s;
        self.accel[self.next] = *accel_m_s2;
        self.sum_a += accel_m_s2;
        self.sum_a2 += accel_m_s2.norm_squared();
        self.sum_w2 += gyro_rad_s.norm_squared();
        self.next = if self.next + 1 == w { 0 } else { self.next + 1 };
        self.filled = (self.filled + 1).min(w);
        self.since_resum += 1;
        if self.since_resum >= RESUM_EVERY {
            self.resum();
        }
        let n = self.filled as f64;
        let inv_n = 1.0 / n;
        let statistic = match self.kind {
            DetectorKind::Are => self.sum_w2.max(0.0) * self.inv_var_g * inv_n,
            DetectorKind::Mv => {
                // Σ|a − ā|² = Σ|a|² − |Σa|²/n
                (self.sum_a2 - self.sum_a.norm_squared() * inv_n).max(0.0) * self.inv_var_a * inv_n
            }
            DetectorKind::Shoe => {
                // Σ|a − g·ā/|ā||² = Σ|a|² − 2g·|Σa| + n·g²
                let g = self.gravity_m_s2;
                let sa = (self.sum_a2 - 2.0 * g * self.sum_a.norm() + n * g * g).max(0.0);
                (sa * self.inv_var_a + self.sum_w2.max(0.0) * self.inv_var_g) * inv_n
            }
        };
        self.last_statistic = statistic;
        // Fast or varying gait: the foot never stops rotating, and the quietest moment of a
        // stride lies above a fixed threshold. A sample within `factor` of the quietest statistic
        // of the last stride cycle counts too (capped), so the threshold follows the gait.
        let threshold = match &mut self.adaptive {
            Some((factor, max, recent)) => {
                let quietest = recent.push(t_s, statistic);
                self.threshold.max((*factor * quietest).min(*max))
            }
            None => self.threshold,
        };
        self.last_threshold = threshold;
        let full = self.filled == w;
        let raw = full && statistic < threshold;
        if raw {
            self.raw_since_s.get_or_insert(t_s);
        } else {
            self.raw_since_s = None;
        }
        let age = self.raw_since_s.map_or(0.0, |t0| t_s - t0);
        let stance = raw && age >= self.min_stance_s;
        StanceDecision {
            statistic,
            raw,
            stance,
            moving: full && !raw,
            stance_age_s: if stance { age } else { 0.0 },
        }
    }
}

/// What one sample does to the current stance event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StanceEdge {
    /// Nothing new: not a stance sample, or a stance sample right after another.
    None,
    /// A new stance (footfall) begins on this sample.
    Began,
    /// The stance goes on after a pause of at most the merge gap.
    Resumed,
}

/// Stances separated by pauses of at most `merge_gap_s` form one event: after a pause (or a gap
/// in the data: a step longer than `max_step_s`), a stance sample begins a new event when the
/// last stance sample lies more than `merge_gap_s` back, else it continues the current one.
/// Decided on each stance sample, so it adds no latency.
#[derive(Debug, Clone, Copy)]
pub struct StanceEvents {
    merge_gap_s: f64,
    max_step_s: f64,
    was_stance: bool,
    last_s: f64,
    last_stance_s: f64,
    count: u64,
}

impl StanceEvents {
    /// Events that bridge pauses of up to `merge_gap_s` (0: every stance is its own event);
    /// a step longer than `max_step_s` is a gap in the data, not a continuing stance.
    pub fn new(merge_gap_s: f64, max_step_s: f64) -> Self {
        Self {
            merge_gap_s,
            max_step_s,
            was_stance: false,
            last_s: f64::NEG_INFINITY,
            last_stance_s: f64::NEG_INFINITY,
            count: 0,
        }
    }

    /// Events begun so far.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The detector's stance flag of the sample at `t_s`.
    pub fn push(&mut self, t_s: f64, stance: bool) -> StanceEdge {
        let gap_in_data = t_s - std::mem::replace(&mut self.last_s, t_s) > self.max_step_s;
        let was = std::mem::replace(&mut self.was_stance, stance) && !gap_in_data;
        if !stance {
            return StanceEdge::None;
        }
        let edge = if was {
            StanceEdge::None
        } else if t_s - self.last_stance_s > self.merge_gap_s {
            self.count += 1;
            StanceEdge::Began
        } else {
            StanceEdge::Resumed
        };
        self.last_stance_s = t_s;
        edge
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use corridor_shared::config::Config;

    #[test]
    fn static_is_stance_and_rotation_is_not() {
        let cfg = Config::default().detector;
        let mut d = StanceDetector::new(&cfg, 9.81);
        let g = Vector3::new(0.0, 0.0, 9.81);
        let mut last = None;
        for i in 0..100 {
            last = Some(d.push(i as f64 * 0.005, &Vector3::zeros(), &g));
        }
        let last = last.unwrap();
        assert!(last.stance && last.stance_age_s > 0.3);
        let moving = d.push(0.5, &Vector3::new(0.0, 3.0, 0.0), &g);
        assert!(!moving.raw && !moving.stance && moving.stance_age_s == 0.0);
    }

    #[test]
    fn running_sums_equal_the_window_formulas() {
        for kind in [DetectorKind::Shoe, DetectorKind::Are, DetectorKind::Mv] {
            let mut cfg = Config::default().detector;
            cfg.kind = kind;
            let mut d = StanceDetector::new(&cfg, 9.81);
            let mut hist = Vec::new();
            for i in 0..10_000 {
                let t = i as f64 * 0.005;
                let w = Vector3::new((t * 3.0).sin(), 0.2 * (t * 7.0).cos(), 0.01 * t.sin());
                let a = Vector3::new(0.3 * (t * 5.0).sin(), 0.1, 9.81 + 0.5 * (t * 2.0).cos());
                hist.push((w, a));
                let got = d.push(t, &w, &a).statistic;
                let win = &hist[hist.len().saturating_sub(cfg.window)..];
                let n = win.len() as f64;
                let mean: Vector3<f64> = win.iter().map(|x| x.1).sum::<Vector3<f64>>() / n;
                let sa: f64 = match kind {
                    DetectorKind::Mv => win.iter().map(|x| (x.1 - mean).norm_squared()).sum(),
                    _ => win
                        .iter()
                        .map(|x| (x.1 - mean.normalize() * 9.81).norm_squared())
                        .sum(),
                };
                let sg: f64 = win.iter().map(|x| x.0.norm_squared()).sum();
                let want = match kind {
                    DetectorKind::Shoe => {
                        (sa / cfg.sigma_accel_m_s2.get().powi(2)
                            + sg / cfg.sigma_gyro_rad_s.get().powi(2))
                            / n
                    }
                    DetectorKind::Are => sg / cfg.sigma_gyro_rad_s.get().powi(2) / n,
                    DetectorKind::Mv => sa / cfg.sigma_accel_m_s2.get().powi(2) / n,
                };
                assert!(
                    (got - want).abs() <= 1e-6 * want.abs().max(1.0),
                    "{kind:?} at {i}: {got} vs {want}"
                );
            }
        }
    }

    /// A fast gait: 0.3 s "stances" that still rotate at 0.8 rad/s between 0.5 s swings at
    /// 6 rad/s. The fixed threshold (about 0.55 rad/s) finds none; the adaptive one finds each.
    #[test]
    fn the_adaptive_threshold_follows_a_gait_that_never_stops_rotating() {
        let g = Vector3::new(0.0, 0.0, 9.81);
        let count = |adaptive: bool| {
            let mut cfg = Config::default().detector;
            if adaptive {
                cfg.adaptive_factor =
                    Some(corridor_shared::config::Positive::new("f", 3.0).unwrap());
                cfg.adaptive_max_threshold =
                    corridor_shared::config::Positive::new("m", 3e5).unwrap();
            }
            let mut d = StanceDetector::new(&cfg, 9.81);
            let (mut stances, mut was) = (0, false);
            for i in 0..1600 {
                let t = i as f64 * 0.005;
                let phase = t % 0.8;
                let w = if phase < 0.3 { 0.8 } else { 6.0 };
                let now = d.push(t, &Vector3::new(0.0, w, 0.0), &g).stance;
                stances += usize::from(now && !was);
                was = now;
            }
            stances
        };
        assert_eq!(count(false), 0);
        // 10 cycles; the first needs one stride of history.
        assert!((9..=10).contains(&count(true)), "{}", count(true));
    }

    /// A gait that never stops rotating (0.8 rad/s "stances", 6 rad/s swings, 0.8 s cycles):
    /// the threshold is raised by the gait, and `raised` says so once the look-back holds a
    /// whole window (1.5 s) of continuous samples: not in the first 1.5 s, and not again until
    /// 1.5 s after a 0.3 s loss, which leaves the look-back's blocks holding the stride before.
    #[test]
    fn raised_needs_a_whole_look_back_of_continuous_samples() {
        let g = Vector3::new(0.0, 0.0, 9.81);
        let mut cfg = Config::default().detector;
        cfg.adaptive_factor = Some(corridor_shared::config::Positive::new("f", 3.0).unwrap());
        cfg.adaptive_max_threshold = corridor_shared::config::Positive::new("m", 3e5).unwrap();
        cfg.adaptive_window_s = corridor_shared::config::Positive::new("w", 1.5).unwrap();
        let mut d = StanceDetector::new(&cfg, 9.81);
        let mut raised_at = Vec::new();
        let mut moving = 0;
        for i in 0..1600 {
            // 0.3 s lost from 4.0 s.
            if (800..860).contains(&i) {
                continue;
            }
            let t = i as f64 * 0.005;
            let w = if t % 0.8 < 0.3 { 0.8 } else { 6.0 };
            let decision = d.push(t, &Vector3::new(0.0, w, 0.0), &g);
            moving += usize::from(decision.moving);
            if d.raised(t) {
                raised_at.push(t);
            }
        }
        assert!(moving > 0);
        let first = raised_at[0];
        assert!((1.5..2.0).contains(&first), "first raised at {first}");
        // Nothing between the loss and a whole look-back after it.
        assert!(
            raised_at.iter().all(|&t| !(4.0..5.8).contains(&t)),
            "raised at {:?}",
            raised_at.iter().find(|&&t| (4.0..5.8).contains(&t))
        );
        assert!(raised_at.iter().any(|&t| t >= 5.8));
    }

    #[test]
    fn a_short_pause_does_not_split_a_stance_but_a_swing_or_a_gap_does() {
        let mut e = StanceEvents::new(0.3, 0.05);
        // stance 0–0.1 s, pause 0.1–0.3 s, stance 0.3–0.4 s, swing 0.4–0.8 s, stance from 0.8 s
        let stance_at = |t: f64| t < 0.1 || (0.3..0.4).contains(&t) || t >= 0.8;
        let edges: Vec<(usize, StanceEdge)> = (0..200)
            .map(|i| (i, e.push(i as f64 * 0.005, stance_at(i as f64 * 0.005))))
            .filter(|(_, x)| *x != StanceEdge::None)
            .collect();
        assert_eq!(
            edges,
            vec![
                (0, StanceEdge::Began),
                (60, StanceEdge::Resumed),
                (160, StanceEdge::Began)
            ]
        );
        assert_eq!(e.count(), 2);
        // After a gap in the data longer than the merge gap a stance sample begins a new
        // stance, whether the sample before the gap was stance or not.
        assert_eq!(e.push(0.995, true), StanceEdge::None);
        assert_eq!(e.push(1.5, true), StanceEdge::Began);
        assert_eq!(e.push(1.505, false), StanceEdge::None);
        assert_eq!(e.push(3.0, true), StanceEdge::Began);
        // Without merging the pause splits it.
        let mut e = StanceEvents::new(0.0, 0.05);
        let began = (0..200)
            .filter(|&i| e.push(i as f64 * 0.005, stance_at(i as f64 * 0.005)) == StanceEdge::Began)
            .count();
        assert_eq!(began, 3);
    }

    #[test]
    fn short_dips_are_not_stances() {
        let cfg = Config::default().detector; // min 0.04 s
        let mut d = StanceDetector::new(&cfg, 9.81);
        let g = Vector3::new(0.0, 0.0, 9.81);
        let spin = Vector3::new(2.0, 0.0, 0.0);
        for i in 0..20 {
            d.push(i as f64 * 0.005, &spin, &g);
        }
        // 6 quiet samples = 0.025 s after the window fills: too short
        let mut any = false;
        for i in 20..31 {
            any |= d.push(i as f64 * 0.005, &Vector3::zeros(), &g).stance;
        }
        assert!(!any);
    }
}
