//! Command-line flags of `corridor` and their dispatch to the library.
//!
//! Map of the submodules (one per command, each with its flags):
//! - [`model`]: [`ModelArgs`](model::ModelArgs), the configuration flags shared by every command that runs the
//!   estimator;
//! - [`run`]: `corridor run`, the offline runner;
//! - [`eval`]: `corridor eval`, the results table of a suite;
//! - [`serve`]: `corridor serve`, the daemon;
//! - [`diagnose`]: `corridor diagnose`, the residual diagnosis;
//! - [`demo`]: `corridor demo`, the tour of the bundled recordings, and [`demo_daemon`], its
//!   section that replays a run through the daemon to a logger and a PDR consumer.

mod demo;
mod demo_daemon;
mod diagnose;
mod eval;
mod model;
mod run;
mod serve;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(
    name = "corridor",
    version,
    about = "Gyro-bias and attitude estimation for foot-mounted IMUs from map headings"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run the estimator over a CSV log and write estimates, innovations and a summary.
    Run(Box<run::RunArgs>),
    /// Run a suite of recordings through the baselines and the bias modes; print the table.
    Eval(eval::EvalArgs),
    /// The demo on the bundled measured recordings: the results table, the residual-diagnosis
    /// loop, one recording with the paper's injected bias (summary and figures), the second
    /// sensor, and the same injected run replayed through the daemon to a logger and a PDR
    /// consumer.
    Demo(demo::DemoArgs),
    /// Run the estimator as a daemon behind iceoryx2 services until SIGINT/SIGTERM.
    Serve(serve::ServeArgs),
    /// Diagnose the model on a log: rank the effects its residuals show, add the top one, and
    /// report the error before and after (report.json, report.md, residuals.svg).
    Diagnose(diagnose::DiagnoseArgs),
}

pub fn main() -> ExitCode {
    corridor_client::init_tracing("info");
    let cli = Cli::parse();
    match dispatch(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn dispatch(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Run(a) => run::run(&a),
        Command::Demo(a) => demo::demo(&a),
        Command::Serve(a) => serve::serve(&a),
        Command::Diagnose(a) => diagnose::diagnose(&a),
        Command::Eval(a) => eval::eval(a),
    }
}
