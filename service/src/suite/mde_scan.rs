//! The detectable sizes checked by injection, part of the detection matrix (`corridor diagnose
//! --suite`): on each normal-gait walk, for each effect whose power the diagnosis measures
//! ([`REFERENCES`]: z scale, the two couplings into z, clock rate, g-sensitivity), the size the
//! diagnosis predicts it can detect on the clean walk, then that effect injected at
//! [`MDE_FACTORS`] times the prediction (up to the largest size plausible for a working sensor,
//! [`Reference::plausible_max`](crate::diagnose::Reference)), each judged afresh: its power
//! score (the matched filter's `β̂/se`, the figure the prediction is about) and whether the
//! ranking names it at all. The onset test of a g-sensitivity (the bias change when walking
//! begins, [`crate::diagnose::onset_change`]) has its own row, [`ONSET_VARIANT`]: its
//! prediction comes from the same probe injection, its score is the test's own. So have the
//! bias-change test's step and ramp on z ([`crate::diagnose::DriftProbe`]), each predicted from
//! its own probe.
//!
//! A prediction is right when the walk shows the effect from about the predicted size on: at
//! that size the score reaches the threshold half the time, at twice it almost always (an
//! expected z of 6.6 against 3.3), at half it seldom (1.6). With one noise draw per walk the
//! scan gives, per walk, the smallest factor from which every larger one is detected; the
//! prediction agrees within a factor of 2 when that factor lies in [½, 2].

use super::SuiteRecording;
use super::detection::injected_walk;
use crate::diagnose::BLOCK_S;
use crate::diagnose::{
    Analysis, DriftProbe, Effect, MDE_Z, OnsetChange, PLACEBO_SHIFTS, REFERENCES, Reference,
    SIGNIFICANT, apply_fix, format_unit, judge, judge_names, placebo_z,
};
use crate::runner::RunError;
use crate::stats::normal_cdf;
use corridor_shared::config::ConfigFile;
use corridor_shared::imu_csv::ImuLog;
use corridor_shared::injection::LogInjection;
use corridor_shared::truth_csv::TruthPoint;
use serde::Serialize;

/// The injected sizes, as multiples of the walk's predicted detectable size (steps of √2 from
/// ¼ to 4).
pub const MDE_FACTORS: [f64; 9] = [
    0.25,
    0.353_553_390_593_273_8,
    0.5,
    std::f64::consts::FRAC_1_SQRT_2,
    1.0,
    std::f64::consts::SQRT_2,
    2.0,
    2.828_427_124_746_190_3,
    4.0,
];

/// The row of the onset test (a g-sensitivity seen in the bias when walking begins:
/// [`crate::diagnose::onset_change`]), scanned as the power fits are.
pub const ONSET_VARIANT: &str = "g-sensitivity, onset";

/// Why a row has no scan when the starting model has the effect's state.
const MODELLED: &str = "the starting model has the effect's state";

/// One injected size of a scan.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ScanPoint {
    /// Multiple of the predicted detectable size.
    pub factor: f64,
    /// The injected size (the effect's unit).
    pub size: f64,
    /// The power fit of the injected variant: the size the residuals show.
    pub estimate: f64,
    /// Its score (−log₁₀ p).
    pub power_score: f64,
    /// The ranking names the effect (score ≥ [`SIGNIFICANT`]).
    pub named: bool,
}

/// The scan of one effect on one walk.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ScanRow {
    /// Recording.
    pub recording: String,
    /// The variant (`z scale`, `y→z coupling` …).
    pub variant: String,
    /// Unit of the sizes.
    pub unit: String,
    /// The detectable size predicted on the clean walk.
    pub predicted: Option<f64>,
    /// The power score of the clean walk itself: from [`SIGNIFICANT`] on, the walk already
    /// shows the effect (or something with its signature) and an injection of any size is
    /// "detected": the scan cannot check the prediction there.
    pub clean_score: Option<f64>,
    /// The clean walk's fitted size `β̂` and its standard error (the effect's unit).
    pub clean_estimate: Option<(f64, f64)>,
    /// The RMS of [`PLACEBO_SHIFTS`] placebo z-scores on the clean walk (the signature moved
    /// along the walk, [`placebo_z`]): about 1 where the standard error is right.
    pub placebo_z_rms: Option<f64>,
    /// The response the prediction assumed: the part of the signature a probe injection moved
    /// the clean walk's residuals by (the prediction is `MDE_Z·se/response`).
    pub response: Option<f64>,
    /// Why there is no scan: the walk cannot show the effect (the diagnosis's reason), or the
    /// starting model already has the effect's state.
    pub skipped: Option<String>,
    /// The injected sizes, smallest first.
    pub points: Vec<ScanPoint>,
    /// The smallest factor from which the power score reaches [`SIGNIFICANT`] at every larger
    /// one (`None`: not at the largest injected).
    pub power_from: Option<f64>,
    /// The same for the ranking's naming of the effect.
    pub named_from: Option<f64>,
}

impl ScanRow {
    /// The prediction agrees within a factor of 2 with the power scores (`None` without a scan).
    pub fn power_agrees(&self) -> Option<bool> {
        self.scanned().then(|| within_factor_2(self.power_from))
    }

    /// The prediction agrees within a factor of 2 with the ranking's naming.
    pub fn named_agrees(&self) -> Option<bool> {
        self.scanned().then(|| within_factor_2(self.named_from))
    }

    /// The clean walk's own power score is significant.
    pub fn shows_clean(&self) -> bool {
        self.clean_score.is_some_and(|s| s >= SIGNIFICANT)
    }

    fn scanned(&self) -> bool {
        !self.points.is_empty()
    }
}

/// Where the prediction is right, the share of walks whose power score reaches the threshold
/// at `factor` times the predicted size: the fitted size is the injected one plus the walk's
/// own noise, `β̂/se = z + MDE_Z·factor` with `z` standard normal, detected when
/// `|β̂/se| ≥ MDE_Z`.
pub fn expected_detection(factor: f64) -> f64 {
    1.0 - normal_cdf(MDE_Z * (1.0 - factor)) + normal_cdf(-MDE_Z * (1.0 + factor))
}

/// Where the prediction is right, the share of walks on which it agrees within a factor of 2:
/// detected from 2× on ([`MDE_FACTORS`]' 2, 2.8 and 4) but not at 0.35× (the factor below ½;
/// detection grows with the factor on the side that matters, so these two bound the run).
pub fn expected_agreement() -> f64 {
    expected_detection(2.0) - expected_detection(MDE_FACTORS[1])
}

fn within_factor_2(from: Option<f64>) -> bool {
    // the grid's factors are computed, not typed: compare with a margin
    from.is_some_and(|f| (0.5 - 1e-9..=2.0 + 1e-9).contains(&f))
}

/// The smallest factor from which every larger factor is detected: the scan's points are in
/// increasing size. `None` when the largest is not detected.
pub fn detected_from(points: &[(f64, bool)]) -> Option<f64> {
    let mut from = None;
    for &(factor, detected) in points.iter().rev() {
        if !detected {
            break;
        }
        from = Some(factor);
    }
    from
}

/// Whether `model` already has the state that fixes `effect` (every fix of the effect is a
/// no-op on it): an injection of the effect is then absorbed, and nothing is left to name.
pub fn already_modelled(effect: Effect, model: &ConfigFile) -> bool {
    !effect.fixes().is_empty()
        && effect
            .fixes()
            .iter()
            .all(|&(fix, _)| !apply_fix(fix, &mut model.clone()))
}

/// The scan of every measured effect on one walk, on the walk's starting `model` (the one the
/// matrix's injected columns use); `progress` sees each row when it is done.
pub fn scan_walk(
    r: &SuiteRecording,
    log: &ImuLog,
    truth: &[TruthPoint],
    model: &ConfigFile,
    mut progress: impl FnMut(&ScanRow),
) -> Result<Vec<ScanRow>, RunError> {
    let (clean, _) = judge(log, model, Some(truth), None)?;
    let mut rows = Vec::new();
    for (k, reference) in REFERENCES.iter().enumerate() {
        let power = clean.power.iter().find(|p| p.variant == reference.variant);
        let placebo = placebo_z(&clean.stances, k, PLACEBO_SHIFTS);
        let mut row = ScanRow {
            recording: r.name.clone(),
            variant: reference.variant.to_string(),
            unit: reference.unit.to_string(),
            predicted: power.and_then(|p| p.mde),
            clean_score: power.map(|p| p.score),
            clean_estimate: power.map(|p| (p.estimate, p.std_err)),
            response: power.and_then(|p| p.response),
            placebo_z_rms: (!placebo.is_empty()).then(|| {
                (placebo.iter().map(|z| z * z).sum::<f64>() / placebo.len() as f64).sqrt()
            }),
            ..ScanRow::default()
        };
        if already_modelled(reference.effect, model) {
            row.skipped = Some(MODELLED.into());
        } else if let Some(predicted) = row.predicted {
            // Sizes beyond any plausible one of a working sensor are not injected: there the
            // filter itself fails (a g-sensitivity of 0.04 rad/s per m/s² leaves no fit).
            scan_points(
                &mut row,
                log,
                truth,
                model,
                &Probe::of(reference),
                predicted,
                |a| {
                    let fit = a.power.iter().find(|p| p.variant == reference.variant);
                    (
                        fit.map_or(f64::NAN, |p| p.estimate),
                        fit.map_or(0.0, |p| p.score),
                    )
                },
            )?;
        } else {
            row.skipped = Some(
                power
                    .and_then(|p| p.cannot.clone())
                    .unwrap_or_else(|| "no prediction".into()),
            );
        }
        progress(&row);
        rows.push(row);
    }
    let row = scan_onset(r, log, truth, model, &clean)?;
    progress(&row);
    rows.push(row);
    for kind in DriftProbe::ALL {
        let row = scan_drift(kind, r, log, truth, model, &clean)?;
        progress(&row);
        rows.push(row);
    }
    Ok(rows)
}

/// The scan of the onset test's detectable g-sensitivity: injected at [`MDE_FACTORS`] times it,
/// its own score (when it points along the force change) and the ranking's naming.
fn scan_onset(
    r: &SuiteRecording,
    log: &ImuLog,
    truth: &[TruthPoint],
    model: &ConfigFile,
    clean: &Analysis,
) -> Result<ScanRow, RunError> {
    let reference = REFERENCES
        .iter()
        .find(|x| x.effect == Effect::GSensitivity)
        .expect("g-sensitivity is a reference");
    let test_score = |o: Option<&OnsetChange>| o.filter(|o| o.explains()).map_or(0.0, |o| o.score);
    let mut row = ScanRow {
        recording: r.name.clone(),
        variant: ONSET_VARIANT.to_string(),
        unit: reference.unit.to_string(),
        predicted: clean.onset.and_then(|o| o.mde),
        clean_score: clean.onset.as_ref().map(|o| test_score(Some(o))),
        clean_estimate: clean.onset.map(|o| (o.k_taken_up, f64::NAN)),
        ..ScanRow::default()
    };
    if already_modelled(reference.effect, model) {
        row.skipped = Some(MODELLED.into());
        return Ok(row);
    }
    let Some(predicted) = row.predicted else {
        row.skipped = Some("no onset test (no rest before the walk, or too short)".into());
        return Ok(row);
    };
    scan_points(
        &mut row,
        log,
        truth,
        model,
        &Probe::of(reference),
        predicted,
        |a| {
            (
                a.onset.map_or(f64::NAN, |o| o.k_taken_up),
                test_score(a.onset.as_ref()),
            )
        },
    )?;
    Ok(row)
}

/// The scan of the bias-change test's detectable step or ramp ([`crate::diagnose::drift_mde`]):
/// the probe's change on z injected at [`MDE_FACTORS`] times it, the test's own score and the
/// ranking's naming of a bias drift.
fn scan_drift(
    kind: DriftProbe,
    r: &SuiteRecording,
    log: &ImuLog,
    truth: &[TruthPoint],
    model: &ConfigFile,
    clean: &Analysis,
) -> Result<ScanRow, RunError> {
    let test_score = |a: &Analysis| a.bias_change.as_ref().map_or(0.0, |c| c.score);
    let mut row = ScanRow {
        recording: r.name.clone(),
        variant: kind.variant().to_string(),
        unit: kind.unit().to_string(),
        predicted: clean.bias_change.as_ref().and_then(|c| kind.mde_of(c)),
        clean_score: clean.bias_change.as_ref().map(|_| test_score(clean)),
        ..ScanRow::default()
    };
    if already_modelled(Effect::BiasDrift, model) {
        row.skipped = Some(MODELLED.into());
        return Ok(row);
    }
    let why_not = if !clean.bias_change_applies {
        Some(
            "no bias-change test for this model (its bias is no random walk of the error-state filter, or it never tracked)",
        )
    } else if clean.bias_change.is_none() {
        Some("no bias-change test (fewer than two blocks with a usable σ after tracking began)")
    } else {
        match row.predicted {
            None => Some(
                "not measured (the probe's run gave no test with the same blocks, or did not move it)",
            ),
            Some(m) if m > kind.plausible_max() => Some("beyond any plausible size"),
            Some(_) => None,
        }
    };
    if let Some(why) = why_not {
        row.skipped = Some(why.into());
        return Ok(row);
    }
    let predicted = row.predicted.expect("measured above");
    let inject = |size| kind.injection(&log.rows, size);
    let probe = Probe {
        effect: Effect::BiasDrift,
        inject: &inject,
        plausible_max: kind.plausible_max(),
    };
    scan_points(&mut row, log, truth, model, &probe, predicted, |a| {
        (f64::NAN, test_score(a))
    })?;
    Ok(row)
}

/// What a scan injects: the effect the ranking should name, the injection of a size, and the
/// largest size a working sensor could have.
struct Probe<'a> {
    effect: Effect,
    inject: &'a dyn Fn(f64) -> LogInjection,
    plausible_max: f64,
}

impl<'a> Probe<'a> {
    fn of(reference: &'a Reference) -> Self {
        Probe {
            effect: reference.effect,
            inject: &reference.probe,
            plausible_max: reference.plausible_max,
        }
    }
}

/// Injects `probe` at [`MDE_FACTORS`] × `predicted` (up to its plausible limit), judges each
/// afresh, and fills `row`'s points and the factors its test (`test`: the estimate and score of
/// the judged walk) and the ranking's naming hold from.
fn scan_points(
    row: &mut ScanRow,
    log: &ImuLog,
    truth: &[TruthPoint],
    model: &ConfigFile,
    probe: &Probe,
    predicted: f64,
    test: impl Fn(&Analysis) -> (f64, f64),
) -> Result<(), RunError> {
    for factor in MDE_FACTORS
        .into_iter()
        .filter(|f| f * predicted <= probe.plausible_max)
    {
        let size = factor * predicted;
        let (injected, truth) = injected_walk(log, truth, &(probe.inject)(size));
        let (a, _) = judge_names(&injected, model, Some(&truth), None)?;
        let (estimate, power_score) = test(&a);
        row.points.push(ScanPoint {
            factor,
            size,
            estimate,
            power_score,
            named: a
                .effects
                .iter()
                .any(|f| f.name == probe.effect && f.score >= SIGNIFICANT),
        });
    }
    let flags = |hit: fn(&ScanPoint) -> bool| -> Vec<(f64, bool)> {
        row.points.iter().map(|p| (p.factor, hit(p))).collect()
    };
    row.power_from = detected_from(&flags(|p| p.power_score >= SIGNIFICANT));
    row.named_from = detected_from(&flags(|p| p.named));
    Ok(())
}

fn format_from(from: Option<f64>, largest: f64) -> String {
    from.map_or(format!("> {largest:.2}×"), |f| format!("{f:.2}×"))
}

/// The scans' Markdown: per walk and effect the prediction and the factors from which the
/// power score and the ranking's naming hold; then, per effect, on how many walks each holds at
/// each factor, and on how many the prediction agrees within a factor of 2.
pub fn scan_markdown(rows: &[ScanRow]) -> String {
    let variants: Vec<&str> = REFERENCES
        .iter()
        .map(|r| r.variant)
        .chain([ONSET_VARIANT])
        .chain(DriftProbe::ALL.map(DriftProbe::variant))
        .collect();
    let mut recordings: Vec<&str> = Vec::new();
    for r in rows {
        if !recordings.contains(&r.recording.as_str()) {
            recordings.push(&r.recording);
        }
    }
    let mut md = format!(
        "
Predicted detectable sizes checked by injection: each effect injected into the clean walk at {} × the size the diagnosis predicts there (the walk's starting model, as in the injected columns), judged afresh; sizes beyond any plausible one of a working sensor are left out (`to k×`: the largest injected). `power from`: the smallest factor from which the power fit's score reaches {SIGNIFICANT} at every larger one (the figure the prediction is about: reached half the time at 1×, almost always at 2×); `named from`: the same for the ranking naming the effect. The prediction agrees within a factor of 2 when that factor is in [½, 2]. `(clean s)`: the clean walk's own power score s is already significant, so every injection is detected and the prediction is not checked there. `cannot`: the diagnosis says the walk cannot show the effect; `modelled`: the starting model has its state. `{ONSET_VARIANT}`: the onset test of a g-sensitivity (the filter's bias moving along the specific force walking adds, as walking begins), its prediction from the same probe injection, its `power from` the test's own score (`cannot`: no test, the walk has no rest before it or too few blocks). `{}` and `{}`: the bias-change test (the filter's bias against its random walk, a χ² over its {BLOCK_S:.0} s blocks) on a step on z at mid-walk and a ramp on z from a tenth of the walk, each predicted from its own probe injection (the size at which the test, any direction's noncentral χ² beyond its critical value, fires half the time), its `power from` the test's own score, its `named from` the ranking naming a bias drift (whose residual tests may see it first); `cannot`: the walk has fewer than two blocks after tracking began (or the size was not measured, or lies beyond any plausible one: `detection.json` says which).\n\n| recording |",
        MDE_FACTORS
            .iter()
            .map(|f| format!("{f:.2}"))
            .collect::<Vec<_>>()
            .join(", "),
        DriftProbe::Step.variant(),
        DriftProbe::Ramp.variant(),
    );
    for v in &variants {
        md.push_str(&format!(" {v}: predicted | power from | named from |"));
    }
    md.push_str("\n|---|");
    md.push_str(&"---|---|---|".repeat(variants.len()));
    md.push('\n');
    for rec in &recordings {
        md.push_str(&format!("| {rec} |"));
        for v in &variants {
            let Some(row) = rows.iter().find(|r| r.recording == *rec && r.variant == *v) else {
                md.push_str(" — | — | — |");
                continue;
            };
            if row.points.is_empty() {
                let why = if row.skipped.as_deref() == Some(MODELLED) {
                    "modelled"
                } else {
                    "cannot"
                };
                md.push_str(&format!(" {why} | — | — |"));
                continue;
            }
            let shown_clean = if row.shows_clean() {
                format!(" (clean {:.1})", row.clean_score.unwrap_or(f64::NAN))
            } else {
                String::new()
            };
            let largest = row.points.last().map_or(0.0, |p| p.factor);
            let up_to = if largest < MDE_FACTORS[MDE_FACTORS.len() - 1] {
                format!(" (to {largest:.2}×)")
            } else {
                String::new()
            };
            md.push_str(&format!(
                " {}{up_to} | {}{shown_clean} | {} |",
                row.predicted
                    .map_or("—".to_string(), |p| format_unit(&row.unit, p)),
                format_from(row.power_from, largest),
                format_from(row.named_from, largest)
            ));
        }
        md.push('\n');
    }
    md.push_str("\nPer effect, over the walks scanned: on how many the power score reaches the threshold (and the ranking names the effect) at each factor (`of m`: injected on m walks, the others' sizes being beyond the plausible), and on how many the prediction agrees within a factor of 2. The placebo z RMS: the clean walk's power fit with the signature moved along the walk (19 circular shifts over its middle half), whose z-scores are standard normal where the standard error is right.\n\n| effect | walks |");
    for f in MDE_FACTORS {
        md.push_str(&format!(" {f:.2}× |"));
    }
    md.push_str(" power agrees (walks not significant clean) | named agrees | significant clean | placebo z RMS, median (range) over every walk |\n|---|---|");
    md.push_str(&"---|".repeat(MDE_FACTORS.len() + 4));
    md.push('\n');
    md.push_str("| *expected where the predictions are right* | |");
    for f in MDE_FACTORS {
        md.push_str(&format!(" {:.1} % |", 100.0 * expected_detection(f)));
    }
    md.push_str(&format!(
        " {:.0} % | | | 1 |\n",
        100.0 * expected_agreement()
    ));
    for v in &variants {
        let scanned: Vec<&ScanRow> = rows
            .iter()
            .filter(|r| r.variant == *v && !r.points.is_empty())
            .collect();
        let n = scanned.len();
        md.push_str(&format!("| {v} | {n} |"));
        for k in 0..MDE_FACTORS.len() {
            let power = scanned
                .iter()
                .filter(|r| {
                    r.points
                        .get(k)
                        .is_some_and(|p| p.power_score >= SIGNIFICANT)
                })
                .count();
            let named = scanned
                .iter()
                .filter(|r| r.points.get(k).is_some_and(|p| p.named))
                .count();
            // (the points are the factors from the smallest up: a row without point k stopped
            // below it, at the plausible limit)
            let injected = scanned.iter().filter(|r| r.points.len() > k).count();
            let of = if injected < n {
                format!(" of {injected}")
            } else {
                String::new()
            };
            md.push_str(&format!(" {power} ({named}){of} |"));
        }
        let count =
            |f: fn(&ScanRow) -> Option<bool>| scanned.iter().filter(|r| f(r) == Some(true)).count();
        let clean = scanned.iter().filter(|r| r.shows_clean()).count();
        let checkable = scanned.iter().filter(|r| !r.shows_clean());
        let mut placebo: Vec<f64> = rows
            .iter()
            .filter(|r| r.variant == *v)
            .filter_map(|r| r.placebo_z_rms)
            .collect();
        placebo.sort_by(f64::total_cmp);
        let placebo = match (placebo.first(), placebo.last()) {
            (Some(lo), Some(hi)) => format!("{:.1} ({lo:.1}–{hi:.1})", placebo[placebo.len() / 2]),
            _ => "—".to_string(),
        };
        md.push_str(&format!(
            " {} of {} | {} of {n} | {clean} | {placebo} |\n",
            checkable.filter(|r| r.power_agrees() == Some(true)).count(),
            n - clean,
            count(ScanRow::named_agrees),
        ));
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detected_from_is_the_start_of_the_run_of_detections_that_reaches_the_largest_size() {
        let f = |v: &[(f64, bool)]| detected_from(v);
        assert_eq!(f(&[(0.5, false), (1.0, true), (2.0, true)]), Some(1.0));
        // a detection below a miss does not count: the threshold is above the miss
        assert_eq!(f(&[(0.5, true), (1.0, false), (2.0, true)]), Some(2.0));
        assert_eq!(f(&[(0.5, true), (1.0, true)]), Some(0.5));
        assert_eq!(f(&[(0.5, true), (1.0, false)]), None);
        assert_eq!(f(&[]), None);
    }

    #[test]
    fn a_right_prediction_is_detected_half_the_time_at_itself_and_agrees_on_most_walks() {
        assert!((expected_detection(1.0) - 0.5).abs() < 1e-3);
        assert!((expected_detection(0.5) - 0.05).abs() < 2e-3);
        assert!(expected_detection(2.0) > 0.999);
        // the same by brute force over the walk's noise: the share of z whose run of
        // detections starts within [½, 2]
        let (mut agree, mut total) = (0.0, 0.0);
        let dz = 1e-3;
        for k in -8000..8000 {
            let z = f64::from(k) * dz;
            let w = (-0.5 * z * z).exp();
            let flags: Vec<(f64, bool)> = MDE_FACTORS
                .iter()
                .map(|&f| (f, (z + MDE_Z * f).abs() >= MDE_Z))
                .collect();
            total += w;
            if within_factor_2(detected_from(&flags)) {
                agree += w;
            }
        }
        let brute = agree / total;
        assert!((brute - expected_agreement()).abs() < 2e-3, "{brute}");
        assert!(brute > 0.97, "{brute}");
    }

    #[test]
    fn agreement_is_a_start_within_half_and_twice_the_prediction() {
        let row = |from: Option<f64>| ScanRow {
            recording: String::new(),
            variant: String::new(),
            unit: String::new(),
            predicted: Some(1.0),
            clean_score: None,
            clean_estimate: None,
            response: None,
            placebo_z_rms: None,
            skipped: None,
            points: vec![ScanPoint {
                factor: 1.0,
                size: 1.0,
                estimate: 0.0,
                power_score: 0.0,
                named: false,
            }],
            power_from: from,
            named_from: None,
        };
        for (from, agrees) in [
            (Some(MDE_FACTORS[1]), false),
            (Some(MDE_FACTORS[2]), true),
            (Some(MDE_FACTORS[6]), true),
            (Some(MDE_FACTORS[7]), false),
            (None, false),
        ] {
            assert_eq!(row(from).power_agrees(), Some(agrees), "{from:?}");
        }
        assert_eq!(row(Some(1.0)).named_agrees(), Some(false));
        let mut unscanned = row(Some(1.0));
        unscanned.points.clear();
        assert_eq!(unscanned.power_agrees(), None);
    }
}
