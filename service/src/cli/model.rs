//! [`ModelArgs`]: the configuration flags shared by every command that runs the estimator.

use anyhow::Result;
use clap::Args;
use corridor_shared::config::{
    BiasPrior, Config, ConfigFile, ConfigOverrides, DaemonSettings, Mode,
};
use std::path::PathBuf;

/// Configuration flags shared by every command that runs the estimator.
#[derive(Args, Debug, Clone)]
pub struct ModelArgs {
    /// Configuration file (TOML); built-in defaults when absent.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Corridor map (TOML with [[corridor]] tables); switches the heading source to the map.
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Walking direction at the start, degrees in the map frame (overrides the config).
    #[arg(long, allow_negative_numbers = true)]
    pub start_heading_deg: Option<f64>,
    /// Orientation of the building's dominant directions, degrees (overrides the config).
    #[arg(long, allow_negative_numbers = true)]
    pub grid_deg: Option<f64>,
    /// Estimation mode: zupt, paper, rotation_aware or eskf (overrides the config).
    #[arg(long, value_parser = ["zupt", "paper", "rotation_aware", "eskf"])]
    pub mode: Option<String>,
    /// Gyro-bias prior: none or rest_mean (overrides the config).
    #[arg(long, value_parser = ["none", "rest_mean"])]
    pub prior: Option<String>,
}

impl ModelArgs {
    /// Reads the config file and applies the overrides; errors name the key and the value,
    /// and the flag when the value came from one.
    pub fn config(&self) -> Result<Config> {
        let file = match &self.config {
            Some(p) => ConfigFile::read(p)?,
            None => ConfigFile::default(),
        };
        let path = self
            .config
            .clone()
            .unwrap_or_else(|| PathBuf::from("<built-in defaults>"));
        Ok(self.overrides()?.validate(&file, &path)?)
    }

    /// The `[daemon]` section of the config file, validated.
    pub fn daemon_settings(&self) -> Result<DaemonSettings> {
        let path = self
            .config
            .clone()
            .unwrap_or_else(|| PathBuf::from("<built-in defaults>"));
        Ok(self
            .config_file()?
            .validate_daemon()
            .map_err(|e| corridor_shared::config::with_path(e, &path))?)
    }

    /// The config file with the overrides applied, not yet validated.
    pub fn config_file(&self) -> Result<ConfigFile> {
        let mut file = match &self.config {
            Some(p) => ConfigFile::read(p)?,
            None => ConfigFile::default(),
        };
        self.overrides()?.apply(&mut file);
        Ok(file)
    }

    /// The flags that override the config file.
    pub fn overrides(&self) -> Result<ConfigOverrides> {
        // The flag's own message only: serde's "unknown variant" says the same again.
        let mode =
            match &self.mode {
                Some(m) => Some(toml::Value::String(m.clone()).try_into::<Mode>().map_err(
                    |_| {
                        anyhow::anyhow!(
                            "--mode {m:?}: expected zupt, paper, rotation_aware or eskf"
                        )
                    },
                )?),
                None => None,
            };
        let gyro_bias_prior = match &self.prior {
            Some(p) => Some(
                toml::Value::String(p.clone())
                    .try_into::<BiasPrior>()
                    .map_err(|_| anyhow::anyhow!("--prior {p:?}: expected none or rest_mean"))?,
            ),
            None => None,
        };
        Ok(ConfigOverrides {
            mode,
            gyro_bias_prior,
            start_heading_deg: self.start_heading_deg,
            grid_deg: self.grid_deg,
        })
    }
}
