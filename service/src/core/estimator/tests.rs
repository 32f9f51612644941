//! Unit tests of the estimator's per-sample pipeline; `tests/headings.rs` those of the external
//! headings, `tests/typical_bias.rs` those of the unit's typical bias.

use super::*;
use corridor_shared::config::{Config, ConfigFile, NonNegative};

fn level_rest(t_s: f64) -> ImuInput {
    ImuInput {
        t_s,
        gyro_rad_s: [0.0; 3],
        accel_m_s2: [0.0, 0.0, 9.81],
    }
}

/// 3 s of level rest with the gyro reading `bias`, then one moving sample (alignment ends).
fn rest_then_move(est: &mut Estimator, bias: [f64; 3]) -> Estimate {
    let dt = 0.005;
    for k in 0..600 {
        let s = ImuInput {
            t_s: k as f64 * dt,
            gyro_rad_s: bias,
            accel_m_s2: [0.0, 0.0, 9.81],
        };
        est.step(&s).unwrap();
    }
    let moving = ImuInput {
        t_s: 600.0 * dt,
        gyro_rad_s: [0.0, 3.0, 0.0],
        accel_m_s2: [0.0, 0.0, 9.81],
    };
    *est.step(&moving).unwrap()
}

#[test]
fn rotation_about_z_at_a_known_rate_gives_the_known_heading() {
    let mut est = Estimator::new(Config::default(), HeadingAid::None);
    let dt = 0.005;
    let mut k = 0;
    while k < 400 {
        est.step(&level_rest(k as f64 * dt)).unwrap();
        k += 1;
    }
    assert_eq!(est.phase(), Phase::Aligning);
    // 0.25 s at 4 rad/s about z: the heading turns by exactly 1 rad. (The rate is high
    // enough for the windowed detector to call the first rotating sample motion.)
    for _ in 0..50 {
        let s = ImuInput {
            t_s: k as f64 * dt,
            gyro_rad_s: [0.0, 0.0, 4.0],
            accel_m_s2: [0.0, 0.0, 9.81],
        };
        est.step(&s).unwrap();
        k += 1;
    }
    let e = est.step(&level_rest(k as f64 * dt)).unwrap();
    assert_eq!(e.phase, Phase::Calibrating);
    // 49 full steps plus half of the first and of the last step (trapezoid) = 50 steps.
    assert!((e.yaw_rad - 1.0).abs() < 1e-9, "yaw {}", e.yaw_rad);
    assert!(e.roll_rad.abs() < 1e-9 && e.pitch_rad.abs() < 1e-9);
}

#[test]
fn rest_mean_prior_recovers_a_static_bias() {
    let cfg = ConfigFile::default().validate().unwrap();
    // A still rest's mean is a measurement with the floor's σ, fused with the prior without a
    // rest (zero, `gyro_bias_initial_sd_rad_s`): nearly all of it is taken.
    let (floor, initial) = (
        cfg.eskf.gyro_bias_prior_sd_rad_s.get(),
        cfg.eskf.gyro_bias_initial_sd_rad_s.get(),
    );
    let gain = initial.powi(2) / (initial.powi(2) + floor.powi(2));
    assert!(gain > 0.99 && gain < 1.0, "{gain}");
    let bias = [0.004, -0.002, 0.006];
    let mut est = Estimator::new(cfg, HeadingAid::None);
    let e = rest_then_move(&mut est, bias);
    for (got, want) in e.gyro_bias_rad_s.iter().zip(bias) {
        assert!((got - gain * want).abs() < 1e-12, "{got} vs {want}");
    }
}

/// `n` samples from `t0_s` reading `gyro` and `accel` (level foot: gravity along z).
fn feed(est: &mut Estimator, t0_s: f64, n: usize, gyro: [f64; 3], accel: [f64; 3]) -> f64 {
    let dt = 0.005;
    for k in 0..n {
        let s = ImuInput {
            t_s: t0_s + k as f64 * dt,
            gyro_rad_s: gyro,
            accel_m_s2: accel,
        };
        est.step(&s).unwrap();
    }
    t0_s + n as f64 * dt
}

#[test]
fn a_short_first_stance_aligns_without_a_bias_prior_unless_switched_off() {
    let bias = [0.004, -0.002, 0.006];
    let (level, pushed) = ([0.0, 0.0, 9.81], [30.0, 0.0, 9.81]);
    for min_start_stance_s in [0.1, 0.0] {
        let mut cfg = Config::default();
        cfg.alignment.min_start_stance_s =
            NonNegative::new("alignment.min_start_stance_s", min_start_stance_s).unwrap();
        let mut est = Estimator::new(cfg, HeadingAid::None);
        // 0.2 s of stance (shorter than min_rest_s = 0.5 s), then the foot moves.
        let t = feed(&mut est, 0.0, 40, bias, level);
        let e = *est
            .step(&ImuInput {
                t_s: t,
                gyro_rad_s: bias,
                accel_m_s2: pushed,
            })
            .unwrap();
        if min_start_stance_s > 0.0 {
            assert_ne!(est.phase(), Phase::Aligning);
            assert!(est.counters().started_without_rest);
            // No rest-mean prior from a walking stance: the bias starts at zero.
            assert_eq!(e.gyro_bias_rad_s, [0.0; 3]);
        } else {
            assert_eq!(est.phase(), Phase::Aligning, "waits for a rest");
            assert_eq!(est.counters().alignment_restarts, 1);
        }
    }
}

/// A rest that ends too soon after a loss that came too soon starts the alignment again
/// once: the part after the loss, too short to start from as well, is not a second restart (it
/// was counted twice, a review found).
#[test]
fn an_alignment_started_again_after_a_loss_is_counted_once() {
    let (level, pushed) = ([0.0, 0.0, 9.81], [30.0, 0.0, 9.81]);
    let mut est = Estimator::new(Config::default(), HeadingAid::None);
    // 0.3 s of rest, 0.5 s lost, 0.05 s of rest (shorter than min_start_stance_s), then motion.
    let t = feed(&mut est, 0.0, 60, [0.0; 3], level);
    let t = feed(&mut est, t + 0.5, 10, [0.0; 3], level);
    assert_eq!(est.phase(), Phase::Aligning);
    assert_eq!(est.counters().gaps, 1, "the loss is counted");
    feed(&mut est, t, 1, [0.0, 3.0, 0.0], pushed);
    assert_eq!(
        est.phase(),
        Phase::Aligning,
        "waits for a stance to start from"
    );
    assert_eq!(est.counters().alignment_restarts, 1);
}

#[test]
fn a_later_rest_observes_the_bias_with_a_zero_rate_update() {
    let bias = [0.004, -0.002, 0.006];
    let (level, pushed) = ([0.0, 0.0, 9.81], [30.0, 0.0, 9.81]);
    let (mut z_error, mut y_error) = (Vec::new(), Vec::new());
    for zero_rate_updates in [true, false] {
        let mut cfg = Config::default();
        cfg.alignment.gyro_bias_prior = BiasPrior::None;
        cfg.eskf.zero_rate_updates = zero_rate_updates;
        let mut est = Estimator::new(cfg, HeadingAid::None);
        // Aligned on a 1 s rest without prior, a push, a landing (120 ms of the foot still
        // rolling at 0.25 rad/s) and a 2 s rest, a 0.1 s wobble (shorter than the merge gap:
        // the stance may still resume), a short stance, a push. The landing is the rest's first
        // 50 ms blocks: no reference for what is still (the initial rest's motion test, anchored
        // on the first block, left every quiet block out and the rest was never fused).
        let t = feed(&mut est, 0.0, 200, bias, level);
        let t = feed(&mut est, t, 10, bias, pushed);
        let landing = [bias[0], bias[1] + 0.25, bias[2]];
        let t = feed(&mut est, t, 24, landing, level);
        let t = feed(&mut est, t, 400, bias, level);
        let wobble = [bias[0], bias[1] + 2.0, bias[2]];
        let t = feed(&mut est, t, 20, wobble, level);
        let stances = est.counters().stances;
        let t = feed(&mut est, t, 30, bias, level);
        assert_eq!(
            est.counters().stances,
            stances,
            "one stance across the wobble"
        );
        let t = feed(&mut est, t, 1, bias, pushed);
        let e = *est
            .step(&ImuInput {
                t_s: t + 0.005,
                gyro_rad_s: bias,
                accel_m_s2: pushed,
            })
            .unwrap();
        // The rest before the wobble is tested at the wobble's first sample (a rest must be
        // uninterrupted); the short stance after it is no rest.
        let want = u64::from(zero_rate_updates);
        assert_eq!(est.counters().zero_rate_updates, want);
        z_error.push((e.gyro_bias_rad_s[2] - bias[2]).abs());
        y_error.push((e.gyro_bias_rad_s[1] - bias[1]).abs());
    }
    // The heading axis is unobservable by zero velocity alone: only the zero-rate update
    // finds its bias.
    assert!(z_error[0] < 5e-4, "with zero-rate update: {}", z_error[0]);
    assert!(z_error[1] > 3e-3, "without: {}", z_error[1]);
    // The landing is left out of the rest's mean (in it, it read as a y bias of 0.25 rad/s ×
    // 120 ms over the rest).
    assert!(y_error[0] < 5e-4, "the landing's axis: {}", y_error[0]);
}

#[test]
fn a_rest_through_which_the_foot_turns_slowly_is_not_taken_for_the_bias() {
    // A foot that pivots steadily at 0.3 rad/s passes the stance detector with a small rate
    // spread, so the rest's σ is small; its mean rate is not the bias. Fused, it pulled the
    // bias to the turn rate (or, past the bias limit, failed the health check at every sample
    // and froze the estimator).
    let bias = [0.004, -0.002, 0.006];
    let (level, pushed) = ([0.0, 0.0, 9.81], [30.0, 0.0, 9.81]);
    let turning = [bias[0], bias[1], bias[2] + 0.3];
    let mut est = Estimator::new(Config::default(), HeadingAid::None);
    let t = feed(&mut est, 0.0, 200, bias, level);
    let t = feed(&mut est, t, 10, bias, pushed);
    let t = feed(&mut est, t, 400, turning, level);
    let t = feed(&mut est, t, 10, bias, pushed);
    let t = feed(&mut est, t, 400, bias, level);
    let e = *est
        .step(&ImuInput {
            t_s: t,
            gyro_rad_s: bias,
            accel_m_s2: pushed,
        })
        .unwrap();
    let c = est.counters();
    assert_eq!((c.zero_rate_refused, c.health_restores), (1, 0), "{c:?}");
    // the quiet rest after it is fused
    assert_eq!(c.zero_rate_updates, 1, "{c:?}");
    assert!((e.gyro_bias_rad_s[2] - bias[2]).abs() < 1e-3, "{e:?}");
}

#[test]
fn a_clipped_gyro_axis_is_counted_and_widens_the_attitude_only_when_modelled() {
    let bias = [0.0; 3];
    let (level, pushed) = ([0.0, 0.0, 9.81], [30.0, 0.0, 9.81]);
    let mut roll = Vec::new();
    for sd in [0.5, 0.0] {
        let mut cfg = Config::default();
        cfg.eskf.clipped_rate_sd_rad_s =
            NonNegative::new("eskf.clipped_rate_sd_rad_s", sd).unwrap();
        let rail = cfg.sensor.gyro_range_rad_s();
        let mut est = Estimator::new(cfg, HeadingAid::None);
        let t = feed(&mut est, 0.0, 200, bias, level);
        // A swing with the x axis at its rail, then a long stance: the ZUPTs see the tilt
        // the unmeasured rotation would have caused and correct the attitude, more so when
        // its variance says that the attitude is uncertain.
        let t = feed(&mut est, t, 20, [rail, 0.0, 0.0], pushed);
        let t = feed(&mut est, t, 20, [-rail, 0.0, 0.0], pushed);
        feed(&mut est, t, 100, bias, level);
        assert_eq!(est.counters().clipped_samples, 40);
        roll.push(est.p.out.roll_rad);
    }
    assert_ne!(roll[0], roll[1], "the clipping model changes the estimate");
}

#[test]
fn a_rest_that_sways_gives_a_prior_as_uncertain_as_its_mean() {
    let cfg = ConfigFile::default().validate().unwrap();
    let floor = cfg.eskf.gyro_bias_prior_sd_rad_s.get();
    let initial = cfg.eskf.gyro_bias_initial_sd_rad_s.get();
    let mut est = Estimator::new(cfg, HeadingAid::None);
    // 3 s of "rest" whose x rate alternates ±0.05 rad/s every 0.25 s (a foot that sways
    // without the detector noticing), then motion.
    let level = [0.0, 0.0, 9.81];
    let mut t = 0.0;
    for k in 0..12 {
        let sway = if k % 2 == 0 { 0.05 } else { -0.05 };
        t = feed(&mut est, t, 50, [0.002 + sway, -0.001, 0.003], level);
    }
    feed(&mut est, t, 1, [0.0, 3.0, 0.0], level);
    let p = est.bias_state().unwrap().gyro_bias_cov;
    // x: 0.05 rad/s spread over √(number of 50 ms blocks) ≈ 5e-3, fused with the sensor's
    // spread of biases (0.01): ≈ 4.7e-3, ten times the floor; y, z still (within one step of
    // noise) at the floor.
    let x_sd = p[0][0].sqrt();
    assert!(x_sd > 4e-3 && x_sd < initial, "x σ {x_sd}");
    for axis in [1, 2] {
        assert!(
            p[axis][axis].sqrt() < 1.1 * floor,
            "axis {axis}: {}",
            p[axis][axis].sqrt()
        );
    }
}

#[test]
fn warm_start_takes_the_saved_state_fuses_a_fresh_rest_and_refuses_bad_states() {
    let bias = [0.004, -0.002, 0.006];
    // Within the gate of the fresh rest (σ 5e-4): 1-2σ away on each axis.
    let saved = WarmStart {
        gyro_bias_rad_s: [0.0035, -0.0015, 0.0052],
        gyro_bias_cov: [[1e-8, 0.0, 0.0], [0.0, 2e-8, 1e-9], [0.0, 1e-9, 3e-8]],
    };
    let mut est = Estimator::new(Config::default(), HeadingAid::None);
    let mut bad = saved;
    bad.gyro_bias_cov[0][0] = -1.0;
    assert!(est.set_warm_start(bad).is_err());
    bad = saved;
    bad.gyro_bias_rad_s[2] = f64::NAN;
    assert!(est.set_warm_start(bad).is_err());
    assert!(est.bias_state().is_none(), "no state before alignment");
    est.set_warm_start(saved).unwrap();
    rest_then_move(&mut est, bias);
    let state = est.bias_state().unwrap();
    // The fresh rest is fused into the saved state: each axis between the two (nearer the
    // saved one, whose σ, 1e-4, is below the rest's floor of 5e-4), its variance below the
    // saved one.
    for (k, &r) in bias.iter().enumerate() {
        let (s, got) = (saved.gyro_bias_rad_s[k], state.gyro_bias_rad_s[k]);
        assert!(
            (got - s) * (r - s) > 0.0 && (got - s).abs() < 0.5 * (r - s).abs(),
            "axis {k}: {got}"
        );
        assert!(state.gyro_bias_cov[k][k] < saved.gyro_bias_cov[k][k]);
    }
    assert_eq!(est.counters().zero_rate_refused, 0);
    // A saved state far beyond the rest's gate (the bias moved while the estimator was down):
    // the rest replaces it.
    let stale = WarmStart {
        gyro_bias_rad_s: [0.001, 0.002, 0.003],
        ..saved
    };
    let mut est = Estimator::new(Config::default(), HeadingAid::None);
    est.set_warm_start(stale).unwrap();
    rest_then_move(&mut est, bias);
    let state = est.bias_state().unwrap();
    assert_eq!(est.counters().zero_rate_refused, 1);
    for (k, &r) in bias.iter().enumerate() {
        assert!(
            (state.gyro_bias_rad_s[k] - r).abs() < 1e-4,
            "axis {k}: {state:?}"
        );
    }
    // Without a rest prior the saved state is taken as it is (one step of noise later).
    let mut cfg = Config::default();
    cfg.alignment.gyro_bias_prior = BiasPrior::None;
    let mut est = Estimator::new(cfg, HeadingAid::None);
    est.set_warm_start(saved).unwrap();
    rest_then_move(&mut est, bias);
    let state = est.bias_state().unwrap();
    assert_eq!(state.gyro_bias_rad_s, saved.gyro_bias_rad_s);
    assert!((state.gyro_bias_cov[1][2] - 1e-9).abs() < 1e-15);
    assert!(state.gyro_bias_cov[0][0] >= 1e-8 && state.gyro_bias_cov[0][0] < 1.01e-8);
}

#[test]
fn a_warm_start_handed_in_between_a_glitched_stamp_and_the_sample_that_exposes_it_is_kept() {
    let mut est = Estimator::new(Config::default(), HeadingAid::None);
    rest_then_move(&mut est, [0.004, -0.002, 0.006]);
    let moving = |t_s| ImuInput {
        t_s,
        gyro_rad_s: [0.0, 3.0, 0.0],
        accel_m_s2: [0.0, 0.0, 9.81],
    };
    // 0.9 s ahead: accepted as a gap, provisional.
    est.step(&moving(3.9)).unwrap();
    let saved = WarmStart {
        gyro_bias_rad_s: [0.001, 0.001, 0.001],
        gyro_bias_cov: [[1e-8, 0.0, 0.0], [0.0, 1e-8, 0.0], [0.0, 0.0, 1e-8]],
    };
    est.set_warm_start(saved).unwrap();
    // Goes back and follows the time before it: the 3.9 s sample is dropped, and the state
    // goes back to the copy before it, which had not seen the warm start.
    let e = *est.step(&moving(3.005)).unwrap();
    assert_eq!(e.glitch_t_s, Some(3.9));
    assert_eq!(est.counters().rejected_time_jump, 1);
    let state = est.bias_state().unwrap();
    for k in 0..3 {
        assert!(
            (state.gyro_bias_rad_s[k] - 0.001).abs() < 1e-6,
            "axis {k}: {state:?}"
        );
        assert!(state.gyro_bias_cov[k][k] < 1.1e-8, "axis {k}: {state:?}");
    }
}

#[test]
fn bad_samples_are_refused_counted_and_change_nothing() {
    let mut est = Estimator::new(Config::default(), HeadingAid::None);
    est.step(&level_rest(0.0)).unwrap();
    est.step(&level_rest(0.005)).unwrap();
    let mut nan = level_rest(0.01);
    nan.gyro_rad_s[1] = f64::NAN;
    let err = est.step(&nan).unwrap_err();
    assert!(err.to_string().contains("gy_rad_s"), "{err}");
    let err = est.step(&level_rest(0.005)).unwrap_err();
    assert!(matches!(err, SampleError::TimeNotIncreasing { prev_t_s, .. } if prev_t_s == 0.005));
    est.step(&level_rest(0.01)).unwrap();
    let c = est.counters();
    assert_eq!(
        (c.samples, c.rejected_non_finite, c.rejected_time),
        (3, 1, 1)
    );
}

/// A bad time stamp on the stream's very first sample (a daemon's producer that sends garbage
/// first): before, it became the time base and every later sample was refused as "not
/// increasing", for ever. Now the two samples after it, which follow each other, replace it:
/// the first sample is dropped after the fact and the estimator runs as on the clean stream.
#[test]
fn a_bad_first_time_stamp_is_dropped_once_the_next_samples_agree() {
    let rest_then_walk = |est: &mut Estimator, t0: usize| {
        let mut last = None;
        for k in t0..700 {
            let mut s = level_rest(k as f64 * 0.005);
            if k >= 600 {
                s.gyro_rad_s = [0.0, 3.0, 0.0];
            }
            last = Some(*est.step(&s).unwrap());
        }
        last.unwrap()
    };
    let mut clean = Estimator::new(Config::default(), HeadingAid::None);
    clean.step(&level_rest(0.005)).unwrap();
    let clean_last = rest_then_walk(&mut clean, 2);

    let mut est = Estimator::new(Config::default(), HeadingAid::None);
    est.step(&level_rest(1e9)).unwrap();
    assert!(matches!(
        est.step(&level_rest(0.0)),
        Err(SampleError::TimeNotIncreasing { .. })
    ));
    let e = *est.step(&level_rest(0.005)).unwrap();
    assert_eq!(e.replaced_first_t_s, Some(1e9));
    let last = rest_then_walk(&mut est, 2);
    assert_eq!(last.replaced_first_t_s, None);
    let c = est.counters();
    // 1e9 dropped (a time jump), 0.0 refused (not increasing), 0.005 … 3.495 s accepted.
    assert_eq!(
        (c.samples, c.rejected_time_jump, c.rejected_time),
        (699, 1, 1)
    );
    // The same stream as one that started at 0.005 s: the same estimate.
    assert_eq!(last.nav_from_body, clean_last.nav_from_body);
    assert_eq!(last.phase, clean_last.phase);
}

/// A stance that the detector splits (foot flat, a 0.1 s wobble, foot flat again) is one
/// stance: one `stance_began`, one count (one NavSample for the daemon's consumers). Without
/// merging it is two.
#[test]
fn a_stance_split_by_a_short_pause_is_one_stance() {
    let (level, spin) = ([0.0, 0.0, 9.81], [0.0, 2.0, 0.0]);
    for (merge_gap_s, want) in [(0.3, 1), (0.0, 2)] {
        let mut cfg = Config::default();
        cfg.detector.merge_gap_s = NonNegative::new("detector.merge_gap_s", merge_gap_s).unwrap();
        let mut est = Estimator::new(cfg, HeadingAid::None);
        let t = feed(&mut est, 0.0, 200, [0.0; 3], level); // aligning rest
        let t = feed(&mut est, t, 100, spin, level); // swing
        let before = est.counters().stances;
        let mut began = 0;
        let mut t_s = t;
        // stance 0.2 s, wobble 0.1 s, stance 0.2 s, swing 0.5 s
        for (n, gyro) in [(40, [0.0; 3]), (20, spin), (40, [0.0; 3]), (100, spin)] {
            for _ in 0..n {
                let e = est
                    .step(&ImuInput {
                        t_s,
                        gyro_rad_s: gyro,
                        accel_m_s2: level,
                    })
                    .unwrap();
                began += u64::from(e.stance_began);
                t_s += 0.005;
            }
        }
        assert_eq!(began, want, "merge gap {merge_gap_s}");
        assert_eq!(
            est.counters().stances - before,
            want,
            "merge gap {merge_gap_s}"
        );
    }
}

/// The runner and the daemon print an estimate's events through `Estimate::notices`: one
/// wording, and a bridged gap said as bridged (the daemon used to call every gap a new segment).
#[test]
fn an_estimate_says_its_events_once_in_one_wording() {
    let mut e = Estimate::default();
    assert_eq!(e.notices().count(), 0);
    e.gap_s = Some(0.1);
    e.gap_crossing = Some(GapCrossing::Bridged);
    e.velocity_reset = true;
    let said: Vec<String> = e.notices().map(|n| n.to_string()).collect();
    assert_eq!(said.len(), 2);
    assert_eq!(said[0], "gap of 0.100 s in the data; bridged by one step");
    assert!(said[1].ends_with("velocity reset"), "{}", said[1]);
    e.gap_s = Some(0.3);
    e.gap_crossing = Some(GapCrossing::Filled);
    e.velocity_reset = false;
    let said: Vec<String> = e.notices().map(|n| n.to_string()).collect();
    assert_eq!(
        said,
        ["gap of 0.300 s in the data; filled with the same phase of the stride before"]
    );
    e.gap_s = Some(10.0);
    e.gap_crossing = Some(GapCrossing::NewSegment);
    e.replaced_first_t_s = Some(1e9);
    let said: Vec<String> = e.notices().map(|n| n.to_string()).collect();
    assert!(
        said[0].ends_with("a new segment starts here"),
        "{}",
        said[0]
    );
    assert!(
        said[1].contains("1000000000 s was an outlier"),
        "{}",
        said[1]
    );
}

/// A start in fast gait that goes back to an earlier stance (`fast_start.rs`) leaves the
/// estimator as a live start on that stance would have: from the first estimate it gives on,
/// every estimate is the live start's, bit for bit, and so are the counts. The live start is
/// made by taking the gait as fast from the first sample (as the replay takes it over its
/// window), with the replay off. Both fast walks, cut where a daemon might have started while
/// the wearer walks (exp38 at 19.084 s is the stance end nearest 30 % of its footprints). A
/// replay that counted its stances by the current sample's stance events, not the replayed
/// sample's, took every replayed stance after the first for part of it (exp38 from 18.0 s:
/// estimates metres apart, a stance fewer).
#[test]
fn a_replayed_start_is_a_live_start_on_the_same_stance() {
    use corridor_shared::config::ConfigOverrides;
    use corridor_shared::imu_csv::{ImuCsvOptions, read_imu_csv};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let config = |replay_s: f64| {
        let path = root.join("configs/gdins.toml");
        let mut file = ConfigFile::read(&path).unwrap();
        file.alignment.fast_gait_replay_s = Some(replay_s);
        let o = ConfigOverrides {
            start_heading_deg: Some(0.0),
            ..Default::default()
        };
        o.validate(&file, &path).unwrap()
    };
    for (walk, cut_s) in [
        ("gdins_exp38_zigzag_extreme", 19.084),
        ("gdins_exp38_zigzag_extreme", 18.0),
        ("gdins_exp34_fast_out_and_back", 18.2),
    ] {
        let path = root.join("tests/data").join(walk).join("imu.csv");
        let log = read_imu_csv(&path, &ImuCsvOptions::default()).unwrap();
        let run = |cfg: Config, fast: bool| {
            let aid = crate::runner::heading_aid(&cfg, None).unwrap();
            let mut est = Estimator::new(cfg, aid);
            alignment::GAIT_TAKEN_AS_FAST.with(|c| c.set(fast));
            let out: Vec<Estimate> = (log.rows.iter())
                .filter(|r| r.t_s >= cut_s)
                .map(|r| *est.step(&ImuInput::from(r)).unwrap())
                .collect();
            alignment::GAIT_TAKEN_AS_FAST.with(|c| c.set(false));
            (out, *est.counters())
        };
        let (replayed, mut replayed_counts) = run(config(3.0), false);
        let (live, live_counts) = run(config(0.0), true);
        let started = |out: &[Estimate]| out.iter().position(|e| e.phase != Phase::Aligning);
        let (k, k_live) = (started(&replayed).unwrap(), started(&live).unwrap());
        let back_s = replayed_counts.start_replayed_ms as f64 * 1e-3;
        assert!(
            back_s > 0.3,
            "{walk} from {cut_s} s: went back {back_s:.3} s"
        );
        assert!(
            (replayed[k].t_s - live[k_live].t_s - back_s).abs() < 0.01,
            "{walk} from {cut_s} s: went back {back_s:.3} s from {:.3} s, the live start is at \
             {:.3} s",
            replayed[k].t_s,
            live[k_live].t_s
        );
        // The first estimate that differs, if any (the whole vectors are too long to print),
        // by their printed values: a rejected heading event's direction is NaN, never equal to
        // itself.
        let same = |a: &Estimate, b: &Estimate| format!("{a:?}") == format!("{b:?}");
        let differs = (k..replayed.len()).find(|&i| !same(&replayed[i], &live[i]));
        assert_eq!(
            differs.map(|i| (&replayed[i], &live[i])),
            None,
            "{walk} from {cut_s} s: replayed, then live"
        );
        replayed_counts.start_replayed_ms = 0;
        assert_eq!(replayed_counts, live_counts, "{walk} from {cut_s} s");
    }
}

#[test]
fn the_calibrated_mounting_yaw_gives_the_foot_axis_the_stride_heading_at_a_tilted_stance() {
    // The mounting yaw is learnt so that the foot-axis observation (the heading of the foot's
    // forward axis, `Eskf::predicted_heading`) reads the stride's direction at the stance it
    // is learnt on, also where that stance is tilted otherwise than the rest (a sensor that
    // sits rolled and pitched on the shoe, a foot flat on a slope or on its edge). At these
    // stances (2–5° from the rest's tilt) the stride's azimuth in the levelled sensor frame
    // leaves the foot axis up to 0.26° off the stride, the ZYX yaw of the attitude 0.05°.
    let cfg = ConfigFile::default().validate().unwrap();
    let mut est = Estimator::new(cfg, HeadingAid::None);
    let sensor_on_shoe = from_euler_zyx(0.3, -0.2, 0.0);
    let up_in_sensor = sensor_on_shoe.inverse() * Vector3::new(0.0, 0.0, 9.81);
    for k in 0..600 {
        let s = ImuInput {
            t_s: k as f64 * 0.005,
            gyro_rad_s: [0.0; 3],
            accel_m_s2: up_in_sensor.into(),
        };
        est.step(&s).unwrap();
    }
    let moving = ImuInput {
        t_s: 3.0,
        gyro_rad_s: [0.0, 3.0, 0.0],
        accel_m_s2: up_in_sensor.into(),
    };
    est.step(&moving).unwrap();
    let Stage::Running(eskf) = &mut est.stage else {
        panic!("not aligned after 3 s of rest")
    };
    let mut worst: f64 = 0.0;
    for (k, (d_roll, d_pitch)) in [(0.035, 0.0), (0.0, -0.035), (0.05, 0.08), (-0.09, 0.03)]
        .into_iter()
        .enumerate()
    {
        let psi = 0.7 + 1.9 * k as f64;
        let stride_rad = wrap_pi(psi - 0.4 + 0.3 * k as f64);
        eskf.nav_from_body = rot_z(psi) * from_euler_zyx(d_roll, d_pitch, 0.0) * est.p.tilt0;
        est.p.mount_yaw_rad = est.p.mount_yaw_of_stride(eskf, stride_rad);
        est.p.update_forward_body();
        let heading = eskf.predicted_heading(&est.p.foot_forward_body());
        worst = worst.max(wrap_pi(heading - stride_rad).abs());
    }
    assert!(
        worst < 1e-12,
        "the foot axis reads {worst:e} rad off the stride"
    );
}

mod headings;
mod typical_bias;

#[test]
fn a_refused_heading_is_said_with_its_values_in_short() {
    // σ = 1e300 was printed with its 301 digits (a review).
    let mut est = Estimator::new(Config::default(), HeadingAid::None);
    let err = est.queue_heading(0.0, 0.5, 1e300).unwrap_err().to_string();
    assert!(err.contains("σ 1e300 rad") && err.len() < 240, "{err}");
    assert_eq!(est.counters().headings_refused, 1);
}
