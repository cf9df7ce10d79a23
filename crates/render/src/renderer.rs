//! The renderer: cloth state + colliders + camera -> [`AsciiFrame`].

use cloth_mesh::{ClothMesh, ClothState, Vec3, vertex_normals};
use cloth_mesh::{Collider, Plane, Sphere};

use crate::bounds::plane_basis;
use crate::glyphs::{
    BACK_RAMP, FLOOR_GLYPH, FRONT_RAMP, HAND_GLYPH, PIN_GLYPH, SPHERE_RAMP, bayer_threshold,
    ramp_glyph,
};
use crate::raster::{LineFill, Material, Target};
use crate::{
    AsciiFrame, Bounds, Camera, Cell, Extent, Light, Mode, Projected, RenderError, RenderOptions,
    Rgb, View, ViewSpec,
};

/// Pins hidden by at most this fraction of the scene's diagonal still show: a pin lies on the
/// surface it is drawn over, so only a real fold in front of it should hide it.
const PIN_DEPTH_TOLERANCE: f64 = 0.02;

/// Owns every buffer a frame needs (depth, materials, shades, normals, projected vertices), so
/// rendering allocates nothing once the first frame of a given size has been drawn.
#[derive(Debug, Default, Clone)]
pub struct Renderer {
    /// The camera of the last frame drawn, its pixels per cell and its width in pixels: what
    /// [`Renderer::surface_at`] reads the depth buffer with.
    last: Option<(Camera, (usize, usize), usize)>,
    normals: Vec<Vec3>,
    screen: Vec<Option<Projected>>,
    vertex_shade: Vec<[f32; 2]>,
    depth: Vec<f64>,
    material: Vec<Material>,
    shade: Vec<f32>,
}

/// What the lights need, fixed for one frame.
struct Lighting {
    light: Light,
    direction: Vec3,
    ambient: f64,
    diffuse: f64,
    fill: f64,
}

impl Lighting {
    fn new(o: &RenderOptions) -> Self {
        let direction = match o.light {
            Light::Direction(d) => d.normalize(),
            Light::Point(_) => Vec3::y(),
        };
        Self {
            light: o.light,
            direction,
            ambient: o.ambient,
            diffuse: o.diffuse,
            fill: o.fill,
        }
    }

    /// Unit vector from `p` to the light.
    fn towards_light(&self, p: Vec3) -> Vec3 {
        match self.light {
            Light::Direction(_) => self.direction,
            Light::Point(lp) => {
                let d = lp - p;
                let n = d.norm();
                if n > 0.0 { d / n } else { Vec3::y() }
            }
        }
    }

    /// Lambert key light plus headlight plus ambient, clamped to [0, 1].
    fn intensity(&self, n: Vec3, l: Vec3, v: Vec3) -> f32 {
        let i = self.ambient + self.diffuse * n.dot(&l).max(0.0) + self.fill * n.dot(&v).max(0.0);
        i.clamp(0.0, 1.0) as f32
    }
}

impl Renderer {
    /// A renderer with empty buffers; they grow on the first frame.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Bytes a renderer's buffers and the frame it fills take, for a cloth of `points` points
    /// drawn into a frame of `cells` character cells in `mode`: per point a normal, a
    /// projected vertex and its shades; per pixel a depth, a material and a shade; per cell
    /// the frame's cell.
    #[must_use]
    pub fn memory_estimate(points: usize, cells: usize, mode: Mode) -> u64 {
        let (sx, sy) = mode.pixels_per_cell();
        let per_point = size_of::<Vec3>() + size_of::<Option<Projected>>() + size_of::<[f32; 2]>();
        let per_pixel = size_of::<f64>() + size_of::<Material>() + size_of::<f32>();
        let per_cell = size_of::<Cell>();
        let pixels = cells.saturating_mul(sx * sy);
        (points as u64)
            .saturating_mul(per_point as u64)
            .saturating_add((pixels as u64).saturating_mul(per_pixel as u64))
            .saturating_add((cells as u64).saturating_mul(per_cell as u64))
    }

    /// Draws `state` of `mesh` with its `colliders` as seen by `view` into `frame`, at the
    /// frame's size.
    ///
    /// # Errors
    /// [`RenderError::StateMismatch`] when the state is not the mesh's,
    /// [`RenderError::NonFinite`] for a NaN or infinite position, [`RenderError::BadOption`] for
    /// an option or camera out of range.
    pub fn render(
        &mut self,
        mesh: &ClothMesh,
        state: &ClothState,
        colliders: &[Collider],
        view: &ViewSpec,
        options: &RenderOptions,
        frame: &mut AsciiFrame,
    ) -> Result<(), RenderError> {
        options.validate()?;
        let positions = &state.positions;
        if positions.len() != mesh.len() {
            return Err(RenderError::StateMismatch {
                positions: positions.len(),
                points: mesh.len(),
            });
        }
        let shown: &[Collider] = if options.show_colliders {
            colliders
        } else {
            &[]
        };
        let solid = Bounds::of_solids(positions, shown)?;
        let content = solid.with_floors(&solid, shown);
        let patch_source = match view.extent {
            Extent::Auto => solid,
            Extent::Fixed(b) => b,
        };
        let (sx, sy) = options.mode.pixels_per_cell();
        let (pw, ph) = (frame.width() * sx, frame.height() * sy);
        let aspect = options.cell_aspect * sx as f64 / sy as f64;
        let orbit_spec;
        let fitting = if view.view == View::Orbit && view.fit_orbit && view.margin.is_finite() {
            orbit_spec = ViewSpec {
                margin: view.orbit_margin(frame.width(), frame.height()),
                ..*view
            };
            &orbit_spec
        } else {
            view
        };
        let camera = Camera::new(fitting, &content, pw, ph, aspect)?;
        self.last = Some((camera, (sx, sy), pw));
        let lighting = Lighting::new(options);

        // NOTE: clear + resize keeps the capacity, so after the first frame of a size nothing
        // here allocates.
        let n = pw * ph;
        self.depth.clear();
        self.depth.resize(n, f64::INFINITY);
        self.material.clear();
        self.material.resize(n, Material::Empty);
        self.shade.clear();
        self.shade.resize(n, 0.0);

        vertex_normals(mesh, positions, &mut self.normals);
        self.screen.clear();
        self.vertex_shade.clear();
        for (p, nrm) in positions.iter().zip(&self.normals) {
            self.screen.push(camera.project(*p));
            let (l, v) = (lighting.towards_light(*p), camera.towards_viewer(*p));
            self.vertex_shade.push([
                lighting.intensity(*nrm, l, v),
                lighting.intensity(-nrm, l, v),
            ]);
        }

        let mut target = Target {
            width: pw,
            height: ph,
            depth: &mut self.depth,
            material: &mut self.material,
            shade: &mut self.shade,
        };
        draw_cloth(
            &mut target,
            mesh,
            &self.screen,
            &self.vertex_shade,
            &Faces {
                positions,
                camera: &camera,
                two_sided: options.two_sided,
            },
        );
        for c in shown {
            match c {
                Collider::Sphere(s) => draw_sphere(&mut target, &camera, s, &lighting),
                Collider::Plane(p) => draw_floor(&mut target, &camera, p, &patch_source),
            }
        }

        // NOTE: the outline is drawn after the contrast stretch, with its mapping: it adds
        // pixels along the border only, and must not shift the glyphs of the whole face.
        let mut mapping = [None, None];
        if options.auto_contrast {
            for (map, face) in mapping.iter_mut().zip([Material::Front, Material::Back]) {
                *map = stretch(face, &self.material, &mut self.shade);
            }
        }
        let mut target = Target {
            width: pw,
            height: ph,
            depth: &mut self.depth,
            material: &mut self.material,
            shade: &mut self.shade,
        };
        let faces = Faces {
            positions,
            camera: &camera,
            two_sided: options.two_sided,
        };
        draw_outline(
            &mut target,
            mesh,
            &self.screen,
            &self.vertex_shade,
            &faces,
            mapping,
        );
        compose(frame, options, &self.material, &self.shade, pw);
        if options.show_pins {
            let tol = PIN_DEPTH_TOLERANCE * content.diagonal();
            for (i, _) in mesh.pinned().iter().enumerate().filter(|(_, p)| **p) {
                let Some(p) = self.screen[i] else { continue };
                if !(p.x >= 0.0 && p.y >= 0.0 && p.x < pw as f64 && p.y < ph as f64) {
                    continue;
                }
                let (px, py) = (p.x as usize, p.y as usize);
                // Depth keys of a perspective camera are -1/z, so a distance tol is tol/z^2.
                let key_tol = if camera.is_perspective() {
                    tol * p.depth * p.depth
                } else {
                    tol
                };
                if p.depth <= self.depth[py * pw + px] + key_tol {
                    let fg = options.color.then_some(PIN_COLOUR);
                    if let Some(cell) = frame.get_mut(px / sx, py / sy) {
                        *cell = Cell {
                            glyph: PIN_GLYPH,
                            fg,
                            bg: None,
                        };
                    }
                }
            }
        }
        if let Some(hand) = options.hand
            && let Some(p) = camera.project(hand)
            && p.x >= 0.0
            && p.y >= 0.0
            && p.x < pw as f64
            && p.y < ph as f64
        {
            // NOTE: the held point is on the surface drawn over it; the pins' tolerance lets
            // only a real fold in front hide it.
            let (px, py) = (p.x as usize, p.y as usize);
            let tol = PIN_DEPTH_TOLERANCE * content.diagonal();
            let key_tol = if camera.is_perspective() {
                tol * p.depth * p.depth
            } else {
                tol
            };
            if p.depth <= self.depth[py * pw + px] + key_tol
                && let Some(cell) = frame.get_mut(px / sx, py / sy)
            {
                *cell = Cell {
                    glyph: HAND_GLYPH,
                    fg: options.color.then_some(HAND_COLOUR),
                    bg: None,
                };
            }
        }
        if options.legend {
            draw_legend(frame, view);
        }
        Ok(())
    }

    /// The camera of the last frame drawn.
    #[must_use]
    pub fn camera(&self) -> Option<&Camera> {
        self.last.as_ref().map(|(c, _, _)| c)
    }

    /// The point of the cloth seen at cell `(column, row)` of the last frame drawn, m: of the
    /// cloth's pixels in the cell, the nearest to the viewer (so what is in front is what is
    /// picked), or, when the cell shows no cloth, of the cells around it (a cursor is a cell
    /// wide, a thin strand of cloth may miss its centre). `None` when no cloth is there or
    /// nothing was drawn.
    #[must_use]
    pub fn surface_at(&self, column: usize, row: usize) -> Option<Vec3> {
        let &(ref camera, (sx, sy), pw) = self.last.as_ref()?;
        let ph = self.depth.len().checked_div(pw)?;
        let nearest_in = |cx: usize, cy: usize| -> Option<(f64, usize, usize)> {
            let mut best: Option<(f64, usize, usize)> = None;
            for py in cy * sy..((cy + 1) * sy).min(ph) {
                for px in cx * sx..((cx + 1) * sx).min(pw) {
                    let i = py * pw + px;
                    if matches!(self.material[i], Material::Front | Material::Back)
                        && best.is_none_or(|(d, _, _)| self.depth[i] < d)
                    {
                        best = Some((self.depth[i], px, py));
                    }
                }
            }
            best
        };
        let hit = nearest_in(column, row).or_else(|| {
            let mut around = None;
            for (dx, dy) in [
                (-1, 0),
                (1, 0),
                (0, -1),
                (0, 1),
                (-1, -1),
                (1, -1),
                (-1, 1),
                (1, 1),
            ] {
                let (Some(cx), Some(cy)) =
                    (column.checked_add_signed(dx), row.checked_add_signed(dy))
                else {
                    continue;
                };
                if let Some(h) = nearest_in(cx, cy)
                    && around.is_none_or(|(d, _, _)| h.0 < d)
                {
                    around = Some(h);
                }
            }
            around
        })?;
        let (depth, px, py) = hit;
        Some(camera.unproject(px as f64 + 0.5, py as f64 + 0.5, depth))
    }
}

/// Bins of the shade histogram used by [`stretch`].
const BINS: usize = 64;
/// Fraction of a face's pixels allowed below the low end (and above the high end) of the stretch.
const CLIP: f64 = 0.02;
/// Smallest shade range stretched to the full ramp: at most a 4x magnification, so a flat,
/// evenly lit sheet stays flat instead of showing amplified rounding.
const MIN_RANGE: f32 = 0.25;

/// Remaps the shades of `face`'s pixels so their 2nd to 98th percentile fills [0, 1]; returns
/// the mapping, `(lo, range)` for `(s - lo) / range`, or `None` when the face has no pixels.
fn stretch(face: Material, material: &[Material], shade: &mut [f32]) -> Option<(f32, f32)> {
    let mut hist = [0u32; BINS];
    let mut count = 0u32;
    for (m, s) in material.iter().zip(shade.iter()) {
        if *m == face {
            hist[(s.clamp(0.0, 1.0) * (BINS - 1) as f32 + 0.5) as usize] += 1;
            count += 1;
        }
    }
    if count == 0 {
        return None;
    }
    let cut = (f64::from(count) * CLIP) as u32;
    let percentile = |bins: &mut dyn Iterator<Item = usize>| {
        let mut seen = 0;
        for b in bins {
            seen += hist[b];
            if seen > cut {
                return b as f32 / (BINS - 1) as f32;
            }
        }
        0.0
    };
    let lo = percentile(&mut (0..BINS));
    let hi = percentile(&mut (0..BINS).rev());
    // A narrow range (a flat, evenly lit sheet) is centred on the middle of the ramp, where
    // small variations can show both ways, instead of pinned to an end of it.
    let range = (hi - lo).max(MIN_RANGE);
    let lo = f32::midpoint(lo, hi) - range / 2.0;
    for (m, s) in material.iter().zip(shade.iter_mut()) {
        if *m == face {
            *s = ((*s - lo) / range).clamp(0.0, 1.0);
        }
    }
    Some((lo, range))
}

/// Colour of a pin marker.
const PIN_COLOUR: Rgb = Rgb(255, 70, 70);
/// The held point's colour: apart from the pins' red and the cloth's shades.
const HAND_COLOUR: Rgb = Rgb(255, 220, 40);

/// What decides which face of the cloth a triangle shows.
struct Faces<'a> {
    positions: &'a [Vec3],
    camera: &'a Camera,
    two_sided: bool,
}

impl Faces<'_> {
    /// The face triangle `a b c` shows, by its geometric normal against the direction to the
    /// viewer, and its index in the vertex shades; `None` for a back face not drawn.
    fn of(&self, a: usize, b: usize, c: usize) -> Option<(Material, usize)> {
        let (wa, wb, wc) = (self.positions[a], self.positions[b], self.positions[c]);
        let normal = (wb - wa).cross(&(wc - wa));
        let towards = self.camera.towards_viewer((wa + wb + wc) / 3.0);
        if normal.dot(&towards) >= 0.0 {
            Some((Material::Front, 0))
        } else if self.two_sided {
            Some((Material::Back, 1))
        } else {
            None
        }
    }
}

/// Rasterises every cloth triangle, choosing the face it shows ([`Faces::of`]); triangles
/// thinner than a pixel also get their edges drawn, so a sheet seen edge-on stays a visible
/// line instead of falling between pixel centres.
fn draw_cloth(
    target: &mut Target<'_>,
    mesh: &ClothMesh,
    screen: &[Option<Projected>],
    vertex_shade: &[[f32; 2]],
    faces: &Faces<'_>,
) {
    for &[a, b, c] in mesh.triangles() {
        let (a, b, c) = (a as usize, b as usize, c as usize);
        let (Some(pa), Some(pb), Some(pc)) = (screen[a], screen[b], screen[c]) else {
            continue;
        };
        let Some((material, k)) = faces.of(a, b, c) else {
            continue;
        };
        let s = [vertex_shade[a][k], vertex_shade[b][k], vertex_shade[c][k]];
        let v = [pa, pb, pc];
        let covered = target.triangle(v, s, material);
        // A triangle whose smallest altitude (twice its area over its longest side) is under a
        // pixel can fall between pixel centres; if it did, its longest edge, which lies within
        // a pixel of all of it, is drawn as a line.
        if covered == 0 {
            let area2 = (pb.x - pa.x) * (pc.y - pa.y) - (pb.y - pa.y) * (pc.x - pa.x);
            let side2 = |i: usize, j: usize| (v[j].x - v[i].x).powi(2) + (v[j].y - v[i].y).powi(2);
            let (mut i, mut j, mut longest2) = (0, 1, side2(0, 1));
            for (a, b) in [(1, 2), (2, 0)] {
                let l = side2(a, b);
                if l > longest2 {
                    (i, j, longest2) = (a, b, l);
                }
            }
            if area2 * area2 < longest2 {
                target.line(v[i], v[j], s[i], s[j], material, LineFill::Nearer);
            }
        }
    }
}

/// Draws the cloth's border (the edges along the grid's first and last rows and columns) as
/// lines into the pixels it passes through that its triangles left to the background, each in
/// the face of its triangle, its shades remapped by `mapping` (the front's and the back's
/// contrast stretch, when there was one).
///
/// NOTE: a triangle covers the pixels whose centres it contains (with the top-left rule on its
/// edges), which leaves a pixel the border passes through empty whenever the border runs
/// between the pixel's centre and the cloth. An edge of the grid that lies along a pixel row
/// (a pinned edge in the top view) runs within a hair of the row's centres, on one side or the
/// other as it sags, so the row came out dashed. Inside the cloth every pixel centre lies in
/// some triangle: only the border needs the pixels it passes through.
fn draw_outline(
    target: &mut Target<'_>,
    mesh: &ClothMesh,
    screen: &[Option<Projected>],
    vertex_shade: &[[f32; 2]],
    faces: &Faces<'_>,
    mapping: [Option<(f32, f32)>; 2],
) {
    let (nw, nh) = (mesh.nw(), mesh.nh());
    // Whether `a -> b` is an edge of the border: neighbours along the first or last row or
    // column.
    let border = |a: usize, b: usize| {
        let ((xa, ya), (xb, yb)) = ((a % nw, a / nw), (b % nw, b / nw));
        (ya == yb && (ya == 0 || ya == nh - 1) && xa.abs_diff(xb) == 1)
            || (xa == xb && (xa == 0 || xa == nw - 1) && ya.abs_diff(yb) == 1)
    };
    for &[a, b, c] in mesh.triangles() {
        let t = [a as usize, b as usize, c as usize];
        for (i, j) in [(0, 1), (1, 2), (2, 0)] {
            let (p, q) = (t[i], t[j]);
            if !border(p, q) {
                continue;
            }
            let (Some(pp), Some(pq)) = (screen[p], screen[q]) else {
                continue;
            };
            let Some((material, k)) = faces.of(t[0], t[1], t[2]) else {
                continue;
            };
            let map = |s: f32| match mapping[k] {
                Some((lo, range)) => ((s - lo) / range).clamp(0.0, 1.0),
                None => s,
            };
            let (sp, sq) = (map(vertex_shade[p][k]), map(vertex_shade[q][k]));
            target.line(pp, pq, sp, sq, material, LineFill::Outline);
        }
    }
}

/// The projected pixel box of `corners`, clipped to the target; the whole target when a
/// corner is behind the camera.
fn pixel_box(
    target: &Target<'_>,
    camera: &Camera,
    corners: &[Vec3],
) -> (usize, usize, usize, usize) {
    let (mut x0, mut y0, mut x1, mut y1) = (
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    );
    for c in corners {
        let Some(p) = camera.project(*c) else {
            return (0, 0, target.width, target.height);
        };
        x0 = x0.min(p.x);
        y0 = y0.min(p.y);
        x1 = x1.max(p.x);
        y1 = y1.max(p.y);
    }
    let clip = |v: f64, hi: usize| v.clamp(0.0, hi as f64) as usize;
    (
        clip(x0.floor(), target.width),
        clip(y0.floor(), target.height),
        clip(x1.ceil() + 1.0, target.width),
        clip(y1.ceil() + 1.0, target.height),
    )
}

/// The sphere is drawn at this fraction of its collision radius, as the course does: cloth
/// points rest on the true surface, but the flat triangles between them cut chords into it, so a
/// full-size sphere would poke through a cloth draped over it.
const SPHERE_DRAW_SCALE: f64 = 0.92;

/// Ray-casts a sphere at every pixel centre of its projected box, shading the hit with the
/// sphere's exact normal. Depth-tested against the cloth like any other surface.
fn draw_sphere(target: &mut Target<'_>, camera: &Camera, s: &Sphere, lighting: &Lighting) {
    let radius = s.radius * SPHERE_DRAW_SCALE;
    let r = Vec3::repeat(radius);
    let cube = Bounds {
        min: s.origin - r,
        max: s.origin + r,
    };
    let (x0, y0, x1, y1) = pixel_box(target, camera, &cube.corners());
    for y in y0..y1 {
        for x in x0..x1 {
            let (o, d) = camera.ray(x as f64 + 0.5, y as f64 + 0.5);
            let oc = o - s.origin;
            let b = oc.dot(&d);
            let disc = b * b - (oc.dot(&oc) - radius * radius);
            if disc < 0.0 {
                continue;
            }
            let root = disc.sqrt();
            // The first hit in front of the camera (the second when the camera is inside).
            for t in [-b - root, -b + root] {
                let hit = o + d * t;
                let depth = camera.depth_of(hit);
                if depth.is_finite() {
                    let n = (hit - s.origin) / radius;
                    let shade = lighting.intensity(
                        n,
                        lighting.towards_light(hit),
                        camera.towards_viewer(hit),
                    );
                    target.plot(x, y, depth, Material::Sphere, shade);
                    break;
                }
            }
        }
    }
}

/// Draws a plane as a checkered floor patch under `over` (ray-cast per pixel, tiles of a
/// power-of-ten size fixed in world space so they do not swim), plus its outline when seen
/// nearly edge-on. The outline only fills empty pixels: a cloth resting on the floor, seen
/// edge-on in the same pixel row, must stay visible.
fn draw_floor(target: &mut Target<'_>, camera: &Camera, plane: &Plane, over: &Bounds) {
    let n = plane.normal;
    let corners = Bounds::floor_patch(over, plane.point, n);
    let (u, v) = plane_basis(n);
    let coord = |p: Vec3| ((p - plane.point).dot(&u), (p - plane.point).dot(&v));
    let (a0, b0) = coord(corners[0]);
    let (a1, b1) = coord(corners[2]);
    let tile = 10f64.powf(((a1 - a0).max(b1 - b0) / 4.0).log10().floor());
    let (x0, y0, x1, y1) = pixel_box(target, camera, &corners);
    for y in y0..y1 {
        for x in x0..x1 {
            let (o, d) = camera.ray(x as f64 + 0.5, y as f64 + 0.5);
            let denom = d.dot(&n);
            if denom.abs() < 1e-12 {
                continue;
            }
            let hit = o + d * ((plane.point - o).dot(&n) / denom);
            let (a, b) = coord(hit);
            if !(a0..=a1).contains(&a) || !(b0..=b1).contains(&b) {
                continue;
            }
            let depth = camera.depth_of(hit);
            if !depth.is_finite() {
                continue;
            }
            let parity = ((a / tile).floor() + (b / tile).floor()).rem_euclid(2.0);
            let material = if parity < 0.5 {
                Material::FloorA
            } else {
                Material::FloorB
            };
            target.plot(x, y, depth, material, 0.5);
        }
    }
    if !camera.is_perspective() && n.dot(&camera.forward()).abs() < 0.2 {
        for i in 0..4 {
            let (Some(p), Some(q)) = (
                camera.project(corners[i]),
                camera.project(corners[(i + 1) % 4]),
            ) else {
                continue;
            };
            target.line(p, q, 0.5, 0.5, Material::FloorEdge, LineFill::Empty);
        }
    }
}

/// The glyph of a pixel in ascii mode.
fn glyph(material: Material, shade: f32, x: usize, y: usize) -> char {
    match material {
        Material::Empty | Material::FloorB => ' ',
        Material::Front => ramp_glyph(FRONT_RAMP, shade, x, y),
        Material::Back => ramp_glyph(BACK_RAMP, shade, x, y),
        Material::Sphere => ramp_glyph(SPHERE_RAMP, shade, x, y),
        Material::FloorA | Material::FloorEdge => FLOOR_GLYPH,
    }
}

/// The decorative colour of a pixel: a warm front, a cool back, a green sphere, grey floors.
fn colour(material: Material, shade: f32) -> Option<Rgb> {
    let scaled = |base: (f32, f32, f32)| {
        let k = 0.3 + 0.7 * shade.clamp(0.0, 1.0);
        Rgb(
            (base.0 * k + 0.5) as u8,
            (base.1 * k + 0.5) as u8,
            (base.2 * k + 0.5) as u8,
        )
    };
    match material {
        Material::Empty => None,
        Material::Front => Some(scaled((250.0, 190.0, 120.0))),
        Material::Back => Some(scaled((120.0, 170.0, 250.0))),
        Material::Sphere => Some(scaled((150.0, 220.0, 150.0))),
        Material::FloorA => Some(Rgb(120, 120, 120)),
        Material::FloorB => Some(Rgb(60, 60, 60)),
        Material::FloorEdge => Some(Rgb(150, 150, 150)),
    }
}

/// Whether a pixel counts as drawn when only glyph shapes show (floor gaps do not).
fn covered(material: Material) -> bool {
    !matches!(material, Material::Empty | Material::FloorB)
}

/// Turns the pixel buffers into cells for the frame's mode.
fn compose(
    frame: &mut AsciiFrame,
    options: &RenderOptions,
    material: &[Material],
    shade: &[f32],
    pw: usize,
) {
    let (w, h) = (frame.width(), frame.height());
    let pick = |m: Material, s: f32| if options.color { colour(m, s) } else { None };
    for cy in 0..h {
        for cx in 0..w {
            let cell = match options.mode {
                Mode::Ascii => {
                    let i = cy * pw + cx;
                    Cell {
                        glyph: glyph(material[i], shade[i], cx, cy),
                        fg: pick(material[i], shade[i]),
                        bg: None,
                    }
                }
                Mode::Half => {
                    let (i, j) = (2 * cy * pw + cx, (2 * cy + 1) * pw + cx);
                    half_cell(
                        (material[i], shade[i]),
                        (material[j], shade[j]),
                        options.color,
                        (cx, cy),
                    )
                }
                Mode::Braille => {
                    // Dot bits of U+2800 by (column, row) within the 2 x 4 cell.
                    const BITS: [[u32; 4]; 2] =
                        [[0x01, 0x02, 0x04, 0x40], [0x08, 0x10, 0x20, 0x80]];
                    let mut bits = 0;
                    let mut fg = None;
                    for (dx, column) in BITS.iter().enumerate() {
                        for (dy, bit) in column.iter().enumerate() {
                            let (px, py) = (2 * cx + dx, 4 * cy + dy);
                            let i = py * pw + px;
                            let level = match material[i] {
                                Material::Empty | Material::FloorB => 0.0,
                                Material::FloorA => 0.2,
                                Material::FloorEdge => 1.0,
                                // Lift shadows so a dark surface keeps a few dots and never
                                // reads as empty background.
                                _ => 0.2 + 0.8 * shade[i],
                            };
                            if level > bayer_threshold(px, py) {
                                bits |= bit;
                                if fg.is_none() {
                                    fg = pick(material[i], shade[i]);
                                }
                            }
                        }
                    }
                    Cell {
                        glyph: char::from_u32(0x2800 + bits).unwrap_or(' '),
                        fg,
                        bg: None,
                    }
                }
            };
            if let Some(c) = frame.get_mut(cx, cy) {
                *c = cell;
            }
        }
    }
}

/// Shade blocks, darkest first: a half-block cell without colour covered top and bottom.
pub const SHADE_BLOCKS: &[char] = &['░', '▒', '▓', '█'];

/// One half-block cell from its upper and lower pixel (material, shade) at cell `at`.
///
/// With colour, each half takes its pixel's colour. Without, a half-covered cell is its half
/// block, and a covered one a shade block ([`SHADE_BLOCKS`], dithered) of the two pixels'
/// mean shade, so the cloth keeps its shading rather than becoming a flat silhouette.
fn half_cell(
    (mu, su): (Material, f32),
    (ml, sl): (Material, f32),
    color: bool,
    (cx, cy): (usize, usize),
) -> Cell {
    if color {
        match (colour(mu, su), colour(ml, sl)) {
            (None, None) => Cell::BLANK,
            (Some(u), l) => Cell {
                glyph: '\u{2580}',
                fg: Some(u),
                bg: l,
            },
            (None, Some(l)) => Cell {
                glyph: '\u{2584}',
                fg: Some(l),
                bg: None,
            },
        }
    } else {
        let glyph = match (covered(mu), covered(ml)) {
            (false, false) => ' ',
            (true, false) => '\u{2580}',
            (false, true) => '\u{2584}',
            // NOTE: lifted like braille's dots, so a dark surface never reads as empty.
            (true, true) => ramp_glyph(SHADE_BLOCKS, 0.2 + 0.8 * 0.5 * (su + sl), cx, cy),
        };
        Cell {
            glyph,
            fg: None,
            bg: None,
        }
    }
}

/// A three-line axis legend in the bottom-left corner of an orthographic view, when it fits.
fn draw_legend(frame: &mut AsciiFrame, view: &ViewSpec) {
    let Some((up, right)) = view.view.axis_labels() else {
        return;
    };
    let h = frame.height();
    if h < 12 || frame.width() < 20 {
        return;
    }
    frame.put_str(0, h - 3, up, None);
    frame.put_str(0, h - 2, "|", None);
    frame.put_str(0, h - 1, "+--", None);
    frame.put_str(3, h - 1, right, None);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{FrameSize, View};
    use cloth_mesh::GridSpec;

    fn flat_cloth() -> (ClothMesh, ClothState) {
        let mesh = ClothMesh::new(&GridSpec {
            num_width_points: 11,
            num_height_points: 11,
            pinned: vec![(0, 0), (10, 0)],
            ..GridSpec::default()
        })
        .unwrap();
        let state = ClothState::new(&mesh);
        (mesh, state)
    }

    fn draw(
        mesh: &ClothMesh,
        state: &ClothState,
        colliders: &[Collider],
        view: View,
        options: &RenderOptions,
    ) -> AsciiFrame {
        let mut frame = AsciiFrame::new(FrameSize::new(40, 20).unwrap());
        Renderer::new()
            .render(
                mesh,
                state,
                colliders,
                &ViewSpec::new(view, mesh),
                options,
                &mut frame,
            )
            .unwrap();
        frame
    }

    fn glyphs(frame: &AsciiFrame) -> String {
        frame.to_plain()
    }

    #[test]
    fn a_flat_cloth_seen_from_above_fills_its_square_with_front_glyphs() {
        let (mesh, state) = flat_cloth();
        let frame = draw(&mesh, &state, &[], View::Top, &RenderOptions::default());
        // A 1 m square in a 40 x 20 frame of 2:1 cells with a 4 % margin: 1 m spans
        // 40 * 0.92 = 36.8 columns and 18.4 rows, so every cell of columns 3..37, rows 1..19 is
        // cloth and, seen from its normal's side, front face. No holes anywhere inside.
        for y in 1..19 {
            for x in 3..37 {
                let g = frame.get(x, y).unwrap().glyph;
                assert!(
                    FRONT_RAMP.contains(&g) || g == PIN_GLYPH,
                    "({x}, {y}) = {g:?}\n{}",
                    glyphs(&frame)
                );
            }
        }
        // The border runs through the cells it passes (row 0 from 0.8 rows down, column 1 from
        // 1.6 columns in); the margin beyond it stays empty.
        assert!(
            (2..38).all(|x| FRONT_RAMP.contains(&frame.get(x, 0).unwrap().glyph)
                || frame.get(x, 0).unwrap().glyph == PIN_GLYPH),
            "{}",
            glyphs(&frame)
        );
        assert!((0..20).all(|y| frame.get(0, y).unwrap().glyph == ' '));
        assert!((0..40).all(|x| frame.get(x, 19).unwrap().glyph != ' ' || !(2..38).contains(&x)));
    }

    #[test]
    fn from_below_the_same_cloth_shows_its_back_face() {
        let (mesh, state) = flat_cloth();
        let frame = draw(&mesh, &state, &[], View::Bottom, &RenderOptions::default());
        let g = frame.get(20, 10).unwrap().glyph;
        assert!(BACK_RAMP.contains(&g), "{g:?}");
        let one_sided = RenderOptions {
            two_sided: false,
            show_pins: false,
            ..RenderOptions::default()
        };
        let frame = draw(&mesh, &state, &[], View::Bottom, &one_sided);
        assert!(
            frame.cells().iter().all(|c| c.glyph == ' '),
            "back faces culled"
        );
    }

    #[test]
    fn a_cloth_seen_exactly_edge_on_is_still_a_line() {
        // The flat cloth at y = 1 seen from the side has zero projected area; thin triangles
        // are drawn as lines, so it shows as one full row of 0.92 * 40 columns.
        let (mesh, state) = flat_cloth();
        let frame = draw(&mesh, &state, &[], View::Side, &RenderOptions::default());
        let drawn = frame.cells().iter().filter(|c| c.glyph != ' ').count();
        assert!((36..=40).contains(&drawn), "{drawn}\n{}", glyphs(&frame));
    }

    #[test]
    fn a_sphere_in_front_hides_the_cloth_and_one_behind_is_hidden() {
        let (mesh, state) = flat_cloth();
        let options = RenderOptions::default();
        // Seen from above, a sphere above the cloth's centre hides it; one below is hidden.
        for (y, expect_sphere) in [(1.5, true), (0.5, false)] {
            let ball = Collider::Sphere(Sphere {
                origin: Vec3::new(0.5, y, 0.5),
                radius: 0.2,
                friction: 0.0,
            });
            let frame = draw(&mesh, &state, &[ball], View::Top, &options);
            let g = frame.get(20, 10).unwrap().glyph;
            assert_eq!(
                SPHERE_RAMP.contains(&g),
                expect_sphere,
                "{g:?}\n{}",
                glyphs(&frame)
            );
            assert_eq!(FRONT_RAMP.contains(&g), !expect_sphere);
        }
    }

    #[test]
    fn shading_follows_the_normals_towards_the_light() {
        // With only a key light straight down the top view, a cloth facing up is lit fully and a
        // cloth tilted by 60 degrees gets cos 60 = 1/2: the glyph levels differ accordingly.
        let (mesh, state) = flat_cloth();
        let options = RenderOptions {
            light: Light::Direction(Vec3::y()),
            ambient: 0.0,
            fill: 0.0,
            diffuse: 1.0,
            auto_contrast: false,
            show_pins: false,
            ..RenderOptions::default()
        };
        let level = |frame: &AsciiFrame| {
            let g = frame.get(20, 10).unwrap().glyph;
            FRONT_RAMP.iter().position(|r| *r == g).unwrap()
        };
        let flat = draw(&mesh, &state, &[], View::Top, &options);
        assert_eq!(level(&flat), FRONT_RAMP.len() - 1);
        // Rotate the cloth 60 degrees about x: y' = z sin, z' = z cos.
        let (s, c) = (60f64.to_radians().sin(), 60f64.to_radians().cos());
        let mut tilted = state.clone();
        for p in &mut tilted.positions {
            *p = Vec3::new(p.x, 1.0 + p.z * s, p.z * c);
        }
        let frame = draw(&mesh, &tilted, &[], View::Top, &options);
        // 0.5 * 8 = level 4 exactly; the dither may round either way by at most one.
        assert!((3..=5).contains(&level(&frame)), "{}", level(&frame));
    }

    #[test]
    fn a_pinned_edge_seen_from_the_top_has_no_gaps_at_200x60() {
        // A 50 x 50 cloth pinned at the two ends of its first row, that row pulled inwards by
        // up to 3 mm as a sagging cloth pulls it (0.17 rows at this size): the edge then runs
        // just past the centres of the pixel row it lies in, and the cloth must still cover
        // that row from pin to pin.
        let mesh = ClothMesh::new(&GridSpec {
            pinned: vec![(0, 0), (49, 0)],
            ..GridSpec::default()
        })
        .unwrap();
        let mut state = ClothState::new(&mesh);
        for i in 0..50 {
            state.positions[i].z += 0.003 * (std::f64::consts::PI * i as f64 / 49.0).sin();
        }
        let mut frame = AsciiFrame::new(FrameSize::new(200, 60).unwrap());
        Renderer::new()
            .render(
                &mesh,
                &state,
                &[],
                &ViewSpec::new(View::Top, &mesh),
                &RenderOptions::default(),
                &mut frame,
            )
            .unwrap();
        let pins: Vec<(usize, usize)> = (0..60)
            .flat_map(|y| (0..200).map(move |x| (x, y)))
            .filter(|&(x, y)| frame.get(x, y).unwrap().glyph == PIN_GLYPH)
            .collect();
        assert_eq!(pins.len(), 2, "{pins:?}\n{}", glyphs(&frame));
        let (y, x0, x1) = (pins[0].1, pins[0].0, pins[1].0);
        let gaps: Vec<usize> = (x0..x1)
            .filter(|&x| frame.get(x, y).unwrap().glyph == ' ')
            .collect();
        assert!(
            gaps.is_empty(),
            "gaps at columns {gaps:?}\n{}",
            glyphs(&frame)
        );
    }

    #[test]
    fn pins_are_marked_where_they_are() {
        let (mesh, state) = flat_cloth();
        let frame = draw(&mesh, &state, &[], View::Top, &RenderOptions::default());
        let pins: Vec<(usize, usize)> = (0..20)
            .flat_map(|y| (0..40).map(move |x| (x, y)))
            .filter(|&(x, y)| frame.get(x, y).unwrap().glyph == PIN_GLYPH)
            .collect();
        // Pins at (0, 0) and (10, 0): x = 0 and 1 m, z = 0, which the top view puts at the top
        // (z grows downwards) edge, 20 * 0.04 = 0.8 rows down, so in row 0; 36.8 columns apart.
        assert_eq!(pins.len(), 2, "{pins:?}");
        assert!(pins.iter().all(|&(_, y)| y == 0));
        assert!((36..=38).contains(&(pins[1].0 - pins[0].0)));
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let (mesh, mut state) = flat_cloth();
        let mut frame = AsciiFrame::with_size(40, 20).unwrap();
        let mut r = Renderer::new();
        let view = ViewSpec::new(View::Side, &mesh);
        state.positions[7].y = f64::NAN;
        assert_eq!(
            r.render(
                &mesh,
                &state,
                &[],
                &view,
                &RenderOptions::default(),
                &mut frame
            ),
            Err(RenderError::NonFinite { index: 7 })
        );
        state.positions.pop();
        assert!(matches!(
            r.render(
                &mesh,
                &state,
                &[],
                &view,
                &RenderOptions::default(),
                &mut frame
            ),
            Err(RenderError::StateMismatch { .. })
        ));
        let (mesh, state) = flat_cloth();
        let bad = RenderOptions {
            cell_aspect: 0.0,
            ..RenderOptions::default()
        };
        let e = r
            .render(&mesh, &state, &[], &view, &bad, &mut frame)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "cell_aspect is 0, but it must be between 0.25 and 8 (cell height / width)"
        );
    }

    #[test]
    fn every_mode_and_view_fills_exactly_the_frame() {
        let (mesh, state) = flat_cloth();
        let floor = Collider::Plane(Plane {
            point: Vec3::zeros(),
            normal: Vec3::y(),
            friction: 0.5,
        });
        for mode in Mode::ALL {
            for view in View::ALL {
                let options = RenderOptions {
                    mode,
                    ..RenderOptions::default()
                };
                let frame = draw(&mesh, &state, &[floor], view, &options);
                let text = frame.to_plain();
                assert_eq!(text.lines().count(), 20);
                assert!(text.lines().all(|l| l.chars().count() == 40));
                assert!(
                    frame
                        .cells()
                        .iter()
                        .any(|c| c.glyph != ' ' && c.glyph != '\u{2800}')
                );
            }
        }
    }

    /// The nearest point of `positions` to `at`.
    fn nearest(positions: &[Vec3], at: Vec3) -> usize {
        (0..positions.len())
            .min_by(|&a, &b| {
                (positions[a] - at)
                    .norm()
                    .total_cmp(&(positions[b] - at).norm())
            })
            .unwrap()
    }

    #[test]
    fn every_camera_unprojects_what_it_projects() {
        let (mesh, _) = flat_cloth();
        let content = Bounds {
            min: Vec3::zeros(),
            max: Vec3::new(1.0, 1.0, 1.0),
        };
        for view in [
            View::Side,
            View::Top,
            View::Front,
            View::Bottom,
            View::Orbit,
        ] {
            let camera = Camera::new(&ViewSpec::new(view, &mesh), &content, 80, 40, 2.0).unwrap();
            for p in [
                Vec3::new(0.3, 0.9, 0.2),
                Vec3::new(0.5, 0.5, 0.5),
                Vec3::new(1.0, 0.1, 0.8),
            ] {
                let q = camera.project(p).unwrap();
                let back = camera.unproject(q.x, q.y, q.depth);
                assert!((back - p).norm() < 1e-12, "{view}: {p} came back as {back}");
            }
        }
    }

    #[test]
    fn the_surface_under_a_cell_is_the_layer_in_front() {
        // pinned4's grid with its right half folded over its left, 5 cm above it.
        let mesh = ClothMesh::pinned_grid(50).unwrap();
        let mut state = ClothState::new(&mesh);
        for p in &mut state.positions {
            if p.x > 0.5 {
                *p = Vec3::new(1.0 - p.x, 1.05, p.z);
            }
        }
        let options = RenderOptions::default();
        let size = FrameSize::new(60, 30).unwrap();
        for (view, upper) in [(View::Top, true), (View::Bottom, false)] {
            let mut frame = AsciiFrame::new(size);
            let mut r = Renderer::new();
            let spec = ViewSpec::new(view, &mesh);
            r.render(&mesh, &state, &[], &spec, &options, &mut frame)
                .unwrap();
            let camera = *r.camera().unwrap();
            // The cell over the point (0.25, z = 0.5) of the left half.
            let q = camera.project(Vec3::new(0.25, 1.0, 0.5)).unwrap();
            let (sx, sy) = options.mode.pixels_per_cell();
            let (col, row) = (q.x as usize / sx, q.y as usize / sy);
            let at = r.surface_at(col, row).unwrap();
            let expected_y = if upper { 1.05 } else { 1.0 };
            assert!((at.y - expected_y).abs() < 1e-9, "{view}: {at}");
            let picked = nearest(&state.positions, at);
            let column = picked % mesh.nw();
            assert_eq!(column > 24, upper, "{view}: picked column {column}");
            // Off the cloth: nothing.
            assert_eq!(r.surface_at(0, 0), None, "{view}");
        }
    }

    #[test]
    fn a_sphere_in_front_hides_the_cloth_from_the_hand_and_the_held_point_is_marked() {
        let (mesh, state) = flat_cloth();
        let centre = state.positions[mesh.index(5, 5)];
        let hand = RenderOptions {
            hand: Some(centre),
            ..RenderOptions::default()
        };
        let frame = draw(&mesh, &state, &[], View::Top, &hand);
        assert_eq!(glyphs(&frame).matches(HAND_GLYPH).count(), 1);
        // A ball above the centre, seen from above, covers it.
        let ball = Collider::Sphere(Sphere {
            origin: centre + Vec3::new(0.0, 0.3, 0.0),
            radius: 0.2,
            friction: 0.0,
        });
        let frame = draw(&mesh, &state, &[ball], View::Top, &hand);
        assert_eq!(glyphs(&frame).matches(HAND_GLYPH).count(), 0);
        let mut r = Renderer::new();
        let mut frame = AsciiFrame::new(FrameSize::new(40, 20).unwrap());
        let spec = ViewSpec::new(View::Top, &mesh);
        r.render(&mesh, &state, &[ball], &spec, &hand, &mut frame)
            .unwrap();
        let q = r.camera().unwrap().project(centre).unwrap();
        assert_eq!(r.surface_at(q.x as usize, q.y as usize), None);
    }
}
