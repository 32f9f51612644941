//! Tests of the power fits and of how their findings enter the ranking.

use super::*;
use crate::diagnose::signature_fit::tests::noise;

#[test]
fn placebo_fits_are_standard_normal_on_white_residuals_and_wide_on_slow_ones() {
    // A signature that rises and falls over the walk (turns accumulating), and residuals
    // that are white, then a slow wave of their own (a period of 80 rows, ten times the
    // Newey–West window of HAC_LAGS rows): structure the window cannot see, which lines up
    // with the shifted signature now more, now less.
    let stance = |i: usize, r_rad: f64| StanceResidual {
        sample: i,
        t_s: i as f64,
        kind: ResidualKind::FootAxis,
        r_rad,
        direction_rad: 0.0,
        weight: 1.0,
        sd_rad: 0.2,
        candidates: crate::core::heading::Candidates::Spaced {
            spacing_rad: std::f64::consts::FRAC_PI_2,
        },
        accepted: true,
        signature: [(i as f64 / 15.0).sin(); N_REFERENCES],
    };
    let rms = |z: &[f64]| (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
    let white: Vec<StanceResidual> = (0..600).map(|i| stance(i, 0.01 * noise(i))).collect();
    let z = placebo_z(&white, 0, PLACEBO_SHIFTS);
    assert_eq!(z.len(), PLACEBO_SHIFTS);
    assert!((0.5..1.6).contains(&rms(&z)), "white: {z:?}");
    let slow: Vec<StanceResidual> = (0..600)
        .map(|i| stance(i, 0.02 * (i as f64 / 13.0 + 1.0).sin() + 0.005 * noise(i)))
        .collect();
    let z = placebo_z(&slow, 0, PLACEBO_SHIFTS);
    assert!(rms(&z) > 2.0, "slow wave: {z:?}");
}

/// A measured variant: a 5 % fit at `score`, detectable from 2 %.
fn power(effect: Effect, variant: &'static str, score: f64) -> Power {
    Power {
        effect,
        variant,
        unit: "fraction",
        estimate: 0.05,
        std_err: 0.005,
        score,
        mde: Some(0.02),
        cannot: None,
        residuals: 120,
        response: Some(0.9),
        mde_signature: Some(0.018),
        mde_check_failed: Vec::new(),
        indistinguishable_from: Vec::new(),
    }
}

#[test]
fn a_signature_scores_its_effect_where_the_residual_regression_has_no_finding() {
    // Too few used heading observations: the ranking has only `unexplained`.
    let only_unexplained = || {
        vec![Finding {
            name: Effect::Unexplained,
            score: 0.0,
            evidence: "only 5 heading observations: too few to test".into(),
            fix: None,
            mde: None,
        }]
    };
    let p = [
        power(Effect::GyroScaleFactor, "z scale", 30.0),
        power(Effect::Timing, "clock rate", 12.0),
    ];
    let mut effects = only_unexplained();
    apply_power(&mut effects, &p, true);
    assert_eq!(effects[0].name, Effect::GyroScaleFactor);
    assert_eq!(effects[0].score, 30.0);
    assert_eq!(effects[0].fix, Some(super::super::Fix::ScaleFactor));
    assert_eq!(effects[0].mde, Some(0.02));
    // said once: the report read "residual regression: residual regression: not tested"
    assert_eq!(
        effects[0].evidence.matches("residual regression:").count(),
        1,
        "{}",
        effects[0].evidence
    );
    // timing keeps its own tests: its signature only adds to their evidence
    assert!(effects.iter().all(|f| f.name != Effect::Timing));
    // the bias-filter modes do not score by the signature
    let mut effects = only_unexplained();
    apply_power(&mut effects, &p, false);
    assert_eq!(effects.len(), 1);
}

#[test]
fn a_degenerate_fit_scores_nothing_and_says_why() {
    // Residuals that follow the z scale's signature exactly: 3 of them fit any size at no
    // error (a 10 s log: −99 % at score 30, a review); 60 that say +50 %, far beyond any
    // plausible scale factor, are no sensor's either (a straight leg: −33° at 9.5 σ).
    let stance = |i: usize, scale: f64| StanceResidual {
        sample: i,
        t_s: i as f64,
        kind: ResidualKind::FootAxis,
        r_rad: scale * (i as f64 / 7.0).sin() + 1e-4 * noise(i),
        direction_rad: 0.0,
        weight: 1.0,
        sd_rad: 0.05,
        candidates: crate::core::heading::Candidates::Spaced {
            spacing_rad: std::f64::consts::FRAC_PI_2,
        },
        accepted: true,
        signature: [(i as f64 / 7.0).sin(); N_REFERENCES],
    };
    let z_scale = |stances: &[StanceResidual]| {
        walk_power(stances)
            .into_iter()
            .find(|p| p.variant == "z scale")
            .unwrap()
    };
    let few: Vec<StanceResidual> = (0..3).map(|i| stance(i, 0.01)).collect();
    let p = z_scale(&few);
    assert_eq!(p.score, 0.0, "{p:?}");
    assert!(
        p.cannot.as_deref().unwrap().contains("too few to fit"),
        "{p:?}"
    );
    let huge: Vec<StanceResidual> = (0..60).map(|i| stance(i, 0.5)).collect();
    let p = z_scale(&huge);
    assert_eq!(p.score, 0.0, "{p:?}");
    assert!(
        p.cannot
            .as_deref()
            .unwrap()
            .contains("beyond 2 × any plausible"),
        "{p:?}"
    );
    // A plausible size on as many residuals is scored.
    let real: Vec<StanceResidual> = (0..60).map(|i| stance(i, 0.03)).collect();
    let p = z_scale(&real);
    assert!(p.score >= SIGNIFICANT && p.cannot.is_none(), "{p:?}");
    assert!((p.estimate - 0.03).abs() < 0.005, "{p:?}");
}

#[test]
fn a_name_whose_variant_the_walk_cannot_show_says_so() {
    let power = |variant, score, cannot: Option<&str>| Power {
        effect: Effect::GyroScaleFactor,
        variant,
        unit: "fraction",
        estimate: 0.01,
        std_err: 0.002,
        score,
        mde: cannot.is_none().then_some(0.02),
        cannot: cannot.map(str::to_string),
        residuals: 120,
        response: Some(-0.53),
        mde_signature: Some(0.018),
        mde_check_failed: Vec::new(),
        indistinguishable_from: Vec::new(),
    };
    let named = |score| Finding {
        name: Effect::GyroScaleFactor,
        score,
        evidence: String::new(),
        fix: None,
        mde: None,
    };
    let why =
        "the model absorbs it: an injected 5.00 % moves the residuals by -53 % of its signature";
    let p = [power("z scale", 7.2, Some(why))];
    let caveat = named_but_cannot_show(&p, &named(7.2)).expect("a caveat");
    assert!(
        caveat.starts_with(&format!(
            "this walk cannot show z scale ({why}): the score 7.2"
        )),
        "{caveat}"
    );
    // a variant the walk can show, or a score that is not the signature's: no caveat
    let p = [power("z scale", 7.2, None)];
    assert_eq!(named_but_cannot_show(&p, &named(7.2)), None);
    let p = [power("z scale", 2.0, Some(why))];
    assert_eq!(named_but_cannot_show(&p, &named(7.2)), None);
}

#[test]
fn a_name_carries_the_effects_its_best_variant_cannot_be_told_from() {
    // exp18's clean walk: a z scale named at 7.3, its signature the clock rate's (ρ = +1.00) and
    // the x→z coupling's (−0.94); the y→z coupling's own list does not count, only the variant
    // that scored.
    let power = |effect, variant, score, alternatives: &[(&str, f64)]| Power {
        indistinguishable_from: alternatives
            .iter()
            .map(|&(v, rho)| (v.to_string(), rho))
            .collect(),
        ..power(effect, variant, score)
    };
    let p = [
        power(
            Effect::GyroScaleFactor,
            "z scale",
            7.3,
            &[("x→z coupling", -0.94), ("clock rate", 1.0)],
        ),
        power(
            Effect::AxisMisalignment,
            "y→z coupling",
            1.0,
            &[("g-sensitivity", 0.95)],
        ),
        power(Effect::AxisMisalignment, "x→z coupling", 0.5, &[]),
    ];
    let named = |name, score| Finding {
        name,
        score,
        evidence: String::new(),
        fix: None,
        mde: None,
    };
    let alternatives = indistinguishable_from_named(&p, &named(Effect::GyroScaleFactor, 7.3));
    let effects: Vec<(Effect, &str)> = alternatives
        .iter()
        .map(|(e, v, _)| (*e, v.as_str()))
        .collect();
    assert_eq!(
        effects,
        [
            (Effect::Timing, "clock rate"),
            (Effect::AxisMisalignment, "x→z coupling")
        ]
    );
    // a misalignment's best variant here is the y→z coupling
    let alternatives = indistinguishable_from_named(&p, &named(Effect::AxisMisalignment, 1.0));
    assert_eq!(alternatives.len(), 1);
    assert_eq!(alternatives[0].0, Effect::GSensitivity);
    // an effect without a signature fit carries none
    assert!(indistinguishable_from_named(&p, &named(Effect::HeadingOffset, 9.0)).is_empty());
}
