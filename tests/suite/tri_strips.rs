//! The triangle models' tensile strip as a fitter runs it: each elongation starts on the
//! secant through the last two equilibria, and a trial's Newton budget ends a strip that
//! cannot settle.

use kshell::scene::{SceneError, TriTensile};
use kshell::solve::SolveError;
use kshell::tri::{Stiffness, TriKind, TriMaterial};

/// A stvk-ds material the cotton fit reaches before its shear stage: the fitted warp spline,
/// a stiff weft and a soft linear shear (yarn-to-shear ratio about 180), the cantilevers'
/// ASTM bending.
fn cotton_trial(shear: f64) -> TriMaterial {
    let warp = vec![100_752.3, 31_959.5, 35_104.1, 41_384.3, 56_552.1];
    TriMaterial {
        kind: TriKind::StvkDs,
        curves: [
            Stiffness::spline(0.0, 0.08, warp).unwrap(),
            Stiffness::constant(40_000.0),
            Stiffness::constant(shear),
            Stiffness::constant(2.7e-5),
            Stiffness::constant(1.8e-5),
            Stiffness::constant(2.2e-5),
        ],
        coupling: 0.0,
        areal_density: 0.1036,
    }
}

/// The fit's strip: 50 × 75 mm on 8 × 12 faces.
fn strip(angle_deg: f64) -> TriTensile {
    let mut s = TriTensile::new(0.05, 0.075, angle_deg);
    s.mesh = (8, 12);
    s
}

/// Five elongations of 1.2 mm up to 6 mm (8 % strain).
const ELONGATIONS: [f64; 5] = [1.2e-3, 2.4e-3, 3.6e-3, 4.8e-3, 6.0e-3];

/// Started from the last equilibrium stretched affinely along the strip, every elongation of
/// the 45° strip rebuilt its lateral contraction and wrinkles in 5 to 32 Newton iterations
/// (backward-Euler steps among them); on the secant each after the first takes 3 or 4.
#[test]
fn a_strip_starts_each_elongation_on_the_secant() {
    let points = strip(45.0)
        .run(&cotton_trial(567.55), &ELONGATIONS)
        .unwrap();
    let later: Vec<usize> = points[1..].iter().map(|p| p.report.iterations).collect();
    assert!(later.iter().all(|&n| n <= 8), "{later:?}");
    // the forces are the equilibria's, whatever the start: the bias strip is near linear
    let f = |i: usize| points[i].force;
    assert!((f(4) / f(0) - 5.79).abs() < 0.05, "{} {}", f(0), f(4));
}

/// A trial's budget holds over the whole run: the 67.5° strip needs about 50 Newton
/// iterations for its first elongation, so a budget of 30 fails it as not converged, with
/// no sub-steps after the budget is spent.
#[test]
fn a_strip_stops_when_its_budget_is_spent() {
    let m = cotton_trial(567.55);
    let mut s = strip(67.5);
    assert!(s.run(&m, &ELONGATIONS).is_ok());
    s.budget = Some(30);
    match s.run(&m, &ELONGATIONS) {
        Err(SceneError::Solve {
            source: SolveError::NotConverged { .. },
            ..
        }) => {}
        other => panic!("{other:?}"),
    }
}
