//! The validated configuration: types that cannot hold a bad value.

use super::*;
use serde::Serialize;

/// A validated configuration.
#[derive(Debug, Clone, Serialize)]
pub struct Config {
    /// Bias estimation mode.
    pub mode: Mode,
    /// Convergence bound on the part of a start bias error the estimate still carries.
    pub converged_unabsorbed: Fraction,
    /// Largest regular time step.
    pub max_dt_s: Positive,
    /// Longest gap bridged by one step (0: none).
    pub max_bridge_s: NonNegative,
    /// Longest gap filled from the stride before (0: none).
    pub max_fill_s: NonNegative,
    /// Largest plausible foot speed (health check).
    pub max_speed_m_s: Positive,
    /// What the sensor can output, and the time-step bounds.
    pub sensor: crate::sensor::SensorLimits,
    /// Alignment.
    pub alignment: AlignmentConfig,
    /// Zero-velocity detection.
    pub detector: DetectorConfig,
    /// ZUPT filter.
    pub eskf: EskfConfig,
    /// The paper's bias filter.
    pub bias_kf: BiasKfConfig,
    /// Heading aiding.
    pub heading: HeadingConfig,
    /// Model extensions.
    pub model: ModelSettings,
}

/// Validated `[model]`: `None` = extension off.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ModelSettings {
    /// Bias-rate random walk.
    pub bias_rate_rw_rad_s2_sqrt_s: Option<Positive>,
    /// Initial σ of the bias rate.
    pub bias_rate_initial_sd_rad_s2: Positive,
    /// Scale-factor initial σ.
    pub scale_factor_sd: Option<Positive>,
    /// Heading-offset initial σ, rad.
    pub heading_offset_sd_rad: Option<Positive>,
    /// g-sensitivity initial σ.
    pub g_sensitivity_sd: Option<Positive>,
    /// Cross-coupling (into the sensor z axis) initial σ, rad.
    pub gyro_coupling_z_sd_rad: Option<Positive>,
    /// What every sample's specific force is multiplied by: `1 / (1 + model.accel_scale_factor)`
    /// (1 without it).
    pub accel_correction: Positive,
}

/// Validated `[daemon]`.
#[derive(Debug, Clone, Serialize)]
pub struct DaemonSettings {
    /// Domain name (validated again, against iceoryx2's rules, when the daemon opens it).
    pub domain: String,
    /// `true` for lossless delivery.
    pub lossless: bool,
    /// Channel capacity (≥ 1).
    pub channel_capacity: usize,
    /// Bias sample period.
    pub bias_period_s: Positive,
    /// Diagnostics period.
    pub diagnostics_period_s: Positive,
    /// Health log period.
    pub health_period_s: Positive,
    /// Checkpoint file.
    pub checkpoint_path: Option<PathBuf>,
    /// Runtime directory of the secured domain (absolute), or `None` for the open domain.
    pub runtime_dir: Option<PathBuf>,
    /// Checkpoint period.
    pub checkpoint_period_s: Positive,
    /// Stall bound of lossless publishing.
    pub stall_timeout_s: Positive,
    /// Silence of the followed IMU producer after which another one takes over.
    pub producer_takeover_s: Positive,
}

/// Validated `[alignment]`.
#[derive(Debug, Clone, Serialize)]
pub struct AlignmentConfig {
    /// Shortest initial rest.
    pub min_rest_s: Positive,
    /// Gyro-bias prior.
    pub gyro_bias_prior: BiasPrior,
    /// Fixed gravity, or `None` for the rest mean.
    pub gravity_m_s2: Option<Positive>,
    /// Tail of the rest left out of the means.
    pub rest_tail_s: NonNegative,
    /// An initial-rest block further than this from the rest's mean rate is motion, rad/s.
    pub rest_max_rate_change_rad_s: Positive,
    /// Shortest first stance that aligns without a rest (0: wait for a rest).
    pub min_start_stance_s: NonNegative,
    /// Shortest stance seen whole that aligns in fast gait (the detector's threshold raised).
    pub fast_gait_start_stance_s: NonNegative,
    /// How far back a start in fast gait may go, s (0: off).
    pub fast_gait_replay_s: NonNegative,
    /// σ of roll and pitch when a walking stance aligns (no rest), rad.
    pub start_stance_tilt_sd_rad: Positive,
    /// The largest initial-rest mean rate (magnitude) taken as the bias prior, rad/s (`None`:
    /// only the sensor's largest bias, per axis).
    pub max_prior_rate_rad_s: Option<Positive>,
    /// Where the bias starts without a rest, with the rest-mean prior (`None`: zero, with
    /// `eskf.gyro_bias_initial_sd_rad_s`).
    pub typical_gyro_bias: Option<TypicalGyroBias>,
}

/// A sensor unit's typical gyro bias (`alignment.typical_gyro_bias_rad_s` and its σ): each
/// axis finite and within `sensor.max_gyro_bias_rad_s`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TypicalGyroBias {
    /// The bias, rad/s, sensor axes.
    pub rad_s: [f64; 3],
    /// Its σ on each axis, rad/s.
    pub sd_rad_s: Positive,
}

/// Validated `[detector]`.
#[derive(Debug, Clone, Serialize)]
pub struct DetectorConfig {
    /// Statistic.
    pub kind: DetectorKind,
    /// Window in samples (≥ 1).
    pub window: usize,
    /// Threshold.
    pub threshold: Positive,
    /// Accelerometer σ.
    pub sigma_accel_m_s2: Positive,
    /// Gyro σ.
    pub sigma_gyro_rad_s: Positive,
    /// Shortest stance.
    pub min_stance_s: NonNegative,
    /// Longest pause inside one stance.
    pub merge_gap_s: NonNegative,
    /// Adaptive factor (off when `None`).
    pub adaptive_factor: Option<Positive>,
    /// Adaptive look-back.
    pub adaptive_window_s: Positive,
    /// Largest adaptive threshold.
    pub adaptive_max_threshold: Positive,
    /// Shortest dip taken as a late footfall (off when `None`).
    pub late_stance_min_s: Option<Positive>,
    /// Stride periods after which a footfall is overdue (off when `None`).
    pub overdue_stride_factor: Option<Positive>,
}

/// Validated `[eskf]`.
#[derive(Debug, Clone, Serialize)]
pub struct EskfConfig {
    /// Accelerometer white-noise density, m/s²/√Hz.
    pub accel_noise_m_s2: Positive,
    /// Gyro white-noise density, rad/s/√Hz.
    pub gyro_noise_rad_s: Positive,
    /// Gyro-bias random walk.
    pub gyro_bias_rw_rad_s_sqrt_s: NonNegative,
    /// Initial bias σ without prior (about zero); the rest-mean prior is fused with it.
    pub gyro_bias_initial_sd_rad_s: Positive,
    /// Floor of the rest-mean prior's σ.
    pub gyro_bias_prior_sd_rad_s: Positive,
    /// ZUPT σ.
    pub zupt_sd_m_s: Positive,
    /// Initial tilt σ.
    pub initial_tilt_sd_rad: Positive,
    /// ZUPT lever arm (0 = a constant ZUPT σ).
    pub zupt_lever_arm_m: NonNegative,
    /// The covariance's propagation interval between updates (0 = every sample).
    pub covariance_step_s: NonNegative,
    /// Zero-rate updates at later rests.
    pub zero_rate_updates: bool,
    /// A long rest is fused every this many seconds of its settled part.
    pub zero_rate_interval_s: Positive,
    /// Gyro noise density while the foot rests, rad/s/√Hz.
    pub rest_gyro_noise_rad_s: Positive,
    /// Above this yaw σ the stance updates leave the yaw alone (0: off).
    pub stance_yaw_max_sd_rad: NonNegative,
    /// Sensor height above the rolling contact (0: plain ZUPT).
    pub zupt_rolling_height_m: NonNegative,
    /// σ of the true rate's excess over a clipped gyro axis.
    pub clipped_rate_sd_rad_s: NonNegative,
    /// Peaks cut off by a gyro rail put back (a parabola through the samples around each run).
    pub restore_clipped_peaks: bool,
}

/// Validated `[bias_kf]`.
#[derive(Debug, Clone, Serialize)]
pub struct BiasKfConfig {
    /// Roll/pitch reference σ.
    pub tilt_sd_rad: Positive,
    /// Bias random walk.
    pub bias_rw_rad_s_sqrt_s: NonNegative,
}

/// Validated `[heading]`, angles in radians.
#[derive(Debug, Clone, Serialize)]
pub struct HeadingConfig {
    /// Source.
    pub source: HeadingSource,
    /// Observation σ.
    pub sigma_rad: Positive,
    /// Grid orientation.
    pub grid_rad: Finite,
    /// Grid spacing.
    pub grid_step_rad: Positive,
    /// Start walking direction.
    pub start_heading_rad: Finite,
    /// Association gate.
    pub gate_rad: Positive,
    /// Straight-walk limit.
    pub straight_max_change_rad: Positive,
    /// Straight-walk look-back.
    pub straight_strides: usize,
    /// Mounting-yaw calibration stances.
    pub calibration_strides: usize,
    /// Observation delay into a stance.
    pub obs_delay_s: NonNegative,
    /// σ of the start heading.
    pub start_heading_sd_rad: Positive,
    /// Observations of the `eskf` mode.
    pub observations: HeadingObservations,
    /// Stride-direction σ.
    pub stride_sigma_rad: Positive,
    /// Shortest observed stride.
    pub min_stride_m: Positive,
    /// Footprints of the straight-line test (0 = off).
    pub line_footprints: usize,
    /// Largest lateral distance of the straight-line test.
    pub line_lateral_m: Positive,
    /// Stride observations one stance late (the line test with the next footprint too).
    pub stride_look_ahead: bool,
    /// Largest angle between a fused foot axis's direction and the stride before it (`None`:
    /// no such test).
    pub foot_axis_stride_max_rad: Option<Positive>,
    /// Prior probability of an aligned stance.
    pub aligned_prior: Fraction,
    /// Smallest fused association weight.
    pub min_weight: Fraction,
    /// Straight strides in a row, off every direction by one angle, after which the heading is
    /// taken as lost (`None`: never).
    pub reacquire_strides: Option<u32>,
}

impl Default for DaemonSettings {
    fn default() -> Self {
        ConfigFile::default()
            .validate_daemon()
            .expect("the built-in daemon defaults are valid")
    }
}

impl Default for Config {
    fn default() -> Self {
        ConfigFile::default()
            .validate()
            .expect("the built-in defaults are valid")
    }
}
