//! The one table of live parameters: label, unit, range, steps, how to read and write it.
//!
//! The parameter panel, its keys (select, nudge, type a value, restore) and the prompt's validation
//! all read the rows of [`row`]: the fixed [`PARAMS`], then one row per numeric option of the
//! active solver, made from its registry entry. Adding a parameter is one entry here. Values are
//! shown and edited in the units of the course's GUI (density in g/cm^2, damping in percent);
//! `get`/`set` convert to and from the SI units of [`StepParams`].

use cloth_solver::{Collider, OptionKind, SolverEntry, Vec3};

use cloth_run::{Run, Settings};

/// How a number moves when nudged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Add or subtract the step.
    Linear,
    /// Multiply or divide by the step (a factor > 1): equal ratios per press, for values that
    /// span decades (ks, density).
    Log,
}

/// What kind of value a row holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// A number in `[min, max]`.
    Number {
        /// Smallest allowed value (display units).
        min: f64,
        /// Largest allowed value (display units).
        max: f64,
        /// Fine step: an addend ([`Scale::Linear`]) or a factor ([`Scale::Log`]).
        fine: f64,
        /// Coarse step, likewise.
        coarse: f64,
        /// How steps apply.
        scale: Scale,
        /// Whether only whole numbers are allowed.
        integer: bool,
        /// Decimals shown.
        decimals: usize,
    },
    /// On or off; nudging or Enter flips it.
    Toggle,
    /// One of a few names, held as its index; nudging or Enter moves to the next.
    Choice {
        /// The names, in order.
        choices: &'static [&'static str],
    },
    /// The solver: nudging cycles the registry's solvers. Handled by the update function
    /// because switching builds a new solver; `get`/`set` are unused.
    Solver,
}

/// One live parameter.
#[derive(Debug, Clone, Copy)]
pub struct Param {
    /// Label in the panel, as in the course's GUI.
    pub label: &'static str,
    /// Unit shown after the value (empty for none).
    pub unit: &'static str,
    /// One line of help (shown when the row is selected).
    pub help: &'static str,
    /// The value kind, range and steps.
    pub kind: Kind,
    /// Reads the value in display units; `None` when the scene lacks it (no sphere...).
    pub get: fn(&Settings) -> Option<f64>,
    /// Writes a value in display units (already validated).
    pub set: fn(&mut Settings, f64),
}

/// Fine log step: four presses double the value.
const LOG_FINE: f64 = 1.189_207_115_002_721; // 2^(1/4)
/// Coarse log step: one press doubles the value.
const LOG_COARSE: f64 = 2.0;

fn flag(b: bool) -> f64 {
    if b { 1.0 } else { 0.0 }
}

fn sphere_friction(s: &Settings) -> Option<f64> {
    s.colliders.iter().find_map(|c| match c {
        Collider::Sphere(sp) => Some(sp.friction),
        Collider::Plane(_) => None,
    })
}

fn plane_friction(s: &Settings) -> Option<f64> {
    s.colliders.iter().find_map(|c| match c {
        Collider::Plane(p) => Some(p.friction),
        Collider::Sphere(_) => None,
    })
}

fn set_sphere_friction(s: &mut Settings, v: f64) {
    for c in &mut s.colliders {
        if let Collider::Sphere(sp) = c {
            sp.friction = v;
        }
    }
}

fn set_plane_friction(s: &mut Settings, v: f64) {
    for c in &mut s.colliders {
        if let Collider::Plane(p) = c {
            p.friction = v;
        }
    }
}

fn set_gravity(s: &mut Settings, axis: usize, v: f64) {
    let mut g: Vec3 = s.params.gravity;
    g[axis] = v;
    s.params.gravity = g;
}

const GRAVITY: Kind = Kind::Number {
    min: -100.0,
    max: 100.0,
    fine: 0.1,
    coarse: 1.0,
    scale: Scale::Linear,
    integer: false,
    decimals: 2,
};

const WIND: Kind = Kind::Number {
    min: -1000.0,
    max: 1000.0,
    fine: 0.5,
    coarse: 5.0,
    scale: Scale::Linear,
    integer: false,
    decimals: 1,
};

/// The wind's rows, after the solver's options: clothsim's addition to the course's model,
/// kept below the rows a small terminal must show.
pub const WIND_PARAMS: &[Param] = &[
    Param {
        label: "wind x",
        unit: "m/s",
        help: "the air's velocity, x component: each triangle feels drag across it",
        kind: WIND,
        get: |s| Some(s.params.wind.velocity.x),
        set: |s, v| s.params.wind.velocity.x = v,
    },
    Param {
        label: "wind y",
        unit: "m/s",
        help: "the air's velocity, y component (up is +y)",
        kind: WIND,
        get: |s| Some(s.params.wind.velocity.y),
        set: |s, v| s.params.wind.velocity.y = v,
    },
    Param {
        label: "wind z",
        unit: "m/s",
        help: "the air's velocity, z component",
        kind: WIND,
        get: |s| Some(s.params.wind.velocity.z),
        set: |s, v| s.params.wind.velocity.z = v,
    },
    Param {
        label: "wind drag",
        unit: "",
        help: "the cloth's drag coefficient across the flow (1.2: a flat plate)",
        kind: Kind::Number {
            min: 0.0,
            max: 100.0,
            fine: 0.1,
            coarse: 1.0,
            scale: Scale::Linear,
            integer: false,
            decimals: 2,
        },
        get: |s| Some(s.params.wind.drag),
        set: |s, v| s.params.wind.drag = v,
    },
];

const FRICTION: Kind = Kind::Number {
    min: 0.0,
    max: 1.0,
    fine: 0.05,
    coarse: 0.2,
    scale: Scale::Linear,
    integer: false,
    decimals: 2,
};

/// Every live parameter, in panel order (the course GUI's order, then clothsim's additions).
pub const PARAMS: &[Param] = &[
    Param {
        label: "ks",
        unit: "N/m",
        help: "spring constant (bending springs use 0.2 ks); Verlet diverges past about m/(2 dt^2)",
        kind: Kind::Number {
            min: 0.0,
            max: 1.0e8,
            fine: LOG_FINE,
            coarse: LOG_COARSE,
            scale: Scale::Log,
            integer: false,
            decimals: 0,
        },
        get: |s| Some(s.params.ks),
        set: |s, v| s.params.ks = v,
    },
    Param {
        label: "density",
        unit: "g/cm^2",
        help: "surface density (the file's kg/m^2 divided by 10); point mass follows at once",
        kind: Kind::Number {
            min: 0.01,
            max: 1000.0,
            fine: LOG_FINE,
            coarse: LOG_COARSE,
            scale: Scale::Log,
            integer: false,
            decimals: 2,
        },
        // NOTE: 1 g/cm^2 = 10 kg/m^2, the course GUI's display unit.
        get: |s| Some(s.params.density / 10.0),
        set: |s, v| s.params.density = v * 10.0,
    },
    Param {
        label: "damping",
        unit: "%",
        help: "Verlet keeps (1 - damping/100) of the velocity each step",
        kind: Kind::Number {
            min: 0.0,
            max: 100.0,
            fine: 0.05,
            coarse: 1.0,
            scale: Scale::Linear,
            integer: false,
            decimals: 2,
        },
        get: |s| Some(s.params.damping),
        set: |s, v| s.params.damping = v,
    },
    Param {
        label: "gravity x",
        unit: "m/s^2",
        help: "gravity, x component",
        kind: GRAVITY,
        get: |s| Some(s.params.gravity.x),
        set: |s, v| set_gravity(s, 0, v),
    },
    Param {
        label: "gravity y",
        unit: "m/s^2",
        help: "gravity, y component (up is +y)",
        kind: GRAVITY,
        get: |s| Some(s.params.gravity.y),
        set: |s, v| set_gravity(s, 1, v),
    },
    Param {
        label: "gravity z",
        unit: "m/s^2",
        help: "gravity, z component",
        kind: GRAVITY,
        get: |s| Some(s.params.gravity.z),
        set: |s, v| set_gravity(s, 2, v),
    },
    Param {
        label: "structural",
        unit: "",
        help: "whether structural springs (grid neighbours) exert forces",
        kind: Kind::Toggle,
        get: |s| Some(flag(s.params.structural)),
        set: |s, v| s.params.structural = v != 0.0,
    },
    Param {
        label: "shearing",
        unit: "",
        help: "whether shearing springs (diagonal neighbours) exert forces",
        kind: Kind::Toggle,
        get: |s| Some(flag(s.params.shearing)),
        set: |s, v| s.params.shearing = v != 0.0,
    },
    Param {
        label: "bending",
        unit: "",
        help: "whether bending springs (two apart) exert forces",
        kind: Kind::Toggle,
        get: |s| Some(flag(s.params.bending)),
        set: |s, v| s.params.bending = v != 0.0,
    },
    Param {
        label: "steps/frame",
        unit: "",
        help: "simulation steps per frame; more steps = smaller dt = stiffer cloth stays stable",
        kind: Kind::Number {
            min: 1.0,
            max: 10_000.0,
            fine: 1.0,
            coarse: 10.0,
            scale: Scale::Linear,
            integer: true,
            decimals: 0,
        },
        get: |s| Some(f64::from(s.params.steps_per_frame)),
        set: |s, v| s.params.steps_per_frame = v as u32,
    },
    Param {
        label: "frames/s",
        unit: "fps",
        help: "simulated frames per second; dt = 1 / (frames/s x steps/frame)",
        kind: Kind::Number {
            min: 1.0,
            max: 10_000.0,
            fine: 1.0,
            coarse: 10.0,
            scale: Scale::Linear,
            integer: true,
            decimals: 0,
        },
        get: |s| Some(s.params.frames_per_sec),
        set: |s, v| s.params.frames_per_sec = v,
    },
    Param {
        label: "self-collision",
        unit: "",
        help: "points repel each other closer than twice the thickness",
        kind: Kind::Toggle,
        get: |s| Some(flag(s.params.self_collision)),
        set: |s, v| s.params.self_collision = v != 0.0,
    },
    Param {
        label: "sphere friction",
        unit: "",
        help: "friction of the sphere (0 = slippery, 1 = sticky)",
        kind: FRICTION,
        get: sphere_friction,
        set: set_sphere_friction,
    },
    Param {
        label: "plane friction",
        unit: "",
        help: "friction of the plane (0 = slippery, 1 = sticky)",
        kind: FRICTION,
        get: plane_friction,
        set: set_plane_friction,
    },
    Param {
        label: "stretch limit",
        unit: "",
        help: "the course's constraint: springs end each step at most 10% over rest length",
        kind: Kind::Toggle,
        get: |s| Some(flag(s.params.stretch_limit)),
        set: |s, v| s.params.stretch_limit = v != 0.0,
    },
    Param {
        label: "solver",
        unit: "",
        help: "the time integrator; switching keeps the cloth's motion",
        kind: Kind::Solver,
        get: |_| None,
        set: |_, _| {},
    },
];

/// Readers and writers of the solver's option rows, one per slot of [`Settings::options`]
/// (plain functions, as every row's are).
macro_rules! option_slots {
    ($($i:literal)*) => {
        const OPTION_GET: &[fn(&Settings) -> Option<f64>] = &[$(|s| s.options.get($i).copied()),*];
        const OPTION_SET: &[fn(&mut Settings, f64)] = &[$(|s, v| {
            if let Some(o) = s.options.get_mut($i) {
                *o = v;
            }
        }),*];
    };
}
option_slots!(0 1 2 3 4 5 6 7);

/// The rows of the active solver's options (at most eight; a solver with more shows its first
/// eight): numbers, and choices cycled through their names.
fn option_rows(entry: &SolverEntry) -> impl Iterator<Item = Param> + '_ {
    entry
        .options()
        .iter()
        .zip(OPTION_GET.iter().zip(OPTION_SET))
        .map(|(o, (&get, &set))| {
            let (min, max, _) = o.numeric().unwrap_or((0.0, 0.0, 0.0));
            let integer = matches!(o.kind, OptionKind::Integer { .. });
            // Ranges over three decades step by ratios, like ks; others by a hundredth of the
            // range (whole numbers by one).
            let kind = if let OptionKind::Choice { choices, .. } = o.kind {
                Kind::Choice { choices }
            } else if min > 0.0 && max / min >= 1000.0 {
                Kind::Number {
                    min,
                    max,
                    fine: LOG_FINE,
                    coarse: LOG_COARSE,
                    scale: Scale::Log,
                    integer,
                    decimals: if integer { 0 } else { 3 },
                }
            } else if integer {
                Kind::Number {
                    min,
                    max,
                    fine: 1.0,
                    coarse: 10.0,
                    scale: Scale::Linear,
                    integer,
                    decimals: 0,
                }
            } else {
                Kind::Number {
                    min,
                    max,
                    fine: (max - min) / 100.0,
                    coarse: (max - min) / 10.0,
                    scale: Scale::Linear,
                    integer,
                    decimals: 3,
                }
            };
            Param {
                label: o.name,
                unit: "",
                help: o.description,
                kind,
                get,
                set,
            }
        })
}

/// How many rows the panel has for `sim`: [`PARAMS`], the active solver's options and
/// [`WIND_PARAMS`].
pub fn row_count(sim: &Run) -> usize {
    PARAMS.len() + option_rows(sim.entry()).count() + WIND_PARAMS.len()
}

/// Row `i` of the panel for `sim` (the last row for an `i` past the end).
pub fn row(sim: &Run, i: usize) -> Param {
    let i = i.min(row_count(sim) - 1);
    let options = option_rows(sim.entry()).count();
    match i.checked_sub(PARAMS.len()) {
        None => PARAMS[i],
        Some(k) if k < options => option_rows(sim.entry())
            .nth(k)
            .unwrap_or(PARAMS[PARAMS.len() - 1]),
        Some(k) => WIND_PARAMS[k - options],
    }
}

/// Whether row `i` is one of the solver's options (changing it rebuilds the solver).
pub fn is_option_row(sim: &Run, i: usize) -> bool {
    (PARAMS.len()..PARAMS.len() + option_rows(sim.entry()).count()).contains(&i)
}

impl Param {
    /// The value after `presses` nudges (negative = down), clamped to the range. Toggles flip
    /// on any odd number of presses.
    pub fn nudged(&self, value: f64, presses: i32, coarse: bool) -> f64 {
        match self.kind {
            Kind::Number {
                min,
                max,
                fine,
                coarse: big,
                scale,
                integer,
                ..
            } => {
                let step = if coarse { big } else { fine };
                let v = match scale {
                    Scale::Linear => value + step * f64::from(presses),
                    Scale::Log => {
                        // NOTE: a log scale cannot leave 0 by multiplying; from at or below
                        // the smallest positive step (1 in display units, or `min` when that
                        // is positive) it jumps there, and below it falls to `min`.
                        let floor = if min > 0.0 { min } else { 1.0 };
                        if presses > 0 && value < floor {
                            floor
                        } else if presses < 0 && value <= floor {
                            min
                        } else {
                            value * step.powi(presses)
                        }
                    }
                };
                let v = if integer { v.round() } else { v };
                v.clamp(min, max)
            }
            Kind::Toggle => {
                if presses % 2 == 0 {
                    value
                } else if value != 0.0 {
                    0.0
                } else {
                    1.0
                }
            }
            Kind::Choice { choices } => {
                let n = choices.len().max(1) as i64;
                ((value.round() as i64 + i64::from(presses)).rem_euclid(n)) as f64
            }
            Kind::Solver => value,
        }
    }

    /// Parses typed text as a value for this row.
    ///
    /// # Errors
    /// A message naming the parameter, what was typed and what is allowed.
    pub fn parse(&self, text: &str) -> Result<f64, String> {
        let t = text.trim();
        match self.kind {
            Kind::Number {
                min, max, integer, ..
            } => {
                let allowed = format!(
                    "{} from {} to {}{}",
                    if integer {
                        "a whole number"
                    } else {
                        "a number"
                    },
                    fmt_number(min),
                    fmt_number(max),
                    if self.unit.is_empty() {
                        String::new()
                    } else {
                        format!(" {}", self.unit)
                    }
                );
                let v: f64 = t.parse().map_err(|_| {
                    format!("{}: {t:?} is not a number; enter {allowed}", self.label)
                })?;
                if !v.is_finite() || v < min || v > max {
                    return Err(format!(
                        "{}: {t} is out of range; enter {allowed}",
                        self.label
                    ));
                }
                if integer && v.fract() != 0.0 {
                    return Err(format!(
                        "{}: {t} is not a whole number; enter {allowed}",
                        self.label
                    ));
                }
                Ok(v)
            }
            Kind::Toggle => match t.to_ascii_lowercase().as_str() {
                "on" | "true" | "yes" | "1" => Ok(1.0),
                "off" | "false" | "no" | "0" => Ok(0.0),
                _ => Err(format!("{}: {t:?} is not on or off", self.label)),
            },
            Kind::Choice { choices } => choices
                .iter()
                .position(|c| c.eq_ignore_ascii_case(t))
                .map(|i| i as f64)
                .ok_or_else(|| {
                    format!("{}: {t:?} is not one of {}", self.label, choices.join(", "))
                }),
            Kind::Solver => Err(format!("{}: choose with left/right", self.label)),
        }
    }

    /// The value as shown in the panel (without the unit).
    pub fn format(&self, value: Option<f64>) -> String {
        match (self.kind, value) {
            (_, None) | (Kind::Solver, _) => "-".to_owned(),
            (Kind::Toggle, Some(v)) => if v == 0.0 { "off" } else { "on" }.to_owned(),
            (Kind::Choice { choices }, Some(v)) => choices
                .get(v.round().max(0.0) as usize)
                .map_or_else(|| "-".to_owned(), |&c| c.to_owned()),
            (Kind::Number { decimals, .. }, Some(v)) => {
                // Large values, and small ones that the fixed decimals would show as zero,
                // in scientific notation.
                if v.abs() >= 1.0e7
                    || (decimals > 0 && v != 0.0 && v.abs() < 0.1_f64.powi(decimals as i32))
                {
                    format!("{v:.3e}")
                } else {
                    format!("{v:.decimals$}")
                }
            }
        }
    }
}

/// A range bound for messages: whole numbers without decimals.
pub fn fmt_number(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1.0e7 {
        format!("{v:.0}")
    } else {
        format!("{v}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> Settings {
        Settings {
            params: cloth_solver::StepParams::default(),
            colliders: Vec::new(),
            options: Vec::new(),
        }
    }

    fn row(label: &str) -> &'static Param {
        PARAMS.iter().find(|p| p.label == label).unwrap()
    }

    #[test]
    fn density_is_shown_in_grams_per_square_centimetre() {
        let mut s = settings();
        let d = row("density");
        // The course: 150 kg/m^2 in the file is 15 g/cm^2 on screen.
        assert_eq!((d.get)(&s), Some(15.0));
        (d.set)(&mut s, 20.0);
        assert_eq!(s.params.density, 200.0);
    }

    #[test]
    fn log_steps_multiply_and_four_fine_steps_double() {
        let ks = row("ks");
        let up = ks.nudged(5000.0, 4, false);
        // 2^(1/4) to the fourth is 2 up to rounding of the constant (~1e-16 relative).
        assert!((up - 10_000.0).abs() < 1e-9);
        assert_eq!(ks.nudged(5000.0, -1, true), 2500.0);
        // From 0 a log step must still move.
        assert_eq!(ks.nudged(0.0, 1, false), 1.0);
        assert_eq!(ks.nudged(1.0, -1, false), 0.0);
        assert_eq!(ks.nudged(9.0e7, 1, true), 1.0e8);
    }

    #[test]
    fn typed_values_are_validated_with_the_allowed_range() {
        let damping = row("damping");
        assert_eq!(damping.parse(" 0.5 "), Ok(0.5));
        let e = damping.parse("abc").unwrap_err();
        assert_eq!(
            e,
            "damping: \"abc\" is not a number; enter a number from 0 to 100 %"
        );
        let e = damping.parse("150").unwrap_err();
        assert!(e.contains("out of range"), "{e}");
        assert!(row("steps/frame").parse("2.5").is_err());
        assert!(row("ks").parse("NaN").is_err());
        assert!(row("ks").parse("inf").is_err());
    }

    #[test]
    fn friction_rows_are_absent_without_objects() {
        let s = settings();
        assert_eq!((row("sphere friction").get)(&s), None);
        assert_eq!(row("sphere friction").format(None), "-");
    }

    #[test]
    fn a_choice_row_cycles_through_its_names_and_reads_them_typed() {
        let order = Param {
            label: "order",
            unit: "",
            help: "",
            kind: Kind::Choice {
                choices: &["faithful", "parallel", "colored"],
            },
            get: |s| s.options.first().copied(),
            set: |s, v| s.options[0] = v,
        };
        assert_eq!(order.nudged(0.0, 1, false), 1.0);
        assert_eq!(order.nudged(2.0, 1, false), 0.0, "past the last, the first");
        assert_eq!(order.nudged(0.0, -1, true), 2.0);
        assert_eq!(order.format(Some(2.0)), "colored");
        assert_eq!(order.parse(" Colored "), Ok(2.0));
        assert_eq!(
            order.parse("random").unwrap_err(),
            "order: \"random\" is not one of faithful, parallel, colored"
        );
    }

    #[test]
    fn toggles_flip() {
        let b = row("bending");
        assert_eq!(b.nudged(1.0, 1, false), 0.0);
        assert_eq!(b.nudged(0.0, -1, false), 1.0);
        assert_eq!(b.parse("off"), Ok(0.0));
    }
}
