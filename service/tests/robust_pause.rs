//! A walker who stops mid-walk: the later rest's zero-rate updates on measured data.
//!
//! No bundled walk has a rest after its start, so a pause is inserted at a walk's middle
//! footprint: that stance's quietest sample is held (its specific force the mean of the 11
//! samples around it), with the noise of the initial rest's quietest 0.5 s and, as the gyro
//! bias, the mean rate of that part of the initial rest; the samples after it move on by the
//! pause. The stance before the pause begins with the foot landing and rolling flat (exp40: 0.15
//! s at up to 0.2 rad/s on y): in the rest's mean it read as 1.5e-3 rad/s of y bias, beyond the
//! update's σ, and the update turned the heading by 3° (found so in session 22). A long pause was
//! fused only at its end, so the yaw integrated the difference between the walking bias and the
//! rest's rate, and its σ grew by the swing's gyro noise, for all of it (120 s into exp36: 1.4°,
//! and 12 heading observations in the walk instead of 33); now a rest is fused every
//! `eskf.zero_rate_interval_s` while it lasts, and at the sensor's own noise (session 23).

use corridor_service::core::Counters;
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

const DT_S: f64 = 0.005;
/// The stance updates after the foot's landing turn the yaw by up to 2° in the stance's first
/// second (exp36 at its turn), as at every stance: the pause's own drift is measured after it.
const SETTLED_S: f64 = 2.0;

/// `walk` with a pause of `pause_s`; the pause's mean rate and its first and last times.
fn paused(walk: &str, pause_s: f64) -> (ImuLog, Vector3<f64>, f64, f64) {
    let dir = root().join("tests/data").join(walk);
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
    let n = (pause_s / DT_S) as usize;
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
    (out, w_rest, t_k, t_k + pause_s)
}

fn config() -> corridor_shared::config::Config {
    let path = root().join("configs/gdins.toml");
    ConfigOverrides {
        start_heading_deg: Some(0.0),
        ..Default::default()
    }
    .validate(&ConfigFile::read(&path).unwrap(), &path)
    .unwrap()
}

/// The walk run with the default configuration: its counters, the yaw the pause from `t_start`
/// to `t_end` moved (from [`SETTLED_S`] in, once the landing's stance updates have done their
/// part, to its end), degrees, and the bias at its end.
fn over_the_pause(log: &ImuLog, t_start: f64, t_end: f64) -> (Counters, f64, [f64; 3]) {
    let cfg = config();
    let aid = heading_aid(&cfg, None).unwrap();
    let (mut yaw_start, mut at_end) = (None, None);
    let out = run_log(log, &cfg, &aid, &BiasInjection::default(), |s, e| {
        if s.t_s <= t_start + SETTLED_S {
            yaw_start = Some(e.yaw_rad);
        } else if s.t_s <= t_end {
            at_end = Some((e.gyro_bias_rad_s, e.yaw_rad));
        }
    });
    let (bias, yaw_end) = at_end.unwrap();
    (
        out.counters,
        (yaw_end - yaw_start.unwrap()).to_degrees(),
        bias,
    )
}

#[test]
fn a_pause_mid_walk_observes_the_bias_without_the_landing() {
    let (log, w_pause, t_start, t_end) = paused("gdins_exp40_serpentine_return", 20.0);
    let (counters, turn_deg, bias) = over_the_pause(&log, t_start, t_end);
    assert!(
        counters.zero_rate_updates >= 5,
        "the pause is fused as a rest while it lasts: {} updates",
        counters.zero_rate_updates
    );
    for axis in 0..3 {
        assert!(
            (bias[axis] - w_pause[axis]).abs() < 6e-4,
            "axis {axis}: bias {:.5} at the end of the rest, its mean rate {:.5}",
            bias[axis],
            w_pause[axis]
        );
    }
    assert!(
        turn_deg.abs() < 1.5,
        "the rest turned the heading by {turn_deg:.2}°"
    );
}

#[test]
fn a_long_pause_keeps_the_heading_and_its_observations() {
    // exp36: straight out and back, the pause at its turn. The rest's rate (the initial rest's)
    // differs from the bias the filter walked with by about 2e-3 rad/s on the vertical.
    let (log, _, t_start, t_end) = paused("gdins_exp36_corridor_out_and_back", 120.0);
    let (counters, turn_deg, _) = over_the_pause(&log, t_start, t_end);
    // The walk back is still aided as without the pause.
    let cfg = config();
    let (clean, _, _, _) = paused("gdins_exp36_corridor_out_and_back", 0.0);
    let clean = run_log(
        &clean,
        &cfg,
        &heading_aid(&cfg, None).unwrap(),
        &BiasInjection::default(),
        |_, _| {},
    );
    let used = |c: &Counters| c.heading_used + c.stride_used;
    println!(
        "yaw moved {turn_deg:.2}° over the pause; heading observations used {} (without the pause {})",
        used(&counters),
        used(&clean.counters)
    );
    assert!(
        turn_deg.abs() < 0.5,
        "the 120 s rest turned the heading by {turn_deg:.2}°"
    );
    assert!(
        used(&counters) + 3 >= used(&clean.counters),
        "heading observations used: {} with the pause, {} without",
        used(&counters),
        used(&clean.counters)
    );
}
