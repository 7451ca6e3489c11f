//! The tangents of a strip's equilibria: ∂q/∂(elongation), the elongation predictor's
//! slope, and the force sensitivities ∂F/∂k with ∂q/∂k (adjoint form of Clyde et al. 2017,
//! Eq. 6), refined at the equilibrium itself where the solver's tangent is of a point ahead
//! of a chorded last step.

use super::StripRig;
use crate::solve::SolveError;
use crate::Vec3;

/// Relative change of the adjoint solution under which its refinement on a stale tangent
/// stops ([`crate::solve::Linearization::solve_at_solution`]): above the forward differences'
/// own accuracy (about √ε), under which the refinement stagnates.
const ADJOINT_TOL: f64 = 1e-7;

impl StripRig {
    /// ∂q/∂(elongation) at an equilibrium: with x = T q + x̄ and the jaw's motion u = ∂x̄/∂(dl)
    /// (the moving clamp's y DOFs, and the slaves' offset rates), K ∂q/∂(dl) = −Tᵀ H u.
    pub(super) fn elongation_tangent(&self, lin: &crate::solve::Linearization) -> Vec<f64> {
        let nn = self.model.num_nodes();
        let mut u = vec![[0.0; 3]; nn];
        for &d in &self.top_fixed {
            if d % 3 == 1 {
                u[d / 3][1] = 1.0;
            }
        }
        for (s, r) in self.system.slaves().iter().zip(&self.rate) {
            u[s.dof / 3][s.dof % 3] = *r;
        }
        let mut hu = vec![[0.0; 3]; nn];
        lin.hessian.mul(&u, &mut hu);
        lin.solve_reduced(&self.system, &hu)
            .into_iter()
            .map(|v| -v)
            .collect()
    }

    /// ∂F/∂k and ∂q/∂k (reduced) for every parameter, whether the solution's own tangent had
    /// to be factorised, and whether that tangent turned out not positive definite (the
    /// point is then no minimum, whatever its solve reported).
    #[allow(clippy::type_complexity)]
    pub(super) fn force_sensitivities(
        &self,
        x: &[Vec3],
        lin: Option<crate::solve::Linearization>,
    ) -> Result<(Vec<f64>, Vec<Vec<f64>>, bool, bool), SolveError> {
        // an equilibrium that ended unstable (a wrinkling strip's saddle) gets the
        // sensitivities of a regularised tangent; the point's report says it is not stable
        let mut lin = match lin {
            Some(l) => l,
            None => crate::solve::Linearization::new_regularized(&self.model, &self.system, x)?.0,
        };
        let sens = self
            .model
            .sensitivities_of(x, self.wanted.as_deref())
            .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
        let mut r = vec![[0.0; 3]; x.len()];
        for &(d, c) in &self.motion {
            r[d / 3][d % 3] += c;
        }
        // the adjoint K λ = Tᵀ H r at the equilibrium itself: where the tangent is of a point
        // ahead of a chorded last step, H r and the solve are corrected by products with the
        // tangent at x (forward differences of the gradient, good to about √ε); where the
        // stale tangent is too far off to refine on, the solution's own is factorised
        // (counted as an iteration of the point)
        let hr = if lin.refines() {
            lin.hessian_times(&self.model, x, &r)?
        } else {
            let mut hr = vec![[0.0; 3]; x.len()];
            lin.hessian.mul(&r, &mut hr);
            hr
        };
        let mut fresh = false;
        let mut indefinite = false;
        let lambda = match lin.solve_at_solution(&self.model, &self.system, x, &hr, ADJOINT_TOL)? {
            Some(l) => l,
            None => {
                // the solution's own tangent, regularised where it is not positive definite:
                // a chorded last step is certified on the tangent of the step it follows, and
                // a wrinkling strip at its bifurcation can pass that certificate and end on a
                // saddle (the noise-free cotton's 67.5° strip on a graded 16 × 24 cage at
                // 4.5 mm does, and the whole fit fails without this)
                let (l, sigma) =
                    crate::solve::Linearization::new_regularized(&self.model, &self.system, x)?;
                lin = l;
                indefinite = sigma > 0.0;
                fresh = true;
                let mut hr = vec![[0.0; 3]; x.len()];
                lin.hessian.mul(&r, &mut hr);
                lin.solve_reduced(&self.system, &hr)
            }
        };
        let mut dq = Vec::with_capacity(sens.gradient.len());
        let df = sens
            .gradient
            .iter()
            .enumerate()
            .map(|(j, dg)| {
                if self
                    .wanted
                    .as_ref()
                    .is_some_and(|w| w.get(j) != Some(&true))
                {
                    dq.push(vec![0.0; self.system.num_free]);
                    return 0.0;
                }
                let direct: f64 = self.motion.iter().map(|&(d, c)| c * dg[d / 3][d % 3]).sum();
                let reduced = self.system.reduced(dg);
                // ∂q/∂k, kept for the next run's predictor
                dq.push(lin.parameter_tangent(&self.system, dg));
                direct - lambda.iter().zip(&reduced).map(|(a, b)| a * b).sum::<f64>()
            })
            .collect();
        Ok((df, dq, fresh, indefinite))
    }
}
