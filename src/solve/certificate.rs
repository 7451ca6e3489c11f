//! The tangent probed without assembling it: H(x) v by a forward difference of the gradient,
//! and the stability certificate built on such products, which judges the tangent at a
//! chorded equilibrium positive definite from the factorised tangent of a nearby point (the
//! stability test of Clyde et al. 2017 §6 without its assembly and factorisation).

use super::perturb::{size, uniform};
use super::{FreeSystem, SolveError};
use crate::model::{ClothModel, Want};
use crate::Vec3;
use faer::prelude::Solve;
use faer::sparse::linalg::solvers::Llt;
use faer::MatMut;

/// Power steps of the stability certificate ([`certified`]).
const CERTIFICATE_STEPS: usize = 3;

/// Inverse-iteration steps on K₀ that turn the certificate's random start towards K₀'s soft
/// modes ([`certified`]).
const SOFT_STEPS: usize = 2;

/// The certificate's bound on the spectral radius of K₀⁻¹(K − K₀): K is positive definite
/// wherever the radius is under 1, and the margin covers what three power steps can
/// underestimate.
const CERTIFICATE_RADIUS: f64 = 0.3;

/// Whether the tangent K at the equilibrium `x` (gradient `grad`) is positive definite, judged
/// from the factorised, positive definite K₀ of a nearby point without assembling K: K =
/// K₀(I + M) with M = K₀⁻¹(K − K₀), so K is positive definite wherever the spectral radius of
/// M is under 1. An eigenvalue θ of M is vᵀ(K − K₀)v / vᵀK₀v for its mode v, so a small
/// change of the tangent reaches θ = −1 only along K₀'s soft modes: the pseudo-random start
/// (deterministic) is first turned towards them by [`SOFT_STEPS`] back-substitutions, then
/// [`CERTIFICATE_STEPS`] power steps, each one gradient assembly (K v by a forward
/// difference) and one back-substitution, estimate the radius, which must stay under
/// [`CERTIFICATE_RADIUS`]. A heuristic bound, not a proof (a power estimate is a lower bound
/// of the radius); conservative where the tangent stiffened (θ ≫ 0 fails it too), and a
/// failure costs only the Newton iteration the chord saved.
pub(super) fn certified(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &[Vec3],
    grad: &[Vec3],
    llt: &Llt<usize, f64>,
) -> bool {
    let nf = system.num_free;
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut v: Vec<f64> = (0..nf).map(|_| uniform(&mut seed)).collect();
    // inverse iteration on K₀ first (back-substitutions only): the start leans to K₀'s soft
    // modes, the only ones a small change of the tangent can turn negative
    for _ in 0..SOFT_STEPS {
        llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut v, nf, 1));
        let vn = super::norm(&v);
        if vn == 0.0 || !vn.is_finite() {
            return false;
        }
        v.iter_mut().for_each(|a| *a /= vn);
    }
    let mut radius = f64::INFINITY;
    for _ in 0..CERTIFICATE_STEPS {
        let vn = super::norm(&v);
        if vn == 0.0 || !vn.is_finite() {
            return false;
        }
        v.iter_mut().for_each(|a| *a /= vn);
        // T v over every DOF (the slaves follow their masters)
        let Ok(kv) = hessian_times(model, x, grad, &system.expand(&v)) else {
            return false;
        };
        let mut u = system.reduced(&kv);
        llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut u, nf, 1));
        u.iter_mut().zip(&v).for_each(|(a, b)| *a -= b);
        radius = super::norm(&u);
        v = u;
    }
    radius.is_finite() && radius <= CERTIFICATE_RADIUS
}

/// H(x) v over every DOF, by a forward difference of the gradient `grad` at `x` (one gradient
/// assembly: an eighth of a Hessian assembly on the shell, by `cargo bench --bench
/// shell`). The step is √ε of the body's size along v, so the product is good to about √ε
/// relative.
pub(super) fn hessian_times(
    model: &dyn ClothModel,
    x: &[Vec3],
    grad: &[Vec3],
    v: &[Vec3],
) -> Result<Vec<Vec3>, SolveError> {
    let vmax = v.iter().flatten().fold(0.0f64, |m, a| m.max(a.abs()));
    let mut out = vec![[0.0; 3]; x.len()];
    if vmax == 0.0 {
        return Ok(out);
    }
    let h = f64::EPSILON.sqrt() * size(x).max(f64::MIN_POSITIVE) / vmax;
    let moved: Vec<Vec3> = x
        .iter()
        .zip(v)
        .map(|(p, d)| std::array::from_fn(|c| p[c] + h * d[c]))
        .collect();
    model
        .assemble(&moved, Want::Gradient, Some(&mut out), None)
        .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
    for (o, g) in out.iter_mut().zip(grad) {
        for c in 0..3 {
            o[c] = (o[c] - g[c]) / h;
        }
    }
    Ok(out)
}
