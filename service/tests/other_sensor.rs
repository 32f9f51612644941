//! `corridor run` on the other sensor's walk (the x-io NGIMU, `configs/ngimu.toml`), as a user
//! porting corridor to a second sensor meets it (a review): what the run says of a closed
//! truth, of a configuration without a heading aid, and of one that asks for a map it lacks.

mod common;

use common::TempDir;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// `corridor run` on the x-io walk with `config`, then `extra`; the printed summary, parsed.
fn run_xio(out: &Path, config: &Path, extra: &[&str]) -> (Output, Option<serde_json::Value>) {
    let data = root().join("tests/data/xio_ngimu_long_walk");
    let o = Command::new(env!("CARGO_BIN_EXE_corridor"))
        .args(["run", "--imu"])
        .arg(data.join("imu.csv"))
        .arg("--truth")
        .arg(data.join("ground_truth.csv"))
        .arg("--config")
        .arg(config)
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .expect("corridor runs");
    let brief = serde_json::from_slice(&o.stdout).ok();
    (o, brief)
}

#[test]
fn a_closed_truth_gives_its_loop_closure_on_the_terminal() {
    let out = TempDir::new(&format!("eco-xio-closure-{}", std::process::id()));
    let (o, brief) = run_xio(&out, &root().join("configs/ngimu.toml"), &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let brief = brief.expect("a JSON summary");
    // The truth is the walk's start and end at one place: no footprint RMS, a loop closure
    // (it was only in summary.json).
    assert!(brief["gcp_rms_pct"].is_null());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let (m, pct) = (
        brief["loop_closure_m"].as_f64().expect("loop_closure_m"),
        brief["loop_closure_pct"]
            .as_f64()
            .expect("loop_closure_pct"),
    );
    assert_eq!(Some(m), summary["eval"]["loop_closure_error_m"].as_f64());
    assert_eq!(Some(pct), summary["eval"]["loop_closure_pct"].as_f64());
    assert!(m > 0.0 && pct > 0.0 && pct < 5.0, "{m} m, {pct} %");
}

#[test]
fn a_heading_mode_without_a_heading_aid_says_so_and_blames_no_weave() {
    let out = TempDir::new(&format!("eco-xio-noaid-{}", std::process::id()));
    // configs/ngimu.toml has heading.source = "none" (no map of that building).
    let (o, brief) = run_xio(
        &out,
        &root().join("configs/ngimu.toml"),
        &["--mode", "eskf"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let notes = brief.expect("a JSON summary")["notes"].to_string();
    assert!(notes.contains("no heading aid"), "{notes}");
    // The note for a heading the map never held (a weave, a wrong start heading) is not the
    // one: there was nothing to hold it.
    assert!(
        !notes.contains("no heading observation was used"),
        "{notes}"
    );
}

#[test]
fn map_headings_without_a_map_are_refused() {
    let out = TempDir::new(&format!("eco-xio-nomap-{}", std::process::id()));
    let config = out.join("map.toml");
    let text = std::fs::read_to_string(root().join("configs/ngimu.toml")).unwrap();
    assert!(text.contains("\nsource = \"none\""));
    std::fs::write(
        &config,
        text.replace("\nsource = \"none\"", "\nsource = \"map\""),
    )
    .unwrap();
    // It ran without a heading aid and said nothing.
    let (o, _) = run_xio(&out, &config, &["--mode", "eskf"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.starts_with("error: heading.source = \"map\" needs a corridor map")
            && err.contains("--map"),
        "{err}"
    );
}

#[test]
fn a_flipped_axis_that_the_filter_fights_is_said_without_a_typical_bias() {
    // exp36 with its y axis negated (a left-handed frame), run with a configuration that has
    // no typical bias of the unit: the note on the bias's distance from it cannot fire, and the
    // run said nothing. The clean walk with the same configuration says nothing of it.
    let dir = TempDir::new(&format!("eco-flipped-{}", std::process::id()));
    let src = root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv");
    let text = std::fs::read_to_string(&src).unwrap();
    let mut lines = text.lines();
    let mut flipped = vec![lines.next().unwrap().to_string()];
    flipped.extend(lines.map(|l| {
        let mut f: Vec<String> = l.split(',').map(String::from).collect();
        for k in [2, 5] {
            f[k] = (-f[k].parse::<f64>().unwrap()).to_string();
        }
        f.join(",")
    }));
    let imu = dir.join("imu.csv");
    std::fs::write(&imu, flipped.join("\n") + "\n").unwrap();
    let note_of = |imu: &Path, out: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_corridor"))
            .args(["run", "--imu"])
            .arg(imu)
            .arg("--config")
            .arg(root().join("configs/ngimu.toml"))
            .arg("--out")
            .arg(dir.join(out))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let brief: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        brief["notes"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|n| n.as_str())
            .find(|n| n.contains("reset its velocity"))
            .map(String::from)
    };
    let note = note_of(&imu, "flipped").expect("a note on the resets");
    assert!(note.contains("axes and signs"), "{note}");
    assert_eq!(note_of(&src, "clean"), None);
}
