//! The crate graph keeps the plan in `docs/crates.toml`: which crates the workspace has, which
//! dependencies each may have (normal, build and dev), and the design's boundaries as rules.
//!
//! The check reads the plan and `cargo metadata`, and fails on
//!
//! - a workspace crate that is not in the plan, or a crate of the plan that is neither in the
//!   workspace nor marked `planned`;
//! - a dependency (normal, build or dev) on a workspace crate or on a guarded external crate
//!   that its crate's entry does not allow;
//! - a cycle among the workspace crates (cargo refuses normal cycles, so the cycles left are
//!   closed by dev-dependencies: a crate's tests built against a second copy of itself);
//! - a plan that names a crate it does not know, has a cycle of its own, or breaks one of its
//!   rules (`never`: a crate reaches a crate it must not know; `only`: a crate uses an external
//!   crate reserved to others), so a boundary cannot be widened by editing the plan alone.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;

mod support;

use serde::Deserialize;
use serde_json::{Value, json};
use support::root;

/// Where the plan lives, from the workspace's root.
const PLAN: &str = "docs/crates.toml";

/// The crate plan, as `docs/crates.toml` writes it.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Plan {
    /// External crates whose every use must be planned; other external crates are free.
    #[serde(default)]
    guarded: BTreeSet<String>,
    /// Every crate of the workspace, by package name.
    crates: BTreeMap<String, Entry>,
    /// Crates that must not reach others.
    #[serde(default)]
    never: Vec<Never>,
    /// External crates reserved to a few crates.
    #[serde(default)]
    only: Vec<Only>,
}

/// One crate of the plan.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    /// What the crate holds, in a few words.
    about: String,
    /// True for a crate the plan expects but the workspace does not have yet.
    #[serde(default)]
    planned: bool,
    /// What its library and binaries may depend on.
    #[serde(default)]
    normal: BTreeSet<String>,
    /// What its build script may depend on.
    #[serde(default)]
    build: BTreeSet<String>,
    /// What its tests, benches and examples may use besides `normal`.
    #[serde(default)]
    dev: BTreeSet<String>,
}

/// None of `from` reaches any of `reach`: through its own dependencies of any kind, then
/// through their normal and build dependencies (what any of its targets is built with).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Never {
    why: String,
    from: Vec<String>,
    reach: Vec<String>,
}

/// No crate but `crates` depends directly on any of `may_use`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Only {
    why: String,
    crates: Vec<String>,
    may_use: Vec<String>,
}

/// The kind of a dependency, as cargo lists it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Kind {
    Normal,
    Build,
    Dev,
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Kind::Normal => "normal",
            Kind::Build => "build",
            Kind::Dev => "dev",
        })
    }
}

/// Crate -> dependency -> the kinds it is listed with.
type Graph = BTreeMap<String, BTreeMap<String, BTreeSet<Kind>>>;

/// The workspace as `cargo metadata --no-deps` describes it.
#[derive(Debug, Default)]
struct Workspace {
    /// The workspace's crates.
    crates: BTreeSet<String>,
    /// Every dependency of every workspace crate, external ones included.
    deps: Graph,
}

impl Workspace {
    /// Reads the JSON of `cargo metadata --no-deps --format-version 1`.
    fn from_metadata(metadata: &Value) -> Self {
        let mut ws = Self::default();
        for package in metadata["packages"].as_array().into_iter().flatten() {
            let Some(name) = package["name"].as_str() else {
                continue;
            };
            ws.crates.insert(name.to_owned());
            let deps = ws.deps.entry(name.to_owned()).or_default();
            for dep in package["dependencies"].as_array().into_iter().flatten() {
                let Some(to) = dep["name"].as_str() else {
                    continue;
                };
                let kind = match dep["kind"].as_str() {
                    Some("dev") => Kind::Dev,
                    Some("build") => Kind::Build,
                    _ => Kind::Normal,
                };
                deps.entry(to.to_owned()).or_default().insert(kind);
            }
        }
        ws
    }
}

impl Plan {
    /// The dependencies the plan allows, as a graph.
    fn graph(&self) -> Graph {
        let mut graph = Graph::new();
        for (name, entry) in &self.crates {
            let deps = graph.entry(name.clone()).or_default();
            for (kind, list) in [
                (Kind::Normal, &entry.normal),
                (Kind::Build, &entry.build),
                (Kind::Dev, &entry.dev),
            ] {
                for to in list {
                    deps.entry(to.clone()).or_default().insert(kind);
                }
            }
        }
        graph
    }

    /// Whether the plan lets `from` depend on `to` as a `kind` dependency. A dev-dependency may
    /// also be a normal one (tests may list a normal dependency again, with other features).
    fn allows(&self, from: &str, to: &str, kind: Kind) -> bool {
        self.crates.get(from).is_some_and(|e| match kind {
            Kind::Normal => e.normal.contains(to),
            Kind::Build => e.build.contains(to),
            Kind::Dev => e.dev.contains(to) || e.normal.contains(to),
        })
    }

    /// What is wrong with the plan by itself, one sentence each.
    fn problems(&self) -> Vec<String> {
        let mut bad = Vec::new();
        let known = |name: &str| self.crates.contains_key(name) || self.guarded.contains(name);
        for (name, entry) in &self.crates {
            if entry.about.trim().is_empty() {
                bad.push(format!("{name} does not say what it holds (`about`)"));
            }
            for (kind, list) in [
                (Kind::Normal, &entry.normal),
                (Kind::Build, &entry.build),
                (Kind::Dev, &entry.dev),
            ] {
                for to in list.iter().filter(|to| !known(to)) {
                    bad.push(format!(
                        "{name}'s {kind} list names {to}, neither a crate of the plan nor a \
                         guarded external crate"
                    ));
                }
            }
        }
        for rule in &self.never {
            for name in rule.from.iter().chain(&rule.reach).filter(|n| !known(n)) {
                bad.push(format!("the rule \"{}\" names unknown {name}", rule.why));
            }
        }
        for rule in &self.only {
            for name in rule.crates.iter().filter(|n| !self.crates.contains_key(*n)) {
                bad.push(format!("the rule \"{}\" names unknown {name}", rule.why));
            }
            for name in rule.may_use.iter().filter(|n| !self.guarded.contains(*n)) {
                bad.push(format!(
                    "the rule \"{}\" reserves {name}, which is not guarded",
                    rule.why
                ));
            }
        }
        let graph = self.graph();
        let names: BTreeSet<String> = self.crates.keys().cloned().collect();
        bad.extend(
            cycles(&names, &graph)
                .into_iter()
                .map(|c| format!("the plan {c}")),
        );
        for rule in &self.never {
            for from in &rule.from {
                for (to, path) in reached(&graph, from) {
                    if rule.reach.contains(&to) {
                        bad.push(format!(
                            "the plan lets {from} reach {to} ({path}), but {}",
                            rule.why
                        ));
                    }
                }
            }
        }
        for rule in &self.only {
            for (from, deps) in &graph {
                if rule.crates.contains(from) {
                    continue;
                }
                for to in deps.keys().filter(|to| rule.may_use.contains(*to)) {
                    bad.push(format!("the plan lets {from} use {to}, but {}", rule.why));
                }
            }
        }
        bad
    }

    /// Where the workspace departs from the plan, one sentence each.
    fn departures(&self, ws: &Workspace) -> Vec<String> {
        let mut bad = Vec::new();
        for name in &ws.crates {
            if !self.crates.contains_key(name) {
                bad.push(format!(
                    "{name} is in the workspace but not in the plan ({PLAN})"
                ));
            }
        }
        for (name, entry) in &self.crates {
            if !entry.planned && !ws.crates.contains(name) {
                bad.push(format!(
                    "{name} is in the plan but not in the workspace (mark it `planned = true` \
                     if it is to come)"
                ));
            }
        }
        for (from, deps) in &ws.deps {
            if !self.crates.contains_key(from) {
                continue;
            }
            for (to, kinds) in deps {
                let checked = ws.crates.contains(to)
                    || self.crates.contains_key(to)
                    || self.guarded.contains(to);
                if !checked {
                    continue;
                }
                for kind in kinds.iter().filter(|k| !self.allows(from, to, **k)) {
                    bad.push(format!("{from} -> {to} ({kind}) is not in the plan"));
                }
            }
        }
        bad.extend(cycles(&ws.crates, &ws.deps));
        bad
    }
}

/// The arrow of `from -> to`, labelled with the dependency's kinds unless it is a normal one.
fn hop(graph: &Graph, from: &str, to: &str) -> String {
    let kinds = graph.get(from).and_then(|d| d.get(to));
    match kinds {
        Some(kinds) if !kinds.contains(&Kind::Normal) => {
            let names: Vec<String> = kinds.iter().map(ToString::to_string).collect();
            format!(" -{}-> ", names.join("/"))
        }
        _ => " -> ".to_owned(),
    }
}

/// The cycles of `graph` among `crates` (edges of any kind) that one depth-first search meets,
/// at least one whenever there is any, each written from its first crate in name order as
/// `has a dependency cycle: a -dev-> b -> a`.
fn cycles(crates: &BTreeSet<String>, graph: &Graph) -> Vec<String> {
    /// Depth-first search from `at`; `stack` is the current path.
    fn visit(
        at: &str,
        crates: &BTreeSet<String>,
        graph: &Graph,
        stack: &mut Vec<String>,
        done: &mut BTreeSet<String>,
        found: &mut BTreeSet<Vec<String>>,
    ) {
        stack.push(at.to_owned());
        for to in graph.get(at).into_iter().flat_map(BTreeMap::keys) {
            if !crates.contains(to) || done.contains(to) {
                continue;
            }
            if let Some(start) = stack.iter().position(|c| c == to) {
                let mut cycle = stack[start..].to_vec();
                // Start at the least name, so a cycle found twice is written once.
                let least = (0..cycle.len()).min_by_key(|&i| &cycle[i]).unwrap_or(0);
                cycle.rotate_left(least);
                found.insert(cycle);
            } else {
                visit(to, crates, graph, stack, done, found);
            }
        }
        stack.pop();
        done.insert(at.to_owned());
    }
    let mut found = BTreeSet::new();
    let mut done = BTreeSet::new();
    for name in crates {
        if !done.contains(name) {
            visit(name, crates, graph, &mut Vec::new(), &mut done, &mut found);
        }
    }
    found
        .into_iter()
        .map(|cycle| {
            let mut text = cycle[0].clone();
            for (i, from) in cycle.iter().enumerate() {
                let to = &cycle[(i + 1) % cycle.len()];
                text.push_str(&hop(graph, from, to));
                text.push_str(to);
            }
            format!("has a dependency cycle: {text}")
        })
        .collect()
}

/// Every crate `from` reaches in `graph`, with the path that reaches it first: its own
/// dependencies of any kind, then their normal and build dependencies, and so on (a crate's
/// dev-dependencies are built only for its own tests, so they do not carry on).
fn reached(graph: &Graph, from: &str) -> BTreeMap<String, String> {
    let mut paths = BTreeMap::new();
    let mut todo = vec![(from.to_owned(), from.to_owned(), true)];
    while let Some((at, path, first)) = todo.pop() {
        for (to, kinds) in graph.get(&at).into_iter().flatten() {
            let carries = first || kinds.iter().any(|k| *k != Kind::Dev);
            if !carries || to == from || paths.contains_key(to) {
                continue;
            }
            let path = format!("{path}{}{to}", hop(graph, &at, to));
            paths.insert(to.clone(), path.clone());
            todo.push((to.clone(), path, false));
        }
    }
    paths
}

/// The workspace's root folder.
#[test]
fn the_workspace_keeps_the_crate_plan() {
    let text = std::fs::read_to_string(root().join(PLAN)).expect("the plan is readable");
    let plan: Plan = toml::from_str(&text).unwrap_or_else(|e| panic!("{PLAN}: {e}"));
    assert_eq!(plan.problems(), Vec::<String>::new(), "{PLAN}");

    let metadata = support::metadata();
    let ws = Workspace::from_metadata(&metadata);
    // A plan with only planned crates would pass an empty workspace: make sure it was read.
    assert!(ws.crates.contains("cloth-solver"), "{:?}", ws.crates);
    assert_eq!(plan.departures(&ws), Vec::<String>::new(), "{PLAN}");
}

/// A small house: data, a solver, a renderer, a UI and a binary, a harness on the solver and
/// a planned kit; `serde` is free, `ratatui` and `clap` are guarded.
const HOUSE: &str = r#"
guarded = ["ratatui", "clap"]

[crates.mesh]
about = "data"

[crates.solver]
about = "solvers"
normal = ["mesh"]

[crates.bench]
about = "timing"
normal = ["mesh", "solver"]

[crates.render]
about = "drawing"
normal = ["mesh"]

[crates.tui]
about = "the UI"
normal = ["render", "solver", "ratatui"]

[crates.bin]
about = "the binary"
normal = ["tui", "clap"]
build = ["mesh"]
dev = ["bench"]

[crates.kit]
about = "to come"
planned = true
normal = ["solver"]

[[never]]
why = "the renderer knows no solver"
from = ["render"]
reach = ["solver"]

[[only]]
why = "only the UI touches the terminal"
crates = ["tui"]
may_use = ["ratatui"]
"#;

fn house() -> Plan {
    toml::from_str(HOUSE).expect("the house's plan parses")
}

/// `cargo metadata`'s JSON for `crates` with the dependencies `edges`.
fn metadata(crates: &[&str], edges: &[(&str, &str, Kind)]) -> Value {
    json!({
        "packages": crates
            .iter()
            .map(|name| json!({
                "name": name,
                "dependencies": edges
                    .iter()
                    .filter(|(from, _, _)| from == name)
                    .map(|(_, to, kind)| json!({
                        "name": to,
                        "kind": match kind {
                            Kind::Normal => Value::Null,
                            Kind::Build => json!("build"),
                            Kind::Dev => json!("dev"),
                        },
                    }))
                    .collect::<Vec<_>>(),
            }))
            .collect::<Vec<_>>(),
    })
}

/// The house's crates (the planned kit not yet built).
const BUILT: [&str; 6] = ["mesh", "solver", "bench", "render", "tui", "bin"];

/// The house's dependencies as planned, and a free external one.
fn planned_edges() -> Vec<(&'static str, &'static str, Kind)> {
    vec![
        ("mesh", "serde", Kind::Normal),
        ("solver", "mesh", Kind::Normal),
        ("bench", "mesh", Kind::Normal),
        ("bench", "solver", Kind::Normal),
        ("render", "mesh", Kind::Normal),
        ("tui", "render", Kind::Normal),
        ("tui", "solver", Kind::Normal),
        ("tui", "ratatui", Kind::Normal),
        ("bin", "tui", Kind::Normal),
        ("bin", "clap", Kind::Normal),
        ("bin", "mesh", Kind::Build),
        ("bin", "bench", Kind::Dev),
        // A dev-dependency may list a normal one again.
        ("bin", "tui", Kind::Dev),
    ]
}

/// The departures of the house's workspace with `extra` dependencies.
fn departures_with(extra: &[(&'static str, &'static str, Kind)]) -> Vec<String> {
    let mut edges = planned_edges();
    edges.extend_from_slice(extra);
    house().departures(&Workspace::from_metadata(&metadata(&BUILT, &edges)))
}

#[test]
fn the_check_passes_a_workspace_that_keeps_the_plan() {
    assert_eq!(house().problems(), Vec::<String>::new());
    assert_eq!(departures_with(&[]), Vec::<String>::new());
}

#[test]
fn the_check_fails_on_an_unplanned_edge_of_each_kind() {
    assert_eq!(
        departures_with(&[("render", "solver", Kind::Normal)]),
        ["render -> solver (normal) is not in the plan"]
    );
    assert_eq!(
        departures_with(&[("render", "solver", Kind::Dev)]),
        ["render -> solver (dev) is not in the plan"]
    );
    assert_eq!(
        departures_with(&[("solver", "mesh", Kind::Build)]),
        ["solver -> mesh (build) is not in the plan"]
    );
    // A normal edge where only a dev one is planned.
    assert_eq!(
        departures_with(&[("bin", "bench", Kind::Normal)]),
        ["bin -> bench (normal) is not in the plan"]
    );
}

#[test]
fn the_check_guards_the_guarded_external_crates_only() {
    assert_eq!(
        departures_with(&[("render", "ratatui", Kind::Normal)]),
        ["render -> ratatui (normal) is not in the plan"]
    );
    assert_eq!(
        departures_with(&[("bench", "clap", Kind::Dev)]),
        ["bench -> clap (dev) is not in the plan"]
    );
    assert_eq!(
        departures_with(&[
            ("render", "serde", Kind::Normal),
            ("tui", "rayon", Kind::Dev)
        ]),
        Vec::<String>::new()
    );
}

#[test]
fn the_check_fails_on_a_dev_cycle() {
    // The solver's tests using the harness built on the solver.
    assert_eq!(
        departures_with(&[("solver", "bench", Kind::Dev)]),
        [
            "solver -> bench (dev) is not in the plan",
            "has a dependency cycle: bench -> solver -dev-> bench",
        ]
    );
    // The renderer's tests driving the UI, which is built on the renderer.
    assert_eq!(
        departures_with(&[("render", "tui", Kind::Dev)]),
        [
            "render -> tui (dev) is not in the plan",
            "has a dependency cycle: render -dev-> tui -> render",
        ]
    );
}

#[test]
fn the_check_fails_on_a_crate_missing_from_the_plan_or_the_workspace() {
    let mut crates = BUILT.to_vec();
    crates.push("helper");
    let ws = Workspace::from_metadata(&metadata(&crates, &planned_edges()));
    assert_eq!(
        house().departures(&ws),
        ["helper is in the workspace but not in the plan (docs/crates.toml)"]
    );
    // Without the harness: the planned kit may be missing, the harness may not.
    let edges: Vec<_> = planned_edges()
        .into_iter()
        .filter(|(from, to, _)| *from != "bench" && *to != "bench")
        .collect();
    let crates: Vec<&str> = BUILT.into_iter().filter(|c| *c != "bench").collect();
    let ws = Workspace::from_metadata(&metadata(&crates, &edges));
    assert_eq!(
        house().departures(&ws),
        [
            "bench is in the plan but not in the workspace (mark it `planned = true` if it is to come)"
        ]
    );
}

#[test]
fn the_plan_itself_must_keep_its_rules() {
    // The renderer's benches using the harness reach the solver through it.
    let mut plan = house();
    plan.crates
        .get_mut("render")
        .unwrap()
        .dev
        .insert("bench".into());
    assert_eq!(
        plan.problems(),
        [
            "the plan lets render reach solver (render -dev-> bench -> solver), but the renderer \
          knows no solver"
        ]
    );
    let mut plan = house();
    plan.crates
        .get_mut("bin")
        .unwrap()
        .normal
        .insert("ratatui".into());
    assert_eq!(
        plan.problems(),
        ["the plan lets bin use ratatui, but only the UI touches the terminal"]
    );
    let mut plan = house();
    plan.crates
        .get_mut("solver")
        .unwrap()
        .dev
        .insert("bench".into());
    assert_eq!(
        plan.problems(),
        ["the plan has a dependency cycle: bench -> solver -dev-> bench"]
    );
}

#[test]
fn the_plan_names_only_crates_it_knows() {
    let mut plan = house();
    plan.crates
        .get_mut("tui")
        .unwrap()
        .normal
        .insert("crossterm".into());
    plan.crates
        .get_mut("bin")
        .unwrap()
        .dev
        .insert("sovler".into());
    assert_eq!(
        plan.problems(),
        [
            "bin's dev list names sovler, neither a crate of the plan nor a guarded external crate",
            "tui's normal list names crossterm, neither a crate of the plan nor a guarded \
             external crate",
        ]
    );
    let typo = HOUSE.replace(
        "normal = [\"mesh\"]\n\n[crates.bench]",
        "nromal = [\"mesh\"]\n\n[crates.bench]",
    );
    assert!(
        toml::from_str::<Plan>(&typo).is_err(),
        "an unknown key is refused"
    );
}
