//! The shell as a [`ClothModel`]: the solver's contract (see [`crate::model`]) met by
//! [`ShellModel`]'s own assembly.

use super::{BlockMatrix, BlockPattern, ShellModel, Want};
use crate::material::OutOfDomain;
use crate::model::ClothModel;
use crate::Vec3;
use std::sync::Arc;

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
