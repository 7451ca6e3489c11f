//! The end of a converging Newton solve: the last step polished on the factorisation that
//! computed it, and chord steps on that same factorisation where one step is not enough
//! (a Shamanskii-type Newton, Kelley, *Iterative Methods for Linear and Nonlinear Equations*,
//! 1995, §5.4), with a stability certificate where the chord has gone far from the tangent it
//! was factorised at. Each chord step costs one gradient assembly and one back-substitution,
//! about an eighth of a Hessian assembly on the shell (`cargo bench --bench shell`) and
//! no factorisation.

use super::linearization::hessian_times;
use super::newton::{balance, uniform};
use super::{FreeSystem, NewtonOptions};
use crate::model::{ClothModel, Want};
use crate::Vec3;
use faer::prelude::Solve;
use faer::sparse::linalg::solvers::Llt;
use faer::MatMut;

/// The relative residual under which a Newton step is polished ([`polish`]): √rtol, the
/// point from which one quadratically convergent step reaches rtol, raised to
/// `chord_from` where chord steps can finish the job.
pub(super) fn polish_from(opts: &NewtonOptions) -> f64 {
    opts.rtol.sqrt().max(opts.chord_from)
}

/// Most chord steps after a polished Newton step.
const CHORD_STEPS: usize = 5;

/// A chord step must cut the residual at least this much, or the chord is abandoned.
const CHORD_RATE: f64 = 0.1;

/// Power steps of the stability certificate ([`certified`]).
const CERTIFICATE_STEPS: usize = 3;

/// Inverse-iteration steps on K₀ that turn the certificate's random start towards K₀'s soft
/// modes ([`certified`]).
const SOFT_STEPS: usize = 2;

/// The certificate's bound on the spectral radius of K₀⁻¹(K − K₀): K is positive definite
/// wherever the radius is under 1, and the margin covers what three power steps can
/// underestimate.
const CERTIFICATE_RADIUS: f64 = 0.3;

/// The last step of a converging Newton solve, taken whole on the factorisation that computed
/// it and checked by one gradient assembly, without a further Hessian assembly and
/// factorisation: from a relative residual r ≤ √rtol a Newton step leaves about r² (quadratic
/// convergence), so the equilibrium usually needs no new tangent. From a larger r (up to
/// `chord_from`) the step leaves about r², and up to [`CHORD_STEPS`] chord steps on the same
/// factorisation, each cutting the residual by about the distance to the solution, finish
/// where a second Newton iteration would have assembled and factorised the tangent again.
///
/// Where the steps land within `rtol` (or the round-off floor, measured with the diagonal of
/// the tangent it came from), `x` moves there and what it found there comes back; the caller
/// keeps the tangent at the preceding point as the linearisation (marked stale). That tangent
/// is positive definite; from beyond √rtol the solution's own is then certified
/// ([`certified`]): a flat strip chorded onto the saddle where it would wrinkle is not
/// reported stable. Where the certificate fails, or the steps do not reach `rtol` but the
/// best point reached is lower in energy and residual than `x`, `x` moves there and the
/// Newton iteration goes on from it (assembling and factorising the tangent there, which
/// finds a saddle if there is one); else `x` stays where it is.
#[allow(clippy::too_many_arguments)]
pub(super) fn polish(
    model: &dyn ClothModel,
    system: &FreeSystem,
    (x, energy0, gnorm0, scale0): (&mut [Vec3], f64, f64, f64),
    d: &[f64],
    llt: &Llt<usize, f64>,
    opts: &NewtonOptions,
    (external, external_scale): (&[Vec3], f64),
    values: &[f64],
) -> Polish {
    let nf = system.num_free;
    let mut trial = x.to_vec();
    system.step(&mut trial, d, 1.0);
    let mut grad = vec![[0.0; 3]; model.num_nodes()];
    let mut gf = vec![0.0; nf];
    let mut best: Option<(Vec<Vec3>, f64)> = None;
    let mut last = gnorm0;
    let mut taken = 0;
    for chord in 0..=CHORD_STEPS {
        let Some(energy) = model
            .assemble(&trial, Want::Gradient, Some(&mut grad), None)
            .ok()
            .filter(|e| e.is_finite())
        else {
            break;
        };
        let b = balance(
            system,
            &trial,
            &grad,
            external,
            external_scale,
            values,
            &mut gf,
        );
        if !b.gnorm.is_finite() {
            break;
        }
        let within = b.gnorm <= opts.rtol * b.scale;
        if within || b.gnorm <= b.floor {
            x.copy_from_slice(&trial);
            let far = gnorm0 > opts.rtol.sqrt() * scale0;
            if far && !certified(model, system, x, &grad, llt) {
                return Polish::Moved {
                    energy,
                    chord_steps: taken,
                };
            }
            return Polish::Converged(Polished {
                energy,
                residual: if b.scale > 0.0 {
                    b.gnorm / b.scale
                } else {
                    b.gnorm
                },
                at_floor: !within,
                gradient: grad,
                chord_steps: chord,
            });
        }
        if b.gnorm < gnorm0 && energy <= energy0 {
            best = Some((trial.clone(), energy));
        }
        // the chord converges linearly: where it does not contract fast, a new tangent pays
        if chord == CHORD_STEPS || b.gnorm > CHORD_RATE * last {
            break;
        }
        last = b.gnorm;
        taken += 1;
        let mut step: Vec<f64> = gf.iter().map(|g| -g).collect();
        llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut step, nf, 1));
        system.step(&mut trial, &step, 1.0);
    }
    match best {
        Some((b, energy)) => {
            x.copy_from_slice(&b);
            Polish::Moved {
                energy,
                chord_steps: taken,
            }
        }
        None => Polish::Missed { chord_steps: taken },
    }
}

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

/// What a polish came to.
pub(super) enum Polish {
    /// within rtol (or the round-off floor), and certified stable
    Converged(Polished),
    /// not within rtol or not certified, but `x` moved to a point lower in energy and
    /// residual (or to the uncertified equilibrium)
    Moved { energy: f64, chord_steps: usize },
    /// `x` unchanged
    Missed { chord_steps: usize },
}

/// Where a polished step landed.
pub(super) struct Polished {
    pub energy: f64,
    /// relative residual
    pub residual: f64,
    /// within the round-off floor rather than `rtol`
    pub at_floor: bool,
    /// over every DOF
    pub gradient: Vec<Vec3>,
    /// chord steps taken after the Newton step
    pub chord_steps: usize,
}
