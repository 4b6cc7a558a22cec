//! `reconbench`: the command-line front end of the reconbench workspace.
//!
//! Each subcommand is a thin wrapper over a library call; all logic lives in the crates.
//! Errors print one line on stderr; bad input (unreadable or malformed files, bad
//! parameters) exits with code 2, other failures with 1.

mod cmd;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = cmd::Cli::parse();
    match cmd::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("reconbench: {}", e.message);
            ExitCode::from(e.code)
        }
    }
}
