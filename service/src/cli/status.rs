//! `corridor status`: the health of the daemon of a domain, one screen, with an exit code for
//! scripts ([`corridor_client::status`]).

use anyhow::Result;
use clap::Args;
use corridor_client::status::{StatusReader, checkpoint_line};
use corridor_client::{ClientError, Domain, EXIT_NO_DAEMON};
use corridor_shared::injection::parse_wait_s;
use corridor_shared::services::DEFAULT_DOMAIN;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

/// Exit code when `--checkpoint` names something that cannot be the daemon's checkpoint (a
/// directory, a file that cannot be read or is no checkpoint).
pub(super) const EXIT_BAD_CHECKPOINT: u8 = 1;

#[derive(Args, Debug)]
pub(super) struct StatusArgs {
    /// iceoryx2 domain of the daemon.
    #[arg(long, default_value = DEFAULT_DOMAIN, value_parser = Domain::parse_name)]
    pub(super) domain: String,
    /// How long to wait for the daemon's answer, s (it publishes diagnostics every
    /// `daemon.diagnostics_period_s`, 1 s by default).
    #[arg(long, default_value_t = 5.0, value_parser = parse_wait_s)]
    pub(super) timeout_s: f64,
    /// The daemon's checkpoint file (`daemon.checkpoint_path`, or its `--checkpoint`): shows
    /// when it was last saved (the daemon does not publish its checkpoints).
    #[arg(long)]
    pub(super) checkpoint: Option<PathBuf>,
    /// Refresh at every diagnostics until Ctrl-C (or until the daemon stops answering).
    #[arg(long)]
    pub(super) watch: bool,
}

/// The `last checkpoint:` line for `path`, or what makes the path no checkpoint (naming it)
/// when it holds neither one nor nothing yet. A file that is there is read as the daemon would
/// (not moved, whatever it holds): a file that is no checkpoint passed for one ("saved 601.8 s
/// ago", a review).
fn checkpoint_status(path: &std::path::Path) -> Result<String, String> {
    let line = checkpoint_line(path).map_err(|e| e.to_string())?;
    match path
        .is_file()
        .then(|| corridor_service::checkpoint::read(path))
    {
        Some(Err(e)) => Err(format!("not a checkpoint the daemon can start from: {e}")),
        _ => Ok(line),
    }
}

/// Prints the status; exit code 0 when healthy, [`EXIT_NO_DAEMON`] when no daemon answers,
/// [`EXIT_BAD_CHECKPOINT`] when `--checkpoint` cannot be read.
pub(super) fn status(a: &StatusArgs) -> Result<ExitCode> {
    let domain = Domain::new(&a.domain)?;
    let timeout = Duration::from_secs_f64(a.timeout_s);
    // The path first: with no daemon running, a directory given for it waited out the timeout
    // and exited 3, as if only the daemon were wrong.
    if let Some(Err(why)) = a.checkpoint.as_deref().map(checkpoint_status) {
        eprintln!("error: --checkpoint: {why}");
        return Ok(ExitCode::from(EXIT_BAD_CHECKPOINT));
    }
    // The hint on a secured domain's runtime directory only when nothing answered at all (it
    // was added to "the daemon is shutting down" as well, a daemon that had been found).
    let no_daemon = |why: &str, hint: String| {
        eprintln!(
            "error: no corridor daemon answers on domain {:?}: {why}{hint}",
            domain.name(),
        );
        Ok(ExitCode::from(EXIT_NO_DAEMON))
    };
    let mut reader = match StatusReader::open(&domain, timeout) {
        Ok(r) => r,
        Err(e @ ClientError::NoPeer { .. }) => {
            eprintln!("error: {e}");
            return Ok(ExitCode::from(EXIT_NO_DAEMON));
        }
        Err(e) => return Err(e.into()),
    };
    let mut first = true;
    loop {
        let status = match reader.next(timeout, first) {
            Ok(Some(s)) => s,
            Ok(None) => {
                // (After a first screen the daemon had been found.)
                let hint = if first {
                    corridor_client::runtime_dir_hint()
                } else {
                    String::new()
                };
                return no_daemon(&format!("no diagnostics within {timeout:?}"), hint);
            }
            Err(ClientError::Interrupted) => {
                // Said as every tool says it (README, exit codes): a watch stopped by Ctrl-C or
                // SIGTERM ended with exit 0 and nothing, like one that had nothing to say. The
                // caller then ends as the signal would (`end_if_interrupted`).
                println!("stopped: interrupted");
                return Ok(ExitCode::SUCCESS);
            }
            Err(e) => return Err(e.into()),
        };
        first = false;
        if a.watch {
            // Clear the screen and go home, then draw.
            print!("\x1b[2J\x1b[H");
        }
        print!("{}", status.render(domain.name()));
        let checkpoint_readable = a.checkpoint.as_deref().is_none_or(|p| {
            let status = checkpoint_status(p);
            match &status {
                Ok(line) => print!("{line}"),
                Err(why) => println!("last checkpoint:  {why}"),
            }
            status.is_ok()
        });
        if !status.healthy() {
            return no_daemon("the daemon is shutting down", String::new());
        }
        if !a.watch {
            return Ok(if checkpoint_readable {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(EXIT_BAD_CHECKPOINT)
            });
        }
    }
}
