//! An accelerometer whose scale is wrong (a driver's range setting, a wrong LSB): the filter
//! takes its gravity from the initial rest, so everything looks consistent inside it and every
//! distance comes out scaled. The quiet stances' specific force is held against gravity
//! (`core/estimator/stance_force.rs`) and the estimator says so, once.

use corridor_service::core::{Estimator, ImuInput, Notice, SPECIFIC_FORCE_TOLERANCE};
use corridor_service::runner::heading_aid;
use corridor_shared::config::Config;
use corridor_shared::imu_csv::{ImuCsvOptions, ImuLog, read_imu_csv};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn walk(name: &str) -> ImuLog {
    read_imu_csv(
        &root().join("tests/data").join(name).join("imu.csv"),
        &ImuCsvOptions::default(),
    )
    .unwrap()
}

/// What the estimator said of the specific force over `log` with the accelerometer scaled by
/// `scale`: the notices (time, text), the count, and the median at the end.
fn run(log: &ImuLog, scale: f64) -> (Vec<(f64, String)>, u64, Option<f64>) {
    let cfg = Config::from_file(&root().join("configs/gdins.toml")).unwrap();
    let mut est = Estimator::new(cfg.clone(), heading_aid(&cfg, None).unwrap());
    let mut said = Vec::new();
    for r in &log.rows {
        let e = est
            .step(&ImuInput {
                t_s: r.t_s,
                gyro_rad_s: r.gyro_rad_s,
                accel_m_s2: r.accel_m_s2.map(|a| a * scale),
            })
            .unwrap();
        said.extend(
            e.notices()
                .filter(|n| matches!(n, Notice::SpecificForceOffGravity(..)))
                .map(|n| (r.t_s, n.to_string())),
        );
    }
    let c = est.counters().specific_force_off_gravity;
    (said, c, est.stance_specific_force_m_s2())
}

#[test]
fn a_scaled_accelerometer_is_said_once_within_the_first_stances() {
    let log = walk("gdins_exp36_corridor_out_and_back");
    for (scale, wrong) in [(0.8, "-20 %"), (1.2, "+20 %"), (0.93, "-7 %")] {
        let (said, count, median) = run(&log, scale);
        assert_eq!(said.len(), 1, "{scale}: {said:?}");
        assert_eq!(count, 1, "{scale}");
        let (t_s, text) = &said[0];
        // Fifteen stances into the walk (it starts at about 2 s), not at its end (70 s).
        assert!(*t_s < 25.0, "{scale}: said at {t_s} s");
        assert!(
            text.contains("last 15 quiet stances") && text.contains(wrong),
            "{scale}: {text}"
        );
        let median = median.unwrap();
        assert!(
            (median / 9.80665 / scale - 1.0).abs() < 0.01,
            "{scale}: {median}"
        );
    }
}

#[test]
fn the_bundled_walks_as_recorded_are_not_taken_for_a_scale_error() {
    // The normal exp36, and the fast exp38, whose whole stances (push-off and landing) read up
    // to 12.8 m/s²: its quiet stances read gravity.
    for name in [
        "gdins_exp36_corridor_out_and_back",
        "gdins_exp38_zigzag_extreme",
    ] {
        let (said, count, median) = run(&walk(name), 1.0);
        assert!(said.is_empty() && count == 0, "{name}: {said:?}");
        let median = median.unwrap();
        assert!(
            (median / 9.80665 - 1.0).abs() < 0.2 * SPECIFIC_FORCE_TOLERANCE,
            "{name}: {median}"
        );
    }
}
