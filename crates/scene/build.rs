//! Embeds every `scenes/*.json` file: writes the `BUNDLED` table into `OUT_DIR`, so a new scene
//! file is bundled with no code edit.
//!
//! A scene's description is its JSON's top-level `description`, or its line in
//! `scenes/descriptions.txt` (for files kept byte for byte as the course ships them, which have
//! no such key). Scenes named in that file come first, in its order; the others follow by name.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn main() -> Result<(), String> {
    let manifest = std::env::var("CARGO_MANIFEST_DIR").map_err(|e| e.to_string())?;
    let dir = Path::new(&manifest).join("scenes");
    println!("cargo::rerun-if-changed=scenes");

    let listed = read_descriptions(&dir.join("descriptions.txt"))?;
    let mut scenes: Vec<(String, PathBuf)> = Vec::new();
    let entries =
        std::fs::read_dir(&dir).map_err(|e| format!("{}: cannot list: {e}", dir.display()))?;
    for entry in entries {
        let path = entry
            .map_err(|e| format!("{}: cannot list: {e}", dir.display()))?
            .path();
        if path.extension().is_none_or(|e| e != "json") {
            continue;
        }
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .ok_or_else(|| format!("{}: the file name is not UTF-8", path.display()))?
            .to_owned();
        scenes.push((name, path));
    }
    let rank = |name: &str| listed.iter().position(|(n, _)| n == name);
    scenes.sort_by(|(a, _), (b, _)| match (rank(a), rank(b)) {
        (Some(x), Some(y)) => x.cmp(&y),
        (Some(_), None) => std::cmp::Ordering::Less,
        (None, Some(_)) => std::cmp::Ordering::Greater,
        (None, None) => a.cmp(b),
    });

    let mut code = String::from(
        "/// Every bundled scene: the course's five (unchanged), then clothsim's own.\n",
    );
    code.push_str("pub const BUNDLED: &[BundledScene] = &[\n");
    for (name, path) in &scenes {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
        let json: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| format!("{}: not valid JSON: {e}", path.display()))?;
        let description = match json.get("description").and_then(|d| d.as_str()) {
            Some(d) => d.to_owned(),
            None => listed
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, d)| d.clone())
                .ok_or_else(|| {
                    format!(
                        "{}: no `description` key, and no `{name}: ...` line in \
                         scenes/descriptions.txt; add one of them",
                        path.display()
                    )
                })?,
        };
        let _ = writeln!(
            code,
            "    BundledScene {{ name: {name:?}, description: {description:?}, \
             json: include_str!({path:?}) }},",
            path = path.display().to_string()
        );
    }
    code.push_str("];\n");
    let out = PathBuf::from(std::env::var("OUT_DIR").map_err(|e| e.to_string())?);
    std::fs::write(out.join("bundled.rs"), code).map_err(|e| format!("cannot write: {e}"))
}

/// The `name: description` lines of `path` (blank lines and `#` comments skipped).
fn read_descriptions(path: &Path) -> Result<Vec<(String, String)>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (name, description) = line.split_once(':').ok_or_else(|| {
            format!(
                "{}:{}: expected `name: description`, found {line:?}",
                path.display(),
                i + 1
            )
        })?;
        out.push((name.trim().to_owned(), description.trim().to_owned()));
    }
    Ok(out)
}
