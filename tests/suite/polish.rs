//! The polished last Newton step (`NewtonOptions::polish`): taken on the factorisation that
//! computed it and checked by a gradient assembly, it must reach the same equilibrium as the
//! solve that assembles and factorises once more, within the residual tolerance, for one
//! Hessian assembly fewer; and the gradient it hands back must be the one at the solution.
//! With chord steps (`NewtonOptions::chord_from`), the same equilibrium for fewer tangents.

use kshell::assembly::{BlockMatrix, Want};
use kshell::material::{load_material, OutOfDomain};
use kshell::model::ClothModel;
use kshell::solve::{newton_linearized, FreeSystem, NewtonOptions};
use kshell::tri::{TriGrid, TriKind, TriMaterial, TriModel};
use kshell::Vec3;
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
use std::sync::Arc;

/// A model that counts its Hessian and gradient-only assemblies.
struct Counting {
    inner: TriModel,
    hessians: AtomicUsize,
    gradients: AtomicUsize,
}

impl ClothModel for Counting {
    fn pattern(&self) -> &Arc<kshell::assembly::BlockPattern> {
        self.inner.pattern()
    }
    fn num_nodes(&self) -> usize {
        self.inner.num_nodes()
    }
    fn assemble(
        &self,
        x: &[Vec3],
        want: Want,
        grad: Option<&mut [Vec3]>,
        hess: Option<&mut BlockMatrix>,
    ) -> Result<f64, OutOfDomain> {
        match want {
            Want::Hessian | Want::ProjectedHessian => {
                self.hessians.fetch_add(1, Relaxed);
            }
            Want::Gradient => {
                self.gradients.fetch_add(1, Relaxed);
            }
            Want::Energy => {}
        }
        self.inner.assemble(x, want, grad, hess)
    }
    fn external_load(&self) -> Vec<Vec3> {
        self.inner.external_load()
    }
    fn convexifies(&self) -> bool {
        self.inner.convexifies()
    }
    fn lumped_mass(&self) -> Vec<f64> {
        self.inner.lumped_mass()
    }
}

/// A 6 × 3 stvk-ds cantilever of the example cotton under gravity, its first column clamped
/// (a bending problem: Newton needs several steps from the flat sheet).
fn cantilever() -> (Counting, FreeSystem, Vec<Vec3>) {
    let cotton = load_material(std::path::Path::new("examples/materials/cotton.toml")).unwrap();
    let mat = TriMaterial::equivalent(TriKind::StvkDs, &cotton, 0.005, 100.0).unwrap();
    let mut inner = TriModel::new(TriGrid::rectangle(0.06, 0.03, 6, 3), mat, 0.0);
    inner.set_gravity([0.0, 0.0, -9.81]);
    let rest = inner.grid.positions();
    let n = inner.num_nodes();
    let fixed: Vec<bool> = (0..3 * n).map(|d| rest[d / 3][0] < 1e-9).collect();
    let system = FreeSystem::new(&inner, &fixed).unwrap();
    let model = Counting {
        inner,
        hessians: AtomicUsize::new(0),
        gradients: AtomicUsize::new(0),
    };
    (model, system, rest)
}

#[test]
fn a_polished_last_step_reaches_the_same_equilibrium_for_one_tangent_fewer() {
    let (model, system, rest) = cantilever();
    let mut runs = Vec::new();
    for polish in [false, true] {
        let opts = NewtonOptions {
            polish,
            // the polish alone (from √rtol); chords are tested below
            chord_from: 0.0,
            rtol: 1e-8,
            max_iterations: 300,
            ..NewtonOptions::default()
        };
        model.hessians.store(0, Relaxed);
        model.gradients.store(0, Relaxed);
        let mut x = rest.clone();
        let (report, lin) = newton_linearized(&model, &system, &mut x, &opts).unwrap();
        assert!(
            report.residual <= 1e-8 || report.precision_limited,
            "{report:?}"
        );
        assert!(report.stable);
        assert_eq!(report.polished, polish, "{report:?}");
        let lin = lin.expect("a stable equilibrium has its linearisation");
        // the gradient handed back is the solution's (the reactions), whichever point the
        // tangent is of
        let mut g = vec![[0.0; 3]; x.len()];
        model
            .inner
            .assemble(&x, Want::Gradient, Some(&mut g), None)
            .unwrap();
        let scale = g.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for (a, b) in lin.gradient.iter().flatten().zip(g.iter().flatten()) {
            assert!((a - b).abs() <= 1e-12 * scale, "{a} against {b}");
        }
        runs.push((
            x,
            report,
            model.hessians.load(Relaxed),
            model.gradients.load(Relaxed),
        ));
    }
    let (plain, polished) = (&runs[0], &runs[1]);
    assert!(
        plain.1.iterations >= 3,
        "a problem that needs several steps"
    );
    // the same equilibrium to within what the residual tolerance allows (a tip deflection of
    // centimetres, agreement to a nanometre)
    let size = rest.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let moved = plain
        .0
        .iter()
        .zip(&rest)
        .map(|(a, b)| (a[2] - b[2]).abs())
        .fold(0.0, f64::max);
    assert!(moved > 1e-3 * size, "the sheet bends: {moved} m");
    for (a, b) in plain.0.iter().flatten().zip(polished.0.iter().flatten()) {
        assert!((a - b).abs() <= 1e-9 * size, "{a} against {b}");
    }
    // the same steps; one Hessian assembly fewer (the confirming one), one gradient more
    assert_eq!(polished.1.iterations, plain.1.iterations);
    assert_eq!(polished.2 + 1, plain.2, "Hessian assemblies");
    assert_eq!(
        polished.3,
        plain.3 + 1 + polished.1.polish_misses,
        "gradient assemblies"
    );
}

/// The cantilever solved with chords from each reach: (positions, report, Hessian assemblies).
fn solve_with_chords(chord_from: f64) -> (Vec<Vec3>, kshell::solve::SolveReport, usize) {
    let (model, system, rest) = cantilever();
    let opts = NewtonOptions {
        chord_from,
        rtol: 1e-8,
        max_iterations: 300,
        ..NewtonOptions::default()
    };
    let mut x = rest;
    let (report, lin) = newton_linearized(&model, &system, &mut x, &opts).unwrap();
    assert!(
        report.residual <= 1e-8 || report.precision_limited,
        "{report:?}"
    );
    assert!(report.stable && lin.is_some(), "{report:?}");
    (x, report, model.hessians.load(Relaxed))
}

#[test]
fn chord_steps_reach_the_same_equilibrium_for_fewer_tangents() {
    let (x0, polish_only, tangents0) = solve_with_chords(0.0);
    assert_eq!(polish_only.chord_steps, 0, "{polish_only:?}");
    // a reach of 0.5: every Newton step from a relative residual of 0.5 down is finished by
    // chords where they contract tenfold a step
    let (x1, chorded, tangents1) = solve_with_chords(0.5);
    assert!(chorded.chord_steps > 0, "{chorded:?}");
    assert!(
        chorded.iterations < polish_only.iterations,
        "{} Newton iterations with chords against {} without",
        chorded.iterations,
        polish_only.iterations
    );
    assert!(
        tangents1 < tangents0,
        "{tangents1} tangents against {tangents0}"
    );
    let size = x0.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for (a, b) in x0.iter().flatten().zip(x1.iter().flatten()) {
        assert!((a - b).abs() <= 1e-9 * size, "{a} against {b}");
    }
}

#[test]
fn the_adjoint_on_a_stale_tangent_is_refined_to_the_solutions_own() {
    let (model, system, rest) = cantilever();
    let opts = NewtonOptions {
        chord_from: 0.5,
        rtol: 1e-8,
        max_iterations: 300,
        ..NewtonOptions::default()
    };
    let mut x = rest;
    let (report, lin) = newton_linearized(&model, &system, &mut x, &opts).unwrap();
    let stale = lin.unwrap();
    assert!(report.polished && stale.refines(), "{report:?}");
    let fresh = kshell::solve::Linearization::new(&model, &system, &x).unwrap();
    assert!(fresh.stale == 0.0 && !fresh.refines());
    // a right-hand side with every DOF loaded: gravity on each node
    let b: Vec<Vec3> = (0..x.len())
        .map(|i| [0.1, -0.2 * (i % 3) as f64, 1.0])
        .collect();
    let exact = fresh.solve_reduced(&system, &b);
    let plain = stale.solve_reduced(&system, &b);
    let refined = stale
        .solve_at_solution(&model, &system, &x, &b, 1e-7)
        .unwrap()
        .expect("a tangent near enough to refine on");
    let size = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let error = |v: &[f64]| {
        v.iter()
            .zip(&exact)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
            / size
    };
    let (before, after) = (error(&plain), error(&refined));
    // measured: 1.3e-3 on the stale tangent, 1.6e-7 refined (the differences' √ε)
    assert!(before > 1e-6, "the stale tangent is off: {before:e}");
    assert!(after <= 1e-6, "refined: {after:e} (stale alone {before:e})");
    // H r by differences of the gradient against the fresh tangent's product
    let mut hb = vec![[0.0; 3]; x.len()];
    fresh.hessian.mul(&b, &mut hb);
    let fd = stale.hessian_times(&model, &x, &b).unwrap();
    let scale = hb.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for (a, e) in fd.iter().flatten().zip(hb.iter().flatten()) {
        assert!((a - e).abs() <= 1e-6 * scale, "{a} against {e}");
    }
}

/// The stability certificate of a chorded solve (`Linearization::certifies`): a positive
/// definite tangent at rest certifies a state just off rest, and refuses a flat sheet
/// compressed past buckling (indefinite: a factorisation there fails) and a state so far
/// away that its tangent is unknown to it.
#[test]
fn a_nearby_tangent_certifies_stability_and_refuses_a_saddle() {
    let cotton = load_material(std::path::Path::new("examples/materials/cotton.toml")).unwrap();
    let mat = TriMaterial::equivalent(TriKind::StvkDs, &cotton, 0.005, 100.0).unwrap();
    let inner = TriModel::new(TriGrid::rectangle(0.06, 0.03, 6, 3), mat, 0.0);
    let rest = inner.grid.positions();
    let n = inner.num_nodes();
    // both short ends clamped
    let fixed: Vec<bool> = (0..3 * n)
        .map(|d| rest[d / 3][0] < 1e-9 || rest[d / 3][0] > 0.06 - 1e-9)
        .collect();
    let system = FreeSystem::new(&inner, &fixed).unwrap();
    let at_rest = kshell::solve::Linearization::new(&inner, &system, &rest).unwrap();
    let scaled = |s: f64| -> Vec<Vec3> { rest.iter().map(|p| [s * p[0], p[1], p[2]]).collect() };
    // the state it was factorised at, and one stretched by 1e-6
    assert!(at_rest.certifies(&inner, &system, &rest).unwrap());
    assert!(at_rest
        .certifies(&inner, &system, &scaled(1.0 + 1e-6))
        .unwrap());
    // compressed by 5 %, flat: a saddle (its own tangent does not factorise)
    let compressed = scaled(0.95);
    assert!(
        kshell::solve::Linearization::new(&inner, &system, &compressed).is_err(),
        "the compressed flat sheet is a saddle"
    );
    assert!(!at_rest.certifies(&inner, &system, &compressed).unwrap());
}
