//! The tangent at an equilibrium, factorised once for any number of right-hand sides (the
//! sensitivity system of Clyde et al. 2017, Eq. 6).

use super::{refine, FreeSystem, Precision, SolveError};
use crate::assembly::{BlockMatrix, Want};
use crate::model::ClothModel;
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
    /// solve's last step was polished ([`super::NewtonOptions::polish`]) this is the polished
    /// point's, while the Hessian is the point's before it.
    pub gradient: Vec<Vec3>,
    pub(super) values: Vec<f64>,
    pub(super) llt: Llt<usize, f64>,
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
    /// Returns the linearization and σ (0 when none was needed).
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
}
