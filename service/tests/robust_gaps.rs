//! Time gaps (issue 9 item 4, issue 10): a step longer than `estimator.max_dt_s` starts a new
//! segment instead of being integrated as one long step.

use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::config::Config;
use corridor_shared::imu_csv::{ImuCsvOptions, ImuLog, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::truth_csv::read_truth_csv;
use std::path::{Path, PathBuf};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/gdins_exp36_corridor_out_and_back")
}

/// (sample time on the original clock, position, speed) of every estimate.
fn trace(log: &ImuLog, cfg: &Config, gap_at_s: f64, gap_s: f64) -> Vec<(f64, [f64; 3], f64)> {
    let aid = heading_aid(cfg, None).unwrap();
    let mut out = Vec::new();
    let c = run_log(log, cfg, &aid, &BiasInjection::default(), |_, e| {
        let t = if e.t_s >= gap_at_s + gap_s {
            e.t_s - gap_s
        } else {
            e.t_s
        };
        let v = e.v_m_s;
        out.push((t, e.p_m, (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()));
    })
    .counters;
    assert_eq!(c.gaps, u64::from(gap_s > 0.0));
    out
}

#[test]
fn a_ten_second_gap_changes_the_footprints_after_it_by_less_than_half_a_metre() {
    // Before: the gap was integrated as one 10 s step (vertical velocity −286 m/s).
    let log = read_imu_csv(&data().join("imu.csv"), &ImuCsvOptions::default()).unwrap();
    let truth = read_truth_csv(&data().join("ground_truth.csv")).unwrap();
    let cfg = Config::from_file(&data().join("../../../configs/gdins.toml")).unwrap();
    let clean = trace(&log, &cfg, f64::INFINITY, 0.0);
    // Mid-swing and at rest: several places.
    for k in [5003, 7010, 9001] {
        let gap_at_s = log.rows[k].t_s;
        let mut gapped = log.clone();
        for r in &mut gapped.rows[k..] {
            r.t_s += 10.0;
        }
        let got = trace(&gapped, &cfg, gap_at_s, 10.0);
        let worst_speed = got.iter().map(|g| g.2).fold(0.0, f64::max);
        assert!(
            worst_speed <= cfg.max_speed_m_s.get(),
            "k {k}: {worst_speed} m/s"
        );
        let at = |tr: &[(f64, [f64; 3], f64)], t: f64| {
            tr[tr.partition_point(|x| x.0 < t).min(tr.len() - 1)].1
        };
        let mut n = 0;
        for p in truth.iter().filter(|p| p.t_s > gap_at_s + 0.1) {
            let (a, b) = (at(&got, p.t_s), at(&clean, p.t_s));
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
            assert!(d < 0.5, "k {k}: footprint at {} s moved by {d} m", p.t_s);
            n += 1;
        }
        assert!(n > 10, "footprints after the gap: {n}");
    }
}
