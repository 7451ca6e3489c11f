//! One linearisation of the solvers' iteration and the measure of its out-of-balance force
//! against the forces in the structure and the round-off floor (the convergence test of
//! [`super`]'s module docs; Clyde et al. 2017 §6).

use super::{norm, FreeSystem, SolveError, SolveReport};
use crate::model::{BlockMatrix, ClothModel, Want};
use crate::Vec3;
use std::time::Instant;

/// One assembly at `x` (energy, gradient, Hessian; K's entries into `values`), measured by
/// [`balance`]; records the energy, the relative residual, the iteration and the assembly time
/// in `report`.
pub(super) fn linearize(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &[Vec3],
    it: usize,
    (grad, hess, values, gf): (&mut [Vec3], &mut BlockMatrix, &mut Vec<f64>, &mut [f64]),
    (external, external_scale): (&[Vec3], f64),
    report: &mut SolveReport,
) -> Result<(f64, Balance), SolveError> {
    let ta = Instant::now();
    let energy = model
        .assemble(x, Want::Hessian, Some(grad), Some(hess))
        .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
    report.assembly_seconds += ta.elapsed().as_secs_f64();
    report.energy = energy;
    system.values(hess, values);
    let b = balance(system, x, grad, external, external_scale, values, gf);
    report.residual = if b.scale > 0.0 {
        b.gnorm / b.scale
    } else {
        b.gnorm
    };
    // forces that overflow compare equal to an infinite round-off floor: never a solution
    if !b.gnorm.is_finite() {
        return Err(if it == 0 {
            SolveError::StartOutOfDomain("its forces are not finite".into())
        } else {
            SolveError::NotConverged {
                iterations: it,
                residual: report.residual,
                factorizations: report.factorizations,
            }
        });
    }
    report.iterations = it;
    if it == 0 && report.initial_residual.is_none() {
        report.initial_residual = Some(report.residual);
    }
    Ok((energy, b))
}

/// The out-of-balance force and what it is measured against.
pub(super) struct Balance {
    /// ‖g_free‖₂.
    pub gnorm: f64,
    /// ‖internal force over all DOFs‖₂ + ‖external load‖₂.
    pub scale: f64,
    /// The round-off floor of the force evaluation.
    pub floor: f64,
}

/// What a residual is measured against: ‖internal force over all DOFs (gradient plus the
/// external load)‖₂ + ‖external load‖₂ (`external_scale`).
pub(super) fn force_scale(grad: &[Vec3], external: &[Vec3], external_scale: f64) -> f64 {
    let mut internal = 0.0;
    for (g, f) in grad.iter().zip(external) {
        for c in 0..3 {
            internal += (g[c] + f[c]).powi(2);
        }
    }
    internal.sqrt() + external_scale
}

/// Reduces `grad` into `gf` and measures it (see the module docs); `values` holds K's entries.
pub(super) fn balance(
    system: &FreeSystem,
    x: &[Vec3],
    grad: &[Vec3],
    external: &[Vec3],
    external_scale: f64,
    values: &[f64],
    gf: &mut [f64],
) -> Balance {
    system.reduce(grad, gf);
    // the round-off floor of the force evaluation: positions are known to ε‖x‖∞, so forces
    // to about ε‖diag K‖‖x‖∞ (residuals stall at 0.15–0.3 of this)
    let diag_norm = system
        .diag
        .iter()
        .map(|&k| values[k] * values[k])
        .sum::<f64>()
        .sqrt();
    let xmax = x.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    Balance {
        gnorm: norm(gf),
        scale: force_scale(grad, external, external_scale),
        floor: 2.0 * f64::EPSILON * diag_norm * xmax,
    }
}
