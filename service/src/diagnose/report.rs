//! The diagnosis report: `report.md`, `report.json` and the `residuals.svg` figure.

use super::analysis::{Analysis, Consistency, HeadingResidual};
use super::catalogue::{Effect, Fix};
use super::{HeldOut, Report};
use crate::runner::RunError;
use std::path::Path;

/// `report.md`, with the figures written next to it.
pub fn write_report(
    dir: &Path,
    report: &Report,
    before: &Analysis,
    after: &Analysis,
) -> Result<(), RunError> {
    use crate::plot::{Figure, Panel, Series};
    use crate::runner::io_at;
    let series = |a: &Analysis, label: &str| {
        let used: Vec<&HeadingResidual> = a.residuals.iter().filter(|r| r.accepted).collect();
        Series::markers(
            label.to_string(),
            used.iter().map(|r| r.t_s).collect(),
            used.iter().map(|r| r.r_rad.to_degrees()).collect(),
        )
    };
    let turn = |a: &Analysis, label: &str| {
        let used: Vec<&HeadingResidual> = a.residuals.iter().filter(|r| r.accepted).collect();
        Series::markers(
            label.to_string(),
            used.iter().map(|r| r.turn_rad.to_degrees()).collect(),
            used.iter().map(|r| r.r_rad.to_degrees()).collect(),
        )
    };
    let fig = Figure::new("Heading residuals before and after the diagnosis")
        .with_panel(
            Panel::new("residual against time", "t (s)", "ψ_map − ψ̂ (°)")
                .with_series(series(before, "before"))
                .with_series(series(after, "after")),
        )
        .with_panel(
            Panel::new(
                "residual against the turn since the last observation",
                "turn (°)",
                "ψ_map − ψ̂ (°)",
            )
            .with_series(turn(before, "before"))
            .with_series(turn(after, "after")),
        );
    let f = dir.join("residuals.svg");
    fig.write_svg(&f).map_err(io_at(&f))?;

    let mut md = String::from("# corridor diagnose\n\n");
    md.push_str(&format!(
        "Top effect on the starting model: **{}**.\n\n",
        report.verdict
    ));
    if let Some(c) = &report.verdict_caveat {
        md.push_str(&format!("But {c}.\n\n"));
    }
    if !report.top_indistinguishable_from.is_empty() {
        md.push_str(&format!(
            "On this walk its signature is indistinguishable from {} (|ρ| > {}): its heading \
             residuals cannot tell these apart.\n\n",
            report.top_indistinguishable_from.join(", "),
            super::power::INDISTINGUISHABLE_CORRELATION
        ));
    }
    md.push_str("## Effects on the starting model (score = −log₁₀ p; significant from 3)\n\n| effect | score | detectable size on this walk | evidence | fix |\n|---|---|---|---|---|\n");
    for e in &report.effects {
        let variants: Vec<String> = report
            .power
            .iter()
            .filter(|p| p.effect == e.name)
            .map(|p| variant_words(p, &e.evidence))
            .chain(
                report
                    .onset
                    .and_then(|o| o.mde)
                    .filter(|_| e.name == Effect::GSensitivity)
                    .map(onset_words),
            )
            .collect();
        let detectable = if !variants.is_empty() {
            variants.join("; ")
        } else if e.name == Effect::BiasDrift {
            let sizes: Vec<String> = super::DriftProbe::ALL
                .into_iter()
                .filter_map(|kind| {
                    let m = report.bias_change.as_ref().and_then(|c| kind.mde_of(c))?;
                    Some(if m <= kind.plausible_max() {
                        format!(
                            "{} ≥ {}",
                            kind.variant(),
                            super::format_unit(kind.unit(), m)
                        )
                    } else {
                        format!("{}: cannot show", kind.variant())
                    })
                })
                .collect();
            if sizes.is_empty() {
                "—".to_string()
            } else {
                sizes.join("; ")
            }
        } else if let Some(m) = e.mde {
            format!("≥ {:.2}°", m.to_degrees())
        } else {
            "—".to_string()
        };
        md.push_str(&format!(
            "| {} | {:.1} | {} | {} | {} |\n",
            e.name,
            e.score,
            detectable,
            e.evidence.replace('|', "/"),
            e.fix.map_or("—", Fix::label)
        ));
    }
    md.push_str(&unlisted_sizes(&report.power, &report.effects));
    md.push_str(&match &report.stride_length {
        Some(super::StrideLine { fit, finding: f }) => format!(
            "\nStride length against the footprints (position information, on the model the heading \
             effects left): score {:.1}, detectable from a {:.2} % scale; {}{}.\n",
            fit.score,
            100.0 * fit.mde,
            f.evidence,
            f.fix
                .filter(|_| fit.score >= super::SIGNIFICANT)
                .map_or(String::new(), |x| format!("; fix `{}`", x.label()))
        ),
        None => format!(
            "\nStride length: not tested (no footprints, or fewer than {} surveyed single strides \
             and fewer than {} surveyed legs, counted after the outlier rule).\n",
            super::MIN_LEGS,
            super::MIN_CORNER_LEGS
        ),
    });
    md.push_str("\n## Loop\n\n| step | effect added | fix | RMS before | RMS after | NIS before | NIS after | whiteness p before | after | kept |\n|---|---|---|---|---|---|---|---|---|---|\n");
    let rms = |c: &Consistency| c.gcp_rms_m.map_or("—".into(), |v| format!("{v:.2} m"));
    for (i, it) in report.iterations.iter().enumerate() {
        md.push_str(&format!(
            "| {} | {} | `{}` | {} | {} | {} | {} | {} | {} | {} |\n",
            i + 1,
            it.effect,
            it.fix,
            rms(&it.before),
            rms(&it.after),
            figure(it.before.nis_mean),
            figure(it.after.nis_mean),
            figure(it.before.whiteness_p),
            figure(it.after.whiteness_p),
            match (it.kept, it.held_out) {
                (k, Some(h)) => {
                    let [b, a] = h.rms_m();
                    format!(
                        "{} ({} {b:.2} → {a:.2} m)",
                        if k { "yes" } else { "no" },
                        match h {
                            HeldOut::SecondHalf { .. } =>
                                "fitted on the first half of the footprints; the second half".into(),
                            HeldOut::EachLeg { legs, .. } => format!(
                                "each of {legs} legs held out in turn, fitted on the others; \
                                 the held-out legs' length error"
                            ),
                        }
                    )
                }
                (true, None) => "yes".into(),
                (false, None) => "no".into(),
            }
        ));
    }
    for w in &report.truth_warnings {
        md.push_str(&format!(
            "\nFootprints: {w} (the footprint RMS before and after counts them).\n"
        ));
    }
    md.push_str(&format!(
        "\nBefore: {} ; after: {} ; final model: {}.\n",
        describe(&report.before),
        describe(&report.after),
        report.final_model.join(", ")
    ));
    if !report.final_estimates.is_empty() {
        md.push_str(&format!(
            "\nThe final model's sensor-error estimates: {}.\n",
            report.final_estimates.join(", ")
        ));
    }
    md.push_str("\n![residuals](residuals.svg)\n");
    let f = dir.join("report.md");
    std::fs::write(&f, md).map_err(io_at(&f))?;
    let f = dir.join("report.json");
    std::fs::write(
        &f,
        serde_json::to_string_pretty(report).expect("serialises") + "\n",
    )
    .map_err(io_at(&f))?;
    Ok(())
}

/// A variant's detectable size in the table, or that the walk cannot show it and why (the
/// reason the probe injection gave was in `report.json` only: the table said "cannot show"
/// beside evidence that said "detectable from …", a review), unless `evidence` says it.
fn variant_words(p: &super::Power, evidence: &str) -> String {
    match (p.mde, &p.cannot) {
        (Some(m), _) if p.mde_check_failed.is_empty() => {
            format!("{} ≥ {}", p.variant, p.format_size(m))
        }
        (Some(m), _) => format!(
            "{} ≥ {} (raised by its check by injection: {})",
            p.variant,
            p.format_size(m),
            p.mde_check_failed
                .iter()
                .map(|&[size, score, moved]| format!(
                    "at {} its fit moved {} (score {score:.1})",
                    p.format_size(size),
                    p.format_size(moved)
                ))
                .collect::<Vec<_>>()
                .join("; ")
        ),
        (None, Some(why)) if !evidence.contains(why.as_str()) => {
            format!("{}: cannot show ({why})", p.variant)
        }
        (None, _) => format!("{}: cannot show", p.variant),
    }
}

/// The detectable sizes of the measured variants whose effect has no row in the effects table
/// (no finding of its own on this walk), as a line after it: where the residual regression gave
/// no `timing` finding, the clock rate's size was in `report.json` only (a review: exp34 clipped).
fn unlisted_sizes(power: &[super::Power], effects: &[super::Finding]) -> String {
    let sizes: Vec<String> = power
        .iter()
        .filter(|p| !effects.iter().any(|e| e.name == p.effect))
        .map(|p| variant_words(p, ""))
        .collect();
    if sizes.is_empty() {
        String::new()
    } else {
        format!(
            "\nDetectable sizes of the effects without a row above (no finding of their own on \
             this walk): {}.\n",
            sizes.join("; ")
        )
    }
}

/// The onset test's detectable g-sensitivity in the table; beyond any plausible one the walk
/// cannot show it there, as the verdict says (the table gave `≥ 6.59e0 rad/s per m/s²` on a
/// clipped exp25, a review).
fn onset_words(m: f64) -> String {
    let max = super::REFERENCES
        .iter()
        .find(|r| r.effect == Effect::GSensitivity)
        .map_or(f64::INFINITY, |r| r.plausible_max);
    if m <= max {
        format!("at the onset of walking ≥ {m:.2e} rad/s per m/s²")
    } else {
        format!(
            "at the onset of walking: cannot show (the smallest size it shows would be {m:.2e} \
             rad/s per m/s², beyond any plausible {max:.2e})"
        )
    }
}

/// A consistency figure with two decimals, or `—` where there is none (no heading observation
/// used: the NIS and the whiteness of nothing were printed as `NaN`, a review).
fn figure(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2}")
    } else {
        "—".into()
    }
}

fn describe(c: &Consistency) -> String {
    let heading = if c.observations == 0 || !c.nis_mean.is_finite() {
        "no heading observation used (no NIS, no whiteness)".to_string()
    } else {
        format!(
            "NIS {:.2} (band {:.2}–{:.2}), whiteness p {}",
            c.nis_mean,
            c.nis_band[0],
            c.nis_band[1],
            figure(c.whiteness_p)
        )
    };
    format!(
        "footprint RMS {}, {heading}, bias ({:.5}, {:.5}, {:.5}) ± ({:.1e}, {:.1e}, {:.1e}) rad/s",
        c.gcp_rms_m.map_or("n/a".into(), |v| format!("{v:.2} m")),
        c.bias_rad_s[0],
        c.bias_rad_s[1],
        c.bias_rad_s[2],
        c.bias_sd_rad_s[0],
        c.bias_sd_rad_s[1],
        c.bias_sd_rad_s[2]
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_model_that_used_no_heading_observation_says_so_not_nan() {
        // exp17 with a 2e-2 g-sensitivity, exp37 clipped: "NIS NaN (band NaN–NaN), whiteness
        // p NaN" (a review).
        let mut c = Consistency {
            gcp_rms_m: Some(1.25),
            gcp_rms_pct: Some(3.9),
            nis_mean: f64::NAN,
            nis_band: [f64::NAN; 2],
            whiteness_p: f64::NAN,
            whiteness_fraction_outside: f64::NAN,
            observations: 0,
            rss_rad2: 0.0,
            nis_too_large: false,
            nis_p: f64::NAN,
            bias_rad_s: [1e-3, -2e-3, 3e-3],
            bias_sd_rad_s: [1e-4; 3],
        };
        let text = describe(&c);
        assert!(!text.contains("NaN"), "{text}");
        assert!(text.contains("no heading observation used"), "{text}");
        assert_eq!(figure(f64::NAN), "—");
        c.observations = 12;
        c.nis_mean = 0.8;
        c.nis_band = [0.4, 1.8];
        c.whiteness_p = 0.35;
        let text = describe(&c);
        assert!(
            text.contains("NIS 0.80 (band 0.40–1.80), whiteness p 0.35"),
            "{text}"
        );
    }

    #[test]
    fn the_table_says_why_a_walk_cannot_show_a_variant_and_an_onset_size() {
        let why =
            "the model absorbs it: an injected 5.00 % moves the residuals by -1 % of its signature";
        let p = super::super::Power {
            effect: Effect::GyroScaleFactor,
            variant: "z scale",
            unit: "fraction",
            estimate: -0.018,
            std_err: 0.006,
            score: 2.4,
            mde: None,
            cannot: Some(why.into()),
            residuals: 110,
            response: Some(-0.013),
            mde_signature: Some(0.0206),
            mde_check_failed: Vec::new(),
            indistinguishable_from: Vec::new(),
        };
        let evidence = "z scale: signature fit -1.81 % ± 0.62 %, detectable from 2.06 % if the \
                        residuals follow the signature";
        assert_eq!(
            variant_words(&p, evidence),
            format!("z scale: cannot show ({why})")
        );
        // said once: a reason the evidence gives already is not repeated
        assert_eq!(
            variant_words(&p, &format!("{evidence}; this walk cannot show it: {why}")),
            "z scale: cannot show"
        );
        let shown = super::super::Power {
            mde: Some(0.0263),
            cannot: None,
            ..p.clone()
        };
        assert_eq!(variant_words(&shown, evidence), "z scale ≥ 2.63 %");
        // a size its check by injection raised says from what (exp32's z scale)
        let raised = super::super::Power {
            mde: Some(0.0374),
            mde_check_failed: vec![[0.0374, 30.0, -0.01]],
            ..shown.clone()
        };
        assert_eq!(
            variant_words(&raised, evidence),
            "z scale ≥ 3.74 % (raised by its check by injection: at 3.74 % its fit moved -1.00 % \
             (score 30.0))"
        );
        assert_eq!(
            onset_words(5.86e-3),
            "at the onset of walking ≥ 5.86e-3 rad/s per m/s²"
        );
        assert!(
            onset_words(6.59).starts_with("at the onset of walking: cannot show"),
            "{}",
            onset_words(6.59)
        );
        // A variant whose effect has no finding (no `timing` row): its size after the table.
        let clock = super::super::Power {
            effect: Effect::Timing,
            variant: "clock rate",
            mde: Some(0.0125),
            cannot: None,
            ..p.clone()
        };
        let sf = super::super::Finding {
            name: Effect::GyroScaleFactor,
            score: 4.0,
            evidence: evidence.into(),
            fix: None,
            mde: None,
        };
        let line = unlisted_sizes(&[p.clone(), clock.clone()], std::slice::from_ref(&sf));
        assert!(line.contains(": clock rate ≥ 1.25 %."), "{line}");
        assert!(!line.contains("z scale"), "{line}");
        assert_eq!(unlisted_sizes(&[p, clock], &[]).matches("≥").count(), 1);
    }
}
