//! Running every recording of a suite: each on its own ([`run_suite_each`], `corridor eval`:
//! one that fails does not cost the others their rows), or all or nothing ([`run_suite`], the
//! demo).

use super::{
    Ctx, Footprint, RejectedRows, SuiteError, SuiteRecording, SuiteRow, front_end, read_suite,
    run_recording,
};
use crate::runner::{self, RunError, heading_aid};
use corridor_shared::config::Mode;
use corridor_shared::injection::BiasInjection;
use std::path::{Path, PathBuf};

/// Runs the suite (the table's rows); the first recording that fails fails it.
pub fn run_suite(path: &Path) -> Result<Vec<SuiteRow>, SuiteError> {
    run_suite_each(path)?.all_or_first_failure()
}

/// The rows of the recordings that ran, and what failed in the others: what the commands over a
/// suite return (the table, `--loops`, `--ensemble`, `--sweep`; the detection matrix runs its
/// recordings through it too), so that one recording that fails does not cost the others their
/// rows.
#[derive(Debug)]
pub struct SuiteRun<T = SuiteRow> {
    /// The rows, in the suite file's order (the sweep's: one per parameter).
    pub rows: Vec<T>,
    /// The recordings that failed (a log or a truth that cannot be read or evaluated), in
    /// the suite file's order.
    pub failed: Vec<SuiteError>,
}

impl<T> SuiteRun<T> {
    /// The rows when every recording ran, else the first failure (the demo: all or nothing).
    pub fn all_or_first_failure(self) -> Result<Vec<T>, SuiteError> {
        match self.failed.into_iter().next() {
            Some(e) => Err(e),
            None => Ok(self.rows),
        }
    }

    /// Each recording in turn through `row`: its row, or its failure, which the next
    /// recording does not wait on. An error that is not a recording's own (a file of the
    /// command's, such as the sweep file) stops the whole command.
    pub(super) fn each<'a, R: 'a>(
        recordings: impl IntoIterator<Item = &'a R>,
        mut row: impl FnMut(&'a R) -> Result<T, SuiteError>,
    ) -> Result<Self, SuiteError> {
        let mut out = SuiteRun {
            rows: Vec::new(),
            failed: Vec::new(),
        };
        for r in recordings {
            match row(r) {
                Ok(v) => out.rows.push(v),
                Err(e @ SuiteError::Run { .. }) => out.failed.push(e),
                Err(e) => return Err(e),
            }
        }
        Ok(out)
    }
}

/// Runs the suite, each recording on its own: one that fails does not stop the others.
pub fn run_suite_each(path: &Path) -> Result<SuiteRun, SuiteError> {
    let suite = read_suite(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let inj = suite
        .inject_gyro_bias_rad_s
        .unwrap_or([0.001, 0.001, 0.005]);
    let best_mode = suite.best_mode.unwrap_or(Mode::Eskf);
    fn wrap(r: &SuiteRecording) -> impl FnOnce(RunError) -> SuiteError + '_ {
        move |source| SuiteError::Run {
            name: r.name.clone(),
            source: Box::new(source),
        }
    }
    let mut ran = Vec::new();
    // (with each recording's place in the file, to give the failures of both passes in order)
    let mut failed = Vec::new();
    for (i, r) in suite.recordings.iter().enumerate() {
        match run_recording(base, r, inj, best_mode).map_err(wrap(r)) {
            Ok(row) => ran.push((i, r, row)),
            Err(e) => failed.push((i, e)),
        }
    }
    // A restart without rest from a checkpoint needs the other walks' final biases: a second
    // pass, which reads each log again rather than keeping every log in memory.
    let finals: Vec<(&PathBuf, [f64; 3])> = ran
        .iter()
        .map(|(_, r, row)| (&r.config, row.final_bias_rad_s))
        .collect();
    let mut rows = Vec::new();
    for (i, (place, r, mut row)) in ran.into_iter().enumerate() {
        let others: Vec<[f64; 3]> = finals
            .iter()
            .enumerate()
            .filter(|(j, (config, bias))| {
                *j != i && *config == &r.config && bias.iter().all(|v| v.is_finite())
            })
            .map(|(_, (_, bias))| *bias)
            .collect();
        match without_rest_from_checkpoint(base, r, best_mode, &others).map_err(wrap(r)) {
            Ok(fp) => {
                row.front_end.without_rest_checkpoint = fp;
                rows.push(row);
            }
            Err(e) => failed.push((place, e)),
        }
    }
    failed.sort_by_key(|&(place, _)| place);
    Ok(SuiteRun {
        rows,
        failed: failed.into_iter().map(|(_, e)| e).collect(),
    })
}

/// The default run on the log cut [`KEPT_REST_S`] before its first footprint, started from the
/// checkpoint the other walks give ([`front_end::checkpoint_from`]).
fn without_rest_from_checkpoint(
    base: &Path,
    r: &SuiteRecording,
    best: Mode,
    others: &[[f64; 3]],
) -> Result<Option<Footprint>, RunError> {
    // The second pass over the log: its rejected rows were said in the first.
    let ctx = Ctx::open(base, r, RejectedRows::AlreadySaid)?;
    let cfg = ctx.default_config(best)?;
    let Some(ws) = front_end::checkpoint_from(others, cfg.eskf.gyro_bias_prior_sd_rad_s.get())
    else {
        return Ok(None);
    };
    let Some(cut) = ctx.without_rest() else {
        return Ok(None);
    };
    let aid = heading_aid(&cfg, None)?;
    let out = runner::run_log_warm(
        &cut.log,
        &cfg,
        &aid,
        &BiasInjection::default(),
        ws,
        |_, _| {},
    )?;
    cut.footprint(&out).map(Some)
}
