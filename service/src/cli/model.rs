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
    /// Corridor map (TOML with `[[corridor]]` tables); switches the heading source to the map.
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Direction of the walk's first stride, degrees in the map frame (overrides the config):
    /// the filter anchors that stride to it (`heading.start_heading_sd_deg`). For a walk that
    /// starts from standing in a corridor, that corridor's direction; a walk that starts in a
    /// weave or across a corridor needs the stride's own direction.
    #[arg(long, allow_negative_numbers = true)]
    pub start_heading_deg: Option<f64>,
    /// Orientation of the building's dominant directions, degrees (overrides the config).
    #[arg(long, allow_negative_numbers = true)]
    pub grid_deg: Option<f64>,
    /// Estimation mode: zupt, paper, rotation_aware or eskf (overrides the config).
    #[arg(long, value_parser = listed::<Mode>(&["zupt", "paper", "rotation_aware", "eskf"]))]
    pub mode: Option<Mode>,
    /// Gyro-bias prior: none or rest_mean (overrides the config).
    #[arg(long, value_parser = listed::<BiasPrior>(&["none", "rest_mean"]))]
    pub prior: Option<BiasPrior>,
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
        Ok(self.overrides().validate(&file, &path)?)
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
        self.overrides().apply(&mut file);
        Ok(file)
    }

    /// The flags that override the config file.
    pub fn overrides(&self) -> ConfigOverrides {
        ConfigOverrides {
            mode: self.mode,
            gyro_bias_prior: self.prior,
            start_heading_deg: self.start_heading_deg,
            grid_deg: self.grid_deg,
        }
    }
}

/// The parser of a flag that takes one of `names`, the config's own spellings of `T`'s values
/// (the argument parser refuses any other and lists these).
fn listed<T>(names: &'static [&'static str]) -> impl clap::builder::TypedValueParser<Value = T>
where
    T: serde::de::DeserializeOwned + Clone + Send + Sync + 'static,
{
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(names).map(|name| {
        toml::Value::String(name)
            .try_into::<T>()
            .expect("every listed name is one of the config's values")
    })
}
