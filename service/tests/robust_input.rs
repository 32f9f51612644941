//! Faults in the input (issue 10, findings 2 and 3): absurd values and absurd times are refused,
//! counted, and leave the rest of the run as it would have been.

use corridor_service::core::{Estimator, ImuInput, Notice, Phase};
use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::config::Config;
use corridor_shared::imu_csv::{ImuCsvOptions, ImuLog, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn exp36() -> (ImuLog, Config) {
    let log = read_imu_csv(
        &root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv"),
        &ImuCsvOptions::default(),
    )
    .unwrap();
    let cfg = Config::from_file(&root().join("configs/gdins.toml")).unwrap();
    (log, cfg)
}

/// Final position and bias of `log` through the runner, and the estimator counters.
fn run(log: &ImuLog, cfg: &Config) -> Outcome {
    let aid = heading_aid(cfg, None).unwrap();
    let out = run_log(log, cfg, &aid, &BiasInjection::default(), |_, _| {});
    let n = out.trace.t_s.len();
    (
        out.trace.xy_m[n - 1],
        out.trace.bias_rad_s[n - 1],
        out.counters,
    )
}

fn close(a: [f64; 2], b: [f64; 2], tol_m: f64) -> bool {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt() < tol_m
}

#[test]
fn one_absurd_accel_and_one_absurd_gyro_are_refused_and_the_run_matches_the_clean_one() {
    let (log, cfg) = exp36();
    let (xy_clean, bias_clean, _) = run(&log, &cfg);
    let mut bad = log.clone();
    // Before: az = 1e30 gave positions of 1e26 m, and 1e300 turned the whole state NaN.
    bad.rows[5000].accel_m_s2[2] = 1e30;
    bad.rows[9000].gyro_rad_s[1] = 1e300;
    let (xy, bias, c) = run(&bad, &cfg);
    assert_eq!(c.rejected_implausible, 2);
    assert_eq!(c.samples, log.rows.len() as u64 - 2);
    assert!(close(xy, xy_clean, 0.5), "{xy:?} vs clean {xy_clean:?}");
    for k in 0..3 {
        assert!(
            (bias[k] - bias_clean[k]).abs() < 5e-4,
            "{bias:?} vs {bias_clean:?}"
        );
    }
}

#[test]
fn a_run_of_zero_filled_samples_is_refused_and_the_run_is_that_of_the_log_without_them() {
    // A driver that fills what it did not get with zeros (or a sensor that died for a second):
    // fused, 200 of them mid-swing were a free fall. Refused, the run is that of the log with
    // those rows cut out, bit for bit: a loss, crossed as any other.
    let (log, cfg) = exp36();
    let (at, len) = (7546, 200);
    let mut zeros = log.clone();
    for r in &mut zeros.rows[at..at + len] {
        r.gyro_rad_s = [0.0; 3];
        r.accel_m_s2 = [0.0; 3];
    }
    let mut cut = log.clone();
    cut.rows.drain(at..at + len);
    let aid = heading_aid(&cfg, None).unwrap();
    let with_zeros = run_log(&zeros, &cfg, &aid, &BiasInjection::default(), |_, _| {});
    let without = run_log(&cut, &cfg, &aid, &BiasInjection::default(), |_, _| {});
    assert_eq!(with_zeros.counters.rejected_implausible, len as u64);
    assert_eq!(with_zeros.counters.samples, without.counters.samples);
    assert_eq!(with_zeros.trace.xy_m, without.trace.xy_m);
    assert_eq!(with_zeros.trace.bias_rad_s, without.trace.bias_rad_s);
    // One zero on an axis, or five, is a measurement.
    let mut some = log.clone();
    some.rows[at].accel_m_s2 = [0.0; 3];
    some.rows[at + 1].gyro_rad_s = [0.0; 3];
    some.rows[at + 2].accel_m_s2[2] = 0.0;
    some.rows[at + 2].gyro_rad_s = [0.0; 3];
    let (_, _, c) = run(&some, &cfg);
    assert_eq!(c.rejected_implausible, 0);
    assert_eq!(c.samples, log.rows.len() as u64);
}

#[test]
fn an_absurd_time_in_a_stream_does_not_become_the_time_base() {
    // The daemon path: no CSV reader in front of the estimator.
    let (log, cfg) = exp36();
    let mut est = Estimator::new(cfg.clone(), heading_aid(&cfg, None).unwrap());
    let n = log.rows.len();
    let mut last = None;
    for (k, r) in log.rows.iter().enumerate() {
        let t_s = if k == n / 2 || k == n - 1 {
            1e30
        } else {
            r.t_s
        };
        let s = ImuInput {
            t_s,
            gyro_rad_s: r.gyro_rad_s,
            accel_m_s2: r.accel_m_s2,
        };
        if let Ok(e) = est.step(&s) {
            last = Some(*e);
        }
    }
    let c = est.counters();
    assert_eq!((c.rejected_time_jump, c.rejected_time), (2, 0));
    assert_eq!(c.samples, n as u64 - 2);
    let e = last.unwrap();
    assert!(
        e.t_s < 100.0 && e.p_m.iter().all(|p| p.abs() < 100.0),
        "{e:?}"
    );
}

#[test]
fn a_stream_in_g_is_not_aligned_on_and_says_so() {
    // The daemon path: no CSV reader (whose units check refuses such a log) in front of the
    // estimator. A stream in g aligned with gravity taken as 1 m/s² from its rest and walked
    // strides a tenth as long, with nothing said.
    let (log, cfg) = exp36();
    let mut est = Estimator::new(cfg.clone(), heading_aid(&cfg, None).unwrap());
    let mut said = Vec::new();
    for r in &log.rows {
        let s = ImuInput {
            t_s: r.t_s,
            gyro_rad_s: r.gyro_rad_s,
            accel_m_s2: r.accel_m_s2.map(|a| a / 9.80665),
        };
        let e = est.step(&s).unwrap();
        said.extend(
            e.notices()
                .filter(|n| matches!(n, Notice::NotGravity(..)))
                .map(|n| n.to_string()),
        );
        assert_eq!(est.phase(), Phase::Aligning, "aligned at {} s", r.t_s);
    }
    let c = est.counters();
    // The initial rest, then every stance of the walk (each a candidate first stance).
    assert!(c.alignment_not_gravity > 20, "{c:?}");
    assert_eq!(said.len() as u64, c.alignment_not_gravity);
    assert!(
        said[0].contains("a mean specific force of 1.00") && said[0].contains("in g"),
        "{}",
        said[0]
    );
    // In m/s² the same rest aligns.
    let mut est = Estimator::new(cfg.clone(), heading_aid(&cfg, None).unwrap());
    let aligned = log.rows.iter().any(|r| {
        let s = ImuInput {
            t_s: r.t_s,
            gyro_rad_s: r.gyro_rad_s,
            accel_m_s2: r.accel_m_s2,
        };
        est.step(&s).unwrap();
        est.phase() != Phase::Aligning
    });
    assert!(aligned && est.counters().alignment_not_gravity == 0);
}

#[test]
fn short_fast_gait_stances_with_a_scale_error_are_not_taken_for_a_stream_in_g() {
    // A walking stance reads far from gravity: a review found exp38's first stances after
    // 21.9 s at up to +22 %, and with a 3 % accelerometer scale error the first tolerance (±25 %)
    // refused them and lost 9 s of walking. A stream in g reads −90 %.
    let log = read_imu_csv(
        &root().join("tests/data/gdins_exp38_zigzag_extreme/imu.csv"),
        &ImuCsvOptions::default(),
    )
    .unwrap();
    let cfg = Config::from_file(&root().join("configs/gdins.toml")).unwrap();
    let mut est = Estimator::new(cfg.clone(), heading_aid(&cfg, None).unwrap());
    let aligned_at = log
        .rows
        .iter()
        .filter(|r| r.t_s >= 21.9)
        .find_map(|r| {
            let s = ImuInput {
                t_s: r.t_s,
                gyro_rad_s: r.gyro_rad_s,
                accel_m_s2: r.accel_m_s2.map(|a| a * 1.03),
            };
            est.step(&s).unwrap();
            (est.phase() != Phase::Aligning).then_some(r.t_s)
        })
        .unwrap();
    assert_eq!(est.counters().alignment_not_gravity, 0);
    assert!(aligned_at < 25.0, "aligned at {aligned_at} s");
}

#[test]
fn a_state_broken_by_a_sample_the_limits_let_through_falls_back_to_the_last_good_state() {
    // Limits as wide as the configuration takes, so that the plausibility check lets an
    // 800 g spike through: the health check after the update is what must catch it (before: positions of 1e26 m, or a NaN state with
    // `converged = 1`, and a garbage bias saved in the daemon's checkpoint).
    use corridor_shared::sensor::{MAX_ACCEL_RANGE_M_S2, MAX_GYRO_RANGE_RAD_S, MAX_NORM_FACTOR};
    let (log, mut cfg) = exp36();
    cfg.sensor = corridor_shared::sensor::SensorFile {
        // The widest the configuration takes (1e300 was taken before the ranges were
        // bounded): a single axis passes up to twice the range.
        max_accel_m_s2: Some(MAX_NORM_FACTOR * MAX_ACCEL_RANGE_M_S2),
        max_gyro_rad_s: Some(MAX_NORM_FACTOR * MAX_GYRO_RANGE_RAD_S),
        accel_range_m_s2: Some(MAX_ACCEL_RANGE_M_S2),
        gyro_range_rad_s: Some(MAX_GYRO_RANGE_RAD_S),
        ..Default::default()
    }
    .validate()
    .unwrap();
    let (xy_clean, bias_clean, _) = run(&log, &cfg);
    // Just within the widest axis limit, 8000 m/s² (1e4 and 1e6 were used before the ranges
    // were bounded). Not every spike the widest limits let through is undone so well: at 3.5e3,
    // 4e3, 5e3 and 6e3 m/s² the health check fires but the final position is 1-5 m off the
    // clean run's (a sensor's own limits refuse such spikes: ±16 g lets 314 m/s² through an
    // axis). (Not 1e30: the stance detector's running window sums would lose every small value
    // for the next 4096 samples; the plausibility check is what keeps such values out of them.)
    for value in [7.9e3] {
        let mut bad = log.clone();
        bad.rows[5000].accel_m_s2[2] = value;
        bad.rows[9000].accel_m_s2[0] = -value;
        let aid = heading_aid(&cfg, None).unwrap();
        let mut faults = 0;
        let mut worst_speed: f64 = 0.0;
        let mut prev: Option<([f64; 3], [f64; 3], [f64; 4])> = None;
        let mut undone_exactly = 0;
        let out = run_log(&bad, &cfg, &aid, &BiasInjection::default(), |_, e| {
            faults += usize::from(e.health_fault.is_some());
            // The first failed sample of a run is undone: the estimate is the state before it,
            // bit for bit (the filter propagates into a spare buffer that keeps that state).
            if let (Some(_), Some((p, v, q))) = (e.health_fault, prev) {
                assert_eq!((e.p_m, e.v_m_s, e.nav_from_body), (p, v, q));
                undone_exactly += 1;
            }
            prev = e
                .health_fault
                .is_none()
                .then_some((e.p_m, e.v_m_s, e.nav_from_body));
            let v = e.v_m_s;
            worst_speed = worst_speed.max((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt());
            assert!(
                e.p_m
                    .iter()
                    .chain(&e.gyro_bias_rad_s)
                    .all(|x| x.is_finite())
            );
        });
        let c = out.counters;
        assert!(undone_exactly >= 2, "{undone_exactly}");
        assert_eq!(c.rejected_implausible, 0);
        assert!(
            c.health_restores >= 2 && faults as u64 == c.health_restores,
            "{c:?}"
        );
        assert!(worst_speed <= cfg.max_speed_m_s.get(), "{worst_speed}");
        let n = out.trace.t_s.len();
        let (xy, bias) = (out.trace.xy_m[n - 1], out.trace.bias_rad_s[n - 1]);
        // The failed update is undone: as if the sample had been refused.
        assert!(
            close(xy, xy_clean, 0.5),
            "{value}: {xy:?} vs clean {xy_clean:?}"
        );
        for k in 0..3 {
            assert!(
                (bias[k] - bias_clean[k]).abs() < 5e-4,
                "{bias:?} vs {bias_clean:?}"
            );
        }
    }
}

#[test]
fn a_clean_recording_never_fails_the_health_check() {
    let (log, cfg) = exp36();
    let (_, _, c) = run(&log, &cfg);
    assert_eq!(c.health_restores, 0);
}

#[test]
fn a_burst_of_bad_samples_right_after_the_calibration_does_not_undo_it() {
    // The paper's and the rotation-aware modes get their heading observer when the mounting
    // yaw is calibrated, in the middle of a stance. A burst of samples that break the state
    // right after it made the health check restore the stance copy taken before it (or the
    // state before the calibrating sample): the phase stayed "tracking", the observer was
    // gone, and no heading was observed again (reviewer's demo: 0 of 12 on exp17).
    use corridor_service::core::Phase;
    use corridor_shared::config::Mode;
    let (log, mut cfg) = exp36();
    for mode in [Mode::Paper, Mode::RotationAware] {
        cfg.mode = mode;
        let aid = heading_aid(&cfg, None).unwrap();
        let mut calibrated_at = None;
        let clean = run_log(&log, &cfg, &aid, &BiasInjection::default(), |i, e| {
            if e.phase == Phase::Tracking && calibrated_at.is_none() {
                calibrated_at = Some(i.t_s);
            }
        });
        let t0 = calibrated_at.expect("calibrated") + 0.01;
        let mut bad = log.clone();
        for r in bad
            .rows
            .iter_mut()
            .filter(|r| (t0..t0 + 0.15).contains(&r.t_s))
        {
            // Within the limits (an axis beyond twice its range is refused as absurd).
            r.accel_m_s2 = [150.0, 0.0, 0.0];
        }
        let out = run_log(&bad, &cfg, &aid, &BiasInjection::default(), |_, _| {});
        let (c, c0) = (out.counters, clean.counters);
        assert!(
            c.health_restores > 3,
            "{mode:?}: the burst must fail the check: {c:?}"
        );
        assert!(
            c.heading_used * 10 >= c0.heading_used * 8,
            "{mode:?}: {} heading observations against {} on the clean walk",
            c.heading_used,
            c0.heading_used
        );
    }
}

/// A 0.1 s burst of garbage vertical force (60 m/s², within the sensor's limits, so accepted)
/// just after a footfall of exp17 builds a velocity of about 5 m/s that the next stance update
/// finds. Before, that update turned the attitude and the bias by what only the velocity got
/// wrong: the bias ended at [−0.013, −0.011, 0.014] rad/s against [0.0004, −0.0027, 0.0043]
/// clean, and 1 heading observation was used instead of 11. Now the velocity is reset first
/// (counted), and the bias and the heading aid carry on as on the clean walk; the position
/// keeps what the burst did to it (nothing tells how long the wrong velocity lasted).
#[test]
fn a_burst_of_garbage_force_resets_the_velocity_and_spares_the_bias_and_heading() {
    let ((_, bias_clean, c_clean), (_, bias, c)) = exp17_with_a_burst(7.5, 60.0);
    assert_eq!((c_clean.velocity_resets, c.velocity_resets), (0, 1));
    for k in 0..3 {
        assert!(
            (bias[k] - bias_clean[k]).abs() < 5e-4,
            "{bias:?} vs clean {bias_clean:?}"
        );
    }
    assert!(
        c.heading_used + 1 >= c_clean.heading_used,
        "{} heading observations used, {} on the clean walk",
        c.heading_used,
        c_clean.heading_used
    );
}

/// A burst of garbage force (150 m/s² on z for 0.1 s, within the limits) in exp17's first
/// corner fails the health check until the state of the last healthy stance is restored. That
/// state holds the heading from before the corner: before, the heading stayed about 80° off for
/// the rest of the walk and outside the association's gate (1 heading observation used instead
/// of 11, 27 % of path).
/// Now the turn the gyro measured since that stance is added back.
///
/// The restored state is from before the stance's footprint was cloned: the footprints the
/// stride observations had recorded since no longer match the filter's, and are forgotten
/// (before, the next stance observed one stride judged by the next one's line test and turn,
/// and the one after a double stride).
///
/// The restored heading is still about 7° off, by more than its variance says, so the strides
/// after it run off the corridor with the foot: the foot-axis stride test
/// (`heading.foot_axis_stride_max_deg`) would refuse the foot axes that bring it back (7
/// heading observations, 3.4 % of path, instead of 11 and 2.9 %). It waits until a stride runs
/// along its corridor again.
#[test]
fn a_state_restored_in_a_turn_keeps_the_turn() {
    let ((_, _, c_clean), (_, _, c)) = exp17_with_a_burst(7.7, 150.0);
    assert!(
        c.health_restores > MAX_UNDONE,
        "{} restores",
        c.health_restores
    );
    assert_eq!(c_clean.footprints_forgotten, 0);
    assert!(c.footprints_forgotten >= 1, "{c:?}");
    assert!(
        c.heading_used + 1 >= c_clean.heading_used,
        "{} heading observations used, {} on the clean walk",
        c.heading_used,
        c_clean.heading_used
    );
}

type Outcome = ([f64; 2], [f64; 3], corridor_service::core::Counters);

/// exp17 through the runner clean, and with the vertical force replaced by `accel_z_m_s2` for
/// the 0.1 s from `t0_s`.
fn exp17_with_a_burst(t0_s: f64, accel_z_m_s2: f64) -> (Outcome, Outcome) {
    let log = read_imu_csv(
        &root().join("tests/data/gdins_exp17_rect_loop_small/imu.csv"),
        &ImuCsvOptions::default(),
    )
    .unwrap();
    let cfg = Config::from_file(&root().join("configs/gdins.toml")).unwrap();
    let mut bad = log.clone();
    for r in bad
        .rows
        .iter_mut()
        .filter(|r| (t0_s..t0_s + 0.1).contains(&r.t_s))
    {
        r.accel_m_s2[2] = accel_z_m_s2;
    }
    (run(&log, &cfg), run(&bad, &cfg))
}

/// Failed checks in a row that only undo their update (the estimator's `MAX_UNDONE_UPDATES`):
/// more restore the last healthy stance.
const MAX_UNDONE: u64 = 3;
