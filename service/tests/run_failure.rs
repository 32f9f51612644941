//! A failed `corridor run` leaves no partial output (issue 10, finding 6); a run or a diagnosis
//! that cannot be right is refused before any output (session 40).
//!
//! Before the runner streamed, `estimates.csv` and `innovations.csv` were written to their final
//! names while the run went on, and a run that failed after them (the log never aligned, the
//! truth could not be evaluated) left them behind as if they were results. Now every output is
//! written as `NAME.partial` and renamed only when the run succeeded.

mod common;

use common::TempDir;
use corridor_service::runner::{RunError, RunOptions, run};
use corridor_shared::config::Config;
use corridor_shared::imu_csv::{ImuCsvError, ImuCsvOptions};
use corridor_shared::injection::BiasInjection;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn exp36() -> PathBuf {
    root().join("tests/data/gdins_exp36_corridor_out_and_back")
}

fn options(imu: &Path, truth: Option<PathBuf>, out: &Path) -> RunOptions {
    RunOptions {
        imu: imu.to_owned(),
        config: Config::from_file(&root().join("configs/gdins.toml")).unwrap(),
        map: None,
        truth,
        injection: BiasInjection::default(),
        plots: true,
        out_dir: out.to_owned(),
        csv: ImuCsvOptions::default(),
        warm_start: None,
    }
}

/// `corridor diagnose --imu IMU [--truth TRUTH] --config configs/gdins.toml --out OUT`.
fn diagnose(imu: &Path, truth: Option<&Path>, out: &Path) -> std::process::Output {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_corridor"));
    c.args(["diagnose", "--imu"]).arg(imu);
    if let Some(t) = truth {
        c.arg("--truth").arg(t);
    }
    c.arg("--config")
        .arg(root().join("configs/gdins.toml"))
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

/// The names in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// exp36's rows from line `from` on (no initial rest), with its header.
fn without_rest(dir: &Path, from: usize) -> PathBuf {
    let text = std::fs::read_to_string(exp36().join("imu.csv")).unwrap();
    let mut lines = text.lines();
    let mut out = String::from(lines.next().unwrap());
    out.push('\n');
    for l in lines.skip(from) {
        out.push_str(l);
        out.push('\n');
    }
    let path = dir.join("no_rest.csv");
    std::fs::write(&path, out).unwrap();
    path
}

#[test]
fn a_run_that_fails_after_writing_leaves_no_output() {
    let dir = TempDir::new(&format!("run-failure-{}", std::process::id()));
    let out = dir.join("out");
    // A log that starts walking, with the start from a short stance switched off: it never
    // aligns, found only after every row was estimated.
    let imu = without_rest(&dir, 1500);
    let mut opts = options(&imu, None, &out);
    opts.config.alignment.min_start_stance_s = corridor_shared::config::NonNegative::ZERO;
    let err = run(&opts).unwrap_err();
    assert!(matches!(err, RunError::NeverAligned { .. }), "{err}");
    assert_eq!(listing(&out), Vec::<String>::new());

    // Every sample refused (an injection beyond the plausible rate): an error naming the first
    // refusal, not an exit 0 with an empty summary.
    let mut opts = options(&exp36().join("imu.csv"), None, &out);
    opts.injection.constant_rad_s = [100.0, 0.0, 0.0];
    let err = run(&opts).unwrap_err();
    match &err {
        RunError::NothingAccepted { samples, first, .. } => {
            // The log named once: the first refusal by its line.
            assert!(*samples > 10_000 && first.starts_with("line 2: "), "{err}");
            assert_eq!(err.to_string().matches("imu.csv").count(), 1, "{err}");
        }
        _ => panic!("{err}"),
    }
    assert_eq!(listing(&out), Vec::<String>::new());

    // Truth that cannot be evaluated (one footprint): found after the outputs were written.
    let truth = dir.join("one_footprint.csv");
    let gt = std::fs::read_to_string(exp36().join("ground_truth.csv")).unwrap();
    std::fs::write(&truth, gt.lines().take(2).collect::<Vec<_>>().join("\n")).unwrap();
    let err = run(&options(&exp36().join("imu.csv"), Some(truth), &out)).unwrap_err();
    assert!(matches!(err, RunError::Eval { .. }), "{err}");
    assert_eq!(listing(&out), Vec::<String>::new());

    // Too many bad rows at the end of a log: the reader says so at its end.
    let bad = dir.join("bad_tail.csv");
    let mut text = std::fs::read_to_string(exp36().join("imu.csv")).unwrap();
    for _ in 0..200 {
        text.push_str("garbage\n");
    }
    std::fs::write(&bad, text).unwrap();
    let err = run(&options(&bad, None, &out)).unwrap_err();
    assert!(
        matches!(err, RunError::Imu(ImuCsvError::TooManyRejected { .. })),
        "{err}"
    );
    assert_eq!(listing(&out), Vec::<String>::new());
}

#[test]
fn a_failed_run_leaves_the_previous_outputs_as_they_were() {
    let dir = TempDir::new(&format!("run-failure-prev-{}", std::process::id()));
    let out = dir.join("out");
    let truth = exp36().join("ground_truth.csv");
    run(&options(
        &exp36().join("imu.csv"),
        Some(truth.clone()),
        &out,
    ))
    .unwrap();
    let names = listing(&out);
    assert_eq!(
        names,
        [
            "bias.svg",
            "covariance.svg",
            "estimates.csv",
            "innovations.csv",
            "summary.json",
            "trajectory.svg"
        ]
    );
    let summary = std::fs::read(out.join("summary.json")).unwrap();
    let estimates_len = std::fs::metadata(out.join("estimates.csv")).unwrap().len();
    let imu = without_rest(&dir, 1500);
    assert!(run(&options(&imu, Some(truth), &out)).is_err());
    assert_eq!(listing(&out), names);
    assert_eq!(std::fs::read(out.join("summary.json")).unwrap(), summary);
    assert_eq!(
        std::fs::metadata(out.join("estimates.csv")).unwrap().len(),
        estimates_len
    );
}

#[test]
fn an_output_that_is_an_input_is_refused_and_the_input_kept() {
    // `--imu same/estimates.csv --out same` replaced the log with its own estimates, exit 0.
    let out = TempDir::new("eco-output-is-input");
    let imu = out.join("estimates.csv");
    std::fs::copy(exp36().join("imu.csv"), &imu).unwrap();
    let before = std::fs::read(&imu).unwrap();
    let e = run(&options(&imu, None, &out)).unwrap_err();
    assert!(matches!(e, RunError::OutputIsInput { .. }), "{e}");
    assert!(e.to_string().contains("estimates.csv"), "{e}");
    assert_eq!(std::fs::read(&imu).unwrap(), before);
    // The truth as `summary.json` too.
    let truth = out.join("summary.json");
    std::fs::copy(exp36().join("ground_truth.csv"), &truth).unwrap();
    let e = run(&options(
        &exp36().join("imu.csv"),
        Some(truth.clone()),
        &out,
    ))
    .unwrap_err();
    assert!(matches!(e, RunError::OutputIsInput { .. }), "{e}");
    assert!(std::fs::read_to_string(&truth).unwrap().starts_with("t_s,"));
    // And as a staging name (`NAME.partial` is created first: it was truncated before it was
    // read).
    let staged = out.join("innovations.csv.partial");
    std::fs::copy(exp36().join("imu.csv"), &staged).unwrap();
    let e = run(&options(&staged, None, &out)).unwrap_err();
    assert!(matches!(e, RunError::OutputIsInput { .. }), "{e}");
    assert_eq!(std::fs::read(&staged).unwrap(), before);
    // An output directory that cannot be made says what it tried (it said only "…: Not a
    // directory", a review).
    let under_a_file = imu.join("o");
    let e = run(&options(&exp36().join("imu.csv"), None, &under_a_file)).unwrap_err();
    assert!(matches!(e, RunError::OutDir { .. }), "{e}");
    assert!(
        e.to_string().starts_with(&format!(
            "cannot create the output directory {}",
            under_a_file.display()
        )),
        "{e}"
    );
}

#[test]
fn diagnose_refuses_footprints_it_cannot_score() {
    // Footprints on another clock: `corridor run` refused them, `corridor diagnose` reported
    // "footprint RMS n/a", exit 0.
    let out = TempDir::new("eco-diagnose-truth");
    let text = std::fs::read_to_string(exp36().join("ground_truth.csv")).unwrap();
    let mut lines = text.lines();
    let mut shifted = vec![lines.next().unwrap().to_string()];
    shifted.extend(lines.map(|l| {
        let (t, rest) = l.split_once(',').unwrap();
        format!("{},{rest}", t.parse::<f64>().unwrap() + 1000.0)
    }));
    let truth = out.join("truth.csv");
    std::fs::write(&truth, shifted.join("\n") + "\n").unwrap();
    let o = diagnose(&exp36().join("imu.csv"), Some(&truth), &out.join("report"));
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.starts_with(&format!(
            "error: {}: the footprints cannot be scored",
            truth.display()
        )) && err.contains("on its clock"),
        "{err}"
    );
    assert!(!out.join("report").exists());
}

#[test]
fn diagnose_refuses_a_log_that_never_aligned() {
    // 2 s of rest and no walking: `corridor run` refused it, `corridor diagnose` wrote a report
    // of NaN ("NIS NaN (band NaN–NaN)") and exited 0 (a review).
    let out = TempDir::new("eco-diagnose-rest");
    let text = std::fs::read_to_string(exp36().join("imu.csv")).unwrap();
    let rest = out.join("rest.csv");
    std::fs::write(
        &rest,
        text.lines().take(400).collect::<Vec<_>>().join("\n") + "\n",
    )
    .unwrap();
    let o = diagnose(&rest, None, &out.join("report"));
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.starts_with(&format!("error: {}: no initial rest", rest.display())),
        "{err}"
    );
    assert!(!out.join("report").exists());
}

#[test]
fn diagnose_says_which_footprints_lie_beyond_the_log() {
    // The first half of exp36's log with all of its footprints: `corridor run` warns in
    // `summary.json` that the footprints past the log's end were clamped to it; `corridor
    // diagnose` scored them the same way and said nothing, its footprint RMS before and after
    // (and the loop's kept/not kept) resting on positions the walk never reached (a review).
    let out = TempDir::new("eco-diagnose-clamped");
    let text = std::fs::read_to_string(exp36().join("imu.csv")).unwrap();
    let n = text.lines().count();
    let half = out.join("half.csv");
    std::fs::write(
        &half,
        text.lines().take(n / 2).collect::<Vec<_>>().join("\n") + "\n",
    )
    .unwrap();
    let truth = exp36().join("ground_truth.csv");
    let o = diagnose(&half, Some(&truth), &out.join("report"));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let warning = "GCP time(s) outside the trajectory span, clamped";
    let md = std::fs::read_to_string(out.join("report/report.md")).unwrap();
    assert!(md.contains(&format!("Footprints: {warning}")), "{md}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report/report.json")).unwrap())
            .unwrap();
    assert!(
        json["truth_warnings"][0]
            .as_str()
            .is_some_and(|w| w.starts_with(warning)),
        "{}",
        json["truth_warnings"]
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(warning), "{err}");
}
