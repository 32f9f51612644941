//! The shipped configuration files agree with each other: `configs/service.toml` layers a
//! `[daemon]` section over the sensor's `configs/gdins.toml` (`base`), so the daemon runs the same
//! estimator as `corridor run` and the results suite; and a layered file's own keys win.

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

#[test]
fn a_layered_file_takes_its_base_and_replaces_only_the_keys_it_sets() {
    let dir = std::env::temp_dir().join(format!("corridor-layer-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("sensor.toml"),
        "[eskf]\nzupt_sd_m_s = 0.02\naccel_noise_m_s2 = 0.1\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("daemon.toml"),
        "base = \"sensor.toml\"\n[eskf]\naccel_noise_m_s2 = 0.3\n[daemon]\ndomain = \"x\"\n",
    )
    .unwrap();
    let c = ConfigFile::read(&dir.join("daemon.toml")).unwrap();
    assert_eq!(c.eskf.zupt_sd_m_s, Some(0.02), "from the base");
    assert_eq!(c.eskf.accel_noise_m_s2, Some(0.3), "replaced by the layer");
    assert_eq!(c.daemon.domain.as_deref(), Some("x"));
    // A base with a base, and a base with a bad key, are errors naming the place.
    std::fs::write(dir.join("sensor.toml"), "base = \"other.toml\"\n").unwrap();
    let e = ConfigFile::read(&dir.join("daemon.toml"))
        .unwrap_err()
        .to_string();
    // Said from the file that names the base, with the base's own `base` (it showed the
    // layer's value under the base's name).
    assert!(
        e.starts_with(&format!(
            "{}: base = \"sensor.toml\"",
            dir.join("daemon.toml").display()
        )) && e.contains("names a base itself (base = \"other.toml\")"),
        "{e}"
    );
    std::fs::write(dir.join("sensor.toml"), "[eskf]\nzupt_sd = 1.0\n").unwrap();
    let e = ConfigFile::read(&dir.join("daemon.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("sensor.toml") && e.contains("zupt_sd"), "{e}");
    // A value out of range in the base names the base, not the layer.
    std::fs::write(dir.join("sensor.toml"), "[eskf]\nzupt_sd_m_s = -1.0\n").unwrap();
    let e = ConfigFile::read(&dir.join("daemon.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("sensor.toml") && e.contains("eskf.zupt_sd_m_s"),
        "{e}"
    );
    // A wrong type in the layer is named with its line, as in a file without a base (it lost
    // its line, a review of session 38).
    std::fs::write(dir.join("sensor.toml"), "[eskf]\nzupt_sd_m_s = 0.02\n").unwrap();
    std::fs::write(
        dir.join("daemon.toml"),
        "base = \"sensor.toml\"\n\n[eskf]\naccel_noise_m_s2 = \"abc\"\n",
    )
    .unwrap();
    let e = ConfigFile::read(&dir.join("daemon.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("daemon.toml") && e.contains("line 4") && e.contains("invalid type"),
        "{e}"
    );
    // A base that cannot be read is named from the file that asks for it.
    std::fs::remove_file(dir.join("sensor.toml")).unwrap();
    let e = ConfigFile::read(&dir.join("daemon.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(&dir.join("daemon.toml").display().to_string())
            && e.contains("base = \"sensor.toml\": cannot read"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// The results suite's `suspect_legs` are the truth legs each recording's `meta.json` flags
/// (its `legs_ratio_outside_0.85_1.15`), whether written in the suite file (checked here against
/// the `meta.json` itself) or left out (read from it), and a recording without a `meta.json`
/// flags none.
#[test]
fn the_suites_suspect_legs_are_the_data_sets_own() {
    use corridor_service::suite::FLAGGED_LEGS_KEY;
    let path = configs().join("eval/gdins.toml");
    let suite = corridor_service::suite::read_suite(&path).unwrap();
    let raw: toml::Value = toml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let raw = raw["recording"].as_array().unwrap();
    assert_eq!(raw.len(), suite.recordings.len());
    let (mut flagged, mut written) = (0, 0);
    for (r, entry) in suite.recordings.iter().zip(raw) {
        let meta = path
            .parent()
            .unwrap()
            .join(&r.truth)
            .with_file_name("meta.json");
        let expected: Vec<usize> = match std::fs::read_to_string(&meta) {
            Ok(text) => {
                let m: serde_json::Value = serde_json::from_str(&text).unwrap();
                let legs = &m["truth"]["imu_consistency"]["crude_ins_fit"][FLAGGED_LEGS_KEY];
                serde_json::from_value(legs.clone())
                    .unwrap_or_else(|e| panic!("{}: {e}", meta.display()))
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
            Err(e) => panic!("{}: {e}", meta.display()),
        };
        if let Some(legs) = entry.get("suspect_legs") {
            let legs: Vec<usize> = legs.clone().try_into().unwrap();
            assert_eq!(legs, expected, "{}: the suite file's suspect_legs", r.name);
            written += 1;
        }
        assert_eq!(r.suspect_legs, expected, "{}", r.name);
        flagged += usize::from(!expected.is_empty());
    }
    assert!(flagged > 0, "no recording of the suite has a flagged leg");
    assert!(written > 0, "no recording writes its suspect_legs");
}

/// Every start heading the results suite gives is the rule a suite file without one gets:
/// the first surveyed stride's direction on the building grid (so a recording added without
/// it is scored the way these were).
#[test]
fn the_suites_start_headings_are_the_first_stride_on_the_grid() {
    use corridor_service::suite::{StartHeading, read_suite, start_heading_from_truth};
    use corridor_shared::truth_csv::read_truth_csv;
    let path = configs().join("eval/gdins.toml");
    let suite = read_suite(&path).unwrap();
    assert_eq!(suite.recordings.len(), 16);
    for r in &suite.recordings {
        assert_eq!(r.start_heading, StartHeading::Given, "{}", r.name);
        let truth = read_truth_csv(&path.parent().unwrap().join(&r.truth)).unwrap();
        assert_eq!(
            start_heading_from_truth(&truth, r.grid_deg),
            Some(r.start_heading_deg),
            "{}",
            r.name
        );
    }
}
