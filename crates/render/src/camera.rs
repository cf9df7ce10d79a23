//! Views and cameras: where the picture is seen from and how world points land on pixels.
//!
//! Orientation of the fixed views (x right-handed, y up as in the course):
//!
//! | view   | looks along | screen right | screen up |
//! |--------|-------------|--------------|-----------|
//! | side   | -z          | +x           | +y        |
//! | front  | +x          | +z           | +y        |
//! | top    | -y (down)   | +x           | -z        |
//! | bottom | +y (up)     | +x           | +z        |
//!
//! `side` is the course's default camera direction; `top` is `side` tilted down by 90 degrees
//! (so the side camera's position, +z, is at the bottom of the top view) and `bottom` is `side`
//! tilted up by 90 degrees. `orbit` is a perspective camera on a sphere around a target.
//!
//! Fitting: an orthographic view scales and centres its extent (a box) to fill the frame less a
//! margin. A fitted orbit ([`ViewSpec::fit_orbit`], the default) keeps its direction (the
//! course's, looking along -z, unless turned) and field of view, and moves its target and
//! distance so that the same box fills the frame less the margin, centred, with at least
//! [`ViewSpec::ORBIT_MARGIN_CELLS`] cells empty on each side ([`Orbit::fitted`]). The picture
//! then moves only when the extent does: a front end keeps it still by passing a fixed extent
//! that grows only when the cloth leaves it.

use std::fmt;
use std::str::FromStr;

use cloth_mesh::{ClothMesh, Vec3};

use crate::{Bounds, RenderError};

/// Which way the scene is looked at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum View {
    /// Orthographic, looking along -z: +x right, +y up.
    #[default]
    Side,
    /// Orthographic, looking down -y: +x right, -z up (+z towards the bottom of the screen).
    Top,
    /// Orthographic, looking up +y: +x right, +z up.
    Bottom,
    /// Orthographic, looking along +x: +z right, +y up.
    Front,
    /// Perspective from [`Orbit`]'s yaw, pitch and distance around its target.
    Orbit,
}

impl View {
    /// Every view, in the order of the table in the module docs.
    pub const ALL: [View; 5] = [
        View::Side,
        View::Top,
        View::Bottom,
        View::Front,
        View::Orbit,
    ];

    /// The accepted spellings, for help and error messages.
    pub const NAMES: &'static str = "side, top, bottom, front or orbit";

    /// The lowercase name, as typed on the command line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            View::Side => "side",
            View::Top => "top",
            View::Bottom => "bottom",
            View::Front => "front",
            View::Orbit => "orbit",
        }
    }

    /// A one-line description of the axes, for labels.
    #[must_use]
    pub fn describe(self) -> &'static str {
        match self {
            View::Side => "side: looking -z, +x right, +y up",
            View::Top => "top: looking down, +x right, +z down",
            View::Bottom => "bottom: looking up, +x right, +z up",
            View::Front => "front: looking +x, +z right, +y up",
            View::Orbit => "orbit: perspective",
        }
    }

    /// The `(screen up, screen right)` axis labels of an orthographic view.
    #[must_use]
    pub fn axis_labels(self) -> Option<(&'static str, &'static str)> {
        match self {
            View::Side => Some(("+y", "+x")),
            View::Top => Some(("-z", "+x")),
            View::Bottom => Some(("+z", "+x")),
            View::Front => Some(("+y", "+z")),
            View::Orbit => None,
        }
    }

    /// `(forward, right, up)` unit vectors of an orthographic view.
    fn basis(self) -> Option<(Vec3, Vec3, Vec3)> {
        match self {
            View::Side => Some((-Vec3::z(), Vec3::x(), Vec3::y())),
            View::Front => Some((Vec3::x(), Vec3::z(), Vec3::y())),
            View::Top => Some((-Vec3::y(), Vec3::x(), -Vec3::z())),
            View::Bottom => Some((Vec3::y(), Vec3::x(), Vec3::z())),
            View::Orbit => None,
        }
    }
}

impl FromStr for View {
    type Err = RenderError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim().to_ascii_lowercase();
        View::ALL
            .into_iter()
            .find(|v| v.name() == t)
            .ok_or_else(|| RenderError::Unknown {
                what: "view",
                value: s.to_owned(),
                allowed: View::NAMES,
            })
    }
}

impl fmt::Display for View {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What a view is fitted to: the box an orthographic view fills, and the box a fitted orbit
/// ([`ViewSpec::fit_orbit`]) frames.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Extent {
    /// Fit every frame to what is there now ([`Bounds::of_scene`]): the picture is as large as
    /// possible but may rescale as the cloth moves.
    #[default]
    Auto,
    /// Fit to this box whatever the cloth does, so an animation does not jump. Use the union of
    /// [`Bounds::of_scene`] over the frames to be shown.
    Fixed(Bounds),
}

/// A perspective camera circling a target: the course's mouse-orbit camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    /// The point looked at, metres.
    pub target: Vec3,
    /// Turn about +y, radians; 0 puts the camera on the +z side, looking along -z.
    pub yaw: f64,
    /// Elevation, radians, positive above the target; kept within +-89 degrees.
    pub pitch: f64,
    /// Distance from the target, metres (> 0).
    pub distance: f64,
    /// Vertical field of view, radians (between 1 and 170 degrees).
    pub vfov: f64,
}

impl Orbit {
    /// Largest pitch magnitude, radians (89 degrees): at 90 the up direction is undefined.
    pub const MAX_PITCH: f64 = 89.0 * std::f64::consts::PI / 180.0;

    /// The course's default camera: looking along -z from `target + (0, 0, 1.8 max(w, h))`,
    /// with `target = (mean x, mean y / 2, mean z)` of the start positions and a 40 degree
    /// vertical field of view.
    #[must_use]
    pub fn course_default(mesh: &ClothMesh) -> Self {
        let start = mesh.start_positions();
        let mean = start.iter().sum::<Vec3>() / start.len().max(1) as f64;
        let spec = mesh.spec();
        Self {
            target: Vec3::new(mean.x, mean.y / 2.0, mean.z),
            yaw: 0.0,
            pitch: 0.0,
            distance: 1.8 * spec.width.max(spec.height),
            vfov: 40f64.to_radians(),
        }
    }

    /// This orbit's yaw, pitch and field of view, with the target and distance that fit
    /// `bounds` to a frame `frame_aspect` times wider than tall (as seen: columns over rows
    /// times the cell aspect), less `margin` (a fraction of the frame) on each side.
    ///
    /// The eye is as near as it can be with every corner of the box inside that window, and
    /// placed across the line of sight so that the box's picture is centred in the frame; the
    /// target is the box's middle along the line of sight, so turning circles the scene.
    /// Everything inside the box is then inside the window too: seen from outside it, a
    /// convex box's inside projects inside its corners' outline. `margin` is clamped to 0 to
    /// 0.45; a non-finite or non-positive `frame_aspect`, or a box with no finite size, gives
    /// this orbit back unchanged.
    #[must_use]
    pub fn fitted(&self, bounds: &Bounds, frame_aspect: f64, margin: f64) -> Self {
        let (forward, right, up) = self.basis();
        let usable = 1.0 - 2.0 * margin.clamp(0.0, 0.45);
        // Half the window's height and width over the depth, after the margin.
        let tan_v = usable * (0.5 * self.vfov).tan();
        let tan_h = tan_v * frame_aspect;
        let diagonal = bounds.diagonal();
        if !(tan_h.is_finite() && tan_h > 0.0 && tan_v > 0.0 && diagonal.is_finite()) {
            return *self;
        }
        // Per axis, a corner at (a, c) (across, along the line of sight) is inside the window
        // seen from (e, ec) when |a - e| <= tan (c - ec): the eye must keep
        // e - tan ec >= max(a - tan c) and e + tan ec <= min(a + tan c).
        let mut lo = [f64::NEG_INFINITY; 2];
        let mut hi = [f64::INFINITY; 2];
        let (mut near, mut far) = (f64::INFINITY, f64::NEG_INFINITY);
        for corner in bounds.corners() {
            let c = corner.dot(&forward);
            for (k, (axis, t)) in [(right, tan_h), (up, tan_v)].into_iter().enumerate() {
                let a = corner.dot(&axis);
                lo[k] = lo[k].max(a - t * c);
                hi[k] = hi[k].min(a + t * c);
            }
            near = near.min(c);
            far = far.max(c);
        }
        let eye_c = ((hi[0] - lo[0]) / (2.0 * tan_h)).min((hi[1] - lo[1]) / (2.0 * tan_v));
        // NOTE: a box with no extent across the line of sight (a point) would put the eye on
        // it; keep it a thousandth of the box's size (or a millimetre) in front.
        let eye_c = eye_c.min(near - 1e-3 * diagonal.max(1.0));
        let middle = 0.5 * (near + far);
        let corners = bounds.corners();
        let across = |axis: Vec3| {
            let points = corners.map(|c| (c.dot(&axis), c.dot(&forward) - eye_c));
            centre_across(&points)
        };
        let target = right * across(right) + up * across(up) + forward * middle;
        let distance = middle - eye_c;
        if !(distance.is_finite() && distance > 0.0 && target.iter().all(|x| x.is_finite())) {
            return *self;
        }
        Self {
            target,
            distance,
            ..*self
        }
    }

    /// `(forward, right, up)` unit vectors of the camera, with the pitch clamped as
    /// [`Orbit::eye`] clamps it.
    fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let pitch = self.pitch.clamp(-Self::MAX_PITCH, Self::MAX_PITCH);
        let forward = -Vec3::new(
            pitch.cos() * self.yaw.sin(),
            pitch.sin(),
            pitch.cos() * self.yaw.cos(),
        );
        // NOTE: pitch is clamped below 90 degrees, so forward is never parallel to +y.
        let right = forward.cross(&Vec3::y()).normalize();
        let up = right.cross(&forward);
        (forward, right, up)
    }

    /// Where the camera is, metres.
    #[must_use]
    pub fn eye(&self) -> Vec3 {
        let pitch = self.pitch.clamp(-Self::MAX_PITCH, Self::MAX_PITCH);
        self.target
            + Vec3::new(
                pitch.cos() * self.yaw.sin(),
                pitch.sin(),
                pitch.cos() * self.yaw.cos(),
            ) * self.distance
    }

    fn validate(&self) -> Result<(), RenderError> {
        let bad = |name, value: f64, allowed| {
            Err(RenderError::BadOption {
                name,
                value: value.to_string(),
                allowed,
            })
        };
        if !self.target.iter().all(|c| c.is_finite()) {
            return Err(RenderError::BadOption {
                name: "orbit target",
                value: format!("{:?}", self.target.as_slice()),
                allowed: "three finite numbers (metres)",
            });
        }
        if !(self.yaw.is_finite() && self.pitch.is_finite()) {
            return bad(
                "orbit yaw/pitch",
                self.yaw + self.pitch,
                "finite angles (radians)",
            );
        }
        if !(self.distance.is_finite() && self.distance > 0.0) {
            return bad(
                "orbit distance",
                self.distance,
                "a finite number > 0 (metres)",
            );
        }
        if !(self.vfov.is_finite()
            && (1f64.to_radians()..=170f64.to_radians()).contains(&self.vfov))
        {
            return bad(
                "orbit vertical field of view",
                self.vfov.to_degrees(),
                "between 1 and 170 degrees",
            );
        }
        Ok(())
    }
}

/// Where along one axis across the line of sight an eye puts the picture of `points`, each
/// `(across, depth from the eye)` with depths > 0, in the middle of the frame: the `e` at which
/// the smallest and the largest `(across - e) / depth` are opposite.
///
/// NOTE: both are decreasing in `e`, so their sum is too, and it is >= 0 at the smallest
/// `across` and <= 0 at the largest: bisection finds the root to rounding. From the eye the
/// fit computed (inside the window on both sides), moving to the root shrinks the larger of
/// the two and grows the other up to its size, so the picture stays inside the window.
fn centre_across(points: &[(f64, f64)]) -> f64 {
    let sum = |e: f64| {
        let (lo, hi) = points
            .iter()
            .map(|&(a, d)| (a - e) / d)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
                (l.min(x), h.max(x))
            });
        lo + hi
    };
    let (mut lo, mut hi) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &(a, _)| {
            (l.min(a), h.max(a))
        });
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if sum(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Everything that decides the camera for a frame: the view, what it is fitted to, the margin
/// and, for [`View::Orbit`], the orbit and whether it is fitted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewSpec {
    /// Which view.
    pub view: View,
    /// What the view is fitted to (an orbit not fitted ignores it).
    pub extent: Extent,
    /// Empty border around a fitted view, as a fraction of the frame on each side (0 to 0.45;
    /// default 0.04). [`Renderer`](crate::Renderer) keeps a fitted orbit's border at least
    /// [`ViewSpec::ORBIT_MARGIN_CELLS`] cells wide.
    pub margin: f64,
    /// The perspective camera used by [`View::Orbit`]: as it is, or its direction and field of
    /// view when [`ViewSpec::fit_orbit`] is set.
    pub orbit: Orbit,
    /// Fit the orbit's target and distance to the extent, keeping its yaw, pitch and field of
    /// view ([`Orbit::fitted`]), the way the orthographic views fit theirs (default true).
    /// Pass a fixed extent to keep the camera still while the cloth moves.
    pub fit_orbit: bool,
}

impl ViewSpec {
    /// Fewest cells of empty border a fitted orbit keeps on each side: a fraction of a cell is
    /// no border on a terminal (the cloth's edge would share the frame's edge cells), and the
    /// half cell more keeps a point on the box's far edge out of the last row or column.
    pub const ORBIT_MARGIN_CELLS: f64 = 1.5;

    /// `view`, auto-fitted with the default margin, with the course's default orbit for `mesh`,
    /// fitted.
    #[must_use]
    pub fn new(view: View, mesh: &ClothMesh) -> Self {
        Self {
            view,
            extent: Extent::Auto,
            margin: 0.04,
            orbit: Orbit::course_default(mesh),
            fit_orbit: true,
        }
    }

    /// The orbit this spec is drawn with into a frame of `columns` x `rows` cells, each
    /// `cell_aspect` times taller than wide, as [`Renderer`](crate::Renderer) draws it:
    /// [`ViewSpec::orbit`] itself, or when [`ViewSpec::fit_orbit`] is set, fitted to the
    /// extent (`content` when it is [`Extent::Auto`]) with the margin raised to at least
    /// [`ViewSpec::ORBIT_MARGIN_CELLS`] cells. A front end that lets the user move a fitted
    /// camera starts from this.
    #[must_use]
    pub fn orbit_in(
        &self,
        content: &Bounds,
        columns: usize,
        rows: usize,
        cell_aspect: f64,
    ) -> Orbit {
        if !self.fit_orbit {
            return self.orbit;
        }
        let fit = match self.extent {
            Extent::Auto => *content,
            Extent::Fixed(b) => b,
        };
        self.orbit.fitted(
            &fit,
            columns as f64 / (rows as f64 * cell_aspect),
            self.orbit_margin(columns, rows),
        )
    }

    /// The margin of a fitted orbit in a `columns` x `rows` frame (see
    /// [`ViewSpec::ORBIT_MARGIN_CELLS`]).
    pub(crate) fn orbit_margin(&self, columns: usize, rows: usize) -> f64 {
        let cells = columns.min(rows).max(1) as f64;
        self.margin.max(Self::ORBIT_MARGIN_CELLS / cells).min(0.45)
    }
}

/// The projection part of a [`Camera`].
#[derive(Debug, Clone, Copy, PartialEq)]
enum Projection {
    /// `scale` metres per pixel width.
    Orthographic { scale: f64 },
    /// `focal` length in pixel widths; points nearer than `near` metres are not drawn.
    Perspective { focal: f64, near: f64 },
}

/// A point after projection: pixel coordinates (x right, y down, pixel centres at `i + 0.5`)
/// and a depth key that is smaller for nearer points and varies linearly across a projected
/// triangle (view distance for orthographic, `-1 / distance` for perspective).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Projected {
    /// Column, pixels.
    pub x: f64,
    /// Row, pixels (down).
    pub y: f64,
    /// Depth key: smaller is nearer.
    pub depth: f64,
}

/// A concrete camera for a pixel grid: a view basis plus an orthographic or perspective
/// projection, with the pixels' aspect ratio corrected.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    origin: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    projection: Projection,
    half_w: f64,
    half_h: f64,
    aspect: f64,
}

impl Camera {
    /// The camera of `spec` for a `width` x `height` pixel grid whose pixels are `aspect` times
    /// taller than wide. `content` is what an auto-fitted view frames (ignored by a fixed extent
    /// and by an orbit not fitted). A fitted orbit gets `spec.margin` as it is; the
    /// [`Renderer`](crate::Renderer) raises it to whole cells first ([`ViewSpec::orbit_in`]).
    ///
    /// # Errors
    /// [`RenderError::BadOption`] for a bad margin, aspect or orbit.
    pub fn new(
        spec: &ViewSpec,
        content: &Bounds,
        width: usize,
        height: usize,
        aspect: f64,
    ) -> Result<Self, RenderError> {
        if !(aspect.is_finite() && aspect > 0.0) {
            return Err(RenderError::BadOption {
                name: "pixel aspect",
                value: aspect.to_string(),
                allowed: "a finite number > 0",
            });
        }
        if !(spec.margin.is_finite() && (0.0..=0.45).contains(&spec.margin)) {
            return Err(RenderError::BadOption {
                name: "margin",
                value: spec.margin.to_string(),
                allowed: "between 0 and 0.45 (fraction of the frame)",
            });
        }
        let (half_w, half_h) = (width as f64 / 2.0, height as f64 / 2.0);
        if let Some((forward, right, up)) = spec.view.basis() {
            let fit = match spec.extent {
                Extent::Auto => *content,
                Extent::Fixed(b) => b,
            };
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for c in fit.corners() {
                let q = [c.dot(&right), c.dot(&up), c.dot(&forward)];
                for k in 0..3 {
                    lo[k] = lo[k].min(q[k]);
                    hi[k] = hi[k].max(q[k]);
                }
            }
            let usable = 1.0 - 2.0 * spec.margin;
            let scale_w = (hi[0] - lo[0]) / (width as f64 * usable);
            let scale_h = (hi[1] - lo[1]) / (height as f64 * usable * aspect);
            // NOTE: a single point or a cloth seen exactly edge-on has no extent on one or both
            // axes; never let the scale reach 0 (it divides) or a denormal.
            let scale = scale_w.max(scale_h).max(1e-6);
            let mid = |k: usize| f64::midpoint(lo[k], hi[k]);
            Ok(Self {
                origin: right * mid(0) + up * mid(1) + forward * mid(2),
                forward,
                right,
                up,
                projection: Projection::Orthographic { scale },
                half_w,
                half_h,
                aspect,
            })
        } else {
            spec.orbit.validate()?;
            let o = if spec.fit_orbit {
                let fit = match spec.extent {
                    Extent::Auto => *content,
                    Extent::Fixed(b) => b,
                };
                spec.orbit
                    .fitted(&fit, width as f64 / (height as f64 * aspect), spec.margin)
            } else {
                spec.orbit
            };
            let eye = o.eye();
            let (forward, right, up) = o.basis();
            let focal = half_h * aspect / (o.vfov / 2.0).tan();
            Ok(Self {
                origin: eye,
                forward,
                right,
                up,
                projection: Projection::Perspective {
                    focal,
                    near: o.distance * 1e-3,
                },
                half_w,
                half_h,
                aspect,
            })
        }
    }

    /// Unit vector the camera looks along.
    #[must_use]
    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// Unit vector pointing right on screen.
    #[must_use]
    pub fn right(&self) -> Vec3 {
        self.right
    }

    /// Unit vector pointing up on screen.
    #[must_use]
    pub fn up(&self) -> Vec3 {
        self.up
    }

    /// Where a perspective camera's eye is (`None` for orthographic: it sees along
    /// [`Self::forward`] from everywhere).
    #[must_use]
    pub fn eye(&self) -> Option<Vec3> {
        self.is_perspective().then_some(self.origin)
    }

    /// Whether this is a perspective camera.
    #[must_use]
    pub fn is_perspective(&self) -> bool {
        matches!(self.projection, Projection::Perspective { .. })
    }

    /// Pixel position and depth key of `p`, or `None` when it is behind a perspective camera's
    /// near plane.
    #[must_use]
    pub fn project(&self, p: Vec3) -> Option<Projected> {
        let d = p - self.origin;
        let (u, v, z) = (d.dot(&self.right), d.dot(&self.up), d.dot(&self.forward));
        match self.projection {
            Projection::Orthographic { scale } => Some(Projected {
                x: self.half_w + u / scale,
                y: self.half_h - v / (scale * self.aspect),
                depth: z,
            }),
            Projection::Perspective { focal, near } => (z > near).then(|| Projected {
                x: self.half_w + focal * u / z,
                y: self.half_h - focal * v / (z * self.aspect),
                depth: -1.0 / z,
            }),
        }
    }

    /// The depth key of a world point (see [`Projected::depth`]); +inf behind a perspective
    /// camera.
    #[must_use]
    pub fn depth_of(&self, p: Vec3) -> f64 {
        let z = (p - self.origin).dot(&self.forward);
        match self.projection {
            Projection::Orthographic { .. } => z,
            Projection::Perspective { near, .. } => {
                if z > near {
                    -1.0 / z
                } else {
                    f64::INFINITY
                }
            }
        }
    }

    /// Unit vector from `p` towards the viewer.
    #[must_use]
    pub fn towards_viewer(&self, p: Vec3) -> Vec3 {
        match self.projection {
            Projection::Orthographic { .. } => -self.forward,
            Projection::Perspective { .. } => {
                let d = self.origin - p;
                let n = d.norm();
                if n > 0.0 { d / n } else { -self.forward }
            }
        }
    }

    /// The ray through the pixel position `(x, y)`: origin and unit direction. For an
    /// orthographic camera the origin lies in the plane through the view centre, so the ray
    /// parameter of a hit equals its depth key.
    #[must_use]
    pub fn ray(&self, x: f64, y: f64) -> (Vec3, Vec3) {
        match self.projection {
            Projection::Orthographic { scale } => {
                let u = (x - self.half_w) * scale;
                let v = (self.half_h - y) * scale * self.aspect;
                (self.origin + self.right * u + self.up * v, self.forward)
            }
            Projection::Perspective { focal, .. } => {
                let dir = self.forward
                    + self.right * ((x - self.half_w) / focal)
                    + self.up * ((self.half_h - y) * self.aspect / focal);
                (self.origin, dir.normalize())
            }
        }
    }

    /// The world point drawn at pixel position `(x, y)` with depth key `depth` (see
    /// [`Projected::depth`]): the inverse of [`Self::project`]. With the depth key of a point,
    /// it gives where that point would be if moved across the screen in the plane through it
    /// parallel to the view, which is how a hand drags a point.
    #[must_use]
    pub fn unproject(&self, x: f64, y: f64, depth: f64) -> Vec3 {
        match self.projection {
            Projection::Orthographic { .. } => {
                let (origin, _) = self.ray(x, y);
                origin + self.forward * depth
            }
            Projection::Perspective { focal, .. } => {
                let z = -1.0 / depth;
                let dir = self.forward
                    + self.right * ((x - self.half_w) / focal)
                    + self.up * ((self.half_h - y) * self.aspect / focal);
                self.origin + dir * z
            }
        }
    }

    /// The nearest distance a perspective camera draws, metres (0 for orthographic).
    #[must_use]
    pub fn near(&self) -> f64 {
        match self.projection {
            Projection::Orthographic { .. } => f64::NEG_INFINITY,
            Projection::Perspective { near, .. } => near,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_mesh::GridSpec;

    fn unit_box() -> Bounds {
        Bounds {
            min: Vec3::zeros(),
            max: Vec3::new(1.0, 1.0, 1.0),
        }
    }

    fn spec(view: View) -> ViewSpec {
        ViewSpec {
            margin: 0.0,
            ..ViewSpec::new(view, &ClothMesh::new(&GridSpec::default()).unwrap())
        }
    }

    #[test]
    fn side_view_puts_plus_x_right_and_plus_y_up() {
        let cam = Camera::new(&spec(View::Side), &unit_box(), 40, 20, 2.0).unwrap();
        let o = cam.project(Vec3::zeros()).unwrap();
        let x = cam.project(Vec3::x()).unwrap();
        let y = cam.project(Vec3::y()).unwrap();
        let z = cam.project(Vec3::z()).unwrap();
        assert!(x.x > o.x && (x.y - o.y).abs() < 1e-12);
        assert!(
            y.y < o.y,
            "screen rows grow downwards, so +y is a smaller row"
        );
        // Looking along -z: +z is nearer, at the same pixel.
        assert!(z.depth < o.depth && (z.x - o.x).abs() < 1e-12);
    }

    #[test]
    fn top_view_looks_down_with_plus_z_towards_the_bottom() {
        let cam = Camera::new(&spec(View::Top), &unit_box(), 40, 20, 2.0).unwrap();
        let o = cam.project(Vec3::zeros()).unwrap();
        assert!(cam.project(Vec3::x()).unwrap().x > o.x);
        assert!(cam.project(Vec3::z()).unwrap().y > o.y);
        assert!(
            cam.project(Vec3::y()).unwrap().depth < o.depth,
            "higher is nearer"
        );
    }

    #[test]
    fn fitting_fills_the_limiting_axis_and_corrects_the_cell_aspect() {
        // A 1 m cube in a 40 x 20 frame of cells twice as tall as wide: 20 rows are 40 widths
        // tall, the same as 40 columns, so both axes fill exactly.
        let cam = Camera::new(&spec(View::Side), &unit_box(), 40, 20, 2.0).unwrap();
        let a = cam.project(Vec3::zeros()).unwrap();
        let b = cam.project(Vec3::new(1.0, 1.0, 0.0)).unwrap();
        assert!((a.x - 0.0).abs() < 1e-9 && (b.x - 40.0).abs() < 1e-9);
        assert!((a.y - 20.0).abs() < 1e-9 && (b.y - 0.0).abs() < 1e-9);
        // With square pixels the rows limit: 20 rows for 1 m, so 1 m spans 20 columns, centred.
        let cam = Camera::new(&spec(View::Side), &unit_box(), 40, 20, 1.0).unwrap();
        let a = cam.project(Vec3::zeros()).unwrap();
        let b = cam.project(Vec3::new(1.0, 1.0, 0.0)).unwrap();
        assert!((a.x - 10.0).abs() < 1e-9 && (b.x - 30.0).abs() < 1e-9);
    }

    #[test]
    fn course_default_orbit_looks_along_minus_z_at_the_cloth() {
        let mesh = ClothMesh::new(&GridSpec::default()).unwrap();
        let s = ViewSpec {
            fit_orbit: false,
            ..spec(View::Orbit)
        };
        // Horizontal 1 m cloth at y = 1: target (0.5, 0.5, 0.5), eye 1.8 m further along +z.
        assert!((s.orbit.target - Vec3::new(0.5, 0.5, 0.5)).norm() < 1e-12);
        assert!((s.orbit.eye() - Vec3::new(0.5, 0.5, 2.3)).norm() < 1e-12);
        let cam = Camera::new(&s, &unit_box(), 80, 40, 2.0).unwrap();
        assert!((cam.forward() + Vec3::z()).norm() < 1e-12);
        let c = cam.project(s.orbit.target).unwrap();
        assert!((c.x - 40.0).abs() < 1e-9 && (c.y - 20.0).abs() < 1e-9);
        // The top of the 40 degree field: tan(20 deg) * 1.8 m above the target, at row 0.
        let top = s.orbit.target + Vec3::y() * (1.8 * 20f64.to_radians().tan());
        assert!(cam.project(top).unwrap().y.abs() < 1e-9);
        // Behind the camera nothing projects; depth keys grow with distance.
        assert!(cam.project(Vec3::new(0.5, 0.5, 3.0)).is_none());
        assert!(cam.depth_of(Vec3::new(0.5, 0.5, 0.0)) > cam.depth_of(Vec3::new(0.5, 0.5, 1.0)));
        let _ = mesh;
    }

    /// The pixel window a box's corners project into: `(min x, max x, min y, max y)`.
    fn window(cam: &Camera, b: &Bounds) -> (f64, f64, f64, f64) {
        let mut w = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for c in b.corners() {
            let p = cam.project(c).unwrap();
            w = (w.0.min(p.x), w.1.max(p.x), w.2.min(p.y), w.3.max(p.y));
        }
        w
    }

    #[test]
    fn a_fitted_orbit_frames_the_box_within_the_margin_and_fills_one_axis() {
        // Boxes flat, tall, deep and off the origin, seen along the course's direction and from
        // turned and raised cameras, in a wide and a tall frame of cells twice as tall as wide.
        let boxes = [
            unit_box(),
            Bounds {
                min: Vec3::new(-2.0, 0.0, 0.3),
                max: Vec3::new(1.0, 0.05, 0.4),
            },
            Bounds {
                min: Vec3::new(5.0, -3.0, -1.0),
                max: Vec3::new(5.5, 1.0, 2.0),
            },
        ];
        let margin = 0.1;
        for b in boxes {
            for (yaw, pitch) in [(0.0, 0.0), (0.7, 0.3), (-2.0, -1.2)] {
                for (w, h) in [(60, 20), (20, 40)] {
                    let mut s = spec(View::Orbit);
                    s.margin = margin;
                    s.extent = Extent::Fixed(b);
                    s.orbit.yaw = yaw;
                    s.orbit.pitch = pitch;
                    let cam = Camera::new(&s, &unit_box(), w, h, 2.0).unwrap();
                    let tag = format!("{b:?} yaw {yaw} pitch {pitch} {w}x{h}");
                    // The direction is the orbit's, whatever the box.
                    let dir = (s.orbit.target - s.orbit.eye()).normalize();
                    assert!((cam.forward() - dir).norm() < 1e-12, "{tag}");
                    let (x0, x1, y0, y1) = window(&cam, &b);
                    let (mx, my) = (margin * w as f64, margin * h as f64);
                    let eps = 1e-9;
                    assert!(
                        x0 >= mx - eps && x1 <= w as f64 - mx + eps,
                        "{tag}: x {x0} {x1}"
                    );
                    assert!(
                        y0 >= my - eps && y1 <= h as f64 - my + eps,
                        "{tag}: y {y0} {y1}"
                    );
                    // The eye is as near as the margin allows: one axis meets it on both
                    // sides, and the other is centred.
                    let fills_x = (x0 - mx).abs() < 1e-6 && (x1 - (w as f64 - mx)).abs() < 1e-6;
                    let fills_y = (y0 - my).abs() < 1e-6 && (y1 - (h as f64 - my)).abs() < 1e-6;
                    assert!(fills_x || fills_y, "{tag}: {x0} {x1} {y0} {y1}");
                    let centred = |a: f64, b: f64, n: usize| (a + b - n as f64).abs() < 1e-6;
                    assert!(centred(x0, x1, w) && centred(y0, y1, h), "{tag}");
                    // The orbit turns about the box's middle along the line of sight.
                    let o = s.orbit_in(&unit_box(), w, h, 2.0);
                    let mid = 0.5 * (b.min + b.max);
                    assert!(((o.target - mid).dot(&dir)).abs() < 1e-9, "{tag}");
                }
            }
        }
    }

    #[test]
    fn the_default_orbit_looks_along_the_course_direction_at_its_content() {
        let mut s = spec(View::Orbit);
        s.margin = 0.04;
        let b = Bounds {
            min: Vec3::new(0.0, -0.5, 0.0),
            max: Vec3::new(1.0, 1.0, 1.0),
        };
        let cam = Camera::new(&s, &b, 80, 40, 2.0).unwrap();
        assert!((cam.forward() + Vec3::z()).norm() < 1e-12);
        let (x0, x1, y0, y1) = window(&cam, &b);
        assert!(x0 > 0.0 && x1 < 80.0 && y0 > 0.0 && y1 < 40.0);
        // Unfitted, the same spec draws the orbit as given.
        s.fit_orbit = false;
        assert_eq!(s.orbit_in(&b, 80, 40, 2.0), s.orbit);
    }

    #[test]
    fn a_fitted_orbit_keeps_at_least_one_and_a_half_cells_of_border() {
        let s = ViewSpec::new(View::Orbit, &ClothMesh::new(&GridSpec::default()).unwrap());
        // 4 % of 20 rows is 0.8 rows: raised to 1.5 / 20; 4 % of 200 rows is kept.
        assert!((s.orbit_margin(60, 20) - 0.075).abs() < 1e-12);
        assert!((s.orbit_margin(400, 200) - 0.04).abs() < 1e-12);
        assert!((s.orbit_margin(8, 2) - 0.45).abs() < 1e-12);
    }

    #[test]
    fn rays_pass_through_the_pixels_they_start_from() {
        for view in View::ALL {
            let cam = Camera::new(&spec(view), &unit_box(), 40, 20, 2.0).unwrap();
            let (o, d) = cam.ray(13.5, 7.5);
            let p = cam.project(o + d * 2.0).unwrap();
            assert!(
                (p.x - 13.5).abs() < 1e-9 && (p.y - 7.5).abs() < 1e-9,
                "{view}"
            );
        }
    }

    #[test]
    fn unknown_views_and_bad_orbits_are_named() {
        assert_eq!("TOP".parse::<View>(), Ok(View::Top));
        let e = "diagonal".parse::<View>().unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown view 'diagonal'; expected side, top, bottom, front or orbit"
        );
        let mut s = spec(View::Orbit);
        s.orbit.distance = 0.0;
        assert!(matches!(
            Camera::new(&s, &unit_box(), 40, 20, 2.0),
            Err(RenderError::BadOption {
                name: "orbit distance",
                ..
            })
        ));
    }
}
