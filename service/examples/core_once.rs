//! One pass of the default (eskf) estimator over a bundled walk, nothing else: the program to
//! count the core's instructions per sample with callgrind, a figure that does not depend on
//! the machine's load the way `core_throughput`'s timings do:
//!
//! ```text
//! cargo build --release -p corridor-service --example core_once
//! valgrind --tool=callgrind --toggle-collect='*Estimator*step*' target/release/examples/core_once
//! ```
//!
//! (`--toggle-collect` counts the estimator's steps only, not the reading of the CSV file.)
//!
//! It prints the number of samples and a checksum of the positions (so that the work cannot be
//! optimised away, and two builds can be checked to give the same numbers).
//!
//! With a number of passes (`core_once 200`) it also times each pass and prints the samples per
//! second of the fastest, the 10th percentile and the median: on a shared machine whose speed
//! varies from second to second, the fastest passes of two builds run back to back compare
//! them better than a mean does. A second argument names another configuration file
//! (`core_once 60 my.toml`; default `configs/gdins.toml`).

use corridor_service::core::{Estimator, ImuInput};
use corridor_service::runner::heading_aid;
use corridor_shared::config::{ConfigFile, ConfigOverrides};
use corridor_shared::imu_csv::{ImuCsvOptions, read_imu_csv};
use std::path::Path;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let passes: usize = match std::env::args().nth(1) {
        Some(a) => a
            .parse()
            .map_err(|e| anyhow::anyhow!("passes {a:?}: {e}"))?,
        None => 1,
    };
    anyhow::ensure!(passes >= 1, "passes must be at least 1");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let log = read_imu_csv(
        &root.join("tests/data/gdins_exp29_corridor_circuit/imu.csv"),
        &ImuCsvOptions::default(),
    )?;
    let inputs: Vec<ImuInput> = log.rows.iter().map(ImuInput::from).collect();
    // A second argument: another configuration (e.g. one with a model extension off, to see
    // what it costs).
    let path = std::env::args()
        .nth(2)
        .map_or_else(|| root.join("configs/gdins.toml"), Into::into);
    let cfg = ConfigOverrides {
        start_heading_deg: Some(90.0),
        ..Default::default()
    }
    .validate(&ConfigFile::read(&path)?, &path)?;
    let aid = heading_aid(&cfg, None)?;
    let mut seconds = Vec::with_capacity(passes);
    let mut checksum = 0.0;
    for _ in 0..passes {
        let start = Instant::now();
        let mut est = Estimator::new(cfg.clone(), aid.clone());
        checksum = 0.0;
        for s in &inputs {
            if let Ok(e) = est.step(s) {
                checksum += e.p_m[0] + e.p_m[1];
            }
        }
        seconds.push(start.elapsed().as_secs_f64());
    }
    println!("{} samples, checksum {checksum:.17e}", inputs.len());
    if passes > 1 {
        seconds.sort_by(f64::total_cmp);
        let rate = |s: f64| inputs.len() as f64 / s / 1e6;
        println!(
            "{passes} passes: fastest {:.3} M samples/s, 10th percentile {:.3}, median {:.3}",
            rate(seconds[0]),
            rate(seconds[passes / 10]),
            rate(seconds[passes / 2])
        );
    }
    Ok(())
}
