//! The diagnosis's stride-length line on walks surveyed only at their corners: their legs between
//! corners (4 to 11 of them, each many strides long) give the stride scale where there are too
//! few surveyed single strides, so the loop finds and fixes their short strides, and a clock
//! error there is told from a gyro scale factor by the legs it stretches. Before, these nine
//! walks had no stride-length line at all.

use corridor_service::diagnose::{Effect, Fix, HeldOut, LegKind, SIGNIFICANT};
use corridor_shared::injection::LogInjection;

mod diagnose_common;
use diagnose_common::{clock_told_by_its_strides, config, load, run};

/// exp28 is surveyed at its nine corners (8 legs of 6-65 m). Under the diagnosis's model (a plain
/// zero-velocity update) its legs come out about 3 % short, the short strides of the walks
/// surveyed at every stride; the loop adds the rolling-foot stance update and keeps it, the
/// footprint error falling (0.96 -> 0.38 m in the detection matrix's clean column, where the
/// heading offset is added first).
#[test]
fn a_walk_surveyed_at_its_corners_shows_its_short_strides_and_the_loop_fixes_them() {
    let (log, truth) = load("gdins_exp28_detour_and_long_corridor");
    let r = run(&log, &truth, &config(90.0, true));
    let stride = r.stride_length.as_ref().expect("footprints given");
    eprintln!("{}", stride.finding.evidence);
    assert_eq!(stride.fit.kind, LegKind::CornerLegs, "{stride:?}");
    assert!(stride.fit.legs >= 7, "{stride:?}");
    assert!((0.96..0.99).contains(&stride.fit.ratio), "{stride:?}");
    assert!(stride.finding.score >= SIGNIFICANT, "{stride:?}");
    assert!(
        stride
            .finding
            .evidence
            .contains("legs between surveyed corners"),
        "{}",
        stride.finding.evidence
    );
    let fix = r
        .iterations
        .iter()
        .find(|i| i.effect == Effect::StrideLength)
        .expect("the stride length was tried");
    assert_eq!(fix.fix, Fix::RollingStance);
    assert!(
        fix.kept,
        "{:?} -> {:?}",
        fix.before.gcp_rms_m, fix.after.gcp_rms_m
    );
    let (b, a) = (r.before.gcp_rms_m.unwrap(), r.after.gcp_rms_m.unwrap());
    assert!(a < 0.8 * b, "footprint RMS {b:.3} -> {a:.3} m");
}

/// A clock 3 % fast on exp26 (surveyed at its five corners: 4 legs) stretches every angle by 3 %
/// and every leg by about 6 %. From the heading residuals alone it is a z scale factor (the
/// horizontal gyro axes are barely measured); with the legs it is named `timing`. The model has
/// the rolling-foot stance update (the matrix's cell starts from the clean walk's model, which
/// does not have it on exp26: its four legs show the plain update's short strides at score 2.9
/// only, so there a scale factor is still named).
#[test]
fn a_clock_error_on_a_walk_surveyed_at_its_corners_is_told_by_the_legs_it_stretches() {
    let with = clock_told_by_its_strides("gdins_exp26_narrow_out_and_back", 0.03);
    let stride = with.stride_length.as_ref().expect("footprints given");
    assert_eq!(stride.fit.kind, LegKind::CornerLegs, "{stride:?}");
    assert!(stride.fit.ratio > 1.04, "{stride:?}");
}

/// An accelerometer scale error (+2 %) on exp29, whose model has the rolling-foot stance update:
/// its legs come out long and the stride-length line names it with the scale fix. That fix is
/// fitted on the footprints, so it is judged on footprints it was not fitted on. The first half
/// of exp29's footprints is four legs, one of them the start footprint's 7 % short corridor: no
/// first-half fit (before, the loop could not try the fix at all, and said so). Each of its legs
/// is held out in turn instead, the scale fitted on the others: the held-out legs' error falls,
/// the whole walk's too, and the fix is kept.
#[test]
fn a_scale_fix_on_a_walk_surveyed_at_its_corners_is_judged_on_each_leg_held_out() {
    let (log, truth) = load("gdins_exp29_corridor_circuit");
    let mut cfg = config(90.0, true);
    cfg.eskf.zupt_rolling_height_m = Some(0.08);
    let mut injected = log.clone();
    LogInjection::AccelScale { fraction: 0.02 }.apply(&mut injected.rows);
    let r = run(&injected, &truth, &cfg);
    let stride = r.stride_length.as_ref().expect("footprints given");
    eprintln!("{}", stride.finding.evidence);
    assert_eq!(stride.fit.kind, LegKind::CornerLegs, "{stride:?}");
    assert!(stride.finding.score >= SIGNIFICANT, "{stride:?}");
    assert!(stride.fit.ratio > 1.01, "{stride:?}");
    let it = r
        .iterations
        .iter()
        .find(|i| i.effect == Effect::StrideLength)
        .expect("the scale fix was tried");
    assert!(matches!(it.fix, Fix::StrideScale { .. }), "{:?}", it.fix);
    let Some(HeldOut::EachLeg {
        legs,
        rms_m: [held_before, held_after],
    }) = it.held_out
    else {
        panic!("judged leg by leg: {:?}", it.held_out)
    };
    assert_eq!(legs, stride.fit.legs);
    assert!(held_after < 0.8 * held_before, "{:?}", it.held_out);
    let (b, a) = (it.before.gcp_rms_m.unwrap(), it.after.gcp_rms_m.unwrap());
    assert!(it.kept && a < b, "the whole walk {b:.3} -> {a:.3} m");
}
