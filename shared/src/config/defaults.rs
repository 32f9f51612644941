//! Every default of the configuration, in one place: the value a key takes when the file
//! leaves it out. Each sensor's file (`configs/*.toml`) sets its own figures with how they were
//! chosen; these are the generic fallbacks. Units are in the names, as in the keys. (The
//! `[sensor]` limits keep theirs beside their rules, in `crate::sensor`.) Angles given in
//! degrees in the file are converted exactly as `f64::to_radians` does.

use super::{BiasPrior, DetectorKind, HeadingObservations, HeadingSource, Mode};

/// `estimator.max_speed_m_s`: the swinging foot of a sprinter peaks near 10 m/s.
pub const ESTIMATOR_MAX_SPEED_M_S: f64 = 15.0;

/// `alignment.min_start_stance_s`: a walking stance lasts 0.2–0.6 s; a tenth of a second of
/// quiet foot gives roll and pitch to a few tenths of a degree (0: wait for a rest).
pub const ALIGNMENT_MIN_START_STANCE_S: f64 = 0.1;

/// `alignment.fast_gait_start_stance_s`: six samples at 200 Hz.
pub const ALIGNMENT_FAST_GAIT_START_STANCE_S: f64 = 0.03;

/// `alignment.fast_gait_replay_s`: two of the stance detector's look-backs
/// (`detector.adaptive_window_s`): the fast-gait rule needs one whole look-back of raised
/// threshold, and a start found by it came 1.7-2.1 s after a cut into a fast walk.
pub const ALIGNMENT_FAST_GAIT_REPLAY_S: f64 = 3.0;

/// `alignment.start_stance_tilt_sd_rad`: 2°, what a walking stance's mean specific force says
/// of roll and pitch.
pub const ALIGNMENT_START_STANCE_TILT_SD_RAD: f64 = 0.035;

/// `eskf.clipped_rate_sd_rad_s`: the RMS excess of the peaks reconstructed (a parabola through
/// the samples around each clipped run) in the 110 clipped runs of the 16 gdins walks was
/// 0.44 rad/s.
pub const ESKF_CLIPPED_RATE_SD_RAD_S: f64 = 0.5;

/// `eskf.restore_clipped_peaks`: a peak a gyro rail cut off is put back (`rail_peaks.rs`).
pub const ESKF_RESTORE_CLIPPED_PEAKS: bool = true;

/// `daemon.delivery`: a slow consumer loses the oldest samples, never stalls the daemon.
pub const DAEMON_DELIVERY: &str = "live";

/// `daemon.channel_capacity`, samples: 20 s at 200 Hz between the receive and estimator threads.
pub const DAEMON_CHANNEL_CAPACITY: usize = 4096;

/// Largest `daemon.channel_capacity`, samples. The channel preallocates (and writes) one slot
/// per sample when the daemon starts, about 100 bytes each (an `ImuSample` of 88 bytes, the
/// message's tag and the channel's stamp): 2^19 slots are about 55 MB and hold 44 min at
/// 200 Hz. The estimator takes a sample in microseconds, so a backlog of minutes means it
/// cannot keep up at all, and more only costs memory (2^24 was accepted and took 1.7 GB at
/// start, beyond the 256 MB `MemoryMax` of the shipped unit, `configs/corridor.service`).
pub const DAEMON_CHANNEL_CAPACITY_MAX: usize = 1 << 19;

/// `daemon.domain`.
pub const DAEMON_DOMAIN: &str = "default";

/// `daemon.bias_period_s`, s of sensor time between bias samples.
pub const DAEMON_BIAS_PERIOD_S: f64 = 1.0;

/// Shortest `daemon.bias_period_s`, s of sensor time. The bias changes only at the filter's
/// updates, by far less than its σ from one to the next; ten samples a second see every
/// stance. Shorter (down to 1e-9, which was accepted) only sends the bias at every IMU sample,
/// an output as heavy as the attitude's for nothing.
pub const DAEMON_BIAS_PERIOD_MIN_S: f64 = 0.1;

/// Longest `daemon.bias_period_s` and `daemon.diagnostics_period_s`, s: a periodic output at
/// least once a minute. Beyond it a consumer waits minutes for its first value (`corridor
/// status --watch` gives up after its `--timeout-s`), and a lossless consumer that stalled is
/// waited on again at every one of its samples (the daemon forgets a stall after a minute of
/// quiet, `RECOVERED_AFTER` in `service/src/daemon/stall.rs`).
pub const DAEMON_OUTPUT_PERIOD_MAX_S: f64 = 60.0;

/// `daemon.diagnostics_period_s`, s.
pub const DAEMON_DIAGNOSTICS_PERIOD_S: f64 = 1.0;

/// Shortest wall-clock period or wait of the `[daemon]` section (`diagnostics_period_s`,
/// `health_period_s`, `checkpoint_period_s`, `stall_timeout_s`, `producer_takeover_s`), s: the
/// slice every wait on an iceoryx2 event is cut into
/// ([`EVENT_WAIT_SLICE`](crate::services::EVENT_WAIT_SLICE)), the daemon's and its clients'.
/// A shorter period is due at every wake-up: `health_period_s = 1e-9` logged a health line,
/// and published diagnostics, at every IMU sample, and spun a core when no sample came; a
/// shorter stall timeout or take-over time takes a consumer or producer that is only between
/// two of its wake-ups for a stalled or silent one.
pub const DAEMON_WAKE_S: f64 = crate::services::EVENT_WAIT_SLICE.as_secs_f64();

/// `daemon.health_period_s`, s between health log lines.
pub const DAEMON_HEALTH_PERIOD_S: f64 = 10.0;

/// Longest `daemon.health_period_s`, s: a health line at least every hour, so that the log
/// says the daemon's rates and losses before any incident.
pub const DAEMON_HEALTH_PERIOD_MAX_S: f64 = 3600.0;

/// `daemon.checkpoint_period_s`, s.
pub const DAEMON_CHECKPOINT_PERIOD_S: f64 = 30.0;

/// Longest `daemon.checkpoint_period_s`, s: a day. The daemon also saves at each end of stream
/// and at shutdown; a daemon killed loses at most this much of its bias state's history.
pub const DAEMON_CHECKPOINT_PERIOD_MAX_S: f64 = 86400.0;

/// `daemon.stall_timeout_s`: a lossless consumer that takes nothing for this long is dropped, s.
pub const DAEMON_STALL_TIMEOUT_S: f64 = 1.0;

/// Longest `daemon.stall_timeout_s`, s. While a publish waits on a consumer's full buffer the
/// estimator thread waits with it: no output to anyone, no diagnostics, the input queue
/// filling, and a stop (SIGTERM) waits for it. A dead consumer held the daemon for as long as
/// 1e9 s allowed. (Under the shipped unit, `configs/corridor.service`, a stop has 10 s before
/// SIGKILL, which costs the last checkpoint: keep it well below that there.)
pub const DAEMON_STALL_TIMEOUT_MAX_S: f64 = 60.0;

/// `daemon.producer_takeover_s`: another IMU producer takes over from the followed one once this
/// has sent nothing for this long, s. A driver at 100 Hz or more sends many times within it; a
/// replacement started by hand or by a supervisor after a hang waits at most this.
pub const DAEMON_PRODUCER_TAKEOVER_S: f64 = 1.0;

/// Longest `daemon.producer_takeover_s`, s: the replacement of a hung driver loses the walk
/// that passes while it waits; beyond a minute a hung driver is no longer replaced in any
/// useful time.
pub const DAEMON_PRODUCER_TAKEOVER_MAX_S: f64 = 60.0;

/// `detector.window`, samples.
pub const DETECTOR_WINDOW: usize = 5;

/// `heading.straight_strides`.
pub const HEADING_STRAIGHT_STRIDES: usize = 2;

/// `heading.calibration_strides`: straight strides that fix the mounting yaw.
pub const HEADING_CALIBRATION_STRIDES: usize = 3;

/// `model.bias_rate_initial_sd_rad_s2`.
pub const MODEL_BIAS_RATE_INITIAL_SD_RAD_S2: f64 = 1e-4;

/// `estimator.mode`.
pub const ESTIMATOR_MODE: Mode = Mode::Eskf;

/// `estimator.converged_unabsorbed`: 95 % of a start bias error absorbed.
pub const ESTIMATOR_CONVERGED_UNABSORBED: f64 = 0.05;

/// `estimator.max_dt_s`: a longer step is a gap (bridged up to `max_bridge_s`, filled from the
/// stride before up to `max_fill_s`, else a new segment), s.
pub const ESTIMATOR_MAX_DT_S: f64 = 0.05;

/// `estimator.max_bridge_s`: a gap up to this long is bridged (one step with the rates and
/// forces on both sides of it). Samples cut out of the 14 normal-gait gdins walks at three places
/// each (`docs/experiments/gap-cuts.py`; footprint RMS change, % of path, median / worst, and
/// cuts worse by more than 0.1), as a new segment against bridged: 55 ms +0.02 / +4.30 (16 of
/// 42) against +0.00 / +0.17 (1); 0.1 s +0.06 / +6.54 (20) against +0.00 / +1.82 (7); 0.15 s
/// +0.16 / +8.59 (23) against +0.00 / +2.11 (13); 0.2 s +0.27 / +10.43 (26) against +0.08 /
/// +34.21 (19); 0.3 s +0.34 / +13.79 (28) against +0.62 / +29.00 (31). So the 0.15 s cut, the
/// longest measured at which the bridge is better on all three (it leaves a step of 0.155 s:
/// 0.16). Chosen on the footprints of the whole suite, said so. Measured again in session 17
/// (`configs/gdins.toml`): the bridge keeps the better median and count up to 0.15 s, but its
/// worst case is now worse than a new segment's at 0.1 s (+8.44 against +5.99).
pub const ESTIMATOR_MAX_BRIDGE_S: f64 = 0.16;

/// `estimator.max_fill_s`: a gap longer than `max_bridge_s` up to this long (and within half the
/// last stride period) is filled with the same phase of the stride before, when the rates around
/// it match that stride's (0: off). Samples cut out of the 14 normal-gait gdins walks
/// (`docs/experiments/gap-cuts.py`; footprint RMS change, % of path, median, and cuts worse by
/// more than 0.1, of 42), as a new segment against filled: 0.2 s +0.29 (27) against +0.01 (13);
/// 0.3 s +0.36 (31) against +0.01 (13); 0.4 s +0.67 (37) against +0.02 (17). At 0.55 s filling
/// was worse in sum; 0.45 s fills a 0.4 s cut (a step of 0.405 s).
pub const ESTIMATOR_MAX_FILL_S: f64 = 0.45;

/// `alignment.min_rest_s`, s.
pub const ALIGNMENT_MIN_REST_S: f64 = 0.5;

/// `alignment.gyro_bias_prior`.
pub const ALIGNMENT_GYRO_BIAS_PRIOR: BiasPrior = BiasPrior::RestMean;

/// `alignment.rest_tail_s`: the end of a rest left out of its means, s.
pub const ALIGNMENT_REST_TAIL_S: f64 = 0.5;

/// `alignment.rest_max_rate_change_rad_s`: a 50 ms block of the initial rest whose mean rate lies further
/// than this from the rest's mean so far is motion, rad/s (about 3°/s: the quiet parts of the
/// bundled rests sway by up to about 0.03 rad/s, a foot that rocks before its first step by
/// 0.04–0.2).
pub const ALIGNMENT_REST_MAX_RATE_CHANGE_RAD_S: f64 = 0.05;

/// `detector.kind`.
pub const DETECTOR_KIND: DetectorKind = DetectorKind::Shoe;

/// `detector.threshold` (SHOE: about 0.55 rad/s of rotation at the default σ).
pub const DETECTOR_THRESHOLD: f64 = 1e5;

/// `detector.sigma_accel_m_s2`.
pub const DETECTOR_SIGMA_ACCEL_M_S2: f64 = 0.01;

/// `detector.sigma_gyro_rad_s` (0.1°/s).
pub const DETECTOR_SIGMA_GYRO_RAD_S: f64 = 0.1 * (std::f64::consts::PI / 180.0);

/// `detector.min_stance_s`.
pub const DETECTOR_MIN_STANCE_S: f64 = 0.04;

/// `detector.merge_gap_s`: stances split by a shorter pause of the detector are one footfall,
/// s. Between footfalls the foot swings for at least 0.65 s even in fast gait (the gaps between
/// detected stances over the 16 gdins walks fall below 0.3 s or above 0.65 s, nothing between).
pub const DETECTOR_MERGE_GAP_S: f64 = 0.3;

/// `detector.adaptive_window_s`: about one stride cycle, s.
pub const DETECTOR_ADAPTIVE_WINDOW_S: f64 = 1.5;

/// `detector.adaptive_max_threshold` when absent: this many times the fixed threshold.
pub const DETECTOR_ADAPTIVE_MAX_FACTOR: f64 = 10.0;

/// `eskf.accel_noise_m_s2` (generic and pessimistic; each sensor config sets its own).
pub const ESKF_ACCEL_NOISE_M_S2: f64 = 0.5;

/// `eskf.gyro_noise_rad_s`.
pub const ESKF_GYRO_NOISE_RAD_S: f64 = 0.01;

/// `eskf.gyro_bias_rw_rad_s_sqrt_s`.
pub const ESKF_GYRO_BIAS_RW_RAD_S_SQRT_S: f64 = 1e-4;

/// `eskf.gyro_bias_initial_sd_rad_s`: the bias σ without a prior.
pub const ESKF_GYRO_BIAS_INITIAL_SD_RAD_S: f64 = 0.01;

/// `eskf.gyro_bias_prior_sd_rad_s`: the floor of the rest-mean prior's σ.
pub const ESKF_GYRO_BIAS_PRIOR_SD_RAD_S: f64 = 5e-4;

/// `eskf.zupt_sd_m_s`.
pub const ESKF_ZUPT_SD_M_S: f64 = 0.01;

/// `eskf.initial_tilt_sd_rad` (0.5°).
pub const ESKF_INITIAL_TILT_SD_RAD: f64 = 0.5 * (std::f64::consts::PI / 180.0);

/// `eskf.zupt_lever_arm_m` (0: a constant ZUPT σ).
pub const ESKF_ZUPT_LEVER_ARM_M: f64 = 0.0;

/// `eskf.covariance_step_s`: between updates the covariance is propagated at about 50 Hz, on
/// the samples' summed transition (0: on every sample). Chosen in session 46 on the whole
/// gdins suite against 0, 0.01 and 0.04 s (the figures in `configs/gdins.toml`; README, "How
/// the estimator works").
pub const ESKF_COVARIANCE_STEP_S: f64 = 0.02;

/// `eskf.zero_rate_updates`.
pub const ESKF_ZERO_RATE_UPDATES: bool = true;

/// `eskf.zero_rate_interval_s`: a long rest is fused every 2 s of its settled part.
pub const ESKF_ZERO_RATE_INTERVAL_S: f64 = 2.0;

/// `eskf.rest_gyro_noise_rad_s`: ten times the quietest rests' noise density of the gdins
/// sensor (about 1e-4 rad/s/√Hz, its datasheet's 0.005 °/s/√Hz), the swaying ones' level.
pub const ESKF_REST_GYRO_NOISE_RAD_S: f64 = 1e-3;

/// `eskf.stance_yaw_max_sd_rad` (0: the stance updates move the yaw whatever its σ).
pub const ESKF_STANCE_YAW_MAX_SD_RAD: f64 = 0.0;

/// `eskf.zupt_rolling_height_m` (0: a plain zero-velocity update).
pub const ESKF_ZUPT_ROLLING_HEIGHT_M: f64 = 0.0;

// The floors of the σ keys. A σ only had to be > 0: one whose square underflows (below
// about 1.5e-154) is a variance of exactly 0: with the `[eskf]` and `[heading]` σ at 1e-300
// (and no bias random walk) exp36's filter froze, its bias σ exactly 0, one heading used in
// 3089 stances, 17 % of path off, nothing said (an update whose S is singular changes
// nothing). An observation σ far below what the measurement can
// be made the rotation-aware filter trust it to ruin without a health restore to show for it
// (`bias_kf.tilt_sd_rad` = 1e-4: exp36 30 % of path; `heading.sigma_deg` = 0.1: exp17 15 %,
// bias 0.08 rad/s; at 1e-5 rad and 1e-3° two restores, bias 0.17 rad/s). Each floor lies at
// or below what the best sensor or observation of its kind gives (the tilt's at a calibrated
// accelerometer's 1 mg); within them a filter can be tuned badly, not broken.

/// Smallest tilt σ (`eskf.initial_tilt_sd_rad`, `bias_kf.tilt_sd_rad`,
/// `alignment.start_stance_tilt_sd_rad`), rad (0.06°): a tilt from the specific force is known
/// no better than the accelerometer's bias allows, about 1 mg (1e-3 rad) once calibrated.
pub const TILT_SD_MIN_RAD: f64 = 1e-3;

/// Smallest `eskf.accel_noise_m_s2`, m/s²/√Hz (10 µg/√Hz): below the quietest MEMS
/// accelerometers (about 20 µg/√Hz).
pub const ACCEL_NOISE_MIN_M_S2: f64 = 1e-4;

/// Smallest `eskf.gyro_noise_rad_s` and `eskf.rest_gyro_noise_rad_s`, rad/s/√Hz
/// (0.0006 °/s/√Hz): below the quietest MEMS gyros (about 0.002 °/s/√Hz, 3.5e-5).
pub const GYRO_NOISE_MIN_RAD_S: f64 = 1e-5;

/// Smallest gyro-bias σ of a prior (`eskf.gyro_bias_initial_sd_rad_s`,
/// `eskf.gyro_bias_prior_sd_rad_s`, `alignment.typical_gyro_bias_sd_rad_s`), rad/s (0.2 °/h):
/// below the bias stability of the best MEMS gyros.
pub const GYRO_BIAS_SD_MIN_RAD_S: f64 = 1e-6;

/// Smallest `eskf.zupt_sd_m_s`, m/s: a foot on the floor is still to about a millimetre per
/// second (it rolls), not to 0.1 mm/s.
pub const ZUPT_SD_MIN_M_S: f64 = 1e-4;

/// Smallest `heading.sigma_deg`, degrees: a walker's foot axis varies from one stance to the
/// next by degrees about the corridor's direction, not by half a degree.
pub const FOOT_AXIS_SD_MIN_DEG: f64 = 0.5;

/// Smallest `heading.stride_sigma_deg` and `heading.start_heading_sd_deg`, degrees: a stride's
/// direction between two footprints 1.4 m apart, each placed to about 2 cm, is known to about
/// 1°; ten times better is no stride.
pub const STRIDE_SD_MIN_DEG: f64 = 0.1;

/// `bias_kf.tilt_sd_rad` (1°).
pub const BIAS_KF_TILT_SD_RAD: f64 = std::f64::consts::PI / 180.0;

/// `bias_kf.bias_rw_rad_s_sqrt_s`.
pub const BIAS_KF_BIAS_RW_RAD_S_SQRT_S: f64 = 1e-5;

/// `heading.source`.
pub const HEADING_SOURCE: HeadingSource = HeadingSource::Grid;

/// `heading.sigma_deg`: the foot-axis observation's σ.
pub const HEADING_SIGMA_DEG: f64 = 3.0;

/// `heading.grid_deg`.
pub const HEADING_GRID_DEG: f64 = 0.0;

/// `heading.grid_step_deg`: corridors at right angles.
pub const HEADING_GRID_STEP_DEG: f64 = 90.0;

/// `heading.start_heading_deg`.
pub const HEADING_START_HEADING_DEG: f64 = 0.0;

/// `heading.gate_deg`.
pub const HEADING_GATE_DEG: f64 = 15.0;

/// `heading.straight_max_change_deg`.
pub const HEADING_STRAIGHT_MAX_CHANGE_DEG: f64 = 10.0;

/// `heading.obs_delay_s`: stance age at which the observations are made, s.
pub const HEADING_OBS_DELAY_S: f64 = 0.05;

/// `heading.start_heading_sd_deg`.
pub const HEADING_START_HEADING_SD_DEG: f64 = 1.0;

/// `heading.observations`.
pub const HEADING_OBSERVATIONS: HeadingObservations = HeadingObservations::Both;

/// `heading.stride_sigma_deg`.
pub const HEADING_STRIDE_SIGMA_DEG: f64 = 2.0;

/// `heading.min_stride_m`: shorter displacements are shuffles, m.
pub const HEADING_MIN_STRIDE_M: f64 = 0.5;

/// `heading.line_footprints` (0: no footprint-line test).
pub const HEADING_LINE_FOOTPRINTS: usize = 0;

/// `heading.line_lateral_m`.
pub const HEADING_LINE_LATERAL_M: f64 = 0.05;

/// `heading.stride_look_ahead`.
pub const HEADING_STRIDE_LOOK_AHEAD: bool = false;

/// `heading.aligned_prior`: prior probability of walking along a dominant direction.
pub const HEADING_ALIGNED_PRIOR: f64 = 0.7;

/// `heading.min_weight`.
pub const HEADING_MIN_WEIGHT: f64 = 0.5;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::ConfigFile;

    #[test]
    fn an_empty_file_takes_every_default_and_degrees_convert_as_to_radians_does() {
        let c = ConfigFile::default().validate().unwrap();
        assert_eq!(c.mode, ESTIMATOR_MODE);
        assert_eq!(c.max_speed_m_s.get(), ESTIMATOR_MAX_SPEED_M_S);
        assert_eq!(c.detector.window, DETECTOR_WINDOW);
        assert_eq!(c.detector.sigma_gyro_rad_s.get(), 0.1f64.to_radians());
        assert_eq!(c.eskf.initial_tilt_sd_rad.get(), 0.5f64.to_radians());
        assert_eq!(c.bias_kf.tilt_sd_rad.get(), 1.0f64.to_radians());
        assert_eq!(c.heading.sigma_rad.get(), HEADING_SIGMA_DEG.to_radians());
        assert_eq!(
            c.eskf.clipped_rate_sd_rad_s.get(),
            ESKF_CLIPPED_RATE_SD_RAD_S
        );
        assert_eq!(
            c.detector.adaptive_max_threshold.get(),
            DETECTOR_ADAPTIVE_MAX_FACTOR * DETECTOR_THRESHOLD
        );
        let d = ConfigFile::default().validate_daemon().unwrap();
        assert_eq!(d.domain, DAEMON_DOMAIN);
        assert_eq!(d.channel_capacity, DAEMON_CHANNEL_CAPACITY);
    }
}
