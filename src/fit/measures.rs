//! Small measures the stages share: the axial Green strain of an elongation, the shape error
//! and mean errors of residuals, and residual lists turned into an [`Evaluation`].

use super::optim::Evaluation;
use nalgebra::DMatrix;

/// Green strain along the axis at an elongation.
pub(super) fn green(dl: f64, length: f64) -> f64 {
    let l = 1.0 + dl / length;
    0.5 * (l * l - 1.0)
}

pub(super) fn to_evaluation(r: Vec<f64>, j: Vec<Vec<f64>>, n: usize, jac: bool) -> Evaluation {
    let jacobian = jac.then(|| {
        let mut m = DMatrix::zeros(r.len(), n);
        for (i, row) in j.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                m[(i, c)] = *v;
            }
        }
        m
    });
    Evaluation {
        residuals: r,
        jacobian,
    }
}

/// Shape misfit of a set of curves: each curve's mean |relative error| after its own best
/// force scale, averaged over the curves. `lens` are the curves' point counts and `rel`
/// their relative errors in order. Repeat-to-repeat scatter is mostly a scale (strip width,
/// yarn count per strip), which no law can fit; the degree of η is chosen on what is left.
pub(super) fn shape_error(lens: &[usize], rel: &[f64]) -> f64 {
    let mut k = 0;
    let mut sum = 0.0;
    for &n in lens {
        let q: Vec<f64> = rel[k..k + n].iter().map(|r| 1.0 + r).collect();
        k += n;
        let s = q.iter().sum::<f64>() / q.iter().map(|v| v * v).sum::<f64>().max(1e-300);
        sum += q.iter().map(|v| (s * v - 1.0).abs()).sum::<f64>() / n.max(1) as f64;
    }
    sum / lens.len().max(1) as f64
}

pub(super) fn mean_abs(r: &[f64]) -> f64 {
    r.iter().map(|v| v.abs()).sum::<f64>() / r.len().max(1) as f64
}

/// Mean |r| over the finite values only: the errors of a curve whose excluded points (a
/// saddle's, see `rigs::node_force`) are NaN.
pub(super) fn mean_abs_finite(r: &[f64]) -> f64 {
    let ok: Vec<f64> = r.iter().copied().filter(|v| v.is_finite()).collect();
    mean_abs(&ok)
}
