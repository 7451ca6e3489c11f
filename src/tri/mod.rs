//! Triangle-mesh cloth models beside the subdivision shell (Miguel et al. 2012, "Data-Driven
//! Estimation of Cloth Simulation Models"; Larionov et al. 2022, "Estimating Cloth Elasticity
//! Parameters Using Position-Based Simulation of Compliant Constrained Dynamics"):
//! a triangulated grid ([`grid`]), the models' parameters ([`params`]) with spline stiffness
//! ([`curve`]), and their energies ([`model`]), which the Newton solvers of [`crate::solve`]
//! minimise like the shell's.

pub mod curve;
pub mod file;
pub mod grid;
pub mod jet;
pub mod model;
pub mod params;
pub mod xpbd;

pub use curve::Stiffness;
pub use grid::TriGrid;
pub use model::TriModel;
pub use params::{TriKind, TriMaterial, ZeroStrain};
