//! `clothsim-xpbd`: clothsim with every built-in solver plus `xpbd`.

use std::process::ExitCode;

fn main() -> ExitCode {
    clothsim::run(&clothsim::default_registry().with(clothsim_xpbd::Xpbd::ENTRY))
}
