//! Triangle meshes to draw, read from written shapes: Wavefront OBJ `v`, `vt` and `f` lines
//! (`i`, `i/t`, `i//n`, `i/t/n`, negative indices from the end), polygons split as fans. Normals
//! are recomputed from the geometry (area-weighted, per position), so any OBJ draws alike.
//! Every error names the file and the line.

use crate::mesh::{ObjError, MAX_OBJ_BYTES};
use crate::scene::export::SurfaceMesh;
use crate::Vec3;
use std::collections::HashMap;
use std::path::Path;

/// Vertices (position, unit normal, texture coordinate when the file has them) and triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// Metres of fabric, u along the warp, v along the weft (ks-fit's shapes); None draws the
    /// cloth without yarn lines.
    pub uv: Option<Vec<[f64; 2]>>,
    pub triangles: Vec<[u32; 3]>,
}

/// Reads an OBJ shape.
pub fn read_shape(path: &Path) -> Result<RenderMesh, ObjError> {
    let name = path.display().to_string();
    let text = crate::io::read_text(path, MAX_OBJ_BYTES).map_err(|e| ObjError {
        path: name.clone(),
        line: None,
        message: format!("cannot read file: {e}"),
    })?;
    parse_shape(&text, &name)
}

fn index(tok: &str, count: usize, what: &str) -> Result<usize, String> {
    let i: i64 = tok
        .parse()
        .map_err(|_| format!("{what} index {tok:?} is not an integer"))?;
    let j = if i < 0 { count as i64 + i } else { i - 1 };
    if i == 0 || j < 0 || j >= count as i64 {
        return Err(format!(
            "{what} index {i} is out of range ({count} read so far)"
        ));
    }
    Ok(j as usize)
}

/// Parses OBJ text; `name` is used in error messages.
pub fn parse_shape(text: &str, name: &str) -> Result<RenderMesh, ObjError> {
    let err = |line: usize, message: String| ObjError {
        path: name.to_string(),
        line: Some(line),
        message,
    };
    let mut v: Vec<Vec3> = Vec::new();
    let mut vt: Vec<[f64; 2]> = Vec::new();
    let mut corners: HashMap<(usize, Option<usize>), u32> = HashMap::new();
    let mut out = RenderMesh::default();
    let mut pos_of: Vec<usize> = Vec::new();
    let mut uv: Vec<Option<[f64; 2]>> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let n = n + 1;
        let line = line.split('#').next().unwrap_or("");
        let mut tok = line.split_whitespace();
        match tok.next() {
            Some("v") => {
                let c: Vec<f64> = tok.take(3).map(|t| t.parse().unwrap_or(f64::NAN)).collect();
                if c.len() < 3 || c.iter().any(|x| !x.is_finite()) {
                    return Err(err(n, "a `v` line needs three finite numbers".into()));
                }
                v.push([c[0], c[1], c[2]]);
            }
            Some("vt") => {
                let c: Vec<f64> = tok.take(2).map(|t| t.parse().unwrap_or(f64::NAN)).collect();
                if c.len() < 2 || c.iter().any(|x| !x.is_finite()) {
                    return Err(err(n, "a `vt` line needs two finite numbers".into()));
                }
                vt.push([c[0], c[1]]);
            }
            Some("f") => {
                let mut ids = Vec::new();
                for t in tok {
                    let mut parts = t.split('/');
                    let p = index(parts.next().unwrap_or(""), v.len(), "vertex")
                        .map_err(|m| err(n, m))?;
                    let t = match parts.next() {
                        Some(s) if !s.is_empty() => {
                            Some(index(s, vt.len(), "texture").map_err(|m| err(n, m))?)
                        }
                        _ => None,
                    };
                    let id = *corners.entry((p, t)).or_insert_with(|| {
                        pos_of.push(p);
                        uv.push(t.map(|t| vt[t]));
                        (pos_of.len() - 1) as u32
                    });
                    ids.push(id);
                }
                if ids.len() < 3 {
                    return Err(err(n, "a face needs at least three vertices".into()));
                }
                for k in 1..ids.len() - 1 {
                    out.triangles.push([ids[0], ids[k], ids[k + 1]]);
                }
            }
            _ => {}
        }
    }
    if out.triangles.is_empty() {
        return Err(ObjError {
            path: name.to_string(),
            line: None,
            message: "no faces: nothing to draw".into(),
        });
    }
    let mut normal_of = vec![[0.0; 3]; v.len()];
    let mut twice_area = 0.0;
    for t in &out.triangles {
        let [a, b, c] = t.map(|i| v[pos_of[i as usize]]);
        let (e, f) = (sub(b, a), sub(c, a));
        let nrm = [
            e[1] * f[2] - e[2] * f[1],
            e[2] * f[0] - e[0] * f[2],
            e[0] * f[1] - e[1] * f[0],
        ];
        twice_area += norm(nrm);
        for &i in t {
            let s = &mut normal_of[pos_of[i as usize]];
            for c in 0..3 {
                s[c] += nrm[c];
            }
        }
    }
    let used: Vec<Vec3> = pos_of.iter().map(|&p| v[p]).collect();
    if let Some(why) = degenerate(&used, 0.5 * twice_area) {
        return Err(ObjError {
            path: name.to_string(),
            line: None,
            message: format!("{why}: nothing to draw"),
        });
    }
    out.positions = used;
    out.normals = pos_of.iter().map(|&p| unit(normal_of[p])).collect();
    out.uv = uv.iter().copied().collect::<Option<Vec<_>>>();
    Ok(out)
}

/// Smallest total face area of a shape worth drawing, relative to the square of its
/// bounding-box diagonal: below it the faces are lines or points, and the picture is blank.
const MIN_AREA_FRACTION: f64 = 1e-12;

/// Why the faces' corners `p` with total face area `area` draw nothing, if they do not: every
/// corner at one point, or faces of no area (corners on a line).
fn degenerate(p: &[Vec3], area: f64) -> Option<&'static str> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for q in p {
        for c in 0..3 {
            lo[c] = lo[c].min(q[c]);
            hi[c] = hi[c].max(q[c]);
        }
    }
    let diagonal = norm(sub(hi, lo));
    if diagonal == 0.0 {
        return Some("the shape has zero size (every face's corners at one point)");
    }
    if diagonal.is_finite() && area <= MIN_AREA_FRACTION * diagonal * diagonal {
        return Some("the shape's faces have zero area (their corners lie on a line)");
    }
    None
}

fn norm(a: Vec3) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn unit(a: Vec3) -> Vec3 {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if l > 0.0 {
        [a[0] / l, a[1] / l, a[2] / l]
    } else {
        [0.0, 0.0, 1.0]
    }
}

impl From<&SurfaceMesh> for RenderMesh {
    fn from(s: &SurfaceMesh) -> Self {
        Self {
            positions: s.positions.clone(),
            normals: s.normals.clone(),
            uv: Some(s.uv.clone()),
            triangles: s
                .quads
                .iter()
                .flat_map(|q| {
                    let q = q.map(|i| i as u32);
                    [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quads_with_texture_become_triangles_with_normals() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n";
        let m = parse_shape(text, "sq.obj").unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.normals[2], [0.0, 0.0, 1.0]);
        assert_eq!(m.uv.as_ref().unwrap()[2], [1.0, 1.0]);
    }

    #[test]
    fn errors_name_the_file_and_line() {
        let e = parse_shape("v 0 0 0\nv 1 0 0\nf 1 2 7\n", "bad.obj").unwrap_err();
        assert_eq!(
            e.to_string(),
            "bad.obj:3: vertex index 7 is out of range (2 read so far)"
        );
        let e = parse_shape("v 0 0\n", "short.obj").unwrap_err();
        assert!(e.to_string().starts_with("short.obj:1:"));
        let e = parse_shape("v 0 0 0\n", "none.obj").unwrap_err();
        assert_eq!(e.to_string(), "none.obj: no faces: nothing to draw");
        // without texture coordinates on every corner, no yarn lines
        let m = parse_shape("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n", "t.obj").unwrap();
        assert!(m.uv.is_none());
    }

    #[test]
    fn shapes_without_area_are_refused() {
        let e = parse_shape("v 1 2 3\nv 1 2 3\nv 1 2 3\nf 1 2 3\n", "dot.obj").unwrap_err();
        assert_eq!(
            e.to_string(),
            "dot.obj: the shape has zero size (every face's corners at one point): nothing to draw"
        );
        let e = parse_shape("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "line.obj").unwrap_err();
        assert!(e.to_string().contains("zero area"), "{e}");
        // an unused far vertex does not make a point-sized face drawable
        let text = "v 0 0 0\nv 0 0 0\nv 0 0 0\nv 5 5 5\nf 1 2 3\n";
        assert!(parse_shape(text, "far.obj").is_err());
        // a tiny but real face draws
        let m = parse_shape("v 0 0 0\nv 1e-6 0 0\nv 0 1e-6 0\nf 1 2 3\n", "t.obj").unwrap();
        assert_eq!(m.triangles.len(), 1);
    }
}
