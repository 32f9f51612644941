//! The bounds of the keys a review found unbounded: the `[sensor]` limits, the σ floors and the
//! stance detector's thresholds. Every bundled configuration stays within them.

use super::*;

/// The error of `text` as a config file, with the file named.
fn error_of(text: &str) -> String {
    let f = ConfigFile::parse(text, Path::new("b.toml")).unwrap();
    with_path(f.validate().unwrap_err(), Path::new("b.toml")).to_string()
}

#[test]
fn every_bundled_configuration_loads() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            Config::from_file(&path).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        }
    }
    assert!(n >= 4, "{n} configurations in {}", dir.display());
}

#[test]
fn a_sensor_limit_beyond_any_foot_imu_is_refused_naming_key_and_value() {
    for (text, key, shown) in [
        (
            "[sensor]\ngyro_range_rad_s = 1e30\nmax_gyro_rad_s = 1e30\n",
            "sensor.gyro_range_rad_s",
            "1e30",
        ),
        (
            "[sensor]\naccel_range_m_s2 = 1e30\nmax_accel_m_s2 = 1e30\n",
            "sensor.accel_range_m_s2",
            "1e30",
        ),
        (
            "[sensor]\nmax_gyro_rad_s = 1e30\n",
            "sensor.max_gyro_rad_s",
            "1e30",
        ),
        ("[sensor]\nmax_dt_s = 1e30\n", "sensor.max_dt_s", "1e30"),
        (
            "[sensor]\ngyro_range_rad_s = inf\n",
            "sensor.gyro_range_rad_s",
            "inf",
        ),
    ] {
        let err = error_of(text);
        assert!(
            err.contains(&format!("`{key}` = {shown}")) && err.contains("b.toml"),
            "{text}: {err}"
        );
    }
}
