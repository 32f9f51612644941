//! The accelerometer's scale held against gravity while walking: the median specific force of
//! the last quiet stances.
//!
//! The alignment takes gravity from the initial rest's own specific force, so an accelerometer
//! whose scale is wrong by 20 % aligns with a "gravity" 20 % off and walks strides 20 % off,
//! with nothing looking wrong inside the filter (exp36 scaled by 0.8: footprint RMS 5.5 % of
//! path against 0.26 %, by 0.6: 11 %). Only the number itself says it: on Earth the foot flat
//! on the floor reads 9.78–9.83 m/s². A single stance reads its push-off and landing too (the
//! whole stances of the fast exp38 read up to 12.8 m/s²), so the check takes the samples of
//! each stance that turn slower than [`QUIET_RATE_RAD_S`], and the median over the last
//! [`STANCES`] such stances. On the 16 gdins walks (the default run's stances) that median lies
//! within 9.73–9.90 m/s² at every sample (−0.8 to +1.0 %; the NGIMU walk 9.75–9.76); it is held
//! to [`SPECIFIC_FORCE_TOLERANCE`].
//!
//! The initial rest the filter aligns on is held to the same tolerance at once ([`StanceForce::
//! rest`]): standing still, the foot reads gravity to the accelerometer's scale error, so a walk
//! that starts with a rest is told at its first step, not fifteen quiet stances later (which a
//! fast walk may never have: exp34 keeps 7 of its 25 stances).

use nalgebra::Vector3;

/// Stance samples turning slower than this count (rad/s): the foot flat, not its landing or
/// push-off. At 0.5 rad/s the fast walks keep 7 (exp34) and 17 (exp38) of their 25 and 61
/// stances; with every stance sample, exp38's median of 15 reached 11.7 m/s².
pub const QUIET_RATE_RAD_S: f64 = 0.5;

/// A stance counts with at least this long of quiet samples, s, to half a sample step (five
/// samples at 200 Hz, three at 100 Hz: a count of samples left 100 Hz logs of the fast walks
/// without a median).
pub const MIN_QUIET_S: f64 = 0.025;

/// The median is over this many stances: a few odd ones (a stance on a step, a stamp) do not
/// move it.
pub const STANCES: usize = 15;

/// How far (a fraction) that median may lie from gravity: beyond it the accelerometer's scale
/// (or its units) is wrong, and distances are wrong by as much. An accelerometer's scale error
/// is a fraction of a percent; the suite's medians lie within −0.8 to +1.0 %, the NGIMU walk's
/// rests within ±2 %.
pub const SPECIFIC_FORCE_TOLERANCE: f64 = 0.05;

/// What read the specific force that was said off gravity.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ForceWitness {
    /// The initial rest the filter aligned on (its mean over the blocks in which the foot
    /// stood still).
    InitialRest,
    /// The median of the last [`STANCES`] quiet stances.
    QuietStances,
}

/// A specific force said off gravity: what read it, and the gravity it was held against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OffGravity {
    /// The rest's mean or the stances' median, m/s².
    pub force_m_s2: f64,
    /// The gravity it should read (`alignment.gravity_m_s2`, else standard gravity), m/s².
    pub gravity_m_s2: f64,
    /// What read it.
    pub witness: ForceWitness,
}

/// The running check. Fixed size, no allocation.
#[derive(Debug, Clone, Copy)]
pub(super) struct StanceForce {
    /// Sum of |f| over the current stance's quiet samples, their number and duration (s).
    sum_m_s2: f64,
    quiet: u32,
    quiet_s: f64,
    /// Mean |f| of the last [`STANCES`] stances (a ring), and how many it holds.
    means_m_s2: [f64; STANCES],
    len: usize,
    next: usize,
    /// The mean specific force of the initial rest the filter aligned on (NaN before, or
    /// without a rest).
    rest_m_s2: f64,
    /// What said the specific force off gravity (the rest or the median lies beyond the
    /// tolerance, reported); it is reported again only after the median came back within half
    /// the tolerance.
    said: Option<ForceWitness>,
}

impl Default for StanceForce {
    fn default() -> Self {
        Self {
            sum_m_s2: 0.0,
            quiet: 0,
            quiet_s: 0.0,
            means_m_s2: [f64::NAN; STANCES],
            len: 0,
            next: 0,
            rest_m_s2: f64::NAN,
            said: None,
        }
    }
}

impl StanceForce {
    /// One sample of `dt_s` that the running step took: whether the foot stands, its rate `w`
    /// (rad/s) and specific force `f` (m/s²). A stance sample turning slower than
    /// [`QUIET_RATE_RAD_S`] is summed (per sample: a comparison of squares, and one root for
    /// the quiet ones); the first sample after a stance closes it against `gravity_m_s2()`.
    /// Returns the median and that gravity when the median has just left the tolerance (once,
    /// until it comes back; not while the rest's word that it is off stands).
    #[inline]
    pub(super) fn sample(
        &mut self,
        dt_s: f64,
        stance: bool,
        w: &Vector3<f64>,
        f: &Vector3<f64>,
        gravity_m_s2: impl FnOnce() -> f64,
    ) -> Option<OffGravity> {
        if stance {
            if w.norm_squared() < QUIET_RATE_RAD_S * QUIET_RATE_RAD_S {
                let force_m_s2 = f.norm();
                if force_m_s2.is_finite() {
                    self.sum_m_s2 += force_m_s2;
                    self.quiet += 1;
                    self.quiet_s += dt_s;
                }
            }
            return None;
        }
        if self.quiet == 0 {
            return None;
        }
        let g = gravity_m_s2();
        self.stance_ended(g).map(|median| OffGravity {
            force_m_s2: median,
            gravity_m_s2: g,
            witness: ForceWitness::QuietStances,
        })
    }

    /// The stance whose samples were summed has ended; `gravity_m_s2` is what it should read.
    /// Returns the median when it has just left the tolerance (once, until it comes back).
    /// Out of line: once per stance.
    #[inline(never)]
    fn stance_ended(&mut self, gravity_m_s2: f64) -> Option<f64> {
        let (sum, quiet, quiet_s) = (self.sum_m_s2, self.quiet, self.quiet_s);
        (self.sum_m_s2, self.quiet, self.quiet_s) = (0.0, 0, 0.0);
        // To half a sample step: the stamps jitter (exp38's steps run 4.990–5.013 ms, and five
        // quiet samples summed to 24.99 ms: a review), and a stance of five samples counts.
        if quiet_s + 0.5 * quiet_s / f64::from(quiet) < MIN_QUIET_S {
            return None;
        }
        self.means_m_s2[self.next] = sum / f64::from(quiet);
        self.next = (self.next + 1) % STANCES;
        self.len = (self.len + 1).min(STANCES);
        let median = self.median_m_s2()?;
        let off = (median - gravity_m_s2).abs() / gravity_m_s2;
        if self.said.is_none() && off > SPECIFIC_FORCE_TOLERANCE {
            self.said = Some(ForceWitness::QuietStances);
            return Some(median);
        }
        if self.said.is_some() && off < 0.5 * SPECIFIC_FORCE_TOLERANCE {
            self.said = None;
        }
        None
    }

    /// The initial rest the filter aligned on read `force_m_s2` (its mean over its still
    /// blocks) where gravity is `gravity_m_s2`: beyond the tolerance it is said at once (true),
    /// and the stances say it again only once their median has come back within half the
    /// tolerance and left it again.
    pub(super) fn rest(&mut self, force_m_s2: f64, gravity_m_s2: f64) -> bool {
        self.rest_m_s2 = force_m_s2;
        let off = (force_m_s2 - gravity_m_s2).abs() > SPECIFIC_FORCE_TOLERANCE * gravity_m_s2;
        if off && self.said.is_none() {
            self.said = Some(ForceWitness::InitialRest);
            return true;
        }
        false
    }

    /// The initial rest's mean specific force, m/s², once the filter aligned on a rest.
    pub(super) fn rest_m_s2(&self) -> Option<f64> {
        Some(self.rest_m_s2).filter(|f| f.is_finite())
    }

    /// Whether the rest or the median is off gravity now (said, and the median not back within
    /// half the tolerance).
    pub(super) fn is_off(&self) -> bool {
        self.said.is_some()
    }

    /// What said it, while it is off gravity ([`StanceForce::is_off`]).
    pub(super) fn said_by(&self) -> Option<ForceWitness> {
        self.said
    }

    /// Takes `said`'s word on whether the median was said off gravity: for a pipeline put back
    /// to a copy from before samples whose estimates went out (a glitched stamp's).
    pub(super) fn keep_said(&mut self, said: &StanceForce) {
        self.said = said.said;
    }

    /// The median |f| of the last [`STANCES`] quiet stances, m/s², once there are that many.
    pub(super) fn median_m_s2(&self) -> Option<f64> {
        if self.len < STANCES {
            return None;
        }
        let mut m = self.means_m_s2;
        m.sort_unstable_by(f64::total_cmp);
        Some(m[STANCES / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f64 = 9.80665;

    const DT: f64 = 0.005;

    /// One sample as the running step gives it: |ω| `rate` and |f| `force`; the median when
    /// said.
    fn sample(
        check: &mut StanceForce,
        dt: f64,
        stance: bool,
        rate: f64,
        force: f64,
    ) -> Option<f64> {
        let (w, f) = (Vector3::new(0.0, rate, 0.0), Vector3::new(0.0, 0.0, force));
        check.sample(dt, stance, &w, &f, || G).map(|said| {
            assert_eq!(said.gravity_m_s2, G);
            assert_eq!(said.witness, ForceWitness::QuietStances);
            said.force_m_s2
        })
    }

    /// `n` stances of `quiet` samples at |f| = `f` (and a swing sample after each), 200 Hz;
    /// the medians reported.
    fn walk(check: &mut StanceForce, n: usize, quiet: u32, f: f64) -> Vec<f64> {
        let mut said = Vec::new();
        for _ in 0..n {
            for _ in 0..quiet {
                assert_eq!(sample(check, DT, true, 0.1, f), None);
            }
            // A landing and a push-off: turning fast, reading far more.
            sample(check, DT, true, 2.0, 3.0 * f);
            said.extend(sample(check, DT, false, 5.0, 20.0));
        }
        said
    }

    #[test]
    fn a_scale_error_is_said_once_after_the_stances_it_needs() {
        let mut check = StanceForce::default();
        // 14 stances: no verdict yet.
        assert!(walk(&mut check, STANCES - 1, 20, 0.8 * G).is_empty());
        assert_eq!(check.median_m_s2(), None);
        // The 15th: the median of the quiet samples only (the landing's 3 g left out).
        let said = walk(&mut check, 1, 20, 0.8 * G);
        assert_eq!(said.len(), 1);
        assert!((said[0] - 0.8 * G).abs() < 1e-12, "{said:?}");
        // Said once while it stays off.
        assert!(walk(&mut check, 30, 20, 0.8 * G).is_empty());
    }

    #[test]
    fn gravity_within_the_tolerance_is_not_said() {
        let mut check = StanceForce::default();
        for f in [0.96 * G, 1.04 * G, G] {
            assert!(walk(&mut check, 2 * STANCES, 20, f).is_empty(), "{f}");
        }
        // A few odd stances do not move the median.
        assert!(walk(&mut check, STANCES / 2, 20, 2.0 * G).is_empty());
        assert!(walk(&mut check, STANCES, 20, G).is_empty());
    }

    #[test]
    fn stances_without_enough_quiet_samples_do_not_count() {
        // 25 ms at 200 Hz: five samples count, four do not.
        let mut check = StanceForce::default();
        assert!(walk(&mut check, 5 * STANCES, 4, 0.5 * G).is_empty());
        assert_eq!(check.median_m_s2(), None);
        assert_eq!(walk(&mut check, STANCES, 5, 0.5 * G).len(), 1);
        assert!(check.is_off());
    }

    #[test]
    fn the_quiet_time_counts_not_the_samples() {
        // At 100 Hz three quiet samples are 30 ms: a stance (five samples were asked before,
        // and the fast walks at 100 Hz had no median).
        let mut check = StanceForce::default();
        let mut said = Vec::new();
        for _ in 0..STANCES {
            for _ in 0..3 {
                assert_eq!(sample(&mut check, 0.01, true, 0.1, 0.5 * G), None);
            }
            said.extend(sample(&mut check, 0.01, false, 5.0, 20.0));
        }
        assert_eq!(said.len(), 1);
    }

    #[test]
    fn five_samples_count_at_200_hz_whatever_the_jitter_of_their_stamps() {
        let mut check = StanceForce::default();
        let mut said = Vec::new();
        for k in 0..STANCES {
            for j in 0..5 {
                let dt = 0.005 + if (j + k) % 2 == 0 { -1e-5 } else { 1e-6 };
                assert_eq!(sample(&mut check, dt, true, 0.1, 0.5 * G), None);
            }
            said.extend(sample(&mut check, 0.005, false, 5.0, 20.0));
        }
        assert_eq!(said.len(), 1);
        // Four do not.
        let mut check = StanceForce::default();
        for _ in 0..STANCES {
            for _ in 0..4 {
                sample(&mut check, 0.00501, true, 0.1, 0.5 * G);
            }
            assert_eq!(sample(&mut check, 0.005, false, 5.0, 20.0), None);
        }
    }

    #[test]
    fn a_rest_off_gravity_is_said_at_once_and_the_stances_do_not_say_it_again() {
        let mut check = StanceForce::default();
        assert_eq!(check.rest_m_s2(), None);
        assert!(check.rest(0.8 * G, G));
        assert_eq!(check.rest_m_s2(), Some(0.8 * G));
        assert_eq!(check.said_by(), Some(ForceWitness::InitialRest));
        // The stances read the same: the same episode, the rest's.
        assert!(walk(&mut check, 2 * STANCES, 20, 0.8 * G).is_empty());
        assert_eq!(check.said_by(), Some(ForceWitness::InitialRest));
        // Back to gravity, then off again: said by the stances.
        assert!(walk(&mut check, STANCES, 20, G).is_empty());
        assert!(!check.is_off() && check.said_by().is_none());
        assert_eq!(walk(&mut check, STANCES, 20, 1.2 * G).len(), 1);
        assert_eq!(check.said_by(), Some(ForceWitness::QuietStances));
        // A rest within the tolerance says nothing, and leaves the stances free to say it.
        let mut check = StanceForce::default();
        assert!(!check.rest(1.04 * G, G));
        assert!(!check.is_off());
        assert_eq!(walk(&mut check, STANCES, 20, 0.8 * G).len(), 1);
    }

    #[test]
    fn it_is_said_again_only_after_it_came_back() {
        let mut check = StanceForce::default();
        assert_eq!(walk(&mut check, STANCES, 20, 1.2 * G).len(), 1);
        // Back to 4 % off: inside the tolerance, not inside half of it; still the same episode.
        assert!(walk(&mut check, STANCES, 20, 1.04 * G).is_empty());
        assert!(walk(&mut check, STANCES, 20, 1.2 * G).is_empty());
        // Back to gravity, then off again: said again.
        assert!(walk(&mut check, STANCES, 20, G).is_empty());
        assert_eq!(walk(&mut check, STANCES, 20, 0.7 * G).len(), 1);
    }
}
