//! [`ConfigOverrides`]: the values that replace a configuration file's before validation.

use super::{BiasPrior, Config, ConfigError, ConfigFile, Mode, with_path};
use std::path::Path;

/// Values that replace those of a configuration file before it is validated, so that a bad
/// value is reported under its key (and the file's name) like one read from the file. The one
/// way to override the configuration: the command line (`--mode`, `--prior`,
/// `--start-heading-deg`, `--grid-deg`), a suite's rows and recordings (mode, prior, the map
/// knowledge of each walk), the demo, benches and tests. `None` keeps the file's value.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ConfigOverrides {
    /// `estimator.mode`.
    pub mode: Option<Mode>,
    /// `alignment.gyro_bias_prior`.
    pub gyro_bias_prior: Option<BiasPrior>,
    /// `heading.start_heading_deg`: the direction of the walk's first stride, degrees, map frame.
    pub start_heading_deg: Option<f64>,
    /// `heading.grid_deg`: the orientation of the building's dominant directions, degrees.
    pub grid_deg: Option<f64>,
}

impl ConfigOverrides {
    /// Writes the overridden values into `file`.
    pub fn apply(&self, file: &mut ConfigFile) {
        if let Some(v) = self.mode {
            file.estimator.mode = Some(v);
        }
        if let Some(v) = self.gyro_bias_prior {
            file.alignment.gyro_bias_prior = Some(v);
        }
        if let Some(v) = self.start_heading_deg {
            file.heading.start_heading_deg = Some(v);
        }
        if let Some(v) = self.grid_deg {
            file.heading.grid_deg = Some(v);
        }
    }

    /// A copy of `file` with the overrides applied.
    pub fn applied(&self, file: &ConfigFile) -> ConfigFile {
        let mut file = file.clone();
        self.apply(&mut file);
        file
    }

    /// `file` (read from `path`) with the overrides applied, validated; errors name `path`
    /// and the key, or the command-line flag when the bad value is an override's.
    pub fn validate(&self, file: &ConfigFile, path: &Path) -> Result<Config, ConfigError> {
        self.applied(file).validate().map_err(|e| match e {
            ConfigError::Invalid {
                key, value, rule, ..
            } if self.flag_of(&key).is_some() => ConfigError::Flag {
                flag: self.flag_of(&key).unwrap_or_default(),
                key,
                value,
                rule,
            },
            other => with_path(other, path),
        })
    }

    /// The command-line flag that overrode `key`, if one did.
    fn flag_of(&self, key: &str) -> Option<&'static str> {
        match key {
            "heading.start_heading_deg" if self.start_heading_deg.is_some() => {
                Some("--start-heading-deg")
            }
            "heading.grid_deg" if self.grid_deg.is_some() => Some("--grid-deg"),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_replace_the_file_and_bad_values_name_the_key() {
        let file =
            ConfigFile::parse("[estimator]\nmode = \"zupt\"\n", Path::new("c.toml")).unwrap();
        let o = ConfigOverrides {
            mode: Some(Mode::Paper),
            gyro_bias_prior: Some(BiasPrior::None),
            start_heading_deg: Some(90.0),
            grid_deg: Some(10.0),
        };
        let cfg = o.validate(&file, Path::new("c.toml")).unwrap();
        assert_eq!(cfg.mode, Mode::Paper);
        assert_eq!(cfg.alignment.gyro_bias_prior, BiasPrior::None);
        assert!((cfg.heading.start_heading_rad.get() - 90f64.to_radians()).abs() < 1e-12);
        assert!((cfg.heading.grid_rad.get() - 10f64.to_radians()).abs() < 1e-12);
        // Nothing overridden: the file's value stays.
        let kept = ConfigOverrides::default()
            .validate(&file, Path::new("c.toml"))
            .unwrap();
        assert_eq!(kept.mode, Mode::Zupt);
        let bad = ConfigOverrides {
            start_heading_deg: Some(f64::NAN),
            ..Default::default()
        };
        let err = bad
            .validate(&file, Path::new("c.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("--start-heading-deg NaN") && err.contains("heading.start_heading_deg"),
            "{err}"
        );
    }
}
