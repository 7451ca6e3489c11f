//! Load continuation: bringing a load on in steps, or whole by full-step Newton first.

use super::{
    newton, FreeSystem, NewtonOptions, SolveError, SolveReport, Strategy, FULL_STEP_ITERATIONS,
};
use crate::model::ClothModel;
use crate::Vec3;

/// What a continuation did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContinuationReport {
    /// Load steps solved.
    pub steps: usize,
    /// Newton iterations over all attempts, failed ones included.
    pub iterations: usize,
    /// Numeric factorisations over all attempts, failed ones included.
    pub factorizations: usize,
    /// The last (full-load) solve.
    pub last: SolveReport,
}

/// With [`Strategy::FullStep`], each load step of the ramp that follows a failed whole-load
/// attempt also takes its first this-many Newton steps whole: from the flat strip the Newton
/// step has no in-plane contraction, its membrane energy dwarfs its bending energy, and the
/// line search cuts it to 1/16 and crawls even at 1e-4 of the load (cotton strips of 400 mm
/// at 0° and 200 mm at 45° fail without whole steps; with 5 they solve, and the 200 mm strip
/// at 0° takes 430 iterations where it takes 668 without).
pub const RAMP_FULL_STEPS: usize = 5;

/// Target of [`Strategy::Adaptive`]: the corrector's move as a fraction of the load increment's.
/// On the heavy D1388 cantilever (4×16, 4×32) 0.1 takes 139 and 109 iterations, 0.3 111 and 88,
/// 1 100 and 75 but with 25-iteration corrector solves near the budget; 0.3 keeps them short.
pub const ADAPTIVE_TOL: f64 = 0.3;

/// Raises a load factor t from 0 to 1, `apply(model, t, x)` setting the load (x: the last
/// equilibrium), solving for equilibrium at each step. The first increment is min(1/8,
/// `max_step`). With [`Strategy::Adaptive`] each later one is set from the predictor's error
/// (see there); otherwise it doubles after an easy solve (≤ 12 Newton iterations), up to
/// `max_step`. Either way it halves after a failed solve. Each solve starts from the secant
/// prediction through the last two equilibria. On failure returns the load factor reached for
/// and the error. With [`Strategy::FullStep`] or [`Strategy::TrustRegion`] (and `max_step` 1)
/// the whole load is tried first, by full-step Newton or the trust region; its iterations count
/// in the report whether it is kept or not.
pub fn continuation<M: ClothModel>(
    model: &mut M,
    system: &FreeSystem,
    x: &mut Vec<Vec3>,
    solver: &NewtonOptions,
    max_step: f64,
    mut apply: impl FnMut(&mut M, f64, &[Vec3]),
) -> Result<ContinuationReport, (f64, SolveError)> {
    let opts = NewtonOptions {
        max_iterations: solver.max_iterations.min(30),
        full_steps: match solver.strategy {
            Strategy::FullStep => RAMP_FULL_STEPS,
            _ => solver.full_steps,
        },
        ..*solver
    };
    let mut report = ContinuationReport::default();
    if max_step >= 1.0 {
        if let Some(whole) = whole_load(model, system, x, solver, &mut apply, &mut report) {
            return Ok(whole);
        }
    }
    let (mut factor, mut step) = (0.0f64, 0.125f64.min(max_step));
    let mut previous: Option<(f64, Vec<Vec3>)> = None;
    while factor < 1.0 {
        let target = (factor + step).min(1.0);
        apply(model, target, x);
        let mut trial = x.clone();
        if let Some((f0, x0)) = &previous {
            let r = (target - factor) / (factor - f0);
            for (t, (a, b)) in trial.iter_mut().zip(x.iter().zip(x0)) {
                for c in 0..3 {
                    t[c] = a[c] + r * (a[c] - b[c]);
                }
            }
        }
        let predicted =
            (solver.strategy == Strategy::Adaptive && previous.is_some()).then(|| trial.clone());
        let res = newton(model, system, &mut trial, &opts);
        match res {
            Ok(r) => {
                step = match &predicted {
                    Some(p) => step * adaptive_scale(x, p, &trial),
                    None if r.iterations <= 12 => 2.0 * step,
                    None => step,
                }
                .min(max_step);
                previous = Some((factor, std::mem::replace(x, trial)));
                factor = target;
                report.steps += 1;
                report.iterations += r.iterations;
                report.factorizations += r.factorizations;
                report.last = r;
            }
            Err(e) => {
                report.iterations += opts.max_iterations;
                report.factorizations += failed_factorizations(&e);
                step *= 0.5;
                if step < 1e-4 {
                    apply(model, factor, x);
                    return Err((target, e));
                }
            }
        }
    }
    Ok(report)
}

/// The whole load in one solve, by full-step Newton ([`Strategy::FullStep`]) or the trust region
/// ([`Strategy::TrustRegion`]); `Some` when that reached a stable equilibrium. The attempt's
/// cost is added to `report` either way.
fn whole_load<M: ClothModel>(
    model: &mut M,
    system: &FreeSystem,
    x: &mut Vec<Vec3>,
    solver: &NewtonOptions,
    apply: &mut impl FnMut(&mut M, f64, &[Vec3]),
    report: &mut ContinuationReport,
) -> Option<ContinuationReport> {
    let opts = match solver.strategy {
        Strategy::FullStep => NewtonOptions {
            max_iterations: FULL_STEP_ITERATIONS,
            full_steps: FULL_STEP_ITERATIONS,
            ..*solver
        },
        Strategy::TrustRegion => *solver,
        Strategy::Ramp | Strategy::Adaptive => return None,
    };
    apply(model, 1.0, x);
    let mut trial = x.clone();
    match newton(model, system, &mut trial, &opts) {
        Ok(r) if r.stable => {
            *x = trial;
            return Some(ContinuationReport {
                steps: 1,
                iterations: report.iterations + r.iterations,
                factorizations: report.factorizations + r.factorizations,
                last: r,
            });
        }
        Ok(r) => {
            report.iterations += r.iterations;
            report.factorizations += r.factorizations;
        }
        Err(e) => {
            report.iterations += opts.max_iterations;
            report.factorizations += failed_factorizations(&e);
        }
    }
    None
}

/// Step factor of [`Strategy::Adaptive`] after a solve from `predicted` that ended at
/// `corrected`, the last equilibrium `last`: √(tol / e) within ½–2, e = ‖corrected − predicted‖
/// / ‖corrected − last‖.
fn adaptive_scale(last: &[Vec3], predicted: &[Vec3], corrected: &[Vec3]) -> f64 {
    let dist = |a: &[Vec3], b: &[Vec3]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>())
            .sum::<f64>()
            .sqrt()
    };
    let moved = dist(corrected, last);
    if moved == 0.0 {
        return 2.0;
    }
    let e = dist(corrected, predicted) / moved;
    if e == 0.0 {
        2.0
    } else {
        (ADAPTIVE_TOL / e).sqrt().clamp(0.5, 2.0)
    }
}

/// The factorisations a failed solve made, where its error says (counted with the
/// successful ones: the work done).
fn failed_factorizations(e: &SolveError) -> usize {
    match e {
        SolveError::NotConverged { factorizations, .. } => *factorizations,
        _ => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_adaptive_step_follows_the_predictor_error() {
        let last = vec![[0.0; 3]];
        let corrected = vec![[1.0, 0.0, 0.0]];
        // exact prediction: the step may double
        assert_eq!(adaptive_scale(&last, &corrected, &corrected), 2.0);
        // error equal to the target: the step stays
        let at_tol = vec![[1.0 - ADAPTIVE_TOL, 0.0, 0.0]];
        assert!((adaptive_scale(&last, &at_tol, &corrected) - 1.0).abs() < 1e-12);
        // error 4× the target: half the step (second order: √(1/4))
        let off = vec![[1.0 - 4.0 * ADAPTIVE_TOL, 0.0, 0.0]];
        assert!((adaptive_scale(&last, &off, &corrected) - 0.5).abs() < 1e-12);
        // worse still: never below half
        let far = vec![[-5.0, 0.0, 0.0]];
        assert_eq!(adaptive_scale(&last, &far, &corrected), 0.5);
    }

    #[test]
    fn strategies_parse_by_their_names() {
        for (name, s) in Strategy::ALL {
            assert_eq!(name.parse::<Strategy>(), Ok(s));
            assert_eq!(s.name(), name);
        }
        assert!("newton".parse::<Strategy>().is_err());
    }
}
