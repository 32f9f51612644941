//! Command-line flags of `corridor` and their dispatch to the library.
//!
//! Map of the submodules (one per command, each with its flags):
//! - [`model`]: [`ModelArgs`](model::ModelArgs), the configuration flags shared by every command that runs the
//!   estimator;
//! - [`run`]: `corridor run`, the offline runner;
//! - [`eval`]: `corridor eval`, the results table of a suite;
//! - [`serve`]: `corridor serve`, the daemon;
//! - [`status`]: `corridor status`, the health of a running daemon;
//! - [`diagnose`]: `corridor diagnose`, the residual diagnosis;
//! - [`docs`]: `corridor completions SHELL` and `corridor man`;
//! - [`demo`]: `corridor demo`, the tour of the bundled recordings, and [`demo_daemon`], its
//!   section that replays a run through the daemon to a logger and a PDR consumer.

mod demo;
mod demo_daemon;
mod diagnose;
mod docs;
mod eval;
mod model;
mod run;
mod serve;
mod status;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(
    name = "corridor",
    version,
    about = "Gyro-bias and attitude estimation for foot-mounted IMUs from map headings",
    after_help = "Examples:\n  corridor demo\n  corridor run --imu imu.csv --config configs/gdins.toml --out out/run\n  corridor serve --config configs/service.toml --domain lab\n  corridor <COMMAND> --help\nExit code: 0 success, 1 error, 2 usage error, 3 no daemon answered (corridor status); a command stopped by Ctrl-C (SIGTERM) while it talks to a daemon (status, demo) ends as the signal does: 130 (143) in a shell; serve stopped so exits with 0."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

const RUN_EXAMPLES: &str = "Examples:
  corridor run --imu tests/data/gdins_exp36_corridor_out_and_back/imu.csv --config configs/gdins.toml --out out/exp36
  corridor run --imu imu.csv --config configs/gdins.toml --start-heading-deg -90 --mode paper --plots --out out/run
  corridor run --imu imu.csv --inject-gyro-bias 0.001,-0.001,0.005 --truth ground_truth.csv --out out/injected";
const EVAL_EXAMPLES: &str = "Examples:
  corridor eval --suite configs/eval/gdins.toml
  corridor eval --suite configs/eval/gdins.toml --out out/eval
  corridor eval --suite configs/eval/gdins.toml --ensemble --out out/eval";
const DEMO_EXAMPLES: &str = "Examples:
  corridor demo
  corridor demo --root /path/to/corridor --out /tmp/demo";
const SERVE_EXAMPLES: &str = "Examples:
  corridor serve --config configs/service.toml
  corridor serve --config configs/gdins.toml --domain lab --delivery lossless --checkpoint /var/lib/corridor/bias.bin
  (then, on the same domain: corridor-replay --imu imu.csv --domain lab; corridor status --domain lab)";
const DIAGNOSE_EXAMPLES: &str = "Examples:
  corridor diagnose --imu tests/data/gdins_exp25_multi_corridor/imu.csv --config configs/gdins.toml --out out/diag
  corridor diagnose --imu imu.csv --truth ground_truth.csv --mode paper --out out/diag
  corridor diagnose --suite configs/eval/gdins.toml --out docs/results   (the detection matrix)";

const STATUS_EXAMPLES: &str = "Examples:
  corridor status --domain lab
  corridor status --domain lab --watch --checkpoint /var/lib/corridor/bias.bin
  corridor status --domain lab --timeout-s 2 || systemctl restart corridor
Exit code: 0 healthy, 1 error (a --checkpoint that is no checkpoint, ...), 2 usage error, 3 no daemon answered within the timeout (or it is shutting down); stopped by Ctrl-C (SIGTERM), it ends as the signal does: 130 (143) in a shell.";

const COMPLETIONS_EXAMPLES: &str = "Examples:
  corridor completions bash > ~/.local/share/bash-completion/completions/corridor
  corridor completions zsh > ~/.zfunc/_corridor
  corridor completions fish > ~/.config/fish/completions/corridor.fish";
const MAN_EXAMPLES: &str = "Examples:
  corridor man > corridor.1 && man ./corridor.1
  corridor man | gzip > /usr/local/share/man/man1/corridor.1.gz";

#[derive(Subcommand, Debug)]
enum Command {
    /// Run the estimator over a CSV log and write estimates, innovations and a summary.
    #[command(after_help = RUN_EXAMPLES)]
    Run(Box<run::RunArgs>),
    /// Run a suite of recordings through the baselines and the bias modes; print the table.
    #[command(after_help = EVAL_EXAMPLES)]
    Eval(eval::EvalArgs),
    /// The demo on the bundled measured recordings: the results table, the residual-diagnosis
    /// loop, one recording with the paper's injected bias (summary and figures), the second
    /// sensor, and the same injected run replayed through the daemon to a logger and a PDR
    /// consumer.
    #[command(after_help = DEMO_EXAMPLES)]
    Demo(demo::DemoArgs),
    /// Run the estimator as a daemon behind iceoryx2 services until SIGINT/SIGTERM.
    #[command(after_help = SERVE_EXAMPLES)]
    Serve(serve::ServeArgs),
    /// The health of the daemon of a domain: rates, counters, losses, latency, bias and its σ,
    /// convergence (exit code 0 when healthy, 3 when no daemon answers).
    #[command(after_help = STATUS_EXAMPLES)]
    Status(status::StatusArgs),
    /// Print the shell completion script of corridor.
    #[command(after_help = COMPLETIONS_EXAMPLES)]
    Completions(docs::CompletionsArgs),
    /// Print the man page of corridor (roff), every command included.
    #[command(after_help = MAN_EXAMPLES)]
    Man,
    /// Diagnose the model on a log: rank the effects its residuals show, add the top one, and
    /// report the error before and after (report.json, report.md, residuals.svg).
    #[command(after_help = DIAGNOSE_EXAMPLES)]
    Diagnose(diagnose::DiagnoseArgs),
}

pub fn main() -> ExitCode {
    corridor_client::init_tracing("info");
    let cli = Cli::parse();
    if matches!(
        cli.command,
        Command::Man | Command::Completions(_) | Command::Status(_)
    ) {
        end_quietly_on_a_closed_pipe();
    }
    match dispatch(cli) {
        Ok(code) => code,
        // A flag's value outside the range of the key it sets is a usage error, as the
        // argument parser's own (exit code 2).
        Err(e)
            if e.chain().any(|c| {
                matches!(
                    c.downcast_ref::<corridor_shared::config::ConfigError>(),
                    Some(corridor_shared::config::ConfigError::Flag { .. })
                )
            }) =>
        {
            corridor_client::say_err!("error: {}", corridor_client::error_message(&e));
            ExitCode::from(corridor_client::EXIT_USAGE)
        }
        Err(e) => corridor_client::exit(Err(e)),
    }
}

/// A command that only prints (`corridor man | head -1`, `status`, `completions`) ends quietly
/// when its reader leaves, as `cat` does, instead of reporting "Broken pipe" (a review, session
/// 38): SIGPIPE back to its default, which Rust's start-up sets to ignored. Not for the
/// commands that do work and write files (`run`, `eval`, `diagnose`, `demo`, whose daemon
/// would leave its shared-memory files, and `serve`): their lines go through `say!`, which
/// drops a line it cannot write, and their logs through `init_tracing`, which does the same.
fn end_quietly_on_a_closed_pipe() {
    // SAFETY: signal(2) setting a standard disposition, at start-up before any thread exists;
    // no handler of ours is involved.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// `--out` must be a directory (or not exist yet): said before any work is done, not after a
/// suite of minutes.
fn check_out_dir(out: &std::path::Path) -> anyhow::Result<()> {
    if out.exists() && !out.is_dir() {
        anyhow::bail!("--out {}: exists and is not a directory", out.display());
    }
    Ok(())
}

/// Runs the command; its exit code (`status` has its own, the others succeed or fail).
fn dispatch(cli: Cli) -> anyhow::Result<ExitCode> {
    let done = |r: anyhow::Result<()>| r.map(|()| ExitCode::SUCCESS);
    let out = match &cli.command {
        Command::Run(a) => Some(&a.out),
        Command::Demo(a) => Some(&a.out),
        Command::Diagnose(a) => Some(&a.out),
        Command::Eval(a) => a.out.as_ref(),
        _ => None,
    };
    if let Some(out) = out {
        check_out_dir(out)?;
    }
    match cli.command {
        Command::Run(a) => done(run::run(&a)),
        Command::Demo(a) => done(demo::demo(&a)),
        Command::Serve(a) => done(serve::serve(&a)),
        Command::Diagnose(a) => done(diagnose::diagnose(&a)),
        Command::Eval(a) => done(eval::eval(a)),
        Command::Status(a) => {
            let code = status::status(&a)?;
            // A watch that Ctrl-C or SIGTERM stopped ends as the signal would, as every client
            // tool does (it said "stopped: interrupted").
            corridor_client::end_if_interrupted();
            Ok(code)
        }
        Command::Completions(a) => done(docs::completions(&a)),
        Command::Man => done(docs::man()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every `corridor …` command in the README's code blocks parses: each flag it names
    /// exists and has its value (the prose said `corridor eval --suite FILE --sweep`, which
    /// the parser refuses: `--sweep` takes the sweep file). Optional `[…]` groups are left
    /// out, comments and redirections cut off.
    #[test]
    fn the_readme_commands_parse() {
        let readme = include_str!("../../../README.md");
        let mut in_block = false;
        let mut lines = Vec::new();
        let mut pending = String::new();
        for line in readme.lines() {
            if line.starts_with("```") {
                in_block = !in_block;
                continue;
            }
            if !in_block {
                continue;
            }
            let line = line.split(" #").next().unwrap_or("").trim_end();
            match line.strip_suffix('\\') {
                Some(head) => pending.push_str(head),
                None => lines.push(std::mem::take(&mut pending) + line),
            }
        }
        let mut checked = 0;
        for line in &lines {
            // (an environment set before the command, as CORRIDOR_RUNTIME_DIR=DIR)
            let command = line.trim_start_matches(|c: char| c != ' ' && c != '=');
            let command = match command.strip_prefix('=') {
                Some(rest) => rest.split_once(' ').map_or("", |(_, c)| c),
                None => line,
            };
            if !command.starts_with("corridor ") {
                continue;
            }
            let mut words = Vec::new();
            let mut depth = 0;
            for w in command.split_whitespace() {
                if w == ">" || w == "|" {
                    break;
                }
                depth += w.matches('[').count();
                if depth == 0 {
                    words.push(w);
                }
                depth -= w.matches(']').count();
            }
            if let Err(e) = Cli::try_parse_from(&words) {
                panic!("README: `{line}` does not parse: {e}");
            }
            checked += 1;
        }
        assert!(checked >= 8, "only {checked} commands found in the README");
    }
}
