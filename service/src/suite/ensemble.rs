//! How much does each walk's figure owe to the start heading it was given, and to luck? The
//! default run repeated with the start heading moved by what a map gives it to
//! (`corridor eval --suite FILE --ensemble`).
//!
//! Every walk runs once per start-heading offset in [`START_OFFSETS_DEG`] (the corridor
//! direction a user reads off a map is known to about 1°, the σ `configs/gdins.toml` gives
//! `heading.start_heading_sd_deg`). Two things move a walk's figure then: the start heading
//! itself (a steady trend across the offsets, on walks with few heading observations early on),
//! and the chain of yes/no decisions (stance found, stride on a line, observation associated or
//! not), where on a walk with long unaided stretches one flipped decision moves the whole
//! result (a jump). Either way a walk whose runs spread widely is one whose single figure says
//! little, and the mean over the offsets is the fairer figure to compare two builds with.

use super::{Ctx, Gait, SuiteError, SuiteRun, read_suite, tables::median};
use crate::runner::RunError;
use corridor_shared::config::Mode;
use std::fmt::Write as _;
use std::path::Path;

/// Offsets added to each recording's start heading, degrees.
pub const START_OFFSETS_DEG: [f64; 5] = [-1.0, -0.5, 0.0, 0.5, 1.0];

/// One recording's default run at every offset.
#[derive(Debug, Clone)]
pub struct EnsembleRow {
    /// Recording name.
    pub name: String,
    /// Its gait.
    pub gait: Gait,
    /// Footprint RMS, % of path, per offset of [`START_OFFSETS_DEG`].
    pub rms_pct: Vec<f64>,
}

impl EnsembleRow {
    /// Mean over the offsets, % of path.
    pub fn mean_pct(&self) -> f64 {
        self.rms_pct.iter().sum::<f64>() / self.rms_pct.len().max(1) as f64
    }

    /// Smallest and largest run, % of path (both NaN when a run has no figure: it is not
    /// skipped).
    pub fn range_pct(&self) -> (f64, f64) {
        if self.rms_pct.iter().any(|v| v.is_nan()) {
            return (f64::NAN, f64::NAN);
        }
        let lo = self.rms_pct.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = self
            .rms_pct
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        (lo, hi)
    }
}

/// Runs the default (best mode, rest-mean prior) of every recording at every offset; a
/// recording that fails is named and the others run.
pub fn run_ensemble(suite_path: &Path) -> Result<SuiteRun<EnsembleRow>, SuiteError> {
    let suite = read_suite(suite_path)?;
    let base = suite_path.parent().unwrap_or(Path::new("."));
    let best = suite.best_mode.unwrap_or(Mode::Eskf);
    SuiteRun::each(&suite.recordings, |r| {
        let wrap = |source: RunError| SuiteError::Run {
            name: r.name.clone(),
            source: Box::new(source),
        };
        let ctx = Ctx::open(base, r, super::RejectedRows::Say).map_err(wrap)?;
        let mut rms_pct = Vec::with_capacity(START_OFFSETS_DEG.len());
        for offset in START_OFFSETS_DEG {
            let cfg = ctx.default_config_turned(best, offset).map_err(wrap)?;
            let say = (offset == 0.0).then_some("the default run");
            rms_pct.push(ctx.footprint_at(&cfg, say).map_err(wrap)?.rms_pct);
        }
        Ok(EnsembleRow {
            name: r.name.clone(),
            gait: r.gait,
            rms_pct,
        })
    })
}

/// The summary over the normal-gait walks: the median, mean and largest of the walks' means,
/// and the largest single run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnsembleSummary {
    /// Median over the walks of each walk's mean, % of path.
    pub median_of_means_pct: f64,
    /// Mean of the walks' means, % of path.
    pub mean_of_means_pct: f64,
    /// Largest walk mean, % of path.
    pub worst_mean_pct: f64,
    /// Largest single run, % of path.
    pub worst_run_pct: f64,
}

/// [`EnsembleSummary`] of the normal-gait rows (`None` without any).
pub fn ensemble_summary(rows: &[EnsembleRow]) -> Option<EnsembleSummary> {
    let normal: Vec<&EnsembleRow> = rows.iter().filter(|r| r.gait == Gait::Normal).collect();
    if normal.is_empty() {
        return None;
    }
    let mut means: Vec<f64> = normal.iter().map(|r| r.mean_pct()).collect();
    if means.iter().any(|m| m.is_nan()) {
        // A walk without a figure: no summary figure either, rather than one without it.
        return Some(EnsembleSummary {
            median_of_means_pct: f64::NAN,
            mean_of_means_pct: f64::NAN,
            worst_mean_pct: f64::NAN,
            worst_run_pct: f64::NAN,
        });
    }
    Some(EnsembleSummary {
        mean_of_means_pct: means.iter().sum::<f64>() / means.len() as f64,
        worst_mean_pct: means.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        median_of_means_pct: median(&mut means),
        worst_run_pct: normal
            .iter()
            .map(|r| r.range_pct().1)
            .fold(f64::NEG_INFINITY, f64::max),
    })
}

/// The ensemble as Markdown: a row per walk, then the summary line.
pub fn ensemble_markdown(rows: &[EnsembleRow]) -> String {
    let offsets: Vec<String> = START_OFFSETS_DEG
        .iter()
        .map(|&o| {
            if o == 0.0 {
                "0°".to_owned()
            } else {
                format!("{o:+}°")
            }
        })
        .collect();
    let mut md = format!(
        "The default run (best mode, rest-mean prior) with the start heading moved by {} (a map \
         gives the corridor's direction to about 1°): footprint RMS, % of path.\n\n\
         | recording | gait | {} | mean | half range |\n|---|---|{}---|---|\n",
        offsets.join(", "),
        offsets.join(" | "),
        "---|".repeat(offsets.len()),
    );
    for r in rows {
        let (lo, hi) = r.range_pct();
        let runs: Vec<String> = r.rms_pct.iter().map(|v| format!("{v:.2}")).collect();
        let gait = r.gait.name();
        let _ = writeln!(
            md,
            "| {} | {gait} | {} | {:.2} | {:.2} |",
            r.name,
            runs.join(" | "),
            r.mean_pct(),
            0.5 * (hi - lo)
        );
    }
    if let Some(s) = ensemble_summary(rows) {
        let _ = write!(
            md,
            "\nNormal gait: the walks' means have median {:.2} %, mean {:.2} %, largest {:.2} %; \
             the largest single run is {:.2} %.\n",
            s.median_of_means_pct, s.mean_of_means_pct, s.worst_mean_pct, s.worst_run_pct
        );
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(name: &str, gait: Gait, rms: &[f64]) -> EnsembleRow {
        EnsembleRow {
            name: name.into(),
            gait,
            rms_pct: rms.to_vec(),
        }
    }

    #[test]
    fn the_summary_is_over_the_normal_gait_walks_means() {
        let rows = [
            row("a", Gait::Normal, &[0.2, 0.2, 0.2, 0.2, 0.2]),
            row("b", Gait::Normal, &[0.3, 0.5, 0.4, 0.4, 0.4]),
            row("c", Gait::Normal, &[1.0, 3.0, 2.0, 2.0, 2.0]),
            // A fast walk worse than all of them is reported but not summarised.
            row("d", Gait::Fast, &[9.0, 9.0, 9.0, 9.0, 9.0]),
        ];
        let s = ensemble_summary(&rows).unwrap();
        assert!((s.median_of_means_pct - 0.4).abs() < 1e-12, "{s:?}");
        assert!(
            (s.mean_of_means_pct - (0.2 + 0.4 + 2.0) / 3.0).abs() < 1e-12,
            "{s:?}"
        );
        assert!((s.worst_mean_pct - 2.0).abs() < 1e-12 && (s.worst_run_pct - 3.0).abs() < 1e-12);
        assert_eq!(rows[2].range_pct(), (1.0, 3.0));
        let md = ensemble_markdown(&rows);
        assert!(
            md.contains(
                "| recording | gait | -1° | -0.5° | 0° | +0.5° | +1° | mean | half range |"
            ) && md.contains("| c | normal | 1.00 | 3.00 | 2.00 | 2.00 | 2.00 | 2.00 | 1.00 |"),
            "{md}"
        );
        assert!(md.contains("largest single run is 3.00 %"), "{md}");
        assert_eq!(ensemble_summary(&rows[3..]), None);
        // A run without a figure is not skipped: the walk and the summary say NaN.
        let with_nan = [
            rows[0].clone(),
            row("e", Gait::Normal, &[0.1, f64::NAN, 0.1, 0.1, 0.1]),
        ];
        assert!(with_nan[1].range_pct().1.is_nan() && with_nan[1].mean_pct().is_nan());
        let s = ensemble_summary(&with_nan).unwrap();
        assert!(
            s.median_of_means_pct.is_nan() && s.worst_mean_pct.is_nan() && s.worst_run_pct.is_nan()
        );
    }
}
