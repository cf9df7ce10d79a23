//! Provot's maximum-stretch constraint (step 5 of the course's step).

use std::ops::Range;

use cloth_mesh::{ClothMesh, Spring, Vec3};

use crate::self_collision::dist2;

/// Shortens every spring longer than `ratio * rest` back to exactly that length, in one
/// in-place sweep in spring order (later springs see earlier corrections, as in the course).
///
/// Each end moves half the excess along the spring's current direction, or the free end moves
/// all of it when the other is pinned; springs with both ends pinned are left alone.
/// Compression is not limited. Every spring type is limited, enabled or not.
pub fn limit_stretch(springs: &[Spring], pinned: &[bool], positions: &mut [Vec3], ratio: f64) {
    for s in springs {
        limit_one(s.a as usize, s.b as usize, s.rest, pinned, positions, ratio);
    }
}

/// The course's correction of one spring from `a` to `b`; true when it was over the limit (and
/// so may have moved its ends).
///
/// Generic over how the positions are reached ([`Points`]) so the threaded sweeps use the very
/// same correction as the sequential ones.
#[inline]
pub(crate) fn limit_one<P: Points + ?Sized>(
    a: usize,
    b: usize,
    rest: f64,
    pinned: &[bool],
    positions: &mut P,
    ratio: f64,
) -> bool {
    let (pa, pb) = (positions.at(a), positions.at(b));
    let d = pb - pa;
    let len2 = dist2(&d);
    let max = ratio * rest;
    // NOTE: most springs are inside the limit; `len2 <= max^2 (1 - 4 eps)` proves it without the
    // square root. It is exact: the computed bound is at most the real max^2 (its rounding is
    // within the 4-ulp margin), so the real length is <= max, and so is the correctly rounded
    // sqrt, because `max` is representable and rounding is monotone.
    if len2 <= inside_bound(max) {
        return false;
    }
    let len = len2.sqrt();
    if len <= max {
        return false;
    }
    let excess = d * ((len - max) / len);
    match (pinned[a], pinned[b]) {
        (true, true) => {}
        (true, false) => positions.put(b, pb - excess),
        (false, true) => positions.put(a, pa + excess),
        (false, false) => {
            let half = excess * 0.5;
            positions.put(a, pa + half);
            positions.put(b, pb - half);
        }
    }
    true
}

/// Positions that a stretch correction reads and writes by point index.
pub(crate) trait Points {
    /// Point `i`'s position.
    fn at(&self, i: usize) -> Vec3;
    /// Moves point `i` to `p`.
    fn put(&mut self, i: usize, p: Vec3);
}

impl Points for [Vec3] {
    #[inline]
    fn at(&self, i: usize) -> Vec3 {
        self[i]
    }
    #[inline]
    fn put(&mut self, i: usize, p: Vec3) {
        self[i] = p;
    }
}

/// Squared lengths up to this bound are certainly within `max` (see [`limit_one`]).
///
/// NOTE: one definition for the sequential check and the vectorised pre-pass of the Verlet
/// solver's sweep: both must make the same decision for the same positions, bit for bit.
#[inline(always)]
#[allow(clippy::inline_always)]
pub(crate) fn inside_bound(max: f64) -> f64 {
    max * max * (1.0 - 4.0 * f64::EPSILON)
}

/// The stretch limit's sweep cut into row bands that threads can share
/// ([`ConstraintOrder::Parallel`]).
///
/// Springs are emitted row by row and reach at most two rows back, so the springs of a run of rows
/// are a contiguous part of the spring list and touch only those rows and the two before. The rows
/// are cut into blocks separated by two-row seams: the blocks touch disjoint points and are swept
/// at once, each in spring order (by the Verlet solver's sweep, `verlet/limit.rs`); then the seams
/// (also disjoint from each other) are swept at once. Every spring is visited exactly once and
/// corrected exactly as in the course; only a seam's springs come after the block above them
/// instead of before.
///
/// NOTE: the cut depends only on the mesh (at most [`StretchBands::BLOCKS`] blocks), never on the
/// thread count, so results are the same on any number of threads.
///
/// [`ConstraintOrder::Parallel`]: crate::ConstraintOrder::Parallel
#[derive(Debug, Default, Clone)]
pub(crate) struct StretchBands {
    /// Blocks, then seams, each in increasing order of points.
    blocks: Vec<Band>,
    seams: Vec<Band>,
}

/// A band of the stretch limit's sweep.
#[derive(Debug, Clone)]
pub(crate) struct Band {
    /// The rows whose points emit its springs.
    pub(crate) rows: Range<usize>,
    /// The points its springs touch.
    pub(crate) points: Range<usize>,
}

impl StretchBands {
    /// The most blocks a sweep is cut into: enough to keep a few threads busy, few enough that
    /// the seams (swept after their neighbours) stay a small part of the cloth.
    pub(crate) const BLOCKS: usize = 8;

    /// Cuts `mesh`'s rows into at most [`Self::BLOCKS`] blocks of at least 4 rows.
    pub(crate) fn new(mesh: &ClothMesh) -> Self {
        let (nw, nh) = (mesh.nw(), mesh.nh());
        let band = |r0: usize, r1: usize| Band {
            rows: r0..r1,
            points: r0.saturating_sub(2) * nw..r1 * nw,
        };
        // Blocks of at least 4 rows: block k + 1 then keeps seams k and k + 1 apart (each seam
        // reaches two rows into the block after it).
        let blocks = (nh / 6).clamp(1, Self::BLOCKS);
        let block_rows = nh - 2 * (blocks - 1);
        let (mut out, mut seams) = (Vec::new(), Vec::new());
        let mut start = 0;
        for k in 0..blocks {
            let end = start + block_rows / blocks + usize::from(k < block_rows % blocks);
            out.push(band(start, end));
            if k + 1 < blocks {
                seams.push(band(end, end + 2));
            }
            start = end + 2;
        }
        Self { blocks: out, seams }
    }

    /// The blocks, then the seams: the bands of each list touch disjoint points, and the
    /// lists are swept one after the other.
    pub(crate) fn phases(&self) -> [&[Band]; 2] {
        [&self.blocks, &self.seams]
    }

    /// The most bands of one phase.
    pub(crate) fn widest(&self) -> usize {
        self.blocks.len().max(self.seams.len())
    }
}

/// Runs `sweep` on each of the disjoint `bands` (in increasing order of points) with its own
/// `state` and its window of `positions` (which starts at point `offset`); halves run in
/// parallel when `parallel`. Recursion rather than a list of slices, so nothing is allocated.
pub(crate) fn for_each_band<S: Send>(
    bands: &[Band],
    states: &mut [S],
    positions: &mut [Vec3],
    offset: usize,
    parallel: bool,
    sweep: &(impl Fn(&Band, &mut S, &mut [Vec3]) + Sync),
) {
    match (bands, states) {
        ([], _) | (_, []) => {}
        ([b], [state, ..]) => sweep(
            b,
            state,
            &mut positions[b.points.start - offset..b.points.end - offset],
        ),
        (_, states) => {
            let mid = bands.len() / 2;
            let (left, right) = bands.split_at(mid);
            let (left_states, right_states) = states.split_at_mut(mid.min(states.len()));
            let split = right[0].points.start;
            let (lo, hi) = positions.split_at_mut(split - offset);
            let mut run_left = || for_each_band(left, left_states, lo, offset, parallel, sweep);
            let mut run_right = || for_each_band(right, right_states, hi, split, parallel, sweep);
            if parallel {
                rayon::join(run_left, run_right);
            } else {
                run_left();
                run_right();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_mesh::SpringKind;

    fn spring(rest: f64) -> Spring {
        Spring {
            a: 1,
            b: 0,
            rest,
            kind: SpringKind::Structural,
        }
    }

    #[test]
    fn an_overstretched_spring_ends_at_exactly_the_limit_and_a_short_one_is_untouched() {
        let mut p = vec![Vec3::zeros(), Vec3::new(0.3, 0.4, 0.0)];
        limit_stretch(&[spring(0.4)], &[false, false], &mut p, 1.1);
        // Length 0.5 > 0.44: both ends move 0.03 towards each other, along the spring.
        assert!(((p[1] - p[0]).norm() - 0.44).abs() < 1e-15);
        assert!((p[0] - Vec3::new(0.018, 0.024, 0.0)).norm() < 1e-15);
        let before = p.clone();
        limit_stretch(&[spring(0.41)], &[false, false], &mut p, 1.1);
        assert_eq!(p, before);
    }

    #[test]
    fn a_spring_just_at_the_limit_is_not_moved() {
        // The skip-without-sqrt bound must not swallow springs a rounding error over the limit,
        // nor touch one exactly at it.
        let rest = 1.0 / 49.0;
        let max = 1.1 * rest;
        let mut p = vec![Vec3::zeros(), Vec3::new(max, 0.0, 0.0)];
        limit_stretch(&[spring(rest)], &[false, false], &mut p, 1.1);
        assert_eq!(p[1].x - p[0].x, max);
        let over = f64::from_bits(max.to_bits() + 1);
        let mut p = vec![Vec3::zeros(), Vec3::new(over, 0.0, 0.0)];
        limit_stretch(&[spring(rest)], &[true, false], &mut p, 1.1);
        assert_eq!(
            p[1].x, max,
            "one ulp over: the free end comes back to the limit"
        );
    }
}
