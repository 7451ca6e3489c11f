//! Iterative refinement of a linear solve with the residual accumulated in extended precision
//! (Clyde et al. 2017 §6.3: shell Hessians have condition numbers near 1e10).
//!
//! After x₀ = A⁻¹b from the factorisation, repeat rₖ = b − A xₖ, xₖ₊₁ = xₖ + A⁻¹rₖ while the
//! residual keeps falling. With rₖ computed in working precision the loop stalls at the
//! round-off of the residual itself, about ε |A||x|; with rₖ accumulated in extended precision
//! the correction is accurate and the solution converges to working precision whenever
//! κ(A) ε < 1. Three residual kernels:
//! * [`Precision::F64`]: plain sums;
//! * [`Precision::DoubleDouble`] (default): compensated dot products (Ogita, Rump & Oishi 2005,
//!   "Dot2": TwoProd by fused multiply–add, TwoSum), as accurate as twice the working precision;
//! * [`Precision::Rug`]: MPFR floats of the given precision (≥ 113 bits), the reference.
//!
//! The matrix is symmetric, stored as its lower triangle in compressed columns.

use rug::Float;

/// Arithmetic of the residual.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Precision {
    F64,
    #[default]
    DoubleDouble,
    /// MPFR with this many bits of mantissa.
    Rug(u32),
}

impl std::str::FromStr for Precision {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "f64" => Ok(Self::F64),
            "dd" | "double-double" => Ok(Self::DoubleDouble),
            "rug" => Ok(Self::Rug(113)),
            _ => Err(format!("unknown precision '{s}' (expected f64, dd or rug)")),
        }
    }
}

/// A symmetric matrix by its lower triangle, compressed columns.
#[derive(Clone, Copy, Debug)]
pub struct SymLower<'a> {
    pub col_ptr: &'a [usize],
    pub row_idx: &'a [usize],
    pub values: &'a [f64],
}

impl SymLower<'_> {
    pub fn n(&self) -> usize {
        self.col_ptr.len() - 1
    }

    /// Visits every product term A_ij x_j of row i as (i, A_ij, x_j).
    fn terms(&self, x: &[f64], mut f: impl FnMut(usize, f64, f64)) {
        for c in 0..self.n() {
            for k in self.col_ptr[c]..self.col_ptr[c + 1] {
                let (r, v) = (self.row_idx[k], self.values[k]);
                f(r, v, x[c]);
                if r != c {
                    f(c, v, x[r]);
                }
            }
        }
    }

    /// The product A x.
    pub fn product(&self, x: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.n()];
        self.terms(x, |i, v, xj| out[i] += v * xj);
        out
    }

    /// Row sums of |A_ij||x_j|: the size of the terms a residual adds up.
    pub fn abs_product(&self, x: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.n()];
        self.terms(x, |i, v, xj| out[i] += (v * xj).abs());
        out
    }
}

/// (s, e) with s + e = a + b exactly.
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// r = b − A x in the given precision (rounded to f64 at the end).
pub fn residual(a: &SymLower, x: &[f64], b: &[f64], prec: Precision, r: &mut [f64]) {
    match prec {
        Precision::F64 => {
            r.copy_from_slice(b);
            a.terms(x, |i, v, xj| r[i] -= v * xj);
        }
        Precision::DoubleDouble => {
            let mut s = b.to_vec();
            let mut c = vec![0.0; b.len()];
            a.terms(x, |i, v, xj| {
                let p = -v * xj;
                let pe = (-v).mul_add(xj, -p);
                let (t, e) = two_sum(s[i], p);
                s[i] = t;
                c[i] += pe + e;
            });
            for i in 0..r.len() {
                r[i] = s[i] + c[i];
            }
        }
        Precision::Rug(bits) => {
            let bits = bits.max(113);
            let mut acc: Vec<Float> = b.iter().map(|&v| Float::with_val(bits, v)).collect();
            a.terms(x, |i, v, xj| {
                let p = Float::with_val(bits, v) * xj;
                acc[i] -= p;
            });
            for (ri, f) in r.iter_mut().zip(&acc) {
                *ri = f.to_f64();
            }
        }
    }
}

/// What refinement did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RefineReport {
    /// Corrections applied.
    pub steps: usize,
    /// ‖b − A x‖₂ (as computed in the chosen precision) before each correction and at the end.
    pub residuals: Vec<f64>,
    /// ‖correction‖₂ / ‖x‖₂ of each correction.
    pub corrections: Vec<f64>,
}

/// Refines `x` (already A⁻¹b from `solve`) while the corrections keep shrinking (each at most
/// half the last, and above ε‖x‖), at most `max_steps` corrections. The size of the correction,
/// not the residual, is what to watch: once x is accurate to working precision its residual
/// sits at ε|A||x| however good x is, but an accurately computed residual still yields a
/// meaningful correction.
pub fn refine(
    a: &SymLower,
    b: &[f64],
    x: &mut [f64],
    prec: Precision,
    max_steps: usize,
    solve: impl FnMut(&mut [f64]),
) -> RefineReport {
    refine_to(a, b, x, prec, max_steps, 0.0, solve)
}

/// [`refine`], but no correction is made once ‖b − A x‖₂ ≤ `enough`: a Newton step needs its
/// linear residual small against the nonlinear one, not at working precision (an inexact
/// Newton step with forcing term η leaves η r + O(r²) from a residual r), so the
/// factorisation's own solution, whose residual is checked here in the chosen precision, is
/// usually kept as it is, and the corrections are made where the tangent's conditioning
/// needs them.
pub fn refine_to(
    a: &SymLower,
    b: &[f64],
    x: &mut [f64],
    prec: Precision,
    max_steps: usize,
    enough: f64,
    mut solve: impl FnMut(&mut [f64]),
) -> RefineReport {
    let n = x.len();
    let mut r = vec![0.0; n];
    let mut report = RefineReport::default();
    let norm = |v: &[f64]| v.iter().map(|t| t * t).sum::<f64>().sqrt();
    residual(a, x, b, prec, &mut r);
    report.residuals.push(norm(&r));
    let mut last = f64::INFINITY;
    for _ in 0..max_steps {
        if report
            .residuals
            .last()
            .is_some_and(|&r| r == 0.0 || r <= enough)
        {
            break;
        }
        let mut corr = r.clone();
        solve(&mut corr);
        let size = norm(&corr) / norm(x).max(f64::MIN_POSITIVE);
        if size.is_nan() || size >= 0.5 * last {
            // the corrections stopped converging: this one is noise, keep x as it is
            break;
        }
        for (xi, ci) in x.iter_mut().zip(&corr) {
            *xi += ci;
        }
        report.corrections.push(size);
        report.steps += 1;
        residual(a, x, b, prec, &mut r);
        report.residuals.push(norm(&r));
        last = size;
        if size <= f64::EPSILON {
            break;
        }
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn double_double_matches_rug_on_hard_cancellation() {
        // one row: 1e16·1 − 1e16·1 + 1 − 1e-3: f64 loses the small terms
        let col_ptr = [0, 1, 2, 3, 4];
        let row_idx = [0, 1, 2, 3];
        let values = [1.0, 1.0, 1.0, 1.0];
        let a = SymLower {
            col_ptr: &col_ptr,
            row_idx: &row_idx,
            values: &values,
        };
        let x = [1e16 + 2.0, -1e16, 1.0, -1e-3];
        let b = [1e16 + 2.0 + 1.5, -1e16, 1.0 + 1e-17, -1e-3 + 1e-20];
        let (mut rd, mut rr) = ([0.0; 4], [0.0; 4]);
        residual(&a, &x, &b, Precision::DoubleDouble, &mut rd);
        residual(&a, &x, &b, Precision::Rug(200), &mut rr);
        for i in 0..4 {
            assert!((rd[i] - rr[i]).abs() <= 1e-25 * (x[i].abs() + b[i].abs()));
        }
    }
}
