//! The solver's strategies are different roads to an equilibrium. Where the equilibrium is
//! unique (a bias strip of a stiffening law, no wrinkles) every strategy gives the same clamp
//! forces; where the strip wrinkles (thin and shear-soft: the Hessian is indefinite from the
//! first step) each strategy must still end at a stable state, but not necessarily the same
//! one: wrinkle patterns are not unique.

use kshell::material::{FabricMaterial, OrthotropicStvk};
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
    let m = FabricMaterial {
        name: "thin".into(),
        areal_density: 0.1,
        thickness: 5.0e-5,
        law: OrthotropicStvk {
            a11: 1.0e9,
            a22: 1.0e8,
            a12: 1.0e7,
            g12: 1.0e5,
        }
        .into(),
        bending: None,
    };
    for (name, curve) in curves(&m, &[0.01, 0.03]) {
        let forces: Vec<f64> = curve.iter().map(|p| p.force).collect();
        eprintln!("{name}: {forces:?} N");
        assert!(forces.iter().all(|f| *f > 0.0 && f.is_finite()));
    }
}
