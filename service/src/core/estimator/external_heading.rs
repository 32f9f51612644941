//! An external heading (a map matcher's, over the daemon's angle stream): when it is used,
//! how far it may lie from the prediction, and why one is refused.

/// The NIS beyond which an external heading observation is refused, not fused (16: four σ of
/// the prediction and the observation together; the χ² probability of a right one beyond it is
/// 6e-5). A heading 90° off with σ 1e-6 used to be fused as given and threw the bias to
/// 0.04 rad/s.
pub const EXTERNAL_HEADING_MAX_NIS: f64 = 16.0;

/// How long after its time an external heading may still be used, s: at the first stance
/// observed from [`EXTERNAL_HEADING_LEAD_S`] before its `t_s` on, if that stance is observed
/// within this after it; otherwise it is counted as expired. One whose time already lies this
/// far behind the latest sample when it is handed in is refused then (`headings_refused`): a
/// producer that sent `t_s = 0` (the field's default) mid-walk had each heading expire at the
/// next stance, in the place of the one waiting there, with no word of why. A stride cycle
/// lasts about 1.1 s on the gdins walks, so a heading given during a swing is used at the next
/// stance, and one older than two seconds describes a foot placement already past (it was fused
/// at whatever stance came next, however late: a review).
pub const EXTERNAL_HEADING_MAX_AGE_S: f64 = 2.0;

/// How far before an external heading's `t_s` a stance may be observed and still use it, s: a
/// stance is observed `heading.obs_delay_s` (0.05 s) after it begins and lasts 0.3–0.6 s
/// walking, so a heading stamped within the stance in progress is that stance's. One stamped
/// later waits for its stance (a replay may hand headings in ahead of the samples).
pub const EXTERNAL_HEADING_LEAD_S: f64 = 0.5;

/// How far ahead of the latest sample an external heading's `t_s` may lie, s. The queues
/// between a producer and the estimator hold well under a minute of samples, so a heading
/// stamped an hour ahead is on another clock (Unix time against the sensor's time since it was
/// powered): it would wait for ever, each newer one counted as superseding it (a review).
/// Refused and counted as `headings_refused`; before the first sample there is nothing to
/// compare with.
pub const EXTERNAL_HEADING_MAX_AHEAD_S: f64 = 3600.0;

/// An external heading waiting for its stance ([`crate::core::Estimator::queue_heading`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct QueuedHeading {
    /// The time it refers to, on the estimator's continuous clock (its stamp less the clock's
    /// offset when it was handed in: [`crate::core::clock::SampleClock::offset_s`]), s.
    pub t_s: f64,
    /// Its stamp as given, s.
    pub stamp_s: f64,
    /// The walking (foot) heading in the map frame, rad.
    pub heading_rad: f64,
    /// Its σ, rad.
    pub sd_rad: f64,
}

impl QueuedHeading {
    /// The heading stamped `stamp_s`, on a clock whose stamps are taken less `offset_s`.
    pub fn new(stamp_s: f64, heading_rad: f64, sd_rad: f64, offset_s: f64) -> Self {
        Self {
            t_s: stamp_s - offset_s,
            stamp_s,
            heading_rad,
            sd_rad,
        }
    }

    /// The same heading on a clock with another offset (a copy of the estimator from before a
    /// clock step, put back when the samples after it were dropped as glitched).
    pub fn on_clock(self, offset_s: f64) -> Self {
        Self::new(self.stamp_s, self.heading_rad, self.sd_rad, offset_s)
    }
}

/// An external heading observation that cannot be fused.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error(
    "heading observation refused: t_s {t_s:e} s, heading {heading_rad:e} rad, σ {sd_rad:e} rad ({why})"
)]
pub struct HeadingRefused {
    /// The time given, s.
    pub t_s: f64,
    /// The heading given.
    pub heading_rad: f64,
    /// Its σ.
    pub sd_rad: f64,
    /// Why.
    pub why: WhyRefused,
}

/// Why an external heading was refused on arrival.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WhyRefused {
    /// A time or heading that is not finite, or a σ not in (0, π].
    NotANumber,
    /// Its time lies more than [`EXTERNAL_HEADING_MAX_AHEAD_S`] ahead of the latest sample's.
    Ahead {
        /// The latest sample's time, s.
        latest_s: f64,
    },
    /// Its time lies [`EXTERNAL_HEADING_MAX_AGE_S`] or more behind the latest sample's: no
    /// stance to come (each later than that sample) can use it.
    Behind {
        /// The latest sample's time, s.
        latest_s: f64,
    },
}

impl std::fmt::Display for WhyRefused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            WhyRefused::NotANumber => {
                f.write_str("needs a finite heading, σ in (0, π], and a finite t_s")
            }
            WhyRefused::Ahead { latest_s } => write!(
                f,
                "t_s more than {EXTERNAL_HEADING_MAX_AHEAD_S} s ahead of the latest sample, at \
                 {latest_s} s: on another clock?"
            ),
            WhyRefused::Behind { latest_s } => write!(
                f,
                "t_s {EXTERNAL_HEADING_MAX_AGE_S} s or more behind the latest sample, at \
                 {latest_s} s, so no stance to come can use it: stamped on the IMU samples' clock?"
            ),
        }
    }
}
