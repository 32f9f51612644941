//! The shipped configuration files agree with each other: `configs/service.toml` is the sensor's
//! `configs/gdins.toml` plus a `[daemon]` section, so the daemon runs the same estimator as
//! `corridor run` and the results suite.

use corridor_shared::config::ConfigFile;
use std::path::{Path, PathBuf};

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs")
}

#[test]
fn the_daemon_config_runs_the_sensor_config_estimator() {
    let read =
        |name: &str| ConfigFile::read(&configs().join(name)).unwrap_or_else(|e| panic!("{e}"));
    let (service, sensor) = (read("service.toml"), read("gdins.toml"));
    let estimator = |f: &ConfigFile| serde_json::to_value(f.validate().unwrap()).unwrap();
    assert_eq!(
        estimator(&service),
        estimator(&sensor),
        "configs/service.toml's estimator sections differ from configs/gdins.toml's"
    );
    // And its [daemon] section is valid and not the defaults.
    let d = service.validate_daemon().unwrap();
    assert!(
        d.checkpoint_path.is_some()
            || d.domain != "default"
            || d.lossless
            || d.channel_capacity != 4096,
        "configs/service.toml should say something about the daemon"
    );
}
