//! Wavefront OBJ input and output for control meshes.
//!
//! Read: `v x y z [w]` and `f i j k ...` lines (`i`, `i/t`, `i//n`, `i/t/n`; negative indices count
//! back from the last vertex read), `#` comments. Texture coordinates, normals, groups and
//! materials are ignored. Every error names the file and the line.

use super::{PolyMesh, Topology, TopologyError};
use std::fmt;
use std::path::Path;

/// A mesh as read from an OBJ file, with the line each face came from.
#[derive(Clone, Debug)]
pub struct ObjMesh {
    pub mesh: PolyMesh,
    pub topology: Topology,
    /// 1-based line number of each face's `f` line.
    pub face_lines: Vec<usize>,
}

/// A problem with a mesh file, always naming the file and, where it applies, the line.
#[derive(Debug, thiserror::Error)]
pub struct ObjError {
    pub path: String,
    pub line: Option<usize>,
    pub message: String,
}

impl fmt::Display for ObjError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{}: {}", self.path, line, self.message),
            None => write!(f, "{}: {}", self.path, self.message),
        }
    }
}

/// Largest vertex coordinate accepted: products of coordinates (metrics, curvatures) stay far
/// from overflow.
pub const MAX_COORDINATE: f64 = 1e100;

/// Largest OBJ file read (a 100 000-face quad mesh is about 5 MB).
pub const MAX_OBJ_BYTES: u64 = 1 << 30;

/// Reads and checks an OBJ file.
pub fn read_obj(path: &Path) -> Result<ObjMesh, ObjError> {
    let name = path.display().to_string();
    let text = crate::io::read_text(path, MAX_OBJ_BYTES).map_err(|e| ObjError {
        path: name.clone(),
        line: None,
        message: format!("cannot read file: {e}"),
    })?;
    parse_obj(&text, &name)
}

/// Parses OBJ text; `name` is used in error messages.
pub fn parse_obj(text: &str, name: &str) -> Result<ObjMesh, ObjError> {
    let err = |line: usize, message: String| ObjError {
        path: name.to_string(),
        line: Some(line),
        message,
    };
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    let mut face_lines = Vec::new();
    // a UTF-8 byte-order mark is not part of the first line's first word
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    for (i, raw) in text.lines().enumerate() {
        let lineno = i + 1;
        let line = raw.split('#').next().unwrap_or("").trim();
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => positions.push(parse_vertex(&mut words, lineno, &err)?),
            Some("f") => {
                let face = parse_face(words, lineno, positions.len(), &err)?;
                faces.push(face);
                face_lines.push(lineno);
            }
            _ => {}
        }
    }
    if faces.is_empty() {
        return Err(ObjError {
            path: name.to_string(),
            line: None,
            message: if positions.is_empty() {
                "empty mesh: no vertices and no faces".into()
            } else {
                "no faces: the file defines vertices only".into()
            },
        });
    }
    for (face, &line) in faces.iter().zip(&face_lines) {
        if let Some(&bad) = face.iter().find(|&&v| v as usize >= positions.len()) {
            return Err(err(
                line,
                format!(
                    "vertex index {} out of range (the file defines {} vertices)",
                    bad + 1,
                    positions.len()
                ),
            ));
        }
    }
    let mesh = PolyMesh::new(positions, faces);
    let topology = Topology::build(&mesh).map_err(|TopologyError { face, message }| ObjError {
        path: name.to_string(),
        line: face.map(|f| face_lines[f]),
        message,
    })?;
    Ok(ObjMesh {
        mesh,
        topology,
        face_lines,
    })
}

/// The coordinates of a `v` line (`words` after the `v`).
fn parse_vertex<'a>(
    words: &mut impl Iterator<Item = &'a str>,
    lineno: usize,
    err: &impl Fn(usize, String) -> ObjError,
) -> Result<[f64; 3], ObjError> {
    let mut xyz = [0.0; 3];
    for (k, c) in xyz.iter_mut().enumerate() {
        let w = words
            .next()
            .ok_or_else(|| err(lineno, format!("vertex needs 3 coordinates, found {k}")))?;
        *c = w
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| err(lineno, format!("bad vertex coordinate '{w}'")))?;
        if c.abs() > MAX_COORDINATE {
            return Err(err(
                lineno,
                format!("vertex coordinate {w} is larger than {MAX_COORDINATE:e} in magnitude (the surface's derivatives would overflow)"),
            ));
        }
    }
    Ok(xyz)
}

/// The 0-based vertex indices of an `f` line (`words` after the `f`), `count` vertices read so
/// far.
fn parse_face<'a>(
    words: impl Iterator<Item = &'a str>,
    lineno: usize,
    count: usize,
    err: &impl Fn(usize, String) -> ObjError,
) -> Result<Vec<u32>, ObjError> {
    let mut face = Vec::new();
    for w in words {
        let idx = w.split('/').next().unwrap_or("");
        let n: i64 = idx
            .parse()
            .map_err(|_| err(lineno, format!("bad vertex index '{w}'")))?;
        // negative indices count back from the vertices read so far; positive
        // ones may refer forward and are checked once the whole file is read
        let resolved = if n > 0 {
            n - 1
        } else if n < 0 {
            let count = count as i64;
            if count + n < 0 {
                return Err(err(
                    lineno,
                    format!("vertex index {n} out of range ({count} vertices defined so far)"),
                ));
            }
            count + n
        } else {
            return Err(err(
                lineno,
                "vertex index 0 (OBJ indices start at 1)".into(),
            ));
        };
        let resolved = u32::try_from(resolved).map_err(|_| {
            err(
                lineno,
                format!(
                    "vertex index {n} is beyond the {} vertices a mesh may have",
                    u32::MAX
                ),
            )
        })?;
        face.push(resolved);
    }
    if face.len() < 3 {
        return Err(err(
            lineno,
            format!("face has {} vertices; a face needs at least 3", face.len()),
        ));
    }
    Ok(face)
}

/// Writes a mesh as OBJ text (1-based indices, full precision).
pub fn write_obj(mesh: &PolyMesh, header: &str) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    for line in header.lines() {
        let _ = writeln!(out, "# {line}");
    }
    for p in &mesh.positions {
        let _ = writeln!(out, "v {:?} {:?} {:?}", p[0], p[1], p[2]);
    }
    for f in &mesh.faces {
        out.push('f');
        for v in f {
            let _ = write!(out, " {}", v + 1);
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_negative_indices_and_slashes() {
        let text = "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4/1 -3//2 -2/3/3 -1\n";
        let m = parse_obj(text, "t.obj").unwrap();
        assert_eq!(m.mesh.faces, vec![vec![0, 1, 2, 3]]);
        assert_eq!(m.face_lines, vec![6]);
        assert_eq!(m.topology.num_boundary_edges(), 4);
    }

    #[test]
    fn errors_name_file_and_line() {
        let cases = [
            ("v 0 0 0\nv 1 x 0\n", "t.obj:2: bad vertex coordinate 'x'"),
            (
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 7\n",
                "t.obj:4: vertex index 7 out of range",
            ),
            ("", "t.obj: empty mesh"),
            ("v 0 0 0\n", "t.obj: no faces"),
            ("v 0 0 0\nv 1 0 0\nf 1 2\n", "t.obj:3: face has 2 vertices"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 1 1 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
                "t.obj:8: non-manifold edge",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nf 1 2 3\nf 1 2 4\n",
                "t.obj:6: inconsistent orientation",
            ),
        ];
        for (text, want) in cases {
            let got = parse_obj(text, "t.obj").unwrap_err().to_string();
            assert!(got.starts_with(want), "{got:?} should start with {want:?}");
        }
    }

    #[test]
    fn positive_indices_may_refer_forward() {
        let m = parse_obj("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", "t.obj").unwrap();
        assert_eq!(m.mesh.faces, vec![vec![0, 1, 2]]);
    }

    #[test]
    fn bowtie_vertex_is_rejected() {
        // two triangles touching at vertex 1 only
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv -1 0 0\nv 0 -1 0\nf 1 2 3\nf 1 4 5\n";
        let e = parse_obj(text, "t.obj").unwrap_err().to_string();
        assert!(e.contains("non-manifold vertex 1"), "{e}");
    }

    #[test]
    fn write_then_read_round_trips() {
        let mesh = super::super::rectangular_grid(2.0, 3.0, 2, 3);
        let text = write_obj(&mesh, "grid");
        let back = parse_obj(&text, "g.obj").unwrap();
        assert_eq!(back.mesh, mesh);
    }
}
