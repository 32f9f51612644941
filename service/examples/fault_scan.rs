//! One kind of input fault thrown at a bundled walk at random places, straight into the core as
//! the daemon feeds it (no CSV reader in between), and what it costs: the final horizontal
//! position's distance from the clean run's, per fault, and its median, 90th percentile and
//! largest. `robust_torture.rs` checks that no mix of faults breaks the estimator (nothing
//! panics, every sample is accounted for, no state is not finite); this measures how far each
//! kind of fault moves the result, which is where session 37 found a zero fill fused as a free
//! fall and runs of glitched stamps within `sensor.max_dt_s` taken for a gap.
//!
//! ```text
//! cargo run --release -p corridor-service --example fault_scan -- glitch_run 40
//! cargo run --release -p corridor-service --example fault_scan -- zeros 40 gdins_exp29_corridor_circuit
//! ```
//!
//! Kinds: `gyro` / `accel` (one axis NaN, ±1e30, beyond the range or 0), `time` (one stamp
//! moved by up to ±2 s), `time_absurd` (one stamp NaN, 0, 1e12 or −5), `repeat` (one sample
//! sent twice), `swap` (two samples up to 5 apart swapped), `clock_step` (every stamp from a
//! place on moved by up to ±1 s), `zeros` (1–300 samples with all six values 0), `loss`
//! (1–300 samples lost), `late` (the same loss, and one of the lost samples delivered up to 100
//! samples later), `glitch_run` (1–50 stamps in a row pushed 0–3 s ahead). The same seed
//! gives the same places and sizes for every kind, so `zeros` and `loss` lose the same samples.

use corridor_service::core::{Estimator, ImuInput};
use corridor_service::runner::heading_aid;
use corridor_shared::config::Config;
use corridor_shared::imu_csv::{ImuCsvOptions, read_imu_csv};
use std::path::Path;

const KINDS: [&str; 12] = [
    "gyro",
    "accel",
    "time",
    "time_absurd",
    "repeat",
    "swap",
    "clock_step",
    "zeros",
    "loss",
    "glitch_run",
    "late",
    "none",
];

/// A small deterministic generator (a 64-bit LCG; the top 53 bits as a uniform number).
struct Lcg(u64);

impl Lcg {
    fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    fn below(&mut self, n: usize) -> usize {
        (self.uniform() * n as f64) as usize
    }
}

/// Puts one fault of `kind` into `rows`, at a place drawn from `rng`; says what it did.
fn inject(kind: &str, rows: &mut Vec<ImuInput>, rng: &mut Lcg) -> String {
    let n = rows.len();
    let i = 200 + rng.below(n - 400);
    let (axis, pick, len) = (rng.below(3), rng.below(4), 1 + rng.below(300));
    let end = (i + len).min(n - 10);
    let u = rng.uniform();
    match kind {
        "gyro" | "accel" => {
            let v = [f64::NAN, 1e30, -30.0, 0.0][pick];
            let r = &mut rows[i];
            let x = if kind == "gyro" {
                &mut r.gyro_rad_s
            } else {
                &mut r.accel_m_s2
            };
            x[axis] = if kind == "accel" && pick == 2 {
                300.0
            } else {
                v
            };
            format!("{kind}[{axis}] = {v} at {i}")
        }
        "time" => {
            let d = (u - 0.5) * 4.0;
            rows[i].t_s += d;
            format!("stamp {d:+.3} s at {i}")
        }
        "time_absurd" => {
            rows[i].t_s = [f64::NAN, 0.0, 1e12, -5.0][pick];
            format!("stamp {} at {i}", rows[i].t_s)
        }
        "repeat" => {
            let r = rows[i];
            rows.insert(i, r);
            format!("repeated at {i}")
        }
        "swap" => {
            let j = i + 1 + pick;
            rows.swap(i, j);
            format!("swapped {i} and {j}")
        }
        "clock_step" => {
            let d = u - 0.5;
            for r in &mut rows[i..] {
                r.t_s += d;
            }
            format!("clock {d:+.3} s from {i}")
        }
        "zeros" => {
            for r in &mut rows[i..end] {
                r.gyro_rad_s = [0.0; 3];
                r.accel_m_s2 = [0.0; 3];
            }
            format!("{} zero samples at {i}", end - i)
        }
        "loss" => {
            rows.drain(i..end);
            format!("{} samples lost at {i}", end - i)
        }
        "late" => {
            // A loss, and one of the lost samples delivered late, up to 100 samples after.
            let lost: Vec<ImuInput> = rows.drain(i..end).collect();
            let late = lost[pick.min(lost.len() - 1) * lost.len() / 4];
            let at = (i + 1 + len % 100).min(rows.len() - 1);
            rows.insert(at, late);
            format!("{} samples lost at {i}, one of them late at {at}", end - i)
        }
        "glitch_run" => {
            let (end, d) = ((i + 1 + len % 50).min(n - 10), u * 3.0);
            for r in &mut rows[i..end] {
                r.t_s += d;
            }
            format!("{} stamps {d:+.2} s at {i}", end - i)
        }
        _ => "nothing".into(),
    }
}

/// The final position of `rows` through a fresh estimator.
fn final_position(cfg: &Config, rows: &[ImuInput]) -> anyhow::Result<[f64; 3]> {
    let mut est = Estimator::new(cfg.clone(), heading_aid(cfg, None)?);
    for s in rows {
        let _ = est.step(s);
    }
    Ok(est.last_estimate().p_m)
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let kind = args.next().unwrap_or_else(|| "glitch_run".into());
    anyhow::ensure!(
        KINDS.contains(&kind.as_str()),
        "unknown kind {kind:?}; one of {}",
        KINDS.join(", ")
    );
    let seeds: u64 = args.next().map_or(Ok(40), |s| s.parse())?;
    let walk = args
        .next()
        .unwrap_or_else(|| "gdins_exp36_corridor_out_and_back".into());
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let cfg = Config::from_file(&root.join("configs/gdins.toml"))?;
    let log = read_imu_csv(
        &root.join("tests/data").join(&walk).join("imu.csv"),
        &ImuCsvOptions::default(),
    )?;
    let clean: Vec<ImuInput> = log.rows.iter().map(ImuInput::from).collect();
    let p0 = final_position(&cfg, &clean)?;
    let mut offs = Vec::new();
    for seed in 0..seeds {
        let mut rng = Lcg(seed * 7919 + 1);
        let mut rows = clean.clone();
        let what = inject(&kind, &mut rows, &mut rng);
        let p = final_position(&cfg, &rows)?;
        let off = (p[0] - p0[0]).hypot(p[1] - p0[1]);
        println!(
            "{seed:4}  {off:7.2} m  (height {:+.2} m)  {what}",
            p[2] - p0[2]
        );
        offs.push(off);
    }
    offs.sort_by(f64::total_cmp);
    let at = |q: f64| offs[((offs.len() - 1) as f64 * q).round() as usize];
    println!(
        "{kind} on {walk}, {} places: final position off by median {:.2} m, 90th percentile {:.2} m, largest {:.2} m",
        offs.len(),
        at(0.5),
        at(0.9),
        at(1.0)
    );
    Ok(())
}
