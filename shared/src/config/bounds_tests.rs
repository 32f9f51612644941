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

#[test]
fn a_sigma_below_any_real_sensor_or_observation_is_refused_and_its_floor_taken() {
    use defaults::*;
    // (section, key, floor as written): 1e-300 was taken for each (its square is 0), and the
    // floor itself passes.
    for (section, key, floor) in [
        ("eskf", "accel_noise_m_s2", ACCEL_NOISE_MIN_M_S2),
        ("eskf", "gyro_noise_rad_s", GYRO_NOISE_MIN_RAD_S),
        ("eskf", "rest_gyro_noise_rad_s", GYRO_NOISE_MIN_RAD_S),
        ("eskf", "gyro_bias_initial_sd_rad_s", GYRO_BIAS_SD_MIN_RAD_S),
        ("eskf", "gyro_bias_prior_sd_rad_s", GYRO_BIAS_SD_MIN_RAD_S),
        ("eskf", "zupt_sd_m_s", ZUPT_SD_MIN_M_S),
        ("eskf", "initial_tilt_sd_rad", TILT_SD_MIN_RAD),
        ("bias_kf", "tilt_sd_rad", TILT_SD_MIN_RAD),
        ("alignment", "start_stance_tilt_sd_rad", TILT_SD_MIN_RAD),
        ("heading", "sigma_deg", FOOT_AXIS_SD_MIN_DEG),
        ("heading", "stride_sigma_deg", STRIDE_SD_MIN_DEG),
        ("heading", "start_heading_sd_deg", STRIDE_SD_MIN_DEG),
    ] {
        let err = error_of(&format!("[{section}]\n{key} = 1e-300\n"));
        assert!(
            err.contains(&format!("`{section}.{key}` = 1e-300:")),
            "{key}: {err}"
        );
        let err = error_of(&format!("[{section}]\n{key} = {:e}\n", floor * 0.5));
        assert!(
            err.contains(&format!("`{section}.{key}` = ")),
            "{key}: {err}"
        );
        let text = format!("[{section}]\n{key} = {floor:e}\n");
        ConfigFile::parse(&text, Path::new("b.toml"))
            .unwrap()
            .validate()
            .unwrap_or_else(|e| panic!("{text}: {e}"));
    }
    // The typical bias's σ, which comes with the bias.
    let typical = |sd: &str| {
        format!(
            "[alignment]\ntypical_gyro_bias_rad_s = [0.0, 0.0, 0.0]\n\
             typical_gyro_bias_sd_rad_s = {sd}\n"
        )
    };
    let err = error_of(&typical("1e-300"));
    assert!(
        err.contains("`alignment.typical_gyro_bias_sd_rad_s` = 1e-300:"),
        "{err}"
    );
    ConfigFile::parse(&typical("1e-6"), Path::new("b.toml"))
        .unwrap()
        .validate()
        .unwrap();
}

#[test]
fn a_stance_threshold_that_takes_full_scale_motion_for_a_stance_is_refused() {
    // A review: `threshold = 1e300` was taken (and 1e8 with gdins.toml's sensor): every sample
    // was a stance, and the run ended in "no initial rest followed by motion", naming no key.
    let gdins = "[sensor]\ngyro_range_rad_s = 8.727\naccel_range_m_s2 = 78.45\nmax_gyro_rad_s = 30.0\n\
                 max_accel_m_s2 = 300.0\n[detector]\nsigma_gyro_rad_s = 0.001745\n\
                 sigma_accel_m_s2 = 0.01\n";
    let bound = (8.727f64 / 0.001745).powi(2); // 2.5e7
    for (extra, key, shown) in [
        (
            "threshold = 1e300\n",
            "detector.threshold",
            "1e300 (with sensor.gyro_range_rad_s = 8.727 and detector.sigma_gyro_rad_s = 0.001745",
        ),
        ("threshold = 1e8\n", "detector.threshold", "1e8 (with"),
        (
            "adaptive_factor = 3.0\nadaptive_max_threshold = 1e300\n",
            "detector.adaptive_max_threshold",
            "1e300 (with",
        ),
        // The accelerometer's statistic, the accelerometer's bound: (78.45 / 0.01)² = 6.2e7.
        (
            "kind = \"mv\"\nthreshold = 1e8\n",
            "detector.threshold",
            "1e8 (with sensor.accel_range_m_s2 = 78.45 and detector.sigma_accel_m_s2 = 0.01",
        ),
    ] {
        let err = error_of(&format!("{gdins}{extra}"));
        assert!(
            err.contains(&format!("`{key}` = {shown}")) && err.contains("full scale"),
            "{extra}: {err}"
        );
    }
    // Up to the bound it is taken; the default adaptive cap (ten times the threshold) stays
    // within it, where it used to overflow to inf and name a key the file did not set.
    let c = ConfigFile::parse(
        &format!("{gdins}threshold = {bound:e}\n"),
        Path::new("b.toml"),
    )
    .unwrap()
    .validate()
    .unwrap();
    assert_eq!(c.detector.threshold.get(), bound);
    assert_eq!(c.detector.adaptive_max_threshold.get(), bound);
    let c = ConfigFile::parse(&format!("{gdins}threshold = 1e5\n"), Path::new("b.toml"))
        .unwrap()
        .validate()
        .unwrap();
    assert_eq!(c.detector.adaptive_max_threshold.get(), 1e6);
    let err = error_of("[detector]\nthreshold = 1e308\n");
    assert!(err.contains("`detector.threshold` = 1e308 (with"), "{err}");
}
