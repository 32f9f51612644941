//! The diagnosis on bundled measured recordings with effects injected that the configured
//! model does not declare: it must name the injected effect first, and the model it ends with
//! must have a lower footprint error than the one it started from. On the clean recordings it
//! must not invent an effect beyond the real one it documents (a heading offset on exp25).

use corridor_service::diagnose::{
    DriftProbe, Effect, Fix, HeldOut, Report, SIGNIFICANT, analyse, apply_fix, calibrate_drift,
    judge, judge_names, run_diagnosis,
};
use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::config::{ConfigFile, HeadingObservations};
use corridor_shared::imu_csv::ImuLog;
use corridor_shared::injection::{BiasInjection, LogInjection};
use corridor_shared::truth_csv::TruthPoint;

mod diagnose_common;
use diagnose_common::{clock_told_by_its_strides, config, load, run};

/// A model that declares a nearly constant bias (random walk 1e-5 rad/s/√s): the bias tests
/// inject drifts it does not declare.
fn constant_bias_config() -> ConfigFile {
    let mut f = config(0.0, true);
    f.eskf.gyro_bias_rw_rad_s_sqrt_s = Some(1e-5);
    f
}

fn assert_found_and_fixed(report: &Report, effect: &str) {
    assert_eq!(report.top_effect, effect, "{:#?}", report.effects);
    let first = report.iterations.first().expect("an effect was added");
    assert_eq!(first.effect.name(), effect);
    let (before, after) = (
        report.before.gcp_rms_m.unwrap(),
        report.after.gcp_rms_m.unwrap(),
    );
    assert!(after < before, "footprint RMS {before:.2} -> {after:.2} m");
}

/// Applies `f(t_s, gyro, accel)` to every row.
fn modified(log: &ImuLog, f: impl Fn(f64, &mut [f64; 3], &mut [f64; 3])) -> ImuLog {
    let mut out = log.clone();
    for r in &mut out.rows {
        f(r.t_s, &mut r.gyro_rad_s, &mut r.accel_m_s2);
    }
    out
}

/// exp36's heading residuals show nothing; its footprints show the short strides of a plain
/// zero-velocity update (the model here has no rolling-foot stance update), which the loop
/// fixes with it after the heading effects, and which are within 0.5 % with it.
#[test]
fn clean_recordings_show_only_the_documented_heading_offset_and_short_strides() {
    let (log, truth) = load("gdins_exp36_corridor_out_and_back");
    let r = run(&log, &truth, &config(0.0, false));
    assert_eq!(r.top_effect, "none", "{:#?}", r.effects);
    let stride = r.stride_length.as_ref().expect("footprints given");
    eprintln!("{}", stride.finding.evidence);
    assert!(stride.finding.score >= SIGNIFICANT, "{stride:?}");
    assert!((0.97..0.99).contains(&stride.fit.ratio), "{stride:?}");
    let steps: Vec<(Effect, Fix, bool)> = r
        .iterations
        .iter()
        .map(|i| (i.effect, i.fix, i.kept))
        .collect();
    assert_eq!(steps, [(Effect::StrideLength, Fix::RollingStance, true)]);
    let (b, a) = (r.before.gcp_rms_m.unwrap(), r.after.gcp_rms_m.unwrap());
    assert!(a < b, "footprint RMS {b:.3} -> {a:.3} m");
    let mut rolling = config(0.0, false);
    rolling.eskf.zupt_rolling_height_m = Some(0.08);
    let r = run(&log, &truth, &rolling);
    let stride = r.stride_length.as_ref().expect("footprints given");
    // With the full rolling model (about both horizontal axes) exp36's strides come out
    // 0.32 ± 0.09 % long, right at the significance line (score 3.03; 2.2 % short without it):
    // a scale the size of a survey's own. Taken out as the accelerometer's (fitted on the first
    // half of the footprints) it lowers the second half's error but not the whole walk's
    // (0.392 -> 0.401 m): tried, not kept.
    assert!((stride.fit.ratio - 1.0).abs() < 0.005, "{stride:?}");
    let steps: Vec<(Effect, bool)> = r.iterations.iter().map(|i| (i.effect, i.kept)).collect();
    assert_eq!(steps, [(Effect::StrideLength, false)]);
    let it = &r.iterations[0];
    let Some(HeldOut::SecondHalf {
        rms_m: [held_before, held_after],
    }) = it.held_out
    else {
        panic!("judged on the second half: {:?}", it.held_out)
    };
    assert!(held_after < held_before, "{:?}", it.held_out);
    let (b, a) = (it.before.gcp_rms_m.unwrap(), it.after.gcp_rms_m.unwrap());
    assert!(a > b, "the whole walk {b:.3} -> {a:.3} m");

    let (log, truth) = load("gdins_exp25_multi_corridor");
    let r = run(&log, &truth, &config(0.0, false));
    assert_eq!(r.top_effect, "heading_offset");
    // with the offset in the model nothing else is significant
    let r = run(&log, &truth, &config(0.0, true));
    assert!(
        r.effects.iter().all(|e| e.score < SIGNIFICANT),
        "{:#?}",
        r.effects
    );
    // the bias does not move with the onset of walking, and the onset test says how large a
    // g-sensitivity it would have seen
    let onset = r.onset.expect("a walk that begins after a rest");
    assert!(!onset.explains(), "{onset:?}");
    assert!(onset.mde.is_some_and(|m| m < 0.01), "{onset:?}");
}

/// A g-sensitivity shows in the filter's bias the moment walking begins: a stride's mean
/// specific force differs from the rest's (about 3 m/s², mostly along the sensor's x axis, the
/// foot pitched on average), and the bias takes up the rate error that adds. The bias-change
/// test named it a bias drift before (its fix, a faster bias random walk, does not remove it);
/// the onset test names it, and the g-sensitivity states lower the footprint error.
#[test]
fn injected_g_sensitivity_is_named_from_the_bias_at_the_onset_of_walking_and_fixed() {
    let (mut log, truth) = load("gdins_exp25_multi_corridor");
    LogInjection::GSensitivity {
        k_rad_s_per_m_s2: 0.02,
    }
    .apply(&mut log.rows);
    let r = run(&log, &truth, &config(0.0, true));
    assert_found_and_fixed(&r, "g_sensitivity");
    assert_eq!(r.iterations[0].fix, Fix::GSensitivity);
    let onset = r.onset.expect("a walk that begins after a rest");
    assert!(onset.explains(), "{onset:?}");
}

#[test]
fn injected_z_scale_factor_is_named_and_fixed() {
    let (log, truth) = load("gdins_exp25_multi_corridor");
    let log = modified(&log, |_, g, _| g[2] *= 1.05);
    assert_found_and_fixed(&run(&log, &truth, &config(0.0, true)), "gyro_scale_factor");
}

/// For an injected bias the error that matters is the bias estimate's: the mean |error| of
/// (estimate with injection − estimate without) against the injected bias, z axis, after 20 s.
fn bias_tracking_error(clean: &ImuLog, cfg: &ConfigFile, injected: impl Fn(f64) -> f64) -> f64 {
    let cfg = cfg.validate().unwrap();
    let aid = heading_aid(&cfg, None).unwrap();
    let none = BiasInjection::default();
    let inj = modified(clean, |t, g, _| g[2] += injected(t));
    let a = run_log(clean, &cfg, &aid, &none, |_, _| {});
    let b = run_log(&inj, &cfg, &aid, &none, |_, _| {});
    let (mut sum, mut n) = (0.0, 0.0);
    for (i, &t) in a.trace.t_s.iter().enumerate() {
        if t > 20.0 {
            sum += (b.trace.bias_rad_s[i][2] - a.trace.bias_rad_s[i][2] - injected(t)).abs();
            n += 1.0;
        }
    }
    sum / n
}

/// A bias drift must be named first, and the fix the diagnosis proposes must track the
/// injected bias better than the model it started from. (The footprint error cannot judge
/// it: with a heading observation at every stance these drifts change the footprint RMS by
/// less than the scatter of 12 corner footprints, 0.34–0.40 m.)
fn assert_drift_found_and_tracked(injected: impl Fn(f64) -> f64 + Copy) {
    let (clean, truth) = load("gdins_exp25_multi_corridor");
    let log = modified(&clean, |t, g, _| g[2] += injected(t));
    let start = constant_bias_config();
    let report = run(&log, &truth, &start);
    assert_eq!(report.top_effect, "bias_drift", "{:#?}", report.effects);
    let fix = report.iterations.first().expect("a fix was tried").fix;
    let mut after = start.clone();
    assert!(apply_fix(fix, &mut after), "{fix}");
    let (e0, e1) = (
        bias_tracking_error(&clean, &start, injected),
        bias_tracking_error(&clean, &after, injected),
    );
    eprintln!("  bias tracking error {e0:.2e} -> {e1:.2e} rad/s with {fix}");
    assert!(
        e1 < 0.8 * e0,
        "bias tracking error {e0:.2e} -> {e1:.2e} rad/s with {fix}"
    );
}

#[test]
fn injected_bias_ramp_is_named_and_tracked() {
    assert_drift_found_and_tracked(|t| 2e-4 * (t - 10.0).max(0.0));
}

#[test]
fn injected_bias_step_is_named_and_tracked() {
    assert_drift_found_and_tracked(|t| if t > 52.0 { 0.01 } else { 0.0 });
}

#[test]
fn injected_mounting_slip_is_a_heading_offset() {
    // At 8 s, just after the calibration strides, the sensor turns by 6° on the shoe about the
    // vertical, and the gyro does not see it: from then on the foot's heading differs from the
    // one calibrated at the start.
    let (log, truth) = load("gdins_exp36_corridor_out_and_back");
    let mut log = log;
    LogInjection::MountingSlip {
        angle_rad: 6f64.to_radians(),
        after_s: 8.0,
    }
    .apply(&mut log.rows);
    // Calibrated on one straight stride: with the default three, the slip is still named first
    // (heading_offset 4.4) but adding the offset state raises the footprint error of this walk
    // (1.88 -> 2.10 m), with one it lowers it (1.96 -> 1.75 m). How the fix depends on the
    // mounting calibration is an open point of the diagnosis issue.
    let mut cfg = config(0.0, false);
    cfg.heading.calibration_strides = Some(1);
    assert_found_and_fixed(&run(&log, &truth, &cfg), "heading_offset");
}

#[test]
fn a_gyro_that_clips_below_its_configured_range_is_named_and_fixed() {
    // Every axis cut at ±5 rad/s, with the configuration still saying 8.727: the lost pitch
    // rotation at each toe-off makes tilt and heading jumps that the bias soaks up. Named
    // first on every walk of the detection matrix; its fix (the range at the rail, the
    // attitude variance, the peaks put back) lowers the footprint error on 10 of 14 there
    // (exp17 1.02 -> 0.42 m). Here (the matrix's model without the clean walk's fixes) not on
    // exp26 nor exp25: with the peaks put back the fix raises their error under the
    // diagnosis's model (exp26 0.86 m with the variance alone, 2.23 with the peaks put back,
    // 1.34 without either), and the loop does not keep it. Before session 47 the fix was the
    // variance alone: lower on 8 of 14 walks of the matrix, exp26 1.34 -> 0.50 m here.
    for (name, fixed) in [
        ("gdins_exp17_rect_loop_small", true),
        ("gdins_exp26_narrow_out_and_back", false),
    ] {
        let (mut log, truth) = load(name);
        LogInjection::Clipping { range_rad_s: 5.0 }.apply(&mut log.rows);
        let r = run(&log, &truth, &config(0.0, false));
        assert_eq!(r.top_effect, "gyro_clipping", "{name}: {:#?}", r.effects);
        assert_eq!(r.iterations[0].fix, Fix::GyroRail { milli_rad_s: 5000 });
        if fixed {
            assert_found_and_fixed(&r, "gyro_clipping");
        }
    }
    // The clean walk reaches only its real rail, at the configured range: not named.
    let (clean, truth) = load("gdins_exp26_narrow_out_and_back");
    let r = run(&clean, &truth, &config(0.0, false));
    let clip = r
        .effects
        .iter()
        .find(|e| e.name == Effect::GyroClipping)
        .expect("the real rail is reported");
    assert!(clip.score < SIGNIFICANT, "{clip:?}");
}

#[test]
fn a_slowly_oscillating_bias_is_not_a_confident_wrong_answer() {
    // Outside the catalogue: a bias following a slow oscillation (a temperature-like cycle).
    let (log, truth) = load("gdins_exp25_multi_corridor");
    let log = modified(&log, |t, g, _| {
        g[2] += 0.004 * (std::f64::consts::TAU * t / 40.0).sin()
    });
    let r = run(&log, &truth, &config(0.0, true));
    let top = &r.effects[0];
    assert!(
        matches!(top.name, Effect::Unexplained | Effect::BiasDrift) || top.score < SIGNIFICANT,
        "{:#?}",
        r.effects
    );
}

#[test]
fn injected_timing_drift_is_named_timing_and_fixed() {
    // The logger's clock runs 3 % fast: every time stamp, and so every integrated angle and
    // distance, is stretched. It looks like a scale factor, the same on every axis.
    let (log, truth) = load("gdins_exp25_multi_corridor");
    let mut log = log;
    for r in &mut log.rows {
        r.t_s *= 1.03;
    }
    let truth: Vec<TruthPoint> = truth
        .iter()
        .map(|p| TruthPoint {
            t_s: p.t_s * 1.03,
            ..*p
        })
        .collect();
    assert_found_and_fixed(&run(&log, &truth, &config(0.0, true)), "timing");
}

/// The power of a walk, from the detection matrix (`corridor diagnose --suite
/// configs/eval/gdins.toml`, `docs/results/detection.md`), on two walks with many turns:
/// the detectable size of a z scale factor the diagnosis predicts on the clean walk, and a 2 %
/// one injected (a 5 % one scored 1.4 on exp25 before the residuals of every stance and
/// the signatures) is named first, at a size within a factor of 2 of the prediction.
#[test]
fn a_two_percent_z_scale_factor_is_named_where_the_walk_can_show_it() {
    for (name, heading) in [
        ("gdins_exp25_multi_corridor", 0.0),
        ("gdins_exp28_detour_and_long_corridor", 90.0),
    ] {
        let (log, truth) = load(name);
        // Both walks have a real heading offset (named on the clean walk): it is in the model.
        let cfg = config(heading, true);
        let clean = run(&log, &truth, &cfg);
        let z = clean
            .power
            .iter()
            .find(|p| p.variant == "z scale")
            .expect("the z scale factor's power is measured");
        let mde = z
            .mde
            .expect("these walks turn often: they can show a scale factor");
        eprintln!("{name}: predicted detectable z scale {:.2} %", 100.0 * mde);
        assert!(
            (0.01..=0.04).contains(&mde),
            "{name}: predicted {mde} not within a factor of 2 of the 2 % named below"
        );
        let injected = modified(&log, |_, g, _| g[2] *= 1.02);
        let r = run(&injected, &truth, &cfg);
        assert_eq!(
            r.top_effect, "gyro_scale_factor",
            "{name}: {:#?}",
            r.effects
        );
        let (b, a) = (r.before.gcp_rms_m.unwrap(), r.after.gcp_rms_m.unwrap());
        assert!(a < b, "{name}: footprint RMS {b:.2} -> {a:.2} m");
    }
}

/// The detectable size is checked by injection where it is claimed: at twice the predicted size
/// an effect is detected almost always, so the walk's own fit there must be significant. On
/// exp40 (a serpentine: few heading observations held, many associations that flip with the
/// heading) the probe's response predicted a z scale of 0.91 %, but injected at +2 % and +5 % no
/// scale factor was named and the report said "nothing above the detectable sizes z scale
/// 0.41 %" (its fit moved the other way). Now the check fails at every size up to the plausible
/// limit and the report says the walk cannot show a z scale, naming the sizes tried; on exp25 the
/// prediction passes its check at once.
#[test]
fn a_detectable_size_the_walk_does_not_bear_out_by_injection_is_not_claimed() {
    let (log, truth) = load("gdins_exp40_serpentine_return");
    let r = run(&log, &truth, &config(0.0, false));
    let z = r.power.iter().find(|p| p.variant == "z scale").unwrap();
    assert_eq!(z.mde, None, "{z:?}");
    let why = z.cannot.as_deref().unwrap_or_default();
    assert!(
        why.starts_with("its signature fit does not bear out the probe: injected at "),
        "{why}"
    );
    assert!(
        r.verdict
            .contains("this walk cannot show z scale (its signature fit does not bear out"),
        "{}",
        r.verdict
    );
    let (log, truth) = load("gdins_exp25_multi_corridor");
    let r = run(&log, &truth, &config(0.0, true));
    let z = r.power.iter().find(|p| p.variant == "z scale").unwrap();
    assert!(z.mde.is_some() && z.mde_check_failed.is_empty(), "{z:?}");
}

/// A large z scale factor on exp37 (a square spiral: 25 s of turning) pushes its foot axes out
/// of the gate, so few heading observations are used and the residual regression cannot test
/// it; the signature fit to every stance's residual can, and names it (before, the report said
/// "nothing above the detectable sizes z scale 1.8 %" with that fit at score 30).
#[test]
fn a_scale_factor_that_leaves_few_used_observations_is_named_from_every_stance() {
    let (log, truth) = load("gdins_exp37_spiral_and_corridor");
    let cfg = config(0.0, false);
    let injected = modified(&log, |_, g, _| g[2] *= 1.05);
    let r = run(&injected, &truth, &cfg);
    assert_eq!(r.top_effect, "gyro_scale_factor", "{:#?}", r.effects);
    let sf = &r.effects[0];
    assert!(
        sf.evidence.contains("residual regression: not tested"),
        "the regression could test it: {}",
        sf.evidence
    );
    let (b, a) = (r.before.gcp_rms_m.unwrap(), r.after.gcp_rms_m.unwrap());
    assert!(a < b, "footprint RMS {b:.2} -> {a:.2} m");
}

/// A 1 % clock error on exp37: its gyro scale factors alone are no clock error at 3σ (the
/// horizontal axes are barely measured), but a clock running ε fast also stretches every
/// stride by (1 + ε)², which the footprints show: with them it is named `timing`, without them
/// a scale factor. The model has the rolling-foot stance update (strides right without a clock
/// error), as the detection matrix's injected columns on this walk do.
#[test]
fn a_one_percent_clock_error_is_told_from_a_scale_factor_by_the_strides_it_stretches() {
    let with = clock_told_by_its_strides("gdins_exp37_spiral_and_corridor", 0.01);
    let timing = &with.effects[0];
    assert!(
        timing.evidence.contains("the strides come out +"),
        "{}",
        timing.evidence
    );
}

/// When nothing is significant the report says what the walk could have shown, not a bare
/// `none`.
#[test]
fn nothing_named_comes_with_the_detectable_sizes() {
    let (log, truth) = load("gdins_exp36_corridor_out_and_back");
    let r = run(&log, &truth, &config(0.0, false));
    assert_eq!(r.top_effect, "none");
    eprintln!("{}", r.verdict);
    assert!(
        r.verdict.contains("nothing above the detectable sizes"),
        "{}",
        r.verdict
    );
    for p in &r.power {
        // every measured effect has either a detectable size or a reason it cannot be shown
        assert!(p.mde.is_some() != p.cannot.is_some(), "{p:?}");
        let named = p.mde.map(|m| p.format_size(m));
        assert!(
            named.is_none_or(|s| r.verdict.contains(&format!("{} {s}", p.variant))),
            "{} missing from: {}",
            p.variant,
            r.verdict
        );
    }
    // and so has a bias step or ramp, in the filter's own test
    let c = r.bias_change.as_ref().expect("70 s: three blocks");
    for kind in DriftProbe::ALL {
        let m = kind.mde_of(c).expect("measured");
        assert!(m <= kind.plausible_max(), "{kind:?} {m}");
        assert!(r.verdict.contains(&kind.words(m)), "{}", r.verdict);
    }
}

/// The detection matrix's scan judges its injected walks without the probes that only measure
/// detectable sizes (`judge_names`; `judge` adds them): measuring the sizes must change no name
/// or score of the loop's first step.
#[test]
fn the_scan_names_what_the_loop_names() {
    let (mut log, truth) = load("gdins_exp36_corridor_out_and_back");
    LogInjection::BiasStep {
        axis: 2,
        step_rad_s: 0.025,
        at_s: 35.0,
    }
    .apply(&mut log.rows);
    let cfg = config(0.0, false);
    let (full, _) = judge(&log, &cfg, Some(&truth), None).unwrap();
    let (names, _) = judge_names(&log, &cfg, Some(&truth), None).unwrap();
    let scores = |a: &corridor_service::diagnose::Analysis| -> Vec<(Effect, f64)> {
        a.effects.iter().map(|f| (f.name, f.score)).collect()
    };
    assert_eq!(scores(&full), scores(&names));
    assert!(
        full.effects[0].name == Effect::BiasDrift && full.effects[0].score >= SIGNIFICANT,
        "{:?}",
        scores(&full)
    );
}

/// The bias step and ramp the bias-change test detects on a walk, predicted from one probe
/// injection each: twice the predicted size is detected by the test, half of it is not (the
/// detection matrix's scan checks the same at ¼–4× on every walk: `docs/results/detection.md`).
#[test]
fn the_detectable_bias_step_and_ramp_are_what_the_test_shows() {
    let (log, truth) = load("gdins_exp36_corridor_out_and_back");
    let cfg = config(0.0, false);
    let mut clean = analyse(&log, &cfg, Some(&truth), None).unwrap();
    calibrate_drift(&log, &cfg, None, &mut clean).unwrap();
    let c = clean.bias_change.expect("70 s: three blocks");
    for kind in DriftProbe::ALL {
        let m = kind.mde_of(&c).expect("measured");
        let score = |factor: f64| {
            let mut injected = log.clone();
            kind.injection(&injected.rows, factor * m)
                .apply(&mut injected.rows);
            let a = analyse(&injected, &cfg, None, None).unwrap();
            a.bias_change.map_or(0.0, |c| c.score)
        };
        let (half, twice) = (score(0.5), score(2.0));
        eprintln!("{kind:?}: predicted {m:.2e}, score at 0.5× {half:.1}, at 2× {twice:.1}");
        assert!(twice >= SIGNIFICANT, "{kind:?}: {twice}");
        assert!(half < SIGNIFICANT, "{kind:?}: {half}");
    }
}

/// The fix the diagnosis adds for an axis misalignment (`model.gyro_coupling_z_sd_deg`): its
/// states measure a coupling injected into a measured walk. exp29 turns often and pitches at
/// every stride; the z←x estimate with a 3° x→z coupling injected moves from the clean walk's
/// by the injected 3°, and the z←y estimate stays where it was.
#[test]
fn the_coupling_states_measure_an_injected_axis_misalignment() {
    let (log, truth) = load("gdins_exp29_corridor_circuit");
    let mut cfg = config(90.0, true);
    cfg.model.gyro_coupling_z_sd_deg = Some(3.0);
    let estimate = |log: &ImuLog| -> [[f64; 2]; 2] {
        let d = run_diagnosis(log, &cfg, Some(&truth), None).unwrap();
        eprintln!("{:?}", d.before.estimates_in_words());
        d.before.coupling_z_rad.expect("the coupling states are on")
    };
    let clean = estimate(&log);
    let mut injected = log.clone();
    LogInjection::GyroCoupling {
        from: 0,
        to: 2,
        coupling_rad: 3f64.to_radians(),
    }
    .apply(&mut injected.rows);
    let with = estimate(&injected);
    let moved = [0, 1].map(|k| (with[k][0] - clean[k][0]).to_degrees());
    assert!(
        (moved[0] - 3.0).abs() < 0.5,
        "z←x moved by {:.2}°",
        moved[0]
    );
    assert!(moved[1].abs() < 0.5, "z←y moved by {:.2}°", moved[1]);
    // σ small enough to tell a 3° coupling from none on this walk
    assert!(
        with[0][1].to_degrees() < 1.0,
        "σ {:.2}°",
        with[0][1].to_degrees()
    );
}

/// A coupling of the y gyro axis into z (8°) on exp26, an out-and-back walk: at its stances the
/// coupling's heading error builds up with the turns, as a z scale factor's does (their
/// signatures correlate at +0.93 on this walk), and the z scale is named first. The report
/// must say that the name cannot be told from the coupling on this walk, not give it as a
/// confident one (the detection matrix: 21 of its 45 wrong names are such pairs).
#[test]
fn a_name_the_walk_cannot_tell_from_the_injected_coupling_says_so() {
    let (log, truth) = load("gdins_exp26_narrow_out_and_back");
    let cfg = config(0.0, false);
    let mut injected = log.clone();
    LogInjection::GyroCoupling {
        from: 1,
        to: 2,
        coupling_rad: 8f64.to_radians(),
    }
    .apply(&mut injected.rows);
    let d = run_diagnosis(&injected, &cfg, Some(&truth), None).unwrap();
    let r = &d.report;
    eprintln!("{} | {:?}", r.verdict, r.top_indistinguishable_from);
    assert_eq!(r.top_effect, "gyro_scale_factor");
    assert!(
        r.top_indistinguishable_from
            .iter()
            .any(|a| a.starts_with("axis_misalignment (y→z coupling")),
        "{:?}",
        r.top_indistinguishable_from
    );
    let dir =
        std::env::temp_dir().join(format!("corridor-indistinguishable-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    corridor_service::diagnose::write_report(&dir, r, &d.before, &d.after).unwrap();
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    assert!(
        md.lines().any(
            |l| l.starts_with("On this walk its signature is indistinguishable from")
                && l.contains("axis_misalignment (y→z coupling")
        ),
        "{md}"
    );
}

/// An accelerometer scale error (+2 % on every axis) makes the strides 2 % long: an effect only
/// the footprints show, named on the stride-length line at about its size. The model already has
/// the rolling-foot stance update, so the fix is the scale itself (`model.accel_scale_factor`),
/// fitted on the first half of the footprints and kept because the second half's error falls.
#[test]
fn an_accelerometer_scale_error_is_named_on_the_stride_length_line() {
    let (log, truth) = load("gdins_exp36_corridor_out_and_back");
    let mut cfg = config(0.0, false);
    cfg.eskf.zupt_rolling_height_m = Some(0.08);
    let mut scaled = log.clone();
    LogInjection::AccelScale { fraction: 0.02 }.apply(&mut scaled.rows);
    let clean = run(&log, &truth, &cfg);
    let r = run(&scaled, &truth, &cfg);
    let line = |r: &Report| {
        let l = r.stride_length.clone().expect("footprints at every stride");
        eprintln!("{}", l.finding.evidence);
        l
    };
    let (clean, injected) = (line(&clean), line(&r));
    // The clean walk's strides: 0.3 % long, at the significance line (see
    // `clean_recordings_show_only_the_documented_heading_offset_and_short_strides`).
    assert!((clean.fit.ratio - 1.0).abs() < 0.005, "{clean:?}");
    assert!(injected.finding.score >= SIGNIFICANT, "{injected:?}");
    assert!(
        matches!(injected.finding.fix, Some(Fix::StrideScale { .. })),
        "the model has the rolling update already: {:?}",
        injected.finding.fix
    );
    assert!(injected.fit.mde < 0.02, "{injected:?}");
    let moved = injected.fit.ratio - clean.fit.ratio;
    assert!(
        (moved - 0.02).abs() < 0.003,
        "the stride scale moved by {moved}"
    );
    let step = r
        .iterations
        .iter()
        .find(|i| i.effect == Effect::StrideLength)
        .expect("the stride scale is tried");
    assert!(step.kept, "{step:?}");
    let d = run_diagnosis(&scaled, &cfg, Some(&truth), None).unwrap();
    let k = d
        .final_model
        .model
        .accel_scale_factor
        .expect("the scale is set");
    // the injected 2 % on top of the walk's own 0.3 %, fitted on half of the strides
    assert!((k - 0.02 - (clean.fit.ratio - 1.0)).abs() < 0.005, "{k}");
    let (b, a) = (r.before.gcp_rms_m.unwrap(), r.after.gcp_rms_m.unwrap());
    assert!(a < b, "footprint RMS {b:.3} -> {a:.3} m");
}

#[test]
fn a_heading_the_map_never_held_is_said_beside_what_is_named() {
    // No heading observation can pass a gate of 1e-9° (and no run of strides re-acquires the
    // heading): the model never holds its heading on the map, as a log started in a weave can
    // do (a review: a lost heading named as an 8 % z scale factor at score 30, with no word of
    // it). So can a large effect (exp37's spiral under a 5 % z scale factor), which must still
    // be named: the report names what the residuals show, and says the heading was never held.
    let (log, truth) = load("gdins_exp17_rect_loop_small");
    let mut log = log;
    LogInjection::GyroScale {
        axis: 2,
        fraction: 0.05,
    }
    .apply(&mut log.rows);
    let mut cfg = config(0.0, false);
    cfg.heading.gate_deg = Some(1e-9);
    cfg.heading.reacquire_strides = None;
    let r = run(&log, &truth, &cfg);
    assert!(
        r.verdict.contains("heading was never held") && r.verdict.contains("start in a weave"),
        "{}",
        r.verdict
    );
    // Held by the stride directions alone (no foot axis observed): not said.
    let mut cfg = config(0.0, false);
    cfg.heading.observations = Some(HeadingObservations::Stride);
    let r = run(&log, &truth, &cfg);
    assert!(!r.verdict.contains("never held"), "{}", r.verdict);
    assert_eq!(r.top_effect, "gyro_scale_factor", "{:#?}", r.effects);
}

/// exp32 with a 5 % z scale factor and the heading-offset state its clean walk names (the
/// detection matrix's cell): its stride directions run 3–4° off the corridor on the clean walk
/// and 7–12° with the effect. Weighed by their raw residual, at their 1° σ, they counted for
/// nothing, and the signature fit stayed at what the weaving foot axes show: 0.7 % ± 1.0 % for
/// the 5 % injected. The fit now also starts from each kind's own offset and keeps the start the
/// residuals find more likely: 2.4 % ± 0.8 % (short of 5 % as the fits of the matrix's z scale
/// column are: the model's bias and offset states take up part of the effect).
#[test]
fn the_size_of_a_scale_factor_is_fitted_on_strides_that_run_off_their_corridor() {
    let (log, truth) = load("gdins_exp32_box_and_corridor");
    let injected = modified(&log, |_, g, _| g[2] *= 1.05);
    let r = run(&injected, &truth, &config(0.0, true));
    let z = r
        .power
        .iter()
        .find(|p| p.variant == "z scale")
        .expect("the z scale factor's power is measured");
    eprintln!(
        "z scale fitted {:.2} % ± {:.2} %",
        100.0 * z.estimate,
        100.0 * z.std_err
    );
    assert!(
        (0.015..0.075).contains(&z.estimate),
        "5 % injected, fitted {:.2} %",
        100.0 * z.estimate
    );
}
