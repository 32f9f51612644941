//! End-to-end on a bundled measured recording (exp25, MicroStrain 3DM-GX5-25): the injected
//! bias of the paper's protocol must be recovered, the convergence flag must rise, with the
//! recovery within ±5 % on every axis when it does, and the footprint error must drop.

use corridor_service::eval::EvalOptions;
use corridor_service::runner::{RunOutcome, heading_aid, run_log};
use corridor_service::suite::{convergence, recovery};
use corridor_shared::config::{BiasPrior, ConfigFile, ConfigOverrides, Mode};
use corridor_shared::imu_csv::{ImuCsvOptions, ImuLog, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::truth_csv::read_truth_csv;
use std::path::{Path, PathBuf};

const INJECTED: [f64; 3] = [0.001, 0.001, 0.005];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn run(log: &ImuLog, mode: Mode, inj: BiasInjection) -> RunOutcome {
    let path = root().join("configs/gdins.toml");
    let cfg = ConfigOverrides {
        mode: Some(mode),
        gyro_bias_prior: Some(BiasPrior::None),
        start_heading_deg: Some(0.0),
        grid_deg: None,
    }
    .validate(&ConfigFile::read(&path).unwrap(), &path)
    .unwrap();
    let aid = heading_aid(&cfg, None).unwrap();
    run_log(log, &cfg, &aid, &inj, |_, _| {})
}

#[test]
fn injected_bias_is_recovered_and_footprint_error_drops_on_exp25() {
    let dir = root().join("tests/data/gdins_exp25_multi_corridor");
    let log = read_imu_csv(&dir.join("imu.csv"), &ImuCsvOptions::default()).unwrap();
    let truth = read_truth_csv(&dir.join("ground_truth.csv")).unwrap();
    let inj = BiasInjection {
        constant_rad_s: INJECTED,
        ..Default::default()
    };
    let clean = run(&log, Mode::Eskf, BiasInjection::default());
    let with = run(&log, Mode::Eskf, inj);
    let rec = recovery(&with, &clean, INJECTED);
    for (axis, r) in ["x", "y", "z"].iter().zip(rec) {
        assert!(
            (r - 1.0).abs() < 0.10,
            "axis {axis}: recovered {:.1} % of the injected bias",
            100.0 * r
        );
    }

    // The convergence flag (the filter's own prediction of how much of a start bias error it
    // has absorbed) rises, and when it does the injection is recovered to ±5 % on every axis
    // (hindsight).
    let c = convergence(&with, &clean, INJECTED, 0.0, 0.0);
    let at = c
        .recovered_at_flag
        .expect("the convergence flag never rose");
    assert!(
        c.agrees(),
        "at the flag's rise ({:?} s) recovered {at:?} of the injection",
        c.flag_at_s
    );

    let uncorrected = run(&log, Mode::Zupt, inj);
    let opts = EvalOptions::default();
    let rms = |o: &RunOutcome| {
        o.trace
            .evaluate(&truth, &opts)
            .unwrap()
            .rms_error_m
            .unwrap()
    };
    let (before, after) = (rms(&uncorrected), rms(&with));
    assert!(
        after < 0.4 * before,
        "footprint RMS {after:.2} m vs uncorrected {before:.2} m"
    );
    assert!(
        after < 0.015 * 110.4,
        "footprint RMS {after:.2} m is above 1.5 % of the path"
    );
}

#[test]
fn paper_mode_runs_and_reports_a_bias_on_exp36() {
    // The paper's estimator on a straight out-and-back: it must use heading observations and
    // end with a finite bias whose z component has the injected sign.
    let dir = root().join("tests/data/gdins_exp36_corridor_out_and_back");
    let log = read_imu_csv(&dir.join("imu.csv"), &ImuCsvOptions::default()).unwrap();
    let inj = BiasInjection {
        constant_rad_s: INJECTED,
        ..Default::default()
    };
    let clean = run(&log, Mode::Paper, BiasInjection::default());
    let with = run(&log, Mode::Paper, inj);
    assert!(with.counters.heading_used > 10, "{:?}", with.counters);
    let rec = recovery(&with, &clean, INJECTED);
    assert!(rec[2] > 0.3, "paper z recovery {:.2}", rec[2]);
}
