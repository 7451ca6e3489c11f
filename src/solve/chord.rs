//! The end of a converging Newton solve: the last step polished on the factorisation that
//! computed it, and chord steps on that same factorisation where one step is not enough
//! (a Shamanskii-type Newton, Kelley, *Iterative Methods for Linear and Nonlinear Equations*,
//! 1995, §5.4), with a stability certificate where the chord has gone far from the tangent it
//! was factorised at. Each chord step costs one gradient assembly and one back-substitution,
//! about an eighth of a Hessian assembly on the shell (`cargo bench --bench shell`) and
//! no factorisation.

use super::certificate::certified;
use super::measure::balance;
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
