//! Provot's maximum-stretch constraint (step 5 of the course's step).

use cloth_mesh::{Spring, Vec3};

use crate::self_collision::dist2;

/// Shortens every spring longer than `ratio * rest` back to exactly that length, in one
/// in-place sweep in spring order (later springs see earlier corrections, as in the course).
///
/// Each end moves half the excess along the spring's current direction, or the free end moves
/// all of it when the other is pinned; springs with both ends pinned are left alone.
/// Compression is not limited. Every spring type is limited, enabled or not.
pub fn limit_stretch(springs: &[Spring], pinned: &[bool], positions: &mut [Vec3], ratio: f64) {
    for s in springs {
        limit_one(s, pinned, positions, ratio);
    }
}

/// The course's correction of one spring.
#[inline]
fn limit_one(s: &Spring, pinned: &[bool], positions: &mut [Vec3], ratio: f64) {
    let (a, b) = (s.a as usize, s.b as usize);
    let d = positions[b] - positions[a];
    let len2 = dist2(&d);
    let max = ratio * s.rest;
    // NOTE: most springs are inside the limit; `len2 <= max^2 (1 - 4 eps)` proves it without the
    // square root. It is exact: the computed bound is at most the real max^2 (its rounding is
    // within the 4-ulp margin), so the real length is <= max, and so is the correctly rounded
    // sqrt, because `max` is representable and rounding is monotone.
    if len2 <= max * max * (1.0 - 4.0 * f64::EPSILON) {
        return;
    }
    let len = len2.sqrt();
    if len <= max {
        return;
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
