//! `clothsim`: the CS184 mass-spring cloth in the terminal, with the solvers this build has.

use std::process::ExitCode;

fn main() -> ExitCode {
    clothsim::run(&clothsim::default_registry())
}
