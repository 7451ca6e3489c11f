//! The triangle models (Miguel et al. 2012, Larionov et al. 2022) against what is known of them
//! outside the code: finite differences of every element's energy, a spring chain in closed
//! form, the constant-strain patch test, and discrete-shell bending of a cylinder.

use kshell::assembly::{BlockMatrix, Want};
use kshell::model::ClothModel;
use kshell::solve::{newton, FreeSystem, NewtonOptions};
use kshell::tri::{Stiffness, TriGrid, TriKind, TriMaterial, TriModel};
use kshell::Vec3;

/// A material with a nonlinear spline on every component (values in N/m and N·m).
fn nonlinear(kind: TriKind) -> TriMaterial {
    let s = |k: f64| Stiffness::spline(-0.02, 0.08, vec![k, 1.6 * k, 1.1 * k, 2.5 * k]).unwrap();
    let b = |k: f64| Stiffness::spline(-40.0, 40.0, vec![k, 0.7 * k, 1.3 * k]).unwrap();
    let bend = if kind == TriKind::Springs { 50.0 } else { 2e-5 };
    TriMaterial {
        kind,
        curves: [
            s(3000.0),
            s(2000.0),
            s(150.0),
            b(bend),
            b(0.6 * bend),
            b(0.4 * bend),
        ],
        coupling: if kind == TriKind::Xpbd { 400.0 } else { 0.0 },
        areal_density: 0.1,
    }
}

/// A small grid with every node moved off the plane and stretched a few per cent.
fn perturbed(g: &TriGrid) -> Vec<Vec3> {
    g.positions()
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let t = i as f64;
            [
                p[0] * 1.03 + 2e-4 * (1.7 * t).sin(),
                p[1] * 0.98 + 2e-4 * (2.3 * t).cos(),
                1e-3 * (0.9 * t).sin() + 5e-3 * p[0],
            ]
        })
        .collect()
}

/// Gradient and Hessian of every model against central differences of the energy and the
/// gradient, with a 30° warp, nonlinear splines on all components and gravity.
#[test]
fn gradients_and_hessians_match_finite_differences() {
    for (_, kind) in TriKind::ALL {
        let grid = TriGrid::rectangle(0.03, 0.02, 3, 2);
        let mut m = TriModel::new(grid, nonlinear(kind), 30f64.to_radians());
        m.set_gravity([0.0, 0.0, -9.81]);
        let x = perturbed(&m.grid);
        let n = m.num_nodes();
        let mut g = vec![[0.0; 3]; n];
        let mut h = BlockMatrix::zeros(m.pattern().clone());
        m.assemble(&x, Want::Hessian, Some(&mut g), Some(&mut h))
            .unwrap();
        let eps = 1e-7;
        let gscale = g.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
        let mut dense_h = vec![vec![0.0; 3 * n]; 3 * n];
        for i in 0..n {
            for k in h.pattern.row_ptr[i]..h.pattern.row_ptr[i + 1] {
                let j = h.pattern.col[k] as usize;
                for r in 0..3 {
                    for c in 0..3 {
                        dense_h[3 * i + r][3 * j + c] = h.blocks[k][(r, c)];
                        dense_h[3 * j + c][3 * i + r] = h.blocks[k][(r, c)];
                    }
                }
            }
        }
        let hscale = dense_h
            .iter()
            .flatten()
            .map(|v| v.abs())
            .fold(0.0, f64::max);
        for d in 0..3 * n {
            let mut xp = x.clone();
            let mut xm = x.clone();
            xp[d / 3][d % 3] += eps;
            xm[d / 3][d % 3] -= eps;
            let (mut gp, mut gm) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
            let ep = m
                .assemble(&xp, Want::Gradient, Some(&mut gp), None)
                .unwrap();
            let em = m
                .assemble(&xm, Want::Gradient, Some(&mut gm), None)
                .unwrap();
            let fd = (ep - em) / (2.0 * eps);
            assert!(
                (fd - g[d / 3][d % 3]).abs() < 1e-6 * gscale,
                "{kind:?} gradient {d}: {} vs {fd}",
                g[d / 3][d % 3]
            );
            for e in 0..3 * n {
                let fdh = (gp[e / 3][e % 3] - gm[e / 3][e % 3]) / (2.0 * eps);
                assert!(
                    (fdh - dense_h[e][d]).abs() < 1e-5 * hscale,
                    "{kind:?} Hessian ({e}, {d}): {} vs {fdh}",
                    dense_h[e][d]
                );
            }
        }
    }
}

/// Solves with the DOFs `fixed` held at `x`'s values.
fn solve(m: &TriModel, fixed: &[bool], x: &mut [Vec3]) {
    let system = FreeSystem::new(m, fixed).unwrap();
    let report = newton(m, &system, x, &NewtonOptions::default()).unwrap();
    assert!(report.residual < 1e-8, "{report:?}");
}

/// The Springs model with only its stretch springs is a set of spring chains: a strip of
/// width W held at both ends and pulled to strain ε has every warp spring at strain ε, so the
/// end force is k(ε) ε W exactly (σ = k(ε) ε per unit width, Miguel et al. 2012 Eq. 2), here
/// for a nonlinear spline k, with the interior nodes found by Newton from an uneven start.
#[test]
fn a_spring_chain_carries_its_closed_form_force() {
    let k = Stiffness::spline(0.0, 0.1, vec![1000.0, 3000.0, 2000.0]).unwrap();
    let zero = Stiffness::constant(0.0);
    let mat = TriMaterial {
        kind: TriKind::Springs,
        curves: [
            k.clone(),
            k.clone(),
            zero.clone(),
            zero.clone(),
            zero.clone(),
            zero,
        ],
        coupling: 0.0,
        areal_density: 0.0,
    };
    let (len, width) = (0.1, 0.02);
    let m = TriModel::new(TriGrid::rectangle(len, width, 8, 3), mat, 0.0);
    for strain in [0.013, 0.047, 0.12] {
        let mut x = m.grid.positions();
        let mut fixed = vec![false; 3 * x.len()];
        for (i, p) in x.iter_mut().enumerate() {
            // a 1-D chain: only x moves
            fixed[3 * i + 1] = true;
            fixed[3 * i + 2] = true;
            if p[0] == 0.0 || p[0] == len {
                fixed[3 * i] = true;
            }
            p[0] *=
                1.0 + strain * (1.0 + 0.3 * (p[0] / len * 3.0).sin() * (p[0] != len) as u8 as f64);
            if p[0] > len {
                p[0] = len * (1.0 + strain);
            }
        }
        solve(&m, &fixed, &mut x);
        let mut g = vec![[0.0; 3]; x.len()];
        m.assemble(&x, Want::Gradient, Some(&mut g), None).unwrap();
        let force: f64 = (0..x.len())
            .filter(|&i| m.grid.rest[i][0] == len)
            .map(|i| g[i][0])
            .sum();
        let exact = k.at(strain).0 * strain * width;
        assert!(
            (force - exact).abs() < 1e-9 * exact,
            "ε {strain}: {force} vs {exact}"
        );
    }
}

/// Constant-strain patch test (Irons): with the boundary nodes on an affine map x = F X, the
/// free interior nodes of any triangle membrane must return to F X and the energy be the area
/// times the strain energy density of F's Green (or Baraff–Witkin) strain.
#[test]
fn membranes_pass_the_constant_strain_patch_test() {
    let f = [[1.04, 0.03], [-0.02, 0.97]];
    for kind in [TriKind::SoftConstraints, TriKind::StvkDs, TriKind::Xpbd] {
        let mat = nonlinear(kind);
        let m = TriModel::new(TriGrid::rectangle(0.04, 0.03, 4, 3), mat.clone(), 0.0);
        let target: Vec<Vec3> = m
            .grid
            .rest
            .iter()
            .map(|p| {
                [
                    f[0][0] * p[0] + f[0][1] * p[1],
                    f[1][0] * p[0] + f[1][1] * p[1],
                    0.0,
                ]
            })
            .collect();
        let mut x = target.clone();
        let mut fixed = vec![false; 3 * x.len()];
        for (i, p) in m.grid.rest.iter().enumerate() {
            fixed[3 * i + 2] = true;
            let edge = p[0] == 0.0 || p[1] == 0.0 || p[0] == 0.04 || p[1] == 0.03;
            if edge {
                fixed[3 * i] = true;
                fixed[3 * i + 1] = true;
            } else {
                x[i][0] += 1e-3;
                x[i][1] -= 5e-4;
            }
        }
        solve(&m, &fixed, &mut x);
        for (a, b) in x.iter().zip(&target) {
            assert!(
                (a[0] - b[0]).abs() < 1e-10 && (a[1] - b[1]).abs() < 1e-10,
                "{kind:?}"
            );
        }
        // w_u, w_v are F's columns
        let (wu, wv) = ([f[0][0], f[1][0]], [f[0][1], f[1][1]]);
        let uu = wu[0] * wu[0] + wu[1] * wu[1];
        let vv = wv[0] * wv[0] + wv[1] * wv[1];
        let e = match kind {
            TriKind::SoftConstraints => [uu.sqrt() - 1.0, vv.sqrt() - 1.0],
            _ => [0.5 * (uu - 1.0), 0.5 * (vv - 1.0)],
        };
        let es = wu[0] * wv[0] + wu[1] * wv[1];
        let w = mat.curves[0].density(e[0]).0
            + mat.curves[1].density(e[1]).0
            + mat.curves[2].density(es).0
            + mat.coupling * e[0] * e[1];
        let energy = m.energy(&x).unwrap();
        assert!(
            (energy - 0.04 * 0.03 * w).abs() < 1e-12 * energy.abs(),
            "{kind:?}"
        );
    }
}

/// Discrete-shell bending of a cylinder: the grid wrapped onto a cylinder of curvature κ along
/// x has every cell planar, so the only bent hinges are the (nx − 1) · ny edges across x, each
/// at θ = κ a exactly. With the hinge metric κ = θ/h, h = (A₁ + A₂)/l = a, the energy is
/// ½ D κ² L W (nx − 1)/nx: the continuum plate energy ½ D κ² per unit area (Timoshenko &
/// Woinowsky-Krieger, pure bending of a plate into a cylinder) less the one boundary column,
/// which has no hinge. D is the warp rigidity when the warp runs along x and the weft rigidity
/// when it runs along y, and the same holds for the cylinder along y.
#[test]
fn discrete_shell_bending_of_a_cylinder_matches_the_plate() {
    let (len, width, kappa) = (0.1, 0.06, 25.0);
    let (dw, df) = (3e-5, 1e-5);
    let k = Stiffness::constant;
    for (nx, ny) in [(4, 3), (10, 6), (20, 12)] {
        for (warp_deg, along_x) in [(0.0, true), (90.0, true), (0.0, false)] {
            let mat = TriMaterial {
                kind: TriKind::StvkDs,
                // no membrane: the chords of the arc are shorter than the cells
                curves: [k(0.0), k(0.0), k(0.0), k(dw), k(df), k(7e-6)],
                coupling: 0.0,
                areal_density: 0.0,
            };
            let m = TriModel::new(
                TriGrid::rectangle(len, width, nx, ny),
                mat,
                f64::to_radians(warp_deg),
            );
            let x: Vec<Vec3> = m
                .grid
                .rest
                .iter()
                .map(|p| {
                    let (s, t) = if along_x { (p[0], p[1]) } else { (p[1], p[0]) };
                    let (a, b, c) = (
                        (kappa * s).sin() / kappa,
                        t,
                        (1.0 - (kappa * s).cos()) / kappa,
                    );
                    if along_x {
                        [a, b, c]
                    } else {
                        [b, a, c]
                    }
                })
                .collect();
            let d = if along_x == (warp_deg == 0.0) { dw } else { df };
            let cells = if along_x {
                (nx - 1) * ny
            } else {
                (ny - 1) * nx
            } as f64;
            let expected = 0.5 * d * kappa * kappa * len * width * cells / (nx * ny) as f64;
            let e = m.energy(&x).unwrap();
            assert!(
                (e - expected).abs() < 1e-9 * expected,
                "{nx}×{ny} warp {warp_deg}° along x {along_x}: {e} vs {expected}"
            );
        }
    }
}

/// The XPBD hinge gradient (Bridson et al. 2003's closed form) against the exact derivative of
/// the signed dihedral angle that the Newton energy uses.
#[test]
fn the_xpbd_hinge_gradient_is_the_dihedral_angles() {
    use kshell::tri::jet::{cross, dot, point, sub};
    use kshell::tri::xpbd::dihedral_gradient;
    use nalgebra::Vector3;
    let x: [Vec3; 4] = [
        [0.0, 0.0, 0.0],
        [0.01, 0.001, 0.0005],
        [0.004, 0.008, 0.002],
        [0.006, -0.007, 0.003],
    ];
    let p: Vec<_> = (0..4).map(|k| point::<12>(k, x[k])).collect();
    let e = sub(&p[1], &p[0]);
    let n1 = cross(&e, &sub(&p[2], &p[0]));
    let n2 = cross(&sub(&p[3], &p[0]), &e);
    let theta = (dot(&cross(&n1, &n2), &e) * dot(&e, &e).sqrt().recip()).atan2(&dot(&n1, &n2));
    assert!(theta.v.abs() > 0.1, "a bent hinge: θ = {}", theta.v);
    let g = dihedral_gradient(x.map(|q| Vector3::new(q[0], q[1], q[2])));
    for a in 0..4 {
        for c in 0..3 {
            assert!(
                (g[a][c] - theta.g[3 * a + c]).abs()
                    < 1e-9 * theta.g.iter().map(|v| v.abs()).fold(0.0, f64::max),
                "node {a} component {c}: {} vs {}",
                g[a][c],
                theta.g[3 * a + c]
            );
        }
    }
}

/// XPBD run quasi-statically (Larionov et al. 2022 use it as a statics solver) descends to the
/// equilibrium Newton finds on the same energy, with two errors of its own, both measured here
/// on a small sagging cantilever: Gauss–Seidel's, which falls with the sweeps per step and
/// grows with the stiffness ratio (membrane 2000 N/m against bending 4e-5 N·m), and the bias
/// of the gradient XPBD drops from its Newton step (Macklin et al. 2016 §4: ∇C is taken as
/// constant within a step), which is second order in the step Δt. Every XPBD state's energy is
/// above Newton's minimum and approaches it.
#[test]
fn xpbd_converges_to_newtons_equilibrium() {
    use kshell::tri::xpbd::{xpbd, XpbdOptions};
    let k = Stiffness::constant;
    let material = |membrane: f64| TriMaterial {
        kind: TriKind::Xpbd,
        curves: [
            k(membrane),
            k(0.75 * membrane),
            k(0.15 * membrane),
            k(4e-5),
            k(3e-5),
            k(3.5e-5),
        ],
        coupling: 0.15 * membrane,
        areal_density: 0.1,
    };
    let run = |membrane: f64, runs: &[(usize, usize, f64)]| -> Vec<f64> {
        let mut m = TriModel::new(
            TriGrid::rectangle(0.05, 0.02, 5, 2),
            material(membrane),
            0.3,
        );
        m.set_gravity([0.0, 0.0, -9.81]);
        let mut fixed = vec![false; 3 * m.num_nodes()];
        for i in 0..m.num_nodes() {
            if m.grid.rest[i][0] < 0.011 {
                fixed[3 * i..3 * i + 3].iter_mut().for_each(|f| *f = true);
            }
        }
        let mut newton_x = m.grid.positions();
        solve(&m, &fixed, &mut newton_x);
        let minimum = m.energy(&newton_x).unwrap();
        let sag = newton_x.iter().map(|p| -p[2]).fold(0.0, f64::max);
        assert!(sag > 1e-2, "it sags: {sag}");
        runs.iter()
            .map(|&(steps, sweeps, dt)| {
                let mut x = m.grid.positions();
                xpbd(&m, &fixed, &mut x, &XpbdOptions { steps, sweeps, dt }).unwrap();
                assert!(m.energy(&x).unwrap() > minimum, "Newton's is the minimum");
                x.iter()
                    .zip(&newton_x)
                    .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max))
                    .fold(0.0, f64::max)
                    / sag
            })
            .collect()
    };
    // Gauss–Seidel: stiff membrane, more sweeps per step (measured 3.4e-2, 2.5e-2, 3.6e-3)
    let sweeps = run(
        2000.0,
        &[(100, 100, 0.01), (100, 1000, 0.01), (100, 10000, 0.01)],
    );
    assert!(
        sweeps[0] > sweeps[1] && sweeps[1] > sweeps[2] && sweeps[2] < 5e-3,
        "{sweeps:?}"
    );
    // the step bias: soft membrane, sweeps converged, Δt halved with 4× the steps (measured
    // 3.2e-3, 6.9e-4): the halving cuts the error more than threefold
    let steps = run(20.0, &[(100, 1000, 0.01), (400, 1000, 0.005)]);
    assert!(steps[1] < steps[0] / 3.0 && steps[1] < 1e-3, "{steps:?}");
}
