//! The cloth as a Wavefront OBJ: positions, texture coordinates from the grid, normals.

use std::fmt::Write as _;

use cloth_mesh::{ClothMesh, Vec3, vertex_normals};

/// A Wavefront OBJ of the cloth at `positions`: a comment naming `what`, one `v` per point
/// (metres), one `vt` per point (`u` along the width, `v` along the height, both in [0, 1]
/// over the grid), one area-weighted `vn` per point, and the mesh's triangles as
/// `f a/a/a b/b/b c/c/c` (1-based; every point has its own texture coordinate and normal).
pub fn obj(mesh: &ClothMesh, positions: &[Vec3], what: &str) -> String {
    let mut normals = Vec::new();
    vertex_normals(mesh, positions, &mut normals);
    let mut s = String::with_capacity(mesh.len() * 120);
    let _ = writeln!(s, "# clothsim: {what}");
    for p in positions {
        let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
    }
    let (nw, nh) = (mesh.nw(), mesh.nh());
    let along = |i: usize, n: usize| {
        if n > 1 {
            i as f64 / (n - 1) as f64
        } else {
            0.0
        }
    };
    for y in 0..nh {
        for x in 0..nw {
            let _ = writeln!(s, "vt {} {}", along(x, nw), along(y, nh));
        }
    }
    for n in &normals {
        let _ = writeln!(s, "vn {} {} {}", n.x, n.y, n.z);
    }
    for t in mesh.triangles() {
        let [a, b, c] = t.map(|i| i + 1);
        let _ = writeln!(s, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_mesh::{ClothState, GridSpec};

    #[test]
    fn texture_coordinates_span_the_grid_from_zero_to_one() {
        let mesh = ClothMesh::new(&GridSpec {
            num_width_points: 3,
            num_height_points: 2,
            ..GridSpec::default()
        })
        .unwrap();
        let text = obj(&mesh, &ClothState::new(&mesh).positions, "test");
        let vt: Vec<&str> = text.lines().filter(|l| l.starts_with("vt ")).collect();
        assert_eq!(
            vt,
            [
                "vt 0 0", "vt 0.5 0", "vt 1 0", "vt 0 1", "vt 0.5 1", "vt 1 1"
            ]
        );
        assert_eq!(text.lines().filter(|l| l.starts_with("vn ")).count(), 6);
        assert_eq!(text.lines().filter(|l| l.starts_with("f ")).count(), 4);
        assert!(text.contains("\nf 1/1/1 4/4/4 2/2/2\n"), "{text}");
    }
}
