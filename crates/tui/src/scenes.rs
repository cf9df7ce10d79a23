//! `clothsim scenes`: the bundled scenes, one line each.

/// Prints each bundled scene's name and description.
pub fn run() {
    let width = cloth_scene::BUNDLED
        .iter()
        .map(|s| s.name.len())
        .max()
        .unwrap_or(0);
    for s in cloth_scene::BUNDLED {
        println!("{:width$}  {}", s.name, s.description);
    }
}
