//! The solver's strategies are different roads to an equilibrium. Where the equilibrium is
//! unique (a bias strip of a stiffening law, no wrinkles) every strategy gives the same clamp
//! forces; where the strip wrinkles (thin and shear-soft: the Hessian is indefinite from the
//! first step) each strategy must still end at a stable state, but not necessarily the same
//! one: wrinkle patterns are not unique.

use crate::common::TestLaw;
use kshell::material::FabricMaterial;
use kshell::scene::{TensilePoint, TensileStrip};
use kshell::solve::{NewtonOptions, Strategy};

fn curves(m: &FabricMaterial, strains: &[f64]) -> Vec<(&'static str, Vec<TensilePoint>)> {
    let mut out = Vec::new();
    for (name, strategy) in Strategy::ALL {
        let mut strip = TensileStrip::new(0.05, 0.075, 45.0);
        strip.mesh = (4, 6);
        strip.solver = NewtonOptions {
            strategy,
            max_iterations: 500,
            ..NewtonOptions::default()
        };
        let dl: Vec<f64> = strains.iter().map(|s| s * 0.075).collect();
        let curve = strip.run(m, &dl).unwrap_or_else(|e| panic!("{name}: {e}"));
        for p in &curve {
            assert!(p.report.stable, "{name}: a saddle at {} m", p.elongation);
        }
        out.push((name, curve));
    }
    out
}

#[test]
fn every_strategy_gives_the_same_forces_where_the_equilibrium_is_unique() {
    let m = kshell::atlas::stiffening();
    let all = curves(&m, &[0.1, 0.2]);
    let (_, reference) = &all[0];
    for (name, curve) in &all {
        for (p, q) in curve.iter().zip(reference) {
            let rel = (p.force - q.force).abs() / q.force.abs();
            assert!(rel < 1e-8, "{name}: {} N against {} N", p.force, q.force);
        }
    }
}

#[test]
fn every_strategy_ends_stable_on_a_wrinkling_strip() {
    let m = TestLaw::stvk(1.0e9, 1.0e8, 1.0e7, 1.0e5)
        .named("thin")
        .thickness(5.0e-5)
        .material();
    for (name, curve) in curves(&m, &[0.01, 0.03]) {
        let forces: Vec<f64> = curve.iter().map(|p| p.force).collect();
        eprintln!("{name}: {forces:?} N");
        assert!(forces.iter().all(|f| *f > 0.0 && f.is_finite()));
    }
}

/// Stiff yarns over a soft shear (yarn-to-shear ratio 1000) at 22.5°: a one-step start from the
/// predictor can crawl by backward Euler where two sub-steps converge in a few Newton
/// iterations each. With the fitter's and synth's limit of 500 the first attempt is now held
/// to 40 before the step is cut (measured on 16 × 24, the 6 → 7.5 mm point: 75 iterations of
/// crawl before, 50 with the cap alone, 8 where the Euler predictor is taken for its lower
/// energy), and the point lands on the same equilibrium as a run with half the step.
#[test]
fn a_stiff_yarn_strip_does_not_crawl_from_a_poor_predictor() {
    let m = TestLaw::stvk(1.0e9, 3.0e8, 1.5e8, 1.0e6)
        .named("ratio-1000")
        .density(0.25)
        .thickness(3.0e-4)
        .material();
    let run = |steps: usize| {
        let mut strip = TensileStrip::new(0.05, 0.075, 22.5);
        strip.mesh = (16, 24);
        strip.grading = kshell::scene::STRIP_GRADING;
        strip.solver.max_iterations = 500;
        let dl: Vec<f64> = (1..=steps)
            .map(|k| 7.5e-3 * k as f64 / steps as f64)
            .collect();
        strip.run(&m, &dl).unwrap()
    };
    let coarse = run(5);
    let fine = run(10);
    for (k, p) in coarse.iter().enumerate() {
        assert!(p.report.stable, "a saddle at {} m", p.elongation);
        let q = &fine[2 * k + 1];
        assert!((p.elongation - q.elongation).abs() < 1e-15);
        let rel = (p.force - q.force).abs() / q.force;
        assert!(
            rel < 1e-6,
            "{} m: {} N against {} N",
            p.elongation,
            p.force,
            q.force
        );
    }
    let its: Vec<usize> = coarse.iter().map(|p| p.report.iterations).collect();
    eprintln!("iterations per point: {its:?}");
    assert!(its.iter().all(|&n| n <= 20), "{its:?}");
}

/// Stiff yarns over a soft shear (yarn-to-shear ratio 2e4) at 67.5° on a graded 16 × 24 cage,
/// three points to 4.5 mm: the last point's first attempt runs out of its 40 iterations while
/// settling into a wrinkle pattern (its residual cut tenfold and more), and now goes on with
/// the whole budget where it stopped. Cutting its step in half started the settling again and
/// failed too: that point took 85 iterations before, 48 now (measured in this test's build;
/// five points to 7.5 mm took 828 and 560, and the CLI's build, whose round-off differs, 792
/// and 342 with every force the same to 1e-11 but the last, which lands on another wrinkle
/// state 1.6e-5 lower: wrinkling paths are chaotic, so the bound sits between the two).
#[test]
fn a_settling_first_attempt_keeps_its_budget() {
    let m = TestLaw::stvk(3.0e9, 1.0e9, 5.0e8, 1.5e5)
        .named("ratio-20000")
        .density(0.25)
        .thickness(3.0e-4)
        .material();
    let mut strip = TensileStrip::new(0.05, 0.075, 67.5);
    strip.mesh = (16, 24);
    strip.grading = kshell::scene::STRIP_GRADING;
    strip.solver.max_iterations = 500;
    let dl: Vec<f64> = (1..=3).map(|k| 1.5e-3 * k as f64).collect();
    let curve = strip.run(&m, &dl).unwrap();
    let its: Vec<usize> = curve.iter().map(|p| p.report.iterations).collect();
    eprintln!("iterations per point: {its:?}");
    for w in curve.windows(2) {
        assert!(
            w[1].force > w[0].force,
            "{} N after {} N",
            w[1].force,
            w[0].force
        );
    }
    assert!(curve.iter().all(|p| p.report.stable));
    assert!(its[2] <= 65, "{its:?}");
}

/// A warp strip compressed by 2 % buckles: Newton's factorisation fails from the first step.
/// With a convexified step after each negative-curvature step the default strategy reaches a
/// stable state in 41 iterations (full size, measured); with backward Euler's H + μM there it
/// took 159 (the stability atlas before the change). The bound sits between the two.
#[test]
fn convexified_steps_settle_a_buckling_strip_quickly() {
    let method = kshell::atlas::methods()
        .into_iter()
        .find(|m| m.name == "full-step")
        .expect("the default strategy is in the atlas");
    let row = kshell::atlas::Case::Compression.run(&method, false);
    assert!(row.converged && row.stable, "{}", row.note);
    assert!(row.note.contains("convexified steps"), "{}", row.note);
    assert!(
        row.iterations <= 80,
        "{} iterations: {}",
        row.iterations,
        row.note
    );
}

/// A start whose forces overflow is refused, never returned as converged: an infinite residual
/// once compared equal to the infinite round-off floor it implied, and a strip whose tangent
/// predictor had flown off (a nearly singular tangent) came back as an "equilibrium" with a
/// force of −6e241 N.
#[test]
fn a_start_whose_forces_overflow_is_refused() {
    use kshell::assembly::ShellModel;
    use kshell::mesh::rectangular_grid;
    use kshell::solve::{newton, FreeSystem, SolveError};
    use kshell::subdiv::{BasisOptions, LimitBasis};
    use std::sync::Arc;
    let law = TestLaw::stvk(2.0e8, 1.2e8, 2.0e7, 4.0e6).stvk_law();
    let mesh = rectangular_grid(0.05, 0.075, 2, 3);
    let basis = LimitBasis::new(&mesh, BasisOptions::default()).unwrap();
    let model = ShellModel::new(
        basis,
        kshell::scene::warp_direction(0.0),
        Arc::new(law),
        1.8e-4,
        0.1,
    )
    .unwrap();
    let n = model.num_nodes();
    let rest = model.basis.control_points.clone();
    let fixed: Vec<bool> = (0..3 * n).map(|d| rest[d / 3][1] < 1e-9).collect();
    let system = FreeSystem::new(&model, &fixed).unwrap();
    let mut x: Vec<kshell::Vec3> = rest
        .iter()
        .map(|p| {
            if p[1] < 1e-9 {
                *p
            } else {
                [p[0], p[1], 1e80 * p[1]]
            }
        })
        .collect();
    let r = newton(&model, &system, &mut x, &NewtonOptions::default());
    assert!(matches!(r, Err(SolveError::StartOutOfDomain(_))), "{r:?}");
}
