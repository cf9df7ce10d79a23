//! From JSON text to a ready-to-run scene, with every range checked.

use std::path::Path;

use cloth_mesh::{
    ClothMesh, Collider, GridSpec, MeshError, Orientation, Plane, Sphere, StepParams, Vec3, Wind,
};
use serde_json::{Map, Value};

use std::sync::Arc;

use crate::number::show;
use crate::{SceneError, SceneFile, SimulationBlock, apply_set, bundled, read_scene_file};

/// A loaded scene: everything a run needs.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Where it came from: the bundled name or the file path, as used in messages.
    pub origin: String,
    /// The file as parsed (after `--set` overrides), kept so the scene can be saved back.
    pub file: SceneFile,
    /// The cloth's topology and start positions, shared: scenes built from one grid (the
    /// variants of a study that vary no grid key) can hold one mesh.
    pub mesh: Arc<ClothMesh>,
    /// Live parameters at load time.
    pub params: StepParams,
    /// Collision objects: the sphere, then the plane, when present.
    pub colliders: Vec<Collider>,
    /// The solver the scene asks for (`simulation.solver`), or `None` for the application's
    /// default. Not checked here: this crate knows no solvers; the application checks the name
    /// against the solvers it has, naming this scene and the key.
    pub solver: Option<String>,
    /// The options for that solver (`simulation.solver_options`; empty when absent), checked by
    /// the solver itself when it is built.
    pub solver_options: Map<String, Value>,
}

/// Scene keys that once spelled a solver option, and the option's name: each is refused with
/// the spelling that replaced it, `simulation.solver_options.OPTION`.
const RETIRED_KEYS: [(&str, &str); 3] = [
    ("iterations", "iterations"),
    ("threads", "threads"),
    ("constraint_order", "order"),
];

impl Scene {
    /// The options a run of the solver `name` gets from this scene, as a JSON object.
    ///
    /// `simulation.solver_options` belongs to the scene's own solver (the default one when the
    /// scene names none, whose name the caller passes as `default`), so another solver gets
    /// none of them.
    #[must_use]
    pub fn options_for(&self, name: &str, default: &str) -> Value {
        let own = self.solver.as_deref().unwrap_or(default);
        if own == name {
            Value::Object(self.solver_options.clone())
        } else {
            Value::Object(Map::new())
        }
    }

    /// Whether the scene (its file or a `--set`) gives `simulation.simulation_steps`; when it
    /// does not, a run takes its solver's recommended steps per frame.
    #[must_use]
    pub fn gives_steps(&self) -> bool {
        self.file
            .simulation
            .as_ref()
            .is_some_and(|s| s.simulation_steps.is_some())
    }

    /// Makes `solver` the scene's solver, with `options` (a JSON object) as its options: what
    /// a run chose on the command line becomes what the scene gives, so the live UI's
    /// "restore" and a saved scene keep it.
    pub fn set_solver(&mut self, solver: &str, options: Map<String, Value>) {
        self.solver = Some(solver.to_owned());
        self.solver_options = options;
    }

    /// The scene's file with `params`, `colliders`' friction, the solver `solver` and its
    /// `options` (a JSON object) written into it, so a run edited live can be saved and
    /// reloaded to the same state.
    #[must_use]
    pub fn to_file(
        &self,
        params: &StepParams,
        colliders: &[Collider],
        solver: &str,
        options: &Value,
    ) -> SceneFile {
        let mut f = self.file.clone();
        f.cloth.ks = params.ks;
        f.cloth.density = params.density;
        f.cloth.damping = params.damping;
        f.cloth.enable_structural = params.structural;
        f.cloth.enable_shearing = params.shearing;
        f.cloth.enable_bending = params.bending;
        for c in colliders {
            match c {
                Collider::Sphere(s) => {
                    if let Some(b) = f.sphere.as_mut() {
                        b.friction = s.friction;
                    }
                }
                Collider::Plane(p) => {
                    if let Some(b) = f.plane.as_mut() {
                        b.friction = p.friction;
                    }
                }
            }
        }
        let defaults = StepParams::default();
        let mut sim = f.simulation.take().unwrap_or_default();
        sim.frames_per_sec = Some(params.frames_per_sec);
        sim.simulation_steps = Some(u64::from(params.steps_per_frame));
        sim.gravity = Some([params.gravity.x, params.gravity.y, params.gravity.z]);
        sim.self_collision = Some(params.self_collision);
        sim.stretch_limit = (params.stretch_limit != defaults.stretch_limit
            || sim.stretch_limit.is_some())
        .then_some(params.stretch_limit);
        let (w, d) = (params.wind, defaults.wind);
        sim.wind = (w.velocity != d.velocity || sim.wind.is_some()).then_some([
            w.velocity.x,
            w.velocity.y,
            w.velocity.z,
        ]);
        sim.wind_drag = (w.drag != d.drag || sim.wind_drag.is_some()).then_some(w.drag);
        sim.wind_gust = (w.gust != d.gust || sim.wind_gust.is_some()).then_some(w.gust);
        sim.wind_gust_period = (w.gust_period != d.gust_period || sim.wind_gust_period.is_some())
            .then_some(w.gust_period);
        sim.solver = Some(solver.to_owned());
        let options = options.as_object().cloned().unwrap_or_default();
        sim.solver_options = (!options.is_empty()).then_some(options);
        f.simulation = Some(sim);
        f
    }
}

/// Whether `name_or_path` is written as a path: it names a folder (`./plane`) or ends in
/// `.json`. Anything else is a bare name.
fn is_explicit_path(name_or_path: &str) -> bool {
    Path::new(name_or_path)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
        || name_or_path.contains(std::path::MAIN_SEPARATOR)
        || name_or_path.contains('/')
}

/// Loads a scene by bundled name (`pinned4`) or file path, then applies `sets` overrides.
///
/// A path with a folder in it (`./plane`, `scenes/plane.json`) or ending in `.json` is always
/// a file. A bare name is the bundled scene of that name when there is one, even if a file of
/// that name is in the current folder (write `./plane` for the file; [`shadowing_file`] tells
/// when that happened); a bare name that is not bundled is read as a file. Files are read with
/// the checks of [`read_scene_file`]: regular files only, at most [`crate::MAX_SCENE_BYTES`].
///
/// # Errors
/// [`SceneError`] naming the file, key, value and what is allowed.
pub fn load(name_or_path: &str, sets: &[String]) -> Result<Scene, SceneError> {
    let path = Path::new(name_or_path);
    if !is_explicit_path(name_or_path) {
        if let Some(b) = bundled(name_or_path) {
            return parse(b.json, b.name, sets);
        }
        if std::fs::symlink_metadata(path).is_err() {
            return Err(SceneError::UnknownScene {
                name: name_or_path.to_owned(),
                available: crate::BUNDLED
                    .iter()
                    .map(|b| b.name)
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
    }
    let text = read_scene_file(path)?;
    parse(&text, name_or_path, sets)
}

/// The file that `name` would have named, when [`load`] reads the bundled scene `name` while a
/// file of that name is in the current folder: the path to type for the file (`./plane`).
#[must_use]
pub fn shadowing_file(name: &str) -> Option<String> {
    (!is_explicit_path(name) && bundled(name).is_some() && Path::new(name).exists())
        .then(|| format!("./{name}"))
}

/// Parses scene JSON `text`; `origin` names it in messages.
///
/// # Errors
/// [`SceneError`] naming the origin, key, value and what is allowed.
pub fn parse(text: &str, origin: &str, sets: &[String]) -> Result<Scene, SceneError> {
    // Some editors start UTF-8 files with a byte-order mark; it is not part of the JSON.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let file: SceneFile = if sets.is_empty() {
        // Straight from the text, so type errors keep their line and column.
        let de = &mut serde_json::Deserializer::from_str(text);
        let file = serde_path_to_error::deserialize(&mut *de).map_err(|e| {
            // A list where an object belongs would be read as the fields in order, with
            // errors that make no sense: said by its shape instead.
            serde_json::from_str::<Value>(text)
                .ok()
                .and_then(|v| shape_error(origin, &v))
                .unwrap_or_else(|| field_error(origin, e, Typed::Text(text)))
        })?;
        de.end().map_err(|e| syntax_error(origin, &e))?;
        file
    } else {
        let de = &mut serde_json::Deserializer::from_str(text);
        let mut value: Value = serde_path_to_error::deserialize(&mut *de)
            .map_err(|e| field_error(origin, e, Typed::Text(text)))?;
        de.end().map_err(|e| syntax_error(origin, &e))?;
        for s in sets {
            apply_set(&mut value, s)?;
        }
        if let Some(e) = shape_error(origin, &value) {
            return Err(e);
        }
        serde_path_to_error::deserialize(value)
            .map_err(|e| field_error(origin, e, Typed::Sets(sets)))?
    };
    build(file, origin)
}

fn syntax_error(origin: &str, e: &serde_json::Error) -> SceneError {
    let message = e.to_string();
    // serde_json appends " at line L column C"; we report those separately.
    let message = message
        .split(" at line ")
        .next()
        .unwrap_or(&message)
        .to_owned();
    SceneError::Syntax {
        origin: origin.to_owned(),
        line: e.line(),
        column: e.column(),
        message,
    }
}

/// Where the text of a value as typed can be found for a message: the scene's text (by the
/// error's line and column), or the `--set` arguments (by key).
#[derive(Clone, Copy)]
enum Typed<'a> {
    Text(&'a str),
    Sets(&'a [String]),
}

/// The blocks of a scene file, which must be objects.
const BLOCKS: [&str; 4] = ["cloth", "sphere", "plane", "simulation"];

/// An error for a scene whose top level or block is not an object (a list, a number): serde
/// would read a list as the fields in order and report nonsense about them.
fn shape_error(origin: &str, value: &Value) -> Option<SceneError> {
    let field = |key: &str, found: &Value, what: &str| SceneError::Field {
        origin: origin.to_owned(),
        key: key.to_owned(),
        message: format!("invalid type: {}, expected {what}", kind_of(found)),
        location: None,
    };
    let Some(top) = value.as_object() else {
        return Some(field(
            ".",
            value,
            "an object with the keys cloth and optionally sphere, plane, simulation and \
             description",
        ));
    };
    BLOCKS.iter().find_map(|&key| match top.get(key) {
        Some(v @ (Value::Array(_) | Value::Bool(_) | Value::Number(_) | Value::String(_))) => {
            Some(field(key, v, "an object"))
        }
        _ => None,
    })
}

/// A JSON value's kind in words.
fn kind_of(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "an object",
    }
}

/// The number typed at 1-based `line` and `column` of `text`: the run of number characters
/// that ends at or touches the column (where the parser stopped).
fn typed_at(text: &str, line: usize, column: usize) -> Option<String> {
    let chars: Vec<char> = text.lines().nth(line.checked_sub(1)?)?.chars().collect();
    let numberish = |c: char| c.is_ascii_digit() || matches!(c, '-' | '+' | '.' | 'e' | 'E');
    let mut end = column.min(chars.len());
    while end < chars.len() && numberish(chars[end]) {
        end += 1;
    }
    let mut start = end;
    while start > 0 && numberish(chars[start - 1]) {
        start -= 1;
    }
    (start < end).then(|| chars[start..end].iter().collect())
}

fn field_error(
    origin: &str,
    e: serde_path_to_error::Error<serde_json::Error>,
    typed: Typed<'_>,
) -> SceneError {
    let path = e.path().to_string();
    let inner = e.into_inner();
    let full = inner.to_string();
    let message = full.split(" at line ").next().unwrap_or(&full).to_owned();
    let located = matches!(typed, Typed::Text(_));
    let location = (located && inner.line() > 0).then(|| (inner.line(), inner.column()));
    // A number shown by the parser is its 64-bit float reading (18446744073709551616 becomes
    // 1.8446744073709552e+19): show it as typed.
    let as_typed = match typed {
        Typed::Text(text) => typed_at(text, inner.line(), inner.column()),
        Typed::Sets(sets) => sets.iter().rev().find_map(|s| {
            let (key, value) = s.split_once('=')?;
            (key.trim() == path).then(|| value.trim().to_owned())
        }),
    };
    let message = match (message.split_once('`'), as_typed) {
        (Some((before, rest)), Some(typed))
            if before.ends_with("floating point ") || before.ends_with("integer ") =>
        {
            let after = rest.split_once('`').map_or("", |(_, a)| a);
            format!("{before}`{typed}`{after}")
        }
        _ => message,
    };
    // A number too large for an f64 is found while its key is being read: name the key.
    if message == "number out of range" && path != "." {
        return SceneError::Field {
            origin: origin.to_owned(),
            key: path,
            message: "the number is out of range: a value's magnitude must be below about \
                      1.8e308 (the largest 64-bit float)"
                .to_owned(),
            location,
        };
    }
    if inner.is_syntax() || inner.is_eof() {
        return syntax_error(origin, &inner);
    }
    SceneError::Field {
        origin: origin.to_owned(),
        key: path,
        message: plain_types(&message),
        location,
    }
}

/// serde's type names in words a scene's author uses: no Rust type appears in a message.
pub(crate) fn plain_types(message: &str) -> String {
    let message = message
        .replace("expected f64", "expected a number")
        .replace(
            "expected u64",
            "expected a whole number from 0 to 18446744073709551615",
        )
        .replace("expected i64", "expected a whole number")
        .replace(
            "expected u32",
            "expected a whole number from 0 to 4294967295",
        )
        .replace("expected usize", "expected a whole number >= 0")
        .replace("expected u8", "expected a whole number from 0 to 255")
        .replace("expected a boolean", "expected true or false")
        .replace("invalid type: map", "invalid type: an object")
        .replace("invalid type: sequence", "invalid type: a list")
        .replace("expected a sequence", "expected a list")
        .replace("expected a map", "expected an object")
        .replace("unit value", "null");
    // `struct Name with N elements`, `enum Name`, `tuple struct Name`: a Rust type's name.
    let mut out = String::with_capacity(message.len());
    let mut rest = message.as_str();
    while let Some(i) = ["tuple struct ", "struct ", "enum "]
        .iter()
        .filter_map(|w| rest.find(w).map(|i| (i, *w)))
        .min()
        .map(|(i, w)| (i, w.len()))
    {
        let (at, skip) = i;
        out.push_str(&rest[..at]);
        let after = &rest[at + skip..];
        let name_end = after
            .find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(after.len());
        let mut tail = &after[name_end..];
        if let Some(t) = tail.strip_prefix(" with ") {
            let digits = t.find(|c: char| !c.is_ascii_digit()).unwrap_or(t.len());
            tail = t[digits..]
                .strip_prefix(" elements")
                .or_else(|| t[digits..].strip_prefix(" element"))
                .unwrap_or(tail);
        }
        out.push_str(if skip == "enum ".len() {
            "one of the allowed values"
        } else {
            "an object"
        });
        rest = tail;
    }
    out.push_str(rest);
    out.replace("::", " ")
}

/// `[x, y, z]` as typed (see [`show`]).
fn show3(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", show(v[0]), show(v[1]), show(v[2]))
}

struct Check<'a> {
    origin: &'a str,
}

impl Check<'_> {
    fn fail(&self, key: &str, value: impl std::fmt::Display, allowed: &str) -> SceneError {
        SceneError::Invalid {
            origin: self.origin.to_owned(),
            key: key.to_owned(),
            value: value.to_string(),
            allowed: allowed.to_owned(),
        }
    }

    fn range(
        &self,
        key: &str,
        v: f64,
        ok: impl Fn(f64) -> bool,
        allowed: &str,
    ) -> Result<f64, SceneError> {
        if v.is_finite() && ok(v) {
            Ok(v)
        } else {
            Err(self.fail(key, show(v), allowed))
        }
    }

    fn vec3(&self, key: &str, v: [f64; 3]) -> Result<Vec3, SceneError> {
        if v.iter().all(|c| c.is_finite()) {
            Ok(Vec3::new(v[0], v[1], v[2]))
        } else {
            Err(self.fail(key, show3(v), "three finite numbers"))
        }
    }
}

fn build(file: SceneFile, origin: &str) -> Result<Scene, SceneError> {
    let ck = Check { origin };
    let c = &file.cloth;
    let positive = |v: f64| v > 0.0;
    // The mesh's own bounds, checked here so the error names the scene's key.
    let extent = |v: f64| cloth_mesh::EXTENT_RANGE.contains(&v);
    let unit = |v: f64| (0.0..=1.0).contains(&v);
    ck.range(
        "cloth.width",
        c.width,
        extent,
        "a finite number from 1e-9 to 1e9 (metres)",
    )?;
    ck.range(
        "cloth.height",
        c.height,
        extent,
        "a finite number from 1e-9 to 1e9 (metres)",
    )?;
    ck.range(
        "cloth.thickness",
        c.thickness,
        extent,
        "a finite number from 1e-9 to 1e9 (metres)",
    )?;
    ck.range("cloth.ks", c.ks, |v| v >= 0.0, "a finite number >= 0 (N/m)")?;
    ck.range(
        "cloth.density",
        c.density,
        positive,
        "a finite number > 0 (kg/m^2)",
    )?;
    ck.range(
        "cloth.damping",
        c.damping,
        |v| (0.0..=100.0).contains(&v),
        "between 0 and 100 (percent)",
    )?;
    let orientation = match c.orientation {
        0 => Orientation::Horizontal,
        1 => Orientation::Vertical,
        o => return Err(ck.fail("cloth.orientation", o, "0 (horizontal) or 1 (vertical)")),
    };
    let grid_rule = format!(
        "an integer >= 2, with at most {} points in all",
        cloth_mesh::MAX_POINTS
    );
    let count = |key: &str, v: u64| -> Result<usize, SceneError> {
        if v < 2 || v > cloth_mesh::MAX_POINTS as u64 {
            Err(ck.fail(key, v, &grid_rule))
        } else {
            Ok(v as usize)
        }
    };
    let nw = count("cloth.num_width_points", c.num_width_points)?;
    let nh = count("cloth.num_height_points", c.num_height_points)?;
    if nw * nh > cloth_mesh::MAX_POINTS {
        return Err(ck.fail(
            "cloth.num_width_points * cloth.num_height_points",
            nw * nh,
            &grid_rule,
        ));
    }
    let mut pinned = Vec::new();
    for (i, &[x, y]) in c.pinned.iter().flatten().enumerate() {
        if x < 0 || y < 0 || x as u64 >= nw as u64 || y as u64 >= nh as u64 {
            return Err(ck.fail(
                &format!("cloth.pinned[{i}]"),
                format!("[{x}, {y}]"),
                &format!(
                    "[column, row] with column in 0..={} and row in 0..={}",
                    nw - 1,
                    nh - 1
                ),
            ));
        }
        pinned.push((x as usize, y as usize));
    }

    let sim = file.simulation.clone().unwrap_or_default();
    let SimulationBlock {
        frames_per_sec,
        simulation_steps,
        gravity,
        self_collision,
        stretch_limit,
        solver,
        solver_options,
        iterations,
        threads,
        constraint_order,
        wind,
        wind_drag,
        wind_gust,
        wind_gust_period,
        seed,
    } = sim;
    for ((key, option), given) in
        RETIRED_KEYS
            .iter()
            .zip([&iterations, &threads, &constraint_order])
    {
        if given.is_some() {
            return Err(SceneError::Field {
                origin: origin.to_owned(),
                key: format!("simulation.{key}"),
                message: format!(
                    "no longer a scene key; write simulation.solver_options.{option} (an option \
                     of the scene's solver; `clothsim solvers` lists each solver's options)"
                ),
                location: None,
            });
        }
    }
    let defaults = StepParams::default();
    let frames_per_sec = match frames_per_sec {
        Some(f) => ck.range(
            "simulation.frames_per_sec",
            f,
            |v| v > 0.0 && v <= 10_000.0,
            "a number > 0 and <= 10000",
        )?,
        None => defaults.frames_per_sec,
    };
    let steps_per_frame = match simulation_steps {
        Some(s) if (1..=10_000).contains(&s) => s as u32,
        Some(s) => {
            return Err(ck.fail(
                "simulation.simulation_steps",
                s,
                "an integer from 1 to 10000",
            ));
        }
        None => defaults.steps_per_frame,
    };
    let solver_options = solver_options.unwrap_or_default();
    let gravity = match gravity {
        Some(g) => ck.vec3("simulation.gravity", g)?,
        None => defaults.gravity,
    };
    let wind = {
        let d = defaults.wind;
        let velocity = match wind {
            Some(w) => {
                let v = ck.vec3("simulation.wind", w)?;
                if v.iter().any(|c| c.abs() > 1000.0) {
                    return Err(ck.fail(
                        "simulation.wind",
                        show3(w),
                        "three numbers from -1000 to 1000 (m/s)",
                    ));
                }
                v
            }
            None => d.velocity,
        };
        let number = |key: &str, v: Option<f64>, default: f64, lo: f64, hi: f64, allowed: &str| {
            v.map_or(Ok(default), |v| {
                ck.range(key, v, |v| (lo..=hi).contains(&v), allowed)
            })
        };
        Wind {
            velocity,
            drag: number(
                "simulation.wind_drag",
                wind_drag,
                d.drag,
                0.0,
                100.0,
                "from 0 to 100",
            )?,
            gust: number(
                "simulation.wind_gust",
                wind_gust,
                d.gust,
                0.0,
                10.0,
                "from 0 to 10 (a fraction of the wind)",
            )?,
            gust_period: number(
                "simulation.wind_gust_period",
                wind_gust_period,
                d.gust_period,
                0.01,
                1.0e6,
                "from 0.01 to 1000000 (s)",
            )?,
        }
    };
    let params = StepParams {
        ks: c.ks,
        density: c.density,
        damping: c.damping,
        gravity,
        structural: c.enable_structural,
        shearing: c.enable_shearing,
        bending: c.enable_bending,
        steps_per_frame,
        frames_per_sec,
        self_collision: self_collision.unwrap_or(defaults.self_collision),
        stretch_limit: stretch_limit.unwrap_or(defaults.stretch_limit),
        wind,
    };

    let mut colliders = Vec::new();
    if let Some(s) = &file.sphere {
        colliders.push(Collider::Sphere(Sphere {
            origin: ck.vec3("sphere.origin", s.origin)?,
            radius: ck.range(
                "sphere.radius",
                s.radius,
                positive,
                "a finite number > 0 (metres)",
            )?,
            friction: ck.range("sphere.friction", s.friction, unit, "between 0 and 1")?,
        }));
    }
    if let Some(p) = &file.plane {
        let normal = ck.vec3("plane.normal", p.normal)?;
        let len = normal.norm();
        if !(len > 0.0 && len.is_finite()) {
            return Err(ck.fail("plane.normal", show3(p.normal), "a non-zero vector"));
        }
        colliders.push(Collider::Plane(Plane {
            point: ck.vec3("plane.point", p.point)?,
            normal: normal / len,
            friction: ck.range("plane.friction", p.friction, unit, "between 0 and 1")?,
        }));
    }

    let spec = GridSpec {
        width: c.width,
        height: c.height,
        num_width_points: nw,
        num_height_points: nh,
        // NOTE: the course's loader reads the thickness into a 32-bit float (0.0095 becomes
        // 0.00949999969), and self-collision's reach is twice that value.
        // The bounds were checked on the value as typed; the 32-bit reading of a value at a
        // bound (1e-9 reads as 9.9999997e-10) is held to it.
        thickness: f64::from(c.thickness as f32).clamp(
            *cloth_mesh::EXTENT_RANGE.start(),
            *cloth_mesh::EXTENT_RANGE.end(),
        ),
        orientation,
        pinned,
        seed: seed.unwrap_or(GridSpec::default().seed),
    };
    let mesh = ClothMesh::new(&spec).map_err(|e| mesh_error(origin, &e))?;
    Ok(Scene {
        origin: origin.to_owned(),
        file,
        mesh: Arc::new(mesh),
        params,
        colliders,
        solver,
        solver_options,
    })
}

fn mesh_error(origin: &str, e: &MeshError) -> SceneError {
    // Everything the mesh checks was checked above with key names; this is a backstop.
    SceneError::Field {
        origin: origin.to_owned(),
        key: "cloth".to_owned(),
        message: e.to_string(),
        location: None,
    }
}

#[cfg(test)]
mod tests;
