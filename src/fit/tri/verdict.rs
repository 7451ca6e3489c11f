//! The triangle-model fit's verdict, as the shell fit's (`crate::fit::verdict`): a fitted test
//! whose error exceeds `--max-error` fails the fit (`ks-fit fit --model M` prints FIT FAILED and
//! exits 3); a validation test or a predicted shape is reported, not failed.
//!
//! A strip fitted alone at its angle is judged by its mean |relative error|. Repeats fitted
//! together at one angle differ by a force scale that no law follows (the fit passes through
//! their middle), so each is judged by the larger of its error after its own scale and how far
//! the model lies outside the repeats' scale band. A bend is judged by |drape angle − measured|
//! / measured, a fitted shape by its descriptor's relative error.

use super::TestFit;
use crate::fit::verdict::{drape_error, force_scale, is_over, repeat_error};

/// The scale s with measured ≈ s·model that best explains a curve whose relative residuals
/// are `r` (model/measured = 1 + r; s = Σq/Σq² minimises Σ(s q − 1)²), and the mean |relative
/// error| after it; `None` where no residual is finite.
pub fn repeat_scale(r: &[f64]) -> Option<(f64, f64)> {
    let q: Vec<f64> = r
        .iter()
        .map(|v| 1.0 + v)
        .filter(|q| q.is_finite())
        .collect();
    if q.is_empty() {
        return None;
    }
    Some(force_scale(&q))
}

/// The error the verdict reads for test `i` (see the module doc).
fn judged(tests: &[TestFit], i: usize) -> Option<f64> {
    let t = &tests[i];
    if let Some((a, g)) = t.drape_angle_deg {
        return Some(drape_error(a, g));
    }
    if let Some(s) = &t.shape {
        return Some(s.error);
    }
    let siblings: Vec<&TestFit> = tests
        .iter()
        .filter(|o| o.fitted && o.kind == "tensile" && (o.angle_deg - t.angle_deg).abs() < 1e-9)
        .collect();
    match (t.scale, siblings.len()) {
        (Some((_, scaled)), n) if n >= 2 => {
            let scales: Vec<f64> = siblings
                .iter()
                .filter_map(|o| o.scale.map(|s| s.0))
                .collect();
            Some(repeat_error(scaled, &scales))
        }
        _ => t.avg_rel_error,
    }
}

/// The fitted tests above `max_error` (fraction), each as "kind angle (error %)".
pub fn over(tests: &[TestFit], max_error: f64) -> Vec<String> {
    (0..tests.len())
        .filter(|&i| tests[i].fitted)
        .filter_map(|i| {
            let e = judged(tests, i)?;
            let t = &tests[i];
            is_over(e, max_error).then(|| match (&t.shape, &t.curve) {
                (Some(s), _) => format!("shape {} ({:.1} %)", s.scene, 100.0 * e),
                (None, Some(c)) => format!("{} {}° {c} ({:.1} %)", t.kind, t.angle_deg, 100.0 * e),
                (None, None) => format!("{} {}° ({:.1} %)", t.kind, t.angle_deg, 100.0 * e),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{over, repeat_scale, TestFit};

    fn strip(curve: &str, r: &[f64], fitted: bool) -> TestFit {
        TestFit {
            kind: "tensile",
            angle_deg: 45.0,
            curve: Some(curve.into()),
            avg_rel_error: Some(r.iter().map(|v| v.abs()).sum::<f64>() / r.len() as f64),
            scale: repeat_scale(r),
            drape_angle_deg: None,
            mesh: (8, 8),
            fitted,
            shape: None,
        }
    }

    #[test]
    fn a_pure_scale_is_undone_exactly() {
        // the model 20 % under every point: measured = 1.25 model
        let (s, scaled) = repeat_scale(&[-0.2, -0.2, -0.2]).unwrap();
        assert!((s - 1.25).abs() < 1e-12 && scaled < 1e-12);
    }

    #[test]
    fn repeats_straddling_the_model_pass_and_a_lone_strip_is_judged_raw() {
        // two repeats 15 % either side of the model: raw errors 13–18 %, band contains 1
        let pair = [
            strip("a", &[0.15, 0.15], true),
            strip("b", &[-0.15, -0.15], true),
        ];
        assert!(over(&pair, 0.10).is_empty(), "{:?}", over(&pair, 0.10));
        // the same repeats both above the model: the band misses 1 by 13 %
        let high = [
            strip("a", &[0.15, 0.15], true),
            strip("b", &[0.15, 0.16], true),
        ];
        assert_eq!(over(&high, 0.10).len(), 2);
        // one strip alone, 15 % off, fails; the same as a validation test does not
        assert_eq!(over(&[strip("a", &[0.15, 0.15], true)], 0.10).len(), 1);
        assert!(over(&[strip("a", &[0.15, 0.15], false)], 0.10).is_empty());
    }

    #[test]
    fn a_test_that_does_not_solve_is_over_any_error() {
        assert_eq!(
            over(&[strip("a", &[f64::NAN, f64::NAN], true)], 0.10).len(),
            1
        );
    }

    #[test]
    fn a_bend_is_judged_by_its_relative_angle_error() {
        let bend = |a: f64| TestFit {
            kind: "bend",
            angle_deg: 90.0,
            curve: None,
            avg_rel_error: None,
            scale: None,
            drape_angle_deg: Some((a, 41.5)),
            mesh: (4, 12),
            fitted: true,
            shape: None,
        };
        assert!(over(&[bend(44.0)], 0.10).is_empty());
        assert_eq!(over(&[bend(46.0)], 0.10), ["bend 90° (10.8 %)"]);
    }
}
