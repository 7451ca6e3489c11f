//! [`SurfaceMesh`]: a deformed sheet's surface as a welded quad mesh with normals and texture
//! coordinates, the form in which scenes write, draw and measure their shapes (written by
//! [`super::export`]).

use crate::shape::ShapeMesh;
use crate::Vec3;

/// A sampled limit surface: positions, normals and (u, v) per vertex, quads as vertex indices
/// (counter-clockwise seen from the normal's side).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uv: Vec<[f64; 2]>,
    pub quads: Vec<[usize; 4]>,
}

impl SurfaceMesh {
    /// The sampled sheet as a triangulated shape (quads split along one diagonal).
    pub fn to_shape(&self) -> ShapeMesh {
        ShapeMesh {
            positions: self.positions.clone(),
            uv: Ok(self.uv.clone()),
            triangles: self
                .quads
                .iter()
                .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
                .collect(),
        }
    }
}
