//! Helpers shared by the `diagnose_*` tests: the bundled walks, the diagnosis's model of the
//! sensor and a diagnosis run that prints what it found. Each test binary uses part of it.
#![allow(dead_code)]

use corridor_service::diagnose::{Report, run_diagnosis};
use corridor_shared::config::{ConfigFile, ConfigOverrides, HeadingObservations};
use corridor_shared::imu_csv::{ImuCsvOptions, ImuLog, read_imu_csv};
use corridor_shared::injection::LogInjection;
use corridor_shared::truth_csv::{TruthPoint, read_truth_csv};
use std::path::{Path, PathBuf};

pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

pub fn load(name: &str) -> (ImuLog, Vec<TruthPoint>) {
    let dir = root().join("tests/data").join(name);
    (
        read_imu_csv(&dir.join("imu.csv"), &ImuCsvOptions::default()).unwrap(),
        read_truth_csv(&dir.join("ground_truth.csv")).unwrap(),
    )
}

/// The sensor configuration with the walk's start heading; `offset` adds the heading-offset
/// state (the model the loop ends with on exp25).
///
/// The diagnosis was built on, and is tested with, the foot-axis model it tests the residuals
/// of: the foot axis observed alone, with that model's filter noise (`[eskf]` of
/// `configs/gdins_zupt_baseline.toml`: accelerometer 0.5 m/s², bias random walk 1e-4).
/// With the default's stride directions fused as well, the filter absorbs these effects into
/// its heading and the foot-axis residuals lose their power (a 5 % z scale factor scores 1.1,
/// below significance); with the default's 0.03 m/s² the scale factors fitted for a 3 % clock
/// error disagree between axes (+2.8, +2.4, +3.9 %) and `timing` is no longer told from
/// `gyro_scale_factor`; with its bias random walk of 7e-4 the bias absorbs a mounting slip
/// and the heading-offset fix no longer lowers the footprint error (1.84 -> 2.10 m); and with
/// the default's association weight (`aligned_prior = 0.7`) a foot axis 6° off after a slip is
/// rejected as unlikely, so the heading-offset state cannot learn it (`aligned_prior = 1`
/// restores the plain gate). In the default model the stride directions, which need no mounting
/// yaw, carry the heading through such a slip. These are open points of the diagnosis issue.
pub fn config(start_heading_deg: f64, offset: bool) -> ConfigFile {
    let mut f = ConfigFile::read(&root().join("configs/gdins.toml")).unwrap();
    f.heading.observations = Some(HeadingObservations::FootAxis);
    f.heading.aligned_prior = Some(1.0);
    f.eskf = ConfigFile::read(&root().join("configs/gdins_zupt_baseline.toml"))
        .unwrap()
        .eskf;
    ConfigOverrides {
        start_heading_deg: Some(start_heading_deg),
        ..Default::default()
    }
    .apply(&mut f);
    f.model.heading_offset_sd_deg = offset.then_some(5.0);
    f
}

pub fn run(log: &ImuLog, truth: &[TruthPoint], cfg: &ConfigFile) -> Report {
    let report = run_diagnosis(log, cfg, Some(truth), None).unwrap().report;
    for e in &report.effects {
        eprintln!("    {} {:.1}: {}", e.name, e.score, e.evidence);
    }
    eprintln!(
        "top {} | {}",
        report.top_effect,
        report
            .effects
            .iter()
            .map(|e| format!("{} {:.1}", e.name, e.score))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for it in &report.iterations {
        eprintln!(
            "  + {}: rms {:?} -> {:?} kept {}",
            it.effect, it.before.gcp_rms_m, it.after.gcp_rms_m, it.kept
        );
    }
    report
}

/// The walk of `name` with its clock running `fraction` fast (its footprints' times on that
/// clock), diagnosed on the diagnosis's model with the rolling-foot stance update (strides right
/// without a clock error): with the footprints it must name `timing`, without them a gyro scale
/// factor, the clock's rotation part alone. Returns the report with the footprints.
pub fn clock_told_by_its_strides(name: &str, fraction: f64) -> Report {
    let (log, truth) = load(name);
    let mut cfg = config(0.0, false);
    cfg.eskf.zupt_rolling_height_m = Some(0.08);
    let clock = LogInjection::ClockRate { fraction };
    let t0 = log.rows[0].t_s;
    let mut injected = log.clone();
    clock.apply(&mut injected.rows);
    let truth: Vec<TruthPoint> = truth
        .iter()
        .map(|p| TruthPoint {
            t_s: clock.map_time(t0, p.t_s),
            ..*p
        })
        .collect();
    let with = run(&injected, &truth, &cfg);
    assert_eq!(with.top_effect, "timing", "{:#?}", with.effects);
    let without = run_diagnosis(&injected, &cfg, None, None).unwrap().report;
    assert_eq!(
        without.top_effect, "gyro_scale_factor",
        "{:#?}",
        without.effects
    );
    with
}
