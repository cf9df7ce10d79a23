//! The z-buffered triangle and line rasteriser.
//!
//! Triangles are scan-converted with integer edge functions on vertices snapped to 1/256 pixel
//! and the top-left fill rule, so two triangles sharing an edge cover every pixel centre along it
//! exactly once: no holes, no double hits. Depth keys and shades are interpolated linearly in
//! screen space (exact for depth keys, which [`crate::Camera`] makes screen-linear).

use crate::Projected;

/// Sub-pixel steps per pixel for snapping.
const SUB: f64 = 256.0;
/// Vertices further than this from the origin (pixels) are not drawn: the fixed-point products
/// must stay inside `i64`, and nothing that far off-screen can matter.
const LIMIT: f64 = (1u64 << 20) as f64;

/// What a pixel shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum Material {
    /// Nothing: background.
    #[default]
    Empty,
    /// The cloth's front face (its normals point at the viewer).
    Front,
    /// The cloth's back face.
    Back,
    /// A sphere.
    Sphere,
    /// A floor tile of the first colour.
    FloorA,
    /// A floor tile of the second colour.
    FloorB,
    /// A floor seen edge-on.
    FloorEdge,
}

/// Which pixels a line may write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LineFill {
    /// Any pixel where it is nearer than what is there.
    Nearer,
    /// Only pixels where nothing is drawn yet (lines that must never hide anything).
    Empty,
    /// Pixels where it is nearer than what is there, except the cloth's own: the outline of a
    /// cloth already drawn, filling only the pixels its triangles left out.
    Outline,
}

/// The pixel buffers a frame is drawn into.
pub(crate) struct Target<'a> {
    pub width: usize,
    pub height: usize,
    pub depth: &'a mut [f64],
    pub material: &'a mut [Material],
    pub shade: &'a mut [f32],
}

impl Target<'_> {
    /// Writes a sample if it is nearer than what is there.
    #[inline]
    pub fn plot(&mut self, x: usize, y: usize, depth: f64, material: Material, shade: f32) {
        let i = y * self.width + x;
        if depth < self.depth[i] {
            self.depth[i] = depth;
            self.material[i] = material;
            self.shade[i] = shade;
        }
    }

    /// Fills the triangle `v` with `material`, interpolating the per-vertex shades `s`.
    /// Returns how many pixel centres it covers (drawn or hidden).
    pub fn triangle(&mut self, v: [Projected; 3], s: [f32; 3], material: Material) -> usize {
        if v.iter().any(|p| !(p.x.abs() < LIMIT && p.y.abs() < LIMIT)) {
            return 0;
        }
        // NOTE: truncation rather than rounding (no libm call); any rule works as long as a
        // vertex shared by two triangles snaps to the same point in both, which it does.
        let snap = |p: &Projected| ((p.x * SUB) as i64, (p.y * SUB) as i64);
        let (p0, mut p1, mut p2) = (snap(&v[0]), snap(&v[1]), snap(&v[2]));
        let (v0, mut v1, mut v2) = (v[0], v[1], v[2]);
        let (s0, mut s1, mut s2) = (s[0], s[1], s[2]);
        let mut area = edge(p0, p1, p2);
        if area == 0 {
            return 0;
        }
        if area < 0 {
            std::mem::swap(&mut p1, &mut p2);
            std::mem::swap(&mut v1, &mut v2);
            std::mem::swap(&mut s1, &mut s2);
            area = -area;
        }
        let sub = SUB as i64;
        let min_x = (p0.0.min(p1.0).min(p2.0).div_euclid(sub)).max(0);
        let min_y = (p0.1.min(p1.1).min(p2.1).div_euclid(sub)).max(0);
        let max_x = (p0.0.max(p1.0).max(p2.0).div_euclid(sub)).min(self.width as i64 - 1);
        let max_y = (p0.1.max(p1.1).max(p2.1).div_euclid(sub)).min(self.height as i64 - 1);
        if min_x > max_x || min_y > max_y {
            return 0;
        }
        // Top-left rule: a pixel centre exactly on an edge belongs to the triangle only when the
        // edge is a top or left edge, which a bias of -1 on the other edges implements.
        let bias = |a: (i64, i64), b: (i64, i64)| {
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            if dy < 0 || (dy == 0 && dx > 0) { 0 } else { -1 }
        };
        let (b0, b1, b2) = (bias(p1, p2), bias(p2, p0), bias(p0, p1));
        let start = (min_x * sub + sub / 2, min_y * sub + sub / 2);
        let mut row0 = edge(p1, p2, start);
        let mut row1 = edge(p2, p0, start);
        let mut row2 = edge(p0, p1, start);
        // Stepping one pixel right changes an edge function by -(dy) * SUB, one down by dx * SUB.
        let (sx0, sx1, sx2) = (
            -(p2.1 - p1.1) * sub,
            -(p0.1 - p2.1) * sub,
            -(p1.1 - p0.1) * sub,
        );
        let (sy0, sy1, sy2) = (
            (p2.0 - p1.0) * sub,
            (p0.0 - p2.0) * sub,
            (p1.0 - p0.0) * sub,
        );
        let inv = 1.0 / area as f64;
        let mut covered = 0;
        for y in min_y..=max_y {
            let (mut w0, mut w1, mut w2) = (row0, row1, row2);
            for x in min_x..=max_x {
                if w0 + b0 >= 0 && w1 + b1 >= 0 && w2 + b2 >= 0 {
                    let (l0, l1, l2) = (w0 as f64 * inv, w1 as f64 * inv, w2 as f64 * inv);
                    let depth = l0 * v0.depth + l1 * v1.depth + l2 * v2.depth;
                    let shade = (l0 as f32) * s0 + (l1 as f32) * s1 + (l2 as f32) * s2;
                    self.plot(x as usize, y as usize, depth, material, shade);
                    covered += 1;
                }
                w0 += sx0;
                w1 += sx1;
                w2 += sx2;
            }
            row0 += sy0;
            row1 += sy1;
            row2 += sy2;
        }
        covered
    }

    /// Draws a line from `a` to `b` into every pixel it passes through, one sample per pixel
    /// step, interpolating depth and shade; `fill` says which pixels it may write. Used for
    /// triangles too thin to cover a pixel centre (a cloth seen edge-on), so a sheet never
    /// vanishes between pixel rows, and for the cloth's outline, so its border covers every
    /// pixel it runs through (see `draw_cloth`).
    pub fn line(
        &mut self,
        a: Projected,
        b: Projected,
        sa: f32,
        sb: f32,
        material: Material,
        fill: LineFill,
    ) {
        if [a, b]
            .iter()
            .any(|p| !(p.x.abs() < LIMIT && p.y.abs() < LIMIT))
        {
            return;
        }
        // One sample per pixel step along the longer axis (truncation + 1 is a cheap ceiling).
        let steps = (b.x - a.x).abs().max((b.y - a.y).abs()) as usize + 1;
        for i in 0..=steps {
            let t = i as f64 / steps as f64;
            let (x, y) = (a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t);
            if x < 0.0 || y < 0.0 {
                continue;
            }
            let (xi, yi) = (x as usize, y as usize);
            if xi >= self.width || yi >= self.height {
                continue;
            }
            let depth = a.depth + (b.depth - a.depth) * t;
            let shade = sa + (sb - sa) * t as f32;
            let k = yi * self.width + xi;
            let write = match fill {
                LineFill::Nearer => depth < self.depth[k],
                LineFill::Empty => self.material[k] == Material::Empty,
                LineFill::Outline => {
                    depth < self.depth[k]
                        && !matches!(self.material[k], Material::Front | Material::Back)
                }
            };
            if write {
                self.depth[k] = depth;
                self.material[k] = material;
                self.shade[k] = shade;
            }
        }
    }
}

/// Twice the signed area of `(a, b, p)`: positive when `p` is on the inner side of `a -> b`
/// for the orientation the rasteriser uses.
#[inline]
fn edge(a: (i64, i64), b: (i64, i64), p: (i64, i64)) -> i64 {
    (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Buffers {
        depth: Vec<f64>,
        material: Vec<Material>,
        shade: Vec<f32>,
    }

    impl Buffers {
        fn new(n: usize) -> Self {
            Self {
                depth: vec![f64::INFINITY; n],
                material: vec![Material::Empty; n],
                shade: vec![0.0; n],
            }
        }
        fn target(&mut self, width: usize, height: usize) -> Target<'_> {
            Target {
                width,
                height,
                depth: &mut self.depth,
                material: &mut self.material,
                shade: &mut self.shade,
            }
        }
    }

    fn p(x: f64, y: f64, depth: f64) -> Projected {
        Projected { x, y, depth }
    }

    #[test]
    fn a_split_square_is_covered_exactly_once_without_holes() {
        // Two triangles sharing an irrational-looking diagonal across a 17 x 13 grid: every
        // pixel centre inside the square is covered by exactly one of them (top-left rule).
        let (w, h) = (17, 13);
        let mut hits = vec![0u8; w * h];
        let corners = [
            p(0.3, 0.7, 0.0),
            p(16.6, 0.2, 0.0),
            p(16.9, 12.8, 0.0),
            p(0.1, 12.4, 0.0),
        ];
        for tri in [[0, 1, 2], [0, 2, 3]] {
            let mut b = Buffers::new(w * h);
            let mut t = b.target(w, h);
            t.triangle(tri.map(|i| corners[i]), [1.0; 3], Material::Front);
            for (k, m) in b.material.iter().enumerate() {
                hits[k] += u8::from(*m != Material::Empty);
            }
        }
        // Pixels whose centre is well inside the quad (away from its outer edges by a pixel).
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                assert_eq!(hits[y * w + x], 1, "pixel ({x}, {y})");
            }
        }
    }

    #[test]
    fn the_nearer_triangle_wins_whatever_the_drawing_order() {
        let near = [p(0.0, 0.0, 1.0), p(10.0, 0.0, 1.0), p(0.0, 10.0, 1.0)];
        let far = [p(0.0, 0.0, 2.0), p(10.0, 0.0, 2.0), p(0.0, 10.0, 2.0)];
        let near = (near, 0.25, Material::Front);
        let far = (far, 0.75, Material::Back);
        for order in [[near, far], [far, near]] {
            let mut b = Buffers::new(100);
            let mut t = b.target(10, 10);
            for (tri, shade, material) in order {
                t.triangle(tri, [shade; 3], material);
            }
            // (1, 1) is inside both; the near one (depth 1, shade 0.25, front) shows.
            assert_eq!(b.material[11], Material::Front);
            assert_eq!(b.shade[11], 0.25);
            assert_eq!(b.depth[11], 1.0);
        }
    }

    #[test]
    fn depth_is_interpolated_across_a_tilted_triangle() {
        // Depth = x / 10 across the triangle; at pixel centre (4.5, 1.5) it is 0.45.
        let tri = [p(0.0, 0.0, 0.0), p(10.0, 0.0, 1.0), p(0.0, 10.0, 0.0)];
        let mut b = Buffers::new(100);
        b.target(10, 10).triangle(tri, [0.0; 3], Material::Front);
        assert!((b.depth[14] - 0.45).abs() < 1e-3);
    }

    #[test]
    fn edge_on_and_off_screen_triangles_draw_nothing_and_do_not_panic() {
        let mut b = Buffers::new(100);
        let mut t = b.target(10, 10);
        t.triangle(
            [p(0.0, 5.0, 0.0), p(5.0, 5.0, 0.0), p(9.0, 5.0, 0.0)],
            [1.0; 3],
            Material::Front,
        );
        t.triangle(
            [
                p(-50.0, -50.0, 0.0),
                p(-40.0, -50.0, 0.0),
                p(-50.0, -40.0, 0.0),
            ],
            [1.0; 3],
            Material::Front,
        );
        t.triangle(
            [p(1e30, 0.0, 0.0), p(0.0, 1e30, 0.0), p(f64::NAN, 0.0, 0.0)],
            [1.0; 3],
            Material::Front,
        );
        assert!(b.material.iter().all(|m| *m == Material::Empty));
        // A line covers the edge-on triangle's pixels instead.
        let mut t = b.target(10, 10);
        t.line(
            p(0.0, 5.5, 0.0),
            p(9.9, 5.5, 0.0),
            1.0,
            1.0,
            Material::Front,
            LineFill::Nearer,
        );
        assert!((0..10).all(|x| b.material[50 + x] == Material::Front));
    }
}
