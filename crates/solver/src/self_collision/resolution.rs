//! The resolution: every unpinned point pushed away from the other points of its box closer
//! than `2 * thickness`, box by box, each box's points in index order.

use cloth_mesh::{ClothMesh, Vec3};

use super::memory::{ANCHOR_WAIT, FOLLOW2, MAX_STRIKES, Memory};
use super::{PARALLEL_CHUNK, SpatialHash, dist2};
use crate::disjoint::Disjoint;

impl SpatialHash {
    /// [`SpatialHash::resolve`] with its boxes shared out among `pool`'s threads when there is
    /// one: the same corrections, bit for bit, on any number of threads.
    pub(crate) fn resolve_in(
        &mut self,
        mesh: &ClothMesh,
        positions: &mut [Vec3],
        steps_per_frame: u32,
        pool: Option<&rayon::ThreadPool>,
    ) {
        self.rebuild_in(mesh, positions, pool);
        let repulsion = Repulsion::new(mesh, steps_per_frame);
        // NOTE: a point's correction reads only the points of its own box, and only the
        // points of that box write them, so boxes are independent: sweeping box by box, each
        // box's points in index order, makes exactly the corrections of the course's sweep over
        // all points in index order. That lets a box with no pair within reach at the start of
        // the pass (most of them) be skipped after one look at each pair, half the work of
        // asking every point about every other; a box whose points have barely moved since it
        // was last found clear is skipped without even that (see `Repulsion::allowance`); and
        // threads can take whole boxes.
        // The boxes correct `sorted` (their own contiguous runs), on the pool's threads when
        // there is one, and mark themselves when they moved a point; then the points of the
        // marked boxes (few) take their positions back from their slots.
        let cells = self.start.len() - 1;
        self.touched.clear();
        self.touched.resize(cells, false);
        self.anchor.resize(positions.len(), Vec3::zeros());
        self.sorted.resize(positions.len(), Vec3::zeros());
        let boxes = Boxes {
            repulsion: &repulsion,
            pinned: mesh.pinned(),
            start: &self.start,
            members: &self.members,
            positions,
            anchors: Disjoint::new(&mut self.anchor),
            threaded: pool.is_some(),
        };
        let cuts = Cuts {
            sorted: &mut self.sorted,
            touched: &mut self.touched,
            memory: &mut self.memory[..cells],
        };
        match pool {
            Some(pool) => pool.install(|| boxes.resolve(cuts, 0..cells, 0)),
            None => boxes.resolve(cuts, 0..cells, 0),
        }
        for (c, _) in self.touched.iter().enumerate().filter(|(_, t)| **t) {
            let range = self.start[c] as usize..self.start[c + 1] as usize;
            for (&i, p) in self.members[range.clone()].iter().zip(&self.sorted[range]) {
                positions[i as usize] = *p;
            }
        }
    }
}

/// What the self-collision pass shares between its tasks.
struct Boxes<'a> {
    repulsion: &'a Repulsion,
    pinned: &'a [bool],
    start: &'a [u32],
    members: &'a [u32],
    /// The positions at the start of the pass (corrections go to `sorted`).
    positions: &'a [Vec3],
    /// The points' anchors; a box's task reads and writes those of its own points.
    anchors: Disjoint<'a, Vec3>,
    /// Whether to split the boxes between the current pool's threads.
    threaded: bool,
}

/// The per-slot and per-cell arrays a task of the pass writes: windows starting at a slot and
/// at a cell.
struct Cuts<'a> {
    sorted: &'a mut [Vec3],
    touched: &'a mut [bool],
    memory: &'a mut [Memory],
}

impl Boxes<'_> {
    /// Resolves `cells` (whose points' slots start at `offset`, and whose per-cell windows in
    /// `cuts` start at `cells.start`); when threaded, halving the run of boxes between threads
    /// down to about [`PARALLEL_CHUNK`] points. Recursion rather than a list of chunks, so
    /// nothing is allocated.
    fn resolve(&self, cuts: Cuts<'_>, cells: std::ops::Range<usize>, offset: usize) {
        let Cuts {
            sorted,
            touched,
            memory,
        } = cuts;
        let start = self.start;
        let (lo, hi) = (start[cells.start] as usize, start[cells.end] as usize);
        if !self.threaded || hi - lo <= PARALLEL_CHUNK || cells.len() < 2 {
            for (c, (touched, memory)) in cells.zip(touched.iter_mut().zip(memory)) {
                let range = start[c] as usize..start[c + 1] as usize;
                let window = range.start - offset..range.end - offset;
                let (members, slots) = (&self.members[range], &mut sorted[window]);
                *touched = self.resolve_box(members, slots, memory);
            }
            return;
        }
        // Split at the first box starting in the second half of the points (always inside the
        // run: the run has two boxes or more).
        let half = usize::midpoint(lo, hi);
        let mid = (cells.start + start[cells.clone()].partition_point(|&s| (s as usize) <= half))
            .clamp(cells.start + 1, cells.end - 1);
        let split = start[mid] as usize;
        let (sorted_left, sorted_right) = sorted.split_at_mut(split - offset);
        let (touched_left, touched_right) = touched.split_at_mut(mid - cells.start);
        let (memory_left, memory_right) = memory.split_at_mut(mid - cells.start);
        let left = Cuts {
            sorted: sorted_left,
            touched: touched_left,
            memory: memory_left,
        };
        let right = Cuts {
            sorted: sorted_right,
            touched: touched_right,
            memory: memory_right,
        };
        rayon::join(
            || self.resolve(left, cells.start..mid, offset),
            || self.resolve(right, mid..cells.end, split),
        );
    }

    /// The anchor of point `i`, a point of the box this task resolves.
    #[inline]
    fn anchor(&self, i: u32) -> Vec3 {
        // SAFETY: only the task that resolves a box touches its points' anchors; the run is
        // read and dropped here.
        #[allow(unsafe_code)]
        unsafe {
            self.anchors.run(i as usize, 1)[0]
        }
    }

    /// Sets the anchor of point `i`, a point of the box this task resolves.
    #[inline]
    fn set_anchor(&self, i: u32, p: Vec3) {
        // SAFETY: as in `anchor`: the run is written and dropped here.
        #[allow(unsafe_code)]
        unsafe {
            self.anchors.run(i as usize, 1)[0] = p;
        }
    }

    /// Resolves one box: `members` are its points' indices in index order, `slots` its run of
    /// `sorted`, `memory` what is known of it (updated). True when it moved a point.
    #[inline]
    fn resolve_box(&self, members: &[u32], slots: &mut [Vec3], memory: &mut Memory) -> bool {
        // A lone point has no pair.
        if members.len() < 2 {
            return false;
        }
        // NOTE: a box whose points all moved, since they were anchored, within its allowance of
        // the move of its first point is still clear (see `Repulsion::allowance`): nothing to
        // do. A NaN distance fails the test, so a diverged point is always looked at.
        if memory.allowed >= 0.0 {
            let moved = |i: u32| self.positions[i as usize] - self.anchor(i);
            let (allowed, shift) = (memory.allowed, moved(members[0]));
            if dist2(&shift) <= FOLLOW2 * allowed
                && members[1..]
                    .iter()
                    .all(|&i| dist2(&(moved(i) - shift)) <= allowed)
            {
                memory.skips = memory.skips.saturating_add(1);
                return false;
            }
            // NOTE: the box outran its allowance. Anchors that saved fewer than two looks cost
            // more than they saved (writing them, testing them), so such a box waits before it
            // takes new ones, twice as long each time: a moving cloth soon stops paying for
            // anchors, a settling one gets them back.
            memory.strikes = if memory.skips < 2 {
                (memory.strikes + 1).min(MAX_STRIKES)
            } else {
                0
            };
            memory.wait = ANCHOR_WAIT << memory.strikes;
            memory.allowed = -1.0;
        }
        for (slot, &i) in slots.iter_mut().zip(members) {
            *slot = self.positions[i as usize];
        }
        if let Some(closest2) = self.repulsion.closest_pair_out_of_reach(slots) {
            if memory.wait > 0 {
                memory.wait -= 1;
                return false;
            }
            memory.allowed = self.repulsion.allowance(closest2);
            if memory.allowed >= 0.0 {
                memory.skips = 0;
                for (slot, &i) in slots.iter().zip(members) {
                    self.set_anchor(i, *slot);
                }
            }
            return false;
        }
        memory.allowed = -1.0;
        let mut any = false;
        for (k, &i) in members.iter().enumerate() {
            if self.pinned[i as usize] {
                continue;
            }
            let others = (0..slots.len()).filter(|&j| j != k);
            if let Some(p) = self.repulsion.corrected(slots, k, others) {
                // NOTE: later points of the box see this correction, as in the course.
                slots[k] = p;
                any = true;
            }
        }
        any
    }
}

/// The course's repulsion between points of a box.
#[derive(Debug, Clone, Copy)]
pub(super) struct Repulsion {
    /// `2 * thickness`, metres.
    pub(super) reach: f64,
    /// Squared distances at or above this are certainly out of reach (see `corrected`).
    pub(super) reach2_out: f64,
    /// Steps per frame: the averaged correction is divided by it.
    pub(super) steps: f64,
}

impl Repulsion {
    pub(super) fn new(mesh: &ClothMesh, steps_per_frame: u32) -> Self {
        let reach = 2.0 * mesh.thickness();
        // NOTE: a pair is skipped without its square root when `d^2 >= reach2_out`. That is
        // exact: `reach2_out` is at least the real reach^2 (the product's rounding, half an ulp,
        // is far inside the 4-ulp margin), so such a pair has a real distance >= reach, and the
        // correctly rounded sqrt cannot fall below the representable `reach` either.
        Self {
            reach,
            reach2_out: reach * reach * (1.0 + 4.0 * f64::EPSILON),
            steps: f64::from(steps_per_frame),
        }
    }

    /// The smallest squared distance between two of `members`, or `None` when some pair is
    /// within reach by the test `corrected` skips pairs with (`d^2` is the same bits whichever
    /// point comes first: `a - b` is exactly `-(b - a)`). Infinite for fewer than two points.
    #[inline]
    pub(super) fn closest_pair_out_of_reach(&self, members: &[Vec3]) -> Option<f64> {
        // NOTE: the minimum of the bit patterns: squared distances are never negative, and
        // non-negative floats order as their bits do (a NaN above infinity, so it is only the
        // minimum when every distance is NaN). An integer minimum is one cheap instruction;
        // `f64::min`'s NaN handling is several, and this loop runs over every pair.
        let mut closest = f64::INFINITY.to_bits();
        for (k, p) in members.iter().enumerate() {
            for q in &members[k + 1..] {
                let d2 = dist2(&(p - q));
                if d2 < self.reach2_out {
                    return None;
                }
                closest = closest.min(d2.to_bits());
            }
        }
        Some(f64::from_bits(closest))
    }

    /// The corrected position of the point at `me` among the `members` of its box (their
    /// positions, in index order), or `None` when no other member is within reach.
    /// `candidates`: the other members, in increasing order, or those of them within
    /// `reach2_out` (the others are skipped below anyway).
    #[inline]
    pub(super) fn corrected(
        &self,
        members: &[Vec3],
        me: usize,
        candidates: impl Iterator<Item = usize>,
    ) -> Option<Vec3> {
        let p = members[me];
        let mut correction = Vec3::zeros();
        let mut count = 0u32;
        for k in candidates {
            let d = p - members[k];
            let d2 = dist2(&d);
            if d2 >= self.reach2_out {
                continue;
            }
            let dist = d2.sqrt();
            // NOTE: coincident points (dist == 0) have no direction to separate along; the
            // course would produce NaN here, we skip the pair.
            if dist < self.reach && dist > 0.0 {
                correction += d * ((self.reach - dist) / dist);
                count += 1;
            }
        }
        (count > 0).then(|| p + correction / f64::from(count) / self.steps)
    }
}
