//! The estimator's inputs and outputs: samples, refusals, warm-start states, phases, heading
//! events, counters and the per-sample estimate.

use super::stance_force::{ForceWitness, OffGravity, SPECIFIC_FORCE_TOLERANCE, STANCES};
use crate::core::eskf::Innovation;
use crate::core::heading::Rejection;
use crate::core::health::HealthFault;
use crate::core::stance::{StanceDecision, StanceEdge};

/// One IMU sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuInput {
    /// Sensor time, s.
    pub t_s: f64,
    /// Angular rate, rad/s, sensor axes.
    pub gyro_rad_s: [f64; 3],
    /// Specific force, m/s², sensor axes (points up at rest).
    pub accel_m_s2: [f64; 3],
}

impl From<&corridor_shared::imu_csv::ImuRow> for ImuInput {
    /// A logged row as the estimator takes it (its temperature, if any, is not used).
    fn from(r: &corridor_shared::imu_csv::ImuRow) -> Self {
        Self {
            t_s: r.t_s,
            gyro_rad_s: r.gyro_rad_s,
            accel_m_s2: r.accel_m_s2,
        }
    }
}

/// A sample the estimator refused; it changed nothing.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SampleError {
    /// A component is NaN or infinite.
    #[error("sample at t = {t_s} s: {field} is not finite ({value})")]
    NonFinite {
        /// Sample time.
        t_s: f64,
        /// Which field.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// The time does not increase (by more than `sensor.min_dt_s`).
    #[error("sample at t = {t_s} s does not follow the previous one at {prev_t_s} s")]
    TimeNotIncreasing {
        /// Sample time.
        t_s: f64,
        /// The previous accepted time.
        prev_t_s: f64,
    },
    /// A magnitude beyond what the sensor can output (`sensor.max_gyro_rad_s`,
    /// `sensor.max_accel_m_s2`), or one axis beyond twice its range.
    #[error("sample at t = {t_s} s: {field} = {value:e} is beyond the plausible {limit}")]
    Implausible {
        /// Sample time.
        t_s: f64,
        /// Which magnitude.
        field: &'static str,
        /// Its value.
        value: f64,
        /// The limit.
        limit: f64,
    },
    /// Every gyro and accelerometer value is zero: a driver's fill for a sample it did not get,
    /// or a dead sensor (counted with the implausible samples).
    #[error(
        "sample at t = {t_s} s: every gyro and accelerometer value is 0 (a driver's fill or a dead sensor, not a measurement)"
    )]
    ZeroFill {
        /// Sample time.
        t_s: f64,
    },
    /// The time jumps forward by more than `sensor.max_dt_s` and no later sample confirmed it.
    #[error(
        "sample at t = {t_s} s jumps from the previous one at {prev_t_s} s by more than {max_dt_s} s"
    )]
    TimeJump {
        /// Sample time.
        t_s: f64,
        /// The previous accepted time.
        prev_t_s: f64,
        /// The bound.
        max_dt_s: f64,
    },
}

impl SampleError {
    /// Stable snake_case name of the reason, for counters and summaries.
    pub fn reason(&self) -> &'static str {
        match self {
            SampleError::NonFinite { .. } => "non_finite",
            SampleError::TimeNotIncreasing { .. } => "time_not_increasing",
            SampleError::Implausible { .. } | SampleError::ZeroFill { .. } => "implausible",
            SampleError::TimeJump { .. } => "time_jump",
        }
    }
}

/// A saved bias state: gyro bias and its covariance, sensor axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WarmStart {
    /// Gyro bias, rad/s.
    pub gyro_bias_rad_s: [f64; 3],
    /// Its covariance, (rad/s)², symmetric positive definite.
    pub gyro_bias_cov: [[f64; 3]; 3],
}

/// A warm-start state that is not finite, within `sensor.max_gyro_bias_rad_s`, symmetric and
/// positive definite.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("warm-start state rejected (bias {:?}, covariance {:?}): must be finite, within sensor.max_gyro_bias_rad_s, symmetric and positive definite", .state.gyro_bias_rad_s, .state.gyro_bias_cov)]
pub struct WarmStartError {
    /// The rejected state.
    pub state: WarmStart,
}

/// Estimator phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Phase {
    /// Waiting for the end of the initial rest.
    #[default]
    Aligning,
    /// Fixing the map frame and the sensor's yaw on the foot.
    Calibrating,
    /// Heading observations in use.
    Tracking,
}

impl Phase {
    /// Stable name for CSV and logs.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Aligning => "aligning",
            Phase::Calibrating => "calibrating",
            Phase::Tracking => "tracking",
        }
    }
}

/// What happened to one heading observation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadingEvent {
    /// Foot heading before the update, rad, map frame.
    pub foot_heading_rad: f64,
    /// Associated direction, rad (NaN when rejected).
    pub direction_rad: f64,
    /// `Ok` with the filter innovation, or why it was not used.
    pub outcome: Result<Innovation, Rejection>,
    /// Elapsed time since the observer epoch (bias-filter modes), s.
    pub baseline_s: f64,
    /// When the observed walking ended, s: the stance's own time, or for a stride observed
    /// one stance late (`heading.stride_look_ahead`) the time of the footprint ending it.
    pub observed_t_s: f64,
}

/// Running counters.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    /// Samples accepted.
    pub samples: u64,
    /// Samples refused because a value was not finite.
    pub rejected_non_finite: u64,
    /// Samples refused because time did not increase.
    pub rejected_time: u64,
    /// Samples refused because a magnitude was beyond what the sensor can output, or every value
    /// was zero (a driver's fill, [`SampleError::ZeroFill`]).
    pub rejected_implausible: u64,
    /// Samples refused because their time jumped beyond `sensor.max_dt_s` unconfirmed, and
    /// samples dropped after the fact: a first time the samples after it contradicted, a time
    /// after a gap that the next sample showed to be a glitch.
    pub rejected_time_jump: u64,
    /// Accepted samples with an axis at the rail of its range (probably clipped).
    pub clipped_samples: u64,
    /// Clipped gyro peaks (samples with an axis at its rail, up to two samples without) whose
    /// cut-off rate was put back and the filter propagated again (`eskf.restore_clipped_peaks`).
    pub clipped_peaks_restored: u64,
    /// Clipped gyro peaks that were not put back: a stance, a gap, a health fault, a late
    /// footfall or a warm start came before their end, they lasted longer than
    /// `rail_peaks::MAX_PEAK_SAMPLES`, no run had two samples off the rail either side, or the
    /// filter propagated again failed the health check; and a peak still open when the stream
    /// ends ([`crate::core::Estimator::end_stream`]). In neither count: a peak whose parabolas
    /// all lie under their readings (nothing was cut off: readings within 2 % of the range, not
    /// at it).
    pub clipped_peaks_not_restored: u64,
    /// Samples after which the state failed the health check: the first few in a row undo
    /// the sample's update (the state before it), further ones restore the state of the last
    /// healthy stance.
    pub health_restores: u64,
    /// Health faults that put the filter back to before a footprint it had cloned: the cloned
    /// footprints were forgotten, and strides are observed again from the next ones.
    pub footprints_forgotten: u64,
    /// Stance updates that found a velocity far beyond what the filter allowed (garbage samples
    /// since the last stance) and reset the velocity first.
    pub velocity_resets: u64,
    /// Stances at which the tilt was levelled again from gravity and the bias started again
    /// from zero: after restores of the last healthy stance that did not hold (`recovery.rs`).
    pub relevels: u64,
    /// Steps longer than `estimator.max_dt_s`: up to `estimator.max_bridge_s` bridged (one step
    /// across the gap, covariance widened by what the interpolation misses), longer ones up to
    /// `estimator.max_fill_s` filled from the stride before when it matches, the others start a
    /// new segment (nothing integrated over the gap, velocity and attitude covariance widened).
    /// Those before the filter starts (in the initial rest, or while waiting for one) are in
    /// none of the sub-counts below: nothing is integrated over them.
    pub gaps: u64,
    /// Of the gaps, those bridged.
    pub gaps_bridged: u64,
    /// Of the gaps, those filled from the stride before (`estimator.max_fill_s`).
    pub gaps_filled: u64,
    /// Of the gaps, those taken as the clock stepping forward with nothing lost (the rates
    /// ran on across it): integrated as one sample step.
    pub gaps_clock_steps: u64,
    /// Steps back of the clock across which the rates ran on: taken as a new time base, the
    /// first sample after the step (refused) counted in `rejected_time` (a step back that is not
    /// taken refuses every sample until the stamps pass the last accepted one).
    pub clock_steps_back: u64,
    /// Stances since alignment.
    pub stances: u64,
    /// ZUPT updates.
    pub zupts: u64,
    /// Footfalls the detector missed (a dip of its statistic shorter than a stance with no
    /// stance around it, or a stride cycle without a stance) whose quietest sample got the
    /// stance velocity update late (`detector.late_stance_min_s`,
    /// `detector.overdue_stride_factor`).
    pub late_footfalls: u64,
    /// Such footfalls whose late update was not made (the stride memory no longer reached back
    /// to the sample, or the velocity was too far from a standing foot's).
    pub late_footfalls_dropped: u64,
    /// Heading observations used.
    pub heading_used: u64,
    /// Rejected: not walking straight.
    pub heading_not_straight: u64,
    /// Rejected: no direction within the gate.
    pub heading_outside_gate: u64,
    /// Rejected: outside every corridor.
    pub heading_outside_map: u64,
    /// Rejected: the association weight was below `heading.min_weight` (the residual says the
    /// walker is not walking along the associated direction: a weave, a side-step).
    pub heading_unlikely: u64,
    /// Rejected: the foot axis is off the stride before it (`heading.foot_axis_stride_max_deg`).
    pub heading_off_stride: u64,
    /// Times the heading was taken as lost and its variance widened
    /// (`heading.reacquire_strides`).
    pub heading_reacquisitions: u64,
    /// Stride-direction observations used.
    pub stride_used: u64,
    /// Stride-direction observations rejected (too short, outside the gate, unlikely).
    pub stride_rejected: u64,
    /// Times the initial rest was too short and alignment started over.
    pub alignment_restarts: u64,
    /// Rests (or first stances) not aligned on because their mean specific force was no
    /// gravity: beyond [`GRAVITY_TOLERANCE`] of it (accelerations in g, a wrong scale or a
    /// broken accelerometer; the CSV reader refuses a log in g, a producer's stream reaches the
    /// daemon as it is).
    pub alignment_not_gravity: u64,
    /// Times the specific force left gravity by more than [`SPECIFIC_FORCE_TOLERANCE`]: the
    /// initial rest's, or the median of the last quiet stances (an accelerometer scale or units
    /// wrong: every distance is wrong by as much; `stance_force.rs`). Counted once per time it
    /// left.
    pub specific_force_off_gravity: u64,
    /// 50 ms blocks of the initial rest left out of its means (bias prior, tilt) because the
    /// foot moved in them (`alignment.rest_max_rate_change_rad_s`).
    pub initial_rest_moving_blocks: u64,
    /// Alignment came from a first stance shorter than `alignment.min_rest_s` (no rest-mean
    /// bias prior).
    pub started_without_rest: bool,
    /// A start in fast gait went back this far, ms, to the first stance the fast-gait rule
    /// took once the gait was known, and the filter ran over the samples since
    /// (`alignment.fast_gait_replay_s`); 0 when it did not.
    pub start_replayed_ms: u64,
    /// The initial "rest" turned faster than any bias of the sensor can be
    /// (`sensor.max_gyro_bias_rad_s` on some axis, or `alignment.max_prior_rate_rad_s` in
    /// magnitude: a foot pivoting, or a log started mid-walk), so its mean rate was not taken
    /// as the bias prior.
    pub rest_prior_refused: bool,
    /// Zero-rate updates of the gyro bias at rests after the alignment.
    pub zero_rate_updates: u64,
    /// Rests whose mean rate was not fused: beyond the χ² gate of the bias the filter holds
    /// (a foot that turned slowly through the "rest"), or undone by a health fault in the same
    /// step; at the alignment of a warm start, a rest that disagrees so with the saved bias
    /// replaces it.
    pub zero_rate_refused: u64,
    /// Samples integrated on the smoothed clock because the time stamps jitter (host arrival
    /// times; see `core/clock.rs`).
    pub jittery_clock_samples: u64,
    /// External heading observations refused on arrival: not finite, σ not in (0, π], or a time
    /// more than [`EXTERNAL_HEADING_MAX_AHEAD_S`](super::EXTERNAL_HEADING_MAX_AHEAD_S) ahead of
    /// the latest sample or at least [`EXTERNAL_HEADING_MAX_AGE_S`](super::EXTERNAL_HEADING_MAX_AGE_S)
    /// behind it ([`crate::core::Estimator::queue_heading`]).
    pub headings_refused: u64,
    /// External heading observations replaced by a newer one before the stance that would have
    /// used them (one is kept, the newest).
    pub headings_superseded: u64,
    /// External heading observations refused at their stance: further than
    /// [`EXTERNAL_HEADING_MAX_NIS`](super::EXTERNAL_HEADING_MAX_NIS) (in NIS) from the filter's prediction.
    pub headings_outside_gate: u64,
    /// External heading observations not used because their time had passed: no stance was
    /// observed within [`EXTERNAL_HEADING_MAX_AGE_S`](super::EXTERNAL_HEADING_MAX_AGE_S) after their `t_s`, or they were still
    /// waiting for a stance when their stream ended or the daemon stopped
    /// ([`crate::core::Estimator::expire_pending_heading`]).
    pub headings_expired: u64,
    /// External heading observations fused at their stance in an update that the health check
    /// then undid (not counted as used; not used again).
    pub headings_undone: u64,
}

/// How far (a fraction) the mean specific force of a rest or of a first stance may lie from
/// gravity and still align the filter. A rest reads gravity to within the accelerometer's scale
/// error (the aligning rests of the default runs of the 16 gdins walks: 9.809–9.825 m/s²,
/// `rest_specific_force_m_s2` of `summary.json`; the NGIMU walk 9.62–9.96 wherever it
/// starts); a short walking stance, which a start without a rest aligns on, reads far more (a
/// review started the 16 walks every 10 ms: 7.77–12.00 m/s², −21 to +22 %, on the fast exp38
/// 164 of 7,453 starts beyond 20 %). A log in g reads 1 m/s² (−90 %), a dead accelerometer 0,
/// one in mg about 1000: ±50 % tells them from any stance. Beyond it the estimator does not
/// align, as gravity taken from such a rest scaled every later position (exp36 in g ran with
/// g = 1 m/s² and walked 10.7 m of track instead of 82.7 m, with nothing said). At ±25 % a
/// review's exp38 with a 3 % accelerometer scale error lost 9 s of walking to refused first
/// stances.
pub const GRAVITY_TOLERANCE: f64 = 0.5;

impl Counters {
    /// Samples refused, for any reason (what was neither accepted nor lost elsewhere): with
    /// `samples` they account for every sample handed to the estimator.
    pub fn refused(&self) -> u64 {
        self.rejected_non_finite
            + self.rejected_time
            + self.rejected_implausible
            + self.rejected_time_jump
    }
}

/// The estimate after one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Sample time, s.
    pub t_s: f64,
    /// Phase.
    pub phase: Phase,
    /// Position, m, map frame.
    pub p_m: [f64; 3],
    /// Velocity, m/s, map frame.
    pub v_m_s: [f64; 3],
    /// Attitude `nav_from_body` as (w, x, y, z).
    pub nav_from_body: [f64; 4],
    /// ZYX roll, rad.
    pub roll_rad: f64,
    /// ZYX pitch, rad.
    pub pitch_rad: f64,
    /// ZYX yaw, rad.
    pub yaw_rad: f64,
    /// Gyro bias, rad/s, sensor axes.
    pub gyro_bias_rad_s: [f64; 3],
    /// Its σ, rad/s.
    pub gyro_bias_sd_rad_s: [f64; 3],
    /// The largest fraction, on one axis, of a bias error present when the bias was set (the
    /// rest-mean prior, a saved state or the initial guess; the same size on every axis) that
    /// the estimate still carries: 1 at the start, towards 0 as the walk observes the bias (the
    /// filter's closed-loop response, see `eskf/response.rs`). NaN before alignment (and for a
    /// filter whose bias states are frozen, which no mode uses).
    pub bias_unabsorbed: f64,
    /// Stance flag: this sample is taken as zero velocity.
    pub stance: bool,
    /// A new stance (footfall) begins on this sample; the stance flags until the next one belong
    /// to it (a short pause inside it does not split it: `detector.merge_gap_s`).
    pub stance_began: bool,
    /// The running filter counted a stance on this sample ([`Counters::stances`] rose): the
    /// first running sample of a stance, which may have begun while aligning. The daemon's nav
    /// sample goes out here.
    pub stance_counted: bool,
    /// An axis of this sample is at the rail of its range (probably clipped).
    pub clipped: bool,
    /// Length of the gap before this sample, s, when the step was longer than
    /// `estimator.max_dt_s`, and how it was crossed.
    pub gap_s: Option<f64>,
    /// How the gap before this sample was crossed (with `gap_s`).
    pub gap_crossing: Option<GapCrossing>,
    /// Set when the state failed the health check on this sample and the last good state was
    /// restored (the estimate shows the restored state).
    pub health_fault: Option<HealthFault>,
    /// Set on the sample that showed the stream's first time stamp (this value, s) to be an
    /// outlier: the first sample was dropped after the fact and the estimator started again
    /// here.
    pub replaced_first_t_s: Option<f64>,
    /// Set on the sample that showed the previous accepted sample's time (this value, s), which
    /// had jumped forward by a gap, to be a stamp glitch: that sample was dropped after the fact
    /// (the state is as if it had never come) and this one follows the time before it. After a
    /// run of two or more glitched stamps: the run's first accepted time, every
    /// sample from it on dropped (`glitch_run_dropped` of them).
    pub glitch_t_s: Option<f64>,
    /// With `glitch_t_s`, after a run of glitched stamps: the accepted samples dropped after the
    /// fact (counted with the refused time jumps, as the jumped sample before them was); 0 for
    /// a single glitch. Their estimates were published before.
    pub glitch_run_dropped: u64,
    /// Set on the first sample taken after the clock stepped back (the rates ran on across
    /// the step): the stamps from here on are taken plus this, s (counted in
    /// `clock_steps_back`). The estimates keep the stamps, which go back here.
    pub clock_stepped_back_s: Option<f64>,
    /// The stance update on this sample found a velocity far beyond what the filter allowed
    /// and reset it first (counted in `velocity_resets`).
    pub velocity_reset: bool,
    /// The heading was taken as lost on this sample: the straight strides before it ran this
    /// far (rad) off the nearest direction (counted in `heading_reacquisitions`).
    pub heading_reacquired: Option<f64>,
    /// The start heading (`heading.start_heading_deg`) set the map frame on this sample, at the
    /// first stride's stance: the filter's frame turned about the start point, so the positions
    /// and yaws before this sample (the stance's first, whose footfall the daemon published)
    /// are in the frame before it. Again at a later stance when a health check's restore
    /// forgot the footprints before tracking began; never on a start in fast gait, whose replay
    /// sets the frame before any output.
    pub frame_set: bool,
    /// The rest or stance that would have aligned on this sample was refused: its mean
    /// specific force and the gravity it was held against, m/s² (counted in
    /// `alignment_not_gravity`).
    pub not_gravity_m_s2: Option<(f64, f64)>,
    /// The initial rest that aligned the filter on this sample, or the stance that ended on
    /// it, took the specific force beyond [`SPECIFIC_FORCE_TOLERANCE`] of gravity: the rest's
    /// mean or the last quiet stances' median, and the gravity it was held against (counted in
    /// `specific_force_off_gravity`).
    pub specific_force_off_gravity: Option<OffGravity>,
    /// Zero-velocity detector statistic.
    pub detector_statistic: f64,
    /// Tracking, and less than `estimator.converged_unabsorbed` of a bias error present when the
    /// bias was set is left in the estimate (`bias_unabsorbed`).
    pub converged: bool,
    /// ZUPT innovation, when one was applied on this sample.
    pub zupt: Option<Innovation>,
    /// A footfall the detector missed was updated late on this sample: the time of its
    /// quietest sample, which the update was made at (`detector.late_stance_min_s`,
    /// `detector.overdue_stride_factor`): the sample clock plus what it took back, so the
    /// stamp on a device clock, about the stamp on a smoothed one.
    pub late_footfall_t_s: Option<f64>,
    /// Heading observation event, when one was taken on this sample.
    pub heading: Option<HeadingEvent>,
    /// Stride-direction observation event, when one was taken on this sample
    /// (`foot_heading_rad` then holds the stride direction).
    pub stride: Option<HeadingEvent>,
}

impl Estimate {
    /// Starts the estimate of a new sample: its stamp and what the stance detector and the
    /// input said of it; every event of the previous sample cleared (the state fields stay
    /// until the filter fills them).
    pub(super) fn begin_sample(
        &mut self,
        t_s: f64,
        decision: &StanceDecision,
        edge: StanceEdge,
        clipped: bool,
    ) {
        self.t_s = t_s;
        self.stance = decision.stance;
        self.stance_began = edge == StanceEdge::Began;
        self.stance_counted = false;
        self.clipped = clipped;
        self.health_fault = None;
        self.gap_s = None;
        self.gap_crossing = None;
        self.velocity_reset = false;
        self.heading_reacquired = None;
        self.frame_set = false;
        self.not_gravity_m_s2 = None;
        self.specific_force_off_gravity = None;
        self.replaced_first_t_s = None;
        self.glitch_t_s = None;
        self.glitch_run_dropped = 0;
        self.clock_stepped_back_s = None;
        self.detector_statistic = decision.statistic;
        self.zupt = None;
        self.late_footfall_t_s = None;
        self.heading = None;
        self.stride = None;
    }
}

impl Default for Estimate {
    fn default() -> Self {
        Self {
            t_s: f64::NAN,
            phase: Phase::Aligning,
            p_m: [0.0; 3],
            v_m_s: [0.0; 3],
            nav_from_body: [1.0, 0.0, 0.0, 0.0],
            roll_rad: 0.0,
            pitch_rad: 0.0,
            yaw_rad: 0.0,
            gyro_bias_rad_s: [0.0; 3],
            gyro_bias_sd_rad_s: [f64::NAN; 3],
            bias_unabsorbed: f64::NAN,
            stance: false,
            stance_began: false,
            stance_counted: false,
            clipped: false,
            health_fault: None,
            replaced_first_t_s: None,
            glitch_t_s: None,
            glitch_run_dropped: 0,
            clock_stepped_back_s: None,
            velocity_reset: false,
            heading_reacquired: None,
            frame_set: false,
            not_gravity_m_s2: None,
            specific_force_off_gravity: None,
            gap_s: None,
            gap_crossing: None,
            detector_statistic: f64::NAN,
            converged: false,
            zupt: None,
            late_footfall_t_s: None,
            heading: None,
            stride: None,
        }
    }
}

/// How a gap in the data (a step longer than `estimator.max_dt_s`) was crossed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GapCrossing {
    /// Integrated as one step on the rates and forces on both sides (up to
    /// `estimator.max_bridge_s`).
    Bridged,
    /// Filled with the samples of the same phase one stride earlier (up to
    /// `estimator.max_fill_s`).
    Filled,
    /// Nothing integrated over it: a new segment starts.
    NewSegment,
    /// The rates ran on across it where the stride before says time passing would have
    /// changed them: the clock stepped forward with no sample lost, and one sample step is
    /// integrated (up to `estimator.max_fill_s`).
    ClockStep,
    /// Before the filter starts (in the initial rest, or while waiting for one): nothing to
    /// integrate. A rest goes on after it, or the alignment starts again
    /// (`Counters::alignment_restarts`).
    InRest,
}

/// Something an estimate reports that a log should say, once per event (see
/// [`Estimate::notices`]): the offline runner and the daemon print the same words.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Notice {
    /// A step longer than `estimator.max_dt_s` before this sample, bridged by one step or not.
    Gap {
        /// Its length, s.
        gap_s: f64,
        /// How it was crossed.
        crossing: GapCrossing,
    },
    /// The state failed the health check and an earlier one was restored.
    HealthFault(HealthFault),
    /// The stance update found a velocity far beyond what the filter allowed and reset it.
    VelocityReset,
    /// Straight strides in a row ran this far (rad) off every direction: the heading was taken
    /// as lost and its variance widened.
    HeadingReacquired(f64),
    /// The stream's first sample, at this time (s), was dropped as a time outlier.
    FirstTimeReplaced(f64),
    /// The previous sample, at this time (s) after a gap, was dropped as a stamp glitch.
    TimeGlitch(f64),
    /// After a jump, this many samples from this time (s) on were dropped as glitched stamps.
    GlitchRun(f64, u64),
    /// The clock stepped back: the stamps from here on are taken plus this, s.
    ClockSteppedBack(f64),
    /// A rest (or first stance) was not aligned on: its mean specific force is no gravity
    /// (measured, gravity; m/s²).
    NotGravity(f64, f64),
    /// The initial rest's or the quiet stances' specific force is no gravity.
    SpecificForceOffGravity(OffGravity),
}

impl std::fmt::Display for Notice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Notice::Gap { gap_s, crossing } => write!(
                f,
                "gap of {gap_s:.3} s in the data; {}",
                match crossing {
                    GapCrossing::Bridged => "bridged by one step",
                    GapCrossing::Filled => "filled with the same phase of the stride before",
                    GapCrossing::NewSegment => "a new segment starts here",
                    GapCrossing::ClockStep =>
                        "the rates run on across it: a clock step, integrated as one sample step",
                    GapCrossing::InRest => "before the filter starts (aligning)",
                }
            ),
            Notice::HealthFault(fault) => write!(
                f,
                "estimator state failed the health check ({}); last good state restored",
                fault.name()
            ),
            Notice::VelocityReset => f.write_str(
                "the stance update found a velocity far beyond what the filter allowed (garbage \
                 samples since the last stance?); velocity reset",
            ),
            Notice::HeadingReacquired(off_rad) => write!(
                f,
                "straight strides in a row ran {:+.1}° off every corridor direction: the heading \
                 is taken as lost and its variance widened to find the directions again",
                off_rad.to_degrees()
            ),
            Notice::FirstTimeReplaced(first_t_s) => write!(
                f,
                "the first sample's time {first_t_s} s was an outlier (the samples after it do not \
                 follow it); it was dropped and the estimator starts again here"
            ),
            Notice::TimeGlitch(t_s) => write!(
                f,
                "the previous sample's time {t_s} s was a glitch (this one goes back and follows \
                 the time before it); that sample was dropped after the fact"
            ),
            Notice::GlitchRun(t_s, dropped) => write!(
                f,
                "the jump before time {t_s} s and the {dropped} samples from it on were glitched \
                 stamps (this one goes back and follows the time before the jump); they were \
                 dropped after the fact"
            ),
            Notice::ClockSteppedBack(shift_s) => write!(
                f,
                "the clock stepped back and the rates run on across the step: a new time base, \
                 the stamps from here on taken {shift_s:.3} s later (the first sample after the step refused)"
            ),
            Notice::NotGravity(f_m_s2, g_m_s2) => write!(
                f,
                "the rest or stance before this sample measured a mean specific force of \
                 {f_m_s2:.3} m/s², not gravity ({g_m_s2:.3} m/s² ± {:.0} %): accelerations in g, \
                 a wrong scale or a broken accelerometer? Not aligned on it",
                GRAVITY_TOLERANCE * 100.0
            ),
            Notice::SpecificForceOffGravity(OffGravity {
                force_m_s2,
                gravity_m_s2,
                witness,
            }) => write!(
                f,
                "{} specific force of {force_m_s2:.3} m/s², not gravity ({gravity_m_s2:.3} m/s² \
                 ± {:.0} %): the accelerometer's scale or units look wrong by {:+.1} %, and \
                 distances by about as much",
                match witness {
                    ForceWitness::InitialRest => "the initial rest read a mean".to_string(),
                    ForceWitness::QuietStances =>
                        format!("the foot's last {STANCES} quiet stances read a median"),
                },
                SPECIFIC_FORCE_TOLERANCE * 100.0,
                (force_m_s2 / gravity_m_s2 - 1.0) * 100.0
            ),
        }
    }
}

impl Estimate {
    /// What this sample's estimate reports that a log should say.
    pub fn notices(&self) -> impl Iterator<Item = Notice> {
        let gap = self
            .gap_s
            .zip(self.gap_crossing)
            .map(|(gap_s, crossing)| Notice::Gap { gap_s, crossing });
        gap.into_iter()
            .chain(self.health_fault.map(Notice::HealthFault))
            .chain(self.velocity_reset.then_some(Notice::VelocityReset))
            .chain(self.heading_reacquired.map(Notice::HeadingReacquired))
            .chain(self.replaced_first_t_s.map(Notice::FirstTimeReplaced))
            .chain(self.glitch_t_s.map(|t_s| match self.glitch_run_dropped {
                0 => Notice::TimeGlitch(t_s),
                n => Notice::GlitchRun(t_s, n),
            }))
            .chain(self.clock_stepped_back_s.map(Notice::ClockSteppedBack))
            .chain(self.not_gravity_m_s2.map(|(f, g)| Notice::NotGravity(f, g)))
            .chain(
                self.specific_force_off_gravity
                    .map(Notice::SpecificForceOffGravity),
            )
    }
}
