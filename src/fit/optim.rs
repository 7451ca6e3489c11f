//! Minimisers for the fitter's least-squares objective ε(p) = Σ rᵢ(p)² (Clyde et al. 2017 §5):
//! BFGS with a strong-Wolfe line search (Nocedal & Wright 2006, Algorithms 3.5–3.6, with the
//! update skipped when the curvature condition sᵀy > 0 fails), and Gauss–Newton with a
//! backtracking line search, kept for comparison.
//!
//! The problem hands back residuals and, when asked, their Jacobian; a failed evaluation (a
//! solve that did not converge at a wild trial point) counts as +∞ and makes the line search
//! step back.
//!
//! Each stops at an iteration limit, an objective target, a gradient tolerance, a step that
//! lowers ε by less than a fraction of itself, or (`xtol`) at a (quasi-)Newton step that would
//! move every variable by less than a tolerance, without trying it: a polish whose optimum is
//! that near gains nothing from the line search's evaluations.

mod line_search;

use line_search::{strong_wolfe, C1};
use nalgebra::{DMatrix, DVector};

/// Residuals and (when asked for) the Jacobian ∂r/∂p, one row per residual.
pub struct Evaluation {
    pub residuals: Vec<f64>,
    pub jacobian: Option<DMatrix<f64>>,
}

impl Evaluation {
    pub fn objective(&self) -> f64 {
        self.residuals.iter().map(|r| r * r).sum()
    }

    /// ∇ε = 2 Jᵀ r.
    fn gradient(&self) -> DVector<f64> {
        let j = self
            .jacobian
            .as_ref()
            .expect("gradient asked without a Jacobian");
        2.0 * j.transpose() * DVector::from_column_slice(&self.residuals)
    }
}

/// Which minimiser.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Method {
    /// BFGS on the inverse Hessian, started from the Gauss–Newton matrix.
    Bfgs,
    /// Fletcher & Xu (1987): the Gauss–Newton matrix while it makes fast progress (ε falls by
    /// at least a fifth per step), BFGS updates of it once the residuals' own curvature or a
    /// near-singular Jacobian slows Gauss–Newton down; strong-Wolfe steps throughout.
    #[default]
    Hybrid,
    GaussNewton,
}

impl Method {
    /// The spelling `--method` takes.
    pub fn name(self) -> &'static str {
        match self {
            Self::Bfgs => "bfgs",
            Self::Hybrid => "hybrid",
            Self::GaussNewton => "gauss-newton",
        }
    }
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "bfgs" => Ok(Self::Bfgs),
            "hybrid" => Ok(Self::Hybrid),
            "gauss-newton" | "gn" => Ok(Self::GaussNewton),
            _ => Err(format!(
                "unknown method {s:?} (hybrid, bfgs or gauss-newton)"
            )),
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct OptimOptions {
    pub method: Method,
    pub max_iterations: usize,
    /// stop when an iteration lowers ε by less than this fraction
    pub rel_decrease: f64,
    /// stop when ‖∇ε‖∞ falls below this
    pub gtol: f64,
    /// stop when ε falls below this
    pub target: f64,
    /// longest step tried, in the ∞-norm of the variables (a trust bound on wild trials)
    pub max_step: f64,
    /// stop, without trying it, when a (quasi-)Newton step would move every variable by less
    /// than this (∞-norm): a polish whose optimum is already within it
    pub xtol: f64,
}

impl Default for OptimOptions {
    fn default() -> Self {
        Self {
            method: Method::Bfgs,
            max_iterations: 60,
            rel_decrease: 1e-6,
            gtol: 1e-12,
            target: 0.0,
            max_step: f64::INFINITY,
            xtol: 0.0,
        }
    }
}

/// What a minimisation did.
#[derive(Clone, Debug, Default)]
pub struct OptimReport {
    pub objective: f64,
    pub iterations: usize,
    /// problem evaluations, with or without Jacobian
    pub evaluations: usize,
    /// BFGS updates skipped by the curvature guard
    pub skipped_updates: usize,
    pub stop: String,
}

/// Minimises Σ r(p)² from `p`, which is left at the best point found.
pub fn minimize<E>(
    p: &mut [f64],
    opts: &OptimOptions,
    mut problem: impl FnMut(&[f64], bool) -> Result<Evaluation, E>,
) -> Result<OptimReport, E> {
    let mut report = OptimReport::default();
    let first = problem(p, true)?;
    report.evaluations += 1;
    let mut eval = |q: &[f64], jac: bool, report: &mut OptimReport| {
        report.evaluations += 1;
        problem(q, jac)
            .ok()
            .filter(|e| e.residuals.iter().all(|r| r.is_finite()))
    };
    match opts.method {
        Method::Bfgs => bfgs(p, first, opts, &mut report, &mut eval),
        Method::Hybrid => hybrid(p, first, opts, &mut report, &mut eval),
        Method::GaussNewton => gauss_newton(p, first, opts, &mut report, &mut eval),
    }
    Ok(report)
}

type Eval<'a> = dyn FnMut(&[f64], bool, &mut OptimReport) -> Option<Evaluation> + 'a;

fn bfgs(
    p: &mut [f64],
    first: Evaluation,
    opts: &OptimOptions,
    report: &mut OptimReport,
    eval: &mut Eval,
) {
    let n = p.len();
    let mut x = DVector::from_column_slice(p);
    let mut f = first.objective();
    let mut g = first.gradient();
    // initial inverse Hessian: the Gauss–Newton matrix (2 JᵀJ)⁻¹ of the first point, the
    // exact Hessian of a zero-residual fit; the identity (scaled after the first step) if it
    // is singular
    let (mut h, mut scaled) = match gauss_newton_inverse(&first) {
        Some(h) => (h, true),
        None => (DMatrix::<f64>::identity(n, n), false),
    };
    report.stop = "iteration limit".into();
    for it in 0..opts.max_iterations {
        report.iterations = it;
        if let Some(stop) = stop_before_step(f, &g, opts) {
            report.stop = stop.into();
            break;
        }
        let mut d = -(&h * &g);
        if d.dot(&g) >= 0.0 {
            // the inverse-Hessian estimate lost definiteness: restart from steepest descent
            h = DMatrix::identity(n, n);
            d = -g.clone();
        }
        if let Some(stop) = stop_before_trial(&d, opts).filter(|_| scaled) {
            report.stop = stop.into();
            break;
        }
        if !scaled {
            // first step: a 10 % relative change of ε along steepest descent
            let slope = d.dot(&g).abs();
            if slope > 0.0 {
                d *= (0.1 * f / slope).min(1.0 / d.amax().max(1e-300));
            }
        }
        cap(&mut d, opts.max_step);
        let Some((alpha, fa, ga, _)) = strong_wolfe(&x, f, &g, &d, report, eval) else {
            report.stop = "line search failed".into();
            break;
        };
        let s = alpha * &d;
        let y = &ga - &g;
        let sy = s.dot(&y);
        x += &s;
        let decrease = (f - fa) / f.max(1e-300);
        f = fa;
        g = ga;
        if sy > 1e-12 * s.norm() * y.norm() {
            if !scaled {
                h = DMatrix::identity(n, n) * (sy / y.dot(&y));
                scaled = true;
            }
            let rho = 1.0 / sy;
            let hy = &h * &y;
            let yhy = y.dot(&hy);
            // H ← (I − ρ s yᵀ) H (I − ρ y sᵀ) + ρ s sᵀ
            h += (rho * rho * yhy + rho) * (&s * s.transpose())
                - rho * (&hy * s.transpose() + &s * hy.transpose());
        } else {
            report.skipped_updates += 1;
        }
        if decrease < opts.rel_decrease {
            report.iterations = it + 1;
            report.stop = "relative decrease below tolerance".into();
            break;
        }
        report.iterations = it + 1;
    }
    p.copy_from_slice(x.as_slice());
    report.objective = f;
}

/// Why to stop, without taking a step, at ε = f with gradient g, if at all.
fn stop_before_step(f: f64, g: &DVector<f64>, opts: &OptimOptions) -> Option<&'static str> {
    if f <= opts.target {
        Some("objective below target")
    } else if g.amax() <= opts.gtol {
        Some("gradient below tolerance")
    } else {
        None
    }
}

/// Why not to try the (quasi-)Newton step d, if so: it moves every variable by less than
/// `xtol`.
fn stop_before_trial(d: &DVector<f64>, opts: &OptimOptions) -> Option<&'static str> {
    (d.amax() < opts.xtol).then_some("step below tolerance")
}

/// Shortens d to ∞-norm `max_step` if it is longer.
fn cap(d: &mut DVector<f64>, max_step: f64) {
    let m = d.amax();
    if m > max_step {
        *d *= max_step / m;
    }
}

/// 2 JᵀJ + δI with δ = 1e-10 of the mean diagonal.
fn gauss_newton_matrix(j: &DMatrix<f64>) -> DMatrix<f64> {
    let n = j.ncols();
    let mut a = 2.0 * j.transpose() * j;
    let shift = (1e-10 * a.trace() / n as f64).max(1e-300);
    for i in 0..n {
        a[(i, i)] += shift;
    }
    a
}

/// The Fletcher–Xu hybrid on the Hessian estimate B (see [`Method::Hybrid`]).
fn hybrid(
    p: &mut [f64],
    first: Evaluation,
    opts: &OptimOptions,
    report: &mut OptimReport,
    eval: &mut Eval,
) {
    let n = p.len();
    let mut x = DVector::from_column_slice(p);
    let mut f = first.objective();
    let mut g = first.gradient();
    let mut b = gauss_newton_matrix(first.jacobian.as_ref().expect("Jacobian"));
    report.stop = "iteration limit".into();
    for it in 0..opts.max_iterations {
        report.iterations = it;
        if let Some(stop) = stop_before_step(f, &g, opts) {
            report.stop = stop.into();
            break;
        }
        let mut d = match b.clone().cholesky() {
            Some(c) => c.solve(&(-&g)),
            None => {
                b = DMatrix::identity(n, n) * b.diagonal().amax().max(1.0);
                -&g / b[(0, 0)]
            }
        };
        if let Some(stop) = stop_before_trial(&d, opts) {
            report.stop = stop.into();
            break;
        }
        cap(&mut d, opts.max_step);
        let Some((alpha, fa, ga, ja)) = strong_wolfe(&x, f, &g, &d, report, eval) else {
            report.stop = "line search failed".into();
            break;
        };
        let s = alpha * &d;
        let y = &ga - &g;
        x += &s;
        let decrease = (f - fa) / f.max(1e-300);
        f = fa;
        g = ga;
        let sy = s.dot(&y);
        if decrease >= 0.2 {
            if let Some(j) = &ja {
                b = gauss_newton_matrix(j);
            }
        } else if sy > 1e-12 * s.norm() * y.norm() {
            let bs = &b * &s;
            b += (&y * y.transpose()) / sy - (&bs * bs.transpose()) / s.dot(&bs);
        } else {
            report.skipped_updates += 1;
        }
        report.iterations = it + 1;
        if decrease < opts.rel_decrease {
            report.stop = "relative decrease below tolerance".into();
            break;
        }
    }
    p.copy_from_slice(x.as_slice());
    report.objective = f;
}

/// (2 JᵀJ + δI)⁻¹ with δ = 1e-10 of the mean diagonal, if that is positive definite.
fn gauss_newton_inverse(e: &Evaluation) -> Option<DMatrix<f64>> {
    let j = e.jacobian.as_ref()?;
    let n = j.ncols();
    let mut a = 2.0 * j.transpose() * j;
    let shift = 1e-10 * a.trace() / n as f64;
    if !(shift > 0.0 && shift.is_finite()) {
        return None;
    }
    for i in 0..n {
        a[(i, i)] += shift;
    }
    a.cholesky().map(|c| c.inverse())
}

fn gauss_newton(
    p: &mut [f64],
    first: Evaluation,
    opts: &OptimOptions,
    report: &mut OptimReport,
    eval: &mut Eval,
) {
    let n = p.len();
    let mut x = DVector::from_column_slice(p);
    let mut cur = first;
    let mut f = cur.objective();
    report.stop = "iteration limit".into();
    for it in 0..opts.max_iterations {
        report.iterations = it;
        let j = cur.jacobian.as_ref().expect("Jacobian");
        let r = DVector::from_column_slice(&cur.residuals);
        let g = 2.0 * j.transpose() * &r;
        if let Some(stop) = stop_before_step(f, &g, opts) {
            report.stop = stop.into();
            break;
        }
        // (JᵀJ + 1e-12 tr/n I) δ = −Jᵀr
        let mut a = j.transpose() * j;
        let shift = 1e-12 * a.trace() / n as f64;
        for i in 0..n {
            a[(i, i)] += shift.max(1e-300);
        }
        let Some(chol) = a.cholesky() else {
            report.stop = "singular Gauss–Newton system".into();
            break;
        };
        let mut d = chol.solve(&(-(j.transpose() * &r)));
        if let Some(stop) = stop_before_trial(&d, opts) {
            report.stop = stop.into();
            break;
        }
        cap(&mut d, opts.max_step);
        let slope = g.dot(&d);
        let mut alpha = 1.0;
        let mut accepted = None;
        for _ in 0..30 {
            let xa = &x + alpha * &d;
            if let Some(e) = eval(xa.as_slice(), true, report) {
                let fa = e.objective();
                if fa <= f + C1 * alpha * slope {
                    accepted = Some((xa, e, fa));
                    break;
                }
            }
            alpha *= 0.5;
        }
        let Some((xa, e, fa)) = accepted else {
            report.stop = "line search failed (Gauss–Newton stalled)".into();
            break;
        };
        let decrease = (f - fa) / f.max(1e-300);
        x = xa;
        cur = e;
        f = fa;
        report.iterations = it + 1;
        if decrease < opts.rel_decrease {
            report.stop = "relative decrease below tolerance".into();
            break;
        }
    }
    p.copy_from_slice(x.as_slice());
    report.objective = f;
}

/// The share of the objective ‖r‖² that the Gauss–Newton step from (r, J) is predicted to
/// remove: 1 − ‖r + J δ‖² / ‖r‖², δ the least-squares solution of J δ = −r (0 where r is 0
/// or J has no rank to step with).
pub fn gauss_newton_gain(j: &DMatrix<f64>, r: &[f64]) -> f64 {
    let r = DVector::from_column_slice(r);
    let f = r.norm_squared();
    if f == 0.0 || j.ncols() == 0 {
        return 0.0;
    }
    let svd = j.clone().svd(true, true);
    let top = svd.singular_values.iter().copied().fold(0.0, f64::max);
    match svd.solve(&(-&r), 1e-12 * top) {
        Ok(d) if d.iter().all(|v| v.is_finite()) => {
            let after = (&r + j * d).norm_squared();
            (1.0 - after / f).clamp(0.0, 1.0)
        }
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests;
