//! The Catmull–Clark limit-surface basis (Clyde et al. 2017 §3 discretise the cloth with
//! Catmull–Clark subdivision surfaces, after Cirak, Ortiz & Schröder 2000).
//!
//! Owns: exact evaluation of the limit surface and its first and second parametric derivatives
//! as *stencils* (control index, weight) on regular, boundary and extraordinary faces
//! ([`LimitSurface`]); the two boundary treatments ([`BoundaryRule`]); uniform refinement
//! ([`refine_uniform`]); and the per-mesh table of Gauss-point stencils ([`LimitBasis`]).
//!
//! References: E. Catmull & J. Clark, Recursively generated B-spline surfaces on arbitrary
//! topological meshes, CAD 10(6), 1978. J. Stam, Exact evaluation of Catmull–Clark subdivision
//! surfaces at arbitrary parameter values, SIGGRAPH 1998. F. Cirak, M. Ortiz, P. Schröder,
//! Subdivision surfaces: a new paradigm for thin-shell finite-element analysis, IJNME 47, 2000.

mod basis;
pub mod bspline;
mod cage;
mod ghost;
mod patch;
mod surface;

pub use basis::{BasisBuildError, BasisOptions, LimitBasis};
pub use cage::refine_uniform;
pub use surface::{
    deriv, BasisError, BoundaryRule, FaceKind, LimitPoint, LimitStencil, LimitSurface, StencilTable,
};
