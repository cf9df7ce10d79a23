//! Provot's maximum-stretch constraint (step 5 of the course's step).

use cloth_mesh::{Spring, Vec3};

/// Shortens every spring longer than `ratio * rest` back to exactly that length, in one
/// in-place sweep in spring order (later springs see earlier corrections, as in the course).
///
/// Each end moves half the excess along the spring's current direction, or the free end moves
/// all of it when the other is pinned; springs with both ends pinned are left alone.
/// Compression is not limited. Every spring type is limited, enabled or not.
pub fn limit_stretch(springs: &[Spring], pinned: &[bool], positions: &mut [Vec3], ratio: f64) {
    for s in springs {
        let (a, b) = (s.a as usize, s.b as usize);
        let d = positions[b] - positions[a];
        let len = d.norm();
        let max = ratio * s.rest;
        if len <= max {
            continue;
        }
        let excess = d * ((len - max) / len);
        match (pinned[a], pinned[b]) {
            (true, true) => {}
            (true, false) => positions[b] -= excess,
            (false, true) => positions[a] += excess,
            (false, false) => {
                let half = excess * 0.5;
                positions[a] += half;
                positions[b] -= half;
            }
        }
    }
}
