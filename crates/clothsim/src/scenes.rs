//! `clothsim scenes`: the bundled scenes, one line each.

use std::fmt::Write as _;

use cloth_run::output::Stdout;

/// Prints each bundled scene's name and description.
///
/// # Errors
/// Standard output cannot be written (see [`cloth_run::output`]).
pub fn run() -> anyhow::Result<()> {
    let width = cloth_scene::BUNDLED
        .iter()
        .map(|s| s.name.len())
        .max()
        .unwrap_or(0);
    let mut text = String::new();
    for s in cloth_scene::BUNDLED {
        let _ = writeln!(text, "{:width$}  {}", s.name, s.description);
    }
    let mut out = Stdout::new();
    out.write_all_or_fail(text.as_bytes())?;
    out.finish()
}
