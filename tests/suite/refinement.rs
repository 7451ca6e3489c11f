//! Iterative refinement on a badly conditioned system: the clamped 1-D biharmonic (a beam's
//! bending stiffness, the stiff-and-soft mix of a thin shell in one line), condition number
//! about n⁴/6.

use faer::prelude::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{MatMut, Side};
use kshell::solve::refine::{refine_to, residual, Precision, SymLower};

/// Lower triangle of the pentadiagonal [1, −4, 6, −4, 1] (clamped ends), CSC.
fn biharmonic(n: usize) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    let (mut cp, mut ri, mut v) = (vec![0], Vec::new(), Vec::new());
    for c in 0..n {
        for (off, val) in [
            (0, if c == 0 || c == n - 1 { 7.0 } else { 6.0 }),
            (1, -4.0),
            (2, 1.0),
        ] {
            if c + off < n {
                ri.push(c + off);
                v.push(val);
            }
        }
        cp.push(ri.len());
    }
    (cp, ri, v)
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

struct Outcome {
    true_residual: f64,
    forward_error: f64,
    computed: Vec<f64>,
    rhs_norm: f64,
}

fn run(n: usize, prec: Precision) -> Outcome {
    run_to(n, prec, 0.0)
}

/// The system of size `n` solved and refined until its residual is at most `forcing` ‖b‖.
fn run_to(n: usize, prec: Precision, forcing: f64) -> Outcome {
    let (cp, ri, v) = biharmonic(n);
    let a = SymLower {
        col_ptr: &cp,
        row_idx: &ri,
        values: &v,
    };
    // an exact solution of integers, so that b = A x* is exact in f64 too
    let xs: Vec<f64> = (0..n)
        .map(|i| ((i * 7919 % 1013) as f64 - 506.0) * (1.0 + i as f64))
        .collect();
    let mut b = vec![0.0; n];
    residual(&a, &xs, &vec![0.0; n], Precision::Rug(256), &mut b);
    b.iter_mut().for_each(|t| *t = -*t);
    let sym = SymbolicSparseColMatRef::new_checked(n, n, &cp, None, &ri);
    let symbolic = SymbolicLlt::try_new(sym, Side::Lower).unwrap();
    let llt =
        Llt::try_new_with_symbolic(symbolic, SparseColMatRef::new(sym, &v), Side::Lower).unwrap();
    let solve = |r: &mut [f64]| llt.solve_in_place(MatMut::from_column_major_slice_mut(r, n, 1));
    let mut x = b.clone();
    solve(&mut x);
    let rep = refine_to(&a, &b, &mut x, prec, 10, forcing * norm(&b), solve);
    let mut r = vec![0.0; n];
    residual(&a, &x, &b, Precision::Rug(256), &mut r);
    let fe: Vec<f64> = x.iter().zip(&xs).map(|(a, b)| a - b).collect();
    Outcome {
        true_residual: norm(&r),
        forward_error: norm(&fe) / norm(&xs),
        computed: rep.residuals,
        rhs_norm: norm(&b),
    }
}

/// λ_max / λ_min by power and inverse-power iteration.
fn condition_number(n: usize) -> f64 {
    let (cp, ri, v) = biharmonic(n);
    let a = SymLower {
        col_ptr: &cp,
        row_idx: &ri,
        values: &v,
    };
    let sym = SymbolicSparseColMatRef::new_checked(n, n, &cp, None, &ri);
    let symbolic = SymbolicLlt::try_new(sym, Side::Lower).unwrap();
    let llt =
        Llt::try_new_with_symbolic(symbolic, SparseColMatRef::new(sym, &v), Side::Lower).unwrap();
    let mul = |x: &[f64]| {
        let mut y = vec![0.0; n];
        residual(&a, x, &vec![0.0; n], Precision::F64, &mut y);
        y.iter().map(|t| -t).collect::<Vec<f64>>()
    };
    let (mut hi, mut lo) = (vec![1.0; n], vec![1.0; n]);
    hi[0] = -1.0;
    let (mut lmax, mut lmin_inv) = (0.0, 0.0);
    for _ in 0..300 {
        let y = mul(&hi);
        lmax = norm(&y) / norm(&hi);
        hi = y.iter().map(|t| t / norm(&y)).collect();
        let mut z = lo.clone();
        llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut z, n, 1));
        lmin_inv = norm(&z) / norm(&lo);
        lo = z.iter().map(|t| t / norm(&z)).collect();
    }
    lmax * lmin_inv
}

#[test]
fn extended_precision_residual_beats_plain_refinement() {
    let n = 1000;
    let kappa = condition_number(n);
    assert!(kappa >= 1e10, "condition number {kappa:.3e}");
    let f = run(n, Precision::F64);
    let d = run(n, Precision::DoubleDouble);
    let g = run(n, Precision::Rug(113));
    for (name, o) in [("f64", &f), ("dd", &d), ("rug", &g)] {
        eprintln!(
            "{name}: true residual {:.3e}, forward error {:.3e}, computed residuals {:?}",
            o.true_residual, o.forward_error, o.computed
        );
    }
    // measured (n = 1000, κ ≈ 3e10): f64 stalls at a true residual 3.6e-9 (forward error 5e-9);
    // double-double and rug reach 3.2e-18 (forward error 7e-26: the exact integer solution)
    assert!(
        f.computed.len() <= 3,
        "f64 refinement should stall: {:?}",
        f.computed
    );
    assert!(
        d.true_residual * 100.0 <= f.true_residual,
        "dd {:.3e} vs f64 {:.3e}",
        d.true_residual,
        f.true_residual
    );
    assert!(g.true_residual * 100.0 <= f.true_residual);
    assert!(d.forward_error * 100.0 <= f.forward_error);
}

#[test]
fn double_double_residual_agrees_with_rug_to_1e25_of_the_terms() {
    let n = 600;
    let (cp, ri, v) = biharmonic(n);
    let a = SymLower {
        col_ptr: &cp,
        row_idx: &ri,
        values: &v,
    };
    // the inexact f64 solution: its residual is all cancellation
    let xs: Vec<f64> = (0..n)
        .map(|i| ((i * 7919 % 1013) as f64 - 506.0) * (1.0 + i as f64))
        .collect();
    let x: Vec<f64> = xs
        .iter()
        .enumerate()
        .map(|(i, t)| t * (1.0 + 1e-13 * ((i % 7) as f64 - 3.0)))
        .collect();
    let b: Vec<f64> = {
        let mut r = vec![0.0; n];
        residual(&a, &xs, &vec![0.0; n], Precision::Rug(256), &mut r);
        r.iter().map(|t| -t).collect()
    };
    let (mut rd, mut rr) = (vec![0.0; n], vec![0.0; n]);
    residual(&a, &x, &b, Precision::DoubleDouble, &mut rd);
    residual(&a, &x, &b, Precision::Rug(256), &mut rr);
    let terms = a.abs_product(&x);
    for i in 0..n {
        let size = terms[i] + b[i].abs();
        assert!(
            (rd[i] - rr[i]).abs() <= 1e-25 * size,
            "row {i}: dd {} rug {} (terms {size:.3e})",
            rd[i],
            rr[i]
        );
    }
}

#[test]
fn refinement_stops_once_the_residual_is_small_enough() {
    let n = 1000;
    let full = run_to(n, Precision::DoubleDouble, 0.0);
    let first = full.computed[0] / full.rhs_norm;
    let last = full.computed.last().unwrap() / full.rhs_norm;
    assert!(
        full.computed.len() >= 3 && last < 1e-3 * first,
        "{:?}",
        full.computed
    );
    // enough already: the factorisation's solution is kept, its residual checked once
    let kept = run_to(n, Precision::DoubleDouble, 2.0 * first);
    assert_eq!(kept.computed.len(), 1);
    // a forcing term above the second residual: one correction, no more (measured residuals
    // 3.6e-9, 1.6e-9, 3.2e-18 with every correction)
    let forcing = 2.0 * full.computed[1] / full.rhs_norm;
    assert!(forcing < first);
    let some = run_to(n, Precision::DoubleDouble, forcing);
    let (done, before) = some.computed.split_last().unwrap();
    assert!(*done <= forcing * some.rhs_norm, "{:?}", some.computed);
    assert!(
        before.iter().all(|r| *r > forcing * some.rhs_norm),
        "{:?}",
        some.computed
    );
    assert!(
        some.computed.len() < full.computed.len(),
        "{:?} against {:?}",
        some.computed,
        full.computed
    );
}
