//! The `corridor` binary as the CLI tests call it (`cli.rs`, `cli_eval.rs`).

use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository's root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// `corridor ARGS`.
pub fn corridor(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_corridor"))
        .args(args)
        .output()
        .expect("corridor runs")
}

/// `corridor run --imu IMU --out OUT`, then `extra`.
pub fn run_cmd(imu: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "run",
        "--imu",
        imu.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    corridor(&args)
}

/// The gdins sensor configuration.
pub fn gdins() -> String {
    root()
        .join("configs/gdins.toml")
        .to_str()
        .unwrap()
        .to_string()
}

/// A JSON file, parsed.
pub fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
