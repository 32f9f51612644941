//! The `[sensor]` section: what the IMU can physically output, and the time rule shared by the
//! CSV reader and the estimator.
//!
//! Two kinds of limits:
//! - the **range** (full scale) of each axis. A value at the rail (within [`CLIP_FRACTION`] of
//!   the range) was probably clipped: it is kept, flagged and counted, because it is real data
//!   with a known error;
//! - the **plausible magnitude** |ω| and |f| beyond which a value is absurd (a corrupt record, a
//!   unit mix-up, a bit flip): the sample is rejected. It is set well above √3 × range because
//!   factory calibration (scale factor, misalignment) lets a clipped axis read a few percent beyond
//!   its nominal rail (the gdins logs of the ±8 g 3DM-GX5-25 hold a few values up to 12.5 g).
//!   A single axis beyond [`AXIS_ABSURD_FACTOR`] × its range is absurd too, whatever the norm:
//!   the sensor cannot output it.
//!
//! Each limit is bounded by what a foot IMU can be (the `MIN_*`/`MAX_*` constants below say
//! what and why): a range of 1e30 rad/s was taken and switched clipping and plausibility off.
//!
//! There is no rate-of-change limit: with every axis bounded, a sample-to-sample change is bounded
//! by the plausible magnitude already, and a tighter bound would need the sensor's bandwidth and
//! would reject real heel strikes (tens of g within one sample).
//!
//! Time: a step not above `min_dt_s` is refused; a step longer than `max_dt_s` is a **time jump**:
//! the sample is refused unless the next one confirms the new time base ([`TimeGuard`]), so one
//! corrupt `t_s = 1e30` costs one row, and a real long gap costs one row too. A shorter step that
//! is still a gap (beyond the guard's `gap_dt_s`) is accepted but provisional: when the next time
//! goes back and follows the one before it, the gap's far side was a stamp glitch
//! ([`TimeVerdict::Glitch`]) and is dropped after the fact, so the good samples after it are kept.
//! A jump's far side that a sample confirmed stays provisional too, for as long as the new time
//! base has run for at most `max_dt_s`: a time that goes back behind it and follows the time
//! before the jump says the jump and the times after it were glitched stamps
//! ([`TimeVerdict::GlitchRun`]), dropped after the fact.
//! A time that goes back by at most `max_dt_s` and that the next one follows is a step back of the
//! clock ([`TimeVerdict::StepBack`]): the caller may take it as the new time base (the CSV reader
//! does; the estimator asks the rates).

use serde::{Deserialize, Serialize};

/// Fraction of the range at which a value counts as clipped.
pub const CLIP_FRACTION: f64 = 0.98;
/// A single axis reading beyond this many times its range cannot come from the sensor: the
/// sample is refused. The 16 gdins logs reach 1.02 × the gyro range and 1.56 × the accel range
/// on an axis (factory scaling past the rail), the x-io log a third of either.
pub const AXIS_ABSURD_FACTOR: f64 = 2.0;
/// Default gyro range: ±2000 °/s, the widest common MEMS full scale, rad/s.
pub const DEFAULT_GYRO_RANGE_RAD_S: f64 = 34.906_585;
/// Default accelerometer range: ±16 g, m/s².
pub const DEFAULT_ACCEL_RANGE_M_S2: f64 = 156.906_4;
/// Default largest plausible |ω|: 2 × √3 × the default range, rad/s.
pub const DEFAULT_MAX_GYRO_RAD_S: f64 = 120.0;
/// Default largest plausible |f|: 2 × √3 × the default range, m/s².
pub const DEFAULT_MAX_ACCEL_M_S2: f64 = 540.0;
/// Default largest plausible gyro bias: 0.2 rad/s (11 °/s), above the turn-on bias of any MEMS
/// gyro worth mounting on a foot (datasheets give 0.04–5 °/s).
pub const DEFAULT_MAX_GYRO_BIAS_RAD_S: f64 = 0.2;
/// Narrowest `sensor.gyro_range_rad_s`, rad/s: below the narrowest MEMS gyro full scale
/// (±125 °/s, 2.2 rad/s). A range narrower than this flags a walking foot's every turn as
/// clipped and refuses its swings as beyond the sensor.
pub const MIN_GYRO_RANGE_RAD_S: f64 = 1.0;
/// Widest `sensor.gyro_range_rad_s`, rad/s (5730 °/s): above the full scale of the MEMS IMUs
/// worn on feet (±2000 to ±4000 °/s, 35–70 rad/s; special high-rate gyros beyond that are no
/// foot IMU); a foot's swing peaks near 15 rad/s. Beyond it the range is a unit
/// mix-up or a typo, and it switched the clipping model and the plausibility check off without
/// a word (1e30 was taken: no sample of the gdins walks, railed at 8.7 rad/s, was flagged).
pub const MAX_GYRO_RANGE_RAD_S: f64 = 100.0;
/// Narrowest `sensor.accel_range_m_s2`, m/s²: below the narrowest MEMS accelerometer full
/// scale (±2 g, 19.6 m/s²) and above gravity, which an axis at rest must read inside its rail.
pub const MIN_ACCEL_RANGE_M_S2: f64 = 15.0;
/// Widest `sensor.accel_range_m_s2`, m/s² (about ±400 g): the widest MEMS accelerometers, the
/// high-g ones made for impacts, reach ±400 g; a heel strike reads tens of g.
pub const MAX_ACCEL_RANGE_M_S2: f64 = 4000.0;
/// Largest `sensor.max_gyro_rad_s` and `sensor.max_accel_m_s2`, as a multiple of the widest
/// range: [`AXIS_ABSURD_FACTOR`] × √3 (about 3.46; `2 * 3f64.sqrt()`, written out). A sample
/// within every axis's limit never has a larger norm, so a larger limit checks nothing.
pub const MAX_NORM_FACTOR: f64 = 3.464_101_615_137_754_4;
/// Largest `sensor.min_dt_s`, s: the step of a 1 kHz sensor. The rule refuses duplicated and
/// near-duplicated stamps, which lie far below any foot IMU's sample period (1–10 ms); a
/// larger one refuses the samples of a fast sensor as "not increasing".
pub const MAX_MIN_DT_S: f64 = 1e-3;
/// Largest `sensor.max_dt_s`, s: a step beyond it waits for the next sample to confirm it. Ten
/// seconds are a thousand samples lost at 100 Hz; a longer bound takes a single corrupt stamp
/// that far ahead for a gap, and holds the samples after it as a run that may yet be dropped.
pub const MAX_MAX_DT_S: f64 = 10.0;
/// Default smallest time step: 1 µs (no IMU samples at 1 MHz), s.
pub const DEFAULT_MIN_DT_S: f64 = 1e-6;
/// Default largest time step accepted without confirmation, s.
pub const DEFAULT_MAX_DT_S: f64 = 1.0;

/// `[sensor]` in the TOML file; every key optional.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SensorFile {
    /// Gyro full scale per axis, rad/s (default ±2000 °/s).
    pub gyro_range_rad_s: Option<f64>,
    /// Accelerometer full scale per axis, m/s² (default ±16 g).
    pub accel_range_m_s2: Option<f64>,
    /// Largest plausible |ω|, rad/s; beyond it a sample is rejected (default 120).
    pub max_gyro_rad_s: Option<f64>,
    /// Largest plausible |f|, m/s²; beyond it a sample is rejected (default 540).
    pub max_accel_m_s2: Option<f64>,
    /// Largest plausible gyro bias per axis, rad/s (estimator health, checkpoints; default 0.2).
    pub max_gyro_bias_rad_s: Option<f64>,
    /// Smallest time step, s (default 1e-6).
    pub min_dt_s: Option<f64>,
    /// Largest time step accepted as it comes; a longer one needs the next sample to confirm it
    /// (default 1.0 s).
    pub max_dt_s: Option<f64>,
}

/// Validated `[sensor]`: every limit finite and positive and within the bounds above (ranges in
/// [`MIN_GYRO_RANGE_RAD_S`, `MAX_GYRO_RANGE_RAD_S`] and [`MIN_ACCEL_RANGE_M_S2`,
/// `MAX_ACCEL_RANGE_M_S2`], plausible magnitudes from the range to [`MAX_NORM_FACTOR`] × the
/// widest range, `min_dt_s` ≤ [`MAX_MIN_DT_S`], `max_dt_s` ≤ [`MAX_MAX_DT_S`]), ranges below
/// the plausible magnitudes, `min_dt_s < max_dt_s`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SensorLimits {
    gyro_range_rad_s: f64,
    accel_range_m_s2: f64,
    max_gyro_rad_s: f64,
    max_accel_m_s2: f64,
    max_gyro_bias_rad_s: f64,
    min_dt_s: f64,
    max_dt_s: f64,
}

/// A `[sensor]` key that is not valid: the key, the value and the rule.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorKeyError {
    /// Dotted key.
    pub key: &'static str,
    /// Value found (with the other key's, for a rule between two keys).
    pub value: String,
    /// What it must satisfy.
    pub rule: &'static str,
}

impl Default for SensorLimits {
    fn default() -> Self {
        SensorFile::default()
            .validate()
            .expect("the built-in sensor defaults are valid")
    }
}

impl SensorFile {
    /// Applies the defaults and checks every key.
    pub fn validate(&self) -> Result<SensorLimits, SensorKeyError> {
        let pos = |key: &'static str, v: Option<f64>, d: f64| {
            let v = v.unwrap_or(d);
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(SensorKeyError {
                    key,
                    value: format!("{v:?}"),
                    rule: "must be a finite number > 0",
                })
            }
        };
        let l = SensorLimits {
            gyro_range_rad_s: pos(
                "sensor.gyro_range_rad_s",
                self.gyro_range_rad_s,
                DEFAULT_GYRO_RANGE_RAD_S,
            )?,
            accel_range_m_s2: pos(
                "sensor.accel_range_m_s2",
                self.accel_range_m_s2,
                DEFAULT_ACCEL_RANGE_M_S2,
            )?,
            max_gyro_rad_s: pos(
                "sensor.max_gyro_rad_s",
                self.max_gyro_rad_s,
                DEFAULT_MAX_GYRO_RAD_S,
            )?,
            max_accel_m_s2: pos(
                "sensor.max_accel_m_s2",
                self.max_accel_m_s2,
                DEFAULT_MAX_ACCEL_M_S2,
            )?,
            max_gyro_bias_rad_s: pos(
                "sensor.max_gyro_bias_rad_s",
                self.max_gyro_bias_rad_s,
                DEFAULT_MAX_GYRO_BIAS_RAD_S,
            )?,
            min_dt_s: pos("sensor.min_dt_s", self.min_dt_s, DEFAULT_MIN_DT_S)?,
            max_dt_s: pos("sensor.max_dt_s", self.max_dt_s, DEFAULT_MAX_DT_S)?,
        };
        let rule = |key, value: f64, rule| {
            Err(SensorKeyError {
                key,
                value: format!("{value:?}"),
                rule,
            })
        };
        // What no foot IMU can be (see the bounds' documentation).
        for (key, value, lo, hi, r) in [
            (
                "sensor.gyro_range_rad_s",
                l.gyro_range_rad_s,
                MIN_GYRO_RANGE_RAD_S,
                MAX_GYRO_RANGE_RAD_S,
                "must be in [1, 100] rad/s (a MEMS gyro's full scale is ±125 to ±4000 °/s)",
            ),
            (
                "sensor.accel_range_m_s2",
                l.accel_range_m_s2,
                MIN_ACCEL_RANGE_M_S2,
                MAX_ACCEL_RANGE_M_S2,
                "must be in [15, 4000] m/s² (a MEMS accelerometer's full scale is ±2 to ±400 g)",
            ),
            (
                "sensor.max_gyro_rad_s",
                l.max_gyro_rad_s,
                0.0,
                MAX_NORM_FACTOR * MAX_GYRO_RANGE_RAD_S,
                "must be at most 346.4 rad/s (2 × √3 × the widest gyro range, 100 rad/s)",
            ),
            (
                "sensor.max_accel_m_s2",
                l.max_accel_m_s2,
                0.0,
                MAX_NORM_FACTOR * MAX_ACCEL_RANGE_M_S2,
                "must be at most 13856.4 m/s² (2 × √3 × the widest accelerometer range, 4000 m/s²)",
            ),
            (
                "sensor.min_dt_s",
                l.min_dt_s,
                0.0,
                MAX_MIN_DT_S,
                "must be at most 0.001 s (it refuses duplicated stamps, not a sensor's period)",
            ),
            (
                "sensor.max_dt_s",
                l.max_dt_s,
                0.0,
                MAX_MAX_DT_S,
                "must be at most 10 s (a longer step waits for the next sample to confirm it)",
            ),
        ] {
            if !(lo..=hi).contains(&value) {
                return rule(key, value, r);
            }
        }
        // A rule between two keys names both values: either may be the one mistyped.
        let between = |key, value: f64, other: &str, other_value: f64, rule| {
            Err(SensorKeyError {
                key,
                value: format!("{value:?} (with {other} = {other_value:?})"),
                rule,
            })
        };
        if l.max_gyro_rad_s < l.gyro_range_rad_s {
            return between(
                "sensor.max_gyro_rad_s",
                l.max_gyro_rad_s,
                "sensor.gyro_range_rad_s",
                l.gyro_range_rad_s,
                "must be >= sensor.gyro_range_rad_s",
            );
        }
        if l.max_accel_m_s2 < l.accel_range_m_s2 {
            return between(
                "sensor.max_accel_m_s2",
                l.max_accel_m_s2,
                "sensor.accel_range_m_s2",
                l.accel_range_m_s2,
                "must be >= sensor.accel_range_m_s2",
            );
        }
        if l.min_dt_s >= l.max_dt_s {
            return between(
                "sensor.min_dt_s",
                l.min_dt_s,
                "sensor.max_dt_s",
                l.max_dt_s,
                "must be < sensor.max_dt_s",
            );
        }
        // A limit below any real bias fails the health check at every sample (1e-12 froze the
        // estimate); one above 10 rad/s checks nothing.
        if !(1e-3..=10.0).contains(&l.max_gyro_bias_rad_s) {
            return rule(
                "sensor.max_gyro_bias_rad_s",
                l.max_gyro_bias_rad_s,
                "must be in [0.001, 10] rad/s",
            );
        }
        Ok(l)
    }
}

impl SensorLimits {
    /// Gyro full scale per axis, rad/s.
    pub fn gyro_range_rad_s(&self) -> f64 {
        self.gyro_range_rad_s
    }
    /// Accelerometer full scale per axis, m/s².
    pub fn accel_range_m_s2(&self) -> f64 {
        self.accel_range_m_s2
    }
    /// Largest plausible |ω|, rad/s.
    pub fn max_gyro_rad_s(&self) -> f64 {
        self.max_gyro_rad_s
    }
    /// Largest plausible |f|, m/s².
    pub fn max_accel_m_s2(&self) -> f64 {
        self.max_accel_m_s2
    }
    /// Largest plausible gyro bias per axis, rad/s.
    pub fn max_gyro_bias_rad_s(&self) -> f64 {
        self.max_gyro_bias_rad_s
    }
    /// Smallest time step, s.
    pub fn min_dt_s(&self) -> f64 {
        self.min_dt_s
    }
    /// Largest time step accepted without confirmation, s.
    pub fn max_dt_s(&self) -> f64 {
        self.max_dt_s
    }
    /// `t_s` follows `prev_s` as the time rule wants the next sample to (see [`TimeGuard`]).
    pub fn follows(&self, prev_s: f64, t_s: f64) -> bool {
        step_follows(t_s - prev_s, self.min_dt_s, self.max_dt_s)
    }
}

/// A time step the rule takes without confirmation: more than `min_dt_s`, at most `max_dt_s`.
fn step_follows(dt_s: f64, min_dt_s: f64, max_dt_s: f64) -> bool {
    dt_s > min_dt_s && dt_s <= max_dt_s
}

/// What [`TimeGuard::check`] decided about a sample time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeVerdict {
    /// The time follows the time base: accept it.
    Accept,
    /// The time does not increase by more than `min_dt_s` (duplicates and going back included).
    NotIncreasing,
    /// The time jumps forward by more than `max_dt_s`: refused until a next sample confirms it.
    Jump,
    /// The time follows the previous (refused) jump, and a sample had followed the time base
    /// before it: the jump was a real gap. Accept this one as the new time base (the jumped
    /// sample stays refused; a caller with look-ahead may pass it on, as the CSV reader does).
    NewBase,
    /// The time follows the previous (refused) one, and both contradict the first time base,
    /// which no sample has followed yet: the first time was the outlier. Accept this one as
    /// the new time base; what was taken with the first one has to be dropped by the caller.
    Rebase,
    /// The last accepted time jumped forward by more than the guard's `gap_dt_s` (within
    /// `max_dt_s`), and this one goes back and follows the time before it within `gap_dt_s`:
    /// the last time was a stamp glitch, not a gap. Accept this one (the time before the glitch
    /// is its base); what was taken with the glitched sample has to be dropped by the caller.
    Glitch,
    /// A jump was confirmed as a new time base ([`TimeVerdict::NewBase`]), or a gap's far side
    /// was followed by the next time, at most `max_dt_s` (and [`JUMP_RUN_MAX_SAMPLES`] samples)
    /// ago, with no gap or step back since, and this time goes back behind that base and
    /// follows the time before the jump or gap within `max_dt_s` (after a gap: where the clock
    /// comes back after the run, [`JumpRun::returns_at`]): the jump or gap and every time since
    /// were glitched stamps (two or more in a row), not a gap. Accept
    /// this one (the time before the jump is its base); what was taken since the jump has to be
    /// dropped by the caller ([`TimeGuard::jump_run`] says from which time).
    GlitchRun,
    /// The time follows the previous (refused) one, which went back behind the time base by at
    /// most `max_dt_s` after a sample had followed the base: the clock stepped back (a host clock
    /// set back, a driver that re-sends what it sent) and runs on from there. The caller decides
    /// from what it knows beyond the times (the estimator: the rates) whether to take it as the
    /// new time base ([`TimeGuard::accept`]); not taken, the next time that follows it is a
    /// `StepBack` again, until a time follows the base. A step back beyond `max_dt_s` is never
    /// a time base (a restarted device clock: the daemon starts a new stream).
    StepBack,
}

/// The time rule of the CSV reader and of the estimator: strictly increasing by more than
/// `min_dt_s`; a forward jump beyond `max_dt_s` becomes the new time base only when the next
/// sample follows it within `max_dt_s` (a real gap), otherwise the jumped sample was an outlier.
/// The very first time has nothing to be judged against: until a sample follows it, a time
/// that breaks the rule (earlier, or a jump) is a candidate too, and when the next sample
/// follows that candidate the first time was the outlier ([`TimeVerdict::Rebase`]): one bad
/// stamp on the first row no longer makes every later row "not increasing".
/// A step longer than `gap_dt_s` (a gap, not a jump) is accepted at once but stays provisional
/// until the next accepted time: a next time that goes back and follows the time before the gap
/// within `gap_dt_s` says the gap's far side was a single glitched stamp
/// ([`TimeVerdict::Glitch`]). Without that, one stamp 0.9 s ahead made every good sample of the
/// next 0.9 s "not increasing" (180 samples at 200 Hz, and the walk's footprints 0.95 m off).
/// A glitch of two or more samples in a row beyond `gap_dt_s` and within `max_dt_s` looks like a
/// gap whose far side the next time follows: the run from the far side stays open as a jump's
/// does (below), and ends as glitched stamps the same way (before session 37 it was taken for a
/// gap, and the time going back after it for a step back of the clock, which the estimator
/// could not judge after a gap that started a new segment, so the good samples after the run
/// were refused until the stamps caught up: `examples/fault_scan.rs`). One of two or more
/// samples beyond `max_dt_s` is a jump that the second sample confirms; the run from there stays
/// open for `max_dt_s`, and a time that then goes back and follows the time before the jump
/// ends it as glitched stamps ([`TimeVerdict::GlitchRun`]). Before, two stamps 975 s ahead in
/// the middle of a walk made every later time "not increasing": the rest of the log was lost.
/// A time that goes back by at most `max_dt_s` and is followed by the next one is a step back
/// of the clock ([`TimeVerdict::StepBack`]), which the caller may take as the new time base.
/// The caller calls [`TimeGuard::accept`] with every time it accepts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeGuard {
    min_dt_s: f64,
    max_dt_s: f64,
    gap_dt_s: f64,
    last_s: Option<f64>,
    candidate_s: Option<f64>,
    /// A sample has followed the time base (every accepted time but the very first).
    confirmed: bool,
    /// While the last accepted step was a gap beyond `gap_dt_s` (within `max_dt_s`): the time
    /// before it (the base a glitch would go back to).
    before_gap_s: Option<f64>,
    /// The last time that went back within `max_dt_s` after the base was followed: a step
    /// back when the next time follows it ([`TimeVerdict::StepBack`]).
    back_s: Option<f64>,
    /// A time went back beyond `max_dt_s` since the last accepted one: no step back until a
    /// time follows the base.
    far_back: bool,
    /// Set by `check` on [`TimeVerdict::NewBase`]: the last accepted time before the jump, for
    /// `accept` to open the run.
    new_base_from_s: Option<f64>,
    /// While the run after a confirmed jump is open (see [`TimeVerdict::GlitchRun`]).
    run: Option<JumpRun>,
}

/// Samples after a confirmed jump within which a time that goes back and follows the time
/// before the jump makes them a glitched run ([`TimeVerdict::GlitchRun`]); with `max_dt_s`,
/// it bounds what a caller holds to drop them (1 s at 1 kHz).
pub const JUMP_RUN_MAX_SAMPLES: u32 = 1024;

/// The open run after a confirmed jump.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JumpRun {
    /// The last accepted time before the jump, s.
    pub before_s: f64,
    /// The first accepted time after it (the new base), s.
    pub first_s: f64,
    /// The first accepted time after the latest jump in the run (`first_s` unless a second
    /// jump came within it: the run goes on, from the time before the first), s.
    pub base_s: f64,
    /// Accepted times in the run, the first included.
    pub samples: u32,
    /// The run began at a gap's far side (within `max_dt_s`), not at a jump: it ends as
    /// glitched stamps only where the time that comes back is where the next sample after the
    /// time before the gap would be had the run's samples been stamped right
    /// ([`JumpRun::returns_at`]).
    pub after_gap: bool,
}

impl JumpRun {
    /// Whether `t_s` is where the clock comes back after this run's `samples` glitched stamps,
    /// the last of them at `last_s`: `samples + 1` periods after the time before the gap (the
    /// period: the run's own), within 1.5 periods. A sample lost in the gap and delivered late
    /// lies anywhere in the gap, and is not the return (a review: after a real gap, one late
    /// sample dropped every good sample since the gap as a glitched run, up to 1 s of walking,
    /// and `corridor run` refused whole logs at the 1 % rule).
    pub fn returns_at(&self, t_s: f64, last_s: f64) -> bool {
        if self.samples < 2 {
            return false;
        }
        let period_s = (last_s - self.first_s) / f64::from(self.samples - 1);
        let expected_s = self.before_s + f64::from(self.samples + 1) * period_s;
        (t_s - expected_s).abs() <= 1.5 * period_s
    }
}

impl TimeGuard {
    /// A guard with the given step bounds and no time base yet; a step beyond `gap_dt_s` is
    /// provisional until the next accepted time (infinite: never).
    pub fn new(min_dt_s: f64, max_dt_s: f64, gap_dt_s: f64) -> Self {
        Self {
            min_dt_s,
            max_dt_s,
            gap_dt_s,
            last_s: None,
            candidate_s: None,
            confirmed: false,
            before_gap_s: None,
            back_s: None,
            far_back: false,
            new_base_from_s: None,
            run: None,
        }
    }

    /// The guard of `limits`, with a step beyond `gap_dt_s` provisional.
    pub fn from_limits(limits: &SensorLimits, gap_dt_s: f64) -> Self {
        Self::new(limits.min_dt_s, limits.max_dt_s, gap_dt_s)
    }

    /// Whether the last accepted time is provisional: it came after a gap beyond `gap_dt_s`,
    /// and the next accepted time decides whether it was a glitch ([`TimeVerdict::Glitch`]).
    #[inline]
    pub fn provisional(&self) -> bool {
        self.before_gap_s.is_some()
    }

    /// The last accepted time.
    #[inline]
    pub fn last_s(&self) -> Option<f64> {
        self.last_s
    }

    /// The open run after a confirmed jump, while a time that goes back may still show it to
    /// be glitched stamps ([`TimeVerdict::GlitchRun`]); after a `GlitchRun` verdict (before
    /// `accept`), the run it ends.
    #[inline]
    pub fn jump_run(&self) -> Option<JumpRun> {
        self.run
    }

    /// Judges the finite time `t_s` against the time base; a jump is remembered as the candidate
    /// for a new base.
    #[inline]
    pub fn check(&mut self, t_s: f64) -> TimeVerdict {
        // Every time but the rare ones: a time that follows the base (`new_base_from_s` is
        // empty then: `accept` took it).
        match self.last_s {
            None => TimeVerdict::Accept,
            Some(last) if step_follows(t_s - last, self.min_dt_s, self.max_dt_s) => {
                TimeVerdict::Accept
            }
            Some(last) => self.check_rare(t_s, last),
        }
    }

    /// [`Self::check`] for a time that does not follow the base. Out of line: the rules grew,
    /// and inlined whole they were no longer inlined at all (27 instructions per sample more).
    #[cold]
    #[inline(never)]
    fn check_rare(&mut self, t_s: f64, last: f64) -> TimeVerdict {
        self.new_base_from_s = None;
        let follows = |from: f64| step_follows(t_s - from, self.min_dt_s, self.max_dt_s);
        if let Some(run) = self.run
            && t_s < run.first_s
            && follows(run.before_s)
            && (!run.after_gap || run.returns_at(t_s, last))
        {
            return TimeVerdict::GlitchRun;
        }
        if let Some(before) = self.before_gap_s
            && t_s <= last
            && step_follows(t_s - before, self.min_dt_s, self.gap_dt_s)
        {
            return TimeVerdict::Glitch;
        }
        if let Some(c) = self.candidate_s
            && follows(c)
        {
            return if self.confirmed {
                self.new_base_from_s = Some(last);
                TimeVerdict::NewBase
            } else {
                TimeVerdict::Rebase
            };
        }
        if let Some(b) = self.back_s
            && follows(b)
        {
            // Judged again at the next time, if the caller does not take this one.
            self.back_s = Some(t_s);
            return TimeVerdict::StepBack;
        }
        let dt = t_s - last;
        if dt.is_nan() || dt <= self.min_dt_s {
            if !self.confirmed {
                self.candidate_s = Some(t_s);
            } else if -dt <= self.max_dt_s && !self.far_back {
                // Once a sample has followed the base, going back is a step back's candidate
                // only within `max_dt_s` (beyond, a restarted clock or a bad stamp), and not
                // while the times that went back further catch up with the base. A jump's
                // candidate is kept.
                self.back_s = Some(t_s);
            } else {
                self.back_s = None;
                self.far_back = true;
            }
            return TimeVerdict::NotIncreasing;
        }
        self.candidate_s = Some(t_s);
        self.back_s = None;
        TimeVerdict::Jump
    }

    /// Records `t_s` as accepted: the new time base.
    #[inline]
    pub fn accept(&mut self, t_s: f64) {
        // The time before a gap whose far side was the last accepted time, if it was.
        let after_gap_from = self.before_gap_s;
        // A gap from the last accepted time stays provisional: also from the very first time, and
        // from a gap's far side (accepting the next time confirms that one). Not a time after a
        // refused jump or a replaced first time: those do not follow the last time.
        self.before_gap_s = self.last_s.filter(|&last| {
            let dt_s = t_s - last;
            dt_s > self.gap_dt_s && dt_s <= self.max_dt_s
        });
        if self.new_base_from_s.is_some() || self.run.is_some() || after_gap_from.is_some() {
            self.update_run(t_s, after_gap_from);
        }
        self.confirmed = self.last_s.is_some();
        self.last_s = Some(t_s);
        self.candidate_s = None;
        self.back_s = None;
        self.far_back = false;
    }

    /// The run after a confirmed jump opens at the new base, and the run after a gap's far side
    /// when the next time runs on from it (`after_gap_from`: the time before that gap); either
    /// stays open while the times run on, within `max_dt_s` and [`JUMP_RUN_MAX_SAMPLES`],
    /// without a gap (called by `accept` before the base moves to `t_s`, after `before_gap_s`
    /// is set).
    #[cold]
    #[inline(never)]
    fn update_run(&mut self, t_s: f64, after_gap_from: Option<f64>) {
        self.run = match (self.new_base_from_s.take(), self.run) {
            // A second jump within the run: the run goes on from the time before the first (a
            // review: it opened a new run from the glitched time, and the good times after it
            // were refused again).
            (Some(_), Some(run)) => Some(JumpRun {
                base_s: t_s,
                samples: run.samples.saturating_add(1),
                // A jump within a gap's run: a jump's run from here (its return is not
                // where the gap's count would put it).
                after_gap: false,
                ..run
            }),
            (Some(before_s), None) => Some(JumpRun {
                before_s,
                first_s: t_s,
                base_s: t_s,
                samples: 1,
                after_gap: false,
            }),
            // Two or more stamps glitched by a gap's length look like a gap whose far side the
            // next time follows: the two stay open to being dropped, as a jump's run (found by
            // random faults, `examples/fault_scan.rs`: the clock's return was taken for a step
            // back, and the good samples after it refused until the stamps caught up).
            (None, None) => after_gap_from
                .zip(self.last_s)
                .and_then(|(before_s, far_s)| {
                    step_follows(t_s - far_s, self.min_dt_s, self.gap_dt_s).then_some(JumpRun {
                        before_s,
                        first_s: far_s,
                        base_s: far_s,
                        samples: 2,
                        after_gap: true,
                    })
                }),
            (None, run) => run.and_then(|run| {
                let runs_on = self.last_s.is_some_and(|last| t_s > last)
                    && t_s - run.base_s <= self.max_dt_s
                    && run.samples < JUMP_RUN_MAX_SAMPLES
                    && self.before_gap_s.is_none();
                runs_on.then_some(JumpRun {
                    samples: run.samples + 1,
                    ..run
                })
            }),
        };
    }

    /// Whether a sample has followed the time base (false for the very first time).
    #[inline]
    pub fn confirmed(&self) -> bool {
        self.confirmed
    }
}

#[cfg(test)]
#[path = "sensor_tests.rs"]
mod tests;
