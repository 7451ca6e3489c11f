//! The solvers' entry points (Clyde et al. 2017 §6): equilibrium by Newton's method under the
//! chosen [`Strategy`] (the line search with the backward-Euler fallback,
//! [`super::line_search`], or the trust region, [`super::trust`]), and the stability and
//! residual of a given state.

use super::measure::force_scale;
use super::{norm, FreeSystem, Linearization, NewtonOptions, SolveError, SolveReport, Strategy};
use crate::model::{BlockMatrix, ClothModel, Want};
use crate::Vec3;

/// Whether `x` is a stable state of `system`: its reduced Hessian is positive definite (one
/// assembly and one Cholesky attempt; meaningful at an equilibrium).
pub fn is_stable(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &[Vec3],
) -> Result<bool, SolveError> {
    let mut x = x.to_vec();
    system.apply_constraints(&mut x);
    let mut grad = vec![[0.0; 3]; model.num_nodes()];
    let mut hess = BlockMatrix::zeros(model.pattern().clone());
    model
        .assemble(&x, Want::Hessian, Some(&mut grad), Some(&mut hess))
        .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
    let mut values = Vec::new();
    system.values(&hess, &mut values);
    Ok(system.try_factor(&values)?.is_some())
}

/// The relative residual ‖g_free‖ / force scale of `x` (constraints applied), as the solver
/// measures it at its first iteration (see the module docs of [`super`]): one gradient
/// assembly, for choosing between starts.
pub fn relative_residual(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &[Vec3],
) -> Result<f64, SolveError> {
    let mut x = x.to_vec();
    system.apply_constraints(&mut x);
    let mut grad = vec![[0.0; 3]; model.num_nodes()];
    model
        .assemble(&x, Want::Gradient, Some(&mut grad), None)
        .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
    let external = model.external_load();
    let scale = force_scale(&grad, &external, norm(&external.concat()));
    let gnorm = norm(&system.reduced(&grad));
    Ok(if scale > 0.0 { gnorm / scale } else { gnorm })
}

/// Solves for equilibrium from `x` (fixed DOFs keep their values, slaved ones follow), in place.
///
/// Each iteration assembles energy, gradient and Hessian and tests convergence. A Newton step
/// solves H d = −g (Cholesky, refined); a backward-Euler step solves (H + μM) d = −g, the
/// linearised minimiser of E(x) + μ/2 ‖x − x̂‖²_M (μ = 1/h², M the lumped mass), with μ raised
/// tenfold until the factorisation succeeds. Both are followed by a backtracking line search on
/// the energy. Backward Euler takes over when the Hessian is not positive definite, when the
/// Newton step is not a descent direction, when three Newton steps lower the energy by ≤ 0.1 %
/// without the residual falling tenfold (the paper's triggers), and when the line search cuts a
/// Newton step below 1/8. After each backward-Euler step Newton is tried again; h is adapted
/// like a trust region (μ ÷ 4 after a full step, × 4 after a cut one) and kept between uses.
///
/// With [`Strategy::TrustRegion`] the steps are trust-region steps instead (see
/// [`super::trust`]), the line search and backward Euler kept as the last resort.
pub fn newton(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    opts: &NewtonOptions,
) -> Result<SolveReport, SolveError> {
    newton_linearized(model, system, x, opts).map(|r| r.0)
}

/// [`newton`], also handing back the factorised tangent at the solution when it is positive
/// definite (the stability check factorises it anyway): sensitivities then cost no further
/// assembly or factorisation.
pub fn newton_linearized(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    opts: &NewtonOptions,
) -> Result<(SolveReport, Option<Linearization>), SolveError> {
    let result = match opts.strategy {
        Strategy::TrustRegion => super::trust::trust_region(model, system, x, opts),
        _ => super::line_search::line_search(model, system, x, opts),
    };
    if let Err(e) = &result {
        super::dump::on_failure(model, system, x, e);
    }
    result
}
