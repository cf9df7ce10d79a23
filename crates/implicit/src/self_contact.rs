//! The pairs of points that self-collision may push apart during a step, found at its start.

use cloth_mesh::{ClothMesh, Vec3};

/// Pairs of points closer than a distance `D`, from a uniform grid of cells of side `2 D`: a
/// point's partners within `D` lie, along each axis, in its own cell or the neighbour on the
/// side of the cell's middle it is on, so it looks into those eight.
///
/// Cells are keyed by a hash of their integer coordinates and the points sorted by key, so a
/// search allocates nothing once the arrays have grown. Two cells that share a key only add
/// candidates, which the distance test removes; a pair found twice is kept once.
#[derive(Debug, Default)]
pub(crate) struct SelfContacts {
    /// `(cell key, point)` sorted.
    cells: Vec<(u64, u32)>,
    /// The pairs `(i, j)`, `i < j`, sorted and without repeats.
    pairs: Vec<(u32, u32)>,
}

/// The key of the cell with integer coordinates `c`.
fn cell_key(c: [i64; 3]) -> u64 {
    // NOTE: the large odd multipliers spread neighbouring cells over the key space; a shared
    // key only costs a distance test.
    (c[0] as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (c[1] as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (c[2] as u64).wrapping_mul(0x1656_67B1_9E37_79F9)
}

fn cell_of(p: &Vec3, size: f64) -> [i64; 3] {
    [
        (p.x / size).floor() as i64,
        (p.y / size).floor() as i64,
        (p.z / size).floor() as i64,
    ]
}

/// Per axis, the neighbouring cell on the side of its cell that `p` is nearer to (-1 or +1).
fn near_side(p: &Vec3, size: f64) -> [i64; 3] {
    [p.x, p.y, p.z].map(|v| {
        let scaled = v / size;
        if scaled - scaled.floor() < 0.5 { -1 } else { 1 }
    })
}

impl SelfContacts {
    /// Finds the pairs of points of `mesh`, not both pinned, closer than `reach` in any of
    /// `configurations` (each a position per point), replacing the last search's.
    pub(crate) fn find(&mut self, mesh: &ClothMesh, configurations: &[&[Vec3]], reach: f64) {
        self.pairs.clear();
        if !(reach.is_finite() && reach > 0.0) {
            return;
        }
        let pinned = mesh.pinned();
        let reach2 = reach * reach;
        let size = 2.0 * reach;
        for positions in configurations {
            self.cells.clear();
            self.cells.extend(
                positions
                    .iter()
                    .enumerate()
                    .map(|(i, p)| (cell_key(cell_of(p, size)), i as u32)),
            );
            self.cells.sort_unstable();
            for (i, p) in positions.iter().enumerate() {
                let c = cell_of(p, size);
                let side = near_side(p, size);
                for dx in [0, side[0]] {
                    for dy in [0, side[1]] {
                        for dz in [0, side[2]] {
                            let key = cell_key([c[0] + dx, c[1] + dy, c[2] + dz]);
                            let from = self.cells.partition_point(|&(k, _)| k < key);
                            for &(k, j) in &self.cells[from..] {
                                if k != key {
                                    break;
                                }
                                let j = j as usize;
                                if j <= i || (pinned[i] && pinned[j]) {
                                    continue;
                                }
                                if (positions[j] - p).norm_squared() < reach2 {
                                    self.pairs.push((i as u32, j as u32));
                                }
                            }
                        }
                    }
                }
            }
        }
        self.pairs.sort_unstable();
        self.pairs.dedup();
    }

    /// Forgets the last search's pairs.
    pub(crate) fn clear(&mut self) {
        self.pairs.clear();
    }

    /// The pairs of the last search, `(i, j)` with `i < j`, sorted.
    pub(crate) fn pairs(&self) -> &[(u32, u32)] {
        &self.pairs
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_mesh::{GridSpec, SplitMix64};

    #[test]
    fn finds_exactly_the_pairs_closer_than_the_reach() {
        let mesh = ClothMesh::new(&GridSpec {
            num_width_points: 12,
            num_height_points: 10,
            pinned: vec![(0, 0), (1, 0)],
            ..GridSpec::default()
        })
        .unwrap();
        let mut rng = SplitMix64::new(3);
        let scatter = |rng: &mut SplitMix64| -> Vec<Vec3> {
            (0..mesh.len())
                .map(|_| {
                    Vec3::new(
                        rng.uniform(-0.1, 0.1),
                        rng.uniform(-0.1, 0.1),
                        rng.uniform(-0.1, 0.1),
                    )
                })
                .collect()
        };
        let (a, b) = (scatter(&mut rng), scatter(&mut rng));
        let reach = 0.03;
        let mut found = SelfContacts::default();
        found.find(&mesh, &[&a, &b], reach);
        let mut expected = Vec::new();
        for i in 0..mesh.len() {
            for j in i + 1..mesh.len() {
                let both_pinned = mesh.pinned()[i] && mesh.pinned()[j];
                let close = (a[i] - a[j]).norm() < reach || (b[i] - b[j]).norm() < reach;
                if close && !both_pinned {
                    expected.push((i as u32, j as u32));
                }
            }
        }
        assert!(!expected.is_empty());
        assert_eq!(found.pairs(), expected.as_slice());
    }
}
