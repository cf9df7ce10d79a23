//! `clothsim`, the CS184 mass-spring cloth in the terminal, as a library: the whole application
//! (command line, live UI, `compare`, `simulate`, `render`, `bench`, `scenes`, `solvers`) runs
//! with any [`Registry`] of solvers.
//!
//! The `clothsim` binary is [`run`] with [`default_registry`]. A solver crate written elsewhere
//! builds its own clothsim by adding its entry:
//!
//! ```no_run
//! use std::process::ExitCode;
//!
//! fn main() -> ExitCode {
//!     let registry = clothsim::default_registry(); // .with(my_solver::MySolver::ENTRY)
//!     clothsim::run(&registry)
//! }
//! ```
//!
//! Every name the application lists or checks (the `--solver` values and their help, a scene's
//! `simulation.solver`, the UI's solver row, `clothsim solvers`) comes from the registry. Every
//! error ends as one clear message on stderr and a non-zero exit code; nothing here panics on
//! bad input.

mod args;
mod bench;
mod check;
mod cli;
mod render;
mod scenes;
mod simulate;
mod steal;

use std::ffi::OsString;
use std::io::{IsTerminal as _, Write as _};
use std::process::ExitCode;

pub use cloth_run::default_registry;
use cloth_run::output;
pub use cloth_solver::{Registry, SolverEntry};

/// Runs clothsim with the process's command line and the solvers of `registry`, returning the
/// exit code: success, 1 for an error (printed to stderr as one message), 2 for a command line
/// that does not parse (with clap's explanation).
pub fn run(registry: &Registry) -> ExitCode {
    run_from(registry, std::env::args_os())
}

/// Runs clothsim with the command line `args` and the solvers of `registry`; see [`run`].
///
/// The first argument is the program: its file name without extension (`clothsim-xpbd` for
/// `/usr/bin/clothsim-xpbd`) is the name the help, `--version`, the completion scripts and the
/// manual pages use.
pub fn run_from<I, T>(registry: &Registry, args: I) -> ExitCode
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let args: Vec<OsString> = args.into_iter().map(Into::into).collect();
    // The running binary's own name, so a plug-in binary's help, version, completions and
    // manual pages name it rather than `clothsim`.
    let program = args
        .first()
        .and_then(|a| std::path::Path::new(a).file_stem())
        .map_or_else(
            || cli::PROGRAM.to_owned(),
            |s| s.to_string_lossy().into_owned(),
        );
    cloth_run::headless::set_program_name(&program);
    let cli = match cli::parse(registry, &program, args) {
        Ok(cli) => cli,
        Err(e) => return clap_exit(&program, &e),
    };
    match cli.run(registry, &program) {
        Ok(()) => ExitCode::SUCCESS,
        // A reader that stops early (`| head`) is a normal end.
        Err(e) if output::ended_by_reader(&e) => ExitCode::SUCCESS,
        Err(e) => {
            // Nowhere is left to report a failure to write to stderr; the exit code still says it.
            let _ = writeln!(std::io::stderr(), "{program}: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Prints clap's help, version or usage error through the same output path as the commands:
/// help and version go to standard output (a reader that went away ends quietly, a full disk
/// or a closed standard output is an error), usage errors to stderr with clap's exit code.
fn clap_exit(program: &str, e: &clap::Error) -> ExitCode {
    let styled = e.render();
    let color = std::env::var_os("NO_COLOR").is_none();
    if e.use_stderr() {
        let mut err = std::io::stderr();
        let text = if color && err.is_terminal() {
            styled.ansi().to_string()
        } else {
            styled.to_string()
        };
        let _ = err.write_all(text.as_bytes());
        return ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2));
    }
    let text = if color && output::Stdout::is_terminal() {
        styled.ansi().to_string()
    } else {
        styled.to_string()
    };
    let mut out = output::Stdout::new();
    let written = out
        .write_all_or_fail(text.as_bytes())
        .and_then(|()| out.finish());
    match written {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if output::ended_by_reader(&e) => ExitCode::SUCCESS,
        Err(e) => {
            let _ = writeln!(std::io::stderr(), "{program}: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
