//! `clothsim`: the CS184 mass-spring cloth in the terminal, with the solvers this build has.

use std::process::ExitCode;

fn main() -> ExitCode {
    cloth_tui::run(&cloth_tui::default_registry())
}
