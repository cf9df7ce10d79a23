//! The course's stretch-limit sweep (step 5), with the springs that provably need nothing
//! skipped.
//!
//! # Why
//!
//! The course sweeps every spring in order, in place: later springs see earlier corrections.
//! In a moving cloth only a few springs per sweep are over the limit, yet checking each one is a
//! dependent chain of loads, a squared length and a branch, one spring at a time; that made the
//! sweep a third of a step.
//!
//! # How, and why the result is the course's bit for bit
//!
//! 1. A pre-pass computes the squared length of every spring from the positions at the start of
//!    the sweep, row by row and direction by direction on struct-of-arrays copies (so it runs on
//!    SIMD lanes), and marks the springs not proven inside the limit. It compares with one bound
//!    per direction, the smallest of the springs' own bounds, so it reads no rest lengths (on a
//!    big cloth they are three times the positions' memory); the few springs between that bound
//!    and their own get the exact check below.
//! 2. The sequential sweep walks the springs in the course's order (point by point, the six
//!    directions in order, exactly the spring list's order) and runs the course's check on a
//!    spring only when it is marked or one of its ends has moved since the sweep began.
//!
//! A skipped spring has both ends at their start positions, so the course's check would compute
//! the very squared length of the pre-pass (same operands, same operations) and, that length
//! being at most the smallest [`inside_bound`] of its direction, hence at most its own, skip it
//! too. Every other spring gets the course's
//! check on the current positions. So the sweep makes the same corrections in the same order.

// NOTE: the pre-pass helpers are `#[inline(always)]` so they are compiled into its AVX2 build.
#![allow(clippy::inline_always)]

use std::ops::Range;

use cloth_mesh::Vec3;

use super::ConstraintOrder;
use super::sweep::{DIRECTIONS, Stencil, offsets, valid_columns};

#[cfg(target_arch = "x86_64")]
mod prepass;
#[cfg(target_arch = "x86_64")]
use crate::simd::Avx2;
use crate::simd::Simd;
use crate::stretch::{Band, StretchBands, for_each_band, inside_bound, limit_one};

/// The sweep's bounds and scratch memory, built for one stencil (rebuilt with it).
#[derive(Debug, Default, Clone)]
pub(crate) struct StretchSweep {
    bounds: Bounds,
    /// One per band that may run at once.
    scratch: Vec<BandScratch>,
}

/// The pre-pass's vector row function (`prepass::marks_row_avx2`) when the CPU runs it: the
/// marks of a row from the window's copy, the direction bounds and the row's first emitter.
type VectorRow<'a> = Option<&'a dyn Fn(&[Vec<f64>; 3], &[f64; 6], usize, &mut [u8])>;

/// What every band reads.
#[derive(Debug, Default, Clone)]
struct Bounds {
    /// The vector instructions the pre-pass may use.
    simd: Simd,
    /// The stretch ratio the bounds were computed for.
    ratio: f64,
    /// Per direction: the smallest [`inside_bound`] of its springs.
    floor: [f64; 6],
    /// Per point: bit `t` set when its direction-`t` spring exists.
    exists: Vec<u8>,
}

/// Scratch memory of one band's sweep; grows once.
#[derive(Debug, Default, Clone)]
struct BandScratch {
    /// Struct-of-arrays copy of the band's positions at the start of its sweep.
    soa: [Vec<f64>; 3],
    /// `look[margin + k]`, per emitting point `k` of the band: bit `t` set when its direction-`t`
    /// spring needs the course's check, because the pre-pass could not prove it inside or
    /// (marked during the sweep) its far end has moved. The margins (`BandScratch::margin`)
    /// take the marks a moved point leaves for emitters outside the band, so marking needs no
    /// tests.
    look: Vec<u8>,
    /// The pre-pass's marks of one row, a word per point (see `marks_row`).
    row_marks: Vec<u64>,
}

impl StretchSweep {
    /// Bytes the sweep takes for a cloth of `nw` x `nh` points in `order`: the bounds (a byte
    /// per point) and, for the faithful and parallel orders, each band's copy of its positions,
    /// its marks and a row of pre-pass words. The colored order sweeps without them.
    pub(crate) fn bytes_for(nw: usize, nh: usize, order: ConstraintOrder) -> u64 {
        let n = nw * nh;
        let bands = match order {
            ConstraintOrder::Faithful => 1,
            ConstraintOrder::Parallel => StretchBands::BLOCKS,
            ConstraintOrder::Colored => return n as u64,
        };
        // Each band's window reaches two rows before its own rows.
        let window = n + bands * 2 * nw;
        let soa = 3 * size_of::<f64>() * window;
        let look = window + bands * 2 * BandScratch::margin(nw);
        let row_marks = bands * nw * size_of::<u64>();
        (n + soa + look + row_marks) as u64
    }

    /// Bounds and scratch for sweeps of `stencil`'s springs at the stretch `ratio`.
    pub(crate) fn new(stencil: &Stencil, ratio: f64, simd: Simd) -> Self {
        let (nw, nh) = (stencil.nw(), stencil.nh());
        let exists: Vec<u8> = (0..nw * nh)
            .map(|i| exists_mask(nw, i % nw, i / nw))
            .collect();
        let mut floor = [f64::INFINITY; 6];
        for (t, floor) in floor.iter_mut().enumerate() {
            for (&rest, &mask) in stencil.rest(t).iter().zip(&exists) {
                if mask & (1 << t) != 0 {
                    *floor = floor.min(inside_bound(ratio * rest));
                }
            }
        }
        Self {
            bounds: Bounds {
                simd,
                ratio,
                floor,
                exists,
            },
            scratch: Vec::new(),
        }
    }

    /// One sweep of the stretch limit over all of `stencil`'s springs, in the course's order.
    pub(crate) fn limit(&mut self, stencil: &Stencil, pinned: &[bool], positions: &mut [Vec3]) {
        self.scratch.resize_with(1, BandScratch::default);
        let rows = 0..stencil.nh();
        self.scratch[0].sweep(&self.bounds, stencil, pinned, positions, rows);
    }

    /// The sweep in `bands`' order ([`crate::ConstraintOrder::Parallel`]): the blocks at once,
    /// then the seams at once, each band in the course's order, on `pool`'s threads.
    pub(crate) fn limit_bands(
        &mut self,
        stencil: &Stencil,
        bands: &StretchBands,
        pinned: &[bool],
        positions: &mut [Vec3],
        pool: Option<&rayon::ThreadPool>,
    ) {
        self.scratch
            .resize_with(bands.widest(), BandScratch::default);
        let bounds = &self.bounds;
        let sweep = |band: &Band, scratch: &mut BandScratch, window: &mut [Vec3]| {
            let pinned = &pinned[band.points.clone()];
            scratch.sweep(bounds, stencil, pinned, window, band.rows.clone());
        };
        for phase in bands.phases() {
            let scratch = &mut self.scratch[..];
            match pool {
                Some(pool) => {
                    pool.install(|| for_each_band(phase, scratch, positions, 0, true, &sweep));
                }
                None => for_each_band(phase, scratch, positions, 0, false, &sweep),
            }
        }
    }
}

impl BandScratch {
    /// The sweep over the springs emitted by `rows`, in the course's order. `positions` and
    /// `pinned` are the window of points those springs touch: from two rows before `rows`
    /// (or the first row) to the end of `rows`.
    fn sweep(
        &mut self,
        bounds: &Bounds,
        stencil: &Stencil,
        pinned: &[bool],
        positions: &mut [Vec3],
        rows: Range<usize>,
    ) {
        let nw = stencil.nw();
        let first = rows.start.saturating_sub(2) * nw;
        let emitters = rows.start * nw..rows.end * nw;
        // `base`: the first emitter's index in the window, at most two rows in.
        let base = emitters.start - first;
        let margin = Self::margin(nw);
        let ratio = bounds.ratio;
        self.look.clear();
        self.look.resize(margin + emitters.len() + margin, 0);
        self.prepass(bounds, stencil, positions, first, rows);

        let offsets = offsets(nw);
        // Every offset is negative (partners are earlier points), so the direction-`t` spring
        // ending at point `p` is emitted by `p - offsets[t]`, after `p`.
        let ahead = offsets.map(isize::unsigned_abs);
        let exists = &bounds.exists[emitters.clone()];
        let look = &mut self.look[..];
        // NOTE: a moved point marks, in each direction, the emitter whose spring ends at it,
        // rather than each emitter reading its six partners' moved flags: corrections are rare
        // (well under one per point and step on a hanging cloth), so twelve marks per correction
        // cost less than six loads per emitter. Marks left for
        // emitters already swept, or outside the band, land in the margins and are never read.
        let mark = |look: &mut [u8], p: usize| {
            let at = margin + p - base;
            for (t, &ahead) in ahead.iter().enumerate() {
                look[at + ahead] |= 1 << t;
            }
        };
        for (k, &exists) in exists.iter().enumerate() {
            // `j`: the emitter's index in the window; its global index is `emitters.start + k`.
            let (j, global) = (base + k, emitters.start + k);
            // Its marks are final: the emitter itself cannot have moved yet (earlier springs
            // only touch earlier points), and its own corrections mark later emitters only.
            let mut springs = look[margin + k] & exists;
            // NOTE: the springs to look at are visited by their bits, lowest (earliest in the
            // course's order) first: one loop turn per check instead of six turns with an
            // unpredictable branch each.
            while springs != 0 {
                let t = springs.trailing_zeros() as usize;
                springs &= springs - 1;
                let b = j.wrapping_add_signed(offsets[t]);
                let rest = stencil.rest(t)[global];
                if limit_one(j, b, rest, pinned, positions, ratio) {
                    // Once the emitter has moved, each of its later springs needs the check.
                    springs |= exists & !((2u8 << t) - 1);
                    mark(look, j);
                    mark(look, b);
                }
            }
        }
    }

    /// The margin on each side of `look` for a grid `nw` wide: a moved point marks emitters up
    /// to two rows (`2 nw`) after it, and the first emitter is up to two rows into the window.
    fn margin(nw: usize) -> usize {
        2 * nw + 1
    }

    /// Marks the springs emitted by `rows` that are not proven inside the limit, from the
    /// window's current positions (the window starts at point `first`).
    fn prepass(
        &mut self,
        bounds: &Bounds,
        stencil: &Stencil,
        positions: &[Vec3],
        first: usize,
        rows: Range<usize>,
    ) {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx2) = bounds.simd.avx2() {
            // SAFETY: the CPU runs AVX2: an `Avx2` exists.
            #[allow(unsafe_code)]
            unsafe {
                self.prepass_avx2(avx2, bounds, stencil, positions, first, rows);
            }
            return;
        }
        self.prepass_rows(bounds, stencil, positions, first, rows, None);
    }

    /// The pre-pass compiled for AVX2: the copy vectorised by the compiler, the rows with
    /// every partner row in the window by `prepass::marks_row_avx2`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn prepass_avx2(
        &mut self,
        avx2: Avx2,
        bounds: &Bounds,
        stencil: &Stencil,
        positions: &[Vec3],
        first: usize,
        rows: Range<usize>,
    ) {
        // A closure written here takes this function's target features (no `unsafe` call).
        let row = |soa: &[Vec<f64>; 3], floor: &[f64; 6], a0: usize, out: &mut [u8]| {
            prepass::marks_row_avx2(avx2, soa, floor, a0, out);
        };
        self.prepass_rows(bounds, stencil, positions, first, rows, Some(&row));
    }

    /// The pre-pass itself, for whatever instruction set the caller was compiled for; the rows
    /// with every partner row in the window take `vector`, when given.
    #[inline(always)]
    fn prepass_rows(
        &mut self,
        bounds: &Bounds,
        stencil: &Stencil,
        positions: &[Vec3],
        first: usize,
        rows: Range<usize>,
        vector: VectorRow<'_>,
    ) {
        let nw = stencil.nw();
        self.copy_soa(positions);
        for (k, y) in rows.enumerate() {
            let at = Self::margin(nw) + k * nw;
            let out = &mut self.look[at..at + nw];
            let (floor, a0) = (&bounds.floor, y * nw - first);
            match vector {
                Some(row) if y >= 2 && nw >= 4 => row(&self.soa, floor, a0, out),
                _ => marks_row(&self.soa, bounds, &mut self.row_marks, nw, y, first, out),
            }
        }
    }

    /// The window's positions into the struct-of-arrays copy.
    #[inline(always)]
    fn copy_soa(&mut self, positions: &[Vec3]) {
        for (c, soa) in self.soa.iter_mut().enumerate() {
            soa.clear();
            soa.extend(positions.iter().map(|p| p[c]));
        }
    }
}

/// The marks of the springs emitted by row `y` (of a window starting at point `first`, copied
/// into `soa`) into `out`, one byte per point: bit `t` set when its direction-`t` spring exists
/// and is not proven inside. `row_marks` is scratch.
#[inline(always)]
fn marks_row(
    soa: &[Vec<f64>; 3],
    bounds: &Bounds,
    row_marks: &mut Vec<u64>,
    nw: usize,
    y: usize,
    first: usize,
    out: &mut [u8],
) {
    let [px, py, pz] = soa;
    // NOTE: the marks of a row are gathered in 64-bit words, one per point, the width of a
    // compare's result, and narrowed to bytes once per row: or-ing each direction's compare
    // straight into bytes narrowed the four lanes six times a point.
    row_marks.clear();
    row_marks.resize(nw, 0);
    for (t, &(dx, dy, _)) in DIRECTIONS.iter().enumerate() {
        let cols = valid_columns(nw, dx);
        if y < (-dy) as usize || cols.is_empty() {
            continue;
        }
        let a = y * nw + cols.start - first;
        let b = a.wrapping_add_signed(dx + dy * nw as isize);
        let len = cols.len();
        let floor = bounds.floor[t];
        let (ax, ay, az) = (&px[a..a + len], &py[a..a + len], &pz[a..a + len]);
        let (bx, by, bz) = (&px[b..b + len], &py[b..b + len], &pz[b..b + len]);
        let marks = &mut row_marks[cols];
        for i in 0..len {
            // NOTE: the course's `positions[b] - positions[a]` and `dist2`, operand for
            // operand, so the decision is the sequential check's.
            let (ddx, ddy, ddz) = (bx[i] - ax[i], by[i] - ay[i], bz[i] - az[i]);
            let len2 = ddx * ddx + ddy * ddy + ddz * ddz;
            let inside = len2 <= floor;
            marks[i] |= u64::from(!inside) << t;
        }
    }
    for (out, &marks) in out.iter_mut().zip(&*row_marks) {
        // Six direction bits: the narrowing keeps them all.
        *out = marks as u8;
    }
}

/// Bit `t` set when point `(x, y)` of a grid `nw` wide emits a direction-`t` spring.
fn exists_mask(nw: usize, x: usize, y: usize) -> u8 {
    let mut mask = 0;
    for (t, &(dx, dy, _)) in DIRECTIONS.iter().enumerate() {
        if valid_columns(nw, dx).contains(&x) && y >= (-dy) as usize {
            mask |= 1 << t;
        }
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::self_collision::dist2;
    use crate::stretch::StretchBands;
    use crate::testing::assert_same_bits;
    use crate::{ClothMesh, MAX_STRETCH, limit_stretch};

    #[test]
    fn the_sweep_makes_the_courses_corrections_bit_for_bit() {
        // Points scattered by up to 40 % of the spacing: many springs over the limit, chains of
        // corrections through shared points, pinned corners, and ragged rows (37 wide).
        let mesh = ClothMesh::pinned_grid(37).unwrap();
        let stencil = Stencil::new(&mesh).unwrap();
        let mut rng = cloth_mesh::SplitMix64::new(3);
        let h = 0.4 / 49.0;
        let start: Vec<Vec3> = mesh
            .start_positions()
            .iter()
            .map(|p| p + Vec3::new(rng.uniform(-h, h), rng.uniform(-h, h), rng.uniform(-h, h)))
            .collect();
        let mut course = start.clone();
        limit_stretch(mesh.springs(), mesh.pinned(), &mut course, MAX_STRETCH);
        let mut fast = start.clone();
        let mut sweep = StretchSweep::new(&stencil, MAX_STRETCH, Simd::detect());
        sweep.limit(&stencil, mesh.pinned(), &mut fast);
        let changed = course.iter().zip(&start).filter(|(a, b)| a != b).count();
        assert!(
            changed > mesh.len() / 4,
            "the test must exercise corrections"
        );
        assert_same_bits(&fast, &course);
        // A second sweep over the corrected cloth (reused scratch) agrees as well.
        limit_stretch(mesh.springs(), mesh.pinned(), &mut course, MAX_STRETCH);
        sweep.limit(&stencil, mesh.pinned(), &mut fast);
        assert!(fast.iter().zip(&course).all(|(a, b)| a == b));
    }

    /// A cloth squeezed to 0.9 of its rest lengths (every spring inside the limit, so none is
    /// marked by the pre-pass), with every fifth point pulled off by up to two spacings. Their
    /// corrections move neighbours, whose corrections move theirs: a cascade through springs
    /// that only the moved-point marks send the sweep to. Bending springs get over the limit
    /// only when the cloth between their ends is too, so the cascade needs pulls this large to
    /// reach them.
    fn cascading_cloth(nw: usize, seed: u64) -> (cloth_mesh::ClothMesh, Vec<Vec3>) {
        let mesh = ClothMesh::pinned_grid(nw).unwrap();
        let origin = mesh.start_positions()[0];
        let far = 2.0 / (nw - 1) as f64;
        let mut rng = cloth_mesh::SplitMix64::new(seed);
        let positions = mesh
            .start_positions()
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let squeezed = origin + (p - origin) * 0.9;
                if i % 5 == 0 {
                    squeezed
                        + Vec3::new(
                            rng.uniform(-far, far),
                            rng.uniform(-far, far),
                            rng.uniform(-far, far),
                        )
                } else {
                    squeezed
                }
            })
            .collect();
        (mesh, positions)
    }

    /// Per direction, the springs the course corrects in one sweep from `start` although they
    /// were inside the limit at the start: those the sweep finds only through moved-point
    /// marks.
    fn cascaded(mesh: &cloth_mesh::ClothMesh, start: &[Vec3]) -> [usize; 6] {
        let offsets = offsets(mesh.nw());
        let mut positions = start.to_vec();
        let mut counts = [0; 6];
        for s in mesh.springs() {
            let (a, b) = (s.a as usize, s.b as usize);
            let inside = dist2(&(start[b] - start[a])) <= inside_bound(MAX_STRETCH * s.rest);
            let corrected = limit_one(
                a,
                b,
                s.rest,
                mesh.pinned(),
                positions.as_mut_slice(),
                MAX_STRETCH,
            );
            if inside && corrected {
                let off = b as isize - a as isize;
                let t = offsets.iter().position(|&o| o == off).unwrap();
                counts[t] += 1;
            }
        }
        counts
    }

    #[test]
    fn corrections_cascade_through_unmarked_springs_as_in_the_course() {
        let mut cascades = [0; 6];
        for seed in 0..8 {
            let (mesh, start) = cascading_cloth(17, seed);
            let stencil = Stencil::new(&mesh).unwrap();
            let mut course = start.clone();
            limit_stretch(mesh.springs(), mesh.pinned(), &mut course, MAX_STRETCH);
            let mut fast = start.clone();
            StretchSweep::new(&stencil, MAX_STRETCH, Simd::detect()).limit(
                &stencil,
                mesh.pinned(),
                &mut fast,
            );
            assert_same_bits(&fast, &course);
            for (all, this) in cascades.iter_mut().zip(cascaded(&mesh, &start)) {
                *all += this;
            }
        }
        // Every direction's marks were needed somewhere, or the test proves nothing of them.
        assert!(cascades.iter().all(|&c| c > 0), "cascades: {cascades:?}");
    }

    #[test]
    fn cascades_stay_the_courses_inside_each_band() {
        // Bands of the parallel order: each is swept in the course's order over its own
        // springs, the blocks and then the seams; a cascade reaching a band's first rows marks
        // emitters of the band from points of the two rows before it.
        let nw = 31;
        for seed in 0..6 {
            let (mesh, start) = cascading_cloth(nw, seed);
            let stencil = Stencil::new(&mesh).unwrap();
            let bands = StretchBands::new(&mesh);
            assert!(bands.phases()[1].len() > 1, "the test must cut seams");
            let mut course = start.clone();
            for band in bands.phases().into_iter().flatten() {
                let springs: Vec<_> = mesh
                    .springs()
                    .iter()
                    .filter(|s| band.rows.contains(&(s.a as usize / nw)))
                    .copied()
                    .collect();
                limit_stretch(&springs, mesh.pinned(), &mut course, MAX_STRETCH);
            }
            let mut fast = start.clone();
            StretchSweep::new(&stencil, MAX_STRETCH, Simd::detect()).limit_bands(
                &stencil,
                &bands,
                mesh.pinned(),
                &mut fast,
                None,
            );
            assert_same_bits(&fast, &course);
        }
    }

    /// The marks of `rows` of `positions` (the whole cloth) by the pre-pass the CPU runs and
    /// by the portable one, each masked by the springs that exist.
    fn both_prepasses(
        stencil: &Stencil,
        positions: &[Vec3],
        rows: Range<usize>,
    ) -> (Vec<Vec<u8>>, Vec<u8>) {
        let nw = stencil.nw();
        let sweep = StretchSweep::new(stencil, MAX_STRETCH, Simd::detect());
        let first = rows.start.saturating_sub(2) * nw;
        let window = &positions[first..rows.end * nw];
        let emitters = rows.start * nw..rows.end * nw;
        let margin = BandScratch::margin(nw);
        let run = |portable: bool| {
            let mut scratch = BandScratch::default();
            scratch.look.resize(margin + emitters.len() + margin, 0);
            let (bounds, rows) = (&sweep.bounds, rows.clone());
            if portable {
                scratch.prepass_rows(bounds, stencil, window, first, rows, None);
            } else {
                scratch.prepass(bounds, stencil, window, first, rows);
            }
            let exists = &sweep.bounds.exists[emitters.clone()];
            let marks = &scratch.look[margin..margin + emitters.len()];
            marks
                .iter()
                .zip(exists)
                .map(|(m, e)| m & e)
                .collect::<Vec<u8>>()
        };
        let portable = run(true);
        // The dispatched build.
        (vec![run(false)], portable)
    }

    #[test]
    fn the_dispatched_prepass_marks_what_the_portable_one_marks() {
        // Points jittered so springs fall on both sides of the bounds, one point NaN (all its
        // springs marked), widths that end in a partial group of four or fit none, and bands
        // that start inside the cloth, as threads sweep them.
        for (nw, rows) in [
            (4, 0..4),
            (5, 0..5),
            (7, 0..7),
            (9, 0..9),
            (3, 0..3),
            (53, 0..53),
            (21, 5..11),
            (21, 1..2),
            (21, 14..21),
        ] {
            let mesh = ClothMesh::pinned_grid(nw).unwrap();
            let stencil = Stencil::new(&mesh).unwrap();
            let mut rng = cloth_mesh::SplitMix64::new(nw as u64);
            let h = 0.06 / (nw - 1) as f64;
            let mut positions: Vec<Vec3> = mesh
                .start_positions()
                .iter()
                .map(|p| {
                    p * 1.06 + Vec3::new(rng.uniform(-h, h), rng.uniform(-h, h), rng.uniform(-h, h))
                })
                .collect();
            positions[mesh.len() / 2].y = f64::NAN;
            let (builds, portable) = both_prepasses(&stencil, &positions, rows);
            let marked = portable.iter().filter(|&&m| m != 0).count();
            assert!(
                marked > 0 && marked < portable.len(),
                "{nw}: the test needs marked and unmarked points"
            );
            for (i, marks) in builds.iter().enumerate() {
                assert_eq!(*marks, portable, "{nw} wide, build {i}");
            }
        }
    }

    #[test]
    fn exists_masks_count_the_meshs_springs() {
        let mesh = ClothMesh::pinned_grid(9).unwrap();
        let total: u32 = (0..mesh.len())
            .map(|i| exists_mask(9, i % 9, i / 9).count_ones())
            .sum();
        assert_eq!(total as usize, mesh.springs().len());
    }
}
