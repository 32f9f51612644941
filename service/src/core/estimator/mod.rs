//! The estimator: one IMU sample in, one [`Estimate`] out. Pure: no IO, no clock, no threads,
//! no allocation per sample. The offline runner and the daemon both drive this type.
//!
//! Phases:
//! 1. **Aligning**: while the foot rests, the mean specific force and gyro rate are accumulated.
//!    When motion starts after at least `alignment.min_rest_s` of rest, roll and pitch come from
//!    the mean specific force, gravity from its magnitude, the optional bias prior from the mean
//!    rate, and the yaw is provisionally 0.
//! 2. **Calibrating**: the first stance after the first stride fixes the map frame (that stride
//!    points along `heading.start_heading_deg`); the next `heading.calibration_strides` stances fix
//!    the sensor's yaw on the foot (mounting yaw plus toe-out), assuming the walk goes on straight.
//!    The sensor's tilt on the foot is its tilt during the initial rest (the foot is flat there).
//! 3. **Tracking**: at each stance, once, the foot heading is tested for a straight walk and
//!    associated with a map direction; an accepted direction becomes a heading observation for the
//!    configured mode.
//!
//! The state machine is explicit: a private `Stage` holds the rest sums while aligning and the
//! error-state filter from then on, and every step that needs the filter takes it from there as
//! an argument, so no path can reach the filter before it exists.
//!
//! Files: this one holds [`Estimator`] and its per-sample pipeline; `running.rs` the step once
//! the filter runs, and the estimate it gives; `types.rs` the data it
//! takes and gives (samples, estimates, counters, warm start); `external_heading.rs` when a
//! heading handed in from outside is used, and why one is refused; `alignment.rs` the initial rest
//! (or first stance) that starts the filter, and a warm start; `fast_start.rs` a start in fast
//! gait taken back to the first stance it could have started on; `observations.rs` what happens
//! once per stance (calibration and heading observations); `association.rs` the weighted
//! association with the dominant directions; `navigation.rs` one sample's strapdown step and
//! stance updates; `reacquire.rs` a heading lost beyond the association's reach, and the way
//! back; `rest.rs` the rest sums; `gaps.rs` a step longer than `estimator.max_dt_s` (bridged,
//! filled from the stride before, or a new segment);
//! `stride_memory.rs` the last strides' samples and footfalls that fill one;
//! `late_footfall.rs` a footfall the detector missed (a short dip of its statistic, or a stride
//! cycle without a stance), updated late from the stride memory; `stance_force.rs` the quiet
//! stances' specific force held against gravity (an accelerometer scale gone wrong);
//! `rail_peaks.rs` the peaks a gyro rail cut off, put back and propagated again; `recovery.rs`
//! what it does when the state or the input goes bad (health check, velocity reset, a first
//! time stamp that was an outlier, a glitched one); `gap_copy.rs` the copy of the estimator
//! that undoes a glitched one; `tests.rs` its unit tests.

mod alignment;
mod association;
mod external_heading;
mod fast_start;
mod gap_copy;
mod gaps;
mod late_footfall;
mod navigation;
mod observations;
mod rail_peaks;
mod reacquire;
mod recovery;
mod rest;
mod running;
mod stance_force;
mod stride_memory;
mod types;

pub use association::{association_mixture, association_weight};
use external_heading::QueuedHeading;
pub use external_heading::{
    EXTERNAL_HEADING_LEAD_S, EXTERNAL_HEADING_MAX_AGE_S, EXTERNAL_HEADING_MAX_AHEAD_S,
    EXTERNAL_HEADING_MAX_NIS, HeadingRefused, WhyRefused,
};
pub use types::{
    Counters, Estimate, GRAVITY_TOLERANCE, GapCrossing, HeadingEvent, ImuInput, Notice, Phase,
    SampleError, WarmStart, WarmStartError,
};

use fast_start::Start;
use gaps::Gap;
use recovery::{VELOCITY_RESET_Z2, take_spare};
pub use rest::REST_BLOCK_S;
use rest::{InitialRest, RestMeans, RestSums};
pub use stance_force::{ForceWitness, OffGravity, SPECIFIC_FORCE_TOLERANCE};

use super::bias_kf::{BiasKf, PaperObserver, RotationAwareObserver};
use super::clock::SampleClock;
use super::eskf::{
    BiasStates, CovarianceStep, Eskf, EskfInit, EskfNoise, ExtensionEstimates, ExtensionSd,
    Extensions, Innovation, max_row_sum,
};
use super::heading::{FootprintLine, HeadingAid, Rejection, StraightWalk};
use super::health::{self, HealthLimits, LastGood};
use super::plausibility::{Plausibility, StepBack};
use super::rotation::{
    euler_zyx, from_euler_zyx, heading_of_axis, rolling_velocity, rot_z, tilt_from_specific_force,
    wrap_pi, yaw, yaw_of_axis_with_heading,
};
use super::stance::{StanceDecision, StanceDetector, StanceEdge, StanceEvents};
use corridor_shared::config::{BiasPrior, Config, DetectorConfig, Mode, Positive};
use corridor_shared::sensor::CLIP_FRACTION;

/// Standard gravity, m/s² (a start without rest: no rest to measure it on).
const STANDARD_GRAVITY_M_S2: f64 = 9.80665;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// The bias filter of the `paper` and `rotation_aware` modes.
#[derive(Debug, Clone)]
enum BiasFilter {
    /// The ESKF owns the bias (`zupt`, `eskf`).
    InEskf,
    /// The paper: bias in the foot frame, H = I.
    Paper {
        kf: BiasKf,
        obs: Option<PaperObserver>,
    },
    /// Rotation-aware: bias in sensor axes, H = ∫C.
    RotationAware {
        kf: BiasKf,
        obs: Option<RotationAwareObserver>,
    },
}

/// Where the estimator is in its state machine. The error-state filter exists only once the
/// initial rest has given roll, pitch and gravity, so it lives in the stage that needs it.
#[derive(Debug, Clone)]
enum Stage {
    /// Accumulating the initial rest until motion starts after enough of it
    /// ([`Phase::Aligning`]).
    Aligning(Box<InitialRest>),
    /// Aligned: the filter runs ([`Phase::Calibrating`], then [`Phase::Tracking`]). Boxed: the
    /// filter's covariance is stored inline.
    Running(Box<Eskf>),
}

/// The estimator.
#[derive(Debug, Clone)]
pub struct Estimator {
    stage: Stage,
    p: Pipeline,
    /// The estimator before the last accepted sample, while that sample's time came after a
    /// gap and is provisional: the next sample may show it to be a stamp glitch, and it is then
    /// dropped after the fact (`recovery.rs`). After a jump that a sample confirmed, the copy
    /// before that sample, kept while the run after the jump is open: a time that goes back to
    /// before the jump drops the run. A copy per gap, in a buffer reused from the second gap on
    /// (`gap_copy.rs`).
    before_gap: gap_copy::GapCopy,
    /// A warm start was handed in since `before_gap` was taken: applied again to the filter
    /// restored from it.
    warm_start_since_copy: bool,
}

/// Everything of the estimator but its stage: the per-sample pipeline around the filter, whose
/// methods take the filter from [`Stage::Running`] as an argument.
#[derive(Debug, Clone)]
struct Pipeline {
    cfg: Config,
    /// Shared with copies of the pipeline (it never changes).
    aid: std::sync::Arc<HeadingAid>,
    detector: StanceDetector,
    phase: Phase,
    counters: Counters,
    plausibility: Plausibility,
    last: Option<(f64, Vector3<f64>, Vector3<f64>)>,
    bias: BiasFilter,
    /// Filter and bias filter at the last healthy stance (or at alignment).
    good: LastGood<(Eskf, BiasFilter)>,
    good_saved_this_stance: bool,
    /// The filter before the current update (undone when it fails the check). Its buffer and
    /// the running filter's swap at every sample: `navigate` propagates into this one, so the
    /// state before the sample is kept without a copy.
    before: Option<Box<Eskf>>,
    /// The bias filter before the current update.
    before_bias: LastGood<BiasFilter>,
    consecutive_faults: u32,
    /// The time of the last restore of the healthy stance's state, and how many came within
    /// `RESTORE_LOOP_S` of each other (`recovery.rs`).
    restores_in_a_row: (f64, u32),
    /// The tilt is levelled again at the next stance whatever its angle (after restores that
    /// did not hold).
    relevel_next_stance: bool,
    /// Tilt of the sensor on the flat foot: `R_y(pitch)·R_x(roll)` of the initial rest.
    tilt0: UnitQuaternion<f64>,
    /// Sensor yaw minus foot heading.
    mount_yaw_rad: f64,
    /// The foot's forward axis in sensor axes (from `tilt0` and `mount_yaw_rad`).
    forward_body: Vector3<f64>,
    mount_sum: (f64, f64, usize),
    /// The previous footprint (nominal, map frame) and the direction of the stride that ended
    /// there, for the mounting-yaw calibration.
    last_footprint: Option<([f64; 2], Option<f64>)>,
    /// Yaw of the sensor's levelled x axis at the previous footprint: the foot's turn over a
    /// stride is measured from it.
    footprint_yaw_rad: Option<f64>,
    /// The same at the footprint before it, and the time of the last footprint: what a
    /// stride observed one stance late needs (`heading.stride_look_ahead`).
    prev_footprint_yaw_rad: Option<f64>,
    footprint_t_s: f64,
    /// The footprint-line test's verdict at the previous footprint (look-ahead).
    line_before: Option<bool>,
    /// The state was restored from the last healthy stance and no stride has run along its
    /// corridor since: the heading may be off by more than its variance says.
    heading_suspect: bool,
    /// Straight strides in a row that no direction took (`heading.reacquire_strides`).
    off_direction: reacquire::OffDirectionRun,
    /// The heading was taken as lost and its variance widened: the gate is 3σ until a
    /// direction takes a stride or a foot axis again.
    reacquiring: bool,
    straight: StraightWalk,
    line: Option<FootprintLine>,
    stance_events: StanceEvents,
    /// This sample's stance edge (see `step`).
    stance_edge: StanceEdge,
    /// Stance events seen by the running stage (the per-stance bookkeeping runs once per event).
    stances_seen: u64,
    /// The current stance's look at the heading is its second, after a pause (see `navigate`).
    resumed_look: bool,
    /// The previous navigated sample was a stance sample.
    was_stance: bool,
    clock: SampleClock,
    /// The median specific force of the last quiet stances against gravity (`stance_force.rs`).
    stance_force: stance_force::StanceForce,
    /// The last strides' samples and footfalls, to fill a gap in a swing (`stride_memory.rs`).
    memory: stride_memory::StrideMemory,
    /// Short dips of the detector's statistic and stride cycles without a stance that may be a
    /// missed footfall (`late_footfall.rs`).
    late: late_footfall::LateFootfall,
    /// The filter before a gap's fill or a late footfall's replay, to go back to when the
    /// result fails the health check (`late_footfall::keep`; held inline, no allocation).
    undo: LastGood<late_footfall::Anchor>,
    /// The current stance's sums, for the zero-rate update when it turns out to be a rest.
    stance_rest: RestSums,
    /// A rest was fused by a zero-rate update with the current sample (see `step_running`).
    zero_rate_applied: bool,
    /// Gyro axes of the current sample at their rail.
    clipped_gyro_axes: [bool; 3],
    /// The open clipped peak and the filter before it (`rail_peaks.rs`).
    rails: rail_peaks::RailPeaks,
    stance_obs_done: bool,
    stance_f_sum: (Vector3<f64>, u64),
    pending_heading: Option<QueuedHeading>,
    /// External headings taken in (`queue_heading`), and the newest: what was handed in while
    /// samples that are dropped later ran (`drop_glitched_samples`).
    headings_queued: u64,
    last_queued: Option<QueuedHeading>,
    warm_start: Option<WarmStart>,
    converged_at_s: Option<f64>,
    out: Estimate,
}

impl Estimator {
    /// A new estimator with its heading source.
    pub fn new(cfg: Config, aid: HeadingAid) -> Self {
        let detector = StanceDetector::new(&cfg.detector, 9.80665);
        let straight = StraightWalk::new(
            cfg.heading.straight_strides,
            cfg.heading.straight_max_change_rad.get(),
        );
        let p = Pipeline {
            detector,
            straight,
            line: (cfg.heading.line_footprints > 0).then(|| {
                FootprintLine::new(
                    cfg.heading.line_footprints,
                    cfg.heading.line_lateral_m.get(),
                )
            }),
            aid: std::sync::Arc::new(aid),
            phase: Phase::Aligning,
            counters: Counters::default(),
            plausibility: Plausibility::new(cfg.sensor, cfg.max_dt_s.get()),
            last: None,
            bias: BiasFilter::InEskf,
            good: LastGood::default(),
            good_saved_this_stance: false,
            before: None,
            before_bias: LastGood::default(),
            consecutive_faults: 0,
            restores_in_a_row: (f64::NEG_INFINITY, 0),
            relevel_next_stance: false,
            tilt0: UnitQuaternion::identity(),
            mount_yaw_rad: 0.0,
            forward_body: Vector3::x(),
            mount_sum: (0.0, 0.0, 0),
            last_footprint: None,
            footprint_yaw_rad: None,
            prev_footprint_yaw_rad: None,
            footprint_t_s: f64::NAN,
            line_before: None,
            heading_suspect: false,
            off_direction: reacquire::OffDirectionRun::default(),
            reacquiring: false,
            stance_events: StanceEvents::new(cfg.detector.merge_gap_s.get(), cfg.max_dt_s.get()),
            stance_edge: StanceEdge::None,
            stances_seen: 0,
            resumed_look: false,
            was_stance: false,
            clipped_gyro_axes: [false; 3],
            rails: rail_peaks::RailPeaks::default(),
            clock: SampleClock::default(),
            stance_force: stance_force::StanceForce::default(),
            memory: stride_memory::StrideMemory::default(),
            late: late_footfall::LateFootfall::new(&cfg.detector),
            undo: LastGood::default(),
            // Without the motion test: a later rest begins with a landing, which the test,
            // anchored on the first block, would take as the reference and leave every quiet
            // block out (the zero-rate update then never came). The landing is left out as
            // the tail is: in the mean it was a bias error (exp40 with a 20 s pause: 1.5e-3
            // rad/s on y, its heading turned by 3° when the rest was fused).
            stance_rest: RestSums::new(cfg.alignment.rest_tail_s.get(), None)
                .leaving_out_head(cfg.alignment.rest_tail_s.get()),
            zero_rate_applied: false,
            stance_obs_done: false,
            stance_f_sum: (Vector3::zeros(), 0),
            pending_heading: None,
            headings_queued: 0,
            last_queued: None,
            warm_start: None,
            converged_at_s: None,
            out: Estimate::default(),
            cfg,
        };
        Self {
            stage: Stage::Aligning(Box::new(InitialRest::new(
                p.cfg.alignment.rest_tail_s.get(),
                p.cfg.alignment.rest_max_rate_change_rad_s.get(),
                if p.cfg.alignment.fast_gait_replay_s.get() > 0.0 {
                    fast_start::REPLAY_SAMPLES
                } else {
                    0
                },
            ))),
            p,
            before_gap: gap_copy::GapCopy::default(),
            warm_start_since_copy: false,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.p.cfg
    }

    /// Counters so far.
    pub fn counters(&self) -> &Counters {
        &self.p.counters
    }

    /// The phase.
    pub fn phase(&self) -> Phase {
        self.p.phase
    }

    /// The estimate of the last sample accepted by [`Self::step`].
    pub fn last_estimate(&self) -> &Estimate {
        &self.p.out
    }

    /// First time the bias counted as converged.
    pub fn converged_at_s(&self) -> Option<f64> {
        self.p.converged_at_s
    }

    /// The error-state filter's extension estimates (zero for the extensions that are off),
    /// with the σ of the reported ones that are on.
    pub fn extensions(&self) -> Option<(ExtensionEstimates, ExtensionSd)> {
        match &self.stage {
            Stage::Aligning(_) => None,
            Stage::Running(e) => Some((e.ext, e.extension_sd())),
        }
    }

    /// The sensor's yaw on the foot (mounting yaw and toe-out), rad, once calibrated.
    pub fn mount_yaw_rad(&self) -> Option<f64> {
        (self.p.phase == Phase::Tracking).then_some(self.p.mount_yaw_rad)
    }

    /// The median specific force of the last quiet stances, m/s² (`Counters::
    /// specific_force_off_gravity` says when it left gravity), once enough stances were seen.
    pub fn stance_specific_force_m_s2(&self) -> Option<f64> {
        self.p.stance_force.median_m_s2()
    }

    /// The mean specific force of the initial rest the filter aligned on, m/s² (`None` before
    /// alignment, or after a start without a rest).
    pub fn rest_specific_force_m_s2(&self) -> Option<f64> {
        self.p.stance_force.rest_m_s2()
    }

    /// Whether the specific force is off gravity now: the initial rest's or that median said
    /// so, and the median not yet back within half the tolerance.
    pub fn specific_force_off_gravity_now(&self) -> bool {
        self.p.stance_force.is_off()
    }

    /// What said the specific force off gravity, while it is ([`Estimator::
    /// specific_force_off_gravity_now`]): the initial rest, or the quiet stances' median.
    pub fn specific_force_off_gravity_said_by(&self) -> Option<ForceWitness> {
        self.p.stance_force.said_by()
    }

    /// An external observation of the walking (foot) heading in the map frame at sensor time
    /// `t_s` (the samples' clock) with its σ; it is used instead of the map at the first stance
    /// observed from [`EXTERNAL_HEADING_LEAD_S`] before `t_s` on, and only within
    /// [`EXTERNAL_HEADING_MAX_AGE_S`] after it (else counted, `headings_expired`). A time or
    /// heading that is not finite, a σ that is not in (0, π], a time more than
    /// [`EXTERNAL_HEADING_MAX_AHEAD_S`] ahead of the latest sample, or one at least
    /// [`EXTERNAL_HEADING_MAX_AGE_S`] behind it (judged once that sample's time can no longer
    /// be dropped as a glitched stamp: `Plausibility::settled_t_s`), is refused and counted
    /// (`headings_refused`); at the stance, one further than [`EXTERNAL_HEADING_MAX_NIS`] from
    /// the prediction is refused and counted (`headings_outside_gate`): nothing absurd is
    /// fused. Of several before one stance the newest is used, the others counted
    /// (`headings_superseded`).
    pub fn queue_heading(
        &mut self,
        t_s: f64,
        heading_rad: f64,
        sd_rad: f64,
    ) -> Result<(), HeadingRefused> {
        let latest_s = (self.p.counters.samples > 0).then_some(self.p.out.t_s);
        let why = if !(t_s.is_finite()
            && heading_rad.is_finite()
            && sd_rad > 0.0
            && sd_rad <= std::f64::consts::PI)
        {
            Some(WhyRefused::NotANumber)
        } else if let Some(latest_s) = latest_s
            && t_s - latest_s > EXTERNAL_HEADING_MAX_AHEAD_S
        {
            Some(WhyRefused::Ahead { latest_s })
        } else if let Some(latest_s) = self.p.plausibility.settled_t_s()
            && latest_s - t_s >= EXTERNAL_HEADING_MAX_AGE_S
        {
            // No stance to come can use it (one observed later than the latest sample would
            // find it expired, exactly 2 s behind included), and it would take the place of
            // the one waiting.
            Some(WhyRefused::Behind { latest_s })
        } else {
            None
        };
        if let Some(why) = why {
            self.p.counters.headings_refused += 1;
            return Err(HeadingRefused {
                t_s,
                heading_rad,
                sd_rad,
                why,
            });
        }
        let queued = QueuedHeading::new(t_s, heading_rad, sd_rad, self.p.clock.offset_s());
        self.p.headings_queued += 1;
        self.p.last_queued = Some(queued);
        if self.p.pending_heading.replace(queued).is_some() {
            self.p.counters.headings_superseded += 1;
        }
        Ok(())
    }

    /// The stream has ended: an external heading still waiting for a stance will not be used,
    /// and is counted (`headings_expired`; before, it went uncounted).
    pub fn expire_pending_heading(&mut self) {
        if self.p.pending_heading.take().is_some() {
            self.p.counters.headings_expired += 1;
        }
    }

    /// The stream has ended: what waited for samples that will not come is counted, not
    /// dropped silently: an external heading waiting for a stance (`headings_expired`, see
    /// [`Estimator::expire_pending_heading`]) and a clipped peak still open, which has no two
    /// samples off the rail after it to be put back with (`clipped_peaks_not_restored`). Called
    /// by every runner at the end of its stream (offline, the suite's, the daemon's).
    pub fn end_stream(&mut self) {
        self.expire_pending_heading();
        self.p.drop_rail_peak();
    }

    /// Processes one sample. On error nothing changed and the sample is counted as rejected.
    pub fn step(&mut self, s: &ImuInput) -> Result<&Estimate, SampleError> {
        let w = Vector3::from(s.gyro_rad_s);
        // A known accelerometer scale error (`model.accel_scale_factor`) taken out; the
        // plausibility limits are on what the sensor output.
        let f = Vector3::from(s.accel_m_s2) * self.p.cfg.model.accel_correction.get();
        // A step back of the clock is taken where the rates run on across it (`gaps.rs`).
        // (Everything read only when asked: a step back is rare.)
        let (stage, memory, last, cfg) = (&self.stage, &self.p.memory, &self.p.last, &self.p.cfg);
        let clock = &self.p.clock;
        let judge = |back: &StepBack| {
            matches!(stage, Stage::Running(_))
                && gaps::clock_stepped_back(
                    memory,
                    (last.map(|l| l.0), clock),
                    back,
                    (s.t_s, &w, &f),
                    (cfg.model.accel_correction.get(), cfg.max_dt_s.get()),
                )
        };
        let accepted = match self.p.plausibility.check(s, judge) {
            Ok(a) => a,
            Err(e) => {
                let c = &mut self.p.counters;
                *match e {
                    SampleError::NonFinite { .. } => &mut c.rejected_non_finite,
                    SampleError::TimeNotIncreasing { .. } => &mut c.rejected_time,
                    SampleError::Implausible { .. } | SampleError::ZeroFill { .. } => {
                        &mut c.rejected_implausible
                    }
                    SampleError::TimeJump { .. } => &mut c.rejected_time_jump,
                } += 1;
                return Err(e);
            }
        };
        if accepted.replaced_first_t_s.is_some() {
            self.restart_after_time_outlier();
        }
        let glitch_dropped = if accepted.glitch_t_s.is_some() {
            self.drop_glitched_samples()
        } else {
            0
        };
        // Allocates at the first gap and the first after the alignment (see `before_gap`).
        // A warm start handed in since the copy is applied again if the copy is swapped in.
        if accepted.provisional {
            self.before_gap.save(&self.stage, &self.p);
            self.warm_start_since_copy = false;
        } else if !accepted.in_jump_run {
            self.before_gap.forget();
            self.warm_start_since_copy = false;
        }
        let clipped = accepted.clipped;
        let p = &mut self.p;
        let prev = p.last;
        p.counters.samples += 1;
        p.counters.clipped_samples += u64::from(clipped);
        // A gyro axis at its rail read less than the true rate: the attitude variance grows
        // about that axis in `navigate`.
        let rail = p.gyro_rail_rad_s();
        p.clipped_gyro_axes = if clipped {
            w.map(|v| v.abs() >= rail).into()
        } else {
            [false; 3]
        };
        // The clock stepped back, and the sample refused before this one came one sample
        // step after the last: the stamps from here on are taken plus the step.
        let stepped_back_s = accepted.stepped_back.map(|(last_t_s, first_t_s)| {
            StepBack::shift_s(last_t_s, first_t_s, p.clock.period_s())
        });
        if let Some(shift_s) = stepped_back_s {
            p.clock.step_back(shift_s);
            p.counters.clock_steps_back += 1;
        }
        // Integration runs on the sample clock: the stamps, or while they jitter (host arrival
        // times) a smoothed clock.
        let mut t_clock = p.clock.push(s.t_s);
        p.counters.jittery_clock_samples += u64::from(p.clock.jittery());
        // A clock that stepped forward with nothing lost: the time after the step goes on from
        // one sample step after the time before it.
        let clock_step = match (&self.stage, prev) {
            (Stage::Running(_), Some((t_prev, ..))) if t_clock - t_prev > p.cfg.max_dt_s.get() => p
                .clock_step(t_prev, t_clock, &w)
                .map(|step_s| (t_clock - t_prev, step_s)),
            _ => None,
        };
        if let Some((_, step_s)) = clock_step {
            p.clock.take_back(step_s);
            t_clock -= step_s;
        }
        p.last = Some((t_clock, w, f));
        let decision = p.detector.push(t_clock, &w, &f);
        p.stance_edge = p.stance_events.push(t_clock, decision.stance);
        if p.stance_edge == StanceEdge::Began {
            // Whatever the filter makes of this sample: the stride clock of a gap's fill.
            p.memory.footfall(t_clock);
        }
        p.out.begin_sample(s.t_s, &decision, p.stance_edge, clipped);
        let out = &mut p.out;
        if let Some((gap_s, _)) = clock_step {
            out.gap_s = Some(gap_s);
            out.gap_crossing = Some(GapCrossing::ClockStep);
            p.counters.gaps += 1;
            p.counters.gaps_clock_steps += 1;
        }
        out.replaced_first_t_s = accepted.replaced_first_t_s;
        out.glitch_t_s = accepted.glitch_t_s;
        out.glitch_run_dropped = if accepted.glitch_run {
            glitch_dropped
        } else {
            0
        };
        out.clock_stepped_back_s = stepped_back_s;

        if let Stage::Aligning(rest) = &mut self.stage {
            let t_prev = prev.map(|(t_prev, ..)| t_prev);
            let Some(start) = p.align_sample(rest, t_prev, t_clock, s.t_s, (&w, &f), &decision)
            else {
                return Ok(&self.p.out);
            };
            match start {
                Start::Here(eskf) => self.stage = Stage::Running(eskf),
                Start::Earlier(eskf) => {
                    self.stage = Stage::Running(eskf);
                    return Ok(&self.p.out);
                }
            }
        }
        let Stage::Running(eskf) = &mut self.stage else {
            return Ok(&self.p.out); // not reached: aligned just above
        };
        p.step_running(eskf, s.t_s, prev, (&w, &f), &decision);
        Ok(&self.p.out)
    }

    /// Starts from a saved bias state (e.g. a daemon checkpoint) instead of the configured prior:
    /// used at the end of the next alignment, where a rest-mean prior from that alignment's rest
    /// is fused into it (zupt and eskf modes). Attitude is always re-aligned from the
    /// accelerometer, and the map frame from the first stride, because the foot may have moved
    /// while the estimator was down.
    pub fn set_warm_start(&mut self, ws: WarmStart) -> Result<(), WarmStartError> {
        let bound = self.p.cfg.sensor.max_gyro_bias_rad_s();
        let finite = ws.gyro_bias_rad_s.iter().all(|v| v.abs() <= bound)
            && ws.gyro_bias_cov.iter().flatten().all(|v| v.is_finite());
        let p = Matrix3::from_fn(|i, j| ws.gyro_bias_cov[i][j]);
        let symmetric = (p - p.transpose()).abs().max() <= 1e-12 * p.abs().max().max(1e-300);
        let positive = p.cholesky().is_some();
        if !(finite && symmetric && positive) {
            return Err(WarmStartError { state: ws });
        }
        self.p.warm_start = Some(ws);
        self.warm_start_since_copy = true;
        // A clipped peak open now would be propagated again from before the warm start.
        self.p.drop_rail_peak();
        if let Stage::Running(eskf) = &mut self.stage {
            self.p.apply_warm_start(eskf, &ws);
        }
        Ok(())
    }

    /// Gyro bias (sensor axes) and its full covariance: what a checkpoint saves.
    pub fn bias_state(&self) -> Option<WarmStart> {
        let Stage::Running(eskf) = &self.stage else {
            return None;
        };
        let (b, _, _) = self.p.bias_sensor(eskf);
        let p = match &self.p.bias {
            BiasFilter::InEskf => eskf.gyro_bias_cov(),
            BiasFilter::Paper { kf, .. } => {
                let c = self.p.foot_from_sensor().to_rotation_matrix().into_inner();
                c.transpose() * kf.p * c
            }
            BiasFilter::RotationAware { kf, .. } => kf.p,
        };
        Some(WarmStart {
            gyro_bias_rad_s: b.into(),
            gyro_bias_cov: std::array::from_fn(|i| std::array::from_fn(|j| p[(i, j)])),
        })
    }
}

#[cfg(test)]
mod tests;
