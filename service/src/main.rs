//! `corridor`: the command-line entry point. Thin on purpose: the flags are parsed in
//! [`cli`], and every command calls the library.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
