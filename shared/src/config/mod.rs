//! The estimator configuration: one TOML file per sensor (see `configs/`).
//!
//! Parsing happens in two steps. [`ConfigFile`] mirrors the TOML one to one (serde,
//! `deny_unknown_fields`, every key optional with a documented default). [`ConfigFile::validate`]
//! turns it into [`Config`], whose numbers are [`Positive`], [`NonNegative`], [`Fraction`] or
//! [`Finite`] and whose choices are enums, so code that holds a `Config` never sees a negative
//! noise, a NaN, a zero window or an unknown mode. Every error
//! names the key that is wrong and the value found.
//!
//! Files: this one holds the error, the range check and the enums; `numbers.rs` the checked
//! number types ([`Positive`], [`NonNegative`], [`Fraction`], [`Finite`]); `file.rs` the TOML
//! mirror ([`ConfigFile`]); `settings.rs` the validated types ([`Config`]);
//! `read.rs` reading a file and layering it over its `base`; `validate.rs` the one validation
//! pass between them (`validate_daemon.rs` the `[daemon]` section's); `defaults.rs` every default, as a
//! named constant; `overrides.rs`
//! [`ConfigOverrides`], the one way to replace a file's values (command line, suite, tests).

pub mod defaults;
mod file;
mod numbers;
mod overrides;
mod read;
mod settings;
mod validate;
mod validate_daemon;

pub use file::*;
pub use numbers::{Finite, Fraction, NonNegative, Positive};
pub use overrides::ConfigOverrides;
pub use settings::*;

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
        /// The file (overridden values are reported under the file they replace).
        path: PathBuf,
        /// Dotted key, e.g. `detector.threshold`.
        key: String,
        /// The value found, as text.
        value: String,
        /// What the value must satisfy.
        rule: &'static str,
    },
    /// A value given on the command line (a [`ConfigOverrides`] field) is outside the range of
    /// the key it sets.
    #[error("{flag} {value}: {rule} (it sets the config key `{key}`)")]
    Flag {
        /// The command-line flag, e.g. `--start-heading-deg`.
        flag: &'static str,
        /// Dotted key the flag sets.
        key: String,
        /// The value given, as text.
        value: String,
        /// What the value must satisfy.
        rule: &'static str,
    },
}

pub(crate) fn invalid(key: &str, value: impl std::fmt::Display, rule: &'static str) -> ConfigError {
    let mut value = value.to_string();
    // A number written as 1e300 or 1e-12 is shown so, not as its 301 digits or 12 zeros.
    if let Ok(v) = value.parse::<f64>()
        && v != 0.0
        && (v.abs() >= 1e6 || v.abs() < 1e-4)
    {
        value = format!("{v:e}");
    }
    ConfigError::Invalid {
        path: PathBuf::new(),
        key: key.to_owned(),
        value,
        rule,
    }
}

/// A number as [`invalid`] shows it (1e300 and 1e-12 so, not as their 301 digits or 12 zeros),
/// for a value shown with more text.
pub(crate) fn shown(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e6 || v.abs() < 1e-4) {
        format!("{v:e}")
    } else {
        v.to_string()
    }
}

/// [`invalid`] for a count, shown with all its digits (`invalid` showed a channel capacity of
/// 16777216 as 1.6777216e7, and `usize::MAX` rounded).
pub(crate) fn invalid_count(key: &str, value: u64, rule: &'static str) -> ConfigError {
    ConfigError::Invalid {
        path: PathBuf::new(),
        key: key.to_owned(),
        value: value.to_string(),
        rule,
    }
}

/// `value` under `key` must lie in `[lo, hi]`, the range the quantity can physically take
/// (`rule` says it): a value beyond it used to pass as merely "positive" and broke the run
/// later without naming the key (`initial_tilt_sd_rad = 1e300` froze the estimate).
pub(crate) fn in_range(
    key: &str,
    value: f64,
    lo: f64,
    hi: f64,
    rule: &'static str,
) -> Result<f64, ConfigError> {
    if (lo..=hi).contains(&value) {
        Ok(value)
    } else {
        Err(invalid(key, value, rule))
    }
}

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
mod bounds_tests;

#[cfg(test)]
mod tests;
