//! A walker who stops mid-walk: the later rest's zero-rate update on measured data.
//!
//! No bundled walk has a rest after its start, so a 20 s pause is inserted into exp40 at its
//! middle footprint: that stance's quietest sample is held (its specific force the mean of the
//! 11 samples around it), with the noise of the initial rest's quietest 0.5 s and, as the gyro
//! bias, the mean rate of that part of the initial rest; the samples after it move on by 20 s.
//! The stance before the pause begins with the foot landing and rolling flat (0.15 s at up to
//! 0.2 rad/s on y): in the rest's mean it read as 1.5e-3 rad/s of y bias, beyond the update's σ,
//! and the update turned the heading by 3° (found so in session 22).

use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::config::{ConfigFile, ConfigOverrides};
use corridor_shared::imu_csv::{ImuCsvOptions, ImuLog, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::truth_csv::read_truth_csv;
use nalgebra::Vector3;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

const PAUSE_S: f64 = 20.0;
const DT_S: f64 = 0.005;

/// exp40 with the pause; the pause's mean rate and its first and last times.
fn paused_exp40() -> (ImuLog, Vector3<f64>, f64, f64) {
    let dir = root().join("tests/data/gdins_exp40_serpentine_return");
    let log = read_imu_csv(&dir.join("imu.csv"), &ImuCsvOptions::default()).unwrap();
    let truth = read_truth_csv(&dir.join("ground_truth.csv")).unwrap();
    let rate = |i: usize| Vector3::from(log.rows[i].gyro_rad_s);
    let force = |i: usize| Vector3::from(log.rows[i].accel_m_s2);
    // The quietest 0.5 s of the first 2 s (exp40's rest opens rocking).
    let spread = |i0: usize| -> f64 {
        let mean = (i0..i0 + 100).map(rate).sum::<Vector3<f64>>() / 100.0;
        (i0..i0 + 100)
            .map(|i| (rate(i) - mean).norm_squared())
            .sum()
    };
    let quiet = (0..300)
        .step_by(10)
        .min_by(|&a, &b| spread(a).total_cmp(&spread(b)));
    let quiet = quiet.unwrap();
    let rest = quiet..quiet + 100;
    let w_rest = rest.clone().map(rate).sum::<Vector3<f64>>() / 100.0;
    let f_rest = rest.clone().map(force).sum::<Vector3<f64>>() / 100.0;
    // The quietest sample within 0.15 s of the middle footprint.
    let t_mid = truth[truth.len() / 2].t_s;
    let k = (0..log.rows.len())
        .filter(|&i| (log.rows[i].t_s - t_mid).abs() < 0.15)
        .min_by(|&a, &b| rate(a).norm().total_cmp(&rate(b).norm()))
        .unwrap();
    let f_held = (k - 5..=k + 5).map(force).sum::<Vector3<f64>>() / 11.0;
    let n = (PAUSE_S / DT_S) as usize;
    let t_k = log.rows[k].t_s;
    let mut out = log.clone();
    let pause = (0..n).map(|m| {
        let r = &log.rows[rest.start + m % 100];
        let mut row = *r;
        row.t_s = t_k + (m + 1) as f64 * DT_S;
        row.accel_m_s2 = (f_held + Vector3::from(r.accel_m_s2) - f_rest).into();
        row
    });
    let after: Vec<_> = log.rows[k + 1..]
        .iter()
        .map(|r| {
            let mut r = *r;
            r.t_s += n as f64 * DT_S;
            r
        })
        .collect();
    out.rows.truncate(k + 1);
    out.rows.extend(pause);
    out.rows.extend(after);
    (out, w_rest, t_k, t_k + PAUSE_S)
}

#[test]
fn a_pause_mid_walk_observes_the_bias_without_the_landing() {
    let (log, w_pause, t_start, t_end) = paused_exp40();
    let path = root().join("configs/gdins.toml");
    let cfg = ConfigOverrides {
        start_heading_deg: Some(0.0),
        ..Default::default()
    }
    .validate(&ConfigFile::read(&path).unwrap(), &path)
    .unwrap();
    let aid = heading_aid(&cfg, None).unwrap();
    // The update is the sample after the pause whose bias σ falls to less than half (the
    // bias is not known to better than 3e-3 rad/s on this walk by then): the bias it gives, and
    // the yaw it moved.
    let mut before: Option<(f64, f64)> = None;
    let mut update = None;
    let out = run_log(&log, &cfg, &aid, &BiasInjection::default(), |s, e| {
        let sd = e.gyro_bias_sd_rad_s[0];
        if let Some((sd_before, yaw_before)) = before
            && update.is_none()
            && s.t_s > t_end
            && sd < 0.5 * sd_before
        {
            update = Some((e.gyro_bias_rad_s, e.yaw_rad - yaw_before));
        }
        if s.t_s > t_start {
            before = Some((sd, e.yaw_rad));
        }
    });
    assert_eq!(
        out.counters.zero_rate_updates, 1,
        "the pause is fused as a rest"
    );
    let (bias, turn_rad) = update.expect("the update narrows the bias");
    for axis in 0..3 {
        assert!(
            (bias[axis] - w_pause[axis]).abs() < 6e-4,
            "axis {axis}: bias {:.5} after the rest, its mean rate {:.5}",
            bias[axis],
            w_pause[axis]
        );
    }
    let turn_deg = turn_rad.to_degrees();
    assert!(
        turn_deg.abs() < 1.5,
        "the rest turned the heading by {turn_deg:.2}°"
    );
}
