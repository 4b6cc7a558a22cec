//! `reconbench`: the command-line front end of the reconbench workspace.
//!
//! Each subcommand is a thin wrapper over a library call; all logic lives in the crates.
//! Errors print one line on stderr; bad input (unreadable or malformed files, bad
//! parameters) exits with code 2, other failures with 1.

// Doc comments of the argument structs are the `--help` text, where `<name>` is a
// placeholder for the user, not HTML.
#![allow(rustdoc::invalid_html_tags)]

mod cmd;

use std::process::ExitCode;

use clap::Parser;

/// `println!` panics when stdout is a closed pipe (`reconbench list | head`). Restoring
/// SIGPIPE would need `unsafe`, so this hook ends the process quietly in that one case,
/// as a C tool killed by SIGPIPE would, and defers to the default hook otherwise.
fn quiet_on_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.starts_with("failed printing to stdout") {
            std::process::exit(141);
        }
        default(info);
    }));
}

fn main() -> ExitCode {
    quiet_on_broken_pipe();
    let cli = cmd::Cli::parse();
    match cmd::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("reconbench: {}", e.message);
            ExitCode::from(e.code)
        }
    }
}
