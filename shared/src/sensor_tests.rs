//! The time rule ([`TimeGuard`]), time by time, and the limits' validation.

use super::*;

fn run(times: &[f64]) -> Vec<TimeVerdict> {
    let mut g = TimeGuard::new(1e-6, 1.0, 0.05);
    times
        .iter()
        .map(|&t| {
            let v = g.check(t);
            if matches!(
                v,
                TimeVerdict::Accept
                    | TimeVerdict::NewBase
                    | TimeVerdict::Rebase
                    | TimeVerdict::Glitch
                    | TimeVerdict::GlitchRun
                    | TimeVerdict::StepBack
            ) {
                g.accept(t);
            }
            v
        })
        .collect()
}

#[test]
fn an_outlier_time_is_refused_and_the_good_rows_after_it_are_kept() {
    use TimeVerdict::*;
    assert_eq!(
        run(&[0.0, 0.01, 1e30, 0.02, 0.03]),
        [Accept, Accept, Jump, Accept, Accept]
    );
    assert_eq!(run(&[0.0, 0.01, 1e30]), [Accept, Accept, Jump]);
}

#[test]
fn a_real_gap_costs_one_sample_then_becomes_the_time_base() {
    use TimeVerdict::*;
    assert_eq!(
        run(&[0.0, 0.01, 10.0, 10.01, 10.02]),
        [Accept, Accept, Jump, NewBase, Accept]
    );
    assert_eq!(
        run(&[0.0, 0.01, 0.01, 0.005]),
        [Accept, Accept, NotIncreasing, NotIncreasing]
    );
}

#[test]
fn a_bad_first_time_is_replaced_by_the_two_rows_after_it() {
    use TimeVerdict::*;
    // Far in the future: before, every later row was "not increasing".
    assert_eq!(
        run(&[1e9, 0.005, 0.010, 0.015]),
        [Accept, NotIncreasing, Rebase, Accept]
    );
    // Far in the past: the two rows after it agree, so it goes (a real gap after a good
    // first row would need that row followed first).
    assert_eq!(run(&[-50.0, 0.0, 0.005]), [Accept, Jump, Rebase]);
    // A good first time followed by an outlier: nothing is replaced.
    assert_eq!(
        run(&[0.0, 0.005, -3.0, 0.010]),
        [Accept, Accept, NotIncreasing, Accept]
    );
    // Going back beyond max_dt_s is never confirmed once the base was followed.
    assert_eq!(
        run(&[0.0, 0.005, -3.0, -2.995]),
        [Accept, Accept, NotIncreasing, NotIncreasing]
    );
}

#[test]
fn a_single_stamp_ahead_is_a_glitch_and_the_good_times_after_it_are_kept() {
    use TimeVerdict::*;
    // One stamp 0.9 s ahead (within max_dt_s, so accepted as a gap): the next time goes
    // back and follows the one before it. Before, it and every time up to 0.9 s were
    // "not increasing".
    assert_eq!(
        run(&[0.0, 0.005, 0.905, 0.010, 0.015]),
        [Accept, Accept, Accept, Glitch, Accept]
    );
    // A real gap: the next time follows its far side.
    assert_eq!(
        run(&[0.0, 0.005, 0.905, 0.910, 0.915]),
        [Accept, Accept, Accept, Accept, Accept]
    );
    // Only the time right before the gap is a glitch's base, and only within gap_dt_s.
    assert_eq!(
        run(&[0.0, 0.005, 0.905, 0.2, 0.910]),
        [Accept, Accept, Accept, NotIncreasing, Accept]
    );
    // Two or more stamps in a row a gap's length ahead: once the far side is followed, the
    // run stays open, and a time that goes back and follows the one before the gap shows
    // them to be glitched stamps (session 37; before, they were taken for a gap and the good
    // times after them refused as not increasing, up to the glitch's length).
    // The clock comes back where the sample after the two would be (0.020).
    assert_eq!(
        run(&[0.0, 0.005, 0.905, 0.910, 0.020]),
        [Accept, Accept, Accept, Accept, GlitchRun]
    );
    let mut g = TimeGuard::new(1e-6, 1.0, 0.05);
    for t in [0.0, 0.005, 0.905, 0.910, 0.915] {
        assert!(matches!(g.check(t), Accept));
        g.accept(t);
    }
    let r = g.jump_run().expect("the run after the gap's far side");
    assert_eq!((r.before_s, r.first_s, r.samples), (0.005, 0.905, 3));
    assert_eq!(g.check(0.025), GlitchRun);
    // A sample lost in a real gap and delivered late lies anywhere in the gap: it is refused,
    // not taken for the clock's return (a review: it dropped every good sample since the
    // gap). Samples 0.010..0.900 lost, 0.905.. read; 0.300 comes late, 20 samples on.
    let mut g = TimeGuard::new(1e-6, 1.0, 0.05);
    for k in [0, 1].into_iter().chain(181..201) {
        let t = 0.005 * k as f64;
        assert!(matches!(g.check(t), Accept), "{t}");
        g.accept(t);
    }
    assert_eq!(g.check(0.300), NotIncreasing);
    // The return of a glitched run of 20 is one sample after the time before it plus 20.
    assert_eq!(g.check(0.005 * 22.0), GlitchRun);
    // A real gap: its run closes once the times have run on for max_dt_s, and going back
    // after that is refused as before.
    let mut times = vec![0.0, 0.005];
    times.extend((0..=210).map(|k| 0.905 + 0.005 * k as f64));
    let mut g = TimeGuard::new(1e-6, 1.0, 0.05);
    for &t in &times {
        assert!(matches!(g.check(t), Accept));
        g.accept(t);
    }
    assert!(g.jump_run().is_none(), "closed after max_dt_s");
    assert_eq!(g.check(0.010), NotIncreasing);
    // A step within gap_dt_s is never provisional.
    assert_eq!(
        run(&[0.0, 0.005, 0.045, 0.010]),
        [Accept, Accept, Accept, NotIncreasing]
    );
    // A glitch on the second time, and one on the sample right after a gap's far side:
    // before, the good times after either were refused.
    assert_eq!(run(&[0.0, 0.9, 0.005]), [Accept, Accept, Glitch]);
    assert_eq!(
        run(&[0.0, 0.005, 0.5, 1.3, 0.505]),
        [Accept, Accept, Accept, Accept, Glitch]
    );
    // A time replacing a bad first time is not provisional (one after a confirmed jump
    // opens a run: the next test).
    assert_eq!(
        run(&[-50.0, 0.0, 0.005, -49.99]),
        [Accept, Jump, Rebase, NotIncreasing]
    );
}

#[test]
fn two_or_more_stamps_beyond_max_dt_are_a_glitched_run_when_the_time_comes_back() {
    use TimeVerdict::*;
    // Two stamps 10 s ahead, then the time before them runs on. Before, the second
    // confirmed the jump and every later time was "not increasing": the rest of a log.
    assert_eq!(
        run(&[0.0, 0.005, 10.0, 10.005, 0.015, 0.020]),
        [Accept, Accept, Jump, NewBase, GlitchRun, Accept]
    );
    // Four ahead; and back from behind (a good time may come at most max_dt_s after the
    // time before the jump).
    assert_eq!(
        run(&[0.0, 0.005, 1e6, 1e6 + 0.005, 1e6 + 0.01, 1e6 + 0.015, 0.03]),
        [Accept, Accept, Jump, NewBase, Accept, Accept, GlitchRun]
    );
    assert_eq!(
        run(&[0.0, 0.005, 10.0, 10.005, 1.2]),
        [Accept, Accept, Jump, NewBase, NotIncreasing]
    );
    // A real gap: the run closes once the new base has run on for max_dt_s; a time that
    // goes back after it is refused as before.
    let mut times = vec![0.0, 0.005];
    times.extend((0..=210).map(|k| 10.0 + 0.005 * f64::from(k)));
    times.push(0.010);
    let verdicts = run(&times);
    assert_eq!(verdicts[2..4], [Jump, NewBase]);
    assert!(verdicts[4..213].iter().all(|&v| v == Accept));
    assert_eq!(verdicts[213], NotIncreasing);
    // A second jump within the run: still one run, from the time before the first (a
    // review: the second opened a run of its own, from a glitched time).
    assert_eq!(
        run(&[0.0, 0.005, 10.0, 10.005, 20.0, 20.005, 0.03, 0.035]),
        [
            Accept, Accept, Jump, NewBase, Jump, NewBase, GlitchRun, Accept
        ]
    );
    // ... as it closes at a gap or a step back within the run.
    assert_eq!(
        run(&[0.0, 0.005, 10.0, 10.005, 10.5, 0.010]),
        [Accept, Accept, Jump, NewBase, Accept, NotIncreasing]
    );
    let mut g = TimeGuard::new(1e-6, 1.0, 0.05);
    for t in [0.0, 0.005] {
        g.check(t);
        g.accept(t);
    }
    assert_eq!((g.check(10.0), g.check(10.005)), (Jump, NewBase));
    g.accept(10.005);
    assert_eq!(
        g.jump_run(),
        Some(JumpRun {
            before_s: 0.005,
            first_s: 10.005,
            base_s: 10.005,
            samples: 1,
            after_gap: false,
        })
    );
    assert_eq!((g.check(9.9), g.check(9.905)), (NotIncreasing, StepBack));
    g.accept(9.905);
    assert_eq!(g.jump_run(), None);
    assert_eq!(g.check(0.010), NotIncreasing);
}

#[test]
fn a_clock_that_steps_back_within_max_dt_is_a_step_back_the_caller_may_take() {
    use TimeVerdict::*;
    // Set back by 0.3 s and running on: the first time after the step is refused, the
    // second follows it. Before, every time up to 0.3 s was "not increasing".
    assert_eq!(
        run(&[0.0, 0.005, 0.010, -0.285, -0.280, -0.275]),
        [Accept, Accept, Accept, NotIncreasing, StepBack, Accept]
    );
    // Not taken by the caller: every time that follows is a step back again, until one
    // follows the base.
    let mut g = TimeGuard::new(1e-6, 1.0, 0.05);
    for t in [0.0, 0.005, 0.010] {
        g.check(t);
        g.accept(t);
    }
    assert_eq!(g.check(0.0), NotIncreasing);
    assert_eq!(g.check(0.005), StepBack);
    assert_eq!(g.check(0.010), StepBack);
    assert_eq!(g.check(0.015), Accept);
    // A stray earlier stamp is not a step (the next time follows the base), and neither is
    // a step back beyond max_dt_s (a restarted clock), nor a duplicate followed by the base.
    assert_eq!(
        run(&[0.0, 0.005, -0.5, 0.010]),
        [Accept, Accept, NotIncreasing, Accept]
    );
    assert_eq!(
        run(&[0.0, 0.005, 0.010, -1.5, -1.495]),
        [Accept, Accept, Accept, NotIncreasing, NotIncreasing]
    );
    // ... also once such times have come within max_dt_s of the base.
    assert_eq!(
        run(&[0.0, 0.005, 0.010, -1.5, -0.5, -0.495, 0.015]),
        [
            Accept,
            Accept,
            Accept,
            NotIncreasing,
            NotIncreasing,
            NotIncreasing,
            Accept
        ]
    );
    assert_eq!(
        run(&[0.0, 0.005, 0.005, 0.010]),
        [Accept, Accept, NotIncreasing, Accept]
    );
    // A stray earlier stamp between a real gap's far side and the time that confirms it
    // leaves the gap's candidate (a review found it replaced: one more row lost).
    assert_eq!(
        run(&[0.0, 0.005, 0.010, 5.0, 0.007, 5.005, 5.010]),
        [Accept, Accept, Accept, Jump, NotIncreasing, NewBase, Accept]
    );
}

#[test]
fn provisional_says_whether_the_last_time_came_after_a_gap() {
    let mut g = TimeGuard::new(1e-6, 1.0, 0.05);
    for t in [0.0, 0.005] {
        assert_eq!(g.check(t), TimeVerdict::Accept);
        g.accept(t);
        assert!(!g.provisional());
    }
    assert_eq!(g.check(0.5), TimeVerdict::Accept);
    g.accept(0.5);
    assert!(g.provisional());
    assert_eq!(g.check(0.0), TimeVerdict::NotIncreasing);
    assert!(g.provisional(), "a refused time decides nothing");
    assert_eq!(g.check(0.010), TimeVerdict::Glitch);
    g.accept(0.010);
    assert!(!g.provisional());
    assert_eq!(g.last_s(), Some(0.010));
}

#[test]
fn bad_limits_name_the_key() {
    let f = SensorFile {
        max_gyro_rad_s: Some(1.0),
        gyro_range_rad_s: Some(8.73),
        ..Default::default()
    };
    assert_eq!(f.validate().unwrap_err().key, "sensor.max_gyro_rad_s");
    let f = SensorFile {
        min_dt_s: Some(f64::NAN),
        ..Default::default()
    };
    assert_eq!(f.validate().unwrap_err().key, "sensor.min_dt_s");
    let l = SensorLimits::default();
    assert_eq!(l.max_dt_s(), DEFAULT_MAX_DT_S);
}

#[test]
fn limits_no_foot_imu_can_have_are_refused_with_key_and_value() {
    // A review: 1e30 rad/s was taken as the gyro range (and its plausible magnitude), which
    // turned the clipping flag and the plausibility check off without a word.
    let cases: [(SensorFile, &str, &str); 9] = [
        (
            SensorFile {
                gyro_range_rad_s: Some(1e30),
                max_gyro_rad_s: Some(1e30),
                ..Default::default()
            },
            "sensor.gyro_range_rad_s",
            "1e30",
        ),
        (
            SensorFile {
                gyro_range_rad_s: Some(0.5),
                ..Default::default()
            },
            "sensor.gyro_range_rad_s",
            "0.5",
        ),
        (
            SensorFile {
                accel_range_m_s2: Some(1e30),
                max_accel_m_s2: Some(1e30),
                ..Default::default()
            },
            "sensor.accel_range_m_s2",
            "1e30",
        ),
        (
            SensorFile {
                accel_range_m_s2: Some(9.81),
                ..Default::default()
            },
            "sensor.accel_range_m_s2",
            "9.81",
        ),
        (
            SensorFile {
                max_gyro_rad_s: Some(1e30),
                ..Default::default()
            },
            "sensor.max_gyro_rad_s",
            "1e30",
        ),
        (
            SensorFile {
                max_accel_m_s2: Some(2e4),
                ..Default::default()
            },
            "sensor.max_accel_m_s2",
            "20000",
        ),
        (
            SensorFile {
                min_dt_s: Some(0.005),
                ..Default::default()
            },
            "sensor.min_dt_s",
            "0.005",
        ),
        (
            SensorFile {
                max_dt_s: Some(1e30),
                ..Default::default()
            },
            "sensor.max_dt_s",
            "1e30",
        ),
        (
            SensorFile {
                gyro_range_rad_s: Some(f64::INFINITY),
                ..Default::default()
            },
            "sensor.gyro_range_rad_s",
            "inf",
        ),
    ];
    for (f, key, shown) in cases {
        let e = f.validate().unwrap_err();
        assert_eq!(e.key, key, "{f:?}: {e:?}");
        assert!(e.value.starts_with(shown), "{f:?}: {e:?}");
    }
    // The bounds themselves pass, and the widest sensor with its largest magnitudes.
    let widest = SensorFile {
        gyro_range_rad_s: Some(MAX_GYRO_RANGE_RAD_S),
        accel_range_m_s2: Some(MAX_ACCEL_RANGE_M_S2),
        max_gyro_rad_s: Some(MAX_NORM_FACTOR * MAX_GYRO_RANGE_RAD_S),
        max_accel_m_s2: Some(MAX_NORM_FACTOR * MAX_ACCEL_RANGE_M_S2),
        min_dt_s: Some(MAX_MIN_DT_S),
        max_dt_s: Some(MAX_MAX_DT_S),
        ..Default::default()
    };
    widest.validate().unwrap();
    let narrowest = SensorFile {
        gyro_range_rad_s: Some(MIN_GYRO_RANGE_RAD_S),
        accel_range_m_s2: Some(MIN_ACCEL_RANGE_M_S2),
        ..Default::default()
    };
    narrowest.validate().unwrap();
    assert_eq!(MAX_NORM_FACTOR, AXIS_ABSURD_FACTOR * 3f64.sqrt());
}
