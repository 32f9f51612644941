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
        if !(1..=DAEMON_CHANNEL_CAPACITY_MAX).contains(&channel_capacity) {
            return Err(invalid_count(
                "daemon.channel_capacity",
                channel_capacity as u64,
                "must be in [1, 524288] samples (each preallocated at start)",
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
        // Each range's reason is beside its bound in `defaults`.
        let get = |v: Option<f64>, default: f64| v.unwrap_or(default);
        let daemon = DaemonSettings {
            domain,
            lossless,
            channel_capacity,
            bias_period_s: Positive::in_range(
                "daemon.bias_period_s",
                get(dm.bias_period_s, DAEMON_BIAS_PERIOD_S),
                DAEMON_BIAS_PERIOD_MIN_S,
                DAEMON_OUTPUT_PERIOD_MAX_S,
                "must be in [0.1, 60] s of sensor time",
            )?,
            diagnostics_period_s: Positive::in_range(
                "daemon.diagnostics_period_s",
                get(dm.diagnostics_period_s, DAEMON_DIAGNOSTICS_PERIOD_S),
                DAEMON_WAKE_S,
                DAEMON_OUTPUT_PERIOD_MAX_S,
                "must be in [0.05, 60] s",
            )?,
            health_period_s: Positive::in_range(
                "daemon.health_period_s",
                get(dm.health_period_s, DAEMON_HEALTH_PERIOD_S),
                DAEMON_WAKE_S,
                DAEMON_HEALTH_PERIOD_MAX_S,
                "must be in [0.05, 3600] s",
            )?,
            checkpoint_path: dm.checkpoint_path.clone(),
            runtime_dir: dm.runtime_dir.clone(),
            checkpoint_period_s: Positive::in_range(
                "daemon.checkpoint_period_s",
                get(dm.checkpoint_period_s, DAEMON_CHECKPOINT_PERIOD_S),
                DAEMON_WAKE_S,
                DAEMON_CHECKPOINT_PERIOD_MAX_S,
                "must be in [0.05, 86400] s",
            )?,
            stall_timeout_s: Positive::in_range(
                "daemon.stall_timeout_s",
                get(dm.stall_timeout_s, DAEMON_STALL_TIMEOUT_S),
                DAEMON_WAKE_S,
                DAEMON_STALL_TIMEOUT_MAX_S,
                "must be in [0.05, 60] s",
            )?,
            producer_takeover_s: Positive::in_range(
                "daemon.producer_takeover_s",
                get(dm.producer_takeover_s, DAEMON_PRODUCER_TAKEOVER_S),
                DAEMON_WAKE_S,
                DAEMON_PRODUCER_TAKEOVER_MAX_S,
                "must be in [0.05, 60] s",
            )?,
        };
        Ok(daemon)
    }
}
