//! `corridor-wire`: the wire types for other languages, generated from the Rust definitions
//! ([`corridor_shared::wire_layout`]): `c-header` prints `client/c/corridor_wire.h`, `layout`
//! prints the sizes, alignments and field offsets as JSON (checked by the Python client's test).

use clap::{Parser, Subcommand};
use std::io::Write;

#[derive(Parser, Debug)]
#[command(
    name = "corridor-wire",
    version,
    about = "Print the corridor wire types as a C header or as layout JSON",
    after_help = "Examples:\n  corridor-wire c-header > client/c/corridor_wire.h\n  corridor-wire layout > layout.json\nExit code: 0 success, 1 error (writing the output), 2 usage error."
)]
struct Args {
    #[command(subcommand)]
    what: What,
}

#[derive(Subcommand, Debug)]
enum What {
    /// The C header (C11, with static assertions on every size and offset).
    CHeader,
    /// Size, alignment, iceoryx2 type name, service and field offsets of each type, as JSON.
    Layout,
}

fn main() -> std::process::ExitCode {
    let text = match Args::parse().what {
        What::CHeader => corridor_shared::wire_layout::c_header(),
        What::Layout => corridor_shared::wire_layout::layout_json(),
    };
    // A write error (a full disk, a closed pipe) is said once, not a panic (`print!` panicked
    // with a backtrace on `> /dev/full`).
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: writing to standard output: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
