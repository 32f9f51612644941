//! The one validation pass from [`ConfigFile`] to [`Config`], with the defaults (reading and a
//! layer's `base`: `read.rs`).

use super::defaults::*;
use super::*;
use crate::sensor::SensorLimits;
use std::path::Path;

impl ConfigFile {
    /// Validates every key, applying the defaults.
    pub fn validate(&self) -> Result<Config, ConfigError> {
        let e = &self.estimator;
        let a = &self.alignment;
        let d = &self.detector;
        let k = &self.eskf;
        let b = &self.bias_kf;
        let h = &self.heading;
        let window = d.window.unwrap_or(DETECTOR_WINDOW);
        if window == 0 || window > 1000 {
            return Err(invalid("detector.window", window, "must be in 1..=1000"));
        }
        let straight_strides = h.straight_strides.unwrap_or(HEADING_STRAIGHT_STRIDES);
        if straight_strides > 100 {
            return Err(invalid(
                "heading.straight_strides",
                straight_strides,
                "must be <= 100",
            ));
        }
        if let Some(n) = h.reacquire_strides
            && !(2..=100).contains(&n)
        {
            return Err(invalid(
                "heading.reacquire_strides",
                n,
                "must be in 2..=100",
            ));
        }
        let calibration_strides = h.calibration_strides.unwrap_or(HEADING_CALIBRATION_STRIDES);
        if calibration_strides == 0 || calibration_strides > 100 {
            return Err(invalid(
                "heading.calibration_strides",
                calibration_strides,
                "must be in 1..=100",
            ));
        }
        // The [daemon] section is checked with the rest of the file (`corridor run` refuses a
        // file whose daemon part is wrong too); its settings stay out of the estimator's.
        self.validate_daemon()?;
        let md = &self.model;
        // The extension states' σ (and random walks): positive, and at most `hi`.
        let opt = |key: &str, v: Option<f64>, hi: f64, rule: &'static str| {
            v.map(|v| Positive::in_range(key, v, 0.0, hi, rule))
                .transpose()
        };
        let opt_deg = |key: &str, v: Option<f64>, hi: f64, rule: &'static str| {
            v.map(|v| Positive::from_degrees_in_range(key, v, 0.0, hi, rule))
                .transpose()
        };
        let model = ModelSettings {
            bias_rate_rw_rad_s2_sqrt_s: opt(
                "model.bias_rate_rw_rad_s2_sqrt_s",
                md.bias_rate_rw_rad_s2_sqrt_s,
                1.0,
                "must be in (0, 1] rad/s²/√s",
            )?,
            bias_rate_initial_sd_rad_s2: Positive::in_range(
                "model.bias_rate_initial_sd_rad_s2",
                md.bias_rate_initial_sd_rad_s2
                    .unwrap_or(MODEL_BIAS_RATE_INITIAL_SD_RAD_S2),
                0.0,
                1.0,
                "must be in (0, 1] rad/s²",
            )?,
            scale_factor_sd: opt(
                "model.scale_factor_sd",
                md.scale_factor_sd,
                1.0,
                "must be in (0, 1]",
            )?,
            heading_offset_sd_rad: opt_deg(
                "model.heading_offset_sd_deg",
                md.heading_offset_sd_deg,
                180.0,
                "must be in (0, 180]°",
            )?,
            g_sensitivity_sd: opt(
                "model.g_sensitivity_sd",
                md.g_sensitivity_sd,
                1.0,
                "must be in (0, 1] rad/s per m/s²",
            )?,
            gyro_coupling_z_sd_rad: opt_deg(
                "model.gyro_coupling_z_sd_deg",
                md.gyro_coupling_z_sd_deg,
                90.0,
                "must be in (0, 90]°",
            )?,
            accel_correction: {
                let k = md.accel_scale_factor.unwrap_or(0.0);
                if !(k.is_finite() && k.abs() < 0.2) {
                    return Err(invalid(
                        "model.accel_scale_factor",
                        k,
                        "must be in (-0.2, 0.2): a larger error is a wrong unit, not a scale",
                    ));
                }
                Positive::new("model.accel_scale_factor", 1.0 / (1.0 + k))?
            },
        };
        if let Some(v) = e.converged_sd_rad_s {
            return Err(invalid(
                "estimator.converged_sd_rad_s",
                v,
                "was removed: the convergence flag is now estimator.converged_unabsorbed (the bias σ never fell that low)",
            ));
        }
        let sensor = self
            .sensor
            .validate()
            .map_err(|e| invalid(e.key, e.value, e.rule))?;
        let typical_gyro_bias = typical_gyro_bias(a, sensor.max_gyro_bias_rad_s())?;
        // The statistic's σ before the thresholds, whose bound is in its units.
        let sigma_accel_m_s2 = Positive::in_range(
            "detector.sigma_accel_m_s2",
            d.sigma_accel_m_s2.unwrap_or(DETECTOR_SIGMA_ACCEL_M_S2),
            1e-06,
            100.0,
            "must be in [1e-6, 100] m/s²",
        )?;
        let sigma_gyro_rad_s = Positive::in_range(
            "detector.sigma_gyro_rad_s",
            d.sigma_gyro_rad_s.unwrap_or(DETECTOR_SIGMA_GYRO_RAD_S),
            1e-06,
            10.0,
            "must be in [1e-6, 10] rad/s",
        )?;
        let kind = d.kind.unwrap_or(DETECTOR_KIND);
        let bound = threshold_bound(kind, &sensor, sigma_accel_m_s2, sigma_gyro_rad_s);
        let threshold = stance_threshold(
            "detector.threshold",
            d.threshold.unwrap_or(DETECTOR_THRESHOLD),
            &bound,
        )?;
        let adaptive_max_threshold = match d.adaptive_max_threshold {
            Some(v) => stance_threshold("detector.adaptive_max_threshold", v, &bound)?,
            // Ten times the threshold, within the bound: beyond it nothing more is a stance.
            None => Positive::new(
                "detector.adaptive_max_threshold",
                (DETECTOR_ADAPTIVE_MAX_FACTOR * threshold.get()).min(bound.0),
            )?,
        };
        Ok(Config {
            model,
            mode: e.mode.unwrap_or(ESTIMATOR_MODE),
            converged_unabsorbed: Fraction::new(
                "estimator.converged_unabsorbed",
                e.converged_unabsorbed
                    .unwrap_or(ESTIMATOR_CONVERGED_UNABSORBED),
            )?,
            // A foot IMU samples at 100 Hz or faster (a swing lasts 0.4 s): a regular step longer
            // than 0.1 s integrates a quarter of a swing as one (1e9 took a 10 s hole for a
            // step), and one under 1 ms would make every sample's step a gap.
            max_dt_s: Positive::in_range(
                "estimator.max_dt_s",
                e.max_dt_s.unwrap_or(ESTIMATOR_MAX_DT_S),
                0.001,
                0.1,
                "must be in [0.001, 0.1] s",
            )?,
            // Interpolating across a second of walking is worse than starting anew.
            max_bridge_s: NonNegative::in_range(
                "estimator.max_bridge_s",
                e.max_bridge_s.unwrap_or(ESTIMATOR_MAX_BRIDGE_S),
                0.0,
                1.0,
                "must be in [0, 1] s",
            )?,
            // Half of the slowest stride: a longer gap loses a footfall.
            max_fill_s: NonNegative::in_range(
                "estimator.max_fill_s",
                e.max_fill_s.unwrap_or(ESTIMATOR_MAX_FILL_S),
                0.0,
                1.0,
                "must be in [0, 1] s",
            )?,
            max_speed_m_s: Positive::in_range(
                "estimator.max_speed_m_s",
                e.max_speed_m_s.unwrap_or(ESTIMATOR_MAX_SPEED_M_S),
                1.0,
                100.0,
                "must be in [1, 100] m/s",
            )?,
            sensor,
            alignment: AlignmentConfig {
                min_rest_s: Positive::in_range(
                    "alignment.min_rest_s",
                    a.min_rest_s.unwrap_or(ALIGNMENT_MIN_REST_S),
                    0.0,
                    3600.0,
                    "must be in (0, 3600] s",
                )?,
                gyro_bias_prior: a.gyro_bias_prior.unwrap_or(ALIGNMENT_GYRO_BIAS_PRIOR),
                gravity_m_s2: a
                    .gravity_m_s2
                    // Earth's gravity lies in 9.76–9.84 m/s² anywhere a foot walks.
                    .map(|g| {
                        let rule = "must be in [9.7, 9.9] m/s²";
                        Positive::in_range("alignment.gravity_m_s2", g, 9.7, 9.9, rule)
                    })
                    .transpose()?,
                // The rest is kept in 50 ms blocks for this long: bounded.
                rest_tail_s: NonNegative::in_range(
                    "alignment.rest_tail_s",
                    a.rest_tail_s.unwrap_or(ALIGNMENT_REST_TAIL_S),
                    0.0,
                    60.0,
                    "must be in [0, 60] s",
                )?,
                rest_max_rate_change_rad_s: Positive::in_range(
                    "alignment.rest_max_rate_change_rad_s",
                    a.rest_max_rate_change_rad_s
                        .unwrap_or(ALIGNMENT_REST_MAX_RATE_CHANGE_RAD_S),
                    0.0,
                    10.0,
                    "must be in (0, 10] rad/s",
                )?,
                min_start_stance_s: NonNegative::in_range(
                    "alignment.min_start_stance_s",
                    a.min_start_stance_s.unwrap_or(ALIGNMENT_MIN_START_STANCE_S),
                    0.0,
                    60.0,
                    "must be in [0, 60] s",
                )?,
                fast_gait_start_stance_s: NonNegative::in_range(
                    "alignment.fast_gait_start_stance_s",
                    a.fast_gait_start_stance_s
                        .unwrap_or(ALIGNMENT_FAST_GAIT_START_STANCE_S),
                    0.0,
                    60.0,
                    "must be in [0, 60] s",
                )?,
                fast_gait_replay_s: NonNegative::in_range(
                    "alignment.fast_gait_replay_s",
                    a.fast_gait_replay_s.unwrap_or(ALIGNMENT_FAST_GAIT_REPLAY_S),
                    0.0,
                    60.0,
                    "must be in [0, 60] s",
                )?,
                start_stance_tilt_sd_rad: Positive::in_range(
                    "alignment.start_stance_tilt_sd_rad",
                    a.start_stance_tilt_sd_rad
                        .unwrap_or(ALIGNMENT_START_STANCE_TILT_SD_RAD),
                    TILT_SD_MIN_RAD,
                    1.0,
                    "must be in [0.001, 1] rad",
                )?,
                max_prior_rate_rad_s: a
                    .max_prior_rate_rad_s
                    .map(|v| {
                        Positive::in_range(
                            "alignment.max_prior_rate_rad_s",
                            v,
                            0.0,
                            10.0,
                            "must be in (0, 10] rad/s",
                        )
                    })
                    .transpose()?,
                typical_gyro_bias,
            },
            detector: DetectorConfig {
                kind,
                window,
                threshold,
                sigma_accel_m_s2,
                sigma_gyro_rad_s,
                min_stance_s: NonNegative::in_range(
                    "detector.min_stance_s",
                    d.min_stance_s.unwrap_or(DETECTOR_MIN_STANCE_S),
                    0.0,
                    10.0,
                    "must be in [0, 10] s",
                )?,
                merge_gap_s: NonNegative::in_range(
                    "detector.merge_gap_s",
                    d.merge_gap_s.unwrap_or(DETECTOR_MERGE_GAP_S),
                    0.0,
                    10.0,
                    "must be in [0, 10] s",
                )?,
                adaptive_factor: d
                    .adaptive_factor
                    .map(|v| Positive::new("detector.adaptive_factor", v))
                    .transpose()?,
                adaptive_window_s: Positive::in_range(
                    "detector.adaptive_window_s",
                    d.adaptive_window_s.unwrap_or(DETECTOR_ADAPTIVE_WINDOW_S),
                    0.0,
                    60.0,
                    "must be in (0, 60] s",
                )?,
                adaptive_max_threshold,
                late_stance_min_s: d
                    .late_stance_min_s
                    .map(|v| {
                        // A dip as long as a stance is a stance: longer would never fire.
                        // Beyond it, the other key's value is said too: the user may have
                        // changed that one (a review found `min_stance_s = 0` reported as this
                        // key's 0.02 alone).
                        let min_stance = d.min_stance_s.unwrap_or(DETECTOR_MIN_STANCE_S);
                        if v > min_stance {
                            return Err(invalid(
                                "detector.late_stance_min_s",
                                format!("{v} (with detector.min_stance_s = {min_stance})"),
                                "must be in (0, detector.min_stance_s] s",
                            ));
                        }
                        Positive::in_range(
                            "detector.late_stance_min_s",
                            v,
                            0.0,
                            d.min_stance_s.unwrap_or(DETECTOR_MIN_STANCE_S),
                            "must be in (0, detector.min_stance_s] s",
                        )
                    })
                    .transpose()?,
                // Earlier than a whole stride period, every footfall would be overdue.
                overdue_stride_factor: d
                    .overdue_stride_factor
                    .map(|v| {
                        Positive::in_range(
                            "detector.overdue_stride_factor",
                            v,
                            1.1,
                            5.0,
                            "must be in [1.1, 5] stride periods",
                        )
                    })
                    .transpose()?,
            },
            eskf: EskfConfig {
                accel_noise_m_s2: Positive::in_range(
                    "eskf.accel_noise_m_s2",
                    k.accel_noise_m_s2.unwrap_or(ESKF_ACCEL_NOISE_M_S2),
                    ACCEL_NOISE_MIN_M_S2,
                    100.0,
                    "must be in [1e-4, 100] m/s²/√Hz",
                )?,
                gyro_noise_rad_s: Positive::in_range(
                    "eskf.gyro_noise_rad_s",
                    k.gyro_noise_rad_s.unwrap_or(ESKF_GYRO_NOISE_RAD_S),
                    GYRO_NOISE_MIN_RAD_S,
                    10.0,
                    "must be in [1e-5, 10] rad/s/√Hz",
                )?,
                gyro_bias_rw_rad_s_sqrt_s: NonNegative::in_range(
                    "eskf.gyro_bias_rw_rad_s_sqrt_s",
                    k.gyro_bias_rw_rad_s_sqrt_s
                        .unwrap_or(ESKF_GYRO_BIAS_RW_RAD_S_SQRT_S),
                    0.0,
                    1.0,
                    "must be in [0, 1] rad/s/√s",
                )?,
                gyro_bias_initial_sd_rad_s: Positive::in_range(
                    "eskf.gyro_bias_initial_sd_rad_s",
                    k.gyro_bias_initial_sd_rad_s
                        .unwrap_or(ESKF_GYRO_BIAS_INITIAL_SD_RAD_S),
                    GYRO_BIAS_SD_MIN_RAD_S,
                    10.0,
                    "must be in [1e-6, 10] rad/s",
                )?,
                gyro_bias_prior_sd_rad_s: Positive::in_range(
                    "eskf.gyro_bias_prior_sd_rad_s",
                    k.gyro_bias_prior_sd_rad_s
                        .unwrap_or(ESKF_GYRO_BIAS_PRIOR_SD_RAD_S),
                    GYRO_BIAS_SD_MIN_RAD_S,
                    10.0,
                    "must be in [1e-6, 10] rad/s",
                )?,
                zupt_sd_m_s: Positive::in_range(
                    "eskf.zupt_sd_m_s",
                    k.zupt_sd_m_s.unwrap_or(ESKF_ZUPT_SD_M_S),
                    ZUPT_SD_MIN_M_S,
                    10.0,
                    "must be in [1e-4, 10] m/s",
                )?,
                initial_tilt_sd_rad: Positive::in_range(
                    "eskf.initial_tilt_sd_rad",
                    k.initial_tilt_sd_rad.unwrap_or(ESKF_INITIAL_TILT_SD_RAD),
                    TILT_SD_MIN_RAD,
                    std::f64::consts::PI,
                    "must be in [0.001, π] rad",
                )?,
                zupt_lever_arm_m: NonNegative::in_range(
                    "eskf.zupt_lever_arm_m",
                    k.zupt_lever_arm_m.unwrap_or(ESKF_ZUPT_LEVER_ARM_M),
                    0.0,
                    1.0,
                    "must be in [0, 1] m",
                )?,
                covariance_step_s: NonNegative::in_range(
                    "eskf.covariance_step_s",
                    k.covariance_step_s.unwrap_or(ESKF_COVARIANCE_STEP_S),
                    0.0,
                    0.1,
                    "must be in [0, 0.1] s",
                )?,
                zero_rate_updates: k.zero_rate_updates.unwrap_or(ESKF_ZERO_RATE_UPDATES),
                zero_rate_interval_s: Positive::in_range(
                    "eskf.zero_rate_interval_s",
                    k.zero_rate_interval_s.unwrap_or(ESKF_ZERO_RATE_INTERVAL_S),
                    0.0,
                    3600.0,
                    "must be in (0, 3600] s",
                )?,
                rest_gyro_noise_rad_s: Positive::in_range(
                    "eskf.rest_gyro_noise_rad_s",
                    k.rest_gyro_noise_rad_s
                        .unwrap_or(ESKF_REST_GYRO_NOISE_RAD_S),
                    GYRO_NOISE_MIN_RAD_S,
                    10.0,
                    "must be in [1e-5, 10] rad/s/√Hz",
                )?,
                stance_yaw_max_sd_rad: NonNegative::in_range(
                    "eskf.stance_yaw_max_sd_rad",
                    k.stance_yaw_max_sd_rad
                        .unwrap_or(ESKF_STANCE_YAW_MAX_SD_RAD),
                    0.0,
                    std::f64::consts::PI,
                    "must be in [0, π] rad (0: off)",
                )?,
                zupt_rolling_height_m: NonNegative::in_range(
                    "eskf.zupt_rolling_height_m",
                    k.zupt_rolling_height_m
                        .unwrap_or(ESKF_ZUPT_ROLLING_HEIGHT_M),
                    0.0,
                    1.0,
                    "must be in [0, 1] m",
                )?,
                clipped_rate_sd_rad_s: NonNegative::in_range(
                    "eskf.clipped_rate_sd_rad_s",
                    k.clipped_rate_sd_rad_s
                        .unwrap_or(ESKF_CLIPPED_RATE_SD_RAD_S),
                    0.0,
                    100.0,
                    "must be in [0, 100] rad/s",
                )?,
                restore_clipped_peaks: k
                    .restore_clipped_peaks
                    .unwrap_or(ESKF_RESTORE_CLIPPED_PEAKS),
            },
            bias_kf: BiasKfConfig {
                tilt_sd_rad: Positive::in_range(
                    "bias_kf.tilt_sd_rad",
                    b.tilt_sd_rad.unwrap_or(BIAS_KF_TILT_SD_RAD),
                    TILT_SD_MIN_RAD,
                    std::f64::consts::PI,
                    "must be in [0.001, π] rad",
                )?,
                bias_rw_rad_s_sqrt_s: NonNegative::in_range(
                    "bias_kf.bias_rw_rad_s_sqrt_s",
                    b.bias_rw_rad_s_sqrt_s
                        .unwrap_or(BIAS_KF_BIAS_RW_RAD_S_SQRT_S),
                    0.0,
                    1.0,
                    "must be in [0, 1] rad/s/√s",
                )?,
            },
            heading: HeadingConfig {
                source: h.source.unwrap_or(HEADING_SOURCE),
                sigma_rad: Positive::from_degrees_in_range(
                    "heading.sigma_deg",
                    h.sigma_deg.unwrap_or(HEADING_SIGMA_DEG),
                    FOOT_AXIS_SD_MIN_DEG,
                    90.0,
                    "must be in [0.5, 90]°",
                )?,
                grid_rad: Finite::from_degrees_in_range(
                    "heading.grid_deg",
                    h.grid_deg.unwrap_or(HEADING_GRID_DEG),
                    -360.0,
                    360.0,
                    "must be in [-360, 360]°",
                )?,
                grid_step_rad: {
                    let step = h.grid_step_deg.unwrap_or(HEADING_GRID_STEP_DEG);
                    if !(1.0..=360.0).contains(&step) || (360.0 / step).fract().abs() > 1e-9 {
                        return Err(invalid(
                            "heading.grid_step_deg",
                            step,
                            "must divide 360 and lie in [1, 360]",
                        ));
                    }
                    Positive::from_degrees("heading.grid_step_deg", step)?
                },
                start_heading_rad: Finite::from_degrees_in_range(
                    "heading.start_heading_deg",
                    h.start_heading_deg.unwrap_or(HEADING_START_HEADING_DEG),
                    -360.0,
                    360.0,
                    "must be in [-360, 360]°",
                )?,
                gate_rad: Positive::from_degrees_in_range(
                    "heading.gate_deg",
                    h.gate_deg.unwrap_or(HEADING_GATE_DEG),
                    0.0,
                    180.0,
                    "must be in (0, 180]°",
                )?,
                straight_max_change_rad: Positive::from_degrees_in_range(
                    "heading.straight_max_change_deg",
                    h.straight_max_change_deg
                        .unwrap_or(HEADING_STRAIGHT_MAX_CHANGE_DEG),
                    0.0,
                    180.0,
                    "must be in (0, 180]°",
                )?,
                straight_strides,
                calibration_strides,
                obs_delay_s: NonNegative::in_range(
                    "heading.obs_delay_s",
                    h.obs_delay_s.unwrap_or(HEADING_OBS_DELAY_S),
                    0.0,
                    5.0,
                    "must be in [0, 5] s",
                )?,
                start_heading_sd_rad: Positive::from_degrees_in_range(
                    "heading.start_heading_sd_deg",
                    h.start_heading_sd_deg
                        .unwrap_or(HEADING_START_HEADING_SD_DEG),
                    STRIDE_SD_MIN_DEG,
                    180.0,
                    "must be in [0.1, 180]°",
                )?,
                observations: h.observations.unwrap_or(HEADING_OBSERVATIONS),
                stride_sigma_rad: Positive::from_degrees_in_range(
                    "heading.stride_sigma_deg",
                    h.stride_sigma_deg.unwrap_or(HEADING_STRIDE_SIGMA_DEG),
                    STRIDE_SD_MIN_DEG,
                    90.0,
                    "must be in [0.1, 90]°",
                )?,
                min_stride_m: Positive::in_range(
                    "heading.min_stride_m",
                    h.min_stride_m.unwrap_or(HEADING_MIN_STRIDE_M),
                    0.0,
                    10.0,
                    "must be in (0, 10] m",
                )?,
                line_footprints: match h.line_footprints.unwrap_or(HEADING_LINE_FOOTPRINTS) {
                    n @ (0 | 3..=8) => n,
                    n => {
                        return Err(invalid(
                            "heading.line_footprints",
                            n,
                            "must be 0 (off) or 3..=8",
                        ));
                    }
                },
                line_lateral_m: Positive::in_range(
                    "heading.line_lateral_m",
                    h.line_lateral_m.unwrap_or(HEADING_LINE_LATERAL_M),
                    0.0,
                    10.0,
                    "must be in (0, 10] m",
                )?,
                stride_look_ahead: h.stride_look_ahead.unwrap_or(HEADING_STRIDE_LOOK_AHEAD),
                foot_axis_stride_max_rad: h
                    .foot_axis_stride_max_deg
                    .map(|v| {
                        Positive::from_degrees_in_range(
                            "heading.foot_axis_stride_max_deg",
                            v,
                            0.0,
                            90.0,
                            "must be in (0, 90]°",
                        )
                    })
                    .transpose()?,
                aligned_prior: Fraction::new(
                    "heading.aligned_prior",
                    h.aligned_prior.unwrap_or(HEADING_ALIGNED_PRIOR),
                )?,
                min_weight: Fraction::new(
                    "heading.min_weight",
                    h.min_weight.unwrap_or(HEADING_MIN_WEIGHT),
                )?,
                reacquire_strides: h.reacquire_strides,
            },
        })
    }
}

impl Config {
    /// Reads, parses and validates a TOML file; errors name the file and the key.
    pub fn from_file(path: &Path) -> Result<Self, ConfigError> {
        ConfigFile::read(path)?
            .validate()
            .map_err(|e| with_path(e, path))
    }
}

/// `alignment.typical_gyro_bias_rad_s` with its σ: both or neither, each axis finite and within
/// the sensor's largest bias (a prior the health check would refuse is no prior).
fn typical_gyro_bias(
    a: &AlignmentFile,
    max_bias_rad_s: f64,
) -> Result<Option<TypicalGyroBias>, ConfigError> {
    const KEY: &str = "alignment.typical_gyro_bias_rad_s";
    const SD_KEY: &str = "alignment.typical_gyro_bias_sd_rad_s";
    match (a.typical_gyro_bias_rad_s, a.typical_gyro_bias_sd_rad_s) {
        (None, None) => Ok(None),
        (Some(_), None) => Err(invalid(
            SD_KEY,
            "(not given)",
            "must be given with alignment.typical_gyro_bias_rad_s",
        )),
        (None, Some(_)) => Err(invalid(
            KEY,
            "(not given)",
            "must be given with alignment.typical_gyro_bias_sd_rad_s",
        )),
        (Some(b), Some(sd)) => {
            if b.iter().any(|v| !v.is_finite() || v.abs() > max_bias_rad_s) {
                return Err(invalid(
                    KEY,
                    format!("{b:?}"),
                    "each axis must be finite and within sensor.max_gyro_bias_rad_s",
                ));
            }
            Ok(Some(TypicalGyroBias {
                rad_s: b,
                sd_rad_s: Positive::in_range(
                    SD_KEY,
                    sd,
                    GYRO_BIAS_SD_MIN_RAD_S,
                    0.1,
                    "must be in [1e-6, 0.1] rad/s",
                )?,
            }))
        }
    }
}

/// The largest threshold of the stance detector (on its σ-normalised statistic,
/// `core/stance.rs`): the statistic of a foot turning at the gyro's full scale, (range / σ)²,
/// or for `mv` of an accelerometer spread of its full scale. Above it every sample the sensor
/// can output is a stance: `threshold = 1e300` was taken, and no rest followed by motion was
/// ever found (1e8 did the same on exp36; the bound of gdins.toml is 2.5e7). With the keys
/// it comes from, for the error.
fn threshold_bound(
    kind: DetectorKind,
    sensor: &SensorLimits,
    sigma_accel: Positive,
    sigma_gyro: Positive,
) -> (f64, String) {
    let (range, range_key, sd, sd_key) = match kind {
        DetectorKind::Mv => (
            sensor.accel_range_m_s2(),
            "sensor.accel_range_m_s2",
            sigma_accel.get(),
            "detector.sigma_accel_m_s2",
        ),
        DetectorKind::Shoe | DetectorKind::Are => (
            sensor.gyro_range_rad_s(),
            "sensor.gyro_range_rad_s",
            sigma_gyro.get(),
            "detector.sigma_gyro_rad_s",
        ),
    };
    let bound = (range / sd).powi(2);
    (
        bound,
        format!("with {range_key} = {range} and {sd_key} = {sd}: at most {bound:.4e}"),
    )
}

/// A threshold `value` under `key`, positive and within `bound` ([`threshold_bound`]).
fn stance_threshold(key: &str, value: f64, bound: &(f64, String)) -> Result<Positive, ConfigError> {
    let t = Positive::new(key, value)?;
    if value > bound.0 {
        return Err(invalid(
            key,
            format!("{} ({})", shown(value), bound.1),
            "must be at most (range / σ)² of the statistic's sensor (the gyro's; the \
             accelerometer's for kind = \"mv\"): above it a foot turning at full scale is a stance",
        ));
    }
    Ok(t)
}
