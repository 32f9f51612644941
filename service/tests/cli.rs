//! The `corridor` binary: outputs of `run`, and clear errors for bad input.

mod common;

use common::TempDir;
use common::cli::{corridor, gdins, read_json, root, run_cmd};
use std::path::Path;

fn tmp(name: &str) -> TempDir {
    TempDir::new(&format!("cli-{}-{name}", std::process::id()))
}

#[test]
fn run_writes_estimates_innovations_and_summary() {
    let out = tmp("run");
    let data = root().join("tests/data/gdins_exp36_corridor_out_and_back");
    let o = run_cmd(
        &data.join("imu.csv"),
        &out,
        &[
            "--truth",
            data.join("ground_truth.csv").to_str().unwrap(),
            "--config",
            &gdins(),
            "--inject-gyro-bias",
            "0.001,0.001,0.005",
            "--plots",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let est = std::fs::read_to_string(out.join("estimates.csv")).unwrap();
    let header = est.lines().next().unwrap();
    for col in [
        "t_s",
        "x_m",
        "y_m",
        "z_m",
        "roll_rad",
        "pitch_rad",
        "yaw_rad",
        "bias_x_rad_s",
        "bias_y_rad_s",
        "bias_z_rad_s",
        "bias_sd_x_rad_s",
        "bias_sd_y_rad_s",
        "bias_sd_z_rad_s",
        "bias_unabsorbed",
        "stance",
        "converged",
        "phase",
    ] {
        assert!(header.split(',').any(|c| c == col), "missing column {col}");
    }
    assert_eq!(
        est.lines().count(),
        14_001,
        "one row per sample plus the header"
    );
    // The convergence flag is the unabsorbed part of a start bias error below 5 % while
    // tracking, and the summary's time is its first rise.
    let cols: Vec<&str> = header.split(',').collect();
    let at = |name: &str| cols.iter().position(|c| *c == name).unwrap();
    let (t, u, conv, phase) = (
        at("t_s"),
        at("bias_unabsorbed"),
        at("converged"),
        at("phase"),
    );
    let mut first_rise = None;
    for line in est.lines().skip(1) {
        let v: Vec<&str> = line.split(',').collect();
        let unabsorbed: f64 = v[u].parse().unwrap();
        let converged = v[conv] == "1";
        assert_eq!(
            converged,
            v[phase] == "tracking" && unabsorbed < 0.05,
            "{line}"
        );
        if converged && first_rise.is_none() {
            first_rise = Some(v[t].parse::<f64>().unwrap());
        }
    }
    let summary = read_json(&out.join("summary.json"));
    assert_eq!(summary["converged_at_s"].as_f64(), first_rise);
    assert!(first_rise.is_some(), "the flag never rose on exp36");
    // The log clock's origin, from which the injection's start counts (`converged_at_s` is on
    // the log's clock).
    let imu = std::fs::read_to_string(
        root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv"),
    )
    .unwrap();
    let first_t_s: f64 = imu
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(summary["first_t_s"].as_f64(), Some(first_t_s));
    for key in [
        "bias_rad_s",
        "bias_mean_converged_rad_s",
        "converged_at_s",
        "stances",
        "heading_observations_used",
        "heading_observations_rejected",
        "input_rows_rejected",
    ] {
        assert!(summary.get(key).is_some(), "summary lacks {key}");
    }
    assert_eq!(summary["samples"], 14_000);
    assert_eq!(summary["injected_rows"], 14_000);
    assert!(summary["stances"].as_u64().unwrap() > 50);
    let rms = summary["eval"]["rms_error_m"].as_f64().unwrap();
    assert!(rms > 0.0 && rms < 3.0, "rms {rms}");
    let inn = std::fs::read_to_string(out.join("innovations.csv")).unwrap();
    assert!(inn.lines().any(|l| l.contains(",heading,1,")));
    for fig in ["trajectory.svg", "bias.svg", "covariance.svg"] {
        let svg = std::fs::read_to_string(out.join(fig)).unwrap_or_else(|e| panic!("{fig}: {e}"));
        assert!(svg.starts_with("<svg") || svg.starts_with("<?xml"), "{fig}");
    }
}

#[test]
fn an_injection_that_starts_after_the_log_ends_is_said() {
    // exp36's first 10 s, the injection asked from 1000 s on: it ran with exit 0 and said
    // nothing (a review).
    let dir = tmp("inject_late");
    let src = root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv");
    let text: String = std::fs::read_to_string(src)
        .unwrap()
        .lines()
        .take(2001)
        .map(|l| l.to_owned() + "\n")
        .collect();
    let imu = dir.join("imu.csv");
    std::fs::write(&imu, text).unwrap();
    let brief = |after_s: &str, out: &str| {
        let inject = [
            "--inject-gyro-bias",
            "0.001,0,0",
            "--inject-after-s",
            after_s,
        ];
        let o = run_cmd(&imu, &dir.join(out), &inject);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let summary = read_json(&dir.join(out).join("summary.json"));
        let notes =
            serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()["notes"].to_string();
        // The notes are kept in summary.json too: printed alone, they were lost with the
        // terminal (a review).
        assert_eq!(summary["notes"].to_string(), notes);
        (summary["injected_rows"].as_u64().unwrap(), notes)
    };
    let (rows, notes) = brief("1000", "late");
    assert_eq!(rows, 0);
    assert!(
        notes.contains("nothing was injected: the log ends before --inject-after-s 1000 s"),
        "{notes}"
    );
    let (rows, notes) = brief("5", "in_time");
    assert!((900..1100).contains(&rows), "{rows}");
    assert!(!notes.contains("nothing was injected"), "{notes}");
}

#[test]
fn malformed_rows_are_counted_and_reported_with_line_column_and_value() {
    let dir = tmp("bad");
    let src = root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv");
    let mut lines: Vec<String> = std::fs::read_to_string(src)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    // line 52 of the file: a malformed gyro value; line 60: NaN; line 70: time going backwards
    let mut f: Vec<String> = lines[51].split(',').map(String::from).collect();
    f[2] = "abc".into();
    lines[51] = f.join(",");
    let mut f: Vec<String> = lines[59].split(',').map(String::from).collect();
    f[5] = "NaN".into();
    lines[59] = f.join(",");
    let mut f: Vec<String> = lines[69].split(',').map(String::from).collect();
    f[0] = "0.0001".into();
    lines[69] = f.join(",");
    let imu = dir.join("imu.csv");
    std::fs::write(&imu, lines.join("\n") + "\n").unwrap();
    let out = dir.join("o");
    let o = run_cmd(&imu, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("imu.csv:52") && err.contains("gy_rad_s") && err.contains("abc"),
        "{err}"
    );
    let summary = read_json(&out.join("summary.json"));
    assert_eq!(summary["input_rows_rejected"]["malformed"], 1);
    assert_eq!(summary["input_rows_rejected"]["non_finite"], 1);
    assert_eq!(summary["input_rows_rejected"]["time_not_increasing"], 1);
    assert_eq!(summary["samples"], 14_000 - 3);
    let examples = summary["input_rows_rejected_examples"].to_string();
    assert!(
        examples.contains("imu.csv:60") && examples.contains("ay_m_s2"),
        "{examples}"
    );
}

#[test]
fn absurd_values_and_times_are_refused_counted_and_named_in_the_summary() {
    let dir = tmp("absurd");
    let src = root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv");
    let mut lines: Vec<String> = std::fs::read_to_string(src)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    // line 3001: az = 1e30; line 6001: t_s = 1e30 (before, it became the time base and the
    // 8000 rows after it were rejected, the error naming line 6002); last line: t_s = 1e30.
    let set = |lines: &mut Vec<String>, line: usize, col: usize, v: &str| {
        let mut f: Vec<String> = lines[line - 1].split(',').map(String::from).collect();
        f[col] = v.into();
        lines[line - 1] = f.join(",");
    };
    set(&mut lines, 3001, 6, "1e30");
    set(&mut lines, 6001, 0, "1e30");
    let n = lines.len();
    set(&mut lines, n, 0, "1e30");
    let imu = dir.join("imu.csv");
    std::fs::write(&imu, lines.join("\n") + "\n").unwrap();
    let out = dir.join("o");
    let o = run_cmd(&imu, &out, &["--config", &gdins()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = read_json(&out.join("summary.json"));
    assert_eq!(summary["input_rows_rejected"]["time_jump"], 2);
    assert_eq!(summary["samples_refused_counts"]["implausible"], 1);
    assert_eq!(summary["samples"], 14_000 - 3);
    let refused = summary["samples_refused"].to_string();
    assert!(
        refused.contains("imu.csv:3001") && refused.contains("1e30"),
        "{refused}"
    );
    let examples = summary["input_rows_rejected_examples"].to_string();
    assert!(examples.contains("imu.csv:6001"), "{examples}");
    // And said on the terminal (it was in summary.json alone).
    let notes =
        serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()["notes"].to_string();
    assert!(
        notes.contains("1 of 13998 samples refused, not fused (implausible 1)"),
        "{notes}"
    );
    // The rows the reader rejected too (a review: 60 rows of NaN ran with no note).
    assert!(
        notes.contains("2 rows of the CSV rejected, not read (time_jump 2)"),
        "{notes}"
    );
    let est = std::fs::read_to_string(out.join("estimates.csv")).unwrap();
    let last: Vec<f64> = est
        .lines()
        .last()
        .unwrap()
        .split(',')
        .take(4)
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(last.iter().all(|v| v.abs() < 1000.0), "{last:?}");
}

#[test]
fn too_many_bad_rows_stop_the_run_with_the_first_one_named() {
    let dir = tmp("many");
    let mut text = String::from("t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\n");
    for k in 0..200 {
        let gy = if k % 10 == 3 {
            "abc".to_string()
        } else {
            "0.0".to_string()
        };
        text += &format!("{},0.0,{gy},0.0,0.0,0.0,9.81\n", k as f64 * 0.005);
    }
    let imu = dir.join("imu.csv");
    std::fs::write(&imu, text).unwrap();
    let o = run_cmd(&imu, &dir.join("o"), &[]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("imu.csv:5") && err.contains("gy_rad_s") && err.contains("abc"),
        "{err}"
    );
}

#[test]
fn degrees_per_second_are_refused() {
    let dir = tmp("deg");
    let imu = dir.join("imu.csv");
    let mut text = String::from("t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\n");
    for k in 0..400 {
        let gy = if k > 200 {
            300.0 * ((k as f64) * 0.1).sin()
        } else {
            0.0
        };
        text += &format!("{},0.0,{gy},0.0,0.0,0.0,9.81\n", k as f64 * 0.005);
    }
    std::fs::write(&imu, text).unwrap();
    let o = run_cmd(&imu, &dir.join("o"), &[]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("deg/s"), "{err}");
}

#[test]
fn bad_config_names_the_key() {
    let dir = tmp("cfg");
    let cfg = dir.join("c.toml");
    std::fs::write(&cfg, "[heading]\nsigma_deg = -3.0\n").unwrap();
    let imu = root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv");
    let o = run_cmd(&imu, &dir.join("o"), &["--config", cfg.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("heading.sigma_deg") && err.contains("c.toml"),
        "{err}"
    );
}

#[test]
fn run_starts_from_a_checkpoint_as_the_daemon_does_and_names_a_missing_one() {
    use corridor_service::checkpoint::{Checkpoint, save};
    let dir = tmp("ckpt");
    let imu = root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv");
    let config = root().join("configs/gdins.toml");
    let run = |ckpt: Option<&Path>, out: &str| {
        let mut extra = vec!["--config", config.to_str().unwrap()];
        if let Some(c) = ckpt {
            extra.extend(["--checkpoint", c.to_str().unwrap()]);
        }
        run_cmd(&imu, &dir.join(out), &extra)
    };
    // The bias of the first estimate after the alignment.
    let start_bias = |out: &str| -> [f64; 3] {
        let est = std::fs::read_to_string(dir.join(out).join("estimates.csv")).unwrap();
        let mut lines = est.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |name| header.iter().position(|h| *h == name).unwrap();
        let phase = col("phase");
        let first = lines
            .map(|l| l.split(',').collect::<Vec<_>>())
            .find(|f| f[phase] != "aligning")
            .expect("the walk aligns");
        ["bias_x_rad_s", "bias_y_rad_s", "bias_z_rad_s"].map(|c| first[col(c)].parse().unwrap())
    };
    let o = run(None, "cold");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rest = start_bias("cold");
    let checkpoint = |name: &str, bias: [f64; 3]| {
        let file = dir.join(name);
        save(
            &file,
            &Checkpoint {
                mode: "eskf".into(),
                t_s: 0.0,
                saved_unix_ms: 0,
                gyro_bias_rad_s: bias,
                gyro_bias_cov: [[1e-8, 0.0, 0.0], [0.0, 1e-8, 0.0], [0.0, 0.0, 1e-8]],
                nav_from_body_wxyz: [1.0, 0.0, 0.0, 0.0],
            },
        )
        .unwrap();
        file
    };
    // A tight saved bias 0.8 mrad/s from exp36's rest mean on each axis (within the χ² gate
    // of the two): the rest is fused into it, so the run starts near the saved value.
    let near = rest.map(|b| b + 8e-4);
    let o = run(Some(&checkpoint("near.ckpt", near)), "warm");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let b = start_bias("warm");
    for k in 0..3 {
        assert!(
            (b[k] - near[k]).abs() < 1e-4,
            "axis {k}: {b:?}, saved {near:?}"
        );
    }
    // One 20 mrad/s away (the bias moved while the daemon was down): the rest replaces it.
    let far = rest.map(|b| b + 0.02);
    let o = run(Some(&checkpoint("far.ckpt", far)), "stale");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let b = start_bias("stale");
    for k in 0..3 {
        assert!(
            (b[k] - rest[k]).abs() < 1e-6,
            "axis {k}: {b:?}, rest {rest:?}"
        );
    }
    // A checkpoint of another mode, from which the daemon starts cold: an error naming both
    // (it was used as it was).
    let mut extra = vec!["--config", config.to_str().unwrap(), "--mode", "paper"];
    let near_file = dir.join("near.ckpt");
    extra.extend(["--checkpoint", near_file.to_str().unwrap()]);
    let o = run_cmd(&imu, &dir.join("other_mode"), &extra);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("near.ckpt") && err.contains("\"eskf\"") && err.contains("paper"),
        "{err}"
    );
    // A missing file is an error that names it, said once.
    let o = run(Some(&dir.join("none.ckpt")), "missing");
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("none.ckpt") && err.matches("none.ckpt").count() == 1,
        "{err}"
    );
}

/// The footprints before the first truth leg the data set flags are scored on their own: the
/// suite's figure equals `corridor run`'s evaluation of the same default run against the truth
/// cut before that leg, and a leg the truth does not have is refused, naming the key. The same
/// run's stance ends scored apart for the strides a suite lists as placed by hand.
#[test]
fn a_bad_mode_is_said_once_and_clamped_footprints_are_said_on_the_terminal() {
    let out = tmp("said");
    let data = root().join("tests/data/gdins_exp36_corridor_out_and_back");
    let imu = data.join("imu.csv");
    let o = run_cmd(&imu, &out.join("a"), &["--mode", "kalman"]);
    // A usage error, as an unknown flag (2), and a flag value out of its key's range too.
    assert_eq!(o.status.code(), Some(2));
    let range = run_cmd(&imu, &out.join("a"), &["--start-heading-deg", "400"]);
    assert_eq!(range.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&range.stderr).contains("heading.start_heading_deg"));
    // A relative runtime directory (it exited with 1), and a diagnosis without a log.
    let relative = corridor(&["serve", "--runtime-dir", "run/corridor"]);
    assert_eq!(relative.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&relative.stderr).contains("must be an absolute path"));
    let no_log = corridor(&["diagnose", "--out", out.join("d").to_str().unwrap()]);
    assert_eq!(no_log.status.code(), Some(2));
    // A domain name iceoryx2 cannot use, named with its flag (it exited with 1 as `domain`).
    for args in [
        &["serve", "--domain", "a b"][..],
        &["status", "--domain", ""],
    ] {
        let bad = corridor(args);
        assert_eq!(bad.status.code(), Some(2), "{args:?}");
        assert!(String::from_utf8_lossy(&bad.stderr).contains("'--domain <DOMAIN>'"));
    }
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.matches("kalman").count() == 1 && !err.contains("unknown variant"),
        "{err}"
    );
    // Footprints after the log's end are clamped to it, as the reference evaluation does; the
    // terminal says so (it used to be only in summary.json).
    let truth = out.join("truth.csv");
    let mut text = std::fs::read_to_string(data.join("ground_truth.csv")).unwrap();
    text.push_str("1000.0,0.0,0.0,0.0,99,1\n");
    std::fs::write(&truth, text).unwrap();
    let o = run_cmd(
        &imu,
        &out.join("b"),
        &["--config", &gdins(), "--truth", truth.to_str().unwrap()],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("outside the trajectory span, clamped"),
        "{err}"
    );
}
