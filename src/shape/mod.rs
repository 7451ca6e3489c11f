//! Captured static shapes as fit targets: a triangulated surface read from Wavefront OBJ (a
//! scanned or simulated sheet), and the two ways of comparing a simulated sheet with it that
//! the cloth-estimation literature uses:
//!
//! - **positions** (Miguel et al. 2012, §5): each simulated vertex's distance to the captured
//!   surface ([`distance`]), closest point to closest point, so the two meshes need not match;
//! - **FFT** (Larionov et al. 2022, §5): both sheets resampled on one grid of material
//!   coordinates (the OBJ's `vt`), and the magnitudes of each coordinate's 2-D discrete Fourier
//!   transform compared ([`fft`]); the phase is dropped, so a wrinkle that sits a little aside,
//!   or bulges the other way, still matches.
//!
//! Both errors are made relative: a position error to the target's thinnest spread (the
//! out-of-plane extent of a sheet: the amplitude of a frame's wrinkles, the depth of a drape's
//! folds), an FFT error to the target's spectrum, coordinate by coordinate.

pub mod distance;
pub mod fft;

use crate::Vec3;

/// A triangulated surface, with material coordinates per vertex when the file gave them.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeMesh {
    /// m
    pub positions: Vec<Vec3>,
    /// One (u, v) per vertex, or why there is none (no `vt`, or a vertex with two of them).
    pub uv: Result<Vec<[f64; 2]>, String>,
    pub triangles: Vec<[usize; 3]>,
}

impl Default for ShapeMesh {
    fn default() -> Self {
        Self {
            positions: Vec::new(),
            uv: Err("no texture coordinates".into()),
            triangles: Vec::new(),
        }
    }
}

/// A line of an OBJ file that could not be read.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjError {
    pub line: Option<usize>,
    pub message: String,
}

fn numbers<'a>(
    words: impl Iterator<Item = &'a str>,
    at_least: usize,
    line: usize,
    what: &str,
) -> Result<Vec<f64>, ObjError> {
    let v: Vec<f64> = words
        .map(|w| w.parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| ObjError {
            line: Some(line),
            message: format!("a {what} line needs numbers"),
        })?;
    if v.len() < at_least || v.iter().any(|x| !x.is_finite()) {
        return Err(ObjError {
            line: Some(line),
            message: format!("a {what} line needs {at_least} finite numbers"),
        });
    }
    Ok(v)
}

/// An OBJ index (1-based, or negative: counted back from the last one read) as a 0-based one.
fn index(word: &str, count: usize, line: usize, what: &str) -> Result<usize, ObjError> {
    let bad = |m: String| ObjError {
        line: Some(line),
        message: m,
    };
    let i: i64 = word.parse().map_err(|_| {
        bad(format!(
            "face corner {word:?}: {what} index is not an integer"
        ))
    })?;
    let k = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || k < 0 || k >= count as i64 {
        return Err(bad(format!(
            "face corner {word:?}: {what} index {i} is not among the {count} read so far"
        )));
    }
    Ok(k as usize)
}

impl ShapeMesh {
    /// Reads OBJ text: `v x y z` (times `scale`, to metres), `vt u v`, and `f` faces of three or
    /// more corners `v`, `v/vt`, `v//vn` or `v/vt/vn` (polygons are split as fans); other lines
    /// (normals, groups, materials, comments) are skipped.
    pub fn from_obj(text: &str, scale: f64) -> Result<Self, ObjError> {
        let mut positions = Vec::new();
        let mut texture: Vec<[f64; 2]> = Vec::new();
        let mut uv: Vec<Option<[f64; 2]>> = Vec::new();
        let mut uv_problem: Option<String> = None;
        let mut triangles = Vec::new();
        for (k, raw) in text.lines().enumerate() {
            let line = k + 1;
            let mut words = raw.split_whitespace();
            match words.next() {
                Some("v") => {
                    let p = numbers(words, 3, line, "v")?;
                    positions.push([p[0] * scale, p[1] * scale, p[2] * scale]);
                    uv.push(None);
                }
                Some("vt") => {
                    let t = numbers(words, 2, line, "vt")?;
                    texture.push([t[0], t[1]]);
                }
                Some("f") => {
                    let mut corners = Vec::new();
                    for w in words {
                        let mut parts = w.split('/');
                        let v = index(parts.next().unwrap_or(""), positions.len(), line, "vertex")?;
                        match parts.next().filter(|s| !s.is_empty()) {
                            Some(t) => {
                                let t = texture[index(t, texture.len(), line, "texture")?];
                                match uv[v] {
                                    Some(old) if old != t => {
                                        uv_problem.get_or_insert(format!(
                                            "vertex {} has two texture coordinates (line {line}): the sheet is cut open in (u, v)",
                                            v + 1
                                        ));
                                    }
                                    _ => uv[v] = Some(t),
                                }
                            }
                            None => {
                                uv_problem.get_or_insert(format!(
                                    "the face at line {line} has no texture coordinates"
                                ));
                            }
                        }
                        corners.push(v);
                    }
                    if corners.len() < 3 {
                        return Err(ObjError {
                            line: Some(line),
                            message: "a face needs at least three corners".into(),
                        });
                    }
                    for i in 1..corners.len() - 1 {
                        triangles.push([corners[0], corners[i], corners[i + 1]]);
                    }
                }
                _ => {}
            }
        }
        if triangles.is_empty() {
            return Err(ObjError {
                line: None,
                message: "no faces (f lines): a shape is a surface".into(),
            });
        }
        let uv = match uv_problem {
            Some(p) => Err(p),
            None if texture.is_empty() => Err("the file has no texture coordinates (vt)".into()),
            None => Ok(uv.into_iter().map(|t| t.unwrap_or([f64::NAN; 2])).collect()),
        };
        Ok(Self {
            positions,
            uv,
            triangles,
        })
    }

    /// OBJ text (metres): `v`, `vt` when there are material coordinates, `f` triangles.
    pub fn obj(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        for p in &self.positions {
            let _ = writeln!(s, "v {:?} {:?} {:?}", p[0], p[1], p[2]);
        }
        let uv = self.uv.as_ref().ok();
        for t in uv.into_iter().flatten() {
            let _ = writeln!(s, "vt {:?} {:?}", t[0], t[1]);
        }
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| i + 1);
            if uv.is_some() {
                let _ = writeln!(s, "f {a}/{a} {b}/{b} {c}/{c}");
            } else {
                let _ = writeln!(s, "f {a} {b} {c}");
            }
        }
        s
    }

    /// The square root of the smallest eigenvalue of the vertices' covariance: how far the
    /// surface spreads across its thinnest direction (the wrinkle or fold amplitude of a sheet).
    pub fn thinnest_spread(&self) -> f64 {
        let n = self.positions.len().max(1) as f64;
        let mut mean = [0.0; 3];
        for p in &self.positions {
            (0..3).for_each(|k| mean[k] += p[k] / n);
        }
        let mut c = nalgebra::Matrix3::<f64>::zeros();
        for p in &self.positions {
            let d = nalgebra::Vector3::new(p[0] - mean[0], p[1] - mean[1], p[2] - mean[2]);
            c += d * d.transpose() / n;
        }
        c.symmetric_eigenvalues().min().max(0.0).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_obj_square_reads_as_two_triangles_with_its_texture() {
        let text = "# a square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1 -1/-1/1\n";
        let m = ShapeMesh::from_obj(text, 1e-3).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.positions[2], [1e-3, 1e-3, 0.0]);
        assert_eq!(m.uv.unwrap()[3], [0.0, 1.0]);
    }

    #[test]
    fn bad_obj_lines_are_located() {
        let e = ShapeMesh::from_obj("v 0 0 0\nv 1 0 0\nf 1 2 7\n", 1.0).unwrap_err();
        assert_eq!(e.line, Some(3));
        assert!(e.message.contains("index 7"), "{}", e.message);
        let e = ShapeMesh::from_obj("v 0 0\n", 1.0).unwrap_err();
        assert_eq!(e.line, Some(1));
        let e = ShapeMesh::from_obj("v 0 0 0\n", 1.0).unwrap_err();
        assert!(e.message.contains("no faces"));
        // without vt the shape still reads: positions work, the FFT says why it cannot
        let m = ShapeMesh::from_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 1.0).unwrap();
        assert!(m.uv.unwrap_err().contains("no texture"));
    }

    #[test]
    fn the_thinnest_spread_of_a_tilted_wavy_sheet_is_its_amplitude() {
        // z = a cos(2π x) over a unit square (cell centres: z uncorrelated with x), then turned
        // about the x axis: the spread across the sheet is a/√2 whatever the turn
        let (n, a) = (40, 0.01);
        let t = 0.3f64;
        let mut m = ShapeMesh::default();
        for j in 0..n {
            for i in 0..n {
                let (x, y) = ((i as f64 + 0.5) / n as f64, j as f64 / n as f64);
                let z = a * (2.0 * std::f64::consts::PI * x).cos();
                m.positions
                    .push([x, y * t.cos() - z * t.sin(), y * t.sin() + z * t.cos()]);
            }
        }
        let s = m.thinnest_spread();
        assert!((s / (a / 2f64.sqrt()) - 1.0).abs() < 1e-9, "{s}");
    }
}
