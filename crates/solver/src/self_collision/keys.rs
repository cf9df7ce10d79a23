//! Box keys: the course's box of a point (`floor` of each coordinate over the box size) as one
//! integer, 21 bits per axis.

use cloth_mesh::Vec3;

use super::SpatialHash;
#[cfg(target_arch = "x86_64")]
use crate::simd::Avx2;
use crate::simd::Simd;

/// One axis of a box key: `floor(v) + 2^20`, wrapped to 21 bits, for `v` the coordinate in
/// box sizes.
///
/// NOTE: written with plain float adds and integer bit operations, not `f64::floor` (a libm
/// call on baseline x86-64) or an `as i64` cast (no AVX2 instruction for it), so the key pass
/// runs on SIMD lanes. Adding `1.5 * 2^52` rounds `v` to the nearest integer and leaves that
/// integer, in two's complement, in the low mantissa bits; one is taken off where rounding went
/// up. That is `floor(v)` exactly for every |v| < 2^51. Beyond (a point a million boxes away, or
/// a non-finite one) the key is some box: such points are far beyond `2 * thickness` of any
/// other, and a diverged step is reported by the solver anyway.
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
#[inline(always)]
#[allow(clippy::inline_always)]
pub(super) fn keys_portable(keys: &mut [u64], positions: &[Vec3], size: (f64, f64, f64)) {
    for (k, p) in keys.iter_mut().zip(positions) {
        *k = SpatialHash::key(p, size);
    }
}

/// [`keys_portable`] compiled for AVX2: four points' divisions and bit operations at once, the
/// same operations, so the same keys.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn keys_avx2(_: Avx2, keys: &mut [u64], positions: &[Vec3], size: (f64, f64, f64)) {
    keys_portable(keys, positions, size);
}

/// The box key of every point into `keys`.
///
/// NOTE: on the caller's thread even when the solver has threads: the pass is a few
/// arithmetic operations a point, less than what handing it to a pool costs.
pub(super) fn compute_keys(
    simd: Simd,
    keys: &mut [u64],
    positions: &[Vec3],
    size: (f64, f64, f64),
) {
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = simd.avx2() {
        // SAFETY: the CPU runs AVX2: an `Avx2` exists.
        #[allow(unsafe_code)]
        unsafe {
            keys_avx2(avx2, keys, positions, size);
        }
        return;
    }
    keys_portable(keys, positions, size);
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
