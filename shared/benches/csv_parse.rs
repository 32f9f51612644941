//! Throughput of the IMU CSV parser ([`corridor_shared::imu_csv::parse_imu_csv`]) in rows/s.
//!
//! Reads the bundled `tests/data/gdins_exp29_corridor_circuit/imu.csv` into memory
//! once, or generates 100 000 synthetic rows of the same shape when that file is absent, and
//! benchmarks parsing it from memory with the default options (units check included). Criterion
//! reports the throughput in elements/s, which here are rows/s.
//!
//! Run: `cargo bench -p corridor-shared --bench csv_parse -- --warm-up-time 1 --measurement-time 3`
// `criterion_group!` defines an undocumented `pub fn`.
#![allow(missing_docs)]

use corridor_shared::imu_csv::{ImuCsvOptions, parse_imu_csv};
use criterion::{Criterion, Throughput, black_box, criterion_group, criterion_main};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Number of rows generated when the real file is absent.
const SYNTHETIC_ROWS: usize = 100_000;

/// The real recording, or a synthetic one, as (name, text).
fn input() -> (PathBuf, String) {
    let real = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/gdins_exp29_corridor_circuit/imu.csv");
    if let Ok(text) = std::fs::read_to_string(&real) {
        return (real, text);
    }
    let mut text = String::from(
        "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2,mx_gauss,my_gauss,mz_gauss\n",
    );
    for i in 0..SYNTHETIC_ROWS {
        let t = i as f64 * 0.005;
        let phase = t * std::f64::consts::TAU;
        writeln!(
            text,
            "{t},{},{},{},{},{},{},0.133729354,-0.233613923,0.282398134",
            0.02 * phase.sin(),
            -0.5 * (0.7 * phase).cos(),
            3.0 * (1.3 * phase).sin(),
            1.64785430359375 + 0.1 * phase.cos(),
            6.549063332529899,
            -7.131046057181199 + 0.2 * phase.sin(),
        )
        .expect("writing to a String cannot fail");
    }
    (PathBuf::from("synthetic/imu.csv"), text)
}

fn bench_parse(c: &mut Criterion) {
    let (path, text) = input();
    let opts = ImuCsvOptions::default();
    let log = parse_imu_csv(&text, &path, &opts).expect("benchmark input must parse");
    let rows = log.rows.len() as u64;
    assert!(log.rejected.is_empty(), "benchmark input has rejected rows");

    // A plain wall-clock figure next to criterion's, so the log shows rows/s directly. The best
    // of several parses is reported because it is the least disturbed by other load on the machine.
    let reps = 30;
    let best_s = (0..reps)
        .map(|_| {
            let start = Instant::now();
            black_box(parse_imu_csv(black_box(&text), &path, &opts).unwrap());
            start.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min);
    println!(
        "csv_parse: {} ({rows} rows, {:.1} MB): {:.2} M rows/s, {:.0} MB/s (best of {reps} parses)",
        path.display(),
        text.len() as f64 / 1e6,
        rows as f64 / best_s / 1e6,
        text.len() as f64 / best_s / 1e6,
    );

    let mut group = c.benchmark_group("csv_parse");
    group.throughput(Throughput::Elements(rows));
    group.bench_function("parse_imu_csv", |b| {
        b.iter(|| parse_imu_csv(black_box(&text), &path, &opts).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench_parse);
criterion_main!(benches);
