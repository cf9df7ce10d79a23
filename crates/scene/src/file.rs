//! The scene file's JSON schema, as serde types.
//!
//! These mirror the file one to one (so a loaded scene saves back in the same shape); range
//! checks happen afterwards in [`crate::parse`], where the error can name the value and the rule.

use std::fmt;
use std::marker::PhantomData;

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::{Deserialize, Serialize};

use crate::number::show;

/// A whole scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// clothsim addition: one line saying what the scene shows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// The cloth (required).
    pub cloth: ClothBlock,
    /// An optional sphere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere: Option<SphereBlock>,
    /// An optional plane.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plane: Option<PlaneBlock>,
    /// clothsim addition: how to run the scene. Every key is optional.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub simulation: Option<SimulationBlock>,
}

/// The course's `cloth` block: every key but `pinned` is required.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClothBlock {
    /// Extent along x, metres (> 0).
    pub width: f64,
    /// Extent along the second axis, metres (> 0).
    pub height: f64,
    /// Points along x (>= 2).
    pub num_width_points: u64,
    /// Points along the second axis (>= 2).
    pub num_height_points: u64,
    /// Thickness, metres (> 0); self-collision keeps points twice this apart.
    pub thickness: f64,
    /// 0 = horizontal (xz-plane at y = 1), 1 = vertical (xy-plane).
    pub orientation: i64,
    /// Pinned points as `[column, row]`.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "pins"
    )]
    pub pinned: Option<Vec<[i64; 2]>>,
    /// Whether structural springs act.
    pub enable_structural: bool,
    /// Whether shearing springs act.
    pub enable_shearing: bool,
    /// Whether bending springs act.
    pub enable_bending: bool,
    /// Damping, percent, in [0, 100].
    pub damping: f64,
    /// Density, kg/m^2 (> 0); shown as g/cm^2 (divided by 10) in the UI.
    pub density: f64,
    /// Spring constant, N/m (>= 0).
    pub ks: f64,
}

/// The course's `sphere` block.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereBlock {
    /// Centre, metres.
    #[serde(deserialize_with = "xyz")]
    pub origin: [f64; 3],
    /// Radius, metres (> 0).
    pub radius: f64,
    /// Friction in [0, 1].
    pub friction: f64,
}

/// The course's `plane` block.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneBlock {
    /// A point on the plane, metres.
    #[serde(deserialize_with = "xyz")]
    pub point: [f64; 3],
    /// Normal (any non-zero length; normalised on load).
    #[serde(deserialize_with = "xyz")]
    pub normal: [f64; 3],
    /// Friction in [0, 1].
    pub friction: f64,
}

/// clothsim's `simulation` block; absent keys take the course's values.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationBlock {
    /// Frames per second of simulated time (default 90).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames_per_sec: Option<f64>,
    /// Simulation steps per frame (default 30).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub simulation_steps: Option<u64>,
    /// Gravity, m/s^2 (default [0, -9.8, 0]).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "optional_xyz"
    )]
    pub gravity: Option<[f64; 3]>,
    /// Whether self-collision is on (default true).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub self_collision: Option<bool>,
    /// Whether the 10 % stretch limit is on (default true).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stretch_limit: Option<bool>,
    /// Solver name, as listed by `clothsim solvers` (default: the application's first solver,
    /// `verlet`). This crate keeps it as text; the application checks it against the solvers it
    /// has.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<String>,
    /// Options of the scene's solver, an object (`{"iterations": 20}` for `fast-implicit`); the
    /// solver checks them, and `clothsim solvers` lists each solver's options. They apply to the
    /// solver this file names (or, when it names none, to the default one), not to another
    /// solver chosen on the command line or in the UI.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver_options: Option<serde_json::Map<String, serde_json::Value>>,
    /// A retired spelling of `solver_options.iterations`: read only to be refused with the
    /// spelling that replaced it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub iterations: Option<serde_json::Value>,
    /// A retired spelling of `solver_options.threads`: read only to be refused with the
    /// spelling that replaced it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub threads: Option<serde_json::Value>,
    /// A retired spelling of `solver_options.order`: read only to be refused with the spelling
    /// that replaced it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub constraint_order: Option<serde_json::Value>,
    /// The air's velocity, m/s (default none): each triangle feels the drag of the relative
    /// velocity's normal component (docs/model.md).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "optional_xyz"
    )]
    pub wind: Option<[f64; 3]>,
    /// The cloth's drag coefficient across the flow (default 1.2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wind_drag: Option<f64>,
    /// The gust's amplitude, a fraction of the wind (default 0: steady).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wind_gust: Option<f64>,
    /// The gust's period, s (default 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wind_gust_period: Option<f64>,
    /// Seed of the vertical cloth's z-jitter (default 184).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
}

// NOTE: serde reads `[T; N]` by taking N elements and then finding the array's end, so an array
// of the wrong length fails as a syntax error ("trailing characters") with no key. These read
// the whole array and, when its length is wrong, say so as a value error: the error then names
// the key (`sphere.origin`, `cloth.pinned[3]`), shows the array and says what is allowed.

/// A JSON array of exactly `N` elements, described as `shape` (`[x, y, z]`) in errors.
struct Exact<T, const N: usize> {
    shape: &'static str,
    what: &'static str,
    marker: PhantomData<T>,
}

/// An element that can be shown as written in an error.
trait Element: Copy + Default {
    fn show(&self) -> String;
}

impl Element for f64 {
    fn show(&self) -> String {
        show(*self)
    }
}

impl Element for i64 {
    fn show(&self) -> String {
        self.to_string()
    }
}

impl<'de, T: Deserialize<'de> + Element, const N: usize> Visitor<'de> for Exact<T, N> {
    type Value = [T; N];

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({N} {})", self.shape, self.what)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[T; N], A::Error> {
        let mut items = Vec::with_capacity(N);
        while let Some(x) = seq.next_element::<T>()? {
            items.push(x);
        }
        if items.len() != N {
            let shown: Vec<String> = items.iter().map(Element::show).collect();
            return Err(de::Error::custom(format!(
                "[{}] has {} {}, but it must be {} ({N} {})",
                shown.join(", "),
                items.len(),
                self.what,
                self.shape,
                self.what
            )));
        }
        let mut out = [T::default(); N];
        out.copy_from_slice(&items);
        Ok(out)
    }
}

fn xyz<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
    d.deserialize_seq(Exact::<f64, 3> {
        shape: "[x, y, z]",
        what: "numbers",
        marker: PhantomData,
    })
}

fn optional_xyz<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f64; 3]>, D::Error> {
    struct Xyz([f64; 3]);
    impl<'de> Deserialize<'de> for Xyz {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            xyz(d).map(Xyz)
        }
    }
    Ok(Option::<Xyz>::deserialize(d)?.map(|v| v.0))
}

fn pins<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<[i64; 2]>>, D::Error> {
    struct Pin([i64; 2]);
    impl<'de> Deserialize<'de> for Pin {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            d.deserialize_seq(Exact::<i64, 2> {
                shape: "[column, row]",
                what: "integers",
                marker: PhantomData,
            })
            .map(Pin)
        }
    }
    Ok(Option::<Vec<Pin>>::deserialize(d)?.map(|v| v.into_iter().map(|p| p.0).collect()))
}
