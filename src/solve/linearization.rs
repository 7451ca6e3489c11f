//! The tangent at an equilibrium, factorised once for any number of right-hand sides (the
//! sensitivity system of Clyde et al. 2017, Eq. 6).

use super::certificate::hessian_times;
use super::{refine, FreeSystem, Precision, SolveError};
use crate::model::{BlockMatrix, ClothModel, Want};
use crate::Vec3;
use faer::prelude::Solve;
use faer::sparse::linalg::solvers::Llt;
use faer::MatMut;

/// The tangent of an equilibrium: the full Hessian H and the reduced K = Tᵀ H T, factorised
/// once so that any number of right-hand sides are solved on it (the sensitivity system of
/// Clyde et al. 2017, Eq. 6; constraints are eliminated, so no multipliers appear).
pub struct Linearization {
    pub hessian: BlockMatrix,
    /// ∂E/∂x over every DOF (free and clamped) at the solution: its reactions. Where the
    /// solve's last step is polished ([`super::NewtonOptions::polish`]) this is the polished
    /// point's, while the Hessian is the preceding point's.
    pub gradient: Vec<Vec3>,
    pub(super) values: Vec<f64>,
    pub(super) llt: Llt<usize, f64>,
    /// The relative residual of the state whose tangent this is: 0 for the solution's own;
    /// the start of a polished or chorded last step's otherwise. From [`REFINE_FROM`] on,
    /// [`Linearization::solve_at_solution`] corrects for it.
    pub stale: f64,
}

impl Linearization {
    /// Assembles and factorises at `x` (an equilibrium of `system`). Fails if K is not
    /// positive definite: a saddle has no unique sensitivity.
    pub fn new(
        model: &dyn ClothModel,
        system: &FreeSystem,
        x: &[Vec3],
    ) -> Result<Self, SolveError> {
        let (hessian, values, gradient) = Self::assemble(model, system, x)?;
        let llt = system.try_factor(&values)?.ok_or_else(|| {
            SolveError::Linear("the equilibrium's Hessian is not positive definite".into())
        })?;
        Ok(Self {
            hessian,
            gradient,
            values,
            llt,
            stale: 0.0,
        })
    }

    /// The full Hessian at `x`, the reduced K's values and the gradient.
    fn assemble(
        model: &dyn ClothModel,
        system: &FreeSystem,
        x: &[Vec3],
    ) -> Result<(BlockMatrix, Vec<f64>, Vec<Vec3>), SolveError> {
        let mut grad = vec![[0.0; 3]; model.num_nodes()];
        let mut hessian = BlockMatrix::zeros(model.pattern().clone());
        model
            .assemble(x, Want::Hessian, Some(&mut grad), Some(&mut hessian))
            .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
        let mut values = Vec::new();
        system.values(&hessian, &mut values);
        Ok((hessian, values, grad))
    }

    /// As [`Linearization::new`], but where K is not positive definite (an equilibrium that
    /// ended on a saddle, or on the singular tangent of a wrinkling bifurcation) factorises
    /// K + σ D instead, D = diag K and σ = 1e-10, 1e-8, … 1e-4, the first that succeeds:
    /// sensitivities of a regularised tangent, for a minimiser's search direction only.
    /// Returns the linearization and σ (0 when none is needed).
    pub fn new_regularized(
        model: &dyn ClothModel,
        system: &FreeSystem,
        x: &[Vec3],
    ) -> Result<(Self, f64), SolveError> {
        let (hessian, values, gradient) = Self::assemble(model, system, x)?;
        for sigma in [0.0, 1e-10, 1e-8, 1e-6, 1e-4] {
            let mut shifted = values.clone();
            for &k in &system.diag {
                shifted[k] += sigma * values[k].abs();
            }
            if let Some(llt) = system.try_factor(&shifted)? {
                return Ok((
                    Self {
                        hessian,
                        gradient,
                        values: shifted,
                        llt,
                        stale: 0.0,
                    },
                    sigma,
                ));
            }
        }
        Err(SolveError::Linear(
            "the equilibrium's Hessian is not positive definite, even shifted by 1e-4 of its diagonal".into(),
        ))
    }

    /// K⁻¹ Tᵀ g for a full-length vector g (one refinement step with an f64 residual).
    pub fn solve_reduced(&self, system: &FreeSystem, g: &[Vec3]) -> Vec<f64> {
        let nf = system.num_free;
        let mut rhs = vec![0.0; nf];
        system.reduce(g, &mut rhs);
        let mut d = rhs.clone();
        self.llt
            .solve_in_place(MatMut::from_column_major_slice_mut(&mut d, nf, 1));
        refine::refine(
            &system.sym_lower(&self.values),
            &rhs,
            &mut d,
            Precision::F64,
            1,
            |r| {
                self.llt
                    .solve_in_place(MatMut::from_column_major_slice_mut(r, nf, 1))
            },
        );
        d
    }

    /// H(x) v over every DOF, by a forward difference of the gradient about `x`, the
    /// equilibrium whose gradient this linearisation holds ([`hessian_times`]).
    pub fn hessian_times(
        &self,
        model: &dyn ClothModel,
        x: &[Vec3],
        v: &[Vec3],
    ) -> Result<Vec<Vec3>, SolveError> {
        hessian_times(model, x, &self.gradient, v)
    }

    /// −K⁻¹ Tᵀ g for a full-length g: the equilibrium's parameter tangent ∂q/∂k where g is
    /// ∂(gradient)/∂k (the next run's predictor).
    pub fn parameter_tangent(&self, system: &FreeSystem, g: &[Vec3]) -> Vec<f64> {
        let mut d = self.solve_reduced(system, g);
        d.iter_mut().for_each(|v| *v = -*v);
        d
    }

    /// Whether this (positive definite) tangent certifies the tangent at `x`, a nearby state
    /// of the same system, as positive definite without assembling it: the power estimate of
    /// the spectral radius of K₀⁻¹(K − K₀) under a bound (one gradient assembly and one
    /// back-substitution a step). Conservative: a tangent that stiffened a lot fails too.
    pub fn certifies(
        &self,
        model: &dyn ClothModel,
        system: &FreeSystem,
        x: &[Vec3],
    ) -> Result<bool, SolveError> {
        let mut grad = vec![[0.0; 3]; model.num_nodes()];
        model
            .assemble(x, Want::Gradient, Some(&mut grad), None)
            .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
        Ok(super::certificate::certified(
            model, system, x, &grad, &self.llt,
        ))
    }

    /// Whether the tangent is far enough from the solution's for
    /// [`Linearization::solve_at_solution`] to refine on it: from a relative residual of
    /// [`REFINE_FROM`] (a tangent that stale leaves sensitivities off by about its staleness:
    /// on the bundled cotton's fit, against fresh tangents, up to 1e-5 from polished steps
    /// under 1e-4, 1e-3–1e-2 from chords under 5e-2; `tests/sensitivities.rs` asks for 1e-5,
    /// which a tangent under 1e-4 stale can miss at 2.4e-5).
    pub fn refines(&self) -> bool {
        self.stale > REFINE_FROM
    }

    /// K⁻¹ Tᵀ b with K the tangent at the equilibrium `x` itself: where this linearisation's
    /// tangent is stale ([`Linearization::refines`]), the solve on it is refined by products
    /// with the tangent at `x` ([`Linearization::hessian_times`]), each refinement step cutting
    /// the error by about the stale tangent's relative error, until the correction is under
    /// `tol` of the solution. `None` where that takes more than [`ADJOINT_REFINEMENTS`] steps or
    /// a step does not halve the correction (the tangent too far off to precondition: the
    /// caller factorises the solution's own). Without a stale tangent, as
    /// [`Linearization::solve_reduced`].
    pub fn solve_at_solution(
        &self,
        model: &dyn ClothModel,
        system: &FreeSystem,
        x: &[Vec3],
        b: &[Vec3],
        tol: f64,
    ) -> Result<Option<Vec<f64>>, SolveError> {
        let mut lambda = self.solve_reduced(system, b);
        if !self.refines() {
            return Ok(Some(lambda));
        }
        let nf = system.num_free;
        let rhs = system.reduced(b);
        let mut last = f64::INFINITY;
        for _ in 0..ADJOINT_REFINEMENTS {
            let kl = system.reduced(&self.hessian_times(model, x, &system.expand(&lambda))?);
            let mut r: Vec<f64> = rhs.iter().zip(&kl).map(|(a, b)| a - b).collect();
            self.llt
                .solve_in_place(MatMut::from_column_major_slice_mut(&mut r, nf, 1));
            let size = lambda.iter().fold(0.0f64, |m, a| m.max(a.abs()));
            let change = r.iter().fold(0.0f64, |m, a| m.max(a.abs()));
            if !change.is_finite() || change > 0.5 * last {
                return Ok(None);
            }
            lambda.iter_mut().zip(&r).for_each(|(a, d)| *a += d);
            if change <= tol * size {
                return Ok(Some(lambda));
            }
            last = change;
        }
        Ok(None)
    }
}

/// The staleness from which [`Linearization::solve_at_solution`] refines.
pub const REFINE_FROM: f64 = 1e-6;

/// Most refinement steps of [`Linearization::solve_at_solution`].
pub const ADJOINT_REFINEMENTS: usize = 8;
