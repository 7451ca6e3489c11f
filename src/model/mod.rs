//! The contract between a discretisation and the solver: a cloth model is a total energy over
//! node positions with its gradient and sparse Hessian in 3 × 3 blocks, a constant external
//! load and a lumped mass (the backward-Euler metric). The subdivision shell
//! ([`crate::assembly::ShellModel`], Clyde et al. 2017) is one; the triangle-mesh models of
//! Miguel et al. 2012 ([`crate::tri`]) are the others. Everything in [`crate::solve`] works on
//! any of them.

pub mod compare;

use crate::assembly::{BlockMatrix, BlockPattern, ShellModel, Want};
use crate::material::OutOfDomain;
use crate::Vec3;
use std::sync::Arc;

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
    /// [`crate::assembly::Want`]); models without one hand back their exact Hessian there, and
    /// the solver does not ask them for it.
    fn convexifies(&self) -> bool {
        false
    }
}

impl ClothModel for ShellModel {
    fn pattern(&self) -> &Arc<BlockPattern> {
        &self.pattern
    }
    fn num_nodes(&self) -> usize {
        ShellModel::num_nodes(self)
    }
    fn assemble(
        &self,
        x: &[Vec3],
        want: Want,
        grad: Option<&mut [Vec3]>,
        hess: Option<&mut BlockMatrix>,
    ) -> Result<f64, OutOfDomain> {
        ShellModel::assemble(self, x, want, grad, hess)
    }
    fn external_load(&self) -> Vec<Vec3> {
        ShellModel::external_load(self)
    }
    fn lumped_mass(&self) -> Vec<f64> {
        ShellModel::lumped_mass(self)
    }
    fn energy(&self, x: &[Vec3]) -> Result<f64, OutOfDomain> {
        ShellModel::energy(self, x)
    }
    fn convexifies(&self) -> bool {
        true
    }
}
