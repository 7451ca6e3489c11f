//! The showcase scenes (Clyde et al. 2017 §6, Figures 1 and 5) against what is known of them
//! outside the code: the picture frame's homogeneous shear in closed form, the work–energy
//! balance of each scene's reported force, the drape's held corners, and the exported surface.

use crate::common::{work_balances, TestLaw};
use kshell::material::FabricMaterial;
use kshell::scene::{export, CornerPull, Drape, PictureFrame};

/// The example cotton with a nonlinear (degree-2) shear law.
/// The cotton example's moduli (a12 the file default, half the weaker yarn), linear but for
/// the shear terms given.
fn cotton(shear: &[(f64, f64)]) -> FabricMaterial {
    let law = TestLaw::stvk(2.0e8, 1.2e8, 6.0e7, 4.0e6)
        .named("t")
        .density(0.1036)
        .thickness(0.18e-3);
    if shear.is_empty() {
        return law.material();
    }
    let (mu, alpha): (Vec<f64>, Vec<f64>) = shear.iter().copied().unzip();
    law.shear(&mu, &alpha).material()
}

/// A sheet that follows the frame has Ẽ₁₁ = Ẽ₂₂ = 0 and Ẽ₁₂ = sin γ / 2 exactly, so
/// W = L² τ G₁₂ η₄(sin²γ / 4) and the shear force M / (L cos γ), M = dW/dγ, is
/// F_s = L τ G₁₂ η₄'(sin²γ / 4) sin γ / 2, with η₄'(x) = Σ μᵢ (1 + x)^(αᵢ − 1) (the law of
/// Clyde et al. 2017 Eq. 2). The limit surface of an affine map of the control points is the
/// affine map of the limit surface and 4 × 4 Gauss points integrate a constant exactly, so only
/// the solver's tolerance stands between the two.
#[test]
fn the_in_plane_frame_shear_force_is_the_homogeneous_shear_in_closed_form() {
    let m = cotton(&[(0.6, 1.0), (0.4, 8.0)]);
    let frame = PictureFrame {
        in_plane: true,
        mesh: 6,
        steps: 4,
        ..PictureFrame::new(0.1, 40.0)
    };
    let (points, deformed) = frame.run(&m).expect("the frame solves");
    assert_eq!(points.len(), 4);
    let (l, tau, g12) = (0.1, 0.18e-3, 4.0e6);
    for p in &points {
        let s = p.shear_deg.to_radians().sin();
        let x = s * s / 4.0;
        let deta = 0.6 + 0.4 * (1.0 + x).powf(7.0);
        let exact = l * tau * g12 * deta * s / 2.0;
        let rel = (p.shear_force - exact).abs() / exact;
        assert!(
            rel < 1e-7,
            "γ = {}°: {} N against {exact} N",
            p.shear_deg,
            p.shear_force
        );
        // the pulled diagonal's force: F = 2 F_s cos(α/2), α = 90° − γ
        let half = (90.0 - p.shear_deg).to_radians() / 2.0;
        assert!((p.axial_force - 2.0 * p.shear_force * half.cos()).abs() < 1e-9 * exact);
    }
    assert!(
        deformed.stable,
        "held in the plane, the homogeneous state is stable"
    );
    // the warp and weft moduli do not enter pure shear
    let mut stiff = m.clone();
    stiff.law.a11 *= 3.0;
    let (again, _) = frame.run(&stiff).unwrap();
    let last = (points[3].shear_force, again[3].shear_force);
    assert!((last.0 - last.1).abs() < 1e-7 * last.0, "{last:?}");
}

#[test]
fn the_wrinkling_frame_and_the_corner_pull_forces_do_the_work_the_energy_says() {
    let m = cotton(&[]);
    let frame = PictureFrame {
        mesh: 8,
        steps: 16,
        ..PictureFrame::new(0.1, 30.0)
    };
    let (points, deformed) = frame.run(&m).expect("the frame solves");
    assert!(deformed.stable);
    let q: Vec<f64> = points.iter().map(|p| p.shear_deg.to_radians()).collect();
    let f: Vec<f64> = points.iter().map(|p| p.moment).collect();
    let e: Vec<f64> = points.iter().map(|p| p.report.energy).collect();
    work_balances(&q, &f, &e, "picture frame");
    // wrinkles relax the compressive diagonal: a free sheet carries no more than the flat one
    let flat = 0.1 * 0.18e-3 * 4.0e6 * 30f64.to_radians().sin() / 2.0;
    let last = points.last().unwrap().shear_force;
    assert!(
        last <= flat * (1.0 + 1e-6) && last > 0.5 * flat,
        "{last} N, flat {flat} N"
    );
    let lift = deformed.x.iter().map(|p| p[2].abs()).fold(0.0, f64::max);
    assert!(
        lift > 1e-4,
        "the sheet wrinkles out of its plane ({lift} m)"
    );

    let pull = CornerPull {
        steps: 16,
        ..CornerPull::new(0.1, 0.1)
    };
    let (points, deformed) = pull.run(&m).expect("the corner pull solves");
    assert!(deformed.stable);
    let q: Vec<f64> = points.iter().map(|p| p.displacement).collect();
    let f: Vec<f64> = points.iter().map(|p| p.force).collect();
    let e: Vec<f64> = points.iter().map(|p| p.report.energy).collect();
    work_balances(&q, &f, &e, "corner pull");
    assert!(f.windows(2).all(|w| w[1] > w[0]), "the force rises: {f:?}");
}

#[test]
fn the_drape_hangs_from_its_corners_sixty_centimetres_apart_and_repeats_itself() {
    let m = cotton(&[]);
    let drape = Drape {
        mesh: 8,
        ..Drape::new()
    };
    let (shape, deformed) = drape.run(&m).expect("the drape solves");
    assert!(deformed.stable, "the returned equilibrium is stable");
    // the limit surface's top corners (rest (0, L) and (L, L)) are where the pins hold them
    let surface = export::sample(&deformed.sheet, &deformed.x, 1).unwrap();
    let corner = |x: f64| {
        let i = surface
            .uv
            .iter()
            .position(|t| (t[0] - x).abs() < 1e-9 && (t[1] - 1.0).abs() < 1e-9)
            .expect("a sample at the corner");
        surface.positions[i]
    };
    let (a, b) = (corner(0.0), corner(1.0));
    assert!(
        (a[0] - 0.2).abs() < 1e-9 && a[1].abs() < 1e-9 && a[2].abs() < 1e-9,
        "{a:?}"
    );
    assert!(
        (b[0] - 0.8).abs() < 1e-9 && b[1].abs() < 1e-9 && b[2].abs() < 1e-9,
        "{b:?}"
    );
    // a nearly inextensible 1 m sheet hangs about 1 m below its corners, and not much more
    assert!(
        shape.drop > 0.95 && shape.drop < 1.1,
        "drop {} m",
        shape.drop
    );
    assert!(
        shape.depth > 0.01,
        "the corners' approach buckles the sheet"
    );
    // the mean drop (from the nodes' consistent weights) is the centre of mass of the limit
    // surface: the mean of −z over the rest square, here by the midpoint rule on the surface
    // sampled 8 × 8 per face (an O(h²) rule, h = 1/64 m: about 1e-4 of the drop for folds of
    // 0.2 m radius; measured 2.7e-5)
    let fine = export::sample(&deformed.sheet, &deformed.x, 8).unwrap();
    let (mut moment, mut area) = (0.0, 0.0);
    for q in &fine.quads {
        let [a, b, c, d] = q.map(|i| fine.uv[i]);
        let rest = 0.5 * ((c[0] - a[0]) * (d[1] - b[1]) - (c[1] - a[1]) * (d[0] - b[0])).abs();
        let z = q.iter().map(|&i| fine.positions[i][2]).sum::<f64>() / 4.0;
        moment -= rest * z;
        area += rest;
    }
    assert!((area - 1.0).abs() < 1e-12, "the rest square: {area}");
    assert!(
        (shape.mean_drop - moment).abs() < 2e-4 * moment,
        "mean drop {} m, sampled {moment} m",
        shape.mean_drop
    );
    assert!(shape.mean_drop > 0.4 && shape.mean_drop < shape.drop);
    let (again, other) = drape.run(&m).unwrap();
    assert_eq!(
        (shape.drop, shape.depth, shape.width),
        (again.drop, again.depth, again.width)
    );
    assert_eq!(deformed.x, other.x, "one seed, one answer (to the bit)");
}

#[test]
fn the_exported_surface_is_welded_and_carries_unit_normals_and_fabric_coordinates() {
    let m = cotton(&[]);
    let frame = PictureFrame {
        mesh: 4,
        steps: 2,
        ..PictureFrame::new(0.1, 20.0)
    };
    let (_, d) = frame.run(&m).unwrap();
    let k = 3;
    let s = export::sample(&d.sheet, &d.x, k).unwrap();
    let side = 4 * k + 1;
    assert_eq!(
        s.positions.len(),
        side * side,
        "one vertex per sample, faces welded"
    );
    assert_eq!(s.quads.len(), 16 * k * k);
    for n in &s.normals {
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        assert!((l - 1.0).abs() < 1e-12);
    }
    for t in &s.uv {
        assert!((-1e-12..=0.1 + 1e-12).contains(&t[0]) && (-1e-12..=0.1 + 1e-12).contains(&t[1]));
    }
    // the frame moves the top edge (v = L) by L sin γ along x
    let top =
        s.uv.iter()
            .position(|t| t[0].abs() < 1e-12 && (t[1] - 0.1).abs() < 1e-12);
    let p = s.positions[top.unwrap()];
    assert!(
        (p[0] - 0.1 * 20f64.to_radians().sin()).abs() < 1e-9,
        "{p:?}"
    );
    let obj = s.obj("test");
    assert_eq!(
        obj.lines().filter(|l| l.starts_with("v ")).count(),
        side * side
    );
    assert_eq!(
        obj.lines().filter(|l| l.starts_with("f ")).count(),
        16 * k * k
    );
    let ply = s.ply("test");
    assert!(ply.contains(&format!("element vertex {}\n", side * side)));
    let body = ply.split("end_header\n").nth(1).unwrap();
    assert_eq!(body.lines().count(), side * side + 16 * k * k);
}
