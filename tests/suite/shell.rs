//! The shell engine against finite differences, rigid motions and closed-form strips.

use crate::common::TestLaw;
use kshell::assembly::{BlockMatrix, ShellModel, Want, YarnRule};
use kshell::material::OrthotropicStvk;
use kshell::mesh::{rectangular_grid, shapes, PolyMesh};
use kshell::scene::TensileStrip;
use kshell::subdiv::{BasisOptions, BoundaryRule, FaceKind, LimitBasis};
use kshell::Vec3;
use std::sync::Arc;

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

fn law() -> OrthotropicStvk {
    TestLaw::stvk(2.0e7, 1.2e7, 3.0e6, 1.5e6).stvk_law()
}

fn model_for(mesh: &PolyMesh, rule: BoundaryRule, tau: f64) -> ShellModel {
    let basis = LimitBasis::new(
        mesh,
        BasisOptions {
            boundary: rule,
            gauss_points: 3,
        },
    )
    .unwrap();
    let mut m = ShellModel::new(basis, [0.8, 0.6, 0.1], Arc::new(law()), tau, 0.2).unwrap();
    m.set_gravity([0.0, 0.0, -9.81]);
    // a follower pressure, so that its gradient and Hessian are checked too
    m.set_pressure(-3.0e3);
    m
}

/// Small curved and flat meshes covering regular, boundary and extraordinary faces.
fn cases() -> Vec<(&'static str, PolyMesh)> {
    let mut curved = rectangular_grid(0.04, 0.06, 3, 4);
    for p in &mut curved.positions {
        p[2] = 4.0 * p[0] * p[0] - 3.0 * p[0] * p[1];
    }
    let scale = |mut m: PolyMesh, s: f64| {
        for p in &mut m.positions {
            for c in p.iter_mut() {
                *c *= s;
            }
        }
        m
    };
    vec![
        ("flat grid", rectangular_grid(0.04, 0.06, 3, 4)),
        ("curved grid", curved),
        ("star5 (curved)", scale(shapes::star(5, 2), 0.03)),
        ("L-shape (flat)", scale(shapes::l_shape(2), 0.02)),
        ("cube", scale(shapes::cube(), 0.02)),
    ]
}

fn perturbed(x: &[Vec3], rng: &mut Rng, amp: f64) -> Vec<Vec3> {
    x.iter()
        .map(|p| {
            [
                p[0] + amp * rng.next(),
                p[1] + amp * rng.next(),
                p[2] + amp * rng.next(),
            ]
        })
        .collect()
}

/// Under both yarn rules (the full Gauss rule, and the yarn terms on face centres).
#[test]
fn gradient_and_hessian_match_central_differences() {
    let mut rng = Rng(5);
    let mut kinds = std::collections::HashSet::new();
    let rules = [BoundaryRule::Phantom, BoundaryRule::Ghost];
    let yarns = [YarnRule::Full, YarnRule::Centre];
    for (name, mesh) in cases() {
        for (rule, yarn) in rules.into_iter().flat_map(|r| yarns.map(|y| (r, y))) {
            let tau = 5e-4;
            let mut model = model_for(&mesh, rule, tau);
            model.set_yarn_rule(yarn).unwrap();
            let rule = (rule, yarn);
            kinds.extend(model.basis.face_kinds.iter().copied());
            let x = perturbed(&model.basis.control_points, &mut rng, 2e-3);
            let n = x.len();
            let mut g = vec![[0.0; 3]; n];
            let mut h = BlockMatrix::zeros(model.pattern.clone());
            model
                .assemble(&x, Want::Hessian, Some(&mut g), Some(&mut h))
                .unwrap();
            let gscale = g.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
            let step = 1e-7;
            let mut hcol = vec![[0.0; 3]; n];
            let mut gp = vec![[0.0; 3]; n];
            let mut gm = vec![[0.0; 3]; n];
            for i in 0..n {
                for c in 0..3 {
                    let (mut xp, mut xm) = (x.clone(), x.clone());
                    xp[i][c] += step;
                    xm[i][c] -= step;
                    let fd =
                        (model.energy(&xp).unwrap() - model.energy(&xm).unwrap()) / (2.0 * step);
                    assert!(
                        (fd - g[i][c]).abs() <= 1e-6 * gscale,
                        "{name} {rule:?}: gradient node {i} comp {c}: {fd} vs {}",
                        g[i][c]
                    );
                    // Hessian column by differences of the gradient
                    model
                        .assemble(&xp, Want::Gradient, Some(&mut gp), None)
                        .unwrap();
                    model
                        .assemble(&xm, Want::Gradient, Some(&mut gm), None)
                        .unwrap();
                    let mut e = vec![[0.0; 3]; n];
                    e[i][c] = 1.0;
                    h.mul(&e, &mut hcol);
                    let hscale = hcol.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
                    for j in 0..n {
                        for d in 0..3 {
                            let fd = (gp[j][d] - gm[j][d]) / (2.0 * step);
                            assert!(
                                (fd - hcol[j][d]).abs() <= 1e-6 * hscale,
                                "{name} {rule:?}: Hessian ({j},{d})x({i},{c}): {fd} vs {}",
                                hcol[j][d]
                            );
                        }
                    }
                }
            }
        }
    }
    assert!(kinds.contains(&FaceKind::Extraordinary) && kinds.contains(&FaceKind::Boundary));
}

#[test]
fn rigid_motions_of_a_curved_rest_shape_cost_nothing() {
    for (name, mesh) in cases() {
        let mut model = model_for(&mesh, BoundaryRule::Phantom, 5e-4);
        model.set_gravity([0.0; 3]);
        model.set_pressure(0.0);
        let x0 = model.basis.control_points.clone();
        // an elastic energy scale: the energy of a 1 % stretch
        let stretched: Vec<Vec3> = x0.iter().map(|p| [1.01 * p[0], p[1], p[2]]).collect();
        let scale = model.energy(&stretched).unwrap();
        let (a, b, c) = (0.7f64, -0.4f64, 1.1f64);
        // rotation from Euler angles, then a translation
        let r = nalgebra::Rotation3::from_euler_angles(a, b, c);
        let moved: Vec<Vec3> = x0
            .iter()
            .map(|p| {
                let q = r * nalgebra::Vector3::from(*p) + nalgebra::Vector3::new(0.3, -0.2, 0.05);
                [q[0], q[1], q[2]]
            })
            .collect();
        let mut g = vec![[0.0; 3]; x0.len()];
        let e = model
            .assemble(&moved, Want::Gradient, Some(&mut g), None)
            .unwrap();
        assert!(
            e.abs() <= 1e-10 * scale,
            "{name}: rigid-motion energy {e} vs scale {scale}"
        );
        let mut gs = vec![[0.0; 3]; x0.len()];
        model
            .assemble(&stretched, Want::Gradient, Some(&mut gs), None)
            .unwrap();
        let gscale = gs.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
        let gmax = g.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
        assert!(
            gmax <= 1e-8 * gscale,
            "{name}: rigid-motion gradient {gmax} vs {gscale}"
        );
    }
}

#[test]
fn uniaxial_svk_strip_matches_the_closed_form() {
    // With a12 = 0 there is no Poisson coupling: a strip pulled along the warp (or weft) is in
    // homogeneous uniaxial strain, F = a·τ·W·λ(λ² − 1)/2 with λ = 1 + Δℓ/L, on any mesh.
    let tau = 3e-4;
    let (w, l) = (0.05, 0.075);
    for (angle, a) in [(90.0, 2.0e7), (0.0, 1.2e7)] {
        let m = TestLaw::stvk(2.0e7, 1.2e7, 0.0, 1.0e6)
            .thickness(tau)
            .material();
        for (mesh, rule) in [
            ((2, 3), BoundaryRule::Phantom),
            ((8, 12), BoundaryRule::Phantom),
            ((5, 7), BoundaryRule::Phantom),
            ((2, 3), BoundaryRule::Ghost),
            ((8, 12), BoundaryRule::Ghost),
        ] {
            let mut strip = TensileStrip::new(w, l, angle);
            strip.mesh = mesh;
            strip.boundary = rule;
            let dl: Vec<f64> = (1..=6).map(|i| 0.05 * l * i as f64).collect();
            let curve = strip.run(&m, &dl).unwrap();
            for p in &curve {
                let lam = 1.0 + p.elongation / l;
                let exact = a * tau * w * lam * (lam * lam - 1.0) / 2.0;
                assert!(
                    (p.force / exact - 1.0).abs() < 1e-6,
                    "angle {angle} mesh {mesh:?} {rule:?} λ={lam}: {} vs {exact}",
                    p.force
                );
            }
        }
    }
}

#[test]
fn isotropic_material_gives_the_same_curve_at_every_angle() {
    // isotropy here: a11 = a22 and G12 = a11 − a12
    for a12 in [0.0, 4.0e6] {
        let a11 = 1.5e7;
        let m = TestLaw::stvk(a11, a11, a12, a11 - a12).material();
        let dl = [0.0015, 0.004, 0.0075];
        let reference = TensileStrip::new(0.05, 0.075, 0.0).run(&m, &dl).unwrap();
        for angle in [22.5, 45.0, 90.0] {
            let curve = TensileStrip::new(0.05, 0.075, angle).run(&m, &dl).unwrap();
            for (p, q) in curve.iter().zip(&reference) {
                assert!(
                    (p.force / q.force - 1.0).abs() < 1e-8,
                    "a12 {a12} angle {angle}: {} vs {}",
                    p.force,
                    q.force
                );
            }
        }
    }
}

#[test]
fn parameter_and_thickness_sensitivities_match_differences() {
    // cut-offs tight enough that some Gauss points lie outside the box
    let law = TestLaw::stvk(2.0e7, 1.2e7, 3.0e6, 1.5e6)
        .warp(&[0.6, 0.4], &[1.0, 8.0])
        .weft(&[1.0], &[3.0])
        .shear(&[1.5, -0.5], &[2.0, -2.0])
        .cutoffs((0.0, 0.02), (0.0, 0.03), (-0.02, 0.02))
        .law();
    let mut mesh = rectangular_grid(0.04, 0.06, 3, 4);
    for p in &mut mesh.positions {
        p[2] = 4.0 * p[0] * p[0] - 3.0 * p[0] * p[1];
    }
    let basis = LimitBasis::new(
        &mesh,
        BasisOptions {
            boundary: BoundaryRule::Phantom,
            gauss_points: 3,
        },
    )
    .unwrap();
    let tau = 4e-4;
    let mut rng = Rng(17);
    for yarn in [YarnRule::Full, YarnRule::Centre] {
        let mut model = ShellModel::new(
            basis.clone(),
            [0.8, 0.6, 0.1],
            Arc::new(law.clone()),
            tau,
            0.2,
        )
        .unwrap();
        model.set_yarn_rule(yarn).unwrap();
        let x = perturbed(&model.basis.control_points, &mut rng, 3e-3);
        sensitivities_match_differences(&mut model, &law, &x, &format!("{yarn:?}"));
        // bending of its own: the law's and the thickness's terms (the rigidities' own are
        // checked through the drape angle in tests/sensitivities.rs)
        model.set_bending(Some(kshell::material::BendingRigidity {
            warp: 2e-6,
            weft: 1e-6,
            twist: 3e-7,
        }));
        sensitivities_match_differences(&mut model, &law, &x, &format!("{yarn:?}, own bending"));
    }
}

fn sensitivities_match_differences(
    model: &mut ShellModel,
    law: &kshell::material::Orthotropic,
    x: &[Vec3],
    label: &str,
) {
    let tau = model.thickness;
    let sens = model.sensitivities(x).unwrap();
    let k0 = law.params();
    let n = x.len();
    let mut gp = vec![[0.0; 3]; n];
    let mut gm = vec![[0.0; 3]; n];
    for (j, name) in sens.names.iter().enumerate().take(k0.len() + 1) {
        let is_tau = j == k0.len();
        let base = if is_tau { tau } else { k0[j] };
        let h = 1e-5 * base.abs().max(1e-2);
        let mut eval = |t: f64, g: &mut Vec<[f64; 3]>| -> f64 {
            if is_tau {
                model.set_thickness(tau + t).unwrap();
                model.law = Arc::new(law.clone());
            } else {
                let mut k = k0.clone();
                k[j] += t;
                let mut l = law.clone();
                l.set_params(&k);
                model.law = Arc::new(l);
                model.set_thickness(tau).unwrap();
            }
            model.assemble(x, Want::Gradient, Some(g), None).unwrap()
        };
        let ep = eval(h, &mut gp);
        let em = eval(-h, &mut gm);
        let fd = (ep - em) / (2.0 * h);
        assert!(
            (fd - sens.energy[j]).abs() <= 1e-6 * sens.energy[j].abs().max(1e-12),
            "{label}: ∂E/∂{name}: {fd} vs {}",
            sens.energy[j]
        );
        let scale = sens.gradient[j]
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..n {
            for c in 0..3 {
                let fd = (gp[i][c] - gm[i][c]) / (2.0 * h);
                assert!(
                    (fd - sens.gradient[j][i][c]).abs() <= 1e-6 * scale,
                    "{label}: ∂g/∂{name} node {i} comp {c}: {fd} vs {}",
                    sens.gradient[j][i][c]
                );
            }
        }
    }
    model.set_thickness(tau).unwrap();
}

#[test]
fn edge_moment_gradient_and_hessian_match_differences() {
    let mut mesh = rectangular_grid(0.04, 0.06, 3, 4);
    for p in &mut mesh.positions {
        p[2] = 4.0 * p[0] * p[0] - 3.0 * p[0] * p[1];
    }
    let mut model = model_for(&mesh, BoundaryRule::Ghost, 5e-4);
    model.set_gravity([0.0; 3]);
    model.set_pressure(0.0);
    model.set_edge_moment(&[9, 10, 11], 1.0, 7.0);
    let mut rng = Rng(23);
    let x = perturbed(&model.basis.control_points, &mut rng, 2e-3);
    let n = x.len();
    let mut g = vec![[0.0; 3]; n];
    let mut h = BlockMatrix::zeros(model.pattern.clone());
    model
        .assemble(&x, Want::Hessian, Some(&mut g), Some(&mut h))
        .unwrap();
    // the moment's share alone: remove the elastic part
    let mut ge = vec![[0.0; 3]; n];
    let mut he = BlockMatrix::zeros(model.pattern.clone());
    let mut elastic = model_for(&mesh, BoundaryRule::Ghost, 5e-4);
    elastic.set_gravity([0.0; 3]);
    elastic.set_pressure(0.0);
    elastic
        .assemble(&x, Want::Hessian, Some(&mut ge), Some(&mut he))
        .unwrap();
    let gm: Vec<[f64; 3]> = g
        .iter()
        .zip(&ge)
        .map(|(a, b)| std::array::from_fn(|c| a[c] - b[c]))
        .collect();
    let gscale = gm.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(gscale > 0.0);
    let step = 1e-7;
    let mut gp = vec![[0.0; 3]; n];
    let mut gq = vec![[0.0; 3]; n];
    let mut col = vec![[0.0; 3]; n];
    let mut cole = vec![[0.0; 3]; n];
    // the moment Hessian's largest entry, to scale the comparison of every column
    let mut hmax = 0.0f64;
    for i in 0..n {
        for c in 0..3 {
            let mut e = vec![[0.0; 3]; n];
            e[i][c] = 1.0;
            h.mul(&e, &mut col);
            he.mul(&e, &mut cole);
            for j in 0..n {
                for d in 0..3 {
                    hmax = hmax.max((col[j][d] - cole[j][d]).abs());
                }
            }
        }
    }
    assert!(hmax > 0.0);
    for i in 0..n {
        for c in 0..3 {
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[i][c] += step;
            xm[i][c] -= step;
            let fd = (model.energy(&xp).unwrap()
                - elastic.energy(&xp).unwrap()
                - model.energy(&xm).unwrap()
                + elastic.energy(&xm).unwrap())
                / (2.0 * step);
            assert!(
                (fd - gm[i][c]).abs() <= 1e-6 * gscale,
                "gradient ({i},{c}): {fd} vs {}",
                gm[i][c]
            );
            model
                .assemble(&xp, Want::Gradient, Some(&mut gp), None)
                .unwrap();
            model
                .assemble(&xm, Want::Gradient, Some(&mut gq), None)
                .unwrap();
            let mut e = vec![[0.0; 3]; n];
            e[i][c] = 1.0;
            h.mul(&e, &mut col);
            he.mul(&e, &mut cole);
            let mut ep = vec![[0.0; 3]; n];
            let mut em = vec![[0.0; 3]; n];
            elastic
                .assemble(&xp, Want::Gradient, Some(&mut ep), None)
                .unwrap();
            elastic
                .assemble(&xm, Want::Gradient, Some(&mut em), None)
                .unwrap();
            for j in 0..n {
                for d in 0..3 {
                    let fd = ((gp[j][d] - ep[j][d]) - (gq[j][d] - em[j][d])) / (2.0 * step);
                    let exact = col[j][d] - cole[j][d];
                    assert!(
                        (fd - exact).abs() <= 1e-6 * hmax,
                        "Hessian ({j},{d})x({i},{c}): {fd} vs {exact}"
                    );
                }
            }
        }
    }
}

/// Nearly inextensible yarns do not lock on the centre rule. A 150 × 450 mm bias-extension
/// sample at 45° (a11 = a22 = 1e10 Pa, a12 = 0, G12 = 3e4 Pa, τ = 0.3 mm) pulled 20 mm on
/// 4 × 12 and 8 × 24 uniform cages. Reference: the pin-jointed net of the bias-extension test
/// (Harrison et al. 2004 kinematics: inextensible yarns, no bending; shear angle
/// γ = π/2 − 2 arccos((D + d)/(√2 D)), D = L − W, in the centre region, γ/2 in the four
/// half-sheared triangles; energy τ G12 Σ area (½ sin γ)², force its derivative in d):
/// 0.1738 N (`paper_repro/convergence/stiff_bias/reference.txt`). Measured: the centre rule
/// (what `auto` picks here) 0.1719 and 0.1701 N, the full rule 12.70 and 2.036 N.
#[test]
fn stiff_yarns_on_face_centres_do_not_lock_in_bias_extension() {
    let net = {
        let (w, l, tau, g, d) = (0.15f64, 0.45f64, 3e-4, 3e4, 0.02);
        let big_d = l - w;
        let gamma = |d: f64| {
            std::f64::consts::FRAC_PI_2 - 2.0 * ((big_d + d) / (2f64.sqrt() * big_d)).acos()
        };
        let energy = |d: f64| {
            let g1 = gamma(d);
            tau * g
                * (w * (l - 1.5 * w) * (0.5 * g1.sin()).powi(2)
                    + w * w * (0.5 * (0.5 * g1).sin()).powi(2))
        };
        (energy(d + 1e-6) - energy(d - 1e-6)) / 2e-6
    };
    assert!((net - 0.1738).abs() < 5e-5, "net {net}");
    let m = TestLaw::stvk(1.0e10, 1.0e10, 0.0, 3.0e4)
        .density(0.3)
        .thickness(3e-4)
        .material();
    for mesh in [(4, 12), (8, 24)] {
        let force = |rule: YarnRule| {
            let mut strip = TensileStrip::new(0.15, 0.45, 45.0);
            strip.mesh = mesh;
            strip.yarn_rule = rule;
            strip.run(&m, &[0.02]).unwrap()[0].force
        };
        let (auto, full) = (force(YarnRule::Auto), force(YarnRule::Full));
        assert!(
            (auto / net - 1.0).abs() < 0.03,
            "{mesh:?}: auto (centre) {auto} N against the net's {net} N"
        );
        assert!(full > 5.0 * net, "{mesh:?}: the full rule {full} N");
    }
}
