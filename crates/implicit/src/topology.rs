//! Numbering of the free (unpinned) points and the sparsity patterns built on it.

use cloth_mesh::ClothMesh;

/// Marks a pinned point in [`Topology::free_index`] and a spring with a pinned end in
/// [`Topology::spring_slot`].
pub(crate) const NONE: u32 = u32::MAX;

/// The free points of a mesh and, for each, its free neighbours of higher index, which is the
/// lower-triangular pattern of every matrix the implicit solvers factor.
///
/// Pinned points are eliminated: they are not unknowns, and the springs that tie a free point to
/// a pinned one only add to that point's diagonal block and right-hand side.
#[derive(Debug, Clone)]
pub(crate) struct Topology {
    /// The key the caches were built for: point count, spring count and the pin set.
    points: usize,
    springs: usize,
    pinned: Vec<bool>,
    /// Free index of each point, or [`NONE`] when pinned. Free indices keep point order.
    pub(crate) free_index: Vec<u32>,
    /// Point index of each free point.
    pub(crate) free_points: Vec<u32>,
    /// Start of each free point's list in `neighbours` (length `free + 1`).
    pub(crate) nbr_ptr: Vec<usize>,
    /// Free neighbours of strictly higher free index, sorted, per free point.
    pub(crate) neighbours: Vec<u32>,
    /// For each spring with two free ends: the position of the higher end in the lower end's
    /// neighbour list; [`NONE`] when an end is pinned.
    pub(crate) spring_slot: Vec<u32>,
}

impl Topology {
    /// Numbers the free points of `mesh` and builds the neighbour lists.
    pub(crate) fn new(mesh: &ClothMesh) -> Self {
        let pinned = mesh.pinned().to_vec();
        let mut free_index = vec![NONE; pinned.len()];
        let mut free_points = Vec::new();
        for (i, &p) in pinned.iter().enumerate() {
            if !p {
                free_index[i] = free_points.len() as u32;
                free_points.push(i as u32);
            }
        }
        let nfree = free_points.len();
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); nfree];
        for s in mesh.springs() {
            let (fa, fb) = (free_index[s.a as usize], free_index[s.b as usize]);
            if fa != NONE && fb != NONE && fa != fb {
                let (lo, hi) = (fa.min(fb), fa.max(fb));
                lists[lo as usize].push(hi);
            }
        }
        let mut nbr_ptr = Vec::with_capacity(nfree + 1);
        let mut neighbours = Vec::new();
        nbr_ptr.push(0);
        for list in &mut lists {
            list.sort_unstable();
            list.dedup();
            neighbours.extend_from_slice(list);
            nbr_ptr.push(neighbours.len());
        }
        let spring_slot = mesh
            .springs()
            .iter()
            .map(|s| {
                let (fa, fb) = (free_index[s.a as usize], free_index[s.b as usize]);
                if fa == NONE || fb == NONE || fa == fb {
                    return NONE;
                }
                let (lo, hi) = (fa.min(fb) as usize, fa.max(fb));
                let list = &neighbours[nbr_ptr[lo]..nbr_ptr[lo + 1]];
                // NOTE: `hi` was pushed into this very list above, so the search always hits.
                list.binary_search(&hi).map_or(NONE, |t| t as u32)
            })
            .collect();
        Self {
            points: mesh.len(),
            springs: mesh.springs().len(),
            pinned,
            free_index,
            free_points,
            nbr_ptr,
            neighbours,
            spring_slot,
        }
    }

    /// Whether the caches built for this topology still describe `mesh`.
    pub(crate) fn matches(&self, mesh: &ClothMesh) -> bool {
        self.points == mesh.len()
            && self.springs == mesh.springs().len()
            && self.pinned == mesh.pinned()
    }

    /// Bytes this topology holds.
    pub(crate) fn bytes(&self) -> u64 {
        (self.pinned.len()
            + 4 * (self.free_index.len()
                + self.free_points.len()
                + self.neighbours.len()
                + self.spring_slot.len())
            + 8 * self.nbr_ptr.len()) as u64
    }

    /// Number of free points.
    pub(crate) fn free(&self) -> usize {
        self.free_points.len()
    }

    /// Free neighbours of higher index of free point `f`.
    pub(crate) fn upper_neighbours(&self, f: usize) -> &[u32] {
        &self.neighbours[self.nbr_ptr[f]..self.nbr_ptr[f + 1]]
    }

    /// The scalar lower-triangular pattern (one unknown per free point): column `f` holds the
    /// diagonal, then the higher neighbours in order.
    pub(crate) fn scalar_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        let n = self.free();
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::with_capacity(n + self.neighbours.len());
        col_ptr.push(0);
        for f in 0..n {
            row_idx.push(f);
            row_idx.extend(self.upper_neighbours(f).iter().map(|&q| q as usize));
            col_ptr.push(row_idx.len());
        }
        (col_ptr, row_idx)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_mesh::GridSpec;

    #[test]
    fn pinned_points_are_not_unknowns_and_every_free_spring_has_a_slot() {
        let mesh = ClothMesh::new(&GridSpec {
            num_width_points: 4,
            num_height_points: 3,
            pinned: vec![(0, 0), (3, 0)],
            ..GridSpec::default()
        })
        .unwrap();
        let t = Topology::new(&mesh);
        assert_eq!(t.free(), 10);
        assert_eq!(t.free_index[0], NONE);
        assert_eq!(t.free_index[1], 0);
        for (s, &slot) in mesh.springs().iter().zip(&t.spring_slot) {
            let pinned_end = mesh.pinned()[s.a as usize] || mesh.pinned()[s.b as usize];
            assert_eq!(slot == NONE, pinned_end, "{s:?}");
        }
        let (col_ptr, row_idx) = t.scalar_pattern();
        assert_eq!(col_ptr.len(), 11);
        // Every stored entry is in the lower triangle, rows sorted within a column.
        for j in 0..10 {
            let rows = &row_idx[col_ptr[j]..col_ptr[j + 1]];
            assert!(rows.iter().all(|&r| r >= j));
            assert!(rows.windows(2).all(|w| w[0] < w[1]));
        }
        assert!(t.matches(&mesh));
    }
}
