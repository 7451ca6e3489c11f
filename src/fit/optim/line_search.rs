//! The strong-Wolfe line search of the BFGS minimiser (Nocedal & Wright 2006, Algorithms
//! 3.5–3.6): bracketing, then a zoom by safeguarded cubic interpolation.

use super::{Eval, OptimReport};
use nalgebra::{DMatrix, DVector};

/// A trial point of the line search: α, ε, ∇ε and the slope ∇ε·d.
type Trial = (f64, f64, DVector<f64>, f64, Option<DMatrix<f64>>);
/// An accepted step: α, ε, ∇ε and the Jacobian there.
type Step = (f64, f64, DVector<f64>, Option<DMatrix<f64>>);

/// Strong-Wolfe step along `d` (c₁ = 1e-4, c₂ = 0.9): (α, ε, ∇ε) at the accepted point.
pub(super) fn strong_wolfe(
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

/// The sufficient-decrease constant c₁ of the Wolfe conditions.
pub(super) const C1: f64 = 1e-4;
/// The curvature constant c₂ of the Wolfe conditions.
pub(super) const C2: f64 = 0.9;

/// Most trial points one zoom phase evaluates.
const ZOOM_EVALUATIONS: usize = 8;

/// Zoom between `lo` (sufficient decrease holds) and the other end `a_hi` (its trial, if the
/// evaluation succeeded), by safeguarded cubic interpolation (Nocedal & Wright, Alg. 3.6).
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
