//! `corridor eval`: the results table over the recordings of a suite.

use anyhow::{Context, Result};
use clap::Args;
use corridor_service::suite::SuiteError;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub(super) struct EvalArgs {
    /// Suite file (TOML with `[[recording]]` tables).
    #[arg(long)]
    pub(super) suite: PathBuf,
    /// Also write the table (Markdown) and the rows (JSON) into this directory.
    #[arg(long)]
    pub(super) out: Option<PathBuf>,
    /// Also run the residual-diagnosis loop from the paper's model on every recording (its
    /// table is appended; with --out its reports go under OUT/diagnose).
    #[arg(long)]
    pub(super) loops: bool,
    /// Instead of the table: the leave-one-walk-out check of the parameters listed in this
    /// sweep file (TOML with `[[parameter]]` tables: key = "section.key", values = [...]); with
    /// --out it is written to OUT/sweep.md.
    #[arg(long, conflicts_with = "loops")]
    pub(super) sweep: Option<PathBuf>,
    /// Instead of the table: every recording's default run with its start heading moved by
    /// -1, -0.5, 0, +0.5 and +1° (how much each walk's figure owes to luck); with --out it is
    /// written to OUT/ensemble.md.
    #[arg(long, conflicts_with_all = ["loops", "sweep"])]
    pub(super) ensemble: bool,
}

/// Runs the suite, prints the table and writes it when asked.
pub(super) fn eval(a: EvalArgs) -> Result<()> {
    for (flag, path) in [("--suite", Some(&a.suite)), ("--sweep", a.sweep.as_ref())] {
        if let Some(p) = path
            && let Some(why) = corridor_shared::text_file::not_a_file(p)
        {
            anyhow::bail!("{flag} {}: {why}", p.display());
        }
    }
    if let Some(sweep) = &a.sweep {
        // (With fewer than two walks that ran, `run_sweep` fails and nothing is written.)
        let run = corridor_service::suite::run_sweep(&a.suite, sweep)?;
        let md = corridor_service::suite::sweep_markdown(&run.rows);
        return write_then_fail(
            md,
            &run.failed,
            a.out.as_deref(),
            "sweep.md",
            "in the sweep",
        );
    }
    if a.ensemble {
        let run = corridor_service::suite::run_ensemble(&a.suite)?;
        nothing_ran(run.rows.is_empty(), &run.failed)?;
        let md = corridor_service::suite::ensemble_markdown(&run.rows);
        return write_then_fail(
            md,
            &run.failed,
            a.out.as_deref(),
            "ensemble.md",
            "in the ensemble",
        );
    }
    // A recording that fails does not cost the others their tables: they are written, and
    // the failures make the command fail after them.
    let run = corridor_service::suite::run_suite_each(&a.suite)?;
    nothing_ran(run.rows.is_empty(), &run.failed)?;
    let rows = run.rows;
    let mut md = corridor_service::suite::markdown(&rows);
    md.push_str(&not_scored(&run.failed, "scored"));
    let mut failed = run.failed;
    if a.loops {
        let reports = a.out.as_ref().map_or_else(
            || std::env::temp_dir().join(format!("corridor-loops-{}", std::process::id())),
            |d| d.join("diagnose"),
        );
        let loops = corridor_service::suite::run_loops(&a.suite, &reports)?;
        if a.out.is_none() {
            // Reports were only a by-product; keep nothing behind.
            let _ = std::fs::remove_dir_all(&reports);
        }
        md.push_str(&format!(
            "\nThe residual-diagnosis loop from the paper's model (`corridor diagnose`):\n\n{}{}",
            corridor_service::suite::loops_markdown(&loops.rows),
            not_scored(&loops.failed, "in the loop")
        ));
        failed.extend(loops.failed);
    }
    corridor_client::say_text(&md);
    if let Some(dir) = a.out {
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        std::fs::write(dir.join("results.md"), &md)?;
        std::fs::write(
            dir.join("results.json"),
            serde_json::to_string_pretty(&rows)? + "\n",
        )?;
    }
    fail_if_any(&failed, "the others' tables were written")
}

/// When every recording failed: the command's error, each failure in full, and no table written
/// (an empty one would replace the last good one in `--out`).
fn nothing_ran(no_rows: bool, failed: &[SuiteError]) -> Result<()> {
    if no_rows && !failed.is_empty() {
        anyhow::bail!(
            "no recording ran, nothing written: {}",
            names(failed).join("; ")
        );
    }
    Ok(())
}

/// The failures' messages.
fn names(failed: &[SuiteError]) -> Vec<String> {
    failed.iter().map(ToString::to_string).collect()
}

/// The line under a table that names the recordings left out of it, if any.
fn not_scored(failed: &[SuiteError], what: &str) -> String {
    if failed.is_empty() {
        return String::new();
    }
    format!(
        "\nNot {what} (its run failed): {}.\n",
        names(failed).join("; ")
    )
}

/// The command's error when recordings failed: each named once (its errors are said under
/// the tables, not a second time here).
fn fail_if_any(failed: &[SuiteError], written: &str) -> Result<()> {
    let mut recordings: Vec<&str> = Vec::new();
    for name in failed.iter().filter_map(SuiteError::recording) {
        if !recordings.contains(&name) {
            recordings.push(name);
        }
    }
    match recordings.len() {
        0 => Ok(()),
        n => anyhow::bail!(
            "{n} {} failed, named with {} error under the tables ({written}): {}",
            if n == 1 { "recording" } else { "recordings" },
            if n == 1 { "its" } else { "their" },
            recordings.join("; ")
        ),
    }
}

/// Prints and writes a table (the recordings that failed named under it), then fails when any
/// did.
fn write_then_fail(
    mut md: String,
    failed: &[SuiteError],
    out: Option<&Path>,
    name: &str,
    what: &str,
) -> Result<()> {
    md.push_str(&not_scored(failed, what));
    print_and_write(&md, out, name)?;
    fail_if_any(failed, "the others' table was written")
}

/// Prints a table and, with an output directory, writes it there as `name`.
fn print_and_write(md: &str, out: Option<&Path>, name: &str) -> Result<()> {
    corridor_client::say_text(md);
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        std::fs::write(dir.join(name), md)?;
    }
    Ok(())
}
