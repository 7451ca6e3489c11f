//! An independent oracle: OpenSubdiv's limit stencils, as ported to Rust by the `opensubdiv-rs`
//! crate (0.5.0: adaptive isolation to level 10, Gregory end caps below that, f32 weights, no
//! second derivatives). Our exact basis must agree in position and first derivatives to the
//! port's single precision wherever its evaluation is exact (away from the 2^-10 end-cap
//! squares at extraordinary corners).

use kshell::mesh::{read_obj, PolyMesh};
use kshell::subdiv::{BoundaryRule, LimitSurface};
use opensubdiv_rs::far::{
    AdaptiveOptions, LimitStencilTableFactory, LocationArray, PatchTableFactory,
    StencilTableFactory, StencilTableOptions, TopologyDescriptor, TopologyRefinerFactory,
};
use opensubdiv_rs::sdc::{Options, SchemeType, VtxBoundaryInterpolation};

/// Position, x_u and x_v from OpenSubdiv at (face, u, v) points of an all-quad mesh.
fn opensubdiv_eval(mesh: &PolyMesh, pts: &[(u32, f32, f32)]) -> Vec<[[f64; 3]; 3]> {
    let per_face: Vec<usize> = mesh.faces.iter().map(|f| f.len()).collect();
    let verts: Vec<u32> = mesh.faces.iter().flatten().copied().collect();
    let desc = TopologyDescriptor::new(mesh.num_vertices(), &per_face, &verts);
    let opts =
        Options::default().with_vtx_boundary_interpolation(VtxBoundaryInterpolation::EdgeAndCorner);
    let mut refiner =
        TopologyRefinerFactory::create(desc, SchemeType::Catmark, opts).expect("valid topology");
    refiner.refine_adaptive(AdaptiveOptions::new(10));
    let patches = PatchTableFactory::create(&refiner).expect("patch table");
    let cv = StencilTableFactory::create(&refiner, StencilTableOptions::for_patch_controls());
    let us: Vec<[f32; 1]> = pts.iter().map(|p| [p.1]).collect();
    let vs: Vec<[f32; 1]> = pts.iter().map(|p| [p.2]).collect();
    let locations: Vec<LocationArray> = pts
        .iter()
        .enumerate()
        .map(|(i, p)| LocationArray::new(p.0, &us[i], &vs[i]))
        .collect();
    let table = LimitStencilTableFactory::create(&refiner, &locations, Some(&cv), Some(&patches))
        .expect("limit stencils");
    (0..pts.len())
        .map(|i| {
            let s = table.stencil(i);
            let mut out = [[0.0; 3]; 3];
            for k in 0..s.indices.len() {
                let p = mesh.positions[s.indices[k] as usize];
                let w = [s.weights[k], s.du_weights[k], s.dv_weights[k]];
                for (o, wk) in out.iter_mut().zip(w) {
                    for c in 0..3 {
                        o[c] += wk as f64 * p[c];
                    }
                }
            }
            out
        })
        .collect()
}

#[test]
fn position_and_tangents_match_opensubdiv() {
    for name in ["cube", "star5", "fan4_boundary", "l_shape", "strip_8x12"] {
        let mesh = read_obj(format!("meshes/{name}.obj").as_ref())
            .unwrap()
            .mesh;
        let ours = LimitSurface::new(&mesh, BoundaryRule::Phantom).unwrap();
        // points away from corners: the port's Gregory caps only cover [0, 2^-10]² there
        let mut pts = Vec::new();
        for f in 0..mesh.num_faces() as u32 {
            for (u, v) in [
                (0.25f32, 0.5f32),
                (0.8, 0.125),
                (0.0625, 0.9375),
                (0.5, 0.0),
            ] {
                pts.push((f, u, v));
            }
        }
        let theirs = opensubdiv_eval(&mesh, &pts);
        for (&(f, u, v), t) in pts.iter().zip(&theirs) {
            let p = ours.evaluate(f as usize, u as f64, v as f64).unwrap();
            let scale = [p.d[1], p.d[2]]
                .iter()
                .flat_map(|d| d.iter())
                .fold(0.0f64, |m, x| m.max(x.abs()));
            for k in 0..3 {
                for c in 0..3 {
                    let err = (p.d[k][c] - t[k][c]).abs() / scale;
                    assert!(
                        err < 2e-6,
                        "{name} face {f} ({u},{v}) derivative {k} comp {c}: ours {} OpenSubdiv {} (rel {err:.1e})",
                        p.d[k][c],
                        t[k][c]
                    );
                }
            }
        }
    }
}
