//! A heading turned by a rotation the gyro did not measure (a stumble, a slip of the sensor on
//! the shoe, samples lost in a turn) by more than the association's gate: every stride then
//! looks like walking off the corridor, and before `heading.reacquire_strides` the heading was
//! never found again. Here a rotation about the vertical is added to exp28's samples in the
//! stance at 60 s, where the walker stands in a long corridor.

use corridor_service::eval::EvalOptions;
use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::config::{Config, ConfigFile, ConfigOverrides};
use corridor_shared::imu_csv::{ImuCsvOptions, ImuLog, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::truth_csv::{TruthPoint, read_truth_csv};
use nalgebra::Vector3;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn exp28() -> (ImuLog, Vec<TruthPoint>) {
    let dir = root().join("tests/data/gdins_exp28_detour_and_long_corridor");
    (
        read_imu_csv(&dir.join("imu.csv"), &ImuCsvOptions::default()).unwrap(),
        read_truth_csv(&dir.join("ground_truth.csv")).unwrap(),
    )
}

/// The shipped configuration with exp28's start heading (the suite's); `reacquire` off drops
/// the key.
fn config(reacquire: bool) -> Config {
    let path = root().join("configs/gdins.toml");
    let mut file = ConfigFile::read(&path).unwrap();
    if !reacquire {
        file.heading.reacquire_strides = None;
    }
    ConfigOverrides {
        start_heading_deg: Some(90.0),
        ..Default::default()
    }
    .validate(&file, &path)
    .unwrap()
}

/// `log` with `angle_deg` of rotation about the initial rest's vertical added over 0.1 s,
/// centred on the quietest sample between 60 and 61 s (a stance: the foot is flat, so that
/// axis is the vertical).
fn turned(log: &ImuLog, angle_deg: f64) -> ImuLog {
    let rest = log.rows.iter().take(150);
    let up = rest
        .map(|r| Vector3::from(r.accel_m_s2))
        .sum::<Vector3<f64>>()
        .normalize();
    let (k, _) = log
        .rows
        .iter()
        .enumerate()
        .filter(|(_, r)| (60.0..61.0).contains(&r.t_s))
        .min_by(|(_, a), (_, b)| {
            let n = |r: &corridor_shared::imu_csv::ImuRow| Vector3::from(r.gyro_rad_s).norm();
            n(a).total_cmp(&n(b))
        })
        .unwrap();
    let n = 20;
    let rate = angle_deg.to_radians() / (n as f64 * 0.005);
    let mut out = log.clone();
    for r in &mut out.rows[k - n / 2..k + n / 2] {
        let g = Vector3::from(r.gyro_rad_s) + up * rate;
        r.gyro_rad_s = g.into();
    }
    out
}

/// Footprint RMS, % of path, and how often the heading was taken as lost.
fn run(log: &ImuLog, truth: &[TruthPoint], cfg: &Config) -> (f64, u64) {
    let out = run_log(
        log,
        cfg,
        &heading_aid(cfg, None).unwrap(),
        &BiasInjection::default(),
        |_, _| {},
    );
    let rms = out
        .trace
        .evaluate(truth, &EvalOptions::default())
        .unwrap()
        .rms_error_pct_of_path
        .unwrap();
    (rms, out.counters.heading_reacquisitions)
}

#[test]
fn a_heading_turned_beyond_the_gate_is_found_again() {
    let (log, truth) = exp28();
    let (clean, n) = run(&log, &truth, &config(true));
    assert_eq!(n, 0, "the clean walk never looks lost");
    assert!(clean < 0.2, "{clean:.2} %");
    let bad = turned(&log, 20.0);
    let (lost, n) = run(&bad, &truth, &config(false));
    assert_eq!(n, 0);
    assert!(
        lost > 5.0,
        "without the key the heading stays lost: {lost:.2} %"
    );
    let (found, n) = run(&bad, &truth, &config(true));
    assert_eq!(n, 1, "taken as lost once");
    assert!(found < 2.5, "{found:.2} % (lost: {lost:.2} %)");
}
