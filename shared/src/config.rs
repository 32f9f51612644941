//! The estimator configuration: one TOML file per sensor (see `configs/`).
//!
//! Parsing happens in two steps. [`ConfigFile`] mirrors the TOML one to one (serde,
//! `deny_unknown_fields`, every key optional with a documented default). [`ConfigFile::validate`]
//! turns it into [`Config`], whose fields are [`Positive`], [`Fraction`] or enums, so code that
//! holds a `Config` never sees a negative noise, a zero window or an unknown mode. Every error
//! names the key that is wrong and the value found.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A configuration that could not be read or is not valid.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("{path}: cannot read config: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The TOML is malformed or has an unknown key (the message names it, with line and column).
    #[error("{path}: {message}")]
    Toml {
        /// The file.
        path: PathBuf,
        /// The TOML parser's message, which names the key and position.
        message: String,
    },
    /// A key has a value outside its allowed range.
    #[error("{path}: key `{key}` = {value}: {rule}")]
    Invalid {
        /// The file (or `<override>` for a command-line override).
        path: PathBuf,
        /// Dotted key, e.g. `detector.threshold`.
        key: String,
        /// The value found, as text.
        value: String,
        /// What the value must satisfy.
        rule: &'static str,
    },
}

/// A finite, strictly positive number.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Serialize)]
pub struct Positive(f64);

impl Positive {
    /// Checks `value`, naming `key` in the error.
    pub fn new(key: &str, value: f64) -> Result<Self, ConfigError> {
        if value.is_finite() && value > 0.0 {
            Ok(Self(value))
        } else {
            Err(invalid(key, value, "must be a finite number > 0"))
        }
    }
    /// The value.
    pub fn get(self) -> f64 {
        self.0
    }
}

/// A finite number in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Serialize)]
pub struct Fraction(f64);

impl Fraction {
    /// Checks `value`, naming `key` in the error.
    pub fn new(key: &str, value: f64) -> Result<Self, ConfigError> {
        if (0.0..=1.0).contains(&value) {
            Ok(Self(value))
        } else {
            Err(invalid(key, value, "must be in [0, 1]"))
        }
    }
    /// The value.
    pub fn get(self) -> f64 {
        self.0
    }
}

fn invalid(key: &str, value: impl std::fmt::Display, rule: &'static str) -> ConfigError {
    ConfigError::Invalid {
        path: PathBuf::new(),
        key: key.to_owned(),
        value: value.to_string(),
        rule,
    }
}

fn finite(key: &str, value: f64) -> Result<f64, ConfigError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(invalid(key, value, "must be finite"))
    }
}

fn non_negative(key: &str, value: f64) -> Result<f64, ConfigError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(invalid(key, value, "must be a finite number >= 0"))
    }
}

/// Default largest plausible foot speed, m/s: the swinging foot of a sprinter peaks near 10 m/s.
pub const DEFAULT_MAX_SPEED_M_S: f64 = 15.0;

/// How the gyro bias is estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// The standard ZUPT-aided error-state filter with gyro-bias states and no heading aid.
    Zupt,
    /// The reference paper: a 3-state bias Kalman filter (F = I, H = I) fed by the logarithm of
    /// the quaternion between the gyro attitude and the map's "true" attitude at stance.
    Paper,
    /// The paper's 3-state filter with the body-to-navigation rotation integrated into the
    /// observation matrix (the paper assumes they commute) and the roll/pitch reference taken from
    /// the accelerometer at stance instead of zero.
    RotationAware,
    /// Map headings fused directly into the ZUPT error-state filter, whose gyro-bias states then
    /// become observable on all three axes.
    Eskf,
}

impl Mode {
    /// The config spelling.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Zupt => "zupt",
            Mode::Paper => "paper",
            Mode::RotationAware => "rotation_aware",
            Mode::Eskf => "eskf",
        }
    }
}

/// Zero-velocity detector statistic (Skog et al. 2010).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DetectorKind {
    /// Stance hypothesis optimal detector (GLRT on accelerometer and gyro).
    Shoe,
    /// Angular rate energy.
    Are,
    /// Accelerometer moving variance.
    Mv,
}

/// Where heading observations come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HeadingSource {
    /// No heading observations.
    None,
    /// Map-free dominant directions: the building grid at `grid_deg + k·90°`.
    Grid,
    /// Corridor segments from a map file: heading only while inside a corridor.
    Map,
}

/// Which heading observations the `eskf` mode takes at a stance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HeadingObservations {
    /// The heading of the foot's forward axis (needs the sensor's yaw on the foot).
    FootAxis,
    /// The direction of the stride since the previous footprint (needs no mounting yaw).
    Stride,
    /// Both, the stride first.
    Both,
}

impl HeadingObservations {
    /// Whether the stride direction is observed.
    pub fn stride(self) -> bool {
        matches!(self, Self::Stride | Self::Both)
    }
    /// Whether the foot axis is observed.
    pub fn foot_axis(self) -> bool {
        matches!(self, Self::FootAxis | Self::Both)
    }
}

/// Whether the initial rest's gyro mean is used as a bias prior.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BiasPrior {
    /// No prior: the bias starts at zero with `initial_sd_rad_s` (as in the paper).
    None,
    /// The mean gyro rate over the initial rest.
    RestMean,
}

/// The TOML file, key for key. Every key is optional; the defaults are documented in
/// `configs/gdins.toml`.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ConfigFile {
    /// `[estimator]`
    #[serde(default)]
    pub estimator: EstimatorFile,
    /// `[alignment]`
    #[serde(default)]
    pub alignment: AlignmentFile,
    /// `[detector]`
    #[serde(default)]
    pub detector: DetectorFile,
    /// `[eskf]`
    #[serde(default)]
    pub eskf: EskfFile,
    /// `[bias_kf]`
    #[serde(default)]
    pub bias_kf: BiasKfFile,
    /// `[heading]`
    #[serde(default)]
    pub heading: HeadingFile,
    /// `[model]`: switchable model extensions of the `eskf` mode
    #[serde(default)]
    pub model: ModelFile,
    /// `[daemon]` (only `corridor serve` reads it)
    #[serde(default)]
    pub daemon: DaemonFile,
    /// `[sensor]`: what the IMU can output, and the time-step bounds
    #[serde(default)]
    pub sensor: crate::sensor::SensorFile,
}

/// `[model]` section: extension states of the error-state filter (`eskf` and `zupt` modes).
/// Each key switches its extension on; absent means off.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// Gyro-bias rate states (a linear bias drift): random walk of the rate, rad/s²/√s.
    pub bias_rate_rw_rad_s2_sqrt_s: Option<f64>,
    /// Initial σ of the bias rate, rad/s² (default 1e-4).
    pub bias_rate_initial_sd_rad_s2: Option<f64>,
    /// Gyro scale-factor states per sensor axis: initial σ (dimensionless).
    pub scale_factor_sd: Option<f64>,
    /// Foot-heading offset state: initial σ, degrees.
    pub heading_offset_sd_deg: Option<f64>,
    /// Diagonal g-sensitivity states: initial σ, rad/s per m/s².
    pub g_sensitivity_sd: Option<f64>,
}

/// `[daemon]` section: the estimator service.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DaemonFile {
    /// iceoryx2 domain (a name prefix isolating independent process sets; default `default`).
    pub domain: Option<String>,
    /// `live` (a slow reader loses the oldest samples, counted) or `lossless` (backpressure end
    /// to end); default `live`.
    pub delivery: Option<String>,
    /// Capacity of the receive → estimator channel, samples (default 4096).
    pub channel_capacity: Option<usize>,
    /// Period of bias samples between heading updates, s of sensor time (default 1.0).
    pub bias_period_s: Option<f64>,
    /// Period of diagnostics, s of wall-clock time (default 1.0).
    pub diagnostics_period_s: Option<f64>,
    /// Period of the one-line health log, s of wall-clock time (default 10.0).
    pub health_period_s: Option<f64>,
    /// Checkpoint file; absent: no checkpoint.
    pub checkpoint_path: Option<PathBuf>,
    /// Period of checkpoints while running, s of wall-clock time (default 30.0).
    pub checkpoint_period_s: Option<f64>,
    /// Longest a lossless publish waits on one consumer's full buffer, s (default 1.0); beyond
    /// it the consumer counts as stalled and loses (counted) what its buffer cannot take.
    pub stall_timeout_s: Option<f64>,
}

/// `[estimator]` section.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EstimatorFile {
    /// Bias estimation mode (default `eskf`).
    pub mode: Option<Mode>,
    /// Bias σ on every axis below which the estimate counts as converged (default 2e-4 rad/s).
    pub converged_sd_rad_s: Option<f64>,
    /// Largest regular time step; a longer one is a gap: a new segment, counted (default 0.05 s).
    pub max_dt_s: Option<f64>,
    /// Largest plausible foot speed, m/s; a faster estimate fails the health check (default 15).
    pub max_speed_m_s: Option<f64>,
}

/// `[alignment]` section.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AlignmentFile {
    /// Shortest initial rest that allows alignment (default 0.5 s).
    pub min_rest_s: Option<f64>,
    /// Gyro-bias prior (default `rest_mean`).
    pub gyro_bias_prior: Option<BiasPrior>,
    /// Gravity: the mean specific force over the rest is used when absent.
    pub gravity_m_s2: Option<f64>,
    /// The last part of the rest left out of the means: the foot starts to move before the
    /// detector sees it (default 0.5 s).
    pub rest_tail_s: Option<f64>,
}

/// `[detector]` section.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DetectorFile {
    /// Statistic (default `shoe`).
    pub kind: Option<DetectorKind>,
    /// Window length in samples (default 5).
    pub window: Option<usize>,
    /// Threshold on the statistic (default 1e5 for SHOE with the default σ: about 0.6 rad/s of rotation).
    pub threshold: Option<f64>,
    /// Accelerometer noise σ used by the statistic (default 0.01 m/s²).
    pub sigma_accel_m_s2: Option<f64>,
    /// Gyro noise σ used by the statistic (default 0.1 °/s in rad/s).
    pub sigma_gyro_rad_s: Option<f64>,
    /// Shortest stance kept (default 0.04 s).
    pub min_stance_s: Option<f64>,
    /// Adaptive threshold: a sample is stance when its statistic is below `threshold` or below
    /// this factor times the quietest statistic of the last `adaptive_window_s` (absent: off).
    pub adaptive_factor: Option<f64>,
    /// Look-back of the adaptive threshold, about one stride cycle (default 1.5 s).
    pub adaptive_window_s: Option<f64>,
    /// Largest adaptive threshold (default 10 × `threshold`).
    pub adaptive_max_threshold: Option<f64>,
}

/// `[eskf]` section: the ZUPT-aided error-state filter.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EskfFile {
    /// Accelerometer white noise σ (default 0.5 m/s²: foot dynamics, not just sensor noise).
    pub accel_noise_m_s2: Option<f64>,
    /// Gyro white noise σ (default 0.01 rad/s).
    pub gyro_noise_rad_s: Option<f64>,
    /// Gyro-bias random walk σ per √s (default 1e-4 rad/s/√s).
    pub gyro_bias_rw_rad_s_sqrt_s: Option<f64>,
    /// Initial gyro-bias σ without a prior (default 0.01 rad/s).
    pub gyro_bias_initial_sd_rad_s: Option<f64>,
    /// Initial gyro-bias σ with the rest-mean prior (default 5e-4 rad/s).
    pub gyro_bias_prior_sd_rad_s: Option<f64>,
    /// Zero-velocity pseudo-measurement σ (default 0.01 m/s).
    pub zupt_sd_m_s: Option<f64>,
    /// Initial roll/pitch σ (default 0.5°, in rad).
    pub initial_tilt_sd_rad: Option<f64>,
    /// Lever arm between the sensor and the point the foot rolls about at the edges of a
    /// stance (default 0: off): the ZUPT σ of a sample is √(zupt_sd² + (arm·|ω|)²).
    pub zupt_lever_arm_m: Option<f64>,
}

/// `[bias_kf]` section: the paper's 3-state bias filter.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BiasKfFile {
    /// σ of the roll/pitch reference at stance (default 1°, in rad). The paper takes it as exact.
    pub tilt_sd_rad: Option<f64>,
    /// Bias random walk σ per √s (default 1e-5 rad/s/√s; the paper's F = I with a small Q).
    pub bias_rw_rad_s_sqrt_s: Option<f64>,
}

/// `[heading]` section.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct HeadingFile {
    /// Source of heading observations (default `grid`).
    pub source: Option<HeadingSource>,
    /// σ of one heading observation (default 3°, in degrees).
    pub sigma_deg: Option<f64>,
    /// Orientation of the building grid in the map frame (default 0°).
    pub grid_deg: Option<f64>,
    /// Spacing of the dominant directions (default 90°; 180° means one corridor axis).
    pub grid_step_deg: Option<f64>,
    /// Walking direction at the start, in the map frame (default 0°).
    pub start_heading_deg: Option<f64>,
    /// Largest distance to the nearest direction that is still associated (default 15°).
    pub gate_deg: Option<f64>,
    /// Largest foot-heading change over the last `straight_strides` stances (default 10°).
    pub straight_max_change_deg: Option<f64>,
    /// How many previous stances the straight-walk test looks at (default 2).
    pub straight_strides: Option<usize>,
    /// Stances after the first stride used to fix the sensor's yaw on the foot (default 3).
    pub calibration_strides: Option<usize>,
    /// Seconds into a stance at which the heading observation is taken (default 0.05 s).
    pub obs_delay_s: Option<f64>,
    /// σ of the start heading: how well the first stride is known to follow
    /// `start_heading_deg` (default 1°, in degrees).
    pub start_heading_sd_deg: Option<f64>,
    /// Which observations the `eskf` mode takes (default `both`).
    pub observations: Option<HeadingObservations>,
    /// σ of one stride-direction observation (default 2°, in degrees).
    pub stride_sigma_deg: Option<f64>,
    /// Shortest stride whose direction is observed (default 0.5 m).
    pub min_stride_m: Option<f64>,
    /// Footprints (this one included) that must lie on a line for a stride direction to be
    /// observed (default 0: off; at most 8).
    pub line_footprints: Option<usize>,
    /// Largest distance of those footprints from their line (default 0.05 m).
    pub line_lateral_m: Option<f64>,
    /// Prior probability that a stance's walking direction is a dominant direction, for the
    /// association weight (default 0.7).
    pub aligned_prior: Option<f64>,
    /// Smallest association weight that is still fused (default 0.5).
    pub min_weight: Option<f64>,
}

/// A validated configuration.
#[derive(Debug, Clone, Serialize)]
pub struct Config {
    /// Bias estimation mode.
    pub mode: Mode,
    /// Convergence bound on the bias σ.
    pub converged_sd_rad_s: Positive,
    /// Largest regular time step.
    pub max_dt_s: Positive,
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
    /// The daemon.
    pub daemon: DaemonSettings,
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
    /// Checkpoint period.
    pub checkpoint_period_s: Positive,
    /// Stall bound of lossless publishing.
    pub stall_timeout_s: Positive,
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
    pub rest_tail_s: f64,
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
    pub min_stance_s: f64,
    /// Adaptive factor (off when `None`).
    pub adaptive_factor: Option<Positive>,
    /// Adaptive look-back.
    pub adaptive_window_s: Positive,
    /// Largest adaptive threshold.
    pub adaptive_max_threshold: Positive,
}

/// Validated `[eskf]`.
#[derive(Debug, Clone, Serialize)]
pub struct EskfConfig {
    /// Accelerometer white noise σ.
    pub accel_noise_m_s2: Positive,
    /// Gyro white noise σ.
    pub gyro_noise_rad_s: Positive,
    /// Gyro-bias random walk.
    pub gyro_bias_rw_rad_s_sqrt_s: f64,
    /// Initial bias σ without prior.
    pub gyro_bias_initial_sd_rad_s: Positive,
    /// Initial bias σ with the rest-mean prior.
    pub gyro_bias_prior_sd_rad_s: Positive,
    /// ZUPT σ.
    pub zupt_sd_m_s: Positive,
    /// Initial tilt σ.
    pub initial_tilt_sd_rad: Positive,
    /// ZUPT lever arm (0 = a constant ZUPT σ).
    pub zupt_lever_arm_m: f64,
}

/// Validated `[bias_kf]`.
#[derive(Debug, Clone, Serialize)]
pub struct BiasKfConfig {
    /// Roll/pitch reference σ.
    pub tilt_sd_rad: Positive,
    /// Bias random walk.
    pub bias_rw_rad_s_sqrt_s: f64,
}

/// Validated `[heading]`, angles in radians.
#[derive(Debug, Clone, Serialize)]
pub struct HeadingConfig {
    /// Source.
    pub source: HeadingSource,
    /// Observation σ.
    pub sigma_rad: Positive,
    /// Grid orientation.
    pub grid_rad: f64,
    /// Grid spacing.
    pub grid_step_rad: Positive,
    /// Start walking direction.
    pub start_heading_rad: f64,
    /// Association gate.
    pub gate_rad: Positive,
    /// Straight-walk limit.
    pub straight_max_change_rad: Positive,
    /// Straight-walk look-back.
    pub straight_strides: usize,
    /// Mounting-yaw calibration stances.
    pub calibration_strides: usize,
    /// Observation delay into a stance.
    pub obs_delay_s: f64,
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
    /// Prior probability of an aligned stance.
    pub aligned_prior: Fraction,
    /// Smallest fused association weight.
    pub min_weight: Fraction,
}

impl Default for Config {
    fn default() -> Self {
        ConfigFile::default()
            .validate()
            .expect("the built-in defaults are valid")
    }
}

impl ConfigFile {
    /// Reads and parses a TOML file (no validation yet).
    pub fn read(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parses TOML text; `path` only names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, ConfigError> {
        toml::from_str(text).map_err(|e| ConfigError::Toml {
            path: path.to_owned(),
            message: e.to_string(),
        })
    }

    /// Validates every key, applying the defaults.
    pub fn validate(&self) -> Result<Config, ConfigError> {
        let e = &self.estimator;
        let a = &self.alignment;
        let d = &self.detector;
        let k = &self.eskf;
        let b = &self.bias_kf;
        let h = &self.heading;
        let deg = f64::to_radians;
        let window = d.window.unwrap_or(5);
        if window == 0 || window > 1000 {
            return Err(invalid("detector.window", window, "must be in 1..=1000"));
        }
        let straight_strides = h.straight_strides.unwrap_or(2);
        if straight_strides > 100 {
            return Err(invalid(
                "heading.straight_strides",
                straight_strides,
                "must be <= 100",
            ));
        }
        let calibration_strides = h.calibration_strides.unwrap_or(3);
        if calibration_strides == 0 || calibration_strides > 100 {
            return Err(invalid(
                "heading.calibration_strides",
                calibration_strides,
                "must be in 1..=100",
            ));
        }
        let dm = &self.daemon;
        let delivery = dm.delivery.as_deref().unwrap_or("live");
        let lossless = match delivery.parse::<crate::services::Delivery>() {
            Ok(d) => d == crate::services::Delivery::Lossless,
            Err(_) => {
                return Err(invalid(
                    "daemon.delivery",
                    delivery,
                    "must be live or lossless",
                ));
            }
        };
        let channel_capacity = dm.channel_capacity.unwrap_or(4096);
        if !(1..=1 << 24).contains(&channel_capacity) {
            return Err(invalid(
                "daemon.channel_capacity",
                channel_capacity,
                "must be in 1..=16777216",
            ));
        }
        let domain = dm.domain.clone().unwrap_or_else(|| "default".to_owned());
        // The same rule `corridor serve` applies when it opens the domain.
        if let Err(crate::services::ServiceError::InvalidDomain { rule, .. }) =
            crate::services::Domain::new(&domain)
        {
            return Err(invalid("daemon.domain", format!("{domain:?}"), rule));
        }
        let daemon = DaemonSettings {
            domain,
            lossless,
            channel_capacity,
            bias_period_s: Positive::new("daemon.bias_period_s", dm.bias_period_s.unwrap_or(1.0))?,
            diagnostics_period_s: Positive::new(
                "daemon.diagnostics_period_s",
                dm.diagnostics_period_s.unwrap_or(1.0),
            )?,
            health_period_s: Positive::new(
                "daemon.health_period_s",
                dm.health_period_s.unwrap_or(10.0),
            )?,
            checkpoint_path: dm.checkpoint_path.clone(),
            checkpoint_period_s: Positive::new(
                "daemon.checkpoint_period_s",
                dm.checkpoint_period_s.unwrap_or(30.0),
            )?,
            stall_timeout_s: Positive::new(
                "daemon.stall_timeout_s",
                dm.stall_timeout_s.unwrap_or(1.0),
            )?,
        };
        let md = &self.model;
        let opt = |key: &str, v: Option<f64>| v.map(|v| Positive::new(key, v)).transpose();
        let model = ModelSettings {
            bias_rate_rw_rad_s2_sqrt_s: opt(
                "model.bias_rate_rw_rad_s2_sqrt_s",
                md.bias_rate_rw_rad_s2_sqrt_s,
            )?,
            bias_rate_initial_sd_rad_s2: Positive::new(
                "model.bias_rate_initial_sd_rad_s2",
                md.bias_rate_initial_sd_rad_s2.unwrap_or(1e-4),
            )?,
            scale_factor_sd: opt("model.scale_factor_sd", md.scale_factor_sd)?,
            heading_offset_sd_rad: opt(
                "model.heading_offset_sd_deg",
                md.heading_offset_sd_deg.map(f64::to_radians),
            )?,
            g_sensitivity_sd: opt("model.g_sensitivity_sd", md.g_sensitivity_sd)?,
        };
        Ok(Config {
            daemon,
            model,
            mode: e.mode.unwrap_or(Mode::Eskf),
            converged_sd_rad_s: Positive::new(
                "estimator.converged_sd_rad_s",
                e.converged_sd_rad_s.unwrap_or(2e-4),
            )?,
            max_dt_s: Positive::new("estimator.max_dt_s", e.max_dt_s.unwrap_or(0.05))?,
            max_speed_m_s: Positive::new(
                "estimator.max_speed_m_s",
                e.max_speed_m_s.unwrap_or(DEFAULT_MAX_SPEED_M_S),
            )?,
            sensor: self
                .sensor
                .validate()
                .map_err(|e| invalid(e.key, e.value, e.rule))?,
            alignment: AlignmentConfig {
                min_rest_s: Positive::new("alignment.min_rest_s", a.min_rest_s.unwrap_or(0.5))?,
                gyro_bias_prior: a.gyro_bias_prior.unwrap_or(BiasPrior::RestMean),
                gravity_m_s2: a
                    .gravity_m_s2
                    .map(|g| Positive::new("alignment.gravity_m_s2", g))
                    .transpose()?,
                rest_tail_s: non_negative("alignment.rest_tail_s", a.rest_tail_s.unwrap_or(0.5))?,
            },
            detector: DetectorConfig {
                kind: d.kind.unwrap_or(DetectorKind::Shoe),
                window,
                threshold: Positive::new("detector.threshold", d.threshold.unwrap_or(1e5))?,
                sigma_accel_m_s2: Positive::new(
                    "detector.sigma_accel_m_s2",
                    d.sigma_accel_m_s2.unwrap_or(0.01),
                )?,
                sigma_gyro_rad_s: Positive::new(
                    "detector.sigma_gyro_rad_s",
                    d.sigma_gyro_rad_s.unwrap_or(deg(0.1)),
                )?,
                min_stance_s: non_negative(
                    "detector.min_stance_s",
                    d.min_stance_s.unwrap_or(0.04),
                )?,
                adaptive_factor: d
                    .adaptive_factor
                    .map(|v| Positive::new("detector.adaptive_factor", v))
                    .transpose()?,
                adaptive_window_s: Positive::new(
                    "detector.adaptive_window_s",
                    d.adaptive_window_s.unwrap_or(1.5),
                )?,
                adaptive_max_threshold: Positive::new(
                    "detector.adaptive_max_threshold",
                    d.adaptive_max_threshold
                        .unwrap_or(10.0 * d.threshold.unwrap_or(1e5)),
                )?,
            },
            eskf: EskfConfig {
                accel_noise_m_s2: Positive::new(
                    "eskf.accel_noise_m_s2",
                    k.accel_noise_m_s2.unwrap_or(0.5),
                )?,
                gyro_noise_rad_s: Positive::new(
                    "eskf.gyro_noise_rad_s",
                    k.gyro_noise_rad_s.unwrap_or(0.01),
                )?,
                gyro_bias_rw_rad_s_sqrt_s: non_negative(
                    "eskf.gyro_bias_rw_rad_s_sqrt_s",
                    k.gyro_bias_rw_rad_s_sqrt_s.unwrap_or(1e-4),
                )?,
                gyro_bias_initial_sd_rad_s: Positive::new(
                    "eskf.gyro_bias_initial_sd_rad_s",
                    k.gyro_bias_initial_sd_rad_s.unwrap_or(0.01),
                )?,
                gyro_bias_prior_sd_rad_s: Positive::new(
                    "eskf.gyro_bias_prior_sd_rad_s",
                    k.gyro_bias_prior_sd_rad_s.unwrap_or(5e-4),
                )?,
                zupt_sd_m_s: Positive::new("eskf.zupt_sd_m_s", k.zupt_sd_m_s.unwrap_or(0.01))?,
                initial_tilt_sd_rad: Positive::new(
                    "eskf.initial_tilt_sd_rad",
                    k.initial_tilt_sd_rad.unwrap_or(deg(0.5)),
                )?,
                zupt_lever_arm_m: non_negative(
                    "eskf.zupt_lever_arm_m",
                    k.zupt_lever_arm_m.unwrap_or(0.0),
                )?,
            },
            bias_kf: BiasKfConfig {
                tilt_sd_rad: Positive::new(
                    "bias_kf.tilt_sd_rad",
                    b.tilt_sd_rad.unwrap_or(deg(1.0)),
                )?,
                bias_rw_rad_s_sqrt_s: non_negative(
                    "bias_kf.bias_rw_rad_s_sqrt_s",
                    b.bias_rw_rad_s_sqrt_s.unwrap_or(1e-5),
                )?,
            },
            heading: HeadingConfig {
                source: h.source.unwrap_or(HeadingSource::Grid),
                sigma_rad: Positive::new("heading.sigma_deg", deg(h.sigma_deg.unwrap_or(3.0)))?,
                grid_rad: deg(finite("heading.grid_deg", h.grid_deg.unwrap_or(0.0))?),
                grid_step_rad: {
                    let step = h.grid_step_deg.unwrap_or(90.0);
                    if !(1.0..=360.0).contains(&step) || (360.0 / step).fract().abs() > 1e-9 {
                        return Err(invalid(
                            "heading.grid_step_deg",
                            step,
                            "must divide 360 and lie in [1, 360]",
                        ));
                    }
                    Positive::new("heading.grid_step_deg", deg(step))?
                },
                start_heading_rad: deg(finite(
                    "heading.start_heading_deg",
                    h.start_heading_deg.unwrap_or(0.0),
                )?),
                gate_rad: Positive::new("heading.gate_deg", deg(h.gate_deg.unwrap_or(15.0)))?,
                straight_max_change_rad: Positive::new(
                    "heading.straight_max_change_deg",
                    deg(h.straight_max_change_deg.unwrap_or(10.0)),
                )?,
                straight_strides,
                calibration_strides,
                obs_delay_s: non_negative("heading.obs_delay_s", h.obs_delay_s.unwrap_or(0.05))?,
                start_heading_sd_rad: Positive::new(
                    "heading.start_heading_sd_deg",
                    deg(h.start_heading_sd_deg.unwrap_or(1.0)),
                )?,
                observations: h.observations.unwrap_or(HeadingObservations::Both),
                stride_sigma_rad: Positive::new(
                    "heading.stride_sigma_deg",
                    deg(h.stride_sigma_deg.unwrap_or(2.0)),
                )?,
                min_stride_m: Positive::new("heading.min_stride_m", h.min_stride_m.unwrap_or(0.5))?,
                line_footprints: match h.line_footprints.unwrap_or(0) {
                    n @ (0 | 3..=8) => n,
                    n => {
                        return Err(invalid(
                            "heading.line_footprints",
                            n,
                            "must be 0 (off) or 3..=8",
                        ));
                    }
                },
                line_lateral_m: Positive::new(
                    "heading.line_lateral_m",
                    h.line_lateral_m.unwrap_or(0.05),
                )?,
                aligned_prior: Fraction::new(
                    "heading.aligned_prior",
                    h.aligned_prior.unwrap_or(0.7),
                )?,
                min_weight: Fraction::new("heading.min_weight", h.min_weight.unwrap_or(0.5))?,
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

/// Fills in the file name of a validation error.
pub fn with_path(err: ConfigError, path: &Path) -> ConfigError {
    match err {
        ConfigError::Invalid {
            key, value, rule, ..
        } => ConfigError::Invalid {
            path: path.to_owned(),
            key,
            value,
            rule,
        },
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        let c = Config::default();
        assert_eq!(c.mode, Mode::Eskf);
        assert_eq!(c.detector.window, 5);
        assert!((c.heading.grid_step_rad.get() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn unknown_key_is_named() {
        let err = ConfigFile::parse("[detector]\nthreshhold = 3.0\n", Path::new("x.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("threshhold"), "{err}");
        assert!(err.contains("x.toml"), "{err}");
    }

    #[test]
    fn bad_values_name_key_and_value() {
        let f = ConfigFile::parse("[eskf]\nzupt_sd_m_s = -1.0\n", Path::new("a.toml")).unwrap();
        let err = with_path(f.validate().unwrap_err(), Path::new("a.toml")).to_string();
        assert!(err.contains("eskf.zupt_sd_m_s"), "{err}");
        assert!(err.contains("-1"), "{err}");
        assert!(err.contains("a.toml"), "{err}");

        let f =
            ConfigFile::parse("[heading]\ngrid_step_deg = 70.0\n", Path::new("a.toml")).unwrap();
        assert!(
            f.validate()
                .unwrap_err()
                .to_string()
                .contains("grid_step_deg")
        );

        let f = ConfigFile::parse("[detector]\nwindow = 0\n", Path::new("a.toml")).unwrap();
        assert!(
            f.validate()
                .unwrap_err()
                .to_string()
                .contains("detector.window")
        );
    }

    #[test]
    fn daemon_section_is_validated() {
        let f =
            ConfigFile::parse("[daemon]\ndelivery = \"sometimes\"\n", Path::new("s.toml")).unwrap();
        assert!(
            f.validate()
                .unwrap_err()
                .to_string()
                .contains("daemon.delivery")
        );
        let f = ConfigFile::parse("[daemon]\ndomain = \"a b\"\n", Path::new("s.toml")).unwrap();
        assert!(
            f.validate()
                .unwrap_err()
                .to_string()
                .contains("daemon.domain")
        );
        // The longest domain the services accept passes, one more character does not (config
        // and `corridor serve` once disagreed: 64 against 48).
        let long = |n: usize| format!("[daemon]\ndomain = \"{}\"\n", "d".repeat(n));
        let max = crate::services::MAX_DOMAIN_LEN;
        let ok = ConfigFile::parse(&long(max), Path::new("s.toml")).unwrap();
        crate::services::Domain::new(&ok.validate().unwrap().daemon.domain).unwrap();
        let err = ConfigFile::parse(&long(max + 1), Path::new("s.toml"))
            .unwrap()
            .validate()
            .unwrap_err()
            .to_string();
        assert!(err.contains("daemon.domain") && err.contains("48"), "{err}");
        let f = ConfigFile::parse(
            "[daemon]\ndelivery = \"lossless\"\nchannel_capacity = 8\n",
            Path::new("s.toml"),
        )
        .unwrap();
        let c = f.validate().unwrap();
        assert!(c.daemon.lossless);
        assert_eq!(c.daemon.channel_capacity, 8);
    }

    #[test]
    fn unknown_mode_is_rejected() {
        let err = ConfigFile::parse("[estimator]\nmode = \"magic\"\n", Path::new("m.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("magic"), "{err}");
    }
}
