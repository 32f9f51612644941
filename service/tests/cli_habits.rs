//! CLI habits of the `corridor` binary (issue 12): negative numbers are values, errors are
//! printed once and without a backtrace, every command's `--help` has examples.

mod common;

use common::TempDir;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn corridor(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_corridor"))
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("corridor runs")
}

#[test]
fn negative_headings_are_values_not_flags() {
    let out = TempDir::new(&format!("eco-negative-{}", std::process::id()));
    let imu = root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv");
    let o = corridor(&[
        "run",
        "--imu",
        imu.to_str().unwrap(),
        "--config",
        root().join("configs/gdins.toml").to_str().unwrap(),
        "--start-heading-deg",
        "-90",
        "--grid-deg",
        "-45",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["samples"], 14_000);
}

#[test]
fn a_user_error_is_printed_once_without_a_backtrace() {
    let out = TempDir::new(&format!("eco-error-{}", std::process::id()));
    let o = corridor(&[
        "run",
        "--imu",
        "/nonexistent/imu.csv",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("error: /nonexistent/imu.csv"), "{err}");
    assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
    assert!(!err.contains("backtrace"), "{err}");
}

#[test]
fn every_command_help_has_examples() {
    for cmd in [
        &[][..],
        &["run"],
        &["eval"],
        &["demo"],
        &["serve"],
        &["diagnose"],
        &["status"],
        &["completions"],
        &["man"],
    ] {
        let mut args = cmd.to_vec();
        args.push("--help");
        let o = corridor(&args);
        assert!(o.status.success(), "{args:?}");
        let help = String::from_utf8_lossy(&o.stdout);
        let examples = help
            .split_once("Examples:")
            .unwrap_or_else(|| panic!("{args:?}: no examples in\n{help}"))
            .1;
        let invocation = format!("corridor {}", cmd.first().unwrap_or(&""));
        assert!(
            examples.contains(invocation.trim_end()),
            "{args:?}: {examples}"
        );
    }
}

#[test]
fn the_command_list_describes_each_command() {
    let o = corridor(&["--help"]);
    let help = String::from_utf8_lossy(&o.stdout);
    for (cmd, about) in [
        ("diagnose", "Diagnose the model on a log"),
        ("status", "The health of the daemon of a domain"),
        ("completions", "shell completion"),
        ("man", "man page"),
    ] {
        let line = help
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{cmd} ")))
            .unwrap_or_else(|| panic!("{cmd} not listed in\n{help}"));
        assert!(line.contains(about), "{line}");
    }
}

#[test]
fn completions_and_man_page_cover_every_command() {
    let bash = corridor(&["completions", "bash"]);
    assert!(bash.status.success());
    let bash = String::from_utf8_lossy(&bash.stdout);
    assert!(bash.contains("_corridor()"), "{bash}");
    for cmd in ["run", "serve", "status", "diagnose"] {
        assert!(bash.contains(&format!("corridor__subcmd__{cmd}")), "{cmd}");
    }
    assert!(bash.contains("--start-heading-deg"));
    let zsh = corridor(&["completions", "zsh"]);
    assert!(
        zsh.status.success() && String::from_utf8_lossy(&zsh.stdout).contains("#compdef corridor")
    );

    let man = corridor(&["man"]);
    assert!(man.status.success());
    let man = String::from_utf8_lossy(&man.stdout);
    assert!(
        man.starts_with(".ie") || man.contains(".TH corridor"),
        "{man}"
    );
    for section in ["CORRIDOR RUN", "CORRIDOR SERVE", "CORRIDOR STATUS"] {
        assert!(man.contains(section), "missing {section}");
    }
    assert!(man.contains("start\\-heading\\-deg"), "flags are listed");
}

#[test]
fn a_nan_flag_value_is_an_error_naming_the_flag() {
    let data = root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv");
    let out = TempDir::new(&format!("eco-nanflag-{}", std::process::id()));
    let run_cmd = |extra: &[&str]| {
        let mut args = vec![
            "run",
            "--imu",
            data.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        corridor(&args)
    };
    let o = run_cmd(&["--inject-after-s", "nan"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--inject-after-s") && err.contains("nan"),
        "{err}"
    );
    // A flag that overrides a config key: the flag is named, not the config file.
    let o = run_cmd(&["--start-heading-deg", "400"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.starts_with("error: --start-heading-deg 400: must be in")
            && err.contains("heading.start_heading_deg")
            && !err.contains("built-in defaults"),
        "{err}"
    );
}

#[test]
fn a_full_disk_is_an_error_not_a_panic() {
    // `> /dev/full`: the completions panicked in clap_complete (exit 101, a backtrace).
    for args in [&["completions", "bash"][..], &["man"][..]] {
        let o = Command::new(env!("CARGO_BIN_EXE_corridor"))
            .args(args)
            .env("RUST_BACKTRACE", "1")
            .stdout(std::fs::File::create("/dev/full").unwrap())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.starts_with("error: ")
                && err.contains("No space left")
                && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn flags_that_would_do_nothing_are_usage_errors() {
    // --inject-after-s alone injected nothing, silently; --timeout-s 0 could not be met.
    let imu = root().join("tests/data/gdins_exp17_rect_loop_small/imu.csv");
    let out = TempDir::new(&format!("eco-nothing-{}", std::process::id()));
    for (args, flag) in [
        (
            vec![
                "run",
                "--imu",
                imu.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
                "--inject-after-s",
                "5",
            ],
            "--inject-gyro-bias",
        ),
        (vec!["status", "--timeout-s", "0"], "--timeout-s"),
    ] {
        let o = corridor(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(flag), "{args:?}: {err}");
    }
}

#[test]
fn a_demo_away_from_the_repository_says_to_give_its_root() {
    // It said "./configs/eval/gdins.toml: No such file or directory" (noticed in session 44).
    let dir = TempDir::new(&format!("eco-demo-root-{}", std::process::id()));
    let out = dir.join("out");
    let o = corridor(&[
        "demo",
        "--root",
        dir.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("configs/eval/gdins.toml not found") && err.contains("--root"),
        "{err}"
    );
    assert!(o.stdout.is_empty() && !out.exists());
}

#[test]
fn an_out_path_that_is_a_file_is_refused_before_any_work() {
    let dir = TempDir::new(&format!("eco-outfile-{}", std::process::id()));
    let file = dir.join("afile");
    std::fs::write(&file, "").unwrap();
    for args in [
        vec!["eval", "--suite", "configs/eval/gdins.toml", "--out"],
        vec!["diagnose", "--suite", "configs/eval/gdins.toml", "--out"],
        vec!["demo", "--out"],
    ] {
        let mut args = args.clone();
        args.push(file.to_str().unwrap());
        let o = corridor(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?}");
        // Refused up front: nothing computed or printed (eval printed its whole table first).
        assert!(
            err.contains("exists and is not a directory") && o.stdout.is_empty(),
            "{args:?}: {err}"
        );
    }
}
