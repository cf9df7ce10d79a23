//! `clothsim`: the CS184 mass-spring cloth in the terminal.
//!
//! With no arguments it opens the live terminal UI on the bundled `pinned4` scene; subcommands
//! run headless (`simulate`, `render`, `scenes`). Every error ends as one clear message on stderr and a
//! non-zero exit code; nothing here panics on bad input.

mod app;
mod bench;
mod cli;
mod guard;
mod output;
mod render;
mod scenes;
mod simulate;
mod solvers;
mod steal;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = cli::Cli::parse();
    match cli.run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("clothsim: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
