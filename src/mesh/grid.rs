//! Programmatic rectangular cages (strips for the virtual lab).

use super::PolyMesh;

/// A flat `width` × `length` rectangle in the z = 0 plane, split into `nx` × `ny` quads.
///
/// x runs over [0, width] with `nx` faces, y over [0, length] with `ny` faces. Vertex (i, j) has
/// index `j * (nx + 1) + i`; face (i, j) has index `j * nx + i` and corners
/// (i, j), (i+1, j), (i+1, j+1), (i, j+1), so its u runs along +x and its v along +y and its
/// normal is +z.
///
/// Note: this is the *control* cage. With the phantom boundary rule its limit surface covers the
/// same rectangle exactly, because the rule reproduces affine maps up to the boundary.
pub fn rectangular_grid(width: f64, length: f64, nx: usize, ny: usize) -> PolyMesh {
    let mut positions = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            positions.push([
                width * i as f64 / nx as f64,
                length * j as f64 / ny as f64,
                0.0,
            ]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut faces = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            faces.push(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    PolyMesh::new(positions, faces)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Topology;

    #[test]
    fn grid_counts_and_valences() {
        let m = rectangular_grid(50.0, 75.0, 8, 12);
        assert_eq!(m.num_vertices(), 9 * 13);
        assert_eq!(m.num_faces(), 96);
        let t = Topology::build(&m).unwrap();
        assert_eq!(t.num_boundary_edges(), 2 * (8 + 12));
        let corners = t.valence.iter().filter(|&&v| v == 2).count();
        let sides = t.valence.iter().filter(|&&v| v == 3).count();
        let inner = t.valence.iter().filter(|&&v| v == 4).count();
        assert_eq!((corners, sides, inner), (4, 2 * (7 + 11), 7 * 11));
    }
}
