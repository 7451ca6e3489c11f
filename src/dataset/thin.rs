//! Thinning a long curve to the points that carry its shape: a curve above
//! [`crate::limits::MAX_CURVE_POINTS`] keeps the points that a piecewise-linear interpolation
//! needs to stay within [`THINNING_TOLERANCE`] of its force range at every point it drops.

/// The largest force error of a thinned curve's piecewise-linear interpolation at a dropped
/// point, as a fraction of the full curve's force range (largest minus smallest force).
pub const THINNING_TOLERANCE: f64 = 1e-3;

/// The indices of the points to keep, first and last included, so that the piecewise-linear
/// interpolation through them is within `tol` (in force units) of the force of every point
/// between. `x` is strictly increasing.
///
/// Greedy, in one pass: from the last kept point (the anchor) the slopes of lines that pass
/// within `tol` of every point seen so far form an interval; the segment may end at a point
/// whose slope from the anchor lies in it. When the interval empties, the last point that
/// could end the segment is kept and becomes the anchor.
pub(super) fn thin(x: &[f64], y: &[f64], tol: f64) -> Vec<usize> {
    let n = x.len();
    if n <= 2 {
        return (0..n).collect();
    }
    let mut keep = vec![0];
    let mut anchor = 0;
    while anchor < n - 1 {
        let end = segment_end(x, y, anchor, tol);
        keep.push(end);
        anchor = end;
    }
    keep
}

/// The farthest point that a straight segment from `anchor` may end at with every point
/// between within `tol` of it (the next point at least).
fn segment_end(x: &[f64], y: &[f64], anchor: usize, tol: f64) -> usize {
    let (xa, ya) = (x[anchor], y[anchor]);
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    let mut end = anchor + 1;
    for k in anchor + 1..x.len() {
        let dx = x[k] - xa;
        let slope = (y[k] - ya) / dx;
        if slope >= lo && slope <= hi {
            end = k;
        }
        lo = lo.max((y[k] - tol - ya) / dx);
        hi = hi.min((y[k] + tol - ya) / dx);
        if lo > hi {
            break;
        }
    }
    end
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The largest |force − interpolation| over every point of the full curve.
    fn worst_error(x: &[f64], y: &[f64], keep: &[usize]) -> f64 {
        let mut worst: f64 = 0.0;
        for w in keep.windows(2) {
            let (a, b) = (w[0], w[1]);
            for i in a..=b {
                let t = (x[i] - x[a]) / (x[b] - x[a]);
                worst = worst.max((y[i] - (y[a] + t * (y[b] - y[a]))).abs());
            }
        }
        worst
    }

    #[test]
    fn a_smooth_curve_keeps_few_points_within_the_tolerance() {
        let n = 100_000;
        let x: Vec<f64> = (0..n).map(|i| 6.0 * i as f64 / n as f64).collect();
        let y: Vec<f64> = x.iter().map(|e| 40.0 * e + 2.0 * e * e * e).collect();
        let tol = THINNING_TOLERANCE * (y[n - 1] - y[0]);
        let keep = thin(&x, &y, tol);
        assert_eq!((keep[0], *keep.last().unwrap()), (0, n - 1));
        assert!(keep.windows(2).all(|w| w[0] < w[1]));
        assert!(keep.len() < 100, "{} points kept", keep.len());
        assert!(worst_error(&x, &y, &keep) <= tol * (1.0 + 1e-9));
    }

    #[test]
    fn noise_and_steps_stay_within_the_tolerance() {
        // a deterministic scatter of ±0.5 % and a force drop (a yarn breaking)
        let n = 20_000;
        let x: Vec<f64> = (1..=n).map(|i| i as f64 * 1e-3).collect();
        let y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, e)| {
                let noise = ((i * 7919) % 101) as f64 / 100.0 - 0.5;
                let drop = if i > n / 2 { -30.0 } else { 0.0 };
                100.0 * e * e + noise + drop
            })
            .collect();
        let tol = 0.4;
        let keep = thin(&x, &y, tol);
        assert!(worst_error(&x, &y, &keep) <= tol * (1.0 + 1e-9));
        assert!(keep.len() < n, "nothing dropped");
        assert_eq!(thin(&x[..2], &y[..2], tol), [0, 1]);
    }
}
