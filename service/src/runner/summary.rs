//! `summary.json`: what a run says about itself.

use super::*;

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// The IMU log.
    pub imu: String,
    /// Estimation mode.
    pub mode: &'static str,
    /// Where heading observations came from: `"map"`, `"grid"` or `"none"`.
    pub heading_aid: &'static str,
    /// Final bias, rad/s, sensor axes.
    pub bias_rad_s: [f64; 3],
    /// Final bias σ.
    pub bias_sd_rad_s: [f64; 3],
    /// Mean bias over the converged phase (from `converged_at_s` on), or null.
    pub bias_mean_converged_rad_s: Option<[f64; 3]>,
    /// First time the estimate carried less than `estimator.converged_unabsorbed` of a bias
    /// error present when the bias was set (a real-time criterion), on the log's clock (as the
    /// estimates' `t_s`; `first_t_s` is where that clock started).
    pub converged_at_s: Option<f64>,
    /// Sensor yaw on the foot found by the calibration, degrees.
    pub mount_yaw_deg: Option<f64>,
    /// Injected bias (constant part), rad/s.
    pub injected_gyro_bias_rad_s: [f64; 3],
    /// Injected ramp, rad/s².
    pub injected_gyro_bias_ramp_rad_s2: [f64; 3],
    /// Injection start, s after the log's first sample (`first_t_s`).
    pub injected_after_s: f64,
    /// Rows the injection was added to (0 without one, or when the log ends before
    /// `injected_after_s`).
    pub injected_rows: u64,
    /// The log's first sample time, s, on its own clock: the origin of `injected_after_s`
    /// (the times a user gives count from the log's start), while `converged_at_s` and the
    /// estimates are on the log's clock (a review read the two as one clock).
    pub first_t_s: Option<f64>,
    /// Input rows in the file (accepted by the reader).
    pub samples_read: u64,
    /// Samples the estimator processed.
    pub samples: u64,
    /// Stances.
    pub stances: u64,
    /// ZUPT updates.
    pub zupts: u64,
    /// Gaps (steps above `estimator.max_dt_s`).
    pub gaps: u64,
    /// Of them, bridged (up to `estimator.max_bridge_s`).
    pub gaps_bridged: u64,
    /// Of them, filled from the stride before (`estimator.max_fill_s`).
    pub gaps_filled: u64,
    /// Of them, taken as the clock stepping forward with nothing lost.
    pub gaps_clock_steps: u64,
    /// Steps back of the clock taken as a new time base (the rates ran on across them).
    pub clock_steps_back: u64,
    /// Heading observations used.
    pub heading_observations_used: u64,
    /// Heading observations rejected, by reason.
    pub heading_observations_rejected: BTreeMap<&'static str, u64>,
    /// Stride-direction observations used.
    pub stride_observations_used: u64,
    /// Stride-direction observations rejected (too short, outside the gate or unlikely).
    pub stride_observations_rejected: u64,
    /// Input rows rejected by the CSV reader, by reason.
    pub input_rows_rejected: BTreeMap<&'static str, u64>,
    /// The first few rejected rows, with file, line, column and value.
    pub input_rows_rejected_examples: Vec<String>,
    /// Rows read whose `temp_c` field was empty or no finite number (their temperature unknown;
    /// the rows are used).
    pub input_temperature_missing: u64,
    /// Samples refused by the estimator (after the reader), by reason.
    pub samples_refused_counts: BTreeMap<&'static str, u64>,
    /// The first samples refused by the estimator, with file, line and reason.
    pub samples_refused: Vec<String>,
    /// Accepted samples with an axis at the rail of its range (probably clipped).
    pub clipped_samples: u64,
    /// Clipped gyro peaks whose cut-off rate was put back (see `Counters`).
    pub clipped_peaks_restored: u64,
    /// Clipped gyro peaks not put back, and why they may not be (see `Counters`).
    pub clipped_peaks_not_restored: u64,
    /// Updates that failed the estimator's health check (the last good state was restored).
    pub health_restores: u64,
    /// Of those, the ones that forgot the cloned footprints (see `Counters`).
    pub footprints_forgotten: u64,
    /// Stance updates that found a velocity far beyond what the filter allowed and reset it.
    pub velocity_resets: u64,
    /// Stances at which the tilt was levelled again from gravity (see `Counters`).
    pub relevels: u64,
    /// Times the heading was taken as lost and its variance widened (straight strides in a row
    /// off every direction: `heading.reacquire_strides`).
    pub heading_reacquisitions: u64,
    /// Samples integrated on the smoothed clock because the stamps jitter (host arrival times).
    pub jittery_clock_samples: u64,
    /// External heading observations refused as absurd (an offline run has none; the daemon
    /// takes them from its angle stream).
    pub headings_refused: u64,
    /// External heading observations replaced by a newer one before their stance.
    pub headings_superseded: u64,
    /// External heading observations refused at their stance as too far from the prediction.
    pub headings_outside_gate: u64,
    /// External heading observations not used because their time had passed (no stance within
    /// 2 s after it) or still waiting for a stance when the stream ended.
    pub headings_expired: u64,
    /// External heading observations whose update the health check undid.
    pub headings_undone: u64,
    /// Alignment came from a short first stance (no initial rest, no rest-mean prior).
    pub started_without_rest: bool,
    /// Rests or first stances not aligned on because their mean specific force was no
    /// gravity (`Counters::alignment_not_gravity`).
    pub alignment_not_gravity: u64,
    /// Times the initial rest's specific force or the quiet stances' median left gravity by
    /// more than `core::SPECIFIC_FORCE_TOLERANCE` (an accelerometer scale or units wrong;
    /// `Counters::specific_force_off_gravity`).
    pub specific_force_off_gravity: u64,
    /// The initial rest's mean specific force, m/s² (`null` without a rest).
    pub rest_specific_force_m_s2: Option<f64>,
    /// That median at the end of the log, m/s² (`null` before enough quiet stances).
    pub stance_specific_force_m_s2: Option<f64>,
    /// The specific force was off gravity at the end of the log (said, by the rest or the
    /// median, and the median not back within half the tolerance).
    pub specific_force_off_gravity_at_end: bool,
    /// A start in fast gait went back this far, ms, to an earlier stance (see `Counters`).
    pub start_replayed_ms: u64,
    /// The initial rest turned faster than a bias of the sensor can be
    /// (`alignment.max_prior_rate_rad_s`, `sensor.max_gyro_bias_rad_s`): no rest-mean prior.
    pub rest_prior_refused: bool,
    /// 50 ms blocks of the initial rest left out of the bias prior and the tilt because the
    /// foot moved in them.
    pub initial_rest_moving_blocks: u64,
    /// How far the final bias lies from the unit's typical one (plus what was injected), in its
    /// σ, on the farthest axis (`alignment.typical_gyro_bias_rad_s`; `None` without one, or with
    /// an injected ramp).
    pub bias_from_typical_sd: Option<f64>,
    /// Zero-rate updates of the bias at rests after the alignment.
    pub zero_rate_updates: u64,
    /// Rests not fused (see the estimator's counter of the same name).
    pub zero_rate_refused: u64,
    /// Footfalls the detector missed, updated late (`detector.late_stance_min_s`,
    /// `detector.overdue_stride_factor`).
    pub late_footfalls: u64,
    /// Late footfalls whose update was not made (see the estimator's counter).
    pub late_footfalls_dropped: u64,
    /// What the input did that a user should know about, in words (the notes `corridor run`
    /// prints; they were printed only, and lost with the terminal).
    pub notes: Vec<String>,
    /// Footprint evaluation (first-leg alignment), when truth was given.
    pub eval: Option<EvalReport>,
    /// The files this run wrote into its output directory (names), this one included: what a
    /// later run into the same directory may remove when it does not write them again.
    pub outputs: Vec<String>,
}
