//! Box keys: the course's box of a point (`floor` of each coordinate over the box size) as one
//! integer, 21 bits per axis.

use cloth_mesh::Vec3;

use super::SpatialHash;

/// One axis of a box key: `floor(v) + 2^20`, wrapped to 21 bits, for `v` the coordinate in
/// box sizes.
///
/// NOTE: written with plain float adds and integer bit operations, not `f64::floor` (a libm call on
/// baseline x86-64), so the key loop has no call in it. Adding `1.5 * 2^52` rounds `v` to the
/// nearest integer and leaves that integer, in two's complement, in the low mantissa bits; one is
/// taken off where rounding went up. That is `floor(v)` exactly for every |v| < 2^51. Beyond (a
/// point a million boxes away, or a non-finite one) the key is some box: such points are far beyond
/// `2 * thickness` of any other, and a diverged step is reported by the solver anyway.
#[inline(always)]
#[allow(clippy::inline_always)]
pub(super) fn box_bits(v: f64) -> u64 {
    const ROUND: f64 = 6_755_399_441_055_744.0;
    let m = v + ROUND;
    let rounded_up = m - ROUND > v;
    m.to_bits()
        .wrapping_sub(u64::from(rounded_up))
        .wrapping_add(1 << 20)
        & 0x1F_FFFF
}

/// The box key of every point into `keys` (see [`SpatialHash::key`]).
pub(super) fn compute_keys(keys: &mut [u64], positions: &[Vec3], size: (f64, f64, f64)) {
    for (k, p) in keys.iter_mut().zip(positions) {
        *k = SpatialHash::key(p, size);
    }
}

impl SpatialHash {
    /// The key of `p`'s box: its integer box coordinates, 21 bits per axis.
    #[inline(always)]
    #[allow(clippy::inline_always)]
    fn key(p: &Vec3, (w, h, t): (f64, f64, f64)) -> u64 {
        // Offset so negative boxes stay distinct; a box index beyond +-2^20 (a cloth a million
        // boxes away) wraps, which only merges far-apart boxes: harmless, the distance test
        // still rejects the pairs.
        (box_bits(p.x / w) << 42) | (box_bits(p.y / h) << 21) | box_bits(p.z / t)
    }
}
