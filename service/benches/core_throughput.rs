//! Core throughput: samples per second through the estimator on one core, CSV parsing
//! excluded (the log is parsed once, before timing). Prints criterion's throughput figure for
//! each mode.
// `criterion_group!` defines an undocumented `pub fn`.
#![allow(missing_docs)]

use corridor_service::core::{Estimator, ImuInput};
use corridor_service::runner::heading_aid;
use corridor_shared::config::{ConfigFile, ConfigOverrides, Mode};
use corridor_shared::imu_csv::{ImuCsvOptions, read_imu_csv};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::Path;

fn bench(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let log = read_imu_csv(
        &root.join("tests/data/gdins_exp29_corridor_circuit/imu.csv"),
        &ImuCsvOptions::default(),
    )
    .expect("bundled recording");
    let inputs: Vec<ImuInput> = log.rows.iter().map(ImuInput::from).collect();
    let mut group = c.benchmark_group("core");
    group.throughput(Throughput::Elements(inputs.len() as u64));
    for mode in [Mode::Zupt, Mode::Paper, Mode::RotationAware, Mode::Eskf] {
        let path = root.join("configs/gdins.toml");
        let cfg = ConfigOverrides {
            mode: Some(mode),
            start_heading_deg: Some(90.0),
            ..Default::default()
        }
        .validate(&ConfigFile::read(&path).expect("config"), &path)
        .expect("valid");
        let aid = heading_aid(&cfg, None).expect("aid");
        group.bench_function(mode.name(), |b| {
            b.iter(|| {
                let mut est = Estimator::new(cfg.clone(), aid.clone());
                let mut acc = 0.0;
                for s in &inputs {
                    if let Ok(e) = est.step(s) {
                        acc += e.p_m[0];
                    }
                }
                black_box(acc)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
