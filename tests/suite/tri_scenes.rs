//! The showcase scenes on the triangle models (Miguel et al. 2012, Larionov et al. 2022)
//! against what is known outside the code: the in-plane picture frame's homogeneous shear in
//! closed form (constant-strain triangles follow an affine boundary motion exactly), the
//! work–energy balance of the reported forces, and the drape's held corners.

use crate::common::work_balances;
use kshell::scene::{CornerPull, Drape, PictureFrame};
use kshell::solve::NewtonOptions;
use kshell::tri::{Stiffness, TriKind, TriMaterial};

/// A woven-like material on `kind`: stiff yarns, a shear spline stiffening 2.5×, soft bending
/// (N/m and N·m), 100 g/m².
fn material(kind: TriKind) -> TriMaterial {
    let shear = Stiffness::spline(0.0, 0.5, vec![400.0, 600.0, 1000.0]).unwrap();
    let bend = Stiffness::constant(2e-5);
    TriMaterial {
        kind,
        curves: [
            Stiffness::constant(3.0e4),
            Stiffness::constant(2.0e4),
            shear,
            bend.clone(),
            bend.clone(),
            bend,
        ],
        coupling: if kind == TriKind::Xpbd { 3.0e3 } else { 0.0 },
        areal_density: 0.1,
    }
}

/// Held in its plane, a sheet that follows the frame F = [[1, sin γ], [0, cos γ]] has, in
/// every triangle, w_u = (1, 0) and w_v = (sin γ, cos γ): warp and weft strains 0 (Green and
/// Baraff–Witkin alike) and shear strain w_u·w_v = sin γ. So W = L² W_s(sin γ) and the shear
/// force M / (L cos γ), M = dW/dγ, is L W_s′(sin γ) = L σ_s(sin γ), with σ_s the shear
/// component's stress (`Stiffness::density`), whatever the mesh.
#[test]
fn the_in_plane_frame_on_every_membrane_model_is_the_homogeneous_shear() {
    for kind in [TriKind::StvkDs, TriKind::SoftConstraints, TriKind::Xpbd] {
        let m = material(kind);
        let frame = PictureFrame {
            in_plane: true,
            mesh: 6,
            steps: 4,
            ..PictureFrame::new(0.1, 35.0)
        };
        let (points, deformed) = frame.run_tri(&m).expect("the frame solves");
        assert_eq!(points.len(), 4);
        for p in &points {
            let s = p.shear_deg.to_radians().sin();
            let exact = 0.1 * m.curves[2].density(s).1;
            let rel = (p.shear_force - exact).abs() / exact;
            assert!(
                rel < 1e-8,
                "{kind:?} at γ = {}°: {} N against {exact} N",
                p.shear_deg,
                p.shear_force
            );
        }
        assert!(deformed.stable, "{kind:?}");
        // every node sits at its affine image
        let g = 35f64.to_radians();
        for (x, r) in deformed.x.iter().zip(deformed.sheet.rest()) {
            let want = [r[0] + r[1] * g.sin(), r[1] * g.cos(), 0.0];
            assert!(
                (0..3).all(|c| (x[c] - want[c]).abs() < 1e-9),
                "{kind:?}: {x:?} vs {want:?}"
            );
        }
    }
}

#[test]
fn the_free_frame_and_the_corner_pull_do_the_work_their_energy_says() {
    let m = material(TriKind::StvkDs);
    let frame = PictureFrame {
        mesh: 10,
        steps: 16,
        ..PictureFrame::new(0.1, 30.0)
    };
    let (points, deformed) = frame.run_tri(&m).expect("the frame solves");
    assert!(deformed.stable);
    let q: Vec<f64> = points.iter().map(|p| p.shear_deg.to_radians()).collect();
    let f: Vec<f64> = points.iter().map(|p| p.moment).collect();
    let e: Vec<f64> = points.iter().map(|p| p.report.energy).collect();
    work_balances(&q, &f, &e, "picture frame");
    // a free sheet carries no more than the flat one
    let flat = 0.1 * m.curves[2].density(30f64.to_radians().sin()).1;
    let last = points.last().unwrap().shear_force;
    assert!(
        last <= flat * (1.0 + 1e-6) && last > 0.3 * flat,
        "{last} N, flat {flat} N"
    );

    let pull = CornerPull {
        steps: 16,
        ..CornerPull::new(0.1, 0.05)
    };
    let (points, deformed) = pull.run_tri(&m).expect("the corner pull solves");
    assert!(deformed.stable);
    let q: Vec<f64> = points.iter().map(|p| p.displacement).collect();
    let f: Vec<f64> = points.iter().map(|p| p.force).collect();
    let e: Vec<f64> = points.iter().map(|p| p.report.energy).collect();
    work_balances(&q, &f, &e, "corner pull");
    assert!(f.windows(2).all(|w| w[1] > w[0]), "the force rises: {f:?}");
}

#[test]
fn the_drape_on_a_triangle_model_hangs_from_its_pins() {
    let m = material(TriKind::StvkDs);
    // the scene command's budget: a folding sheet spends long stretches in backward Euler
    let drape = Drape {
        mesh: 8,
        solver: NewtonOptions {
            max_iterations: 500,
            ..NewtonOptions::default()
        },
        ..Drape::new()
    };
    let (shape, deformed) = drape.run_tri(&m).expect("the drape solves");
    assert!(deformed.stable, "the returned equilibrium is stable");
    let s = &deformed.sheet;
    let (a, b) = (deformed.x[s.node(0, 8)], deformed.x[s.node(8, 8)]);
    assert_eq!(a, [0.2, 0.0, 0.0]);
    assert_eq!(b, [0.8, 0.0, 0.0]);
    assert!(
        shape.drop > 0.95 && shape.drop < 1.1,
        "drop {} m",
        shape.drop
    );
    assert!(
        shape.depth > 0.01,
        "the corners' approach buckles the sheet"
    );
    // the centre of mass hangs between the corners and the lowest point
    assert!(
        shape.mean_drop > 0.4 && shape.mean_drop < shape.drop,
        "mean drop {} m",
        shape.mean_drop
    );
    let (again, other) = drape.run_tri(&m).unwrap();
    assert_eq!(shape.depth, again.depth);
    assert_eq!(deformed.x, other.x, "one seed, one answer (to the bit)");
}
