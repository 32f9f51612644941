//! `corridor eval`: the results table over the recordings of a suite.

use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub(super) struct EvalArgs {
    /// Suite file (TOML with [[recording]] tables).
    #[arg(long)]
    pub(super) suite: PathBuf,
    /// Also write the table (Markdown) and the rows (JSON) into this directory.
    #[arg(long)]
    pub(super) out: Option<PathBuf>,
}

/// Runs the suite, prints the table and writes it when asked.
pub(super) fn eval(a: EvalArgs) -> Result<()> {
    let rows = corridor_service::suite::run_suite(&a.suite)?;
    let md = corridor_service::suite::markdown(&rows);
    print!("{md}");
    if let Some(dir) = a.out {
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        std::fs::write(dir.join("results.md"), &md)?;
        std::fs::write(
            dir.join("results.json"),
            serde_json::to_string_pretty(&rows)? + "\n",
        )?;
    }
    Ok(())
}
