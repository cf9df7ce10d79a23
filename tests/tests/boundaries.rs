//! The crate graph guards the house's boundaries: read from `cargo metadata`, it must have no
//! forbidden edge.
//!
//! - the data crates (cloth-mesh, cloth-scene) and cloth-render know no solver: none of them
//!   depends, directly or through other workspace crates, on cloth-solver or cloth-implicit;
//! - cloth-solver does not depend on cloth-implicit (the implicit solvers are one optional
//!   crate among others, built on the trait);
//! - only cloth-tui uses the terminal: no other workspace crate lists ratatui or crossterm.
//!
//! Normal and build dependencies count; dev-dependencies do not (a benchmark of the renderer may
//! drive a solver to get a cloth that has moved, without the library knowing any).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::Command;

use serde_json::{Value, json};

/// Crates that must not reach a solver crate.
const SOLVER_FREE: [&str; 3] = ["cloth-mesh", "cloth-scene", "cloth-render"];
/// The solver crates they must not reach.
const SOLVERS: [&str; 2] = ["cloth-solver", "cloth-implicit"];
/// The only crate allowed to use the terminal libraries.
const TERMINAL_CRATE: &str = "cloth-tui";
/// The terminal libraries.
const TERMINAL: [&str; 2] = ["ratatui", "crossterm"];

/// Every forbidden edge of the workspace described by `metadata` (the JSON of
/// `cargo metadata --no-deps --format-version 1`), one sentence each.
fn forbidden_edges(metadata: &Value) -> Vec<String> {
    // Workspace crate -> the crates it lists as normal or build dependencies.
    let mut deps: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for package in metadata["packages"].as_array().into_iter().flatten() {
        let Some(name) = package["name"].as_str() else {
            continue;
        };
        let listed = package["dependencies"]
            .as_array()
            .into_iter()
            .flatten()
            .filter(|d| d["kind"].as_str() != Some("dev"))
            .filter_map(|d| d["name"].as_str())
            .map(str::to_owned)
            .collect();
        deps.insert(name.to_owned(), listed);
    }
    let reach = |from: &str| -> BTreeSet<String> {
        let mut seen = BTreeSet::new();
        let mut todo = vec![from.to_owned()];
        while let Some(c) = todo.pop() {
            for d in deps.get(&c).into_iter().flatten() {
                if seen.insert(d.clone()) {
                    todo.push(d.clone());
                }
            }
        }
        seen
    };
    let mut bad = Vec::new();
    for from in SOLVER_FREE {
        let reached = reach(from);
        for solver in SOLVERS {
            if reached.contains(solver) {
                bad.push(format!("{from} depends on {solver}"));
            }
        }
    }
    if reach("cloth-solver").contains("cloth-implicit") {
        bad.push("cloth-solver depends on cloth-implicit".to_owned());
    }
    for (from, listed) in &deps {
        if from == TERMINAL_CRATE {
            continue;
        }
        for term in TERMINAL {
            if listed.contains(term) {
                bad.push(format!("{from} depends on {term}"));
            }
        }
    }
    bad
}

#[test]
fn the_workspace_has_no_forbidden_dependency() {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("../Cargo.toml");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned());
    let out = Command::new(cargo)
        .args([
            "metadata",
            "--no-deps",
            "--format-version",
            "1",
            "--manifest-path",
        ])
        .arg(&manifest)
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let metadata: Value = serde_json::from_slice(&out.stdout).expect("cargo metadata is JSON");
    // The check must have looked at the real workspace, not at nothing.
    let names: Vec<&str> = metadata["packages"]
        .as_array()
        .expect("packages")
        .iter()
        .filter_map(|p| p["name"].as_str())
        .collect();
    for name in SOLVER_FREE.iter().chain(&SOLVERS).chain([&TERMINAL_CRATE]) {
        assert!(
            names.contains(name),
            "{name} is not in the workspace: {names:?}"
        );
    }
    assert_eq!(forbidden_edges(&metadata), Vec::<String>::new());
}

/// A workspace in `cargo metadata`'s shape.
fn workspace(crates: &Graph) -> Value {
    json!({
        "packages": crates
            .iter()
            .map(|(name, deps)| json!({
                "name": name,
                "dependencies": deps
                    .iter()
                    .map(|(d, kind)| json!({"name": d, "kind": kind}))
                    .collect::<Vec<_>>(),
            }))
            .collect::<Vec<_>>(),
    })
}

/// Crates and their dependencies, as `(crate, [(dependency, kind)])`.
type Graph = Vec<(&'static str, Vec<(&'static str, Option<&'static str>)>)>;

/// The house as it should be.
fn clean() -> Graph {
    vec![
        ("cloth-mesh", vec![("nalgebra", None)]),
        ("cloth-scene", vec![("cloth-mesh", None), ("serde", None)]),
        ("cloth-solver", vec![("cloth-mesh", None)]),
        (
            "cloth-render",
            vec![("cloth-mesh", None), ("cloth-solver", Some("dev"))],
        ),
        ("cloth-implicit", vec![("cloth-solver", None)]),
        ("cloth-helper", vec![("cloth-mesh", Some("build"))]),
        (
            "cloth-tui",
            vec![
                ("cloth-scene", None),
                ("ratatui", None),
                ("crossterm", None),
            ],
        ),
    ]
}

/// The forbidden edges of the clean house with `from -> to` added.
fn with_edge(from: &str, to: &'static str) -> Vec<String> {
    let mut crates = clean();
    if let Some((_, deps)) = crates.iter_mut().find(|(n, _)| *n == from) {
        deps.push((to, None));
    }
    forbidden_edges(&workspace(&crates))
}

#[test]
fn the_check_passes_the_house_as_designed() {
    let crates = clean();
    assert_eq!(forbidden_edges(&workspace(&crates)), Vec::<String>::new());
}

#[test]
fn the_check_fails_on_each_kind_of_forbidden_edge() {
    assert_eq!(
        with_edge("cloth-scene", "cloth-solver"),
        ["cloth-scene depends on cloth-solver"]
    );
    // Through cloth-implicit, cloth-render also reaches cloth-solver.
    assert_eq!(
        with_edge("cloth-render", "cloth-implicit"),
        [
            "cloth-render depends on cloth-solver",
            "cloth-render depends on cloth-implicit"
        ]
    );
    assert_eq!(
        with_edge("cloth-solver", "cloth-implicit"),
        ["cloth-solver depends on cloth-implicit"]
    );
    assert_eq!(
        with_edge("cloth-render", "crossterm"),
        ["cloth-render depends on crossterm"]
    );
    assert_eq!(
        with_edge("cloth-implicit", "ratatui"),
        ["cloth-implicit depends on ratatui"]
    );
}

#[test]
fn the_check_follows_edges_through_other_workspace_crates() {
    // cloth-mesh -> cloth-helper -> cloth-solver: the data crate reaches a solver indirectly,
    // and so do cloth-scene and cloth-render through it.
    let mut crates = clean();
    for (name, deps) in &mut crates {
        match *name {
            "cloth-mesh" => deps.push(("cloth-helper", None)),
            "cloth-helper" => deps.push(("cloth-solver", Some("build"))),
            _ => {}
        }
    }
    assert_eq!(
        forbidden_edges(&workspace(&crates)),
        [
            "cloth-mesh depends on cloth-solver",
            "cloth-scene depends on cloth-solver",
            "cloth-render depends on cloth-solver"
        ]
    );
}
