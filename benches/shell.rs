//! Shell engine speed: Gauss points assembled per second (energy + gradient + Hessian) and a
//! full Newton solve of a 32 × 48 bias strip at 10 % strain, with the split of its time
//! between assembly and factorisation.
//!
//! Run: `cargo bench --bench shell` (medians over repeated runs).

use kshell::assembly::{BlockMatrix, ShellModel, Want};
use kshell::material::{FabricMaterial, OrthotropicStvk};
use kshell::mesh::rectangular_grid;
use kshell::scene::{warp_direction, TensileStrip};
use kshell::subdiv::{BasisOptions, LimitBasis};
use std::hint::black_box;
use std::sync::Arc;
use std::time::Instant;

fn median(mut t: Vec<f64>) -> f64 {
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn main() {
    let law = OrthotropicStvk {
        a11: 2.0e8,
        a22: 1.2e8,
        a12: 2.0e7,
        g12: 4.0e6,
    };
    let material = FabricMaterial {
        name: "bench".into(),
        areal_density: 0.1036,
        thickness: 1.8e-4,
        law: law.into(),
        bending: None,
    };
    let mesh = rectangular_grid(0.05, 0.075, 32, 48);
    let basis = LimitBasis::new(&mesh, BasisOptions::default()).unwrap();
    let model =
        ShellModel::new(basis, warp_direction(45.0), Arc::new(law), 1.8e-4, 0.1036).unwrap();
    let n = model.num_nodes();
    let points = model.basis.num_points();
    // a smoothly deformed state
    let x: Vec<[f64; 3]> = model
        .basis
        .control_points
        .iter()
        .map(|p| {
            [
                p[0] * (1.0 - 0.02 * p[1] / 0.075),
                p[1] * 1.1,
                1e-3 * (p[0] * 40.0).sin(),
            ]
        })
        .collect();
    let mut g = vec![[0.0; 3]; n];
    let mut h = BlockMatrix::zeros(model.pattern.clone());
    for (what, want) in [
        ("energy", Want::Energy),
        ("energy+gradient", Want::Gradient),
        ("energy+gradient+Hessian", Want::Hessian),
    ] {
        let runs = 9;
        let t: Vec<f64> = (0..runs)
            .map(|_| {
                let s = Instant::now();
                let gr = if want == Want::Energy {
                    None
                } else {
                    Some(&mut g[..])
                };
                let hs = if want == Want::Hessian {
                    Some(&mut h)
                } else {
                    None
                };
                black_box(model.assemble(black_box(&x), want, gr, hs).unwrap());
                s.elapsed().as_secs_f64()
            })
            .collect();
        let m = median(t);
        println!(
            "assembly 32x48 ({points} Gauss points), {what:<24} {:>8.2} ms  {:>10.0} points/s",
            m * 1e3,
            points as f64 / m
        );
    }
    // full Newton solve: 45° strip, 10 % strain in one step from rest
    let mut strip = TensileStrip::new(0.05, 0.075, 45.0);
    strip.mesh = (32, 48);
    let mut walls = Vec::new();
    let mut last = None;
    for _ in 0..5 {
        let s = Instant::now();
        let r = strip.run(&material, &[0.0075]).unwrap();
        walls.push(s.elapsed().as_secs_f64());
        last = Some(r[0].clone());
    }
    let p = last.unwrap();
    let r = &p.report;
    println!(
        "Newton solve, 32x48 bias strip to 10 % strain: {:.0} ms wall (median of 5, set-up included); \
         last run: {} iterations, {} factorisations, solve {:.0} ms = assembly {:.0} % + factorisation/solve {:.0} % + other; force {:.4} N",
        median(walls) * 1e3,
        r.iterations,
        r.factorizations,
        r.seconds * 1e3,
        100.0 * r.assembly_seconds / r.seconds,
        100.0 * r.factor_seconds / r.seconds,
        p.force
    );
}
