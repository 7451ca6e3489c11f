//! Control meshes: what the subdivision basis is built on.
//!
//! A [`PolyMesh`] is the cage as read from a file or built by a scene: positions plus faces given
//! as counter-clockwise vertex loops. [`Topology`] checks that the cage is a manifold surface
//! (every edge in one or two faces, consistently oriented; every vertex a single fan) and records
//! what the limit basis needs: edge–face incidence, boundary edges, vertex valences.
//!
//! The Catmull–Clark basis works on quads. A cage with triangles or n-gons is turned into an
//! all-quad cage by one uniform Catmull–Clark step ([`crate::subdiv::refine_uniform`]); this keeps
//! the limit surface unchanged (it is the same subdivision surface) and is what the CLI does.

mod grid;
mod obj;
pub mod shapes;

pub use grid::{graded_grid, rectangular_grid, Grading};
pub use obj::{parse_obj, read_obj, write_obj, ObjError, ObjMesh, MAX_OBJ_BYTES};

use crate::Vec3;
use std::collections::HashMap;

/// Sentinel for "no face" in edge–face incidence.
pub const NO_FACE: u32 = u32::MAX;

/// A polygonal control mesh. Faces are vertex loops, counter-clockwise seen from the side the
/// surface normal points to.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PolyMesh {
    pub positions: Vec<Vec3>,
    pub faces: Vec<Vec<u32>>,
}

impl PolyMesh {
    pub fn new(positions: Vec<Vec3>, faces: Vec<Vec<u32>>) -> Self {
        Self { positions, faces }
    }

    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    pub fn num_faces(&self) -> usize {
        self.faces.len()
    }

    /// True when every face has four corners.
    pub fn is_all_quads(&self) -> bool {
        self.faces.iter().all(|f| f.len() == 4)
    }
}

/// What is wrong with a cage's connectivity; `face` is the 0-based index of the face whose
/// insertion revealed the problem (the OBJ reader turns it into a file line).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct TopologyError {
    pub face: Option<usize>,
    pub message: String,
}

impl TopologyError {
    fn at(face: usize, message: String) -> Self {
        Self {
            face: Some(face),
            message,
        }
    }
}

/// Edge and vertex incidence of a manifold polygon mesh.
#[derive(Clone, Debug)]
pub struct Topology {
    /// Undirected edges as (smaller, larger) vertex index.
    pub edges: Vec<[u32; 2]>,
    /// The one or two faces on each edge (`NO_FACE` in the second slot on a boundary).
    pub edge_faces: Vec<[u32; 2]>,
    /// `face_edges[f][k]` is the edge from corner k to corner k+1 of face f.
    pub face_edges: Vec<Vec<u32>>,
    /// Faces around each vertex (unordered).
    pub vertex_faces: Vec<Vec<u32>>,
    /// Number of edges at each vertex.
    pub valence: Vec<u32>,
    /// Whether a vertex lies on a boundary edge.
    pub on_boundary: Vec<bool>,
    edge_index: HashMap<(u32, u32), u32>,
}

/// Checks that face `fi` has at least three corners, each a vertex of the mesh (`nv` of them),
/// none used twice.
fn check_face(fi: usize, face: &[u32], nv: usize) -> Result<(), TopologyError> {
    if face.len() < 3 {
        return Err(TopologyError::at(
            fi,
            format!(
                "face {fi} has {} corners; a face needs at least 3",
                face.len()
            ),
        ));
    }
    for (k, &v) in face.iter().enumerate() {
        if v as usize >= nv {
            return Err(TopologyError::at(
                fi,
                format!(
                    "face {fi} uses vertex {} but the mesh has {nv} vertices",
                    v + 1
                ),
            ));
        }
        if face[..k].contains(&v) {
            return Err(TopologyError::at(
                fi,
                format!("face {fi} uses vertex {} twice", v + 1),
            ));
        }
    }
    Ok(())
}

/// The edges met so far while walking the faces, each with its faces and the direction its
/// first face runs along it.
#[derive(Default)]
struct EdgeBuilder {
    edge_index: HashMap<(u32, u32), u32>,
    edges: Vec<[u32; 2]>,
    edge_faces: Vec<[u32; 2]>,
    /// direction of the edge as seen by its first face: true when it runs small -> large
    first_dir: Vec<bool>,
}

impl EdgeBuilder {
    /// The edge from `a` to `b` of face `fi`: a new one, or the second face of one met earlier
    /// (running the other way, else the mesh is non-manifold or inconsistently oriented).
    fn add(&mut self, fi: usize, a: u32, b: u32) -> Result<u32, TopologyError> {
        let key = (a.min(b), a.max(b));
        let forward = a < b;
        Ok(match self.edge_index.get(&key) {
            None => {
                let e = self.edges.len() as u32;
                self.edge_index.insert(key, e);
                self.edges.push([key.0, key.1]);
                self.edge_faces.push([fi as u32, NO_FACE]);
                self.first_dir.push(forward);
                e
            }
            Some(&e) => {
                let slot = &mut self.edge_faces[e as usize];
                if slot[1] != NO_FACE {
                    return Err(TopologyError::at(
                        fi,
                        format!(
                            "non-manifold edge: vertices {} and {} are shared by more than two faces",
                            key.0 + 1,
                            key.1 + 1
                        ),
                    ));
                }
                if slot[0] == fi as u32 {
                    return Err(TopologyError::at(
                        fi,
                        format!("face {fi} uses the edge {}-{} twice", key.0 + 1, key.1 + 1),
                    ));
                }
                if self.first_dir[e as usize] == forward {
                    return Err(TopologyError::at(
                        fi,
                        format!(
                            "inconsistent orientation: face {fi} runs along edge {}-{} in the same direction as face {}",
                            a + 1,
                            b + 1,
                            slot[0]
                        ),
                    ));
                }
                slot[1] = fi as u32;
                e
            }
        })
    }
}

impl Topology {
    /// Builds incidence and checks that the mesh is a consistently oriented 2-manifold, possibly
    /// with boundary. Vertices used by no face are allowed (they carry no surface) and reported
    /// by [`Topology::isolated_vertices`].
    pub fn build(mesh: &PolyMesh) -> Result<Self, TopologyError> {
        let nv = mesh.positions.len();
        let mut builder = EdgeBuilder::default();
        let mut face_edges = Vec::with_capacity(mesh.faces.len());
        let mut vertex_faces = vec![Vec::new(); nv];

        for (fi, face) in mesh.faces.iter().enumerate() {
            check_face(fi, face, nv)?;
            let mut fe = Vec::with_capacity(face.len());
            for k in 0..face.len() {
                let a = face[k];
                let b = face[(k + 1) % face.len()];
                let e = builder.add(fi, a, b)?;
                fe.push(e);
                vertex_faces[a as usize].push(fi as u32);
            }
            face_edges.push(fe);
        }
        let EdgeBuilder {
            edge_index,
            edges,
            edge_faces,
            ..
        } = builder;

        let mut valence = vec![0u32; nv];
        let mut boundary_edges_at = vec![0u32; nv];
        for (e, ends) in edges.iter().enumerate() {
            let boundary = edge_faces[e][1] == NO_FACE;
            for &v in ends {
                valence[v as usize] += 1;
                if boundary {
                    boundary_edges_at[v as usize] += 1;
                }
            }
        }
        let topo = Self {
            edges,
            edge_faces,
            face_edges,
            vertex_faces,
            valence,
            on_boundary: boundary_edges_at.iter().map(|&n| n > 0).collect(),
            edge_index,
        };
        topo.check_fans(mesh, &boundary_edges_at)?;
        Ok(topo)
    }

    /// Vertex manifoldness: the faces around each vertex form one fan, with no or two boundary
    /// edges (`boundary_edges_at`).
    fn check_fans(&self, mesh: &PolyMesh, boundary_edges_at: &[u32]) -> Result<(), TopologyError> {
        let nv = mesh.positions.len();
        for v in 0..nv {
            let faces = &self.vertex_faces[v];
            if faces.is_empty() {
                continue;
            }
            let nb = boundary_edges_at[v];
            let fans = self.count_fans(mesh, v as u32);
            if fans != 1 || (nb != 0 && nb != 2) {
                let last = *faces.iter().max().unwrap_or(&0) as usize;
                return Err(TopologyError::at(
                    last,
                    format!(
                        "non-manifold vertex {}: its faces form {fans} separate fans",
                        v + 1
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Number of edge-connected groups among the faces around `v`.
    fn count_fans(&self, mesh: &PolyMesh, v: u32) -> usize {
        let faces = &self.vertex_faces[v as usize];
        let mut group: Vec<usize> = (0..faces.len()).collect();
        fn root(g: &mut [usize], mut i: usize) -> usize {
            while g[i] != i {
                g[i] = g[g[i]];
                i = g[i];
            }
            i
        }
        for (i, &f) in faces.iter().enumerate() {
            let face = &mesh.faces[f as usize];
            let k = face.iter().position(|&x| x == v).unwrap_or(0);
            // the two edges of face f at v
            for e in [
                self.face_edges[f as usize][k],
                self.face_edges[f as usize][(k + face.len() - 1) % face.len()],
            ] {
                let [f0, f1] = self.edge_faces[e as usize];
                let other = if f0 == f { f1 } else { f0 };
                if other == NO_FACE {
                    continue;
                }
                if let Some(j) = faces.iter().position(|&x| x == other) {
                    let (a, b) = (root(&mut group, i), root(&mut group, j));
                    group[a] = b;
                }
            }
        }
        (0..faces.len())
            .filter(|&i| root(&mut group, i) == i)
            .count()
    }

    /// Index of the edge between two vertices, if there is one.
    pub fn edge_between(&self, a: u32, b: u32) -> Option<u32> {
        self.edge_index.get(&(a.min(b), a.max(b))).copied()
    }

    pub fn is_boundary_edge(&self, e: u32) -> bool {
        self.edge_faces[e as usize][1] == NO_FACE
    }

    pub fn num_boundary_edges(&self) -> usize {
        self.edge_faces.iter().filter(|f| f[1] == NO_FACE).count()
    }

    /// Vertices that belong to no face.
    pub fn isolated_vertices(&self) -> usize {
        self.vertex_faces.iter().filter(|f| f.is_empty()).count()
    }
}
