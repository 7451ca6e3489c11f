//! The fallback factorisations of the line-search solver (Clyde et al. 2017 §6): backward Euler
//! (H + μM) and the convexified Hessian.

use super::{FreeSystem, SolveError, SolveReport};
use crate::model::{BlockMatrix, ClothModel, Want};
use crate::Vec3;
use faer::sparse::linalg::solvers::Llt;
use std::time::Instant;

/// Assembles and factorises the convexified Hessian at `x` ([`Want::ProjectedHessian`]: each
/// Gauss point's section tangent projected onto its positive semidefinite part, compression
/// dropped from the stress term, the moments' term left out) into `values`; `None` where it is
/// singular (its factorisation counted).
///
/// Used for the fallback step that follows a negative-curvature step: the curvature step
/// leaves the saddle, and a step on this tangent, which keeps every stiffness that is positive,
/// then moves the whole state down at once, where backward Euler (H + μM) damps every soft mode
/// alike. Alone, without the curvature steps, it cannot leave a symmetric saddle (its gradient
/// has no component along the buckling mode) and stalls there.
pub(super) fn convexified_factor(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &[Vec3],
    hess: &mut BlockMatrix,
    values: &mut Vec<f64>,
    report: &mut SolveReport,
) -> Result<Option<Llt<usize, f64>>, SolveError> {
    let ta = Instant::now();
    model
        .assemble(x, Want::ProjectedHessian, None, Some(hess))
        .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
    report.assembly_seconds += ta.elapsed().as_secs_f64();
    system.values(hess, values);
    let llt = system.try_factor(values)?;
    if llt.is_none() {
        report.factorizations += 1;
    }
    Ok(llt)
}

/// Factorises H + μM, raising μ tenfold until the factorisation succeeds. `values` comes back
/// holding H + μM.
pub(super) fn backward_euler_factor(
    system: &FreeSystem,
    values: &mut [f64],
    mass: &[f64],
    mu: &mut f64,
    report: &mut SolveReport,
) -> Result<Llt<usize, f64>, SolveError> {
    let mean_diag =
        system.diag.iter().map(|&k| values[k].abs()).sum::<f64>() / system.diag.len().max(1) as f64;
    let mean_mass = mass.iter().sum::<f64>() / mass.len().max(1) as f64;
    if !mu.is_finite() || *mu <= 0.0 {
        // start where the mass term is a thousandth of the stiffness
        *mu = 1e-3 * mean_diag / mean_mass.max(f64::MIN_POSITIVE);
    }
    let mut applied = 0.0;
    for _ in 0..40 {
        for (&k, &m) in system.diag.iter().zip(mass) {
            values[k] += (*mu - applied) * m;
        }
        applied = *mu;
        if let Some(llt) = system.try_factor(values)? {
            return Ok(llt);
        }
        report.factorizations += 1;
        *mu *= 10.0;
    }
    Err(SolveError::Linear(
        "no backward-Euler step size makes the system positive definite".into(),
    ))
}
