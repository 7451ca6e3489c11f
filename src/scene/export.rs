//! A deformed sheet's limit surface as a mesh other tools load: sampled k × k per cage face,
//! the samples welded where faces meet (by rest position), with unit normals and texture
//! coordinates, written as Wavefront OBJ or ASCII PLY.
//!
//! Texture coordinates are the rest position in metres of fabric: u along the warp, v along
//! the weft (a texture with one repeat per metre tiles the cloth at its true scale).

use super::sheet::{Sheet, SheetModel};
use super::SceneError;
use crate::assembly::ShellModel;
use crate::shape::ShapeMesh;
use crate::Vec3;
use std::collections::HashMap;
use std::fmt::Write;

/// A sampled limit surface: positions, normals and (u, v) per vertex, quads as vertex indices
/// (counter-clockwise seen from the normal's side).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uv: Vec<[f64; 2]>,
    pub quads: Vec<[usize; 4]>,
}

impl SurfaceMesh {
    /// The sampled sheet as a triangulated shape (quads split along one diagonal).
    pub fn to_shape(&self) -> ShapeMesh {
        ShapeMesh {
            positions: self.positions.clone(),
            uv: Ok(self.uv.clone()),
            triangles: self
                .quads
                .iter()
                .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
                .collect(),
        }
    }
}

/// Samples the limit surface of `sheet` at control points `x`, `k` × `k` quads per cage face.
pub fn sample(sheet: &Sheet<ShellModel>, x: &[Vec3], k: usize) -> Result<SurfaceMesh, SceneError> {
    let k = k.max(1);
    let surface = sheet.model.basis.surface();
    let rest = sheet.rest();
    let uvs: Vec<[f64; 2]> = (0..=k)
        .flat_map(|b| (0..=k).map(move |a| [a as f64 / k as f64, b as f64 / k as f64]))
        .collect();
    let mut out = SurfaceMesh::default();
    let mut welded: HashMap<(i64, i64), usize> = HashMap::new();
    let key_scale = 1e6 * k as f64 * sheet.n as f64 / sheet.side;
    for face in 0..surface.num_faces() {
        let stencils = surface
            .stencils(face, &uvs)
            .map_err(|e| SceneError::Basis(e.into()))?;
        let mut ids = Vec::with_capacity(uvs.len());
        for s in &stencils {
            let r = s.apply(rest).x();
            let key = (
                (r[0] * key_scale).round() as i64,
                (r[1] * key_scale).round() as i64,
            );
            let id = *welded.entry(key).or_insert_with(|| {
                let p = s.apply(x);
                out.positions.push(p.x());
                out.normals.push(p.normal());
                out.uv.push([r[0], r[1]]);
                out.positions.len() - 1
            });
            ids.push(id);
        }
        for b in 0..k {
            for a in 0..k {
                let at = |i: usize, j: usize| ids[j * (k + 1) + i];
                out.quads
                    .push([at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)]);
            }
        }
    }
    Ok(out)
}

/// A triangle model's sheet as a surface: its nodes, one quad per grid cell (the quad's
/// diagonal is the renderer's, not necessarily the model's), unit normals averaged from the
/// cells around each node, texture coordinates the rest positions.
pub fn lattice_surface<M: SheetModel>(sheet: &Sheet<M>, x: &[Vec3]) -> SurfaceMesh {
    let n = sheet.n;
    let mut out = SurfaceMesh::default();
    let id = |i: usize, j: usize| j * (n + 1) + i;
    for j in 0..=n {
        for i in 0..=n {
            let v = sheet.node(i, j);
            out.positions.push(x[v]);
            let r = sheet.rest()[v];
            out.uv.push([r[0], r[1]]);
        }
    }
    let mut normals = vec![[0.0; 3]; out.positions.len()];
    for j in 0..n {
        for i in 0..n {
            let q = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
            let p = |k: usize| out.positions[q[k]];
            let (a, b) = (sub(p(2), p(0)), sub(p(3), p(1)));
            let c = [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ];
            for &v in &q {
                (0..3).for_each(|k| normals[v][k] += c[k]);
            }
            out.quads.push(q);
        }
    }
    out.normals = normals
        .into_iter()
        .map(|v| {
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if l > 0.0 {
                [v[0] / l, v[1] / l, v[2] / l]
            } else {
                [0.0, 0.0, 1.0]
            }
        })
        .collect();
    out
}

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

impl SurfaceMesh {
    /// Wavefront OBJ: `v`, `vn` and `vt` lines, one of each per vertex, and `f v/vt/vn` quads.
    pub fn obj(&self, comment: &str) -> String {
        let mut s = String::new();
        for line in comment.lines() {
            let _ = writeln!(s, "# {line}");
        }
        for p in &self.positions {
            let _ = writeln!(s, "v {:.9} {:.9} {:.9}", p[0], p[1], p[2]);
        }
        for n in &self.normals {
            let _ = writeln!(s, "vn {:.6} {:.6} {:.6}", n[0], n[1], n[2]);
        }
        for t in &self.uv {
            let _ = writeln!(s, "vt {:.9} {:.9}", t[0], t[1]);
        }
        for q in &self.quads {
            let _ = write!(s, "f");
            for &i in q {
                let _ = write!(s, " {0}/{0}/{0}", i + 1);
            }
            s.push('\n');
        }
        s
    }

    /// ASCII PLY: vertices with x y z nx ny nz s t, quads as 4-vertex faces.
    pub fn ply(&self, comment: &str) -> String {
        let mut s = String::from("ply\nformat ascii 1.0\n");
        for line in comment.lines() {
            let _ = writeln!(s, "comment {line}");
        }
        let _ = writeln!(s, "element vertex {}", self.positions.len());
        for p in ["x", "y", "z", "nx", "ny", "nz", "s", "t"] {
            let _ = writeln!(s, "property double {p}");
        }
        let _ = writeln!(s, "element face {}", self.quads.len());
        s.push_str("property list uchar int vertex_indices\nend_header\n");
        for ((p, n), t) in self.positions.iter().zip(&self.normals).zip(&self.uv) {
            let _ = writeln!(
                s,
                "{:.9} {:.9} {:.9} {:.6} {:.6} {:.6} {:.9} {:.9}",
                p[0], p[1], p[2], n[0], n[1], n[2], t[0], t[1]
            );
        }
        for q in &self.quads {
            let _ = writeln!(s, "4 {} {} {} {}", q[0], q[1], q[2], q[3]);
        }
        s
    }
}
