use super::line_search::C2;
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
            jacobian: jac.then(|| DMatrix::from_row_slice(3, 2, &[3.0, 0.0, 0.0, 0.5, 1.0, 1.0])),
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
