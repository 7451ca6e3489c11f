//! A cold strip point's attempts (Dirichlet increments): the predictor with a short budget,
//! sub-steps where that fails, and the whole budget last, resumed where the first attempt
//! stopped; a first attempt that is still settling goes on without the sub-steps.

use super::{Equilibrium, Last, SceneError, Solved, StripRig};
use crate::solve::SolveError;
use crate::Vec3;

/// Newton iterations the first cold solve of a point may take; past them its step is cut into
/// sub-steps (the whole budget comes last; see [`StripRig::solve_cold`]).
const FIRST_TRY_ITERATIONS: usize = 40;

/// How many times a first attempt must have cut its start's relative residual to go on with
/// the whole budget rather than with sub-steps.
const SETTLING: f64 = 10.0;

impl StripRig {
    /// The equilibrium at `dl` from the predictor (Euler or quadratic, whichever starts at the
    /// lower energy). Outside a fitter's trial (`retry_iterations` unset) the cheap attempts
    /// come first, each held to [`FIRST_TRY_ITERATIONS`]: the predictor, then the step from
    /// the last equilibrium cut into 2, 4 and 8 equal sub-steps, each predicted from the
    /// previous one. Where they all fail, the whole budget (`max_iterations`: the
    /// backward-Euler fallback's time to settle a wrinkling strip) goes to the predictor, then
    /// to the other predictor, then to the sub-steps. A large step into a wrinkling strip can
    /// land where Newton stagnates (cotton at 45° on a graded 8 × 12 cage, 4 to 6 mm in one
    /// step, leaves the relative residual at 1; two sub-steps solve it); stiff yarns over a soft
    /// shear at 22.5° crawl by backward Euler from a one-step start that two sub-steps solve in
    /// five Newton iterations each, so the sub-steps come ahead of the whole budget; and at a
    /// yarn-to-shear ratio of 2e4 the 67.5° strip on 32 × 48 settles within the budget from
    /// the quadratic start but not from Euler's, even where Euler's starts 1 % lower in energy.
    /// A first attempt that cuts its start's residual tenfold or more within its 40 iterations
    /// ([`StripRig::settling`]) goes straight on with the whole budget, without the cheap
    /// sub-steps: it is a wrinkle pattern settling, which a half-step only starts again (on
    /// the ratio-2e4 strips this saves over a third of the iterations, with every force
    /// and fitted value the same; see `paper_repro/stiff_fit`).
    /// Where the first half-step fails too, the cheap phase ends there: what is hard is then
    /// the state (a wrinkle pattern reorganising over hundreds of iterations), not the step,
    /// and quarter and eighth steps only spend 80–120 iterations more ahead of the whole
    /// budget. The whole budget resumes the first attempt where it stopped rather than
    /// repeating its iterations from the predictor, which saves about a tenth of the Newton
    /// iterations of the ratio-2e4 fit with every fitted value the same; a cheap attempt from
    /// the second predictor ahead of the sub-steps costs more than it saves.
    pub(super) fn solve_cold(
        &mut self,
        previous: &Last,
        before: Option<&(f64, Vec<Vec3>)>,
        dl: f64,
        max_iterations: usize,
    ) -> Solved {
        // the quadratic predictor where it starts lower in energy than Euler's (two energy
        // assemblies): on stiff yarns the path bends too sharply for it (the ratio-1000 strip at
        // 22.5°, 6 to 7.5 mm, takes 50 iterations from it and 8 from Euler), while on the
        // bundled fabrics it saves a few iterations
        let mut starts = vec![self.predict(previous, before, dl)];
        if before.is_some() {
            let euler = self.predict(previous, None, dl);
            if self.start_energy(dl, &euler) < self.start_energy(dl, &starts[0]) {
                starts.insert(0, euler);
            } else {
                starts.push(euler);
            }
        }
        if self.retry_iterations.is_some() {
            return self.solve_at(dl, starts.swap_remove(0), max_iterations);
        }
        let limit = max_iterations.min(FIRST_TRY_ITERATIONS);
        self.stopped_at = None;
        let first = self.solve_at(dl, starts[0].clone(), limit);
        if first.is_ok() {
            return first;
        }
        // the whole budget later resumes this attempt where it stopped, not from its start
        let resume = self.stopped_at.take().filter(|s| s.0 == dl).map(|s| s.1);
        if !self.settling(dl, &starts[0], &first) {
            if let Some(s) = self.sub_steps(previous, dl, limit, true) {
                return Ok(s);
            }
        }
        if limit == max_iterations {
            return first;
        }
        let mut last = first;
        let resumes = std::iter::once(resume).chain(std::iter::repeat(None));
        for (x0, resume) in starts.into_iter().zip(resumes) {
            last = match resume {
                Some(x) => self.solve_at(dl, x, max_iterations - limit),
                None => self.solve_at(dl, x0, max_iterations),
            };
            if last.is_ok() {
                return last;
            }
        }
        self.sub_steps(previous, dl, max_iterations, false)
            .map_or(last, Ok)
    }

    /// Whether a first attempt that ran out of iterations is settling rather than stuck: it
    /// cut the relative residual of its start `x0` at least [`SETTLING`]-fold. Its state is then
    /// a wrinkle pattern converging slowly, which the whole budget finishes, and sub-steps would
    /// start that work again (see [`StripRig::solve_cold`]).
    fn settling(&mut self, dl: f64, x0: &[Vec3], first: &Solved) -> bool {
        let Err(SceneError::Solve {
            source: SolveError::NotConverged { residual, .. },
            ..
        }) = first
        else {
            return false;
        };
        *residual <= self.start_residual(dl, x0) / SETTLING
    }

    /// The equilibrium at `dl` reached from the last one in 2, 4, then 8 equal sub-steps, each
    /// predicted from the previous one and held to `limit` iterations (`None` where every
    /// division fails; with `quick`, as soon as the first half-step fails).
    fn sub_steps(
        &mut self,
        previous: &Last,
        dl: f64,
        limit: usize,
        quick: bool,
    ) -> Option<Equilibrium> {
        let start = previous.as_ref().map_or(0.0, |p| p.0);
        for n in [2, 4, 8] {
            let mut last = previous.clone();
            for k in 1..=n {
                let e = start + (dl - start) * k as f64 / n as f64;
                let x0 = self.predict(&last, None, e);
                let Ok((x, report, lin)) = self.solve_at(e, x0, limit) else {
                    if n == 2 && k == 1 && quick {
                        // half the step cannot be reached either: the state is what is hard
                        // (see `solve_cold`), and finer divisions would start the same way
                        return None;
                    }
                    break;
                };
                if k == n {
                    return Some((x, report, lin));
                }
                self.spent += report.iterations;
                self.spent_factorizations += report.factorizations;
                let slope = lin.as_ref().map(|l| self.elongation_tangent(l));
                last = Some((e, x, slope));
            }
        }
        None
    }
}
