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
    graded_grid(width, length, nx, ny, Grading::UNIFORM)
}

/// How a strip's control rows and columns crowd towards its edges: the cage line k of n sits
/// at g(k/n) of the side with g(t) = t − a sin(2πt)/(2π), 0 ≤ a < 1, so the cells at both
/// edges are (1 − a)/(1 + a) times the middle ones and g is smooth, odd about each edge (a
/// reflected ghost line stays on the lattice) and one-to-one on the whole line. The limit
/// surface of a graded cage covers the same rectangle (the boundary rules interpolate the
/// edge lines); only how the parameter domain is spread over it changes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grading {
    /// a across the strip (x, towards its free edges)
    pub across: f64,
    /// a along the strip (y, towards the jaws)
    pub along: f64,
}

/// "across,along", as `--grading` takes it.
impl std::fmt::Display for Grading {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "{},{}", self.across, self.along)
    }
}

impl Grading {
    pub const UNIFORM: Self = Self {
        across: 0.0,
        along: 0.0,
    };

    /// g(t) with strength `a`.
    pub fn map(a: f64, t: f64) -> f64 {
        use std::f64::consts::TAU;
        t - a * (TAU * t).sin() / TAU
    }

    /// t with g(t) = s (Newton from s; g' ≥ 1 − a > 0).
    pub fn inverse(a: f64, s: f64) -> f64 {
        use std::f64::consts::TAU;
        let mut t = s;
        for _ in 0..50 {
            let f = Self::map(a, t) - s;
            let d = 1.0 - a * (TAU * t).cos();
            let step = f / d;
            t -= step;
            if step.abs() < 1e-15 {
                break;
            }
        }
        t
    }

    /// Whether both strengths are in [0, 1).
    pub fn is_valid(&self) -> bool {
        [self.across, self.along]
            .iter()
            .all(|a| a.is_finite() && (0.0..1.0).contains(a))
    }
}

/// [`rectangular_grid`] with its lines crowded towards the edges by `grading`.
pub fn graded_grid(width: f64, length: f64, nx: usize, ny: usize, grading: Grading) -> PolyMesh {
    let mut positions = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            positions.push([
                width * Grading::map(grading.across, i as f64 / nx as f64),
                length * Grading::map(grading.along, j as f64 / ny as f64),
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
    fn grading_is_one_to_one_odd_at_the_edges_and_inverted() {
        for a in [0.0, 0.3, 0.7, 0.95] {
            assert_eq!(Grading::map(a, 0.0), 0.0);
            assert!((Grading::map(a, 1.0) - 1.0).abs() < 1e-15);
            for t in [-0.2, 0.05, 0.3, 0.5, 0.9, 1.1] {
                // odd about both edges: a reflected ghost line stays on the lattice
                assert!((Grading::map(a, -t) + Grading::map(a, t)).abs() < 1e-15);
                assert!((Grading::map(a, 1.0 + t) + Grading::map(a, 1.0 - t) - 2.0).abs() < 1e-14);
                assert!((Grading::inverse(a, Grading::map(a, t)) - t).abs() < 1e-13);
            }
        }
        // edge cells (1 − a)/(1 + a) of the middle ones, to first order in 1/n
        let g = graded_grid(
            1.0,
            1.0,
            2,
            40,
            Grading {
                across: 0.0,
                along: 0.5,
            },
        );
        let y = |j: usize| g.positions[j * 3][1];
        let ratio = (y(1) - y(0)) / (y(21) - y(20));
        assert!((ratio - 1.0 / 3.0).abs() < 0.01, "{ratio}");
    }

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
