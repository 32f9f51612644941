//! The `[daemon]` section's one validation pass, into [`DaemonSettings`] (what `corridor serve`
//! needs besides the estimator's [`Config`]).

use super::defaults::*;
use super::*;

impl ConfigFile {
    /// Validates the `[daemon]` section into [`DaemonSettings`] (what `corridor serve` needs
    /// besides the estimator's [`Config`]).
    pub fn validate_daemon(&self) -> Result<DaemonSettings, ConfigError> {
        let dm = &self.daemon;
        let delivery = dm.delivery.as_deref().unwrap_or(DAEMON_DELIVERY);
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
        let channel_capacity = dm.channel_capacity.unwrap_or(DAEMON_CHANNEL_CAPACITY);
        if !(1..=1 << 24).contains(&channel_capacity) {
            return Err(invalid(
                "daemon.channel_capacity",
                channel_capacity,
                "must be in 1..=16777216",
            ));
        }
        let domain = dm
            .domain
            .clone()
            .unwrap_or_else(|| DAEMON_DOMAIN.to_owned());
        // The same rule `corridor serve` applies when it opens the domain.
        if let Err(crate::services::ServiceError::InvalidDomain { rule, .. }) =
            crate::services::Domain::check_name(&domain)
        {
            return Err(invalid("daemon.domain", format!("{domain:?}"), rule));
        }
        // An empty path was taken: "no checkpoint; cold start path=", then a save's rename
        // failed at every stream's end (a review; the `--checkpoint ""` flag is refused).
        if dm
            .checkpoint_path
            .as_ref()
            .is_some_and(|p| p.as_os_str().is_empty())
        {
            return Err(invalid(
                "daemon.checkpoint_path",
                "\"\"",
                "must be a file's path (leave the key out for no checkpoint)",
            ));
        }
        if let Some(dir) = &dm.runtime_dir
            && !dir.is_absolute()
        {
            return Err(invalid(
                "daemon.runtime_dir",
                format!("{:?}", dir.display().to_string()),
                "must be an absolute path",
            ));
        }
        let daemon = DaemonSettings {
            domain,
            lossless,
            channel_capacity,
            bias_period_s: period(
                "daemon.bias_period_s",
                dm.bias_period_s.unwrap_or(DAEMON_BIAS_PERIOD_S),
            )?,
            diagnostics_period_s: period(
                "daemon.diagnostics_period_s",
                dm.diagnostics_period_s
                    .unwrap_or(DAEMON_DIAGNOSTICS_PERIOD_S),
            )?,
            health_period_s: period(
                "daemon.health_period_s",
                dm.health_period_s.unwrap_or(DAEMON_HEALTH_PERIOD_S),
            )?,
            checkpoint_path: dm.checkpoint_path.clone(),
            runtime_dir: dm.runtime_dir.clone(),
            checkpoint_period_s: period(
                "daemon.checkpoint_period_s",
                dm.checkpoint_period_s.unwrap_or(DAEMON_CHECKPOINT_PERIOD_S),
            )?,
            stall_timeout_s: period(
                "daemon.stall_timeout_s",
                dm.stall_timeout_s.unwrap_or(DAEMON_STALL_TIMEOUT_S),
            )?,
            producer_takeover_s: period(
                "daemon.producer_takeover_s",
                dm.producer_takeover_s.unwrap_or(DAEMON_PRODUCER_TAKEOVER_S),
            )?,
        };
        Ok(daemon)
    }
}

/// A daemon period or timeout: positive and at most [`crate::injection::MAX_TIME_S`] (1e300 s
/// passed as positive and panicked where the daemon made a duration of it).
fn period(key: &'static str, v: f64) -> Result<Positive, ConfigError> {
    let max = crate::injection::MAX_TIME_S;
    Positive::in_range(key, v, 0.0, max, "must be in (0, 1e9] s")
}
