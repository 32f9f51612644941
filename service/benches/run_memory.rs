//! Peak memory of `corridor run` on a long log (issue 10, finding 6): prints the process's
//! peak RSS (its `ru_maxrss`, what `/usr/bin/time -v` reports as "Maximum resident set size")
//! and the wall time for a log of exp36 repeated to 5 M rows (about 700 MB of CSV, 2.4 GB of
//! outputs, written to the system's temporary directory and removed after).
//!
//! Run: `cargo bench -p corridor-service --bench run_memory [-- --rows N] [-- --plots]`
//! (`--plots` also evaluates against exp36's footprints and draws the figures).
//!
//! Measured on the 2-core machine: before the runner streamed, 1 134 940 KiB (1.08 GiB) for
//! 5 M rows in 20 s; streaming, 7 820 KiB in 20 s (14 696 KiB with `--plots` and truth); in
//! session 34, 8 612 KiB in 22 s (16 380 KiB in 21 s).

#[path = "../tests/common/mod.rs"]
mod common;

use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// Rows of the log unless `--rows` says otherwise.
const DEFAULT_ROWS: u64 = 5_000_000;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rows = args
        .iter()
        .position(|a| a == "--rows")
        .and_then(|i| args.get(i + 1))
        .map_or(DEFAULT_ROWS, |v| v.parse().expect("--rows takes a count"));
    let plots = args.iter().any(|a| a == "--plots");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let data = root.join("tests/data/gdins_exp36_corridor_out_and_back");
    let dir = common::TempDir::new(&format!("run-memory-bench-{}", std::process::id()));
    let imu = dir.join("imu.csv");
    common::repeat_log(&data.join("imu.csv"), rows, &imu);
    let mb = std::fs::metadata(&imu).expect("log written").len() as f64 / 1e6;
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_corridor"));
    cmd.arg("run")
        .arg("--imu")
        .arg(&imu)
        .arg("--config")
        .arg(root.join("configs/gdins.toml"))
        .arg("--out")
        .arg(dir.join("out"));
    if plots {
        cmd.arg("--plots")
            .arg("--truth")
            .arg(data.join("ground_truth.csv"));
    }
    let t0 = Instant::now();
    let out = cmd.output().expect("corridor runs");
    let wall_s = t0.elapsed().as_secs_f64();
    assert!(
        out.status.success(),
        "corridor run failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    // SAFETY: getrusage fills the zeroed struct it is given.
    let usage = unsafe {
        let mut u: libc::rusage = std::mem::zeroed();
        assert_eq!(libc::getrusage(libc::RUSAGE_CHILDREN, &mut u), 0);
        u
    };
    let rss_kib = usage.ru_maxrss;
    println!(
        "corridor run{}: {rows} rows ({mb:.0} MB of CSV) in {wall_s:.1} s, peak RSS {rss_kib} KiB ({:.1} MiB)",
        if plots { " --plots --truth" } else { "" },
        rss_kib as f64 / 1024.0
    );
}
