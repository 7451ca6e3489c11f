//! A deformed sheet's limit surface as a mesh other tools load, written as Wavefront OBJ or
//! ASCII PLY: the [`SurfaceMesh`] that [`sample`] (the shell's limit surface, k × k per cage
//! face, welded where faces meet by rest position) and [`lattice_surface`] (a triangle model's
//! nodes) produce from a [`super::sheet::Sheet`], with unit normals and texture coordinates.
//!
//! Texture coordinates are the rest position in metres of fabric: u along the warp, v along
//! the weft (a texture with one repeat per metre tiles the cloth at its true scale).

pub use super::sheet::{lattice_surface, sample};
pub use super::surface::SurfaceMesh;
use std::fmt::Write;

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
