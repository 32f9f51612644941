//! The residual-diagnosis loop on every recording of a suite.

use super::{SuiteError, SuiteRun, read_suite};
use crate::runner::RunError;
use corridor_shared::config::{ConfigFile, Mode};
use std::path::Path;

/// The residual-diagnosis loop on every recording of a suite, starting from the paper's model
/// (the sensor configuration without its `[model]` extensions, `mode = paper`). Writes each
/// report under `out/<report_dir_name(recording)>/` and returns each recording's row of the
/// summary table ([`loops_markdown`]), or its failure (and no report: an earlier one of that
/// recording is removed). Runs after the suite's table ([`super::run_suite_each`]), which said what each
/// log's input cost (`eval --loops`, the demo).
pub fn run_loops(path: &Path, out: &Path) -> Result<SuiteRun<String>, SuiteError> {
    let suite = read_suite(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    SuiteRun::each(&suite.recordings, |r| {
        let wrap = |source: RunError| SuiteError::Run {
            name: r.name.clone(),
            source: Box::new(source),
        };
        // An earlier report of a recording that fails now would read as this run's.
        let dir = out.join(super::file::report_dir_name(&r.name));
        if dir.exists() {
            std::fs::remove_dir_all(&dir).map_err(|e| wrap(crate::runner::io_at(&dir)(e)))?;
        }
        let (log, truth) =
            super::read_recording(base, r, super::RejectedRows::AlreadySaid).map_err(wrap)?;
        let mut file = ConfigFile::read(&base.join(&r.config)).map_err(|e| wrap(e.into()))?;
        // The paper's model: no extension states (a model change, not an override).
        file.model = Default::default();
        r.overrides(Mode::Paper, None).apply(&mut file);
        let crate::diagnose::Diagnosis {
            report,
            before,
            after,
            ..
        } = crate::diagnose::run_diagnosis(&log, &file, Some(&truth), None).map_err(wrap)?;
        std::fs::create_dir_all(&dir).map_err(|e| wrap(crate::runner::io_at(&dir)(e)))?;
        crate::diagnose::write_report(&dir, &report, &before, &after).map_err(wrap)?;
        let added: Vec<String> = report
            .iterations
            .iter()
            .map(|it| {
                format!(
                    "{} ({:.1}){}",
                    it.effect,
                    it.score,
                    match (it.kept, it.fix) {
                        (true, _) => "",
                        (false, crate::diagnose::Fix::StrideScale { .. }) => {
                            " — tried, footprint error (of the second half, or of the walk) not lower, not kept"
                        }
                        (false, _) => " — tried, footprint error rose, not kept",
                    }
                )
            })
            .collect();
        let left = report
            .final_effects
            .first()
            .filter(|e| e.score >= crate::diagnose::SIGNIFICANT)
            .map_or("nothing significant".to_string(), |e| {
                format!("{} ({:.1})", e.name, e.score)
            });
        let rms = |c: &crate::diagnose::Consistency| {
            c.gcp_rms_m.map_or("—".into(), |v| format!("{v:.2} m"))
        };
        Ok(format!(
            "| {} | {} | {} → {} | {:.2} → {:.2} | {} |\n",
            r.name,
            if added.is_empty() {
                "none".to_string()
            } else {
                added.join(", ")
            },
            rms(&report.before),
            rms(&report.after),
            report.before.nis_mean,
            report.after.nis_mean,
            left
        ))
    })
}

/// The summary table of [`run_loops`]'s rows (Markdown).
pub fn loops_markdown(rows: &[String]) -> String {
    let mut md = String::from(
        "| recording | effects added, in order (score = −log₁₀ p) | footprint RMS before → after | heading NIS before → after | left |\n|---|---|---|---|---|\n",
    );
    md.extend(rows.iter().map(String::as_str));
    md
}
