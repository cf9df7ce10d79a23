//! The solvers this application offers: the default registry, the choice of a solver for a
//! scene, and `clothsim solvers`.
//!
//! This is the one place that names concrete solvers ([`default_registry`]); everything else
//! reads whatever registry the application was started with.

use std::fmt::Write as _;

use anyhow::Context as _;
use cloth_mesh::ClothMesh;
use cloth_scene::{Scene, SceneError};
use cloth_solver::{OptionError, OptionKind, Registry, Solver, SolverEntry, Verlet};
use serde_json::Value;

/// The solvers of this build: [`Verlet`] (the default), then, with the `implicit` feature,
/// `implicit` and `fast-implicit`.
#[must_use]
pub fn default_registry() -> Registry {
    let registry = Registry::new().with(Verlet::ENTRY);
    #[cfg(feature = "implicit")]
    let registry = registry
        .with(cloth_implicit::ImplicitEuler::ENTRY)
        .with(cloth_implicit::FastImplicit::ENTRY);
    registry
}

/// A solver chosen for a scene: its entry and the options it is built with.
#[derive(Debug, Clone)]
pub struct Choice {
    /// The solver's entry.
    pub entry: SolverEntry,
    /// Its options, a checked JSON object.
    pub options: Value,
}

impl Choice {
    /// The registered solver `name` with `options`, checked against its entry.
    ///
    /// # Errors
    /// When `name` is not registered or its entry refuses `options`.
    pub fn checked(registry: &Registry, name: &str, options: &Value) -> anyhow::Result<Self> {
        let entry = *registry.get(name)?;
        entry.check(options)?;
        Ok(Self {
            entry,
            options: options.clone(),
        })
    }

    /// Builds the solver for `mesh`.
    ///
    /// # Errors
    /// When the solver cannot be built with these options.
    pub fn build(&self, mesh: &ClothMesh) -> anyhow::Result<Box<dyn Solver>> {
        Ok(self.entry.build(mesh, &self.options)?)
    }
}

/// The solver for `scene`: `name` when the user chose one (on the command line or in the UI),
/// else the scene's `simulation.solver`, else the registry's first; with the options the scene
/// gives it (see [`Scene::options_for`]), checked.
///
/// # Errors
/// A name that is not registered or options the solver refuses, naming the scene, the key, the
/// value and what is allowed.
pub fn choose(registry: &Registry, scene: &Scene, name: Option<&str>) -> anyhow::Result<Choice> {
    let default = registry
        .default_entry()
        .context("this clothsim has no solvers registered")?;
    let entry = match (name, scene.solver.as_deref()) {
        (Some(name), _) => *registry.get(name)?,
        (None, Some(name)) => *registry.get(name).map_err(|e| SceneError::Invalid {
            origin: scene.origin.clone(),
            key: "simulation.solver".to_owned(),
            value: format!("{name:?}"),
            allowed: format!(
                "one of the solvers of this clothsim: {}",
                e.available
                    .iter()
                    .map(|n| format!("{n:?}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })?,
        (None, None) => *default,
    };
    let options = scene.options_for(entry.name(), default.name());
    entry
        .check(&options)
        .map_err(|e| scene_option_error(scene, &e))?;
    Ok(Choice { entry, options })
}

/// A refused option of a scene, named by the scene's key that gave it.
fn scene_option_error(scene: &Scene, e: &OptionError) -> anyhow::Error {
    let key = match e.key() {
        Some(key) => format!("simulation.solver_options.{key}"),
        None => "simulation.solver_options".to_owned(),
    };
    anyhow::anyhow!("{}: {key}: {e}", scene.origin)
}

/// The steps per frame a run of `entry` on `scene` takes: the scene's
/// `simulation.simulation_steps` when the file or a `--set` gives it, else the solver's
/// recommendation ([`SolverEntry::steps_per_frame`]).
#[must_use]
pub fn steps_for(scene: &Scene, entry: &SolverEntry) -> u32 {
    if scene.gives_steps() {
        scene.params.steps_per_frame
    } else {
        entry.steps_per_frame()
    }
}

/// Solver options given on the command line, in the order given: each is checked against
/// the chosen solver's entry by [`prepare`], and overrides what the scene gives it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Flags {
    /// Each option as `(flag as typed, option name, value)`, e.g.
    /// `("--threads 2", "threads", 2)`.
    pub given: Vec<(String, String, Value)>,
}

impl Flags {
    /// Adds `option = value`, given on the command line as `flag`.
    #[must_use]
    pub fn with(mut self, flag: impl Into<String>, option: &str, value: Value) -> Self {
        self.given.push((flag.into(), option.to_owned(), value));
        self
    }

    /// Parses `KEY=VALUE` as a solver option: the value is JSON when it parses as JSON (a
    /// number, `true`, a quoted string) and a bare string otherwise (`order=colored`).
    ///
    /// # Errors
    /// A text without `=` or with an empty key.
    pub fn parse_option(text: &str) -> Result<(String, Value), String> {
        let Some((key, value)) = text.split_once('=') else {
            return Err(format!(
                "{text:?} is not KEY=VALUE; write a solver option and its value, e.g. threads=2 \
                 (`clothsim solvers` lists every solver's options)"
            ));
        };
        let key = key.trim();
        if key.is_empty() {
            return Err(format!("{text:?} has no option name before '='"));
        }
        let value = value.trim();
        let value = serde_json::from_str(value).unwrap_or_else(|_| Value::from(value));
        Ok((key.to_owned(), value))
    }
}

/// Readies `scene` for a run of the solver `name` (the scene's own when `None`, see
/// [`choose`]) with the options `flags` gives on the command line: the chosen solver and its
/// options become the scene's (so a live UI's "restore" and a saved scene keep them), and the
/// steps per frame become [`steps_for`] the chosen solver.
///
/// Nothing is dropped silently: the scene's `solver_options` belong to the scene's own solver,
/// so when `name` chooses another one each of them must be an option of that one too (and
/// passes to it), or it is an error naming both solvers; a flag for an option the chosen
/// solver does not declare is an error naming the solvers that do.
///
/// # Errors
/// What [`choose`] refuses, scene options meant for another solver, and flags the chosen
/// solver has no option for or refuses.
pub fn prepare(
    registry: &Registry,
    scene: &mut Scene,
    name: Option<&str>,
    flags: &Flags,
) -> anyhow::Result<Choice> {
    let default = registry
        .default_entry()
        .context("this clothsim has no solvers registered")?;
    let own = scene
        .solver
        .clone()
        .unwrap_or_else(|| default.name().to_owned());
    let mut choice = choose(registry, scene, name)?;
    let entry = choice.entry;
    let own_entry = registry.get(&own).ok().copied();
    if own_entry.is_none_or(|e| e.name() != entry.name()) && !scene.solver_options.is_empty() {
        for (key, value) in &scene.solver_options {
            if entry.option(key).is_none() {
                anyhow::bail!(
                    "{}: simulation.solver_options.{key} ({value}) is given for the scene's \
                     solver {own}, but --solver {} has no {key} option; remove it from the \
                     scene, or run {own}",
                    scene.origin,
                    entry.name()
                );
            }
        }
        choice.options = Value::Object(scene.solver_options.clone());
        entry
            .check(&choice.options)
            .map_err(|e| scene_option_error(scene, &e))?;
    }
    let mut options = choice.options.as_object().cloned().unwrap_or_default();
    for (flag, option, value) in &flags.given {
        if entry.option(option).is_none() {
            let with: Vec<&str> = registry
                .entries()
                .iter()
                .filter(|e| e.option(option).is_some())
                .map(SolverEntry::name)
                .collect();
            anyhow::bail!(
                "{flag}: the {} solver has no {option} option (solvers with one: {})",
                entry.name(),
                if with.is_empty() {
                    "none".to_owned()
                } else {
                    with.join(", ")
                }
            );
        }
        options.insert(option.clone(), value.clone());
        entry
            .check(&Value::Object(options.clone()))
            .map_err(|e| anyhow::anyhow!("{flag}: {e}"))?;
    }
    scene.set_solver(entry.name(), options.clone());
    scene.params.steps_per_frame = steps_for(scene, &entry);
    Ok(Choice {
        entry,
        options: Value::Object(options),
    })
}

/// The text of `clothsim solvers`: each solver's name, description and steps per frame, then
/// its options with what they allow and their default.
#[must_use]
pub fn listing(registry: &Registry) -> String {
    let width = registry
        .entries()
        .iter()
        .flat_map(|e| {
            std::iter::once(e.name().len()).chain(e.options().iter().map(|o| o.name.len() + 2))
        })
        .max()
        .unwrap_or(0);
    let mut out = String::new();
    for (i, e) in registry.entries().iter().enumerate() {
        let steps = e.steps_per_frame();
        let _ = writeln!(
            out,
            "{:width$}  {}; {steps} step{} per frame{}",
            e.name(),
            e.description(),
            if steps == 1 { "" } else { "s" },
            if i == 0 { " (the default)" } else { "" },
        );
        for o in e.options() {
            let default = match o.kind {
                OptionKind::Choice { default, .. } => format!("{default:?}"),
                _ => o.default_value().to_string(),
            };
            let _ = writeln!(
                out,
                "  {:w$}  {}: {}, default {default}",
                o.name,
                o.description,
                o.allowed(),
                w = width - 2,
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_listing_shows_every_solver_and_option_of_the_registry() {
        let text = listing(&default_registry());
        let first = text.lines().next().unwrap();
        assert!(first.starts_with("verlet "), "{first}");
        assert!(
            first.ends_with("30 steps per frame (the default)"),
            "{first}"
        );
        assert!(text.contains("  threads "), "{text}");
        #[cfg(feature = "implicit")]
        {
            assert!(text.contains("\nfast-implicit  "), "{text}");
            assert!(
                text.contains("an integer from 1 to 1000, default 10"),
                "{text}"
            );
            assert!(text.contains("1 step per frame"), "{text}");
        }
    }

    fn scene(sets: &[&str]) -> Scene {
        let sets: Vec<String> = sets.iter().map(|s| (*s).to_owned()).collect();
        cloth_scene::load("pinned4", &sets).unwrap()
    }

    #[test]
    fn an_unknown_scene_solver_is_named_with_the_registered_ones() {
        let e = choose(
            &default_registry(),
            &scene(&["simulation.solver=\"rk4\""]),
            None,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("pinned4: simulation.solver is \"rk4\", but it must be one of the solvers of this clothsim: \"verlet\""),
            "{e}"
        );
    }

    #[test]
    fn scene_options_reach_their_own_solver_only() {
        let registry = Registry::new().with(Verlet::ENTRY);
        let s = scene(&["simulation.solver_options={\"threads\": 2}"]);
        let c = choose(&registry, &s, None).unwrap();
        assert_eq!(c.options, serde_json::json!({"threads": 2}));
        let e = choose(
            &registry,
            &scene(&["simulation.solver_options={\"bogus\": 1}"]),
            None,
        )
        .unwrap_err()
        .to_string();
        assert_eq!(
            e,
            "pinned4: simulation.solver_options.bogus: the verlet solver has no option \"bogus\"; its options: threads, order"
        );
    }

    #[cfg(feature = "implicit")]
    #[test]
    fn options_meant_for_another_solver_are_an_error_naming_both() {
        let registry = default_registry();
        // The scene's options are verlet's (it names no solver); fast-implicit has no `bogus`.
        let mut s = scene(&["simulation.solver_options={\"bogus\": 1}"]);
        let e = prepare(&registry, &mut s, Some("fast-implicit"), &Flags::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("pinned4: simulation.solver_options.bogus (1) is given for the scene's solver verlet, but --solver fast-implicit has no bogus option"),
            "{e}"
        );
        // An option both have passes on, and is checked by the chosen solver.
        let mut s = scene(&["simulation.solver_options={\"iterations\": 0}"]);
        let registry = Registry::new()
            .with(cloth_implicit::FastImplicit::ENTRY)
            .with(cloth_implicit::ImplicitEuler::ENTRY);
        let e = prepare(&registry, &mut s, Some("implicit"), &Flags::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("simulation.solver_options.iterations"), "{e}");
    }

    #[cfg(feature = "implicit")]
    #[test]
    fn a_flag_reaches_the_chosen_solver_and_is_checked_by_it() {
        let registry = default_registry();
        let mut s = scene(&[]);
        let flags = Flags::default().with("--option iterations=4", "iterations", 4.into());
        let c = prepare(&registry, &mut s, Some("fast-implicit"), &flags).unwrap();
        assert_eq!(c.options, serde_json::json!({"iterations": 4}));
        // The choice becomes the scene's, so a run built from it (the UI's restore) keeps it.
        assert_eq!(s.options_for("fast-implicit", "verlet"), c.options);
        let flags = Flags::default().with("--option iterations=0", "iterations", 0.into());
        let e = prepare(&registry, &mut scene(&[]), Some("fast-implicit"), &flags)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("--option iterations=0: "), "{e}");
        let flags = Flags::default().with("--option bogus=1", "bogus", 1.into());
        let e = prepare(&registry, &mut scene(&[]), Some("fast-implicit"), &flags)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("--option bogus=1: the fast-implicit solver has no bogus option"),
            "{e}"
        );
    }
}
