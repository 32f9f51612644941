//! The external headings' path through the estimator (a map matcher's `queue_heading`): the
//! gate in every mode, each heading used at its own time, and every heading counted once (used,
//! refused, superseded, outside the gate, expired, undone), also through glitched samples
//! dropped after the fact.

use super::*;

/// The heading and σ waiting for a stance.
fn pending(est: &Estimator) -> Option<(f64, f64)> {
    est.p.pending_heading.map(|h| (h.heading_rad, h.sd_rad))
}

#[test]
fn an_absurd_external_heading_is_refused_and_counted() {
    let mut est = Estimator::new(Config::default(), HeadingAid::None);
    for (t, h, sd) in [
        (0.0, f64::NAN, 0.01),
        (0.0, 0.3, 0.0),
        (0.0, 0.3, -1.0),
        (0.0, 0.3, f64::INFINITY),
        (0.0, 1e300 * 1e300, 0.1),
        (f64::NAN, 0.3, 0.01),
        (f64::INFINITY, 0.3, 0.01),
        (f64::NEG_INFINITY, 0.3, 0.01),
    ] {
        assert!(est.queue_heading(t, h, sd).is_err(), "{t} {h} {sd}");
    }
    assert_eq!(est.counters().headings_refused, 8);
    assert!(est.p.pending_heading.is_none());
    est.queue_heading(0.0, 0.3, 0.01).unwrap();
    assert_eq!(pending(&est), Some((0.3, 0.01)));
    // A newer one before the stance replaces it, counted.
    est.queue_heading(0.0, 0.4, 0.02).unwrap();
    assert_eq!(pending(&est), Some((0.4, 0.02)));
    assert_eq!(est.counters().headings_superseded, 1);
    // One still waiting when the stream ends is counted (it went uncounted).
    est.expire_pending_heading();
    est.expire_pending_heading();
    assert!(est.p.pending_heading.is_none());
    assert_eq!(est.counters().headings_expired, 1);
}

/// Runs `rows` from `*i` to the sample before the next stance observation, queues a heading
/// `off_rad` plus `off_sd` σ (the prediction's and `sd` together) from the filter's prediction
/// of the foot axis there, runs that stance, and says how many were used and refused by the
/// gate, and how far the bias moved, rad/s.
fn heading_at_next_stance(
    est: &mut Estimator,
    rows: &[ImuInput],
    i: &mut usize,
    (off_rad, off_sd, sd): (f64, f64, f64),
) -> (u64, u64, f64) {
    // Where the next stance takes a heading: found on a copy, with one no gate refuses.
    let mut probe = est.clone();
    probe
        .queue_heading(rows[*i].t_s, 0.0, std::f64::consts::PI)
        .unwrap();
    let mut at = *i;
    while probe.p.pending_heading.is_some() {
        probe.step(&rows[at]).unwrap();
        at += 1;
    }
    while *i + 1 < at {
        est.step(&rows[*i]).unwrap();
        *i += 1;
    }
    let Stage::Running(e) = &est.stage else {
        panic!("not running at sample {i}")
    };
    let (predicted, var) = e.heading_prediction(&est.p.foot_forward_body());
    let (c0, b0) = (*est.counters(), est.last_estimate().gyro_bias_rad_s);
    let heading = predicted + off_rad + off_sd * (var + sd * sd).sqrt();
    est.queue_heading(rows[*i].t_s, wrap_pi(heading), sd)
        .unwrap();
    while est.p.pending_heading.is_some() {
        est.step(&rows[*i]).unwrap();
        *i += 1;
    }
    let c = est.counters();
    let b = est.last_estimate().gyro_bias_rad_s;
    let moved = (0..3).map(|k| (b[k] - b0[k]).abs()).fold(0.0, f64::max);
    (
        c.heading_used - c0.heading_used,
        c.headings_outside_gate - c0.headings_outside_gate,
        moved,
    )
}

#[test]
fn an_external_heading_far_from_the_prediction_is_refused_in_every_mode() {
    // A heading 90° off the prediction with σ 1e-3, at 30 s of exp36. The gate was the eskf
    // mode's alone: in the paper and rotation-aware modes one such heading moved the bias by
    // 0.05 rad/s, ten times its value (a review). One 2σ off is fused in each.
    let (shipped, rows) = exp36_inputs();
    for mode in [Mode::Eskf, Mode::Paper, Mode::RotationAware] {
        let cfg = Config {
            mode,
            ..shipped.clone()
        };
        let (mut est, mut i) = tracking_at_30_s(cfg, &rows);
        let far = (std::f64::consts::FRAC_PI_2, 0.0, 1e-3);
        let (used, gated, moved) = heading_at_next_stance(&mut est, &rows, &mut i, far);
        assert_eq!((used, gated), (0, 1), "{mode:?}");
        assert!(moved < 1e-4, "{mode:?}: the bias moved by {moved} rad/s");
        let near = (0.0, 2.0, 0.05);
        let (used, gated, _) = heading_at_next_stance(&mut est, &rows, &mut i, near);
        assert_eq!((used, gated), (1, 0), "{mode:?}");
    }
}

#[test]
fn a_heading_update_the_health_check_undoes_is_not_counted_as_used() {
    // The paper mode with a bias bound of 0.008 rad/s (the walk's z bias is 0.005), and a
    // heading within the gate (3.5σ of the prediction and the observation together) whose σ
    // of 1e-3 moves the bias filter's z by 0.0046 rad/s, past the bound: the health check
    // undoes the update. It was counted as used, and the external heading it took was
    // counted nowhere (a review).
    let (cfg, rows) = exp36_inputs();
    let (mut est, mut i) = tracking_at_30_s(paper_with_bias_bound(cfg, 0.008), &rows);
    let c0 = *est.counters();
    let (used, gated, _) = heading_at_next_stance(&mut est, &rows, &mut i, (0.0, 3.5, 1e-3));
    let c = est.counters();
    assert_eq!(
        c.health_restores - c0.health_restores,
        1,
        "the update was undone"
    );
    assert_eq!((used, gated), (0, 0));
    assert_eq!(c.headings_undone - c0.headings_undone, 1);
    assert!(est.p.pending_heading.is_none());
}

#[test]
fn a_heading_used_by_a_glitched_sample_and_replaced_since_is_counted() {
    // H1 waits; the sample that uses it at its stance is stamped 0.1 s ahead (a gap, so
    // provisional); H2 is handed in; the next sample shows the stamp to be a glitch. The use
    // of H1 is undone with the sample, and H2 replaces it: H1 was counted nowhere (a review).
    let (cfg, rows) = exp36_inputs();
    let aid = crate::runner::heading_aid(&cfg, None).unwrap();
    let mut est = Estimator::new(cfg, aid);
    let mut i = 0;
    while est.phase() != Phase::Tracking {
        est.step(&rows[i]).unwrap();
        i += 1;
    }
    // The first sample that uses a heading (σ π: no gate refuses it).
    let h1 = (0.0, std::f64::consts::PI);
    loop {
        let mut trial = est.clone();
        trial.queue_heading(rows[i].t_s, h1.0, h1.1).unwrap();
        let glitched = ImuInput {
            t_s: rows[i].t_s + 0.1,
            ..rows[i]
        };
        trial.step(&glitched).unwrap();
        if trial.p.pending_heading.is_none() {
            est = trial;
            break;
        }
        est.step(&rows[i]).unwrap();
        i += 1;
    }
    // Without H2, H1 is pending again, and nothing is superseded.
    let mut alone = est.clone();
    assert!(alone.step(&rows[i + 1]).unwrap().glitch_t_s.is_some());
    assert_eq!(pending(&alone), Some(h1));
    assert_eq!(alone.counters().headings_superseded, 0);
    let h2 = (0.5, std::f64::consts::PI);
    est.queue_heading(rows[i + 1].t_s, h2.0, h2.1).unwrap();
    assert!(est.step(&rows[i + 1]).unwrap().glitch_t_s.is_some());
    assert_eq!(pending(&est), Some(h2));
    let c = est.counters();
    assert_eq!((c.headings_superseded, c.headings_outside_gate), (1, 0));
}

/// exp36's samples and the shipped configuration.
fn exp36_inputs() -> (Config, Vec<ImuInput>) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let log = corridor_shared::imu_csv::read_imu_csv(
        &root.join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv"),
        &Default::default(),
    )
    .unwrap();
    let cfg = Config::from_file(&root.join("configs/gdins.toml")).unwrap();
    (cfg, log.rows.iter().map(ImuInput::from).collect())
}

/// An estimator with `cfg` run over `rows` until it tracks and 30 s have passed, and the
/// index of the next row.
fn tracking_at_30_s(cfg: Config, rows: &[ImuInput]) -> (Estimator, usize) {
    let aid = crate::runner::heading_aid(&cfg, None).unwrap();
    let mut est = Estimator::new(cfg, aid);
    let mut i = 0;
    while est.phase() != Phase::Tracking || i < 6000 {
        est.step(&rows[i]).unwrap();
        i += 1;
    }
    (est, i)
}

/// `cfg` in the paper mode with the plausible gyro bias bounded by `bound_rad_s`.
fn paper_with_bias_bound(cfg: Config, bound_rad_s: f64) -> Config {
    let s = &cfg.sensor;
    let sensor = corridor_shared::sensor::SensorFile {
        gyro_range_rad_s: Some(s.gyro_range_rad_s()),
        accel_range_m_s2: Some(s.accel_range_m_s2()),
        max_gyro_rad_s: Some(s.max_gyro_rad_s()),
        max_accel_m_s2: Some(s.max_accel_m_s2()),
        max_gyro_bias_rad_s: Some(bound_rad_s),
        ..Default::default()
    }
    .validate()
    .unwrap();
    Config {
        mode: Mode::Paper,
        sensor,
        ..cfg
    }
}

#[test]
fn a_heading_handed_in_during_a_glitched_run_is_pending_after_the_drop() {
    // A run of 150 stamps 975 s ahead. H2 is handed in after the run's first sample, and a
    // stance in the run uses it; the first good time drops the run. H2 was lost (the copy from
    // before the run had no pending heading) and counted as superseded (a review). Stamped on
    // the good clock instead, the run's stance finds it 975 s old and counts it expired: that
    // is undone with the run as well, and it is pending again.
    let (cfg, rows) = exp36_inputs();
    let h2 = (0.5, std::f64::consts::PI);
    let n = 150;
    for glitched_stamp in [true, false] {
        let found = (7000..12000).step_by(97).any(|k| {
            let mut glitched = rows.clone();
            for r in &mut glitched[k..k + n] {
                r.t_s += 975.0;
            }
            let aid = crate::runner::heading_aid(&cfg, None).unwrap();
            let mut est = Estimator::new(cfg.clone(), aid);
            for s in &glitched[..k + 2] {
                let _ = est.step(s);
            }
            assert!(est.p.pending_heading.is_none());
            let t = if glitched_stamp {
                glitched[k + 1].t_s
            } else {
                rows[k + 1].t_s
            };
            est.queue_heading(t, h2.0, h2.1).unwrap();
            for s in &glitched[k + 2..k + n] {
                est.step(s).unwrap();
            }
            if est.p.pending_heading.is_some() {
                return false; // no stance in the run came to it
            }
            let c = *est.counters();
            assert_eq!(c.headings_expired, u64::from(!glitched_stamp), "k {k}");
            let e = *est.step(&glitched[k + n]).unwrap();
            assert_eq!(e.glitch_run_dropped, n as u64 - 1);
            assert_eq!(pending(&est), Some(h2), "k {k}");
            let c = est.counters();
            assert_eq!((c.headings_superseded, c.headings_expired), (0, 0), "k {k}");
            true
        });
        assert!(
            found,
            "no stance of a run came to the heading ({glitched_stamp})"
        );
    }
}

#[test]
fn an_external_heading_is_used_at_its_own_time() {
    // It was fused at whatever stance came next: one stamped 5 s ahead at once, one 3 s old
    // as if new (a review). At 30 s of exp36, σ π (no gate refuses it).
    let (cfg, rows) = exp36_inputs();
    let (est, i) = tracking_at_30_s(cfg, &rows);
    let sd = std::f64::consts::PI;
    // The stances observed from here, and the one that used the heading (its direction is the
    // queued 0.123 rad), with the counters after.
    let run = |t_s: f64| {
        let mut est = est.clone();
        est.queue_heading(t_s, 0.123, sd).unwrap();
        let (mut observed, mut used_at) = (Vec::new(), None);
        for r in &rows[i..i + 2000] {
            let e = *est.step(r).unwrap();
            if let Some(ev) = e.heading {
                observed.push(ev.observed_t_s);
                if ev.direction_rad == 0.123 {
                    used_at = Some(ev.observed_t_s);
                }
            }
        }
        (observed, used_at, *est.counters())
    };
    let now = rows[i].t_s;
    let base = *est.counters();
    // 5 s ahead: the stances before its time use the map; the first from 0.5 s before it on
    // uses it.
    let (observed, used_at, c) = run(now + 5.0);
    let first_due = observed.iter().copied().find(|&t| t >= now + 5.0 - 0.5);
    assert!(observed.iter().filter(|&&t| t < now + 4.5).count() >= 3);
    assert_eq!(used_at, first_due, "stances at {observed:?}");
    assert_eq!(c.headings_expired, base.headings_expired);
    // 3 s behind the latest sample when handed in: no stance to come can use it. Refused on
    // arrival, counted, and saying why; the heading waiting for its stance stays. (It used to
    // wait, take the waiting one's place, counted as superseding it, and expire at the next
    // stance with no word of why: a producer that left `t_s` at 0, the field's default.)
    let mut late = est.clone();
    let latest = late.last_estimate().t_s;
    late.queue_heading(now + 1.0, 0.2, sd).unwrap();
    for t_s in [now - 3.0, 0.0] {
        let err = late.queue_heading(t_s, 0.123, sd).unwrap_err().to_string();
        assert!(
            err.contains(&format!(
                "t_s 2 s or more behind the latest sample, at {latest} s"
            )),
            "{err}"
        );
    }
    let c = late.counters();
    assert_eq!(c.headings_refused, base.headings_refused + 2);
    assert_eq!(c.headings_superseded, base.headings_superseded);
    assert_eq!(pending(&late), Some((0.2, sd)));
    // Exactly 2 s behind: every stance to come is later than the latest sample, so more than
    // 2 s after it: refused too (it was taken, took the waiting one's place and expired).
    let mut edge = est.clone();
    edge.queue_heading(now + 1.0, 0.2, sd).unwrap();
    let t_s = latest - EXTERNAL_HEADING_MAX_AGE_S;
    assert_eq!(latest - t_s, EXTERNAL_HEADING_MAX_AGE_S, "{latest}");
    assert!(edge.queue_heading(t_s, 0.123, sd).is_err());
    assert_eq!(pending(&edge), Some((0.2, sd)));
    assert_eq!(
        edge.counters().headings_superseded,
        base.headings_superseded
    );
    // Just within 2 s when handed in: taken, and the next stance, more than 2 s after its
    // time, finds it expired, counted, and uses the map.
    let (observed, used_at, c) = run(now - 1.99);
    assert!(observed[0] > now - 1.99 + 2.0, "{observed:?}");
    assert_eq!(used_at, None);
    assert_eq!(c.headings_expired, base.headings_expired + 1);
    assert_eq!(c.headings_refused, base.headings_refused);
    // Half a second old: still the next stance's.
    let (observed, used_at, _) = run(now - 0.5);
    assert_eq!(used_at, observed.first().copied());
    // An hour ahead of the latest sample: another clock (Unix time, say), refused and counted;
    // it would have waited for ever, each newer heading counted as superseding it (a review).
    let mut far = est.clone();
    let latest = far.last_estimate().t_s;
    let err = far.queue_heading(latest + 3601.0, 0.1, sd).unwrap_err();
    assert!(err.to_string().contains("3600 s ahead"), "{err}");
    assert_eq!(far.counters().headings_refused, base.headings_refused + 1);
    assert!(far.p.pending_heading.is_none());
    far.queue_heading(latest + 3599.0, 0.1, sd).unwrap();
    assert!(far.p.pending_heading.is_some());
}

#[test]
fn a_heading_update_undone_in_a_glitched_sample_is_pending_again_not_undone() {
    // As `a_heading_update_the_health_check_undoes_is_not_counted_as_used`, with the sample
    // whose update the health check undoes stamped 0.1 s ahead: the next sample drops it. The
    // heading was counted as undone and pending again, twice (a review).
    let (cfg, rows) = exp36_inputs();
    let (mut est, mut i) = tracking_at_30_s(paper_with_bias_bound(cfg, 0.008), &rows);
    for _ in 0..5000 {
        let mut trial = est.clone();
        let Stage::Running(e) = &trial.stage else {
            unreachable!("tracking")
        };
        let (predicted, var) = e.heading_prediction(&trial.p.foot_forward_body());
        let sd: f64 = 1e-3;
        let heading = wrap_pi(predicted + 3.5 * (var + sd * sd).sqrt());
        trial.queue_heading(rows[i].t_s, heading, sd).unwrap();
        let glitched = ImuInput {
            t_s: rows[i].t_s + 0.1,
            ..rows[i]
        };
        trial.step(&glitched).unwrap();
        if trial.counters().headings_undone == 1 {
            assert!(trial.step(&rows[i + 1]).unwrap().glitch_t_s.is_some());
            assert_eq!(trial.counters().headings_undone, 0);
            assert_eq!(pending(&trial), Some((heading, sd)));
            return;
        }
        est.step(&rows[i]).unwrap();
        i += 1;
    }
    panic!("no undone heading update found");
}

#[test]
fn an_external_heading_is_timed_on_the_clock_its_stamps_are_on_after_a_step_back() {
    // The host clock set back by 0.3 s at 30 s of exp36: the stamps from there on are taken
    // plus 0.3 s (`SampleClock::offset_s`). A heading stamped on the new clock 0.3 s after the
    // next stance's observation is that stance's (within `EXTERNAL_HEADING_LEAD_S`), as without
    // the step. Mutation testing found nothing that checked the stance's side of the
    // conversion: with its offset added instead of taken off, the heading is 0.6 s further
    // ahead and waits for a later stance.
    let (cfg, mut rows) = exp36_inputs();
    let (_, i) = tracking_at_30_s(cfg.clone(), &rows);
    for r in &mut rows[i..] {
        r.t_s -= 0.3;
    }
    let (mut est, _) = tracking_at_30_s(cfg, &rows[..i]);
    let mut k = i;
    while est.counters().clock_steps_back == 0 || k < i + 20 {
        let _ = est.step(&rows[k]);
        k += 1;
    }
    assert!(
        (est.p.clock.offset_s() + 0.3).abs() < 0.01,
        "{}",
        est.p.clock.offset_s()
    );
    // The stamp of the sample the next stance is observed at, found on a copy.
    let mut probe = est.clone();
    let at = (k..rows.len())
        .find(|&j| probe.step(&rows[j]).unwrap().heading.is_some())
        .expect("a stance");
    est.queue_heading(rows[at].t_s + 0.3, 0.123, std::f64::consts::PI)
        .unwrap();
    for r in &rows[k..at] {
        est.step(r).unwrap();
    }
    let e = *est.step(&rows[at]).unwrap();
    assert_eq!(e.heading.map(|h| h.direction_rad), Some(0.123));
}
