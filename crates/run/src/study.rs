//! Parameter studies: one scene run as several variants, each with one more `--set` applied,
//! stepped in lockstep and summed up in the same few numbers.
//!
//! `--vary KEY=V1,V2,...` names a key exactly as `--set` does (any scene key, including
//! `simulation.solver`) and 2 to [`MAX_VALUES`] values in `--set`'s value syntax; a variant is
//! the scene loaded with the command's `--set`s and then `KEY=Vi`, so a variant is, bit for bit,
//! the run `--set KEY=Vi` would give. Two `--vary` make a grid (the first across, the second
//! down). Values are separated by commas outside brackets, braces and quotes, so
//! `--vary simulation.gravity=[0,-9.8,0],[0,-1.6,0]` has two values.
//!
//! Variants step on threads (`std::thread::scope`), each on its own state and solver; the
//! lockstep is per frame, so every variant is at the same frame whenever one is looked at.

use std::fmt::Write as _;

use anyhow::{Context as _, bail};
use cloth_mesh::ClothState;
use cloth_scene::Scene;
use cloth_solver::{Registry, kinetic_energy, max_stretch_ratio};
use serde_json::Value;

use crate::guard::Divergence;
use crate::progress::Progress;
use crate::{headless, solvers};

/// The most values one `--vary` takes.
pub const MAX_VALUES: usize = 6;

/// The most `--vary` axes.
pub const MAX_AXES: usize = 2;

/// One `--vary KEY=V1,V2,...`: a dotted scene key and the values it takes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Axis {
    /// The dotted key, as `--set` takes it (`cloth.ks`).
    pub key: String,
    /// The values as typed (trimmed), each in `--set`'s value syntax.
    pub values: Vec<String>,
}

impl Axis {
    /// The key's last part, which names the axis in titles and file names (`ks`).
    pub fn short_key(&self) -> &str {
        self.key.rsplit('.').next().unwrap_or(&self.key)
    }
}

impl std::str::FromStr for Axis {
    type Err = String;

    fn from_str(arg: &str) -> Result<Self, Self::Err> {
        let (key, raw) = arg
            .split_once('=')
            .ok_or_else(|| format!("{arg}: expected KEY=V1,V2,..., e.g. cloth.ks=1,5000,100000"))?;
        let key = key.trim();
        if key.is_empty() || key.split('.').any(str::is_empty) {
            return Err(format!(
                "{arg}: the key must be a dotted path such as cloth.ks or simulation.solver"
            ));
        }
        let values = split_values(raw);
        if values.iter().any(String::is_empty) {
            return Err(format!(
                "{arg}: a value is empty (values are separated by commas)"
            ));
        }
        if !(2..=MAX_VALUES).contains(&values.len()) {
            return Err(format!(
                "{arg}: {} value{}; a study compares 2 to {MAX_VALUES} values",
                values.len(),
                if values.len() == 1 { "" } else { "s" }
            ));
        }
        for (i, v) in values.iter().enumerate() {
            if values[..i].contains(v) {
                return Err(format!("{arg}: the value {v} is given twice"));
            }
        }
        Ok(Self {
            key: key.to_owned(),
            values,
        })
    }
}

/// `raw` split at the commas outside brackets, braces and double quotes, each part trimmed.
fn split_values(raw: &str) -> Vec<String> {
    let mut parts = Vec::new();
    let mut depth = 0_i32;
    let mut quoted = false;
    let mut escaped = false;
    let mut current = String::new();
    for c in raw.chars() {
        match c {
            _ if escaped => escaped = false,
            '\\' if quoted => escaped = true,
            '"' => quoted = !quoted,
            '[' | '{' if !quoted => depth += 1,
            ']' | '}' if !quoted => depth -= 1,
            ',' if !quoted && depth <= 0 => {
                parts.push(current.trim().to_owned());
                current.clear();
                continue;
            }
            _ => {}
        }
        current.push(c);
    }
    parts.push(current.trim().to_owned());
    parts
}

/// Checks the axes together: at most [`MAX_AXES`], each key once.
///
/// # Errors
/// A message naming the repeated key or the count.
pub fn check_axes(axes: &[Axis]) -> anyhow::Result<()> {
    if axes.len() > MAX_AXES {
        bail!(
            "--vary is given {} times; a study has at most {MAX_AXES} axes (a grid)",
            axes.len()
        );
    }
    if let [a, b] = axes
        && a.key == b.key
    {
        bail!("--vary {}: the key is varied twice", a.key);
    }
    Ok(())
}

/// One variant: the values it gives the varied keys, its scene and its solver.
pub struct Variant {
    /// `(key, value)` for each axis, in the axes' order.
    pub values: Vec<(String, String)>,
    /// `short_key=value` for each axis, joined by spaces: the variant's title (`ks=5000`).
    pub title: String,
    /// The scene with the variant's overrides applied.
    pub scene: Scene,
    /// The solver it runs.
    pub choice: solvers::Choice,
}

impl Variant {
    /// The variant's part of a file name: `short_key=value` for each axis joined by dots
    /// (`ks=5000`, `ks=1.density=15`), with path separators replaced.
    pub fn file_label(&self) -> String {
        self.title.replace(' ', ".").replace(['/', '\\'], "_")
    }

    /// The values as JSON (`{"cloth.ks": 5000}`): each value as `--set` reads it.
    pub fn values_json(&self) -> Value {
        let map = self
            .values
            .iter()
            .map(|(k, v)| {
                let value = serde_json::from_str(v).unwrap_or_else(|_| Value::String(v.clone()));
                (k.clone(), value)
            })
            .collect();
        Value::Object(map)
    }
}

/// The variants of `scene_name` with `sets` and then each combination of the axes' values
/// (the first axis varying fastest), each with the solver `solver` or the one its scene names.
///
/// # Errors
/// The first variant whose scene or solver is refused, named by its values.
pub fn variants(
    registry: &Registry,
    scene_name: &str,
    sets: &[String],
    solver: Option<&str>,
    axes: &[Axis],
) -> anyhow::Result<Vec<Variant>> {
    check_axes(axes)?;
    for axis in axes {
        if let Some(set) = sets
            .iter()
            .find(|s| s.split_once('=').is_some_and(|(k, _)| k.trim() == axis.key))
        {
            bail!(
                "--set {set} and --vary {}: the key is varied, so each variant sets it; drop \
                 the --set",
                axis.key
            );
        }
    }
    // The first axis varies fastest: it runs across a row of the grid, the second down.
    let mut combos: Vec<Vec<(String, String, String)>> = vec![Vec::new()];
    for axis in axes {
        let before = std::mem::take(&mut combos);
        combos = axis
            .values
            .iter()
            .flat_map(|v| {
                before.iter().map(move |c| {
                    let mut c = c.clone();
                    c.push((axis.key.clone(), axis.short_key().to_owned(), v.clone()));
                    c
                })
            })
            .collect();
    }
    let mut variants: Vec<Variant> = combos
        .into_iter()
        .map(|combo| {
            let mut all = sets.to_vec();
            all.extend(combo.iter().map(|(k, _, v)| format!("{k}={v}")));
            let title = combo
                .iter()
                .map(|(_, s, v)| format!("{s}={v}"))
                .collect::<Vec<_>>()
                .join(" ");
            let scene =
                cloth_scene::load(scene_name, &all).with_context(|| format!("variant {title}"))?;
            let choice = solvers::choose(registry, &scene, solver)
                .with_context(|| format!("variant {title}"))?;
            Ok(Variant {
                values: combo.into_iter().map(|(k, _, v)| (k, v)).collect(),
                title,
                scene,
                choice,
            })
        })
        .collect::<anyhow::Result<_>>()?;
    share_meshes(&mut variants);
    Ok(variants)
}

/// Makes variants whose grids are the same (every variant of a study that varies no `cloth`
/// grid key) hold one mesh, so a study costs one topology whatever its number of variants.
fn share_meshes(variants: &mut [Variant]) {
    for i in 1..variants.len() {
        let (before, rest) = variants.split_at_mut(i);
        let v = &mut rest[0];
        if let Some(same) = before
            .iter()
            .find(|b| b.scene.mesh.spec() == v.scene.mesh.spec())
        {
            v.scene.mesh = std::sync::Arc::clone(&same.scene.mesh);
        }
    }
}

/// The numbers a study compares, for one variant at one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// The height (y) of the cloth's centre point, m.
    pub centre_height: f64,
    /// The height (y) of its lowest point, m.
    pub lowest_height: f64,
    /// The largest spring length over rest length.
    pub max_stretch: f64,
    /// The kinetic energy, J (velocities from the last step).
    pub kinetic_energy: f64,
    /// Why the run stopped, when the divergence guard stopped it.
    pub diverged: Option<String>,
}

/// A variant running: a [`crate::Run`] of its scene and solver, and where it stopped.
pub struct Run<'a> {
    /// The variant.
    pub variant: &'a Variant,
    inner: crate::Run,
    /// Frames stepped without diverging.
    pub frames: u64,
    /// The frame the guard stopped the run at, and why.
    pub diverged: Option<(u64, Divergence)>,
    /// A step's error (the run stops there too).
    pub failed: Option<String>,
}

impl<'a> Run<'a> {
    /// A run of `variant` from `start` (the scene's start when `None`).
    ///
    /// # Errors
    /// When the solver cannot be built.
    pub fn new(variant: &'a Variant, start: Option<&ClothState>) -> anyhow::Result<Self> {
        let entry = variant.choice.entry;
        let mut run = crate::Run::new(
            variant.scene.clone(),
            Registry::new().with(entry),
            Some(entry.name()),
        )
        .with_context(|| format!("variant {}", variant.title))?;
        run.set_recording(false);
        if let Some(start) = start {
            run.start_from(start.clone(), 0, 0.0);
        }
        Ok(Self {
            variant,
            inner: run,
            frames: 0,
            diverged: None,
            failed: None,
        })
    }

    /// The state at the end of the last frame stepped (the last good one after a divergence).
    pub fn state(&self) -> &ClothState {
        &self.inner.state
    }

    /// Whether the run has stopped (diverged or failed).
    pub fn stopped(&self) -> bool {
        self.diverged.is_some() || self.failed.is_some()
    }

    /// Takes in how frame `frame` of `frames` went, once stepped: a divergence or a failed
    /// step stops the run at the last good state.
    fn settle(&mut self, frame: u64, frames: u64) {
        if self.stopped() {
            return;
        }
        match self.inner.fault.clone() {
            None => self.frames = frame,
            Some(crate::Fault {
                cause: crate::Cause::Diverged(d),
                ..
            }) => self.diverged = Some((frame, d)),
            Some(fault) => {
                let scene = &self.variant.scene;
                let e = headless::fault_error(
                    scene,
                    &scene.params,
                    self.variant.choice.entry.is_explicit(),
                    (frame, frames),
                    &fault,
                );
                self.failed = Some(format!("{e:#}"));
            }
        }
    }

    /// Why the run stopped, in one sentence with its advice, when it did.
    pub fn reason(&self) -> Option<String> {
        if let Some(f) = &self.failed {
            return Some(f.clone());
        }
        self.diverged.as_ref().map(|(frame, d)| {
            let scene = &self.variant.scene;
            format!(
                "diverged at frame {frame} (t = {:.3} s): {}; {}",
                *frame as f64 / scene.params.frames_per_sec,
                d.describe(),
                crate::headless::divergence_advice(
                    scene,
                    &scene.params,
                    &self.variant.choice.entry,
                    d
                )
            )
        })
    }

    /// The summary of the current state.
    pub fn summary(&self) -> Summary {
        summarise(self.variant, &self.inner.state, self.reason())
    }
}

/// The summary of `variant` at `state`.
pub fn summarise(variant: &Variant, state: &ClothState, diverged: Option<String>) -> Summary {
    let mesh = &variant.scene.mesh;
    let centre = mesh.index(mesh.nw() / 2, mesh.nh() / 2);
    let params = &variant.scene.params;
    Summary {
        centre_height: state.positions.get(centre).map_or(f64::NAN, |p| p.y),
        lowest_height: state
            .positions
            .iter()
            .map(|p| p.y)
            .fold(f64::INFINITY, f64::min),
        max_stretch: max_stretch_ratio(mesh, state),
        kinetic_energy: kinetic_energy(state, mesh.point_mass(params.density), params.dt()),
        diverged,
    }
}

/// Steps every run that has not stopped through frame `frame` of `frames` in lockstep, on up
/// to `threads` threads (see [`crate::lockstep::advance`], the live UI's), then counts the
/// steps on `progress`.
pub fn advance_all(
    runs: &mut [Run<'_>],
    frame: u64,
    frames: u64,
    threads: usize,
    progress: &mut Progress,
) {
    let mut live: Vec<&mut crate::Run> = (runs.iter_mut())
        .filter(|r| !r.stopped())
        .map(|r| &mut r.inner)
        .collect();
    crate::lockstep::advance(&mut live, frame, threads, &|_| false);
    for run in runs.iter_mut() {
        run.settle(frame, frames);
    }
    for run in runs.iter() {
        for _ in 0..run.variant.scene.params.steps_per_frame {
            progress.step();
        }
    }
}

/// Threads for `n` variants: one per variant, at most one per core.
pub fn threads_for(n: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
    n.min(cores).max(1)
}

/// The summary table: a header, then a line per variant.
pub fn table(variants: &[Variant], summaries: &[Summary]) -> String {
    let width = variants
        .iter()
        .map(|v| v.title.chars().count())
        .max()
        .unwrap_or(0)
        .max("variant".len());
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:width$}  {:>16}  {:>16}  {:>11}  {:>16}  diverged",
        "variant", "centre height m", "lowest height m", "max stretch", "kinetic energy J"
    );
    for (v, m) in variants.iter().zip(summaries) {
        if m.diverged.is_some() {
            // NOTE: the guard needs a few frames to tell a blow-up, so the last frame it let
            // through may already hold absurd numbers: none are shown.
            let _ = writeln!(
                s,
                "{:width$}  {:>16}  {:>16}  {:>11}  {:>16}  yes",
                v.title, "-", "-", "-", "-"
            );
        } else {
            let _ = writeln!(
                s,
                "{:width$}  {:>16.6}  {:>16.6}  {:>11.4}  {:>16.4e}  no",
                v.title, m.centre_height, m.lowest_height, m.max_stretch, m.kinetic_energy,
            );
        }
    }
    s
}

/// The summary as JSON: a list of objects with the keys `variant` (the values by key),
/// `centre_height`, `lowest_height`, `max_stretch`, `kinetic_energy` and `diverged`; the
/// numbers of a diverged variant are `null`.
pub fn json(variants: &[Variant], summaries: &[Summary]) -> Value {
    Value::Array(
        variants
            .iter()
            .zip(summaries)
            .map(|(v, m)| {
                let shown = |x: f64| {
                    if m.diverged.is_some() {
                        Value::Null
                    } else {
                        Value::from(x)
                    }
                };
                serde_json::json!({
                    "variant": v.values_json(),
                    "centre_height": shown(m.centre_height),
                    "lowest_height": shown(m.lowest_height),
                    "max_stretch": shown(m.max_stretch),
                    "kinetic_energy": shown(m.kinetic_energy),
                    "diverged": m.diverged.is_some(),
                })
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_split_at_commas_outside_brackets_and_quotes() {
        let a: Axis = "simulation.gravity=[0,-9.8,0], [0,-1.6,0]".parse().unwrap();
        assert_eq!(a.key, "simulation.gravity");
        assert_eq!(a.values, vec!["[0,-9.8,0]", "[0,-1.6,0]"]);
        let a: Axis = r#"x.y="a,b",c"#.parse().unwrap();
        assert_eq!(a.values, vec![r#""a,b""#, "c"]);
        assert_eq!(a.short_key(), "y");
    }

    #[test]
    fn an_axis_needs_two_to_six_distinct_values_and_a_dotted_key() {
        for bad in [
            "cloth.ks",
            "cloth.ks=1",
            "cloth.ks=1,2,3,4,5,6,7",
            "cloth.ks=1,,2",
            "cloth.ks=1,1",
            "=1,2",
            "cloth..ks=1,2",
        ] {
            assert!(bad.parse::<Axis>().is_err(), "{bad} is refused");
        }
        let e = "cloth.ks=1".parse::<Axis>().unwrap_err();
        assert!(e.contains("2 to 6 values"), "{e}");
    }

    #[test]
    fn variants_of_one_grid_hold_one_mesh_and_other_grids_their_own() {
        let registry = solvers::default_registry();
        let axes: Vec<Axis> = ["cloth.ks=1,5000", "cloth.width=1,2"]
            .iter()
            .map(|a| a.parse().unwrap())
            .collect();
        let vs = variants(&registry, "pinned2", &[], None, &axes).unwrap();
        // The first axis varies fastest: [ks=1 w=1, ks=5000 w=1, ks=1 w=2, ks=5000 w=2].
        let same =
            |a: usize, b: usize| std::sync::Arc::ptr_eq(&vs[a].scene.mesh, &vs[b].scene.mesh);
        assert!(same(0, 1) && same(2, 3), "a stiffness changes no grid");
        assert!(!same(0, 2), "a width is another grid");
        assert_ne!(vs[0].scene.mesh.spec(), vs[2].scene.mesh.spec());
    }

    #[test]
    fn two_axes_make_a_grid_with_the_first_across() {
        let registry = solvers::default_registry();
        let axes: Vec<Axis> = ["cloth.ks=1,5000", "cloth.density=1,15,1000"]
            .iter()
            .map(|a| a.parse().unwrap())
            .collect();
        let vs = variants(&registry, "pinned2", &[], None, &axes).unwrap();
        let titles: Vec<&str> = vs.iter().map(|v| v.title.as_str()).collect();
        assert_eq!(
            titles,
            [
                "ks=1 density=1",
                "ks=5000 density=1",
                "ks=1 density=15",
                "ks=5000 density=15",
                "ks=1 density=1000",
                "ks=5000 density=1000"
            ]
        );
        assert_eq!(vs[3].scene.params.ks, 5000.0);
        assert_eq!(vs[3].scene.params.density, 15.0);
        assert_eq!(vs[3].file_label(), "ks=5000.density=15");
        let twice = [axes[0].clone(), axes[0].clone()];
        assert!(variants(&registry, "pinned2", &[], None, &twice).is_err());
        let set = ["cloth.ks=3".to_owned()];
        let e = variants(&registry, "pinned2", &set, None, &axes)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("--set cloth.ks=3 and --vary cloth.ks"), "{e}");
    }

    #[test]
    fn a_bad_value_is_refused_naming_the_variant_and_the_key() {
        let registry = solvers::default_registry();
        let axes = ["cloth.ks=5000,-3".parse().unwrap()];
        let e = variants(&registry, "pinned2", &[], None, &axes)
            .err()
            .map(|e| format!("{e:#}"))
            .unwrap_or_default();
        assert!(e.contains("ks=-3") && e.contains("cloth.ks"), "{e}");
    }
}
