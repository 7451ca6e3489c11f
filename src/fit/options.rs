//! The settings of `ks-fit fit` ([`FitOptions`]) and their defaults, with the bounds the
//! command line checks them against: the one place the command line (and through it the batch
//! manifest's option columns) and `ks-fit check`'s preview read them from.

use super::coupling;
use super::optim::Method;
use super::MeshCheckMode;
use super::{BendingMode, Joint, Objective, RepeatMode, TestMeshes, ToeMode};

/// Settings of `ks-fit fit`.
#[derive(Clone, Debug)]
pub struct FitOptions {
    /// Highest degree of each η tried.
    pub max_degree: usize,
    /// Use exactly this degree for every η (no automatic choice), for comparisons.
    pub fixed_degree: Option<usize>,
    /// Meshes of a 50 × 75 mm strip, coarse to fine; other strips keep the element size.
    pub ladder: Vec<(usize, usize)>,
    pub method: Method,
    /// Skip a finer level when it changes the fitted forces by less than this, mean relative
    /// (solved, for the second level); later levels are estimated from the last change at
    /// the mesh check's order (`mesh_check::order`) and judged by its 1 % / 0.3 % rule.
    /// Default 1 %: below the repeat-to-repeat scatter of real tests and the paper's fit
    /// errors (Table 3: 1–5 %).
    pub skip_tol: f64,
    /// A degree is raised only if that lowers the mean relative error by at least this factor.
    pub degree_gain: f64,
    /// Mean relative error below which a degree fits (no higher degree is tried).
    pub degree_good: f64,
    /// Elongation nodes per strip at which the model is solved.
    pub nodes: usize,
    /// A stage stops once its rms relative error is below this, or when an iteration lowers
    /// the objective by less than `rel_decrease`.
    pub fit_tol: f64,
    pub rel_decrease: f64,
    pub max_iterations: usize,
    /// The paper's protocol: 0°, 45° and 90° fitted, other angles validation (default: every
    /// angle fitted unless its `role` says otherwise).
    pub paper_protocol: bool,
    pub repeats: RepeatMode,
    pub toe: ToeMode,
    /// Bound of the validation runs' misalignment diagnostic, degrees (0: off).
    pub max_misalign_deg: f64,
    /// A fitted test whose error exceeds this (mean relative) fails the fit: see [`verdict`].
    pub max_error: f64,
    /// How every strip and cantilever solve of the fit is globalised and its load brought on.
    pub strategy: crate::solve::Strategy,
    /// Bending of its own (fitted rigidities) or the paper's one thickness.
    pub bending: BendingMode,
    /// Estimate how much refining the last mesh level once more would change the fit
    /// ([`MeshCheck`]): one solve of every fitted test on a coarser or the finer mesh.
    pub mesh_check: MeshCheckMode,
    /// Cage grading of every strip ([`crate::scene::STRIP_GRADING`] by default: the bias
    /// strips' forces converge at order 2 on it, 1.2 on uniform cages).
    pub grading: crate::mesh::Grading,
    /// Each strip refined on its own until its mesh error meets its tolerance, or every strip
    /// on the ladder's level ([`TestMeshes`]).
    pub test_meshes: TestMeshes,
    /// How every solve integrates the yarn terms (`Auto`: decided once after the bootstrap).
    pub yarn_rule: crate::assembly::YarnRule,
    /// Whether the shear stage also fits the tension–shear coupling ([`coupling`]).
    pub shear_coupling: coupling::CouplingMode,
    /// How a point's misfit enters the tensile stages' objective ([`Objective`]).
    pub objective: Objective,
    /// Whether the yarn stages also see the off-axis strips ([`Joint`]).
    pub joint: Joint,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            max_degree: 3,
            fixed_degree: None,
            ladder: vec![(8, 12), (16, 24)],
            method: Method::Hybrid,
            skip_tol: 1e-2,
            degree_gain: 0.7,
            degree_good: 2e-3,
            nodes: 9,
            fit_tol: 1e-3,
            rel_decrease: 1e-2,
            max_iterations: 25,
            paper_protocol: false,
            repeats: RepeatMode::All,
            toe: ToeMode::Auto,
            max_misalign_deg: 2.0,
            strategy: crate::solve::Strategy::default(),
            max_error: 0.10,
            bending: BendingMode::Auto,
            mesh_check: MeshCheckMode::default(),
            grading: crate::scene::STRIP_GRADING,
            test_meshes: TestMeshes::Strict,
            yarn_rule: crate::assembly::YarnRule::Auto,
            shear_coupling: coupling::CouplingMode::Auto,
            objective: Objective::Auto,
            joint: Joint::Auto,
        }
    }
}

/// Highest degree of an η the fit accepts (each degree adds two parameters per direction).
pub const MAX_DEGREE: usize = 8;
/// The fewest and the most elongation nodes per strip ([`FitOptions::nodes`]).
pub const NODES_RANGE: (usize, usize) = (4, 200);
/// Largest bound of the misalignment diagnostic ([`FitOptions::max_misalign_deg`]), degrees.
pub const MAX_MISALIGN_DEG: f64 = 15.0;
