//! The results suite on recordings unlike the bundled ones (a review's new-user pass): what it
//! says about them, in `results.md` and `results.json`, as `corridor run` would.

mod common;

use common::TempDir;
use corridor_service::suite::{markdown, run_suite};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A suite file in `dir` over one recording (`imu.csv` and `ground_truth.csv` in `dir`), run
/// with the shipped configurations.
fn suite_of(dir: &Path) -> PathBuf {
    let configs = root().join("configs");
    let suite = dir.join("suite.toml");
    std::fs::write(
        &suite,
        format!(
            "[[recording]]\nname = \"walk\"\nimu = \"imu.csv\"\ntruth = \"ground_truth.csv\"\n\
             config = {:?}\nbaseline_config = {:?}\nstart_heading_deg = 0.0\n",
            configs.join("gdins.toml"),
            configs.join("gdins_zupt_baseline.toml"),
        ),
    )
    .unwrap();
    suite
}

#[test]
fn footprints_after_the_end_of_the_log_are_said_not_silently_clamped() {
    let dir = TempDir::new("suite-truncated");
    let src = root().join("tests/data/gdins_exp17_rect_loop_small");
    // The log ends at 25 s; its last footprint (index 4) was surveyed at 33 s.
    let imu = std::fs::read_to_string(src.join("imu.csv")).unwrap();
    let kept: Vec<&str> = imu
        .lines()
        .take_while(|l| {
            l.split(',').next().unwrap().parse::<f64>().is_err() || {
                l.split(',').next().unwrap().parse::<f64>().unwrap() < 25.0
            }
        })
        .collect();
    std::fs::write(dir.join("imu.csv"), kept.join("\n") + "\n").unwrap();
    std::fs::copy(src.join("ground_truth.csv"), dir.join("ground_truth.csv")).unwrap();
    let rows = run_suite(&suite_of(&dir)).unwrap_or_else(|e| panic!("{e}"));
    let w = &rows[0].eval_warnings;
    assert!(
        w.len() == 1 && w[0].contains("clamped") && w[0].contains("[4]"),
        "{w:?}"
    );
    let md = markdown(&rows);
    assert!(
        md.contains("What the footprint evaluation had to do") && md.contains("walk: GCP time(s)"),
        "{md}"
    );
    let json = serde_json::to_value(&rows).unwrap();
    assert_eq!(json[0]["eval_warnings"][0], w[0].as_str());
}

/// The CSV `src` written to `dst` with every time stamp (its first column) moved by `shift_s`.
fn shifted_csv(src: &Path, dst: &Path, shift_s: f64) {
    let text = std::fs::read_to_string(src).unwrap();
    let mut lines = text.lines();
    let mut out = vec![lines.next().unwrap().to_string()];
    out.extend(lines.map(|l| {
        let (t, rest) = l.split_once(',').unwrap();
        format!("{},{rest}", t.parse::<f64>().unwrap() + shift_s)
    }));
    std::fs::write(dst, out.join("\n") + "\n").unwrap();
}

/// exp17's log and footprints with every time stamp moved by `shift_s`, in `dir`.
fn shifted_exp17(dir: &Path, shift_s: f64) {
    let src = root().join("tests/data/gdins_exp17_rect_loop_small");
    for name in ["imu.csv", "ground_truth.csv"] {
        shifted_csv(&src.join(name), &dir.join(name), shift_s);
    }
}

#[test]
fn the_injections_and_their_times_count_from_the_logs_first_sample() {
    let original = TempDir::new("suite-shift-0");
    shifted_exp17(&original, 0.0);
    let reference = &run_suite(&suite_of(&original)).unwrap()[0];
    // A log stamped in epoch seconds, and one that starts at −30 s: the protocols inject
    // where they injected (from the first sample; from the end of the initial rest) and say
    // their times from the log's start. They inject after 30 s of this one, and into none of
    // that one, if the times are the clock's.
    for (tag, shift_s) in [("epoch", 1.7e9), ("negative", -30.0)] {
        let dir = TempDir::new(&format!("suite-shift-{tag}"));
        shifted_exp17(&dir, shift_s);
        let row = &run_suite(&suite_of(&dir)).unwrap()[0];
        let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 0.03);
        assert!(
            close(row.best_recovery, reference.best_recovery)
                && close(row.paper_recovery, reference.paper_recovery)
                && close(
                    row.best_recovery_prior_late,
                    reference.best_recovery_prior_late
                ),
            "{tag}: {:?} {:?} {:?} against {:?} {:?} {:?}",
            row.best_recovery,
            row.paper_recovery,
            row.best_recovery_prior_late,
            reference.best_recovery,
            reference.paper_recovery,
            reference.best_recovery_prior_late
        );
        let (c, r) = (&row.best_convergence, &reference.best_convergence);
        let near = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(a), Some(b)) => (a - b).abs() < 0.5,
            (a, b) => a.is_none() && b.is_none(),
        };
        assert!(
            (c.walking_from_s - r.walking_from_s).abs() < 0.1
                && near(c.flag_at_s, r.flag_at_s)
                && near(c.settled_at_s, r.settled_at_s),
            "{tag}: {c:?} against {r:?}"
        );
    }
}

/// A suite file in `dir` over exp17 as "bad walk" (its footprints on another clock: its
/// evaluation fails) and then `good` times as it is ("good walk", "good walk 2", ...).
fn suite_with_a_bad_walk(dir: &Path, good: usize) -> PathBuf {
    let mut names = vec![("bad walk".to_string(), "bad".to_string())];
    names.extend((1..=good).map(|k| match k {
        1 => ("good walk".to_string(), "good".to_string()),
        _ => (format!("good walk {k}"), format!("good{k}")),
    }));
    let mut text = String::new();
    for (name, sub) in &names {
        let sub_dir = dir.join(sub);
        std::fs::create_dir_all(&sub_dir).unwrap();
        shifted_exp17(&sub_dir, 0.0);
        if sub == "bad" {
            let truth = sub_dir.join("ground_truth.csv");
            let tmp = sub_dir.join("truth_on_time.csv");
            std::fs::rename(&truth, &tmp).unwrap();
            shifted_csv(&tmp, &truth, 1.7e9);
        }
        let one = std::fs::read_to_string(suite_of(&sub_dir)).unwrap();
        text += &one
            .replace("\"walk\"", &format!("{name:?}"))
            .replace("\"imu.csv\"", &format!("\"{sub}/imu.csv\""))
            .replace(
                "\"ground_truth.csv\"",
                &format!("\"{sub}/ground_truth.csv\""),
            );
        text += "\n";
    }
    let suite = dir.join("suite_with_a_bad_walk.toml");
    std::fs::write(&suite, text).unwrap();
    suite
}

/// `failed` names exactly the bad walk.
fn names_the_bad_walk(failed: &[corridor_service::suite::SuiteError]) {
    assert_eq!(failed.len(), 1, "{failed:?}");
    assert!(
        failed[0].to_string().contains("recording bad walk"),
        "{}",
        failed[0]
    );
}

#[test]
fn a_recording_that_fails_does_not_cost_the_others_their_rows() {
    let dir = TempDir::new("suite-one-bad");
    let suite = suite_with_a_bad_walk(&dir, 1);
    let run = corridor_service::suite::run_suite_each(&suite).unwrap();
    assert_eq!(run.rows.len(), 1);
    assert_eq!(run.rows[0].recording, "good walk");
    names_the_bad_walk(&run.failed);
    // The strict form fails on it.
    let e = run_suite(&suite).unwrap_err().to_string();
    assert!(e.contains("recording bad walk"), "{e}");
}

#[test]
fn the_loop_the_ensemble_and_the_sweep_run_past_a_recording_that_fails() {
    // Each stopped at the first recording that failed, with no table for the others.
    use corridor_service::suite::{run_ensemble, run_loops, run_sweep};
    let dir = TempDir::new("suite-one-bad-each");
    let suite = suite_with_a_bad_walk(&dir, 2);
    let goods = ["good walk", "good walk 2"];
    let ensemble = run_ensemble(&suite).unwrap();
    names_the_bad_walk(&ensemble.failed);
    let names: Vec<&str> = ensemble.rows.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, goods);
    assert!(
        ensemble
            .rows
            .iter()
            .all(|r| r.rms_pct.iter().all(|v| v.is_finite()))
    );

    // An earlier report of the walk that fails now would read as this run's.
    std::fs::create_dir_all(dir.join("loops/bad_walk")).unwrap();
    std::fs::write(dir.join("loops/bad_walk/report.md"), "an earlier run's").unwrap();
    let loops = run_loops(&suite, &dir.join("loops")).unwrap();
    names_the_bad_walk(&loops.failed);
    assert!(!dir.join("loops/bad_walk").exists());
    assert_eq!(loops.rows.len(), 2);
    assert!(
        loops.rows[0].starts_with("| good walk |"),
        "{}",
        loops.rows[0]
    );
    assert!(dir.join("loops/good_walk_2/report.md").is_file());

    let sweep_file = dir.join("sweep.toml");
    std::fs::write(
        &sweep_file,
        "[[parameter]]\nkey = \"heading.sigma_deg\"\nvalues = [3.0, 4.0]\n",
    )
    .unwrap();
    let sweep = run_sweep(&suite, &sweep_file).unwrap();
    names_the_bad_walk(&sweep.failed);
    assert_eq!(sweep.rows[0].walks, goods);
    assert!(sweep.rows[0].rms_pct.iter().all(|at| at.len() == 2));
    // With one walk left there is no fold to hold out: an error naming the rule and the failure.
    let one_dir = TempDir::new("suite-one-bad-sweep");
    let one_good = suite_with_a_bad_walk(&one_dir, 1);
    let e = run_sweep(&one_good, &sweep_file).unwrap_err().to_string();
    assert!(
        e.starts_with(&one_good.display().to_string())
            && e.contains("at least 2 normal-gait walks that run; 1 of 2 did")
            && e.contains("recording bad walk:"),
        "{e}"
    );
    // A value the configuration refuses is said before any run, whatever the recordings do
    // (it was found inside a recording's run, so never when they failed).
    std::fs::write(
        &sweep_file,
        "[[parameter]]\nkey = \"heading.sigma_deg\"\nvalues = [3.0, -3.0]\n",
    )
    .unwrap();
    let e = run_sweep(&one_good, &sweep_file).unwrap_err().to_string();
    assert!(
        e.starts_with(&sweep_file.display().to_string())
            && e.contains("parameter heading.sigma_deg = -3.0"),
        "{e}"
    );
    // A recording whose configuration is invalid as it stands fails its own run and is named;
    // the values are not checked against it (they were, first in the file, and the whole sweep
    // stopped on it as the sweep file's error).
    std::fs::write(
        &sweep_file,
        "[[parameter]]\nkey = \"heading.sigma_deg\"\nvalues = [3.0, 4.0]\n",
    )
    .unwrap();
    let text = std::fs::read_to_string(root().join("configs/gdins.toml")).unwrap();
    std::fs::write(
        dir.join("bad_config.toml"),
        text.replace("\nthreshold = 1e5\n", "\nthreshold = -1.0\n"),
    )
    .unwrap();
    let gdins = format!("{:?}", root().join("configs").join("gdins.toml"));
    let good = std::fs::read_to_string(&suite).unwrap();
    let bad_config = good[..good.find("\n\n").unwrap() + 2]
        .replace("\"bad walk\"", "\"bad config\"")
        .replace("\"bad/", "\"good/")
        .replace(&format!("config = {gdins}"), "config = \"bad_config.toml\"");
    let first_bad = dir.join("first_bad_config.toml");
    std::fs::write(&first_bad, bad_config + &good).unwrap();
    let sweep = run_sweep(&first_bad, &sweep_file).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(sweep.rows[0].walks, goods);
    let failed: Vec<_> = sweep.failed.iter().filter_map(|e| e.recording()).collect();
    assert_eq!(failed, ["bad config", "bad walk"]);
    // Invalid as the runs judge it (the file as it is), though valid with the suite's
    // overrides (its grid): it refused the swept value and stopped the sweep (a review).
    std::fs::write(
        &sweep_file,
        "[[parameter]]\nkey = \"alignment.typical_gyro_bias_sd_rad_s\"\nvalues = [0.002, 0.004]\n",
    )
    .unwrap();
    let no_typical: String = text
        .lines()
        .filter(|l| !l.starts_with("typical_gyro_bias"))
        .map(|l| match l {
            "grid_deg = 0.0" => "grid_deg = 999.0\n".to_owned(),
            l => format!("{l}\n"),
        })
        .collect();
    std::fs::write(dir.join("bad_config.toml"), no_typical).unwrap();
    let sweep = run_sweep(&first_bad, &sweep_file).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(sweep.rows[0].walks, goods);
    let failed: Vec<_> = sweep.failed.iter().filter_map(|e| e.recording()).collect();
    assert_eq!(failed, ["bad config", "bad walk"]);
}

#[test]
fn the_detection_matrix_names_each_recording_that_fails() {
    // Two bad walks (a good one would run the whole matrix, minutes in a debug build): the
    // matrix goes on past the first, names both, and holds no cell of either.
    let dir = TempDir::new("suite-bad-matrix");
    let one = suite_with_a_bad_walk(&dir, 0);
    let text = std::fs::read_to_string(&one).unwrap();
    let suite = dir.join("two_bad.toml");
    std::fs::write(
        &suite,
        text.clone() + &text.replace("\"bad walk\"", "\"bad walk 2\""),
    )
    .unwrap();
    let m = corridor_service::suite::detection_matrix(&suite, |_| {}, |_| {}).unwrap();
    assert!(m.recordings.is_empty() && m.cells.is_empty() && m.mde_scan.is_empty());
    assert_eq!(m.failed.len(), 2, "{:?}", m.failed);
    let names: Vec<&str> = m.failed.iter().map(|f| f.recording.as_str()).collect();
    assert_eq!(names, ["bad walk", "bad walk 2"]);
    assert!(
        m.failed[1].error.starts_with("recording bad walk 2:"),
        "{:?}",
        m.failed
    );
    let md = corridor_service::suite::matrix_markdown(&m);
    assert!(
        md.contains("Not in the matrix (its run failed): recording bad walk:"),
        "{md}"
    );
}

#[test]
fn a_loop_closure_truth_is_not_scored_as_nan() {
    // The x-io walk's truth is its start and end at one place: nothing for the footprint RMS.
    // The suite gave it "NaN %" in its tables and exited 0 (a second-sensor review).
    let dir = TempDir::new("suite-loop-closure");
    let src = root().join("tests/data/xio_ngimu_long_walk");
    for name in ["imu.csv", "ground_truth.csv"] {
        std::fs::copy(src.join(name), dir.join(name)).unwrap();
    }
    let suite = dir.join("suite.toml");
    std::fs::write(
        &suite,
        std::fs::read_to_string(suite_of(&dir))
            .unwrap()
            .replace("gdins.toml", "ngimu.toml")
            .replace("gdins_zupt_baseline.toml", "ngimu.toml"),
    )
    .unwrap();
    let run = corridor_service::suite::run_suite_each(&suite).unwrap();
    assert!(run.rows.is_empty());
    let e = run.failed[0].to_string();
    assert!(
        e.contains("recording walk")
            && e.contains("no footprint error to score")
            && e.contains("loop-closure-only"),
        "{e}"
    );
}

#[test]
fn a_configuration_that_does_not_validate_is_named_with_its_file() {
    // It printed an empty path: "recording walk: : key `detector.threshold` ...".
    let dir = TempDir::new("suite-bad-config");
    shifted_exp17(&dir, 0.0);
    let config = dir.join("bad.toml");
    let text = std::fs::read_to_string(root().join("configs/gdins.toml")).unwrap();
    assert!(text.contains("\nthreshold = 1e5\n"));
    std::fs::write(
        &config,
        text.replace("\nthreshold = 1e5\n", "\nthreshold = -1.0\n"),
    )
    .unwrap();
    let suite = dir.join("suite.toml");
    std::fs::write(
        &suite,
        std::fs::read_to_string(suite_of(&dir)).unwrap().replace(
            &format!("{:?}", root().join("configs").join("gdins.toml")),
            "\"bad.toml\"",
        ),
    )
    .unwrap();
    let run = corridor_service::suite::run_suite_each(&suite).unwrap();
    let e = run.failed[0].to_string();
    assert!(
        e.contains("recording walk")
            && e.contains(&format!("{}: key `detector.threshold`", config.display())),
        "{e}"
    );
}

/// `corridor ARGS --suite SUITE --out OUT`.
fn corridor_on(args: &[&str], suite: &Path, out: &Path) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_corridor"))
        .args(args)
        .arg("--suite")
        .arg(suite)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn corridor_eval_writes_the_others_table_then_fails_naming_the_recording_once() {
    let dir = TempDir::new("suite-one-bad-cli");
    let suite = suite_with_a_bad_walk(&dir, 1);
    let out = dir.join("out");
    let o = corridor_on(&["eval", "--ensemble"], &suite, &out);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert_eq!(o.status.code(), Some(1), "{stdout}\n{stderr}");
    let table = std::fs::read_to_string(out.join("ensemble.md")).unwrap();
    assert!(
        table.contains("| good walk | normal |")
            && table.contains("Not in the ensemble (its run failed): recording bad walk:"),
        "{table}"
    );
    assert!(stdout.contains("| good walk | normal |"), "{stdout}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(
        errors[0]
            == "error: 1 recording failed, named with its error under the tables (the others' \
                table was written): bad walk",
        "{stderr}"
    );
}

#[test]
fn corridor_eval_writes_nothing_when_no_recording_runs() {
    // An empty table replaced the last good one in --out.
    let dir = TempDir::new("suite-all-bad-cli");
    let suite = suite_with_a_bad_walk(&dir, 0);
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    for (flag, file) in [("--ensemble", "ensemble.md"), ("--loops", "results.md")] {
        std::fs::write(out.join(file), "the last good table").unwrap();
        let o = corridor_on(&["eval", flag], &suite, &out);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{flag}: {stderr}");
        assert!(
            stderr.contains("error: no recording ran, nothing written: recording bad walk:"),
            "{flag}: {stderr}"
        );
        assert_eq!(
            std::fs::read_to_string(out.join(file)).unwrap(),
            "the last good table"
        );
    }
    std::fs::write(out.join("detection.md"), "the last good matrix").unwrap();
    let o = corridor_on(&["diagnose"], &suite, &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr
            .contains("error: no normal-gait recording ran, nothing written: recording bad walk:"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("detection.md")).unwrap(),
        "the last good matrix"
    );
    assert!(!out.join("detection.json").exists());
    // No normal-gait recording at all: nothing to put in a matrix either.
    let fast = dir.join("bad").join("fast.toml");
    std::fs::write(
        &fast,
        std::fs::read_to_string(suite_of(&dir.join("bad"))).unwrap() + "gait = \"fast\"\n",
    )
    .unwrap();
    let o = corridor_on(&["diagnose"], &fast, &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("no normal-gait recording"), "{stderr}");
    assert_eq!(
        std::fs::read_to_string(out.join("detection.md")).unwrap(),
        "the last good matrix"
    );
}
