//! The stretch limit in colour classes ([`crate::ConstraintOrder::Colored`]): every spring
//! checked and corrected once a step with the course's formula, in an order with no chains.
//!
//! # Why
//!
//! On a big hanging cloth nearly every spring sits at the limit, so the course's sweep corrects
//! a few springs per point and step. In the course's order each correction moves points that
//! the next spring reads, so the sweep is one long chain of dependent square roots and
//! divisions, and that latency, not the work, dominates the step. No pre-pass helps: almost
//! nothing can be proven inside the limit.
//!
//! # How
//!
//! The springs of one direction split into two classes whose springs share no point:
//!
//! | direction | class of the spring emitted by point (x, y) |
//! |---|---|
//! | (-1, 0) | x mod 2 |
//! | (0, -1), (-1, -1), (1, -1) | y mod 2 |
//! | (-2, 0) | (x / 2) mod 2 |
//! | (0, -2) | (y / 2) mod 2 |
//!
//! Two springs of one direction share a point only when one's emitter is the other's partner,
//! that is, their emitters differ by the direction itself, which changes the class. The sweep
//! takes the directions in the course's order and each direction's classes in turn. Inside a
//! class the corrections are independent: the result is the same in any order (bit for bit),
//! so the processor overlaps them and threads share them by rows, with results that never
//! depend on the thread count.

// NOTE: the row loop and its helpers are `#[inline(always)]` so they are compiled into its AVX2
// build.
#![allow(clippy::inline_always)]

use rayon::ThreadPool;

use cloth_mesh::Vec3;

use super::sweep::{DIRECTIONS, Stencil, offsets, valid_columns};
use crate::disjoint::Disjoint;
use crate::self_collision::PARALLEL_CHUNK;
#[cfg(target_arch = "x86_64")]
use crate::simd::Avx2;
use crate::simd::Simd;
use crate::stretch::{Points, limit_one};

/// One sweep of the stretch limit at `ratio` over `stencil`'s springs, class by class (see the
/// module), on `pool`'s threads when there is one, on AVX2 lanes when `simd` has them.
pub(crate) fn limit_colored(
    stencil: &Stencil,
    pinned: &[bool],
    positions: &mut [Vec3],
    ratio: f64,
    pool: Option<&ThreadPool>,
    simd: Simd,
) {
    let (nw, nh) = (stencil.nw(), stencil.nh());
    let offsets = offsets(nw);
    for (t, &(dx, dy, _)) in DIRECTIONS.iter().enumerate() {
        let columns = valid_columns(nw, dx);
        // Emitting rows: those with a partner row (`dy` is 0 or negative).
        let rows = dy.unsigned_abs()..nh;
        for class in 0..2 {
            let class = Class::of(t, class);
            let springs = Springs {
                stencil,
                t,
                offset: offsets[t],
                class,
                row_columns: class.columns_in(columns.clone()),
                nw,
                ratio,
                pinned,
                simd,
            };
            let shared = Disjoint::new(positions);
            match pool {
                Some(pool) => pool.install(|| springs.sweep(&shared, rows.clone(), true)),
                None => springs.sweep(&shared, rows.clone(), false),
            }
        }
    }
}

/// Which springs of a direction one class holds.
#[derive(Debug, Clone, Copy)]
enum Class {
    /// Emitters in rows `y` with `(y >> shift) & 1 == bit`.
    Rows { shift: u32, bit: usize },
    /// Emitters in columns `x` with `(x >> shift) & 1 == bit`.
    Columns { shift: u32, bit: usize },
}

impl Class {
    /// Class `bit` (0 or 1) of direction `t` (an index into `DIRECTIONS`).
    fn of(t: usize, bit: usize) -> Self {
        match t {
            0 => Self::Columns { shift: 0, bit },
            4 => Self::Columns { shift: 1, bit },
            5 => Self::Rows { shift: 1, bit },
            _ => Self::Rows { shift: 0, bit },
        }
    }

    fn has_row(self, y: usize) -> bool {
        match self {
            Self::Rows { shift, bit } => (y >> shift) & 1 == bit,
            Self::Columns { .. } => true,
        }
    }

    fn has_column(self, x: usize) -> bool {
        match self {
            Self::Columns { shift, bit } => (x >> shift) & 1 == bit,
            Self::Rows { .. } => true,
        }
    }

    /// The class's columns among `valid` in a row: the first, and how many; the `i`-th is
    /// [`Class::column`]`(first, i)`.
    fn columns_in(self, valid: std::ops::Range<usize>) -> (usize, usize) {
        let mut columns = valid.filter(|&x| self.has_column(x));
        let first = columns.next();
        let count = usize::from(first.is_some()) + columns.count();
        let first = first.unwrap_or(0);
        // The pairs of columns of a `shift: 1` class are counted from their first column.
        debug_assert!(!matches!(self, Self::Columns { shift: 1, .. }) || first % 2 == 0);
        (first, count)
    }

    /// The `i`-th of the class's columns in a row, from the first (see [`Class::columns_in`]):
    /// every column, every other column, or every other pair of columns.
    #[inline(always)]
    fn column(self, first: usize, i: usize) -> usize {
        match self {
            Self::Rows { .. } => first + i,
            Self::Columns { shift: 0, .. } => first + 2 * i,
            Self::Columns { .. } => first + 4 * (i >> 1) + (i & 1),
        }
    }
}

/// The springs of one class.
struct Springs<'a> {
    stencil: &'a Stencil,
    /// Their direction (an index into `DIRECTIONS`), and its partner offset.
    t: usize,
    offset: isize,
    class: Class,
    /// The first of the class's columns in a row, and how many (see [`Class::columns_in`]).
    row_columns: (usize, usize),
    nw: usize,
    ratio: f64,
    pinned: &'a [bool],
    simd: Simd,
}

impl Springs<'_> {
    /// Checks and corrects the class's springs emitted by `rows`; when `threaded`, halving the
    /// rows between the current pool's threads down to about [`PARALLEL_CHUNK`] points.
    /// Recursion rather than a list of chunks, so nothing is allocated.
    fn sweep(&self, shared: &Disjoint<'_, Vec3>, rows: std::ops::Range<usize>, threaded: bool) {
        if threaded && rows.len() * self.nw > 2 * PARALLEL_CHUNK {
            let mid = rows.start + rows.len() / 2;
            rayon::join(
                || self.sweep(shared, rows.start..mid, true),
                || self.sweep(shared, mid..rows.end, true),
            );
            return;
        }
        // SAFETY: this task alone sweeps these rows of the class, whose springs touch points
        // that no other spring of the class touches (see the module).
        #[allow(unsafe_code)]
        let mut points = unsafe { View::new(shared) };
        #[cfg(target_arch = "x86_64")]
        if let Some(avx2) = self.simd.avx2() {
            // SAFETY: the CPU runs AVX2: an `Avx2` exists.
            #[allow(unsafe_code)]
            unsafe {
                self.rows_avx2(avx2, &mut points, rows);
            }
            return;
        }
        self.rows_portable(&mut points, rows);
    }

    /// [`Springs::rows`] compiled for AVX2, with [`limit_group_avx2`]: four springs' checks
    /// and corrections at once, the same operations, so the same corrections.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn rows_avx2(&self, _: Avx2, points: &mut View<'_>, rows: std::ops::Range<usize>) {
        let layout = Layout::of(self.class);
        self.rows(points, rows, |a, rest, points| {
            debug_assert!({
                let mut lanes = layout.emitters(a[0]);
                lanes.sort_unstable();
                lanes == a
            });
            limit_group_avx2(
                layout,
                a[0],
                self.offset,
                rest,
                self.pinned,
                points,
                self.ratio,
            );
        });
    }

    /// Checks and corrects the class's springs emitted by `rows`, [`LANES`] at a time with
    /// `lanes` (given the emitters, the direction's rest lengths and the points), the rest one
    /// by one.
    #[inline(always)]
    fn rows<P: Points + ?Sized>(
        &self,
        points: &mut P,
        rows: std::ops::Range<usize>,
        mut lanes: impl FnMut([usize; LANES], &[f64], &mut P),
    ) {
        let rest = self.stencil.rest(self.t);
        let (first, count) = self.row_columns;
        let full = count - count % LANES;
        for y in rows.filter(|&y| self.class.has_row(y)) {
            let row = y * self.nw;
            let emitter = |i: usize| row + self.class.column(first, i);
            for i in (0..full).step_by(LANES) {
                lanes(
                    [emitter(i), emitter(i + 1), emitter(i + 2), emitter(i + 3)],
                    rest,
                    points,
                );
            }
            for a in (full..count).map(emitter) {
                self.limit_one(a, rest, points);
            }
        }
    }

    /// `limit_one` on the spring emitted by `a`.
    #[inline(always)]
    fn limit_one<P: Points + ?Sized>(&self, a: usize, rest: &[f64], points: &mut P) {
        let b = a.wrapping_add_signed(self.offset);
        limit_one(a, b, rest[a], self.pinned, points, self.ratio);
    }

    /// [`Springs::rows`] one spring at a time, for CPUs without AVX2.
    fn rows_portable(&self, points: &mut View<'_>, rows: std::ops::Range<usize>) {
        self.rows(points, rows, |a, rest, points| {
            for a in a {
                self.limit_one(a, rest, points);
            }
        });
    }
}

/// Springs checked at once: four f64 lanes of AVX2.
const LANES: usize = 4;

/// How the ends of a group of [`LANES`] springs of a class lie in memory, from the group's
/// first emitter `a0` and its partner `b0` (see [`Class::column`]).
#[cfg(target_arch = "x86_64")]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Layout {
    /// The emitters are the 4 points from `a0`, their partners the 4 points from `b0`, in
    /// another row (directions with `dy < 0`).
    Rows,
    /// The 8 points from `b0`: partners at places 0, 2, 4, 6, emitters at 1, 3, 5, 7
    /// (direction (-1, 0)).
    Pairs,
    /// The 8 points from `b0`: partners at places 0, 1, 4, 5, emitters at 2, 3, 6, 7
    /// (direction (-2, 0)).
    Quads,
}

#[cfg(target_arch = "x86_64")]
impl Layout {
    fn of(class: Class) -> Self {
        match class {
            Class::Rows { .. } => Self::Rows,
            Class::Columns { shift: 0, .. } => Self::Pairs,
            Class::Columns { .. } => Self::Quads,
        }
    }

    /// The emitters of the group whose first emitter is `a0`, in the lanes' order.
    fn emitters(self, a0: usize) -> [usize; LANES] {
        match self {
            Self::Rows => [a0, a0 + 1, a0 + 2, a0 + 3],
            // The lanes of `split`'s unpacks and half swaps.
            Self::Pairs => [a0, a0 + 4, a0 + 2, a0 + 6],
            Self::Quads => [a0, a0 + 1, a0 + 4, a0 + 5],
        }
    }
}

/// [`limit_one`] on the [`LANES`] springs of a class whose first emitter is `a0` (partners at
/// `offset`), laid out as `layout` says: the ends read with whole-vector loads and spread into
/// x, y and z lanes, the four checks at once and, when any spring is over the limit, the four
/// square roots and divisions at once; then the ends go back with whole-vector stores.
///
/// NOTE: every lane keeps the course's operations and their order (`d = b - a`, the squared
/// length summed x, y, z, the bound of `inside_bound`, `(len - max) / len`, halves by `* 0.5`),
/// with correctly rounded packed square roots and divisions, so each spring gets exactly
/// `limit_one`'s bits; a spring inside the limit and a pinned end get their own bits back from
/// the blends. One at a time, as `limit_one`, the springs cost a branch each: on a big hanging
/// cloth a third of the checked springs are over the limit, in no pattern a predictor learns.
/// Whole-vector loads and stores, rather than a point at a time, because the ends of a group
/// are consecutive points: 6 loads, 6 stores and about two dozen shuffles in place of 24 scalar
/// loads with inserts and 24 scalar stores.
///
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn limit_group_avx2(
    layout: Layout,
    a0: usize,
    offset: isize,
    rest: &[f64],
    pinned: &[bool],
    points: &mut View<'_>,
    ratio: f64,
) {
    use lanes::{Lanes, join, load, load4, pins, split, store};
    let b0 = a0.wrapping_add_signed(offset);
    if layout == Layout::Rows {
        let (a, b) = (load(points.run(a0, LANES)), load(points.run(b0, LANES)));
        let rest = load4(&rest[a0..a0 + LANES]);
        let (pin_a, pin_b) = (pins(&pinned[a0..a0 + LANES]), pins(&pinned[b0..b0 + LANES]));
        if let Some((a, b)) = correct(Lanes { a, b }, rest, pin_a, pin_b, ratio) {
            store(points.run(a0, LANES), a);
            store(points.run(b0, LANES), b);
        }
        return;
    }
    // The partners come first in the run of 8 points.
    let run = points.run(b0, 2 * LANES);
    let (lo, hi) = (load(&run[..LANES]), load(&run[LANES..]));
    let rest = &rest[b0..b0 + 2 * LANES];
    let pinned = &pinned[b0..b0 + 2 * LANES];
    let pairs = layout == Layout::Pairs;
    let (_, rest) = split(pairs, load4(&rest[..LANES]), load4(&rest[LANES..]));
    let (pin_b, pin_a) = split(pairs, pins(&pinned[..LANES]), pins(&pinned[LANES..]));
    let mut b = lo;
    let mut a = hi;
    for c in 0..3 {
        (b[c], a[c]) = split(pairs, lo[c], hi[c]);
    }
    if let Some((a, b)) = correct(Lanes { a, b }, rest, pin_a, pin_b, ratio) {
        let (mut lo, mut hi) = (b, a);
        for c in 0..3 {
            (lo[c], hi[c]) = join(pairs, b[c], a[c]);
        }
        let (run_lo, run_hi) = run.split_at_mut(LANES);
        store(run_lo, lo);
        store(run_hi, hi);
    }
}

/// `limit_one` on the lanes' springs, from `a` to `b`: the new ends, or none when every spring
/// is inside the limit.
///
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn correct(
    ends: lanes::Lanes,
    rest: std::arch::x86_64::__m256d,
    pin_a: std::arch::x86_64::__m256d,
    pin_b: std::arch::x86_64::__m256d,
    ratio: f64,
) -> Option<(lanes::Xyz, lanes::Xyz)> {
    use std::arch::x86_64::{
        _CMP_NLE_UQ, _mm256_add_pd, _mm256_and_pd, _mm256_andnot_pd, _mm256_blendv_pd,
        _mm256_cmp_pd, _mm256_div_pd, _mm256_movemask_pd, _mm256_mul_pd, _mm256_or_pd,
        _mm256_set1_pd, _mm256_sqrt_pd, _mm256_sub_pd,
    };
    let lanes::Lanes { a, b } = ends;
    // NOTE: arrays written out, not `array::map`: its closure is not inlined here, and the
    // intrinsics in it became calls.
    let d = [
        _mm256_sub_pd(b[0], a[0]),
        _mm256_sub_pd(b[1], a[1]),
        _mm256_sub_pd(b[2], a[2]),
    ];
    let len2 = _mm256_add_pd(
        _mm256_add_pd(_mm256_mul_pd(d[0], d[0]), _mm256_mul_pd(d[1], d[1])),
        _mm256_mul_pd(d[2], d[2]),
    );
    let max = _mm256_mul_pd(_mm256_set1_pd(ratio), rest);
    // `inside_bound(max)`: `max * max * (1 - 4 eps)`, in that order.
    let bound = _mm256_mul_pd(
        _mm256_mul_pd(max, max),
        _mm256_set1_pd(1.0 - 4.0 * f64::EPSILON),
    );
    // `!(len2 <= bound)`: unordered compares true, so a NaN goes on, as in `limit_one`.
    let outside = _mm256_cmp_pd(len2, bound, _CMP_NLE_UQ);
    if _mm256_movemask_pd(outside) == 0 {
        return None;
    }
    let len = _mm256_sqrt_pd(len2);
    let over = _mm256_and_pd(outside, _mm256_cmp_pd(len, max, _CMP_NLE_UQ));
    let factor = _mm256_div_pd(_mm256_sub_pd(len, max), len);
    // `limit_one`'s cases: a free end moves half the excess when the other is free too,
    // all of it when the other is pinned; a pinned end stays (`andnot`: over and free).
    let both_free = _mm256_andnot_pd(_mm256_or_pd(pin_a, pin_b), over);
    let (move_a, move_b) = (_mm256_andnot_pd(pin_a, over), _mm256_andnot_pd(pin_b, over));
    let half = _mm256_set1_pd(0.5);
    let (mut to_a, mut to_b) = (a, b);
    for c in 0..3 {
        let excess = _mm256_mul_pd(d[c], factor);
        let step = _mm256_blendv_pd(excess, _mm256_mul_pd(excess, half), both_free);
        to_a[c] = _mm256_blendv_pd(a[c], _mm256_add_pd(a[c], step), move_a);
        to_b[c] = _mm256_blendv_pd(b[c], _mm256_sub_pd(b[c], step), move_b);
    }
    Some((to_a, to_b))
}

/// Four points' coordinates as x, y and z lanes, and the shuffles between them and memory.
#[cfg(target_arch = "x86_64")]
mod lanes {
    use std::arch::x86_64::{
        __m256d, _mm_cvtsi32_si128, _mm256_castsi256_pd, _mm256_cvtepu8_epi64,
        _mm256_permute2f128_pd, _mm256_setzero_si256, _mm256_sub_epi64, _mm256_unpackhi_pd,
        _mm256_unpacklo_pd,
    };

    use cloth_mesh::Vec3;

    pub(super) use crate::simd::load4;
    use crate::simd::{deinterleave, interleave};

    /// The x, y and z lanes of four points.
    pub(super) type Xyz = [__m256d; 3];

    /// The two ends of four springs.
    #[derive(Clone, Copy)]
    pub(super) struct Lanes {
        pub(super) a: Xyz,
        pub(super) b: Xyz,
    }

    /// The first four points of `points`, as lanes.
    ///
    /// # Panics
    /// When `points` holds fewer than four points.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) fn load(points: &[Vec3]) -> Xyz {
        // Four points are 12 f64s (`Vec3` is `Pod`: three f64s, no padding).
        let f: &[f64] = bytemuck::cast_slice(&points[..4]);
        deinterleave([load4(&f[..4]), load4(&f[4..8]), load4(&f[8..])])
    }

    /// Writes lanes back as the first four points of `points` ([`load`]'s inverse).
    ///
    /// # Panics
    /// When `points` holds fewer than four points.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) fn store(points: &mut [Vec3], xyz: Xyz) {
        let f: &mut [f64] = bytemuck::cast_slice_mut(&mut points[..4]);
        f.copy_from_slice(bytemuck::cast_slice(&interleave(xyz)));
    }

    /// The first four pin flags of `pinned` as lane masks (all ones where pinned).
    ///
    /// # Panics
    /// When `pinned` holds fewer than four flags.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) fn pins(pinned: &[bool]) -> __m256d {
        let bytes = [pinned[0], pinned[1], pinned[2], pinned[3]];
        // A `bool` is the byte 0 or 1.
        let word = i32::from_le_bytes(bytes.map(u8::from));
        let ones = _mm256_cvtepu8_epi64(_mm_cvtsi32_si128(word));
        _mm256_castsi256_pd(_mm256_sub_epi64(_mm256_setzero_si256(), ones))
    }

    /// The lanes of 8 points (`lo`: places 0-3, `hi`: 4-7) as those at places 0, 2, 4, 6 and 1,
    /// 3, 5, 7 (`pairs`; in the lane order 0 4 2 6 and 1 5 3 7), or else 0, 1, 4, 5 and 2, 3,
    /// 6, 7.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) fn split(pairs: bool, lo: __m256d, hi: __m256d) -> (__m256d, __m256d) {
        if pairs {
            (_mm256_unpacklo_pd(lo, hi), _mm256_unpackhi_pd(lo, hi))
        } else {
            (
                _mm256_permute2f128_pd(lo, hi, 0x20),
                _mm256_permute2f128_pd(lo, hi, 0x31),
            )
        }
    }

    /// [`split`]'s inverse: the unpacks and the half swaps are their own inverses.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub(super) fn join(pairs: bool, first: __m256d, second: __m256d) -> (__m256d, __m256d) {
        split(pairs, first, second)
    }
}

/// One task's access to the positions shared by the tasks of a class.
struct View<'a>(&'a Disjoint<'a, Vec3>);

impl<'a> View<'a> {
    /// # Safety
    /// The task must touch only points that no other task touches while it runs.
    #[allow(unsafe_code)]
    unsafe fn new(shared: &'a Disjoint<'a, Vec3>) -> Self {
        Self(shared)
    }

    /// The `len` points from `start`, this task's alone (`View::new`).
    #[inline(always)]
    fn run(&mut self, start: usize, len: usize) -> &mut [Vec3] {
        // SAFETY: no other task touches these points (`View::new`), and the returned borrow of
        // `self` keeps this task's other runs off them while it lives.
        #[allow(unsafe_code)]
        unsafe {
            self.0.run(start, len)
        }
    }
}

impl Points for View<'_> {
    #[inline(always)]
    fn at(&self, i: usize) -> Vec3 {
        let mut view = View(self.0);
        view.run(i, 1)[0]
    }

    #[inline(always)]
    fn put(&mut self, i: usize, p: Vec3) {
        self.run(i, 1)[0] = p;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MAX_STRETCH;
    use crate::testing::assert_same_bits;
    use cloth_mesh::{ClothMesh, GridSpec, Orientation};

    /// An `nw x nh` cloth at the standard spacing with every seventh point pinned (so lanes
    /// meet every mix of pinned and free ends), scattered by up to 40 % of the spacing: a
    /// third of the springs and more over the limit.
    fn scattered_cloth(nw: usize, nh: usize, seed: u64) -> (ClothMesh, Vec<Vec3>) {
        let pinned = (0..nw * nh)
            .filter(|i| i % 7 == 3)
            .map(|i| (i % nw, i / nw))
            .collect();
        let mesh = ClothMesh::new(&GridSpec {
            width: (nw - 1) as f64 / 49.0,
            height: (nh - 1) as f64 / 49.0,
            num_width_points: nw,
            num_height_points: nh,
            thickness: 0.0095,
            orientation: Orientation::Horizontal,
            pinned,
            ..GridSpec::default()
        })
        .unwrap();
        let mut rng = cloth_mesh::SplitMix64::new(seed);
        let h = 0.4 / 49.0;
        let start = mesh
            .start_positions()
            .iter()
            .map(|p| p + Vec3::new(rng.uniform(-h, h), rng.uniform(-h, h), rng.uniform(-h, h)))
            .collect();
        (mesh, start)
    }

    /// The order the module states, written from the mesh's spring list rather than the
    /// stencil: per direction, class 0 then class 1, each class's springs one by one with
    /// `limit_one`.
    fn reference(mesh: &ClothMesh, positions: &mut [Vec3]) {
        let nw = mesh.nw();
        assert!(nw >= 4);
        let offsets = offsets(nw);
        for (t, &offset) in offsets.iter().enumerate() {
            for bit in 0..2 {
                let class = Class::of(t, bit);
                for s in mesh.springs() {
                    let (a, b) = (s.a as usize, s.b as usize);
                    // From 4 columns on, each direction has its own offset.
                    let in_class = b as isize - a as isize == offset
                        && class.has_row(a / nw)
                        && class.has_column(a % nw);
                    if in_class {
                        limit_one(a, b, s.rest, mesh.pinned(), positions, MAX_STRETCH);
                    }
                }
            }
        }
    }

    #[test]
    fn the_lanes_make_the_stated_orders_corrections_bit_for_bit() {
        // Widths that leave every remainder of lanes in a row, on one thread and on a pool
        // that splits the rows (64 x 150 is over twice `PARALLEL_CHUNK` points).
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        for (nw, nh, seed) in [
            (5, 4, 1),
            (13, 9, 2),
            (22, 17, 3),
            (37, 30, 4),
            (64, 150, 5),
        ] {
            let (mesh, start) = scattered_cloth(nw, nh, seed);
            let stencil = Stencil::new(&mesh).unwrap();
            let mut expected = start.clone();
            reference(&mesh, &mut expected);
            let changed = expected.iter().zip(&start).filter(|(a, b)| a != b).count();
            assert!(changed > mesh.len() / 4, "{nw} x {nh}: too few corrections");
            for (pool, simd) in [None, Some(&pool)]
                .into_iter()
                .zip([Simd::PORTABLE, Simd::detect()])
            {
                for simd in [simd, Simd::detect()] {
                    let mut colored = start.clone();
                    limit_colored(
                        &stencil,
                        mesh.pinned(),
                        &mut colored,
                        MAX_STRETCH,
                        pool,
                        simd,
                    );
                    assert_same_bits(&colored, &expected);
                }
            }
            // Pinned points never move.
            for (i, _) in mesh.pinned().iter().enumerate().filter(|(_, p)| **p) {
                assert_eq!(expected[i], start[i]);
            }
        }
    }

    #[test]
    fn a_non_finite_point_stays_non_finite() {
        let (mesh, mut start) = scattered_cloth(13, 9, 7);
        let stencil = Stencil::new(&mesh).unwrap();
        start[40].x = f64::NAN;
        let mut expected = start.clone();
        reference(&mesh, &mut expected);
        let mut colored = start;
        limit_colored(
            &stencil,
            mesh.pinned(),
            &mut colored,
            MAX_STRETCH,
            None,
            Simd::detect(),
        );
        assert_same_bits(&colored, &expected);
        assert!(colored[40].x.is_nan());
    }

    #[test]
    fn the_springs_of_a_class_share_no_point() {
        // What the threads' disjoint writes and the order-free result rest on.
        let mesh = ClothMesh::pinned_grid(11).unwrap();
        let nw = mesh.nw();
        let offsets = offsets(nw);
        let mut springs = 0;
        for (t, &(dx, dy, _)) in DIRECTIONS.iter().enumerate() {
            for bit in 0..2 {
                let class = Class::of(t, bit);
                let (first, count) = class.columns_in(valid_columns(nw, dx));
                let mut touched = vec![false; mesh.len()];
                for y in (dy.unsigned_abs()..mesh.nh()).filter(|&y| class.has_row(y)) {
                    for i in 0..count {
                        let x = class.column(first, i);
                        assert!(class.has_column(x) && valid_columns(nw, dx).contains(&x));
                        let a = y * nw + x;
                        for p in [a, a.wrapping_add_signed(offsets[t])] {
                            assert!(!touched[p], "direction {t} class {bit}: point {p} twice");
                            touched[p] = true;
                        }
                        springs += 1;
                    }
                }
            }
        }
        assert_eq!(
            springs,
            mesh.springs().len(),
            "every spring in exactly one class"
        );
    }
}
