//! One point of a strip's force curve: its equilibrium (warm, stored or cold start), the
//! reaction on the moving jaw, the force's sensitivities (Clyde et al. 2017, Eq. 6, adjoint
//! form) and the equilibrium kept for the next run.

use super::{Last, Solved, StripRig};
use crate::scene::SceneError;
use crate::solve::{SolveError, SolveReport};
use crate::Vec3;

impl StripRig {
    /// The equilibrium at the `i`th elongation `dl`: from the stored or warm start where it
    /// converges in a few iterations, else cold from the predictor (`previous`: the last
    /// equilibrium, `before`: the one preceding it). Updates `doubt` (this point's start is poor) and
    /// `lost_branch` (a stored start turned out a saddle).
    pub(super) fn solve_point(
        &mut self,
        i: usize,
        dl: f64,
        (previous, before): (&Last, Option<&(f64, Vec<Vec3>)>),
        doubt: &mut bool,
        lost_branch: &mut bool,
    ) -> Solved {
        let mut warm = self.warm_start(i);
        // a point solved earlier: a fitter's trial caps its cold solve (`retry_iterations`)
        let stored = warm.is_some();
        warm = warm.filter(|_| !*lost_branch);
        if *doubt {
            warm = warm.filter(|w| self.warm_beats_predictor(w, previous, before, dl));
        }
        // a warm start that needs many iterations has wandered off (parameters far from
        // the last run's): give up early and solve from the predictor instead
        let warm_solved = match warm {
            Some(x) => self
                .solve_at(
                    dl,
                    x,
                    self.solver.max_iterations.min(super::WARM_ITERATIONS),
                )
                .ok(),
            None => None,
        };
        *doubt = warm_solved
            .as_ref()
            .is_none_or(|r| r.1.initial_residual.unwrap_or(0.0) > super::warm::POOR_START);
        *lost_branch |= warm_solved.as_ref().is_some_and(|r| r.1.saddle_escapes > 0);
        Ok(match warm_solved {
            Some(r) => r,
            None if stored => {
                let limit = self
                    .retry_iterations
                    .unwrap_or(self.solver.max_iterations)
                    .min(self.solver.max_iterations);
                self.solve_cold(previous, before, dl, limit)
                    .map_err(|e| self.point_failure(e))?
            }
            None => self
                .solve_cold(previous, before, dl, self.solver.max_iterations)
                .map_err(|e| self.point_failure(e))?,
        })
    }

    /// The reaction force on the moving jaw at the equilibrium `x`: from the solver's own
    /// gradient where it handed one back (`lin`), else assembled into `grad`.
    pub(super) fn reaction(
        &self,
        x: &[Vec3],
        lin: Option<&crate::solve::Linearization>,
        grad: &mut [Vec3],
    ) -> Result<f64, SceneError> {
        let reaction_error = |e: crate::material::OutOfDomain| SceneError::Solve {
            stage: "reaction".into(),
            source: SolveError::StartOutOfDomain(e.to_string()),
        };
        let grad: &[Vec3] = match lin {
            Some(l) => &l.gradient,
            None => {
                self.model
                    .assemble(x, crate::assembly::Want::Gradient, Some(grad), None)
                    .map_err(reaction_error)?;
                grad
            }
        };
        Ok(self
            .motion
            .iter()
            .map(|&(d, r)| r * grad[d / 3][d % 3])
            .sum())
    }

    /// ∂force/∂k at the `i`th equilibrium `x` (elongation `dl`), keeping ∂q/∂k for the next
    /// run's start; a fresh tangent or a saddle found here enter `report`.
    pub(super) fn point_sensitivities(
        &mut self,
        i: usize,
        dl: f64,
        x: &[Vec3],
        lin: Option<crate::solve::Linearization>,
        report: &mut SolveReport,
    ) -> Result<Vec<f64>, SceneError> {
        let (df, dq, fresh, indefinite) =
            self.force_sensitivities(x, lin)
                .map_err(|source| SceneError::Solve {
                    stage: format!("sensitivities at elongation {:.4} mm", dl * 1e3),
                    source,
                })?;
        self.tangents[i] = Some((self.params.clone(), dq));
        // a tangent factorised again for the sensitivities counts as an iteration
        report.iterations += usize::from(fresh);
        report.factorizations += usize::from(fresh);
        // a saddle found only here is reported like one the solve found: the fitter
        // leaves its point out of the objective
        report.stable &= !indefinite;
        Ok(df)
    }

    /// Stores `x` as the `i`th point's equilibrium under the current parameters, the one it
    /// replaces (solved under other parameters) kept among the earlier ones for the secant
    /// warm start.
    pub(super) fn keep_equilibrium(&mut self, i: usize, x: &[Vec3]) {
        let params = Some(self.params.clone());
        if self.solved_params[i] != params {
            if let (Some(x0), Some(k0)) = (self.equilibria[i].take(), self.solved_params[i].take())
            {
                let earlier = &mut self.earlier[i];
                earlier.retain(|e| e.1.len() == k0.len());
                earlier.insert(0, (x0, k0));
                earlier.truncate(super::warm::SECANTS);
            }
        }
        self.equilibria[i] = Some(x.to_vec());
        self.solved_params[i] = params;
    }
}
