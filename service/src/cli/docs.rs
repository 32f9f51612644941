//! `corridor completions SHELL` and `corridor man`: shell completions and a man page, generated
//! from the clap definitions of [`super::Cli`] (so they cannot miss a flag).

use anyhow::Result;
use clap::{Args, CommandFactory};
use clap_complete::Shell;
use std::io::Write;

#[derive(Args, Debug)]
pub(super) struct CompletionsArgs {
    /// bash, zsh, fish, elvish or powershell.
    pub(super) shell: Shell,
}

/// Prints the completion script of `corridor` for the shell.
pub(super) fn completions(a: &CompletionsArgs) -> Result<()> {
    let mut cmd = super::Cli::command();
    // Into memory first: `generate` panics when its writer fails (`> /dev/full`), and the
    // write below is an error instead.
    let mut script = Vec::new();
    clap_complete::generate(a.shell, &mut cmd, "corridor", &mut script);
    let mut out = std::io::stdout().lock();
    out.write_all(&script)?;
    out.flush()?;
    Ok(())
}

/// Prints the man page of `corridor` (roff), with a section per command.
pub(super) fn man() -> Result<()> {
    let cmd = super::Cli::command();
    let mut out = std::io::stdout().lock();
    clap_mangen::Man::new(cmd.clone()).render(&mut out)?;
    for sub in cmd.get_subcommands().filter(|s| s.get_name() != "help") {
        writeln!(out, ".SH \"CORRIDOR {}\"", sub.get_name().to_uppercase())?;
        let man = clap_mangen::Man::new(sub.clone());
        man.render_description_section(&mut out)?;
        man.render_options_section(&mut out)?;
        if let Some(after) = sub.get_after_help() {
            writeln!(out, ".PP\n.nf\n{after}\n.fi")?;
        }
    }
    Ok(())
}
