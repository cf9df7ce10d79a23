//! Scenes embedded in the binary, addressable by name.

/// A scene file shipped inside the binary.
#[derive(Debug, Clone, Copy)]
pub struct BundledScene {
    /// Name, as typed on the command line (`pinned4`).
    pub name: &'static str,
    /// One line saying what the scene shows.
    pub description: &'static str,
    /// The file's JSON text, byte for byte as in this crate's `scenes/` folder.
    pub json: &'static str,
}

// `BUNDLED`: every `scenes/*.json` file of this crate, written by the build script.
include!(concat!(env!("OUT_DIR"), "/bundled.rs"));

/// The bundled scene called `name` (case-sensitive, as listed by `clothsim scenes`).
#[must_use]
pub fn bundled(name: &str) -> Option<&'static BundledScene> {
    BUNDLED.iter().find(|s| s.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bundled_description_is_its_files_own_where_the_file_has_one() {
        for s in BUNDLED {
            let v: serde_json::Value = serde_json::from_str(s.json).unwrap();
            if let Some(d) = v.get("description").and_then(|d| d.as_str()) {
                assert_eq!(s.description, d, "{}", s.name);
            }
        }
    }
}
