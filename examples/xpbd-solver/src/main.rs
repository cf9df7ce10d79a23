//! `clothsim-xpbd`: clothsim with every built-in solver plus `xpbd`.

use std::process::ExitCode;

fn main() -> ExitCode {
    cloth_tui::run(&cloth_tui::default_registry().with(clothsim_xpbd::Xpbd::ENTRY))
}
