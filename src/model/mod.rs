//! The contract between a discretisation and the solver: a cloth model is a total energy over
//! node positions with its gradient and sparse Hessian in 3 × 3 blocks, a constant external
//! load and a lumped mass (the backward-Euler metric). The subdivision shell
//! ([`crate::assembly::ShellModel`], Clyde et al. 2017) is one; the triangle-mesh models of
//! Miguel et al. 2012 ([`crate::tri`]) are the others. Everything in [`crate::solve`] works on
//! any of them.

pub mod blocks;

use crate::material::OutOfDomain;
use crate::Vec3;
pub use blocks::{BlockMatrix, BlockPattern};
use std::sync::Arc;

/// What to assemble.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Want {
    Energy,
    Gradient,
    Hessian,
    /// A convexified Hessian: at every Gauss point the section tangent is projected onto its
    /// positive semidefinite part, the membrane stress weighting the strains' own Hessian is
    /// replaced by its tensile part, and the bending moments' term is dropped, so that the
    /// assembled matrix is positive semidefinite (a modified-Newton model; see
    /// `solve::newton`).
    ProjectedHessian,
}

impl Want {
    /// Whether a Hessian (exact or projected) is wanted.
    #[inline(always)]
    pub fn hessian(self) -> bool {
        matches!(self, Want::Hessian | Want::ProjectedHessian)
    }
}

/// A discretised cloth whose equilibria are the stationary points of a total energy.
pub trait ClothModel: Sync {
    /// The Hessian's block pattern (fixed for the model's lifetime).
    fn pattern(&self) -> &Arc<BlockPattern>;
    fn num_nodes(&self) -> usize;
    /// Total energy (loads included) and, as asked, its gradient over all nodes (into `grad`,
    /// overwritten) and its Hessian (into `hess`, overwritten).
    fn assemble(
        &self,
        x: &[Vec3],
        want: Want,
        grad: Option<&mut [Vec3]>,
        hess: Option<&mut BlockMatrix>,
    ) -> Result<f64, OutOfDomain>;
    /// The constant external force on each node, N (gravity and dead loads).
    fn external_load(&self) -> Vec<Vec3>;
    /// Lumped mass of each node, kg (a metric when the cloth is weightless).
    fn lumped_mass(&self) -> Vec<f64>;
    /// Total energy.
    fn energy(&self, x: &[Vec3]) -> Result<f64, OutOfDomain> {
        self.assemble(x, Want::Energy, None, None)
    }
    /// Whether [`Want::ProjectedHessian`] gives a convexified Hessian (the shell's, see
    /// [`Want`]); models without one hand back their exact Hessian there, and
    /// the solver does not ask them for it.
    fn convexifies(&self) -> bool {
        false
    }
}
