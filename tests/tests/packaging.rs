//! What `cargo publish` shows of each publishable crate: a description, a licence, a README
//! on disk and its documentation's address, so a crate read on crates.io or docs.rs says what
//! it is and where its guide is.

mod support;

use std::path::PathBuf;

#[test]
fn every_publishable_crate_has_a_readme_a_description_and_its_documentation() {
    let metadata = support::metadata();
    let packages = metadata["packages"].as_array().expect("packages");
    let mut checked = Vec::new();
    for p in packages {
        let name = p["name"].as_str().unwrap_or_default();
        // `publish = false` reads as an empty list of registries.
        if p["publish"].as_array().is_some_and(Vec::is_empty) {
            continue;
        }
        let text = |key: &str| p[key].as_str().unwrap_or_default().to_owned();
        assert!(!text("description").is_empty(), "{name}: no description");
        assert!(!text("license").is_empty(), "{name}: no licence");
        assert_eq!(
            text("documentation"),
            format!("https://docs.rs/{name}"),
            "{name}: its documentation"
        );
        let manifest = PathBuf::from(text("manifest_path"));
        let readme = text("readme");
        assert!(!readme.is_empty(), "{name}: no readme key");
        let readme = manifest.parent().expect("the crate's folder").join(readme);
        let body = std::fs::read_to_string(&readme)
            .unwrap_or_else(|e| panic!("{name}: {}: {e}", readme.display()));
        assert!(body.contains(name), "{name}: its README names it");
        checked.push(name.to_owned());
    }
    for name in [
        "clothsim",
        "cloth-mesh",
        "cloth-solver",
        "cloth-run",
        "cloth-tui",
    ] {
        assert!(
            checked.iter().any(|c| c == name),
            "{name} checked: {checked:?}"
        );
    }
}
