//! A box's pair searches on AVX2 lanes: four pairs per compare instead of one.
//!
//! # Why
//!
//! Self-collision compares every pair of points in a box: once to find whether any pair is
//! within reach (`Repulsion::closest_pair_out_of_reach`), and, in a box where one is, once per
//! point to find its partners within reach (`Repulsion::corrected`). On a folded cloth a box
//! holds tens of points, and these scalar loops, one pair per turn with a branch each, were a
//! fifth of the step on the 128 x 128 cloth. Most pairs are out of reach: here the squared
//! distances of four pairs are computed and compared at once from a struct-of-arrays copy of
//! the box, and only the pairs within reach go on to the scalar correction.
//!
//! # Same bits
//!
//! Each lane computes the squared distance of the scalar loops (`p - q`, then `dist2`, operand
//! for operand, no fused multiply-add) and compares it with the same bound, so the same pairs
//! are found within reach, in the same order, and the corrections are the scalar code's own.
//! The closest distance is a minimum of values, which is the same whatever the order; a NaN
//! distance is skipped, as the scalar loop's minimum of bit patterns skips it (a NaN's bits
//! lie above infinity's). The copy is padded with infinite points: their distance to any
//! point is infinite or NaN, never within reach, and never below a real one.

#![allow(unsafe_code)]

use std::arch::x86_64::{
    __m256d, _CMP_LT_OQ, _mm256_add_pd, _mm256_cmp_pd, _mm256_loadu_pd, _mm256_min_pd,
    _mm256_movemask_pd, _mm256_mul_pd, _mm256_set1_pd, _mm256_storeu_pd, _mm256_sub_pd,
};

use cloth_mesh::Vec3;

use crate::simd::Simd;

/// The most points of a box taken on lanes: the pairs of one point fit a 64-bit mask.
pub(super) const MAX_POINTS: usize = 64;

/// Room for the points and a last group of four reaching past them.
const CAP: usize = MAX_POINTS + 4;

/// A box's positions as three coordinate arrays, padded with infinite points: scratch memory
/// on the stack of the task that resolves boxes, loaded with one box at a time.
///
/// NOTE: made only by [`BoxLanes::new`], which checks that the CPU has AVX2: holding one is the
/// proof the `unsafe` calls of its methods rest on.
pub(super) struct BoxLanes {
    c: [[f64; CAP]; 3],
    n: usize,
}

impl BoxLanes {
    /// Empty lanes, or `None` when `simd` lacks AVX2.
    #[inline]
    pub(super) fn new(simd: Simd) -> Option<Self> {
        simd.avx2().map(|_| Self {
            c: [[f64::INFINITY; CAP]; 3],
            n: 0,
        })
    }

    /// Loads the box at `slots`.
    ///
    /// # Panics
    /// When it has more than [`MAX_POINTS`] points.
    #[inline]
    pub(super) fn load(&mut self, slots: &[Vec3]) {
        let n = slots.len();
        assert!(n <= MAX_POINTS, "a box of {n} points on lanes");
        for (k, p) in slots.iter().enumerate() {
            self.set(k, p);
        }
        for c in &mut self.c {
            c[n..n + 4].fill(f64::INFINITY);
        }
        self.n = n;
    }

    /// Point `k` moved to `p`.
    #[inline]
    pub(super) fn set(&mut self, k: usize, p: &Vec3) {
        for (c, v) in self.c.iter_mut().zip(p.iter()) {
            c[k] = *v;
        }
    }

    /// The smallest squared distance between two of the points, or `None` when a pair is
    /// within `reach2_out` (see `Repulsion::closest_pair_out_of_reach`).
    #[inline]
    pub(super) fn closest_pair_out_of_reach(&self, reach2_out: f64) -> Option<f64> {
        // SAFETY: the CPU has AVX2 (`new` checked it).
        unsafe { self.closest_avx2(reach2_out) }
    }

    /// Bit `k` set when point `k` is not `me` and within `reach2_out` of it.
    #[inline]
    pub(super) fn within_reach(&self, me: usize, reach2_out: f64) -> u64 {
        // SAFETY: the CPU has AVX2 (`new` checked it).
        unsafe { self.within_reach_avx2(me, reach2_out) }
    }

    /// The squared distances from `p` (broadcast coordinates) to points `q..q + 4`.
    ///
    /// # Panics
    /// When `q + 4 > CAP` (never: every caller's `q` is below `n`).
    #[target_feature(enable = "avx2")]
    fn dist2(&self, p: [__m256d; 3], q: usize) -> __m256d {
        let d = [0, 1, 2].map(|c| {
            let lanes: &[f64; 4] = self.c[c][q..q + 4].try_into().expect("four lanes");
            // SAFETY: `lanes` is four readable f64s.
            _mm256_sub_pd(p[c], unsafe { _mm256_loadu_pd(lanes.as_ptr()) })
        });
        _mm256_add_pd(
            _mm256_add_pd(_mm256_mul_pd(d[0], d[0]), _mm256_mul_pd(d[1], d[1])),
            _mm256_mul_pd(d[2], d[2]),
        )
    }

    /// Point `k`'s coordinates, each broadcast to four lanes.
    #[target_feature(enable = "avx2")]
    fn broadcast(&self, k: usize) -> [__m256d; 3] {
        [0, 1, 2].map(|c| _mm256_set1_pd(self.c[c][k]))
    }

    #[target_feature(enable = "avx2")]
    fn closest_avx2(&self, reach2_out: f64) -> Option<f64> {
        let bound = _mm256_set1_pd(reach2_out);
        let mut closest = _mm256_set1_pd(f64::INFINITY);
        for k in 0..self.n.saturating_sub(1) {
            let p = self.broadcast(k);
            for q in (k + 1..self.n).step_by(4) {
                let d2 = self.dist2(p, q);
                if _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(d2, bound)) != 0 {
                    return None;
                }
                // `minpd` returns its second operand when the first is NaN.
                closest = _mm256_min_pd(d2, closest);
            }
        }
        let mut lanes = [0.0; 4];
        // SAFETY: `lanes` is four writable f64s.
        unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), closest) };
        Some(lanes.into_iter().fold(f64::INFINITY, f64::min))
    }

    #[target_feature(enable = "avx2")]
    fn within_reach_avx2(&self, me: usize, reach2_out: f64) -> u64 {
        let bound = _mm256_set1_pd(reach2_out);
        let p = self.broadcast(me);
        let mut within = 0u64;
        for q in (0..self.n).step_by(4) {
            let lanes = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(self.dist2(p, q), bound));
            within |= u64::from(lanes as u32) << q;
        }
        // The padding is never within reach; `me` is at distance zero from itself.
        within & !(1 << me)
    }
}
