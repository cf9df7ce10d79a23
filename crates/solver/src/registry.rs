//! Solvers by name: the entries a binary offers its users, and their options.
//!
//! A solver crate offers each of its solvers through a [`SolverEntry`]: a name as typed on the
//! command line and in scene files, a one-line description, the steps per frame it is meant to
//! run at, the options it takes (each with its kind, range and default) and a constructor from
//! the mesh and an options object. A binary assembles a [`Registry`] of entries from the crates
//! it links (rustup's toolchains, cargo's subcommands: a name is a string checked against what
//! is installed), and everything that lists or checks solver names reads it.
//!
//! Options travel as a JSON object (`{"iterations": 20}`), the same in a scene file's
//! `simulation.solver_options` as anywhere else. [`SolverEntry::build`] checks them against the
//! entry's list before the constructor sees them, so an unknown key, a wrong type or a value
//! out of range is an [`OptionError`] naming the solver, the key and what is allowed.

use cloth_mesh::ClothMesh;
use serde_json::{Map, Value};

use crate::Solver;

/// What values one solver option takes, and its default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OptionKind {
    /// An integer from `min` to `max`, inclusive.
    Integer {
        /// Smallest allowed value.
        min: i64,
        /// Largest allowed value.
        max: i64,
        /// The value when the option is not given.
        default: i64,
    },
    /// A finite number from `min` to `max`, inclusive.
    Number {
        /// Smallest allowed value.
        min: f64,
        /// Largest allowed value.
        max: f64,
        /// The value when the option is not given.
        default: f64,
    },
    /// One of a few names.
    Choice {
        /// The allowed names.
        choices: &'static [&'static str],
        /// The name when the option is not given.
        default: &'static str,
    },
}

/// One option of a solver: its key in the options object, what it does, what it takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverOption {
    /// The key, as written in the options object (`iterations`).
    pub name: &'static str,
    /// What it does, one line, with its unit when it has one.
    pub description: &'static str,
    /// Its values and default.
    pub kind: OptionKind,
}

impl SolverOption {
    /// What the option allows, as a phrase for messages and listings
    /// (`an integer from 1 to 1000`).
    #[must_use]
    pub fn allowed(&self) -> String {
        match self.kind {
            OptionKind::Integer { min, max, .. } => format!("an integer from {min} to {max}"),
            OptionKind::Number { min, max, .. } => format!("a number from {min} to {max}"),
            OptionKind::Choice { choices, .. } => format!("one of {}", quoted(choices)),
        }
    }

    /// The default, as JSON.
    #[must_use]
    pub fn default_value(&self) -> Value {
        match self.kind {
            OptionKind::Integer { default, .. } => Value::from(default),
            OptionKind::Number { default, .. } => Value::from(default),
            OptionKind::Choice { default, .. } => Value::from(default),
        }
    }

    /// The option's numeric range and default, `(min, max, default)`, when it is a number or an
    /// integer (the options a user interface can offer as a numeric row).
    #[must_use]
    pub fn numeric(&self) -> Option<(f64, f64, f64)> {
        match self.kind {
            OptionKind::Integer { min, max, default } => {
                Some((min as f64, max as f64, default as f64))
            }
            OptionKind::Number { min, max, default } => Some((min, max, default)),
            OptionKind::Choice { .. } => None,
        }
    }

    /// Checks `value` for this option.
    fn check(&self, solver: &'static str, value: &Value) -> Result<(), OptionError> {
        let ok = match self.kind {
            OptionKind::Integer { min, max, .. } => value
                .as_i64()
                .or_else(|| {
                    // `10.0` is written by tools that know only floats; accept it as 10.
                    value
                        .as_f64()
                        .filter(|v| v.fract() == 0.0 && v.abs() < 9.0e15)
                        .map(|v| v as i64)
                })
                .is_some_and(|v| (min..=max).contains(&v)),
            OptionKind::Number { min, max, .. } => value
                .as_f64()
                .is_some_and(|v| v.is_finite() && (min..=max).contains(&v)),
            OptionKind::Choice { choices, .. } => {
                value.as_str().is_some_and(|v| choices.contains(&v))
            }
        };
        if ok {
            Ok(())
        } else {
            Err(OptionError::Invalid {
                solver,
                key: self.name.to_owned(),
                value: value.to_string(),
                allowed: self.allowed(),
            })
        }
    }
}

/// Builds a solver for a mesh from its checked options (see [`SolverEntry::build`]).
pub type BuildSolver = fn(&ClothMesh, &Value) -> Result<Box<dyn Solver>, OptionError>;

/// The bytes a solver allocates for a mesh with its checked options (see
/// [`SolverEntry::memory_estimate`]).
pub type EstimateMemory = fn(&ClothMesh, &Value) -> u64;

/// The estimate of an entry that states none: eight arrays of a position per point (the state
/// itself is not counted) and two words per spring, about what an explicit solver with scratch
/// copies of the positions and a self-collision hash keeps.
///
/// ```
/// let mesh = cloth_solver::ClothMesh::new(&cloth_mesh::GridSpec::default())
///     .map_err(|e| e.to_string())?;
/// let bytes = cloth_solver::default_memory_estimate(&mesh);
/// assert_eq!(bytes, 8 * 24 * 2500 + 16 * mesh.springs().len() as u64);
/// # Ok::<(), String>(())
/// ```
#[must_use]
pub fn default_memory_estimate(mesh: &ClothMesh) -> u64 {
    let point = 8 * std::mem::size_of::<crate::Vec3>() as u64;
    (mesh.len() as u64)
        .saturating_mul(point)
        .saturating_add((mesh.springs().len() as u64).saturating_mul(16))
}

/// How a solver is offered to users: a name, a description, its options, a constructor and
/// (optionally) the memory it needs.
///
/// Entries are `const`-built, so a solver crate can publish one per solver as an associated
/// constant:
///
/// ```
/// use cloth_solver::{
///     ClothMesh, OptionError, OptionKind, Solver, SolverEntry, SolverOption, Verlet,
/// };
/// use serde_json::Value;
///
/// fn build(_mesh: &ClothMesh, options: &Value) -> Result<Box<dyn Solver>, OptionError> {
///     let threads = MINE.integer(options, "threads")?;
///     let verlet = Verlet::new()
///         .with_threads(threads as usize)
///         .map_err(|e| OptionError::Failed { solver: "mine", reason: e.to_string() })?;
///     Ok(Box::new(verlet))
/// }
///
/// const MINE: SolverEntry = SolverEntry::new("mine", "Verlet on a few threads", build)
///     .with_steps_per_frame(30)
///     .with_options(&[SolverOption {
///         name: "threads",
///         description: "worker threads",
///         kind: OptionKind::Integer { min: 1, max: 8, default: 2 },
///     }]);
///
/// let mesh = ClothMesh::new(&cloth_mesh::GridSpec::default()).map_err(|e| e.to_string())?;
/// let solver = MINE.build(&mesh, &serde_json::json!({"threads": 3}));
/// assert!(solver.is_ok());
/// let e = MINE.build(&mesh, &serde_json::json!({"threads": 0})).err();
/// assert_eq!(
///     e.map(|e| e.to_string()).as_deref(),
///     Some("the mine solver's option threads is 0, but it must be an integer from 1 to 8")
/// );
/// # Ok::<(), String>(())
/// ```
#[derive(Debug, Clone, Copy)]
pub struct SolverEntry {
    name: &'static str,
    description: &'static str,
    steps_per_frame: u32,
    options: &'static [SolverOption],
    explicit: bool,
    build: BuildSolver,
    memory: Option<EstimateMemory>,
}

impl SolverEntry {
    /// An entry named `name` (lowercase, as typed on the command line), described in one line,
    /// built by `build`; it has no options and is meant for the course's 30 steps per frame
    /// until the `with_` methods say otherwise.
    #[must_use]
    pub const fn new(name: &'static str, description: &'static str, build: BuildSolver) -> Self {
        Self {
            name,
            description,
            steps_per_frame: crate::REFERENCE_STEPS_PER_FRAME,
            options: &[],
            explicit: false,
            build,
            memory: None,
        }
    }

    /// Sets how the solver states the bytes it allocates for a mesh (see
    /// [`SolverEntry::memory_estimate`]).
    #[must_use]
    pub const fn with_memory_estimate(mut self, estimate: EstimateMemory) -> Self {
        self.memory = Some(estimate);
        self
    }

    /// Sets the steps per frame the solver is meant to run at (at least 1), which tests and
    /// the user interface offer when switching to it.
    #[must_use]
    pub const fn with_steps_per_frame(mut self, steps: u32) -> Self {
        self.steps_per_frame = if steps == 0 { 1 } else { steps };
        self
    }

    /// Sets the options the solver takes.
    #[must_use]
    pub const fn with_options(mut self, options: &'static [SolverOption]) -> Self {
        self.options = options;
        self
    }

    /// Marks the solver as explicit: it is stable only below
    /// [`StepParams::explicit_ks_limit`](crate::StepParams::explicit_ks_limit), and a user
    /// interface may warn past it.
    #[must_use]
    pub const fn explicit(mut self) -> Self {
        self.explicit = true;
        self
    }

    /// The name, as typed on the command line and in scene files.
    #[must_use]
    pub const fn name(&self) -> &'static str {
        self.name
    }

    /// A one-line description.
    #[must_use]
    pub const fn description(&self) -> &'static str {
        self.description
    }

    /// The steps per frame the solver is meant to run at.
    #[must_use]
    pub const fn steps_per_frame(&self) -> u32 {
        self.steps_per_frame
    }

    /// The options the solver takes.
    #[must_use]
    pub const fn options(&self) -> &'static [SolverOption] {
        self.options
    }

    /// Whether the solver is explicit, bound by the explicit stability limit.
    #[must_use]
    pub const fn is_explicit(&self) -> bool {
        self.explicit
    }

    /// The bytes the solver will allocate for `mesh` with `options` (its scratch and caches;
    /// the cloth's state is the caller's), so that a caller can refuse a mesh too large for
    /// the memory it has before anything is allocated. From the entry's own estimate
    /// ([`SolverEntry::with_memory_estimate`]), or [`default_memory_estimate`] for an entry
    /// that states none.
    #[must_use]
    pub fn memory_estimate(&self, mesh: &ClothMesh, options: &Value) -> u64 {
        match self.memory {
            Some(estimate) => estimate(mesh, options),
            None => default_memory_estimate(mesh),
        }
    }

    /// The option called `key`, if the solver has one.
    #[must_use]
    pub fn option(&self, key: &str) -> Option<&'static SolverOption> {
        self.options.iter().find(|o| o.name == key)
    }

    /// Checks `options`: a JSON object (or `null`, meaning none) whose keys are this solver's
    /// options, each with an allowed value.
    ///
    /// # Errors
    /// [`OptionError`] naming the solver, the first bad key and what is allowed.
    pub fn check(&self, options: &Value) -> Result<(), OptionError> {
        for (key, value) in self.object(options)? {
            let Some(option) = self.option(key) else {
                return Err(OptionError::Unknown {
                    solver: self.name,
                    key: key.clone(),
                    allowed: if self.options.is_empty() {
                        "none: it takes no options".to_owned()
                    } else {
                        self.options
                            .iter()
                            .map(|o| o.name)
                            .collect::<Vec<_>>()
                            .join(", ")
                    },
                });
            };
            option.check(self.name, value)?;
        }
        Ok(())
    }

    /// Checks `options` (see [`SolverEntry::check`]) and builds the solver for `mesh`.
    ///
    /// # Errors
    /// [`OptionError`] when an option is bad or the solver cannot be built with it.
    pub fn build(&self, mesh: &ClothMesh, options: &Value) -> Result<Box<dyn Solver>, OptionError> {
        self.check(options)?;
        (self.build)(mesh, options)
    }

    /// The integer option `key` from `options`, or its default when absent.
    ///
    /// # Errors
    /// [`OptionError`] when the solver has no integer option `key` or the value is not allowed.
    pub fn integer(&self, options: &Value, key: &str) -> Result<i64, OptionError> {
        self.read(options, key, "an integer", |kind, v| match kind {
            OptionKind::Integer { default, .. } => Some(v.map_or(default, |v| {
                v.as_i64()
                    .or_else(|| v.as_f64().map(|f| f as i64))
                    .unwrap_or(default)
            })),
            _ => None,
        })
    }

    /// The number option `key` from `options`, or its default when absent.
    ///
    /// # Errors
    /// [`OptionError`] when the solver has no number option `key` or the value is not allowed.
    pub fn number(&self, options: &Value, key: &str) -> Result<f64, OptionError> {
        self.read(options, key, "a number", |kind, v| match kind {
            OptionKind::Number { default, .. } => {
                Some(v.and_then(Value::as_f64).unwrap_or(default))
            }
            _ => None,
        })
    }

    /// The choice option `key` from `options`, or its default when absent.
    ///
    /// # Errors
    /// [`OptionError`] when the solver has no choice option `key` or the value is not allowed.
    pub fn choice(&self, options: &Value, key: &str) -> Result<&'static str, OptionError> {
        self.read(options, key, "a choice", |kind, v| match kind {
            OptionKind::Choice { choices, default } => Some(
                (choices.iter().copied())
                    .find(|c| v.and_then(Value::as_str) == Some(*c))
                    .unwrap_or(default),
            ),
            _ => None,
        })
    }

    /// Option `key` (`what`: its kind, for the error) from `options`, checked, as `pick` reads
    /// it from the option's kind and the value given (`None`: absent); `pick` answers `None`
    /// when the option is of another kind.
    fn read<T>(
        &self,
        options: &Value,
        key: &str,
        what: &'static str,
        pick: impl Fn(OptionKind, Option<&Value>) -> Option<T>,
    ) -> Result<T, OptionError> {
        let not_declared = || self.not_declared(key, what);
        let option = self.option(key).ok_or_else(not_declared)?;
        pick(option.kind, None).ok_or_else(not_declared)?;
        let value = self.object(options)?.get(key).filter(|v| !v.is_null());
        if let Some(v) = value {
            option.check(self.name, v)?;
        }
        pick(option.kind, value).ok_or_else(not_declared)
    }

    fn not_declared(&self, key: &str, what: &'static str) -> OptionError {
        OptionError::Failed {
            solver: self.name,
            reason: format!(
                "its constructor reads {what} option {key:?}, which its entry does not declare as such"
            ),
        }
    }

    fn object<'a>(&self, options: &'a Value) -> Result<&'a Map<String, Value>, OptionError> {
        static EMPTY: std::sync::OnceLock<Map<String, Value>> = std::sync::OnceLock::new();
        match options {
            Value::Object(map) => Ok(map),
            Value::Null => Ok(EMPTY.get_or_init(Map::new)),
            other => Err(OptionError::NotAnObject {
                solver: self.name,
                value: other.to_string(),
            }),
        }
    }
}

/// Why a solver's options were refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum OptionError {
    /// The options are not a JSON object.
    #[error(
        "the options of the {solver} solver must be a JSON object such as {{\"key\": value}}, not {value}"
    )]
    NotAnObject {
        /// The solver.
        solver: &'static str,
        /// The value given, as JSON.
        value: String,
    },
    /// A key the solver does not take.
    #[error("the {solver} solver has no option {key:?}; its options: {allowed}")]
    Unknown {
        /// The solver.
        solver: &'static str,
        /// The unknown key.
        key: String,
        /// The keys it takes, comma-separated.
        allowed: String,
    },
    /// A value of the wrong type or out of range.
    #[error("the {solver} solver's option {key} is {value}, but it must be {allowed}")]
    Invalid {
        /// The solver.
        solver: &'static str,
        /// The key.
        key: String,
        /// The value given, as JSON.
        value: String,
        /// What is allowed.
        allowed: String,
    },
    /// The options are valid but the solver cannot be built with them.
    #[error("the {solver} solver cannot be built: {reason}")]
    Failed {
        /// The solver.
        solver: &'static str,
        /// Why.
        reason: String,
    },
}

impl OptionError {
    /// The option's key, when the error is about one key.
    #[must_use]
    pub fn key(&self) -> Option<&str> {
        match self {
            OptionError::Unknown { key, .. } | OptionError::Invalid { key, .. } => Some(key),
            OptionError::NotAnObject { .. } | OptionError::Failed { .. } => None,
        }
    }
}

/// The solvers a binary offers, by name, in menu order.
///
/// The first entry is the default solver (of a scene that names none). Registering a name that
/// is already there replaces that entry in its place, so a binary can put its own
/// implementation behind a built-in name.
#[derive(Debug, Clone, Default)]
pub struct Registry {
    entries: Vec<SolverEntry>,
}

impl Registry {
    /// An empty registry.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds `entry` at the end, or in place of the entry of the same name.
    pub fn register(&mut self, entry: SolverEntry) -> &mut Self {
        match self.entries.iter_mut().find(|e| e.name == entry.name) {
            Some(old) => *old = entry,
            None => self.entries.push(entry),
        }
        self
    }

    /// `self` with `entry` registered (see [`Registry::register`]).
    #[must_use]
    pub fn with(mut self, entry: SolverEntry) -> Self {
        self.register(entry);
        self
    }

    /// The entries, in menu order.
    #[must_use]
    pub fn entries(&self) -> &[SolverEntry] {
        &self.entries
    }

    /// The registered names, in menu order.
    pub fn names(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.entries.iter().map(|e| e.name)
    }

    /// The default solver: the first registered.
    #[must_use]
    pub fn default_entry(&self) -> Option<&SolverEntry> {
        self.entries.first()
    }

    /// The entry called `name` (ASCII case ignored).
    ///
    /// # Errors
    /// [`UnknownSolver`] listing the registered names.
    pub fn get(&self, name: &str) -> Result<&SolverEntry, UnknownSolver> {
        self.entries
            .iter()
            .find(|e| e.name.eq_ignore_ascii_case(name))
            .ok_or_else(|| UnknownSolver {
                name: name.to_owned(),
                available: self.entries.iter().map(|e| e.name).collect(),
            })
    }
}

/// A solver name that no registered entry has.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown solver {name:?}; the solvers are: {}", available.join(", "))]
pub struct UnknownSolver {
    /// The name asked for.
    pub name: String,
    /// The registered names, in menu order.
    pub available: Vec<&'static str>,
}

fn quoted(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("{n:?}"))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Verlet;
    use serde_json::json;

    fn mesh() -> ClothMesh {
        ClothMesh::new(&cloth_mesh::GridSpec::default()).unwrap()
    }

    #[allow(
        clippy::unnecessary_wraps,
        reason = "the constructor signature of every entry"
    )]
    fn plain(_: &ClothMesh, _: &Value) -> Result<Box<dyn Solver>, OptionError> {
        Ok(Box::new(Verlet::new()))
    }

    const OPTIONS: &[SolverOption] = &[
        SolverOption {
            name: "iterations",
            description: "inner iterations",
            kind: OptionKind::Integer {
                min: 1,
                max: 1000,
                default: 10,
            },
        },
        SolverOption {
            name: "tolerance",
            description: "metres",
            kind: OptionKind::Number {
                min: 0.0,
                max: 0.5,
                default: 1e-6,
            },
        },
        SolverOption {
            name: "order",
            description: "sweep order",
            kind: OptionKind::Choice {
                choices: &["faithful", "colored"],
                default: "faithful",
            },
        },
    ];

    const ENTRY: SolverEntry = SolverEntry::new("demo", "a demo", plain)
        .with_steps_per_frame(0)
        .with_options(OPTIONS);

    #[test]
    fn absent_options_take_their_defaults() {
        for none in [json!({}), Value::Null] {
            assert_eq!(ENTRY.integer(&none, "iterations"), Ok(10));
            assert_eq!(ENTRY.number(&none, "tolerance"), Ok(1e-6));
            assert_eq!(ENTRY.choice(&none, "order"), Ok("faithful"));
        }
        let defaults: Vec<(&str, Value)> = (ENTRY.options().iter())
            .map(|o| (o.name, o.default_value()))
            .collect();
        assert_eq!(
            defaults,
            [
                ("iterations", json!(10)),
                ("tolerance", json!(1e-6)),
                ("order", json!("faithful"))
            ]
        );
        // Zero steps per frame would be no time step at all: the entry keeps at least one.
        assert_eq!(ENTRY.steps_per_frame(), 1);
    }

    #[test]
    fn given_options_are_read_back() {
        let o = json!({"iterations": 3, "tolerance": 0.25, "order": "colored"});
        assert!(ENTRY.check(&o).is_ok());
        assert_eq!(ENTRY.integer(&o, "iterations"), Ok(3));
        assert_eq!(
            ENTRY.integer(&json!({"iterations": 4.0}), "iterations"),
            Ok(4)
        );
        assert_eq!(ENTRY.number(&o, "tolerance"), Ok(0.25));
        assert_eq!(ENTRY.choice(&o, "order"), Ok("colored"));
    }

    #[test]
    fn an_unknown_key_names_the_solver_the_key_and_the_keys_it_takes() {
        let e = ENTRY.build(&mesh(), &json!({"bogus": 1})).err();
        assert_eq!(
            e.map(|e| e.to_string()).as_deref(),
            Some(
                "the demo solver has no option \"bogus\"; its options: iterations, tolerance, order"
            )
        );
        let bare = SolverEntry::new("bare", "no options", plain);
        let e = bare.check(&json!({"iterations": 2})).unwrap_err();
        assert_eq!(
            e.to_string(),
            "the bare solver has no option \"iterations\"; its options: none: it takes no options"
        );
        assert_eq!(e.key(), Some("iterations"));
    }

    #[test]
    fn values_out_of_range_or_of_the_wrong_type_are_refused_with_what_is_allowed() {
        for (options, message) in [
            (
                json!({"iterations": 0}),
                "the demo solver's option iterations is 0, but it must be an integer from 1 to 1000",
            ),
            (
                json!({"iterations": 2.5}),
                "the demo solver's option iterations is 2.5, but it must be an integer from 1 to 1000",
            ),
            (
                json!({"iterations": "ten"}),
                "the demo solver's option iterations is \"ten\", but it must be an integer from 1 to 1000",
            ),
            (
                json!({"tolerance": -1}),
                "the demo solver's option tolerance is -1, but it must be a number from 0 to 0.5",
            ),
            (
                json!({"order": "random"}),
                "the demo solver's option order is \"random\", but it must be one of \"faithful\", \"colored\"",
            ),
            (
                json!([1, 2]),
                "the options of the demo solver must be a JSON object such as {\"key\": value}, not [1,2]",
            ),
        ] {
            let e = ENTRY.check(&options).unwrap_err();
            assert_eq!(e.to_string(), message);
            assert!(ENTRY.build(&mesh(), &options).is_err());
        }
    }

    #[test]
    fn a_constructor_reading_an_undeclared_option_fails_rather_than_guessing() {
        let e = ENTRY.integer(&json!({}), "tolerance").unwrap_err();
        assert!(
            matches!(e, OptionError::Failed { solver: "demo", .. }),
            "{e}"
        );
        assert!(ENTRY.number(&json!({}), "missing").is_err());
    }

    #[test]
    fn the_registry_finds_entries_by_name_and_lists_them_when_it_cannot() {
        let other = SolverEntry::new("other", "another", plain);
        let reg = Registry::new().with(ENTRY).with(other);
        assert_eq!(reg.names().collect::<Vec<_>>(), ["demo", "other"]);
        assert_eq!(reg.default_entry().map(SolverEntry::name), Some("demo"));
        assert_eq!(reg.get("OTHER").map(SolverEntry::name), Ok("other"));
        let e = reg.get("rk4").unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown solver \"rk4\"; the solvers are: demo, other"
        );
    }

    #[test]
    fn an_entry_states_its_memory_or_takes_the_default() {
        fn per_point(mesh: &ClothMesh, options: &Value) -> u64 {
            let bytes = options["bytes_per_point"].as_u64().unwrap_or(1);
            bytes * mesh.len() as u64
        }
        let mesh = mesh();
        assert_eq!(
            ENTRY.memory_estimate(&mesh, &Value::Null),
            default_memory_estimate(&mesh)
        );
        let stated = SolverEntry::new("stated", "states it", plain).with_memory_estimate(per_point);
        assert_eq!(
            stated.memory_estimate(&mesh, &json!({"bytes_per_point": 100})),
            100 * 2500
        );
    }

    #[test]
    fn registering_a_taken_name_replaces_that_entry_in_place() {
        let again = SolverEntry::new("demo", "replacement", plain);
        let reg = Registry::new()
            .with(ENTRY)
            .with(SolverEntry::new("other", "another", plain))
            .with(again);
        assert_eq!(reg.entries().len(), 2);
        assert_eq!(reg.entries()[0].description(), "replacement");
    }
}
