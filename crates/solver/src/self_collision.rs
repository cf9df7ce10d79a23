//! Self-collision through a spatial hash (step 3 of the course's step).

use cloth_mesh::{ClothMesh, Vec3};

/// A spatial hash of the cloth's points in boxes of `3 * width / nw` by `3 * height / nh` by the
/// larger of the two, exactly the course's boxes, so the same pairs of points interact.
///
/// The course keys a `std::unordered_map` by a float hash of the box; we key by the box's integer
/// coordinates, sorted once per step, which groups the same points without float-hash collisions
/// and without allocating once the arrays have grown.
#[derive(Debug, Default, Clone)]
pub struct SpatialHash {
    /// `(box key, point index)`, sorted: each box's points are contiguous, in index order.
    entries: Vec<(u64, u32)>,
    /// For each point, the `[start, end)` range of its box in `entries`.
    range_of: Vec<(u32, u32)>,
}

impl SpatialHash {
    /// Box sizes `(w, h, t)` for `mesh`, metres.
    #[must_use]
    pub fn box_size(mesh: &ClothMesh) -> (f64, f64, f64) {
        let spec = mesh.spec();
        let w = 3.0 * spec.width / mesh.nw() as f64;
        let h = 3.0 * spec.height / mesh.nh() as f64;
        (w, h, w.max(h))
    }

    fn key(p: &Vec3, (w, h, t): (f64, f64, f64)) -> u64 {
        // 21 bits per axis, offset so negative boxes stay distinct; a box index beyond +-2^20
        // (a cloth a million boxes away) wraps, which only merges far-apart boxes: harmless,
        // the distance test still rejects the pairs.
        let q = |v: f64, s: f64| ((v / s).floor() as i64).wrapping_add(1 << 20) as u64 & 0x1F_FFFF;
        (q(p.x, w) << 42) | (q(p.y, h) << 21) | q(p.z, t)
    }

    /// Rebuilds the hash from `positions`.
    pub fn rebuild(&mut self, mesh: &ClothMesh, positions: &[Vec3]) {
        let size = Self::box_size(mesh);
        self.entries.clear();
        self.entries.extend(
            positions
                .iter()
                .enumerate()
                .map(|(i, p)| (Self::key(p, size), i as u32)),
        );
        self.entries.sort_unstable();
        self.range_of.resize(positions.len(), (0, 0));
        let mut start = 0;
        while start < self.entries.len() {
            let key = self.entries[start].0;
            let mut end = start + 1;
            while end < self.entries.len() && self.entries[end].0 == key {
                end += 1;
            }
            for &(_, i) in &self.entries[start..end] {
                self.range_of[i as usize] = (start as u32, end as u32);
            }
            start = end;
        }
    }

    /// The points in point `i`'s box (including `i`), in index order, as of the last rebuild.
    pub fn box_of(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let (s, e) = self.range_of[i];
        self.entries[s as usize..e as usize]
            .iter()
            .map(|&(_, j)| j as usize)
    }

    /// Pushes every unpinned point away from the other points of its box that are closer than
    /// `2 * thickness`, by the average correction divided by `steps_per_frame`.
    ///
    /// Points are treated in index order and each one sees the already-corrected positions of
    /// those before it, as in the course; the hash itself is built before any correction.
    pub fn resolve(&mut self, mesh: &ClothMesh, positions: &mut [Vec3], steps_per_frame: u32) {
        self.rebuild(mesh, positions);
        let reach = 2.0 * mesh.thickness();
        let steps = f64::from(steps_per_frame);
        for i in 0..positions.len() {
            if mesh.pinned()[i] {
                continue;
            }
            let (s, e) = self.range_of[i];
            if e - s < 2 {
                continue;
            }
            let p = positions[i];
            let mut correction = Vec3::zeros();
            let mut count = 0u32;
            for &(_, j) in &self.entries[s as usize..e as usize] {
                let j = j as usize;
                if j == i {
                    continue;
                }
                let d = p - positions[j];
                let dist = d.norm();
                // NOTE: coincident points (dist == 0) have no direction to separate along; the
                // course would produce NaN here, we skip the pair.
                if dist < reach && dist > 0.0 {
                    correction += d * ((reach - dist) / dist);
                    count += 1;
                }
            }
            if count > 0 {
                positions[i] = p + correction / f64::from(count) / steps;
            }
        }
    }
}
