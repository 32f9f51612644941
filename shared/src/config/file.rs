//! The TOML file, key for key: every key optional, `deny_unknown_fields`.

use super::*;
use serde::{Deserialize, Serialize};

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
    /// Gyro cross-coupling states into the sensor z axis (from x and from y, an axis
    /// misalignment as it reaches the heading when z is the axis nearest the vertical):
    /// initial σ, degrees.
    pub gyro_coupling_z_sd_deg: Option<f64>,
    /// Not a state: a known accelerometer scale error common to every axis, as a fraction (the
    /// sensor reads `1 + k` times the specific force); every sample's specific force is divided
    /// by `1 + k` before anything uses it. Strides come out `1 + k` times too long with it (the
    /// gravity is taken from the rest), so only position information (surveyed footprints) can
    /// tell it: `corridor diagnose` sets it from their stride ratio. Default 0.
    pub accel_scale_factor: Option<f64>,
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
    /// Runtime directory of a secured domain (absolute; see `corridor_shared::runtime_dir`);
    /// absent: the open domain in `/tmp/iceoryx2`.
    pub runtime_dir: Option<PathBuf>,
    /// Period of checkpoints while running, s of wall-clock time (default 30.0).
    pub checkpoint_period_s: Option<f64>,
    /// Longest a lossless publish waits on one consumer's full buffer, s (default 1.0); beyond
    /// it the consumer counts as stalled and loses (counted) what its buffer cannot take.
    pub stall_timeout_s: Option<f64>,
    /// While the IMU producer the daemon follows is connected and has sent within this time, s
    /// (default 1.0), samples from another producer are refused (counted as foreign); after it,
    /// or once the followed one has ended its stream or closed, the other takes over.
    pub producer_takeover_s: Option<f64>,
}

/// `[estimator]` section.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EstimatorFile {
    /// Bias estimation mode (default `eskf`).
    pub mode: Option<Mode>,
    /// The bias counts as converged once the estimate carries less than this fraction of a
    /// bias error present when the bias was set (the same size on every axis; the filter's
    /// closed-loop response, not its σ; default 0.05).
    pub converged_unabsorbed: Option<f64>,
    /// Removed (the bias σ the flag used to need could never fall low enough): refused with an
    /// error that names `converged_unabsorbed`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub converged_sd_rad_s: Option<f64>,
    /// Largest regular time step; a longer one is a gap, counted (default 0.05 s).
    pub max_dt_s: Option<f64>,
    /// A gap up to this long is bridged: integrated as one step on the rates and forces on
    /// both sides of it, with the attitude and velocity variance that interpolation leaves; a
    /// longer one is filled (`max_fill_s`) or starts a new segment (default 0.16 s; 0: none is
    /// bridged).
    pub max_bridge_s: Option<f64>,
    /// A longer gap up to this long, within half a stride, is filled with the samples of the
    /// same phase one stride earlier when the rates around it match them (default 0.45 s;
    /// 0: off). Also the longest step the estimator may take for a clock step rather than a
    /// loss (so a value at or under `max_bridge_s` keeps that test and fills nothing).
    pub max_fill_s: Option<f64>,
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
    /// A 50 ms block of the initial rest whose mean rate lies further than this from the mean of the
    /// rest's blocks so far is motion (a foot that rocks or shifts its weight while the stance
    /// detector still says stance) and is left out of the means (default 0.05 rad/s). Not
    /// applied to a walking stance that aligns without a rest, nor to the later rests.
    pub rest_max_rate_change_rad_s: Option<f64>,
    /// Without an initial rest of `min_rest_s`, the first stance at least this long aligns the
    /// filter, without a rest-mean bias prior (default 0.1 s; 0 waits for a rest).
    pub min_start_stance_s: Option<f64>,
    /// Fast gait: a stance seen whole (its landing seen) in which the stance detector had
    /// raised its threshold over a whole look-back aligns when at least this long (default
    /// 0.03 s; 0: any such stance; above `min_start_stance_s` it changes nothing). Needs the
    /// adaptive detector (`detector.adaptive_factor`).
    pub fast_gait_start_stance_s: Option<f64>,
    /// A start in fast gait goes back to the first stance of the last this many seconds that
    /// the fast-gait rule would have taken, and the filter runs over the samples since it: the
    /// gait is known to be fast only a look-back after the walk is first seen (default 3 s; cut
    /// to the 1,024 samples the estimator keeps while it aligns, 5.1 s at 200 Hz; 0: off).
    pub fast_gait_replay_s: Option<f64>,
    /// The σ of roll and pitch when a walking stance aligns (no rest), rad: its mean specific
    /// force holds what the foot still accelerates (default 0.035 rad).
    pub start_stance_tilt_sd_rad: Option<f64>,
    /// The largest initial-rest mean rate (its magnitude) taken as the bias prior, rad/s (left
    /// out: only `sensor.max_gyro_bias_rad_s`, per axis). A rest through which the foot pivots
    /// slowly about the vertical shows no other sign of motion, and its mean rate would be a
    /// confident, wrong prior: set it near the largest bias the sensor shows, well below the
    /// health bound.
    pub max_prior_rate_rad_s: Option<f64>,
    /// The gyro bias this sensor unit starts with, rad/s, sensor axes (e.g. the median of the
    /// final biases of its earlier recordings): with `gyro_bias_prior = "rest_mean"`, a start
    /// without a rest (or with one refused as turning) begins here with σ
    /// `typical_gyro_bias_sd_rad_s`, instead of at zero with `eskf.gyro_bias_initial_sd_rad_s`;
    /// so does a bias thrown away (a restore loop, a relevel). A rest is not fused with it: the
    /// rest measures the bias of now. Left out: zero. Both keys or neither.
    pub typical_gyro_bias_rad_s: Option<[f64; 3]>,
    /// The σ of `typical_gyro_bias_rad_s` on each axis, rad/s: the spread of the unit's biases
    /// from one start to the next, with a margin.
    pub typical_gyro_bias_sd_rad_s: Option<f64>,
}

/// `[detector]` section.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DetectorFile {
    /// Statistic (default `shoe`).
    pub kind: Option<DetectorKind>,
    /// Window length in samples (default 5).
    pub window: Option<usize>,
    /// Threshold on the statistic (default 1e5 for SHOE with the default σ: about 0.6 rad/s of
    /// rotation); at most (`sensor.gyro_range_rad_s` / `sigma_gyro_rad_s`)², for `mv`
    /// (`sensor.accel_range_m_s2` / `sigma_accel_m_s2`)²: beyond it a foot turning at the
    /// sensor's full scale would be a stance.
    pub threshold: Option<f64>,
    /// Accelerometer noise σ used by the statistic (default 0.01 m/s²).
    pub sigma_accel_m_s2: Option<f64>,
    /// Gyro noise σ used by the statistic (default 0.1 °/s in rad/s).
    pub sigma_gyro_rad_s: Option<f64>,
    /// Shortest stance kept (default 0.04 s).
    pub min_stance_s: Option<f64>,
    /// Stances split by a pause shorter than this are one stance (one footfall: one stride
    /// observation, one rest test) (default 0.3 s; 0 = off).
    pub merge_gap_s: Option<f64>,
    /// Adaptive threshold: a sample is stance when its statistic is below `threshold` or below
    /// this factor times the quietest statistic of the last `adaptive_window_s` (absent: off).
    pub adaptive_factor: Option<f64>,
    /// Look-back of the adaptive threshold, about one stride cycle (default 1.5 s).
    pub adaptive_window_s: Option<f64>,
    /// Largest adaptive threshold (default 10 × `threshold`), within the bound of `threshold`.
    pub adaptive_max_threshold: Option<f64>,
    /// A late footfall: a dip of the statistic below the threshold at least this long but
    /// shorter than `min_stance_s`, with no stance within `merge_gap_s` before or after it, is a
    /// footfall the detector missed; its quietest sample gets the zero-velocity update,
    /// `merge_gap_s` late (absent: off).
    pub late_stance_min_s: Option<f64>,
    /// An overdue footfall: when this many stride periods have passed since the last footfall
    /// without a stance, the quietest sample of the cycle (below the adaptive threshold's cap)
    /// is a footfall the detector missed, updated late as above (absent: off).
    pub overdue_stride_factor: Option<f64>,
}

/// `[eskf]` section: the ZUPT-aided error-state filter.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EskfFile {
    /// Accelerometer white-noise density, m/s²/√Hz (the velocity's variance grows by σ²·dt per
    /// step; the key's name keeps the unit it had: a datasheet's per-sample σ is this times
    /// √rate) (default 0.5: foot dynamics, not just sensor noise).
    pub accel_noise_m_s2: Option<f64>,
    /// Gyro white-noise density, rad/s/√Hz (the attitude's variance grows by σ²·dt per step)
    /// (default 0.01).
    pub gyro_noise_rad_s: Option<f64>,
    /// Gyro-bias random walk σ per √s (default 1e-4 rad/s/√s).
    pub gyro_bias_rw_rad_s_sqrt_s: Option<f64>,
    /// Initial gyro-bias σ without a prior, about zero: the sensor's spread of biases (default
    /// 0.01 rad/s). The rest-mean prior is fused with it.
    pub gyro_bias_initial_sd_rad_s: Option<f64>,
    /// The floor of the rest-mean prior's σ, added to the rest's own standard error (default
    /// 5e-4 rad/s).
    pub gyro_bias_prior_sd_rad_s: Option<f64>,
    /// Zero-velocity pseudo-measurement σ (default 0.01 m/s).
    pub zupt_sd_m_s: Option<f64>,
    /// Initial roll/pitch σ (default 0.5°, in rad).
    pub initial_tilt_sd_rad: Option<f64>,
    /// Lever arm between the sensor and the point the foot rolls about at the edges of a
    /// stance (default 0: off): the ZUPT σ of a sample is √(zupt_sd² + (arm·|ω|)²).
    pub zupt_lever_arm_m: Option<f64>,
    /// Between updates (the swing), the covariance is propagated once per interval of about
    /// this length on the samples' summed transition, s (default 0.02; 0: on every sample).
    /// Stance samples are propagated at once; an update, or a decision from the covariance,
    /// brings the waiting steps up to date first (the per-sample health check reads the
    /// covariance as of the last step).
    pub covariance_step_s: Option<f64>,
    /// Zero-rate updates: every later rest of at least `alignment.min_rest_s` (its first and
    /// its last `alignment.rest_tail_s` left out) observes the gyro bias like the initial rest,
    /// with σ √(`gyro_bias_prior_sd_rad_s`² + the rest's spread²) (default true).
    pub zero_rate_updates: Option<bool>,
    /// A rest longer than this is fused while it lasts, every this many seconds of its
    /// settled part, not only at its end (default 2 s): the yaw integrates the difference
    /// between the filter's bias and the rest's rate until the bias is observed.
    pub zero_rate_interval_s: Option<f64>,
    /// The gyro noise density while the foot rests (from the first zero-rate update of a rest
    /// to its end), rad/s/√Hz: the sensor's own noise, not the swing's error budget of `gyro_noise_rad_s`
    /// (default 1e-3).
    pub rest_gyro_noise_rad_s: Option<f64>,
    /// Above this yaw σ the stance velocity updates leave the yaw alone (a Schmidt update: its
    /// estimate and variance stay, the other states see its correlations), rad (default 0:
    /// off). Stance updates observe the yaw only through the horizontal force at the stance's
    /// edges, where the foot's motion is least modelled; with the yaw wide (after a long gap,
    /// or without heading information for long) they turned it by degrees.
    pub stance_yaw_max_sd_rad: Option<f64>,
    /// Height of the sensor above the floor contact about which the foot rolls at heel strike
    /// and heel-off, m: the stance velocity update expects the sensor to move at this height
    /// times the rate about the foot's lateral axis, along the walking direction (default 0: a
    /// plain zero-velocity update).
    pub zupt_rolling_height_m: Option<f64>,
    /// A gyro axis at its rail (`sensor.gyro_range_rad_s`) read less than the true rate: the
    /// attitude variance grows about that axis by (this σ × dt)² per clipped sample, rad/s
    /// (default 0.5; 0: no clipping model).
    pub clipped_rate_sd_rad_s: Option<f64>,
    /// The peak a gyro rail cut off is put back: a parabola through the two samples before and
    /// the two after each run of samples at the rail gives the rate the rail cut off, and the
    /// filter propagates again through those samples with it, two samples after the run's end
    /// (default true).
    pub restore_clipped_peaks: Option<bool>,
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
    /// Direction of the walk's first stride, in the map frame (default 0°): for a walk that
    /// starts from standing in a corridor, that corridor's.
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
    /// Observe each stride one stance late, once the footprint after it is known: the line
    /// test must then hold both with the stride's own footprint last and with the next one
    /// (default false).
    pub stride_look_ahead: Option<bool>,
    /// The `eskf` mode fuses a foot axis only when the stride that brought the foot there runs
    /// within this angle of the direction the foot axis is associated with (degrees; default:
    /// absent, no such test).
    pub foot_axis_stride_max_deg: Option<f64>,
    /// Prior probability that a stance's walking direction is a dominant direction, for the
    /// association weight (default 0.7).
    pub aligned_prior: Option<f64>,
    /// Smallest association weight that is still fused (default 0.5).
    pub min_weight: Option<f64>,
    /// The `eskf` mode takes its heading as lost after this many straight strides in a row
    /// that no direction takes and that run off the nearest one by one angle: it widens the
    /// heading variance to that angle so that the directions can be found again (default:
    /// absent, never).
    pub reacquire_strides: Option<u32>,
}
