//! The limit basis against the outside world: partition of unity, affine reproduction, finite
//! differences, C¹ continuity across edges, the classical limit-point masks, convergence of
//! uniform subdivision, and consistency of the two boundary rules.

use kshell::mesh::{rectangular_grid, shapes, PolyMesh, Topology};
use kshell::subdiv::{
    refine_uniform, BasisError, BoundaryRule, FaceKind, LimitBasis, LimitPoint, LimitSurface,
};
use kshell::Vec3;
use std::f64::consts::PI;

/// Deterministic pseudo-random numbers in [0, 1) (xorshift; no dependency needed).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn norm(a: Vec3) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}
fn dist(a: Vec3, b: Vec3) -> f64 {
    norm(sub(a, b))
}

/// Every sample shape, with a name, in a curved (non-planar) version where that matters.
fn shapes_under_test() -> Vec<(&'static str, PolyMesh)> {
    let mut grid = rectangular_grid(0.05, 0.075, 4, 6);
    for p in &mut grid.positions {
        p[2] = 3.0 * p[0] * p[0] - 2.0 * p[0] * p[1] + 0.5 * p[1] * p[1] * p[1] / 0.075;
    }
    let mut l = shapes::l_shape(2);
    for p in &mut l.positions {
        p[2] = 0.1 * p[0] * p[1] - 0.05 * p[1] * p[1];
    }
    vec![
        ("curved grid", grid),
        ("cube", shapes::cube()),
        ("star3", shapes::star(3, 2)),
        ("star5", shapes::star(5, 2)),
        ("star6", shapes::star(6, 2)),
        ("boundary fan (3 faces)", shapes::fan(3, PI, 2)),
        ("boundary fan (4 faces)", shapes::fan(4, 1.5 * PI, 2)),
        ("L-shape", l),
    ]
}

const RULES: [BoundaryRule; 2] = [BoundaryRule::Phantom, BoundaryRule::Ghost];

#[test]
fn partition_of_unity_on_every_face_kind() {
    let mut rng = Rng(7);
    let mut kinds_seen = std::collections::HashSet::new();
    for (name, mesh) in shapes_under_test() {
        for rule in RULES {
            let s = LimitSurface::new(&mesh, rule).unwrap();
            for face in 0..s.num_faces() {
                kinds_seen.insert(s.face_kind(face));
                let uvs: Vec<[f64; 2]> = (0..5).map(|_| [rng.next(), rng.next()]).collect();
                for (st, uv) in s.stencils(face, &uvs).unwrap().iter().zip(&uvs) {
                    for k in 0..6 {
                        let sum: f64 = st.weights.iter().map(|w| w[k]).sum();
                        let want = if k == 0 { 1.0 } else { 0.0 };
                        let scale: f64 = st.weights.iter().map(|w| w[k].abs()).sum();
                        assert!(
                            (sum - want).abs() <= 1e-13 * scale.max(1.0),
                            "{name} {rule:?} face {face} at {uv:?}: derivative {k} weights sum to {sum}"
                        );
                    }
                }
            }
        }
    }
    assert_eq!(
        kinds_seen.len(),
        3,
        "regular, boundary and extraordinary faces all tested"
    );
}

#[test]
fn planar_grid_reproduces_the_affine_map() {
    // a skewed, tilted affine image of a 5 × 7 grid: x = o + a·s + b·t
    let (o, a, b) = ([0.3, -0.2, 1.0], [0.5, 0.1, 0.2], [-0.1, 0.4, 0.3]);
    let (nx, ny) = (5, 7);
    let mut mesh = rectangular_grid(1.0, 1.0, nx, ny);
    for p in &mut mesh.positions {
        let (s, t) = (p[0], p[1]);
        *p = std::array::from_fn(|c| o[c] + a[c] * s + b[c] * t);
    }
    let mut rng = Rng(3);
    for rule in RULES {
        let surf = LimitSurface::new(&mesh, rule).unwrap();
        for face in 0..surf.num_faces() {
            let (i, j) = (face % nx, face / nx);
            for _ in 0..4 {
                let (u, v) = (rng.next(), rng.next());
                let (s, t) = ((i as f64 + u) / nx as f64, (j as f64 + v) / ny as f64);
                let p = surf.evaluate(face, u, v).unwrap();
                let x: Vec3 = std::array::from_fn(|c| o[c] + a[c] * s + b[c] * t);
                let xu: Vec3 = std::array::from_fn(|c| a[c] / nx as f64);
                let xv: Vec3 = std::array::from_fn(|c| b[c] / ny as f64);
                assert!(dist(p.d[0], x) < 1e-13, "{rule:?} face {face}: x");
                assert!(dist(p.d[1], xu) < 1e-13, "{rule:?} face {face}: x_u");
                assert!(dist(p.d[2], xv) < 1e-13, "{rule:?} face {face}: x_v");
                for k in 3..6 {
                    assert!(
                        norm(p.d[k]) < 1e-12,
                        "{rule:?} face {face}: second derivative {k}"
                    );
                }
            }
        }
    }
}

/// Checks analytic derivatives against fourth-order central differences of the evaluator at
/// (u, v): (−f(+2h) + 8 f(+h) − 8 f(−h) + f(−2h)) / 12h. (Near an extraordinary vertex the
/// surface's higher derivatives grow fast, so a second-order difference would measure its own
/// truncation error rather than ours.)
fn check_fd(s: &LimitSurface, face: usize, u: f64, v: f64, what: &str) {
    let h = 1e-4 * u.min(v).min(1.0 - u).min(1.0 - v).min(0.05) / 0.05;
    let at = |u: f64, v: f64| s.evaluate(face, u, v).unwrap();
    let p = at(u, v);
    let (pu, mu, pv, mv) = (at(u + h, v), at(u - h, v), at(u, v + h), at(u, v - h));
    let (pu2, mu2, pv2, mv2) = (
        at(u + 2.0 * h, v),
        at(u - 2.0 * h, v),
        at(u, v + 2.0 * h),
        at(u, v - 2.0 * h),
    );
    let d4 =
        |k: usize, p2: &LimitPoint, p1: &LimitPoint, m1: &LimitPoint, m2: &LimitPoint| -> Vec3 {
            std::array::from_fn(|c| {
                (-p2.d[k][c] + 8.0 * p1.d[k][c] - 8.0 * m1.d[k][c] + m2.d[k][c]) / (12.0 * h)
            })
        };
    let cd_u = |k: usize| d4(k, &pu2, &pu, &mu, &mu2);
    let cd_v = |k: usize| d4(k, &pv2, &pv, &mv, &mv2);
    // scale of first and second derivatives on this face, for a relative measure
    let s1 = norm(p.d[1]).max(norm(p.d[2]));
    let s2 = (3..6).map(|k| norm(p.d[k])).fold(s1, f64::max);
    let checks: [(&str, Vec3, Vec3, f64); 6] = [
        ("x_u", cd_u(0), p.d[1], s1),
        ("x_v", cd_v(0), p.d[2], s1),
        ("x_uu", cd_u(1), p.d[3], s2),
        ("x_uv", cd_v(1), p.d[4], s2),
        ("x_uv (from x_v)", cd_u(2), p.d[4], s2),
        ("x_vv", cd_v(2), p.d[5], s2),
    ];
    for (name, fd, exact, scale) in checks {
        let err = dist(fd, exact) / scale;
        assert!(
            err <= 1e-6,
            "{what} face {face} ({u:.3},{v:.3}) {name}: relative error {err:.2e}"
        );
    }
}

#[test]
fn derivatives_agree_with_finite_differences() {
    let mut rng = Rng(11);
    let mut seen = std::collections::HashSet::new();
    for (name, mesh) in shapes_under_test() {
        for rule in RULES {
            let s = LimitSurface::new(&mesh, rule).unwrap();
            for face in 0..s.num_faces() {
                seen.insert(s.face_kind(face));
                for _ in 0..2 {
                    let (u, v) = (0.02 + 0.96 * rng.next(), 0.02 + 0.96 * rng.next());
                    check_fd(&s, face, u, v, &format!("{name} {rule:?}"));
                }
                // and right next to a corner, deep in the local refinement
                check_fd(
                    &s,
                    face,
                    0.003,
                    0.0021,
                    &format!("{name} {rule:?} near corner"),
                );
            }
        }
    }
    assert_eq!(seen.len(), 3);
}

/// (u, v) on `face` of the point at fraction t along side s (corner s → corner s+1).
fn on_side(s: usize, t: f64) -> (f64, f64) {
    match s {
        0 => (t, 0.0),
        1 => (1.0, t),
        2 => (1.0 - t, 1.0),
        _ => (0.0, 1.0 - t),
    }
}

#[test]
fn tangent_plane_is_continuous_across_every_edge() {
    for (name, mesh) in shapes_under_test() {
        let topo = Topology::build(&mesh).unwrap();
        for rule in RULES {
            let s = LimitSurface::new(&mesh, rule).unwrap();
            for (e, &[f0, f1]) in topo.edge_faces.iter().enumerate() {
                if topo.is_boundary_edge(e as u32) {
                    continue;
                }
                let [a, b] = topo.edges[e];
                let side = |f: u32| {
                    let face = &mesh.faces[f as usize];
                    let k = face.iter().position(|&x| x == a).unwrap();
                    if face[(k + 1) % 4] == b {
                        (k, false) // runs a -> b
                    } else {
                        ((k + 3) % 4, true) // runs b -> a
                    }
                };
                let (s0, rev0) = side(f0);
                let (s1, rev1) = side(f1);
                assert_ne!(rev0, rev1);
                // t measured from a towards b; avoid the corners (extraordinary vertices)
                for t in [0.001, 0.13, 0.5, 0.77, 0.999] {
                    let (u0, v0) = on_side(s0, if rev0 { 1.0 - t } else { t });
                    let (u1, v1) = on_side(s1, if rev1 { 1.0 - t } else { t });
                    let p0 = s.evaluate(f0 as usize, u0, v0).unwrap();
                    let p1 = s.evaluate(f1 as usize, u1, v1).unwrap();
                    let what = format!("{name} {rule:?} edge {a}-{b} t={t}");
                    assert!(dist(p0.x(), p1.x()) < 1e-12, "{what}: positions differ");
                    let (n0, n1) = (p0.normal(), p1.normal());
                    assert!(dist(n0, n1) < 1e-10, "{what}: normals {n0:?} vs {n1:?}");
                }
            }
        }
    }
}

/// The classical Catmull–Clark limit-point masks (Halstead, Kass & DeRose 1993 for interior
/// vertices; the cubic B-spline curve rule (1, 4, 1)/6 on smooth boundaries; corners stay):
/// an independent formula for the limit position of a control vertex.
fn limit_point_mask(mesh: &PolyMesh, topo: &Topology, v: usize) -> Vec3 {
    let p = &mesh.positions;
    let faces = &topo.vertex_faces[v];
    let mut acc = [0.0; 3];
    let mut add = |w: f64, q: Vec3| {
        for c in 0..3 {
            acc[c] += w * q[c];
        }
    };
    if topo.on_boundary[v] {
        if faces.len() == 1 {
            return p[v];
        }
        add(4.0 / 6.0, p[v]);
        for (e, &[a, b]) in topo.edges.iter().enumerate() {
            if topo.is_boundary_edge(e as u32) && (a as usize == v || b as usize == v) {
                add(1.0 / 6.0, p[(a + b) as usize - v]);
            }
        }
        return acc;
    }
    let n = faces.len() as f64;
    let w = 1.0 / (n * (n + 5.0));
    add(n * n * w, p[v]);
    for &f in faces {
        let face = &mesh.faces[f as usize];
        let k = face.iter().position(|&x| x as usize == v).unwrap();
        add(4.0 * w * 0.5, p[face[(k + 1) % 4] as usize]); // each edge neighbour seen by 2 faces
        add(4.0 * w * 0.5, p[face[(k + 3) % 4] as usize]);
        add(w, p[face[(k + 2) % 4] as usize]);
    }
    acc
}

/// Follows parameter (u, v) of `face` down `levels` uniform refinements of an all-quad mesh:
/// returns the level-`levels` vertex sitting at (u, v) (which must be dyadic at that level).
fn vertex_at(levels: &[PolyMesh], face: usize, u: f64, v: f64) -> usize {
    let mut corners: Vec<u32> = levels[0].faces[face].clone();
    let mut f = face;
    let (mut u, mut v) = (u, v);
    for lvl in 0..levels.len() {
        for (k, &(cu, cv)) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            .iter()
            .enumerate()
        {
            if u == cu && v == cv {
                return corners[k] as usize;
            }
        }
        let (i, j) = ((u >= 0.5) as usize, (v >= 0.5) as usize);
        let k = [[0, 3], [1, 2]][i][j];
        // parent corner order is corners (aligned with (u, v)); the child of aligned corner k
        // is refined face 4f + r where r is that corner's index in the stored face
        let stored = &levels[lvl].faces[f];
        let r = stored.iter().position(|&x| x == corners[k]).unwrap();
        f = 4 * f + r;
        let child = &levels[lvl + 1].faces[f];
        let rot = (4 - k) % 4;
        corners = (0..4).map(|q| child[(rot + q) % 4]).collect();
        u = 2.0 * u - i as f64;
        v = 2.0 * v - j as f64;
    }
    panic!("({u}, {v}) is not dyadic at this depth");
}

#[test]
fn limit_masks_on_refined_cages_match_the_basis_exactly() {
    // Independent path: refine the whole cage k times, apply the limit-point masks to the vertex
    // at a dyadic (u, v), and compare with the basis at that (u, v).
    for (name, mesh) in shapes_under_test() {
        let s = LimitSurface::new(&mesh, BoundaryRule::Phantom).unwrap();
        let mut levels = vec![mesh.clone()];
        for _ in 0..3 {
            let last = levels.last().unwrap();
            let t = Topology::build(last).unwrap();
            levels.push(refine_uniform(last, &t));
        }
        let fine = levels.last().unwrap();
        let fine_topo = Topology::build(fine).unwrap();
        for face in 0..mesh.num_faces() {
            for (u, v) in [
                (0.125, 0.125),
                (0.5, 0.25),
                (0.875, 0.625),
                (0.375, 1.0),
                (1.0, 0.5),
            ] {
                let vx = vertex_at(&levels, face, u, v);
                let want = limit_point_mask(fine, &fine_topo, vx);
                let got = s.evaluate(face, u, v).unwrap().x();
                assert!(
                    dist(got, want) < 1e-13,
                    "{name} face {face} ({u},{v}): basis {got:?} vs limit mask {want:?}"
                );
            }
        }
    }
}

#[test]
fn uniform_subdivision_converges_to_the_basis_at_second_order() {
    // Control points of level k approach the limit surface as O(4^-k) in smooth regions.
    for (name, mesh) in shapes_under_test() {
        let s = LimitSurface::new(&mesh, BoundaryRule::Phantom).unwrap();
        let mut levels = vec![mesh.clone()];
        for _ in 0..5 {
            let last = levels.last().unwrap();
            let t = Topology::build(last).unwrap();
            levels.push(refine_uniform(last, &t));
        }
        let (face, u, v) = (mesh.num_faces() / 2, 0.5, 0.5);
        let limit = s.evaluate(face, u, v).unwrap().x();
        let errs: Vec<f64> = (1..levels.len())
            .map(|k| {
                dist(
                    levels[k].positions[vertex_at(&levels[..=k], face, u, v)],
                    limit,
                )
            })
            .collect();
        for w in errs.windows(2).skip(1) {
            let ratio = w[0] / w[1];
            assert!(
                (3.5..4.5).contains(&ratio),
                "{name}: error ratio {ratio:.3} between levels, want about 4 ({errs:?})"
            );
        }
    }
}

#[test]
fn refining_the_cage_does_not_change_the_limit_surface() {
    for (name, mesh) in shapes_under_test() {
        let t = Topology::build(&mesh).unwrap();
        let fine = refine_uniform(&mesh, &t);
        let (s0, s1) = (
            LimitSurface::new(&mesh, BoundaryRule::Phantom).unwrap(),
            LimitSurface::new(&fine, BoundaryRule::Phantom).unwrap(),
        );
        for face in 0..mesh.num_faces() {
            // quadrant of stored corner 0 is child 4f, with the same orientation: (u,v)=(2u,2v)
            let (u, v) = (0.3, 0.45);
            let p0 = s0.evaluate(face, u / 2.0, v / 2.0).unwrap();
            let p1 = s1.evaluate(4 * face, u, v).unwrap();
            assert!(dist(p0.x(), p1.x()) < 1e-13, "{name} face {face}");
            for k in 1..3 {
                let scaled: Vec3 = std::array::from_fn(|c| 0.5 * p0.d[k][c]);
                assert!(
                    dist(scaled, p1.d[k]) < 1e-12,
                    "{name} face {face} derivative {k}"
                );
            }
        }
    }
}

#[test]
fn non_quad_cages_become_quads_after_one_step() {
    // a tetrahedron and a pentagon-capped prism: triangles and n-gons
    let tet = PolyMesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        vec![vec![0, 2, 1], vec![0, 1, 3], vec![1, 2, 3], vec![2, 0, 3]],
    );
    assert_eq!(
        LimitSurface::new(&tet, BoundaryRule::Phantom).unwrap_err(),
        BasisError::NotQuad {
            face: 0,
            corners: 3
        }
    );
    let quads = refine_uniform(&tet, &Topology::build(&tet).unwrap());
    assert!(quads.is_all_quads());
    assert_eq!(quads.num_faces(), 12);
    let basis = LimitBasis::new(&quads, Default::default()).unwrap();
    // closed surface: positive volume, smaller than the tetrahedron's hull 1/6
    let vol = basis.enclosed_volume(&basis.control_points);
    assert!(vol > 0.0 && vol < 1.0 / 6.0, "volume {vol}");
}

#[test]
fn ghost_rule_starts_on_the_phantom_surface_where_both_are_regular() {
    let mut mesh = rectangular_grid(2.0, 3.0, 3, 4);
    for p in &mut mesh.positions {
        p[2] = 0.2 * p[0] * p[1] - 0.1 * p[0] * p[0];
    }
    let a = LimitSurface::new(&mesh, BoundaryRule::Phantom).unwrap();
    let b = LimitSurface::new(&mesh, BoundaryRule::Ghost).unwrap();
    assert_eq!(a.control_points().len(), 20);
    // a ghost per boundary vertex with two faces (2·(2+3)... = 10), three per corner (12)
    assert_eq!(b.control_points().len(), 20 + 10 + 12);
    for face in 0..mesh.num_faces() {
        for (u, v) in [(0.0, 0.0), (0.2, 0.9), (1.0, 0.5)] {
            let (p, q): (LimitPoint, LimitPoint) = (
                a.evaluate(face, u, v).unwrap(),
                b.evaluate(face, u, v).unwrap(),
            );
            for k in 0..6 {
                assert!(dist(p.d[k], q.d[k]) < 1e-12, "face {face} ({u},{v}) d{k}");
            }
        }
    }
}

#[test]
fn extraordinary_vertex_itself_is_refused_with_a_clear_error() {
    let s = LimitSurface::new(&shapes::star(5, 2), BoundaryRule::Phantom).unwrap();
    // face 0 has the centre at its corner 0
    assert_eq!(s.face_kind(0), FaceKind::Extraordinary);
    let e = s.evaluate(0, 0.0, 0.0).unwrap_err();
    assert!(
        matches!(e, BasisError::AtExtraordinaryVertex { face: 0, .. }),
        "{e}"
    );
    assert!(s.evaluate(0, 1e-9, 1e-9).is_ok());
    assert!(matches!(
        s.evaluate(0, 1.5, 0.0),
        Err(BasisError::OutsideFace { .. })
    ));
    assert!(matches!(
        s.evaluate(99, 0.5, 0.5),
        Err(BasisError::NoSuchFace { .. })
    ));
}

#[test]
fn basis_tables_cover_the_flat_strip_exactly() {
    // The phantom rule reproduces the affine map up to the boundary, so the limit surface of a
    // 50 × 75 mm strip cage is exactly that rectangle: area 3.75e-3 m².
    let mesh = rectangular_grid(0.05, 0.075, 8, 12);
    for n in 1..=8 {
        let b = LimitBasis::new(
            &mesh,
            kshell::subdiv::BasisOptions {
                gauss_points: n,
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(b.num_points(), 96 * n * n);
        assert!((b.area(&b.control_points) / 3.75e-3 - 1.0).abs() < 1e-13);
    }
    // the cube's limit surface is a closed, convex-ish blob inside the unit cube
    let b = LimitBasis::new(&shapes::cube(), Default::default()).unwrap();
    let v = b.enclosed_volume(&b.control_points);
    assert!(v > 0.2 && v < 1.0, "volume {v}");
    let (_, max) = b.stencil_sizes();
    assert_eq!(max, 8, "a cube face's one-ring is the whole cube");
}
