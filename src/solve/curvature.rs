//! Steps along negative curvature: where the Hessian K is indefinite (a strip wrinkling or
//! buckling, a sheet leaving a symmetric state) the direction of most negative curvature v is
//! found by inverse iteration on the backward-Euler factor of K + μM, and the energy is searched
//! along ±v (Moré & Sorensen, "On the use of directions of negative curvature in a modified
//! Newton method", Math. Prog. 16, 1979). Backward-Euler steps alone leave a saddle by a factor
//! of about 1 + |λ|/(μ − |λ|) per step, slowly when μ is well above the threshold; a curvature
//! step moves the whole way down the unstable direction at once.

use super::{FreeSystem, SolveReport};
use crate::model::ClothModel;
use crate::Vec3;
use faer::prelude::Solve;
use faer::sparse::linalg::solvers::Llt;
use faer::MatMut;

/// Inverse-iteration sweeps (each one solve with the factor already at hand).
const SWEEPS: usize = 6;

/// The first trial step moves some DOF by this fraction of the body's size. The cotton fit's 380
/// searches all succeed, after 3–10 halvings; starting each search from twice the last
/// accepted step would save those energy evaluations but changes the paths through the
/// wrinkling states: the atlas's a11/G12 = 1e6 strip takes 292 iterations that way, 151 this.
const FIRST_STEP: f64 = 0.05;

/// Direction of most negative curvature of K in the mass metric and its curvature vᵀKv
/// (vᵀMv = 1), or `None` if the direction found has no negative curvature. `shifted` holds
/// K + μM, factorised in `llt`.
pub(super) fn direction(
    system: &FreeSystem,
    llt: &Llt<usize, f64>,
    shifted: &[f64],
    mu: f64,
    mass: &[f64],
    seed: &mut u64,
) -> Option<(Vec<f64>, f64)> {
    let nf = system.num_free;
    let mut v: Vec<f64> = (0..nf).map(|_| super::perturb::uniform(seed)).collect();
    let m_norm = |v: &[f64]| -> f64 {
        v.iter()
            .zip(mass)
            .map(|(a, m)| a * a * m)
            .sum::<f64>()
            .sqrt()
    };
    for _ in 0..SWEEPS {
        let n = m_norm(&v);
        if !(n > 0.0 && n.is_finite()) {
            return None;
        }
        for (a, m) in v.iter_mut().zip(mass) {
            *a *= m / n;
        }
        llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut v, nf, 1));
    }
    let n = m_norm(&v);
    if !(n > 0.0 && n.is_finite()) {
        return None;
    }
    v.iter_mut().for_each(|a| *a /= n);
    // vᵀKv = vᵀ(K + μM)v − μ vᵀMv
    let kv = system.sym_lower(shifted).product(&v);
    let curvature = v.iter().zip(&kv).map(|(a, b)| a * b).sum::<f64>() - mu;
    (curvature < 0.0).then_some((v, curvature))
}

/// Searches the energy along ±v from `x` (the sign that does not go uphill to first order) by
/// halving a first step of [`FIRST_STEP`] of the body's size until the energy falls by at least
/// 1e-4 of the quadratic model's drop; moves `x` and returns true when it does.
#[allow(clippy::too_many_arguments)]
pub(super) fn search(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    trial: &mut [Vec3],
    (v, curvature): (&[f64], f64),
    gf: &[f64],
    energy: f64,
    report: &mut SolveReport,
) -> bool {
    let slope = gf.iter().zip(v).map(|(g, a)| g * a).sum::<f64>();
    let sign = if slope > 0.0 { -1.0 } else { 1.0 };
    let vmax = v.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    if vmax == 0.0 {
        return false;
    }
    let mut tau = FIRST_STEP * super::perturb::size(x) / vmax;
    for _ in 0..30 {
        let model_drop = -(tau * sign * slope + 0.5 * curvature * tau * tau);
        trial.copy_from_slice(x);
        system.step(trial, v, sign * tau);
        if let Ok(e) = model.energy(trial) {
            if e.is_finite() && energy - e >= 1e-4 * model_drop {
                x.copy_from_slice(trial);
                return true;
            }
        }
        tau *= 0.5;
        report.backtracks += 1;
    }
    false
}
