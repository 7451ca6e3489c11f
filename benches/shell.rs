//! Shell engine speed: Gauss points assembled per second (energy + gradient + Hessian), the
//! flops of the assembly's stencil loops against this machine's measured fused multiply-add
//! peak, the cost of the paper's law (η of degree 3) over the linear one, and a full Newton
//! solve of a 32 × 48 bias strip at 10 % strain, with the split of its time between assembly
//! and factorisation.
//!
//! Run: `cargo bench --bench shell` (medians over repeated runs).

use kshell::assembly::{BlockMatrix, ShellModel, Want};
use kshell::material::{Cutoffs, Eta, FabricMaterial, Orthotropic, OrthotropicStvk};
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
    let linear = hessian_seconds(&model, &x);
    flop_rate(&model, linear);
    law_cost(&mesh, &x, linear);
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

/// The median time of one Hessian assembly of `model` at `x`.
fn hessian_seconds(model: &ShellModel, x: &[[f64; 3]]) -> f64 {
    let mut g = vec![[0.0; 3]; model.num_nodes()];
    let mut h = BlockMatrix::zeros(model.pattern.clone());
    let t: Vec<f64> = (0..9)
        .map(|_| {
            let s = Instant::now();
            black_box(model.assemble(black_box(x), Want::Hessian, Some(&mut g), Some(&mut h)))
                .unwrap();
            s.elapsed().as_secs_f64()
        })
        .collect();
    median(t)
}

/// Flops of the assembly's stencil loops at one Gauss point with a stencil of `m` control
/// points (`face_loop.rs`): the surface derivatives (5 × 3 multiply-adds a point), the
/// gradient scatter (the same), R_a = Σ_k W_ak H_k· (5 × 45 a point) and the packed face block
/// H_ab = Σ_l R_al W_bl (5 × 9 multiply-adds and 9 adds a pair a ≤ b). The kinematics and the
/// law at the point are not counted.
fn stencil_flops(m: usize) -> usize {
    let pairs = m * (m + 1) / 2;
    2 * 15 * m + 2 * 15 * m + 2 * 225 * m + pairs * (2 * 45 + 9)
}

/// The counted flops of one Hessian assembly of `model` (`seconds`) against the measured
/// fused multiply-add peak of this machine's cores.
fn flop_rate(model: &ShellModel, seconds: f64) {
    let points = model.basis.num_points();
    let flops: usize = (0..points)
        .map(|q| stencil_flops(model.basis.stencil(q).0.len()))
        .sum();
    let cores = rayon::current_num_threads();
    let rate = flops as f64 / seconds;
    match fma_peak() {
        Some(peak) => println!(
            "Hessian assembly: {:.0} flops a Gauss point in the stencil loops (kinematics and law not counted), \
             {:.2} GFLOP/s on {cores} threads = {:.1} % of {cores} × {:.1} GFLOP/s (one core's AVX2 FMA peak, measured)",
            flops as f64 / points as f64,
            rate * 1e-9,
            100.0 * rate / (cores as f64 * peak),
            peak * 1e-9
        ),
        None => println!(
            "Hessian assembly: {:.0} flops a Gauss point in the stencil loops, {:.2} GFLOP/s on {cores} threads (no AVX2 + FMA to measure a peak)",
            flops as f64 / points as f64,
            rate * 1e-9
        ),
    }
}

/// The extra time a Gauss point takes under the paper's law with η of degree 3 in every
/// direction (two transcendental terms each, expm1 and ln1p) over the linear law, at the same
/// state and mesh.
fn law_cost(mesh: &kshell::mesh::PolyMesh, x: &[[f64; 3]], linear: f64) {
    let eta = |a: f64, b: f64| Eta {
        mu: vec![0.5, 0.3, 0.2],
        alpha: vec![1.0, a, b],
    };
    let law = Orthotropic {
        a11: 2.0e8,
        a22: 1.2e8,
        a12: 2.0e7,
        g12: 4.0e6,
        warp: eta(8.0, 120.0),
        weft: eta(5.0, 60.0),
        shear: eta(3.0, 30.0),
        cutoffs: Cutoffs::none(),
        coupling: None,
    };
    let basis = LimitBasis::new(mesh, BasisOptions::default()).unwrap();
    let model =
        ShellModel::new(basis, warp_direction(45.0), Arc::new(law), 1.8e-4, 0.1036).unwrap();
    assert_eq!(x.len(), model.num_nodes());
    let t = hessian_seconds(&model, x);
    let points = model.basis.num_points() as f64;
    println!(
        "Hessian assembly under the paper's law (η of degree 3 each way): {:.2} ms against {:.2} ms linear, \
         {:.0} ns more a Gauss point ({:.0} % of the linear law's time)",
        t * 1e3,
        linear * 1e3,
        (t - linear) / points * 1e9,
        100.0 * (t - linear) / linear
    );
}

/// One core's peak of 4-wide fused multiply-adds (flops a second): twelve independent chains,
/// enough to cover the instruction's latency on two pipes.
fn fma_peak() -> Option<f64> {
    #[cfg(target_arch = "x86_64")]
    {
        if !(std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma"))
        {
            return None;
        }
        #[target_feature(enable = "avx2,fma")]
        unsafe fn chains(n: usize) -> f64 {
            use std::arch::x86_64::*;
            let a = _mm256_set1_pd(0.999_999);
            let b = _mm256_set1_pd(1e-7);
            let mut acc = [_mm256_set1_pd(1.0); 12];
            for _ in 0..n {
                for v in acc.iter_mut() {
                    *v = _mm256_fmadd_pd(*v, a, b);
                }
            }
            let mut sum = 0.0;
            for v in acc {
                let mut t = [0.0; 4];
                _mm256_storeu_pd(t.as_mut_ptr(), v);
                sum += t.iter().sum::<f64>();
            }
            sum
        }
        let n = 20_000_000;
        let t: Vec<f64> = (0..5)
            .map(|_| {
                let s = Instant::now();
                // SAFETY: the CPU has the features `chains` is compiled for (checked above)
                black_box(unsafe { chains(black_box(n)) });
                s.elapsed().as_secs_f64()
            })
            .collect();
        Some(12.0 * 4.0 * 2.0 * n as f64 / median(t))
    }
    #[cfg(not(target_arch = "x86_64"))]
    None
}
