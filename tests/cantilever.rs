//! Cantilevers against exact elastica solutions: the heavy (self-weight) cantilever of the ASTM
//! D1388 bend test and Sze, Liu & Lo's tip-force cantilever.

use kshell::material::{FabricMaterial, OrthotropicStvk};
use kshell::scene::CantileverBend;
use kshell::subdiv::BoundaryRule;

/// Heavy inextensible elastica, overhang = 2 × bending length c = (D/(ρg))^(1/3): chord angle
/// 41.4873° (RK4 shooting on θ'' = −λ(1−σ) cos θ with λ = 8; recorded in the project's shell
/// benchmark notes, which also show Peirce's closed form to be about 2 % off there).
const HEAVY_ELASTICA_ANGLE: f64 = 41.4873;

fn heavy_case(mesh: (usize, usize), rule: BoundaryRule) -> f64 {
    // a12 = 0 so the strip bends like a beam: D = a11 τ³ / 12 per unit width
    let (a11, tau, rho) = (1.0e8, 2.0e-4, 0.1);
    let m = FabricMaterial {
        name: "elastica".into(),
        areal_density: rho,
        thickness: tau,
        law: OrthotropicStvk {
            a11,
            a22: a11,
            a12: 0.0,
            g12: 1.0e6,
        }
        .into(),
    };
    let d = a11 * tau.powi(3) / 12.0;
    let c = (d / (rho * kshell::assembly::STANDARD_GRAVITY)).cbrt();
    let mut bend = CantileverBend::new(0.025, 2.0 * c, 90.0);
    bend.mesh = mesh;
    bend.boundary = rule;
    bend.run(&m).unwrap().drape_angle_deg
}

#[test]
fn heavy_cantilever_converges_to_the_elastica_angle() {
    let angles: Vec<f64> = [(4, 8), (4, 16), (4, 32)]
        .iter()
        .map(|&m| heavy_case(m, BoundaryRule::Ghost))
        .collect();
    let errors: Vec<f64> = angles
        .iter()
        .map(|a| (a - HEAVY_ELASTICA_ANGLE).abs())
        .collect();
    // measured: 1.29°, 0.045°, 0.0007° (orders 4.9 and 6.1, the last limited by the
    // reference's four decimals)
    assert!(errors[2] < 0.005, "finest mesh: {angles:?}");
    for w in errors.windows(2) {
        let order = (w[0] / w[1]).log2();
        assert!(order > 3.0, "observed order {order:.2} ({angles:?})");
    }
}

#[test]
fn phantom_clamp_pins_the_edge_curvature_and_converges_slowly() {
    // The phantom rule forces zero curvature across a clamped edge, where the moment is
    // largest: at 4 × 32 it is still about 1.4° off (measured), against 0.0007° with ghosts.
    let phantom = heavy_case((4, 32), BoundaryRule::Phantom);
    let err = (phantom - HEAVY_ELASTICA_ANGLE).abs();
    assert!(err > 0.5 && err < 3.0, "phantom 4x32: {phantom}");
}

#[test]
fn tip_force_cantilever_matches_the_exact_elastica() {
    // Sze, Liu & Lo (2004) test 3.1: E = 1.2e6, ν = 0, L = 10, b = 1, h = 0.1, end shear P = 4
    // (P L² / EI = 4). Exact inextensible elastica (RK4 shooting, matching the
    // Mattiasson / Bisshopp–Drucker tables): −u_tip = 3.2894, w_tip = 6.6996.
    let m = FabricMaterial {
        name: "sze".into(),
        areal_density: 1.0,
        thickness: 0.1,
        law: OrthotropicStvk::isotropic(1.2e6, 0.0).into(),
    };
    let mut bend = CantileverBend::new(1.0, 10.0, 90.0);
    bend.mesh = (2, 32);
    bend.gravity = false;
    bend.tip_force = [0.0, 0.0, 4.0];
    let r = bend.run(&m).unwrap();
    let (u, w) = (10.0 - r.tip[1], r.tip[2]);
    assert!((u / 3.2894 - 1.0).abs() < 0.005, "-u_tip = {u}");
    assert!((w / 6.6996 - 1.0).abs() < 0.005, "w_tip = {w}");
}

#[test]
fn end_moment_rolls_the_strip_into_an_arc() {
    // Sze, Liu & Lo (2004) test 3.2: E = 1.2e6, ν = 0, L = 12, b = 1, h = 0.1; a pure end moment
    // M bends the strip into a circular arc of angle θ = M L / EI (a full circle at
    // M_max = 2π EI / L = 50π/3). Exact tip: −u = L (1 − sin θ / θ), w = L (1 − cos θ) / θ.
    // Up to 0.9 of the full circle (324°): beyond 0.94 our Newton stalls at a relative
    // residual of 6e-7 (not yet understood), so the closed circle itself is not tested.
    let m = FabricMaterial {
        name: "sze32".into(),
        areal_density: 1.0,
        thickness: 0.1,
        law: OrthotropicStvk::isotropic(1.2e6, 0.0).into(),
    };
    let (l, ei) = (12.0, 1.2e6 * 0.1f64.powi(3) / 12.0);
    let m_max = 2.0 * std::f64::consts::PI * ei / l;
    for frac in [0.2, 0.45, 0.75, 0.9] {
        let mut bend = CantileverBend::new(1.0, l, 90.0);
        bend.mesh = (2, 32);
        bend.gravity = false;
        bend.tip_moment = frac * m_max;
        let r = bend.run(&m).unwrap();
        let theta = frac * 2.0 * std::f64::consts::PI;
        let (u, w) = (l - r.tip[1], r.tip[2]);
        let (ue, we) = (
            l * (1.0 - theta.sin() / theta),
            l * (1.0 - theta.cos()) / theta,
        );
        eprintln!("M/Mmax {frac}: -u {u} (exact {ue}), w {w} (exact {we})");
        // measured on 2 x 32: tip error 1.8e-5 L at 0.2, 1.2e-4 L at 0.45, 3.3e-4 L at 0.75,
        // 4.3e-4 L at 0.9
        let err = ((u - ue).powi(2) + (w - we).powi(2)).sqrt() / l;
        assert!(
            err < 5e-3,
            "M/Mmax = {frac}: tip ({u}, {w}) vs exact ({ue}, {we})"
        );
    }
}
