//! `LimitBasis`: every Gauss point's stencil and quadrature weight, computed once per mesh.
//!
//! This is the hand-off to the shell kinematics: assembly only gathers control points through
//! these stencils and scatters forces back; no patch type leaks past this module.

use super::bspline::bicubic_weights;
use super::surface::{
    BasisError, BoundaryRule, FaceKind, LimitStencil, LimitSurface, StencilTable,
};
use crate::mesh::PolyMesh;
use crate::quadrature::GaussLegendre;
use crate::Vec3;

/// Options for building a [`LimitBasis`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BasisOptions {
    pub boundary: BoundaryRule,
    /// Gauss points per direction on each face (1 to 8).
    pub gauss_points: usize,
}

impl Default for BasisOptions {
    fn default() -> Self {
        Self {
            boundary: BoundaryRule::Phantom,
            gauss_points: 4,
        }
    }
}

/// Precomputed limit stencils at the Gauss points of every face: quadrature point q belongs to
/// face `q / points_per_face` and its stencil is `stencils.row(q)`.
#[derive(Clone, Debug)]
pub struct LimitBasis {
    pub options: BasisOptions,
    /// Control points the stencils index (mesh vertices first, then ghosts).
    pub control_points: Vec<Vec3>,
    pub num_mesh_vertices: usize,
    pub num_faces: usize,
    pub face_kinds: Vec<FaceKind>,
    pub points_per_face: usize,
    /// (u, v) of each point within its face (the same for every face).
    pub face_uv: Vec<[f64; 2]>,
    /// Quadrature weight × parametric area of each point (parametric area is 1 per face).
    pub quad_weight: Vec<f64>,
    pub stencils: StencilTable,
    surface: std::sync::Arc<LimitSurface>,
}

/// Building a basis failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BasisBuildError {
    #[error(transparent)]
    Surface(#[from] BasisError),
    #[error(transparent)]
    Quadrature(#[from] crate::quadrature::BadOrder),
}

impl LimitBasis {
    /// Builds the basis of a quad mesh.
    pub fn new(mesh: &PolyMesh, options: BasisOptions) -> Result<Self, BasisBuildError> {
        let surface = LimitSurface::new(mesh, options.boundary)?;
        Self::from_surface(&surface, options.gauss_points)
    }

    /// Builds the basis of an already prepared limit surface.
    pub fn from_surface(
        surface: &LimitSurface,
        gauss_points: usize,
    ) -> Result<Self, BasisBuildError> {
        let rule = GaussLegendre::new(gauss_points)?.on_unit_square();
        let face_uv: Vec<[f64; 2]> = rule.iter().map(|r| r.0).collect();
        let bicubic: Vec<[[f64; 16]; 6]> = face_uv
            .iter()
            .map(|&[u, v]| bicubic_weights(u, v, 1.0))
            .collect();
        let nf = surface.num_faces();
        let npf = face_uv.len();
        let mut stencils = StencilTable::new();
        stencils.offsets.reserve(nf * npf);
        stencils.indices.reserve(16 * nf * npf);
        stencils.weights.reserve(16 * nf * npf);
        for face in 0..nf {
            surface.append_stencils(face, &face_uv, Some(&bicubic), &mut stencils)?;
        }
        let quad_weight = (0..nf).flat_map(|_| rule.iter().map(|r| r.1)).collect();
        Ok(Self {
            options: BasisOptions {
                boundary: surface.rule(),
                gauss_points,
            },
            control_points: surface.control_points().to_vec(),
            num_mesh_vertices: surface.num_mesh_vertices(),
            num_faces: nf,
            face_kinds: surface.face_kinds().to_vec(),
            points_per_face: npf,
            face_uv,
            quad_weight,
            stencils,
            surface: std::sync::Arc::new(surface.clone()),
        })
    }

    /// The limit surface the basis samples (to evaluate anywhere else).
    pub fn surface(&self) -> &LimitSurface {
        &self.surface
    }

    /// Number of quadrature points over the whole surface.
    pub fn num_points(&self) -> usize {
        self.quad_weight.len()
    }

    /// Stencil of quadrature point `q`.
    pub fn stencil(&self, q: usize) -> (&[u32], &[[f64; 6]]) {
        self.stencils.row(q)
    }

    /// Owned copy of a stencil.
    pub fn limit_stencil(&self, q: usize) -> LimitStencil {
        self.stencils.get(q)
    }

    /// Area of the limit surface for control positions `x`: Σ_q w_q |x_u × x_v|.
    pub fn area(&self, x: &[Vec3]) -> f64 {
        (0..self.num_points())
            .map(|q| {
                let p = self.limit_stencil(q).apply(x);
                let (a, b) = (p.d[1], p.d[2]);
                let n = [
                    a[1] * b[2] - a[2] * b[1],
                    a[2] * b[0] - a[0] * b[2],
                    a[0] * b[1] - a[1] * b[0],
                ];
                self.quad_weight[q] * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
            })
            .sum()
    }

    /// Volume enclosed by a closed limit surface (divergence theorem, (1/3)∫ x·n dA).
    pub fn enclosed_volume(&self, x: &[Vec3]) -> f64 {
        (0..self.num_points())
            .map(|q| {
                let p = self.limit_stencil(q).apply(x);
                let (a, b, c) = (p.d[1], p.d[2], p.d[0]);
                let n = [
                    a[1] * b[2] - a[2] * b[1],
                    a[2] * b[0] - a[0] * b[2],
                    a[0] * b[1] - a[1] * b[0],
                ];
                self.quad_weight[q] * (c[0] * n[0] + c[1] * n[1] + c[2] * n[2]) / 3.0
            })
            .sum()
    }

    /// Mean and largest number of control points per stencil.
    pub fn stencil_sizes(&self) -> (f64, usize) {
        let n = self.num_points();
        let max = (0..n).map(|q| self.stencil(q).0.len()).max().unwrap_or(0);
        (self.stencils.indices.len() as f64 / n.max(1) as f64, max)
    }
}
