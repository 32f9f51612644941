//! The detection matrix's Markdown (`detection.md`): per column the counts over the recordings,
//! the stride-length line of the clean walks, the effect named first on each walk, and the
//! predicted detectable sizes against the injections.

use super::detection::{DetectionMatrix, MatrixCell, StrideFigure};
use crate::diagnose::{Effect, SIGNIFICANT};

/// The short strides of the clean walks (an effect only the footprints show, tested after the
/// heading effects): on how many walks it could be tested, named, and fixed.
fn stride_markdown(m: &DetectionMatrix) -> String {
    let clean: Vec<&MatrixCell> = m
        .cells
        .iter()
        .filter(|c| c.expected.is_none() && c.case == m.cases[0])
        .collect();
    let tested: Vec<(&MatrixCell, StrideFigure)> = clean
        .iter()
        .filter_map(|c| c.stride_length.map(|s| (*c, s)))
        .collect();
    let named: Vec<String> = tested
        .iter()
        .filter(|(_, s)| s.score >= SIGNIFICANT)
        .map(|(c, s)| {
            let kept = c.added.iter().any(|a| a == "stride_length");
            format!(
                "{} {:.3}{}",
                c.recording.split(' ').next().unwrap_or(&c.recording),
                s.ratio,
                match (s.fixable, kept) {
                    (true, true) => "",
                    (true, false) => " (fix not kept)",
                    (false, _) => " (no fix: the model has the rolling update)",
                }
            )
        })
        .collect();
    format!(
        "\nStride length on the clean walks (estimated / surveyed leg length; position information, \
         tried after the heading effects, with the rolling-foot stance update as its fix): tested on {} of {} \
         walks (on the surveyed single strides where there are {} or more, else on the legs between \
         surveyed corners where there are {}; corner legs on {}), named on {}: {}.\n",
        tested.len(),
        clean.len(),
        crate::diagnose::MIN_LEGS,
        crate::diagnose::MIN_CORNER_LEGS,
        tested.iter().filter(|(_, s)| s.corner_legs).count(),
        named.len(),
        if named.is_empty() {
            "—".to_string()
        } else {
            named.join(", ")
        }
    )
}

/// The wrong names over the injected columns: an effect named first that is not the injected
/// one, and on how many of those the diagnosis said the first is indistinguishable on that walk
/// from the injected effect.
fn wrong_names_markdown(m: &DetectionMatrix) -> String {
    let injected: Vec<&MatrixCell> = m
        .cells
        .iter()
        .filter(|c| c.expected.is_some() && !c.already_modelled)
        .filter(|c| c.expected.as_deref() != Some(Effect::StrideLength.name()))
        .collect();
    let wrong: Vec<&&MatrixCell> = injected
        .iter()
        .filter(|c| !c.named_first && c.top_effect != "none")
        .collect();
    let said = wrong
        .iter()
        .filter(|c| c.expected_is_indistinguishable_from_first())
        .count();
    format!(
        "\nWrong names (the heading effects' injected columns, stride length aside): an effect other \
         than the injected one named first on {} of {} cells; on {said} of them the diagnosis says \
         that on this walk the first one's signature is indistinguishable from the injected \
         effect's (`sf≈time` below), so {} are wrong names without that caveat.\n",
        wrong.len(),
        injected.len(),
        wrong.len() - said
    )
}

/// `detection.md`: per column the counts over the recordings, then the matrix of the effect
/// named first.
pub fn matrix_markdown(m: &DetectionMatrix) -> String {
    let n = m.recordings.len();
    let mut md = format!(
        "The diagnosis on its own model (the sensor configuration without `[model]` extensions, the foot axis observed alone, the plain gate, the baseline's filter noise; see `diagnosis_model`). The clean column runs first; the effects it names are the walk's own, and the injected columns start from the model with their fixes (a column whose effect is already in that model is left out of its counts). Per column, over the {n} normal-gait recordings: the injected effect named first, named first or its injected variant among those the diagnosis says the first is indistinguishable from on that walk (its signature correlating above 0.9: `top_indistinguishable_from`), named at all (score ≥ 3), the footprint error lower after the loop, and, for the clean and out-of-catalogue columns, how many walks name anything. The predicted detectable size is the diagnosis's own for the injected variant on each walk (median over the walks; for the bias ramp and step, the bias-change test's, from its own probe: walks too short for the test are left out of the median).\n\n| injection | expected | named first | named first, or indistinguishable from the first | named at all | after-error lower | median score | predicted detectable size (median) | size injected |\n|---|---|---|---|---|---|---|---|---|\n"
    );
    for case in &m.cases {
        let all: Vec<&MatrixCell> = m.cells.iter().filter(|c| &c.case == case).collect();
        let modelled = all.iter().filter(|c| c.already_modelled).count();
        let cells: Vec<&MatrixCell> = all.into_iter().filter(|c| !c.already_modelled).collect();
        let n = cells.len();
        let count = |f: &dyn Fn(&MatrixCell) -> bool| cells.iter().filter(|c| f(c)).count();
        let expected = cells.first().and_then(|c| c.expected.clone());
        let lower =
            count(&|c| matches!((c.rms_before_m, c.rms_after_m), (Some(b), Some(a)) if a < b));
        let mut scores: Vec<f64> = cells.iter().filter_map(|c| c.expected_score).collect();
        let mut mdes: Vec<f64> = cells.iter().filter_map(|c| c.expected_mde).collect();
        let size = cells.first().map_or(0.0, |c| c.size);
        if expected.is_none() {
            let named = count(&|c| c.top_effect != "none");
            md.push_str(&format!(
                "| {case} | (nothing) | — | — | named something: {named} of {n} | {lower} of {n} | — | — | — |\n"
            ));
            continue;
        }
        md.push_str(&format!(
            "| {case} | {}{} | {} of {n} | {} of {n} | {} of {n} | {lower} of {n} | {} | {} | {} |\n",
            expected.as_deref().unwrap_or("—"),
            if modelled > 0 {
                format!(" ({modelled} walks left out: already modelled)")
            } else {
                String::new()
            },
            count(&|c| c.named_first),
            count(&|c| c.named_first || c.expected_is_indistinguishable_from_first()),
            count(&|c| c.named_at_all),
            median(&mut scores).map_or("—".into(), |v| format!("{v:.1}")),
            median(&mut mdes).map_or("—".into(), |v| format!("{v:.3e}")),
            format_args!("{size:.3e}"),
        ));
    }
    md.push_str(&wrong_names_markdown(m));
    md.push_str(&stride_markdown(m));
    md.push_str("\nThe effect named first on each walk (`·` nothing significant; **bold** = the injected effect; in parentheses: the starting model already had the injected effect's state):\n\n| recording |");
    for case in &m.cases {
        md.push_str(&format!(" {case} |"));
    }
    md.push_str("\n|---|");
    md.push_str(&"---|".repeat(m.cases.len()));
    md.push('\n');
    for rec in &m.recordings {
        md.push_str(&format!("| {rec} |"));
        for case in &m.cases {
            let c = m
                .cells
                .iter()
                .find(|c| &c.recording == rec && &c.case == case);
            let text = c.map_or("?".to_string(), |c| {
                let stride = c.expected.as_deref() == Some(Effect::StrideLength.name());
                let name = if stride && c.named_first {
                    "stride".to_string() // on its own line, not the heading effects'
                } else if c.top_effect == "none" {
                    "·".to_string()
                } else {
                    short(&c.top_effect).to_string()
                };
                // the first, and the injected effect it cannot be told from on this walk
                let name = if c.expected_is_indistinguishable_from_first() {
                    format!("{name}≈{}", short(c.expected.as_deref().unwrap_or("")))
                } else {
                    name
                };
                if c.already_modelled {
                    format!("({name})")
                } else if c.named_first {
                    format!("**{name}**")
                } else {
                    name
                }
            });
            md.push_str(&format!(" {text} |"));
        }
        md.push('\n');
    }
    md.push_str(&prediction_markdown(m));
    md.push_str(&super::mde_scan::scan_markdown(&m.mde_scan));
    md.push_str("\nAbbreviations: sf gyro_scale_factor, mis axis_misalignment, drift bias_drift, off heading_offset, time timing, gs g_sensitivity, tilt mounting_tilt, clip gyro_clipping, unexp unexplained, stride stride_length (its own line: the cell shows it when named there, else the heading effect named first).\n");
    if !m.failed.is_empty() {
        let errors: Vec<&str> = m.failed.iter().map(|f| f.error.as_str()).collect();
        md.push_str(&format!(
            "\nNot in the matrix (its run failed): {}.\n",
            errors.join("; ")
        ));
    }
    md
}

fn short(name: &str) -> &str {
    match name {
        "gyro_scale_factor" => "sf",
        "axis_misalignment" => "mis",
        "bias_drift" => "drift",
        "heading_offset" => "off",
        "timing" => "time",
        "g_sensitivity" => "gs",
        "mounting_tilt" => "tilt",
        "gyro_clipping" => "clip",
        "unexplained" => "unexp",
        other => other,
    }
}

fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

/// Predicted against shown: per walk and injected family (z scale, clock, couplings, the
/// sizes of [`matrix_cases`](super::matrix_cases)), the detectable size the diagnosis predicts on the clean walk and
/// the sizes at which the injection was named at all. The shown threshold lies between the
/// largest size missed below the smallest named and that size; the prediction agrees within a
/// factor of 2 when that interval meets [MDE/2, 2·MDE].
pub fn prediction_markdown(m: &DetectionMatrix) -> String {
    let families: [(&str, &str); 4] = [
        ("z scale", "z scale"),
        ("y→z coupling", "y→z"),
        ("x→z coupling", "x→z"),
        ("clock rate", "clock"),
    ];
    let mut md = String::from(
        "\nPredicted detectable size (on the clean walk) against the injections: `named at` lists the injected sizes named at all (score ≥ 3); `agrees` when the shown threshold (between the largest size missed and the smallest named, above the largest injected when none is named) meets [½, 2] × the prediction. Cells where the starting model already had the effect's state are left out.\n\n| recording |",
    );
    for (variant, _) in &families {
        md.push_str(&format!(" {variant}: predicted | named at | agrees |"));
    }
    md.push_str("\n|---|");
    md.push_str(&"---|---|---|".repeat(families.len()));
    md.push('\n');
    let mut agree = vec![(0usize, 0usize); families.len()];
    for rec in &m.recordings {
        md.push_str(&format!("| {rec} |"));
        let clean = m
            .cells
            .iter()
            .find(|c| &c.recording == rec && c.case == "clean");
        for (k, (variant, prefix)) in families.iter().enumerate() {
            let predicted = clean.and_then(|c| {
                c.detectable
                    .iter()
                    .find(|(v, _)| v == variant)
                    .and_then(|(_, m)| *m)
            });
            let cells: Vec<&MatrixCell> = m
                .cells
                .iter()
                .filter(|c| &c.recording == rec && c.case.starts_with(prefix))
                .collect();
            if cells.is_empty() || cells.iter().any(|c| c.already_modelled) {
                md.push_str(" — | (modelled) | — |");
                continue;
            }
            let mut sizes: Vec<(f64, bool)> =
                cells.iter().map(|c| (c.size, c.named_at_all)).collect();
            sizes.sort_by(|a, b| a.0.total_cmp(&b.0));
            let named: Vec<f64> = sizes.iter().filter(|s| s.1).map(|s| s.0).collect();
            let (lo, hi) = match named.first() {
                Some(&first) => (
                    sizes
                        .iter()
                        .filter(|s| s.0 < first && !s.1)
                        .map(|s| s.0)
                        .fold(0.0, f64::max),
                    first,
                ),
                None => (sizes.last().map_or(0.0, |s| s.0), f64::INFINITY),
            };
            let agrees = predicted.map(|p| lo <= 2.0 * p && hi >= 0.5 * p);
            if let Some(a) = agrees {
                agree[k].1 += 1;
                agree[k].0 += usize::from(a);
            }
            let unit = |v: f64| {
                if variant.contains("coupling") {
                    format!("{:.2}°", v.to_degrees())
                } else {
                    format!("{:.2} %", 100.0 * v)
                }
            };
            md.push_str(&format!(
                " {} | {} | {} |",
                predicted.map_or("cannot".to_string(), unit),
                if named.is_empty() {
                    "none".to_string()
                } else {
                    named
                        .iter()
                        .map(|&v| unit(v))
                        .collect::<Vec<_>>()
                        .join(", ")
                },
                match agrees {
                    Some(true) => "yes",
                    Some(false) => "no",
                    None => "—",
                }
            ));
        }
        md.push('\n');
    }
    md.push_str("| **agree** |");
    for (a, n) in &agree {
        md.push_str(&format!(" | | {a} of {n} |"));
    }
    md.push('\n');
    md
}
