//! The detection matrix of the residual diagnosis (`corridor diagnose --suite FILE`): every
//! normal-gait recording of a suite × each injected sensor error of [`matrix_cases`] (and the
//! clean recording), through [`run_diagnosis`](crate::diagnose::run_diagnosis) on the model the
//! diagnosis was built on ([`diagnosis_model`]). Per cell: the effect named first, whether the
//! injected one is named first and named at all (score ≥ 3), the footprint error before and
//! after the loop, the detectable size the diagnosis predicts for the injected effect and its
//! score; then, per walk, the predicted detectable sizes checked at multiples of themselves
//! ([`super::mde_scan`]). Slow (about 2 minutes): a bench-style command, not a test.

use super::mde_scan::{ScanRow, already_modelled, scan_walk};
use super::{Gait, SuiteError, SuiteRecording, SuiteRun, read_suite};
use crate::diagnose::{
    DriftProbe, Effect, RAMP_FROM_FRACTION, SIGNIFICANT, STEP_AT_FRACTION, run_diagnosis,
};
use crate::runner::RunError;
use corridor_shared::config::{ConfigFile, HeadingObservations};
use corridor_shared::imu_csv::ImuLog;
use corridor_shared::injection::LogInjection;
use corridor_shared::truth_csv::TruthPoint;
use serde::Serialize;
use std::path::Path;

/// What one column of the matrix does to a recording.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CaseInjection {
    /// Nothing: the clean recording.
    Clean,
    /// A sensor error added to the samples; times given as fractions of the walk's duration.
    Log(LogInjection),
    /// The map's directions turned by this many degrees.
    GridOffsetDeg(f64),
}

/// One column of the matrix.
#[derive(Debug, Clone, Copy)]
pub struct MatrixCase {
    /// Short label (`z scale +2 %`).
    pub label: &'static str,
    /// The effect of the catalogue the diagnosis should name (`None` for the clean column and for
    /// errors outside the catalogue).
    pub expected: Option<Effect>,
    /// The injection, with times in fractions of the walk (see [`MatrixCase::resolve`]).
    pub injection: CaseInjection,
    /// Size in the unit of the expected effect's detectable size (fraction, rad, rad/s …).
    pub size: f64,
    /// The power variant of the diagnosis that measures this injection
    /// ([`Power::variant`](crate::diagnose::Power)), or the bias-change test's probe
    /// ([`DriftProbe::variant`]).
    pub variant: Option<&'static str>,
}

impl MatrixCase {
    /// The injection for a walk from `t0_s` lasting `duration_s`: the times of drifts, steps
    /// and slips are given in the case as fractions of the walk and resolved here.
    pub fn resolve(&self, t0_s: f64, duration_s: f64) -> CaseInjection {
        let at = |frac: f64| t0_s + frac * duration_s;
        match self.injection {
            CaseInjection::Log(LogInjection::BiasRamp {
                axis,
                rate_rad_s2,
                after_s,
            }) => CaseInjection::Log(LogInjection::BiasRamp {
                axis,
                rate_rad_s2,
                after_s: at(after_s),
            }),
            CaseInjection::Log(LogInjection::BiasStep {
                axis,
                step_rad_s,
                at_s,
            }) => CaseInjection::Log(LogInjection::BiasStep {
                axis,
                step_rad_s,
                at_s: at(at_s),
            }),
            CaseInjection::Log(LogInjection::MountingSlip { angle_rad, after_s }) => {
                CaseInjection::Log(LogInjection::MountingSlip {
                    angle_rad,
                    after_s: at(after_s),
                })
            }
            other => other,
        }
    }
}

/// The columns: the clean recording and the list of injections (z scale 1/2/5 %, 1° and
/// 2° y→z and x→z couplings, bias ramp and step, heading offset, clock 1 % and 3 %,
/// g-sensitivity, clipping at a smaller range than the sensor's, mounting slip), an
/// accelerometer scale error (strides too long: an effect only the footprints show), and the
/// couplings at 8° and a g-sensitivity of 2e-2 (above most walks' predicted detectable sizes,
/// to check those predictions). Ramp, step and slip sizes are those of the bundled tests; they
/// start at a fixed fraction of each walk.
pub fn matrix_cases() -> Vec<MatrixCase> {
    use CaseInjection::{Clean, Log};
    use Effect::{
        AxisMisalignment, BiasDrift, GyroClipping, GyroScaleFactor, HeadingOffset, Timing,
    };
    use LogInjection::*;
    let deg = f64::to_radians;
    let scale = |label, f: f64| MatrixCase {
        label,
        expected: Some(GyroScaleFactor),
        injection: Log(GyroScale {
            axis: 2,
            fraction: f,
        }),
        size: f,
        variant: Some("z scale"),
    };
    let couple = |label, from: usize, d: f64| MatrixCase {
        label,
        expected: Some(AxisMisalignment),
        injection: Log(GyroCoupling {
            from,
            to: 2,
            coupling_rad: deg(d),
        }),
        size: deg(d),
        variant: Some(if from == 1 {
            "y→z coupling"
        } else {
            "x→z coupling"
        }),
    };
    let clock = |label, f: f64| MatrixCase {
        label,
        expected: Some(Timing),
        injection: Log(ClockRate { fraction: f }),
        size: f,
        variant: Some("clock rate"),
    };
    let gsens = |label, k: f64| MatrixCase {
        label,
        expected: Some(Effect::GSensitivity),
        injection: Log(GSensitivity {
            k_rad_s_per_m_s2: k,
        }),
        size: k,
        variant: Some("g-sensitivity"),
    };
    vec![
        MatrixCase {
            label: "clean",
            expected: None,
            injection: Clean,
            size: 0.0,
            variant: None,
        },
        scale("z scale +1 %", 0.01),
        scale("z scale +2 %", 0.02),
        scale("z scale +5 %", 0.05),
        couple("y→z 1°", 1, 1.0),
        couple("y→z 2°", 1, 2.0),
        couple("x→z 1°", 0, 1.0),
        couple("x→z 2°", 0, 2.0),
        // Above the detectable sizes the clean walks predict (median 4.7° for y→z, 5.1° for
        // x→z): do the predictions hold when an effect is large enough to be seen?
        couple("y→z 8°", 1, 8.0),
        couple("x→z 8°", 0, 8.0),
        MatrixCase {
            label: "bias ramp 2e-4 rad/s²",
            expected: Some(BiasDrift),
            // the bias-change test's probes are these injections (`DriftProbe`)
            injection: Log(BiasRamp {
                axis: 2,
                rate_rad_s2: DriftProbe::Ramp.probe_size(),
                after_s: RAMP_FROM_FRACTION,
            }),
            size: DriftProbe::Ramp.probe_size(),
            variant: Some(DriftProbe::Ramp.variant()),
        },
        MatrixCase {
            label: "bias step 0.01 rad/s",
            expected: Some(BiasDrift),
            injection: Log(BiasStep {
                axis: 2,
                step_rad_s: DriftProbe::Step.probe_size(),
                at_s: STEP_AT_FRACTION,
            }),
            size: DriftProbe::Step.probe_size(),
            variant: Some(DriftProbe::Step.variant()),
        },
        MatrixCase {
            // The foot axis off the walking direction from early on (a mounting yaw that the
            // calibration strides did not see). Turning the map's grid instead is no heading
            // offset: the filter's frame turns with it, strides and foot alike.
            label: "heading offset 3°",
            expected: Some(HeadingOffset),
            injection: Log(MountingSlip {
                angle_rad: deg(3.0),
                after_s: 0.15,
            }),
            size: deg(3.0),
            variant: None,
        },
        clock("clock +1 %", 0.01),
        clock("clock +3 %", 0.03),
        gsens("g-sensitivity 2e-3 rad/s per m/s²", 2e-3),
        // Above the clean walks' predicted detectable size (median 1.3e-2 rad/s per m/s²).
        gsens("g-sensitivity 2e-2 rad/s per m/s²", 2e-2),
        MatrixCase {
            // A rail below the configured range (8.727 rad/s): `gyro_clipping`.
            label: "clipping at ±5 rad/s",
            expected: Some(GyroClipping),
            injection: Log(Clipping { range_rad_s: 5.0 }),
            size: 5.0,
            variant: None,
        },
        MatrixCase {
            // Strides 2 % long: named on the stride-length line, which only walks with
            // footprints at single strides can show.
            label: "accel scale +2 %",
            expected: Some(Effect::StrideLength),
            injection: Log(AccelScale { fraction: 0.02 }),
            size: 0.02,
            variant: None,
        },
        MatrixCase {
            label: "mounting slip 6°",
            expected: Some(HeadingOffset),
            injection: Log(MountingSlip {
                angle_rad: deg(6.0),
                after_s: 0.33,
            }),
            size: deg(6.0),
            variant: None,
        },
    ]
}

/// The model the diagnosis was built on and is tested with (`tests/diagnose_injected.rs`): the
/// recording's sensor configuration without its `[model]` extensions (the heading-offset state
/// of the default is one of the effects to find), the foot axis observed alone, the plain gate
/// (`aligned_prior = 1`), the filter noise of the recording's baseline configuration, and the
/// walk's map knowledge (start heading, grid).
pub fn diagnosis_model(base: &Path, r: &SuiteRecording) -> Result<ConfigFile, RunError> {
    let mut f = ConfigFile::read(&base.join(&r.config))?;
    f.model = Default::default();
    f.heading.observations = Some(HeadingObservations::FootAxis);
    f.heading.aligned_prior = Some(1.0);
    if let Some(b) = &r.baseline_config {
        f.eskf = ConfigFile::read(&base.join(b))?.eskf;
    }
    f.heading.start_heading_deg = Some(r.start_heading_deg);
    f.heading.grid_deg = Some(r.grid_deg);
    Ok(f)
}

/// One cell of the matrix.
#[derive(Debug, Clone, Serialize)]
pub struct MatrixCell {
    /// Recording.
    pub recording: String,
    /// Column label.
    pub case: String,
    /// The effect that should be named.
    pub expected: Option<String>,
    /// Injected size (unit of the expected effect's detectable size).
    pub size: f64,
    /// The effect named first (`none` when nothing is significant).
    pub top_effect: String,
    /// The expected effect is named first.
    pub named_first: bool,
    /// The injected variant ([`MatrixCase::variant`]): the one whose signature the first must
    /// be indistinguishable from for [`MatrixCell::expected_is_indistinguishable_from_first`].
    #[serde(skip)]
    pub variant: Option<&'static str>,
    /// The effects the diagnosis says the first one is indistinguishable from on this walk
    /// (`report.json`'s `top_indistinguishable_from`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub top_indistinguishable_from: Vec<String>,
    /// The expected effect scores ≥ 3.
    pub named_at_all: bool,
    /// The starting model already has the expected effect's fix (a state the clean walk needed):
    /// nothing is left to name, the cell is out of the counts.
    pub already_modelled: bool,
    /// Its score.
    pub expected_score: Option<f64>,
    /// The detectable size the diagnosis predicts for the expected effect on this walk (same
    /// unit as `size`), when it predicts one.
    pub expected_mde: Option<f64>,
    /// The power fit of the injected variant: the size the residuals show.
    pub power_estimate: Option<f64>,
    /// Its score.
    pub power_score: Option<f64>,
    /// The response the diagnosis measured for that variant by its own probe injection.
    pub power_response: Option<f64>,
    /// The diagnosis's verdict.
    pub verdict: String,
    /// The detectable size of every measured variant on this cell's log (`None`: cannot show).
    pub detectable: Vec<(String, Option<f64>)>,
    /// The starting model as the diagnosis lists it (its extension states, the clean walk's own
    /// effects for the injected columns, its bias random walk and mode).
    pub start_model: Vec<String>,
    /// Every effect scoring ≥ 3, best first, as `name score`.
    pub significant: Vec<String>,
    /// Footprint RMS of the starting model, m.
    pub rms_before_m: Option<f64>,
    /// Footprint RMS of the model the loop ends with, m.
    pub rms_after_m: Option<f64>,
    /// Effects the loop added and kept.
    pub added: Vec<String>,
    /// The stride-length finding on the cell's starting model (walks with at least
    /// [`crate::diagnose::MIN_LEGS`] surveyed single strides, or
    /// [`crate::diagnose::MIN_CORNER_LEGS`] surveyed legs): estimated / surveyed length, its
    /// score.
    pub stride_length: Option<StrideFigure>,
}

impl MatrixCell {
    /// The injected effect is not the one named first, but the diagnosis says the first is
    /// indistinguishable from it on this walk: from the injected variant where the case has one
    /// (an x→z coupling injected is not the y→z coupling the first correlates with: exp28's
    /// x→z 8° cell, whose first, a z scale, correlates at −0.96 with the y→z coupling alone).
    pub fn expected_is_indistinguishable_from_first(&self) -> bool {
        // `effect (variant, ρ = …)`
        let Some(prefix) = self.expected.as_deref().map(|e| match self.variant {
            Some(v) => format!("{e} ({v},"),
            None => format!("{e} ("),
        }) else {
            return false;
        };
        !self.named_first
            && self
                .top_indistinguishable_from
                .iter()
                .any(|a| a.starts_with(&prefix))
    }
}

/// The stride-length finding of a cell.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct StrideFigure {
    /// Estimated / surveyed leg length.
    pub ratio: f64,
    /// −log₁₀ p of its difference from 1.
    pub score: f64,
    /// The loop had a fix to try (the model had no rolling-foot stance update).
    pub fixable: bool,
    /// Fitted on the legs between surveyed corners, not on single strides.
    pub corner_legs: bool,
}

/// The whole matrix.
#[derive(Debug, Clone, Serialize)]
pub struct DetectionMatrix {
    /// Normal-gait recordings, in suite order.
    pub recordings: Vec<String>,
    /// Column labels, in order.
    pub cases: Vec<String>,
    /// Cells, recording-major.
    pub cells: Vec<MatrixCell>,
    /// The detectable sizes checked by injection, recording-major ([`ScanRow`]).
    pub mde_scan: Vec<ScanRow>,
    /// The normal-gait recordings whose runs failed: not in the matrix.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub failed: Vec<FailedRecording>,
}

/// A recording left out of the matrix.
#[derive(Debug, Clone, Serialize)]
pub struct FailedRecording {
    /// Its name.
    pub recording: String,
    /// Why (`recording NAME: ...`).
    pub error: String,
}

/// Runs the matrix over the normal-gait recordings of the suite at `path`, and on each walk the
/// scan of the detectable sizes; `progress` sees each cell and `scan_progress` each scan row as
/// it is done.
pub fn detection_matrix(
    path: &Path,
    mut progress: impl FnMut(&MatrixCell),
    mut scan_progress: impl FnMut(&ScanRow),
) -> Result<DetectionMatrix, SuiteError> {
    let suite = read_suite(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let cases = matrix_cases();
    let mut out = DetectionMatrix {
        recordings: Vec::new(),
        cases: cases.iter().map(|c| c.label.to_string()).collect(),
        cells: Vec::new(),
        mde_scan: Vec::new(),
        failed: Vec::new(),
    };
    // A recording that fails is named and leaves no cell: the others' cells are written.
    let run = SuiteRun::each(
        suite.recordings.iter().filter(|r| r.gait == Gait::Normal),
        |r| {
            let wrap = |source: RunError| SuiteError::Run {
                name: r.name.clone(),
                source: Box::new(source),
            };
            let (log, truth) =
                super::read_recording(base, r, super::RejectedRows::Say).map_err(wrap)?;
            let model = diagnosis_model(base, r).map_err(wrap)?;
            // The clean column first: the effects it names are the walk's own (documented in
            // that column), and the injected columns start from the model with their fixes.
            let (clean, documented) = run_cell(&log, &truth, &model, r, &cases[0]).map_err(wrap)?;
            progress(&clean);
            let mut cells = vec![clean];
            for case in &cases[1..] {
                let (cell, _) = run_cell(&log, &truth, &documented, r, case).map_err(wrap)?;
                progress(&cell);
                cells.push(cell);
            }
            let scan = scan_walk(r, &log, &truth, &documented, &mut scan_progress).map_err(wrap)?;
            Ok((r.name.clone(), cells, scan))
        },
    )?;
    for (name, cells, scan) in run.rows {
        out.recordings.push(name);
        out.cells.extend(cells);
        out.mde_scan.extend(scan);
    }
    out.failed = run
        .failed
        .iter()
        .map(|e| FailedRecording {
            recording: e.recording().unwrap_or_default().to_owned(),
            error: e.to_string(),
        })
        .collect();
    Ok(out)
}

/// The walk with `injection` applied: its samples changed, and the footprints' times mapped the
/// same way (a clock error moves them).
pub(super) fn injected_walk(
    log: &ImuLog,
    truth: &[TruthPoint],
    injection: &LogInjection,
) -> (ImuLog, Vec<TruthPoint>) {
    let t0 = log.rows.first().map_or(0.0, |x| x.t_s);
    let mut log = log.clone();
    injection.apply(&mut log.rows);
    let truth = truth
        .iter()
        .map(|p| TruthPoint {
            t_s: injection.map_time(t0, p.t_s),
            ..*p
        })
        .collect();
    (log, truth)
}

/// One cell, and the cell's model with the fixes of every significant effect it names added (in
/// the order named).
fn run_cell(
    log: &ImuLog,
    truth: &[TruthPoint],
    model: &ConfigFile,
    r: &SuiteRecording,
    case: &MatrixCase,
) -> Result<(MatrixCell, ConfigFile), RunError> {
    let t0 = log.rows.first().map_or(0.0, |x| x.t_s);
    let duration = log.rows.last().map_or(0.0, |x| x.t_s) - t0;
    let mut model = model.clone();
    let (log, truth) = match case.resolve(t0, duration) {
        CaseInjection::Clean => (log.clone(), truth.to_vec()),
        CaseInjection::Log(inj) => injected_walk(log, truth, &inj),
        CaseInjection::GridOffsetDeg(d) => {
            model.heading.grid_deg = Some(r.grid_deg + d);
            (log.clone(), truth.to_vec())
        }
    };
    let diagnosis = run_diagnosis(&log, &model, Some(&truth), None)?;
    // The injected columns run the same rows again: what the input cost is said with the clean.
    if matches!(case.resolve(t0, duration), CaseInjection::Clean)
        && let Some(input) = &diagnosis.before.input
    {
        tracing::warn!("{}: {input}", r.name);
    }
    let report = &diagnosis.report;
    // The stride length has its own line (position information): it is "named first" there.
    let on_own_line = case.expected == Some(Effect::StrideLength);
    let expected = case.expected.and_then(|e| {
        if on_own_line {
            report.stride_length.as_ref().map(|l| &l.finding)
        } else {
            report.effects.iter().find(|f| f.name == e)
        }
    });
    let mut with_fixes = model.clone();
    for f in report
        .effects
        .iter()
        .chain(report.stride_length.as_ref().map(|l| &l.finding))
        .filter(|f| f.score >= SIGNIFICANT)
    {
        if let Some(fix) = f.fix {
            crate::diagnose::apply_fix(fix, &mut with_fixes);
        }
    }
    let power = case
        .variant
        .and_then(|v| report.power.iter().find(|p| p.variant == v));
    // (The stride-length fix, the rolling stance update, is no state for a stride scale.)
    let already_modelled =
        !on_own_line && case.expected.is_some_and(|e| already_modelled(e, &model));
    let cell = MatrixCell {
        recording: r.name.clone(),
        case: case.label.to_string(),
        expected: case.expected.map(|e| e.to_string()),
        size: case.size,
        named_first: if on_own_line {
            expected.is_some_and(|f| f.score >= SIGNIFICANT)
        } else {
            case.expected.is_some_and(|e| report.top_effect == e.name())
        },
        named_at_all: expected.is_some_and(|f| f.score >= SIGNIFICANT),
        already_modelled,
        expected_score: expected.map(|f| f.score),
        expected_mde: match case.variant {
            // the bias-change test's own sizes (a step's is also the finding's)
            Some(v) if power.is_none() => DriftProbe::ALL
                .into_iter()
                .find(|k| k.variant() == v)
                .and_then(|k| {
                    report
                        .bias_change
                        .as_ref()
                        .and_then(|c| k.mde_of(c))
                        .filter(|&m| m <= k.plausible_max())
                }),
            Some(_) => power.and_then(|p| p.mde),
            None => expected.and_then(|f| f.mde),
        },
        power_estimate: power.map(|p| p.estimate),
        power_score: power.map(|p| p.score),
        power_response: power.and_then(|p| p.response),
        verdict: report.verdict.clone(),
        detectable: report
            .power
            .iter()
            .map(|p| (p.variant.to_string(), p.mde))
            .collect(),
        start_model: diagnosis.before.model.clone(),
        top_effect: report.top_effect.clone(),
        variant: case.variant,
        top_indistinguishable_from: report.top_indistinguishable_from.clone(),
        significant: report
            .effects
            .iter()
            .filter(|f| f.score >= SIGNIFICANT)
            .map(|f| format!("{} {:.1}", f.name, f.score))
            .collect(),
        rms_before_m: report.before.gcp_rms_m,
        rms_after_m: report.after.gcp_rms_m,
        stride_length: report.stride_length.as_ref().map(|l| StrideFigure {
            ratio: l.fit.ratio,
            score: l.fit.score,
            fixable: l.finding.fix.is_some(),
            corner_legs: l.fit.kind == crate::diagnose::LegKind::CornerLegs,
        }),
        added: report
            .iterations
            .iter()
            .filter(|i| i.kept)
            .map(|i| i.effect.to_string())
            .collect(),
    };
    // the grid offset of the heading-offset column is the injection, not part of the model
    with_fixes.heading.grid_deg = Some(r.grid_deg);
    Ok((cell, with_fixes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_is_indistinguishable_from_the_injected_variant_not_any_of_its_effect() {
        // exp28's x→z 8° cell: a z scale named first, its signature the clock rate's and the y→z
        // coupling's; the x→z coupling injected is not among them
        let cell = |variant, named_first| MatrixCell {
            recording: "exp28".into(),
            case: "x→z 8°".into(),
            expected: Some(Effect::AxisMisalignment.to_string()),
            size: 0.14,
            top_effect: Effect::GyroScaleFactor.to_string(),
            named_first,
            variant,
            top_indistinguishable_from: vec![
                "timing (clock rate, ρ = +0.99)".into(),
                "axis_misalignment (y→z coupling, ρ = -0.96)".into(),
            ],
            named_at_all: false,
            already_modelled: false,
            expected_score: None,
            expected_mde: None,
            power_estimate: None,
            power_score: None,
            power_response: None,
            verdict: String::new(),
            detectable: Vec::new(),
            start_model: Vec::new(),
            significant: Vec::new(),
            rms_before_m: None,
            rms_after_m: None,
            added: Vec::new(),
            stride_length: None,
        };
        assert!(!cell(Some("x→z coupling"), false).expected_is_indistinguishable_from_first());
        assert!(cell(Some("y→z coupling"), false).expected_is_indistinguishable_from_first());
        // a case without a variant: the effect alone
        assert!(cell(None, false).expected_is_indistinguishable_from_first());
        // named first: nothing to excuse
        assert!(!cell(Some("y→z coupling"), true).expected_is_indistinguishable_from_first());
    }
}
