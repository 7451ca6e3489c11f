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

/// A trial point of the line search: α, ε, ∇ε and the slope ∇ε·d.
type Trial = (f64, f64, DVector<f64>, f64, Option<DMatrix<f64>>);
/// An accepted step: α, ε, ∇ε and the Jacobian there.
type Step = (f64, f64, DVector<f64>, Option<DMatrix<f64>>);

/// Strong-Wolfe step along `d` (c₁ = 1e-4, c₂ = 0.9): (α, ε, ∇ε) at the accepted point.
fn strong_wolfe(
    x: &DVector<f64>,
    f0: f64,
    g0: &DVector<f64>,
    d: &DVector<f64>,
    report: &mut OptimReport,
    eval: &mut Eval,
) -> Option<Step> {
    let slope0 = g0.dot(d);
    if slope0 >= 0.0 {
        return None;
    }
    let mut phi = |a: f64, report: &mut OptimReport| -> Option<Trial> {
        let xa = x + a * d;
        let e = eval(xa.as_slice(), true, report)?;
        let g = e.gradient();
        let slope = g.dot(d);
        Some((a, e.objective(), g, slope, e.jacobian))
    };
    let mut prev: Trial = (0.0, f0, g0.clone(), slope0, None);
    let mut a = 1.0;
    for i in 0..20 {
        let Some(t) = phi(a, report) else {
            // a failed evaluation: the step is too long
            return zoom(prev, None, a, f0, slope0, &mut phi, report);
        };
        if t.1 > f0 + C1 * a * slope0 || (i > 0 && t.1 >= prev.1) {
            return zoom(prev, Some(t.clone()), a, f0, slope0, &mut phi, report);
        }
        if t.3.abs() <= -C2 * slope0 {
            return Some((t.0, t.1, t.2, t.4));
        }
        if t.3 >= 0.0 {
            return zoom(
                t.clone(),
                Some(prev.clone()),
                prev.0,
                f0,
                slope0,
                &mut phi,
                report,
            )
            .or(Some((t.0, t.1, t.2, t.4)));
        }
        prev = t;
        a *= 2.0;
    }
    Some((prev.0, prev.1, prev.2, prev.4)).filter(|t| t.0 > 0.0)
}

const C1: f64 = 1e-4;
const C2: f64 = 0.9;

/// Zoom between `lo` (sufficient decrease holds) and the other end `a_hi` (its trial, if the
/// evaluation succeeded), by safeguarded cubic interpolation (Nocedal & Wright, Alg. 3.6).
/// Most trial points one zoom phase evaluates.
const ZOOM_EVALUATIONS: usize = 8;

fn zoom(
    mut lo: Trial,
    mut hi: Option<Trial>,
    mut a_hi: f64,
    f0: f64,
    slope0: f64,
    phi: &mut impl FnMut(f64, &mut OptimReport) -> Option<Trial>,
    report: &mut OptimReport,
) -> Option<Step> {
    // a zoom that has not met the conditions in ZOOM_EVALUATIONS trials is as a rule fighting
    // the noise floor of the equilibrium solves (denim's thickness polish spent 30 that way)
    for _ in 0..ZOOM_EVALUATIONS {
        let (l, h) = (lo.0.min(a_hi), lo.0.max(a_hi));
        let width = h - l;
        if width <= 1e-14 * h.max(1e-300) {
            break;
        }
        let guess = hi
            .as_ref()
            .and_then(|t| cubic_min(lo.0, lo.1, lo.3, t.0, t.1, t.3));
        let a = match guess {
            Some(a) if a > l + 0.1 * width && a < h - 0.1 * width => a,
            _ => 0.5 * (l + h),
        };
        let Some(t) = phi(a, report) else {
            a_hi = a;
            hi = None;
            continue;
        };
        if t.1 > f0 + C1 * a * slope0 || t.1 >= lo.1 {
            a_hi = a;
            hi = Some(t);
        } else {
            if t.3.abs() <= -C2 * slope0 {
                return Some((t.0, t.1, t.2, t.4));
            }
            if t.3 * (a_hi - lo.0) >= 0.0 {
                a_hi = lo.0;
                hi = Some(lo.clone());
            }
            lo = t;
        }
    }
    // no point met the curvature condition: take the best with sufficient decrease
    (lo.0 > 0.0).then_some((lo.0, lo.1, lo.2, lo.4))
}

/// Minimiser of the cubic through (a, fa, sa) and (b, fb, sb), if it exists.
fn cubic_min(a: f64, fa: f64, sa: f64, b: f64, fb: f64, sb: f64) -> Option<f64> {
    if !(fa.is_finite() && fb.is_finite() && sa.is_finite() && sb.is_finite()) {
        return None;
    }
    let d1 = sa + sb - 3.0 * (fa - fb) / (a - b);
    let disc = d1 * d1 - sa * sb;
    if disc < 0.0 {
        return None;
    }
    let d2 = (b - a).signum() * disc.sqrt();
    let m = b - (b - a) * (sb + d2 - d1) / (sb - sa + 2.0 * d2);
    m.is_finite().then_some(m)
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
mod tests {
    use super::*;

    /// The predicted gain of a linear least-squares problem's Gauss–Newton step is exact: all
    /// of ‖r‖² when r lies in J's range, none of it when r is orthogonal to the range, and the
    /// share of r inside the range otherwise.
    #[test]
    fn the_gauss_newton_gain_is_the_share_of_the_residual_in_the_jacobians_range() {
        let j = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 2.0, 0.0, 0.0]);
        assert!((gauss_newton_gain(&j, &[3.0, -1.0, 0.0]) - 1.0).abs() < 1e-14);
        assert_eq!(gauss_newton_gain(&j, &[0.0, 0.0, 5.0]), 0.0);
        let g = gauss_newton_gain(&j, &[3.0, 0.0, 4.0]);
        assert!((g - 9.0 / 25.0).abs() < 1e-14, "{g}");
        assert_eq!(gauss_newton_gain(&j, &[0.0, 0.0, 0.0]), 0.0);
    }

    /// Rosenbrock as residuals r = (10 (y − x²), 1 − x).
    fn rosenbrock(p: &[f64], jac: bool) -> Result<Evaluation, ()> {
        let (x, y) = (p[0], p[1]);
        Ok(Evaluation {
            residuals: vec![10.0 * (y - x * x), 1.0 - x],
            jacobian: jac.then(|| DMatrix::from_row_slice(2, 2, &[-20.0 * x, 10.0, -1.0, 0.0])),
        })
    }

    #[test]
    fn bfgs_and_gauss_newton_find_the_rosenbrock_minimum() {
        for method in [Method::Bfgs, Method::Hybrid, Method::GaussNewton] {
            let mut p = vec![-1.2, 1.0];
            let opts = OptimOptions {
                method,
                max_iterations: 200,
                rel_decrease: 0.0,
                gtol: 1e-10,
                target: 1e-20,
                max_step: f64::INFINITY,
                xtol: 0.0,
            };
            let r = minimize(&mut p, &opts, rosenbrock).unwrap();
            assert!(
                (p[0] - 1.0).abs() < 1e-6 && (p[1] - 1.0).abs() < 1e-6,
                "{method:?}: {p:?} after {r:?}"
            );
        }
    }

    /// A (quasi-)Newton step shorter than `xtol` is not tried: started 1e-4 from the minimum
    /// of a linear least-squares problem, every method stops after its first evaluation at
    /// xtol 1e-3, and steps to the minimum at xtol 1e-5.
    #[test]
    fn a_step_shorter_than_xtol_is_not_tried() {
        let lin = |p: &[f64], jac: bool| -> Result<Evaluation, ()> {
            Ok(Evaluation {
                residuals: vec![3.0 * p[0] - 1.0, 0.5 * p[1] + 2.0, p[0] + p[1] - 0.1],
                jacobian: jac
                    .then(|| DMatrix::from_row_slice(3, 2, &[3.0, 0.0, 0.0, 0.5, 1.0, 1.0])),
            })
        };
        // the least-squares minimum: (JᵀJ)⁻¹ Jᵀ b
        let j = DMatrix::from_row_slice(3, 2, &[3.0, 0.0, 0.0, 0.5, 1.0, 1.0]);
        let b = DVector::from_vec(vec![1.0, -2.0, 0.1]);
        let best = (j.transpose() * &j)
            .cholesky()
            .unwrap()
            .solve(&(j.transpose() * b));
        for method in [Method::Bfgs, Method::Hybrid, Method::GaussNewton] {
            for (xtol, stops) in [(1e-3, true), (1e-5, false)] {
                let mut p = vec![best[0] + 1e-4, best[1] - 1e-4];
                let opts = OptimOptions {
                    method,
                    xtol,
                    ..OptimOptions::default()
                };
                let r = minimize(&mut p, &opts, lin).unwrap();
                if stops {
                    assert_eq!(r.stop, "step below tolerance", "{method:?}");
                    assert_eq!(r.evaluations, 1, "{method:?}");
                    assert_eq!(p, vec![best[0] + 1e-4, best[1] - 1e-4], "{method:?}");
                } else {
                    assert_ne!(r.stop, "step below tolerance", "{method:?}");
                    assert!((p[0] - best[0]).abs() < 1e-8, "{method:?}: {p:?} {r:?}");
                    assert!((p[1] - best[1]).abs() < 1e-8, "{method:?}: {p:?} {r:?}");
                }
            }
        }
    }

    #[test]
    fn strong_wolfe_steps_satisfy_both_conditions() {
        // a quadratic with a badly scaled first step
        let f = |p: &[f64], jac: bool| -> Result<Evaluation, ()> {
            Ok(Evaluation {
                residuals: vec![3.0 * p[0] - 1.0, 0.5 * p[1] + 2.0],
                jacobian: jac.then(|| DMatrix::from_row_slice(2, 2, &[3.0, 0.0, 0.0, 0.5])),
            })
        };
        let x = DVector::from_vec(vec![0.0, 0.0]);
        let e0 = f(x.as_slice(), true).unwrap();
        let (f0, g0) = (e0.objective(), e0.gradient());
        for scale in [1e-3, 1.0, 30.0] {
            let d = -scale * &g0;
            let mut report = OptimReport::default();
            let mut eval = |q: &[f64], j: bool, _: &mut OptimReport| f(q, j).ok();
            let (a, fa, ga, _) = strong_wolfe(&x, f0, &g0, &d, &mut report, &mut eval).unwrap();
            assert!(fa <= f0 + C1 * a * g0.dot(&d), "scale {scale}");
            assert!(ga.dot(&d).abs() <= C2 * g0.dot(&d).abs(), "scale {scale}");
        }
    }
}
