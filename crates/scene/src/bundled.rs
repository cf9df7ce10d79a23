//! Scenes embedded in the binary, addressable by name.

/// A scene file shipped inside the binary.
#[derive(Debug, Clone, Copy)]
pub struct BundledScene {
    /// Name, as typed on the command line (`pinned4`).
    pub name: &'static str,
    /// One line saying what the scene shows.
    pub description: &'static str,
    /// The file's JSON text, byte for byte as in `scenes/`.
    pub json: &'static str,
}

macro_rules! scene {
    ($name:literal, $description:literal) => {
        BundledScene {
            name: $name,
            description: $description,
            json: include_str!(concat!("../../../scenes/", $name, ".json")),
        }
    };
}

/// Every bundled scene: the course's five (unchanged), then clothsim's own (whose descriptions
/// are their files' `description`, word for word).
pub const BUNDLED: &[BundledScene] = &[
    scene!(
        "pinned2",
        "CS184: horizontal cloth pinned at two corners of one edge, swings down and hangs"
    ),
    scene!(
        "pinned4",
        "CS184: horizontal cloth pinned at its four corners, sags into a hammock (the default)"
    ),
    scene!(
        "sphere",
        "CS184: unpinned cloth falls onto a sphere and drapes over it (no floor)"
    ),
    scene!(
        "plane",
        "CS184: unpinned cloth falls flat onto a floor with friction"
    ),
    scene!(
        "selfCollision",
        "CS184: vertical cloth standing on the floor collapses onto itself"
    ),
    scene!(
        "curtain",
        "A curtain hung from every third point of its top edge, swinging out and leaning in a steady breeze"
    ),
    scene!(
        "drape",
        "A tablecloth falls over a sphere and spreads onto the floor beneath"
    ),
    scene!(
        "hammock",
        "A long cloth slung between two fully pinned edges, sagging into a trough"
    ),
];

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
