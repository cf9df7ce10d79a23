//! Helpers shared by the unit tests of the solver's fast paths.

use cloth_mesh::Vec3;

/// Every coordinate of `a` has the bits of `b`'s: the fast paths promise the straightforward
/// path's results exactly, not approximately.
pub(crate) fn assert_same_bits(a: &[Vec3], b: &[Vec3]) {
    assert_eq!(a.len(), b.len());
    for (i, (a, b)) in a.iter().zip(b).enumerate() {
        for c in 0..3 {
            assert_eq!(a[c].to_bits(), b[c].to_bits(), "point {i} axis {c}");
        }
    }
}
