//! One Catmull–Clark refinement step on a (possibly partial) cage.
//!
//! The same rules serve two purposes:
//! * uniform refinement of a whole mesh, on positions ([`refine_uniform`]);
//! * *local symbolic* refinement around an extraordinary vertex, where each "point" is a dense
//!   weight vector over the control points of a small neighbourhood, so that refining composes the
//!   subdivision matrices exactly.
//!
//! A local neighbourhood is cut out of a larger surface, so some of its points lack neighbours
//! that the rules need. The cage tracks this: a vertex is `complete` when every face of the true
//! surface around it belongs to the cage, and an edge with one face is a true boundary only if it
//! is listed in `boundary`; otherwise it is a cut. A refined point whose rule would reach past a
//! cut is marked invalid (`None`), and using an invalid point is an error, never a silent result.
//!
//! Rules (Catmull & Clark 1978, with the usual boundary rules, as OpenSubdiv's
//! `VTX_BOUNDARY_EDGE_AND_CORNER`):
//! * face point: centroid of the face's corners;
//! * interior edge point: (a + b + f₀ + f₁)/4 with f₀, f₁ the adjacent face points;
//!   boundary edge point: (a + b)/2;
//! * interior vertex of valence n: (Q + 2R + (n−3)v)/n, Q the mean of adjacent face points,
//!   R the mean of incident edge midpoints;
//!   boundary vertex with two or more faces: (b₀ + 6v + b₁)/8 along the boundary;
//!   corner (one face): v stays.
//!
//! Refined numbering: vertex points keep their vertex index, then one point per edge, then one per
//! face. Face f with corners c₀…c_{n−1} becomes n quads, the k-th being
//! [vertex(c_k), edge(c_k, c_{k+1}), face(f), edge(c_{k−1}, c_k)], numbered from the running sum of
//! corner counts (4f + k on an all-quad cage).

use crate::mesh::{PolyMesh, Topology};
use std::collections::{HashMap, HashSet};

/// Points that refinement can combine linearly.
pub(crate) trait Affine: Clone {
    fn zero_like(&self) -> Self;
    fn add_scaled(&mut self, a: f64, x: &Self);
}

impl Affine for [f64; 3] {
    fn zero_like(&self) -> Self {
        [0.0; 3]
    }
    fn add_scaled(&mut self, a: f64, x: &Self) {
        for k in 0..3 {
            self[k] += a * x[k];
        }
    }
}

impl Affine for Vec<f64> {
    fn zero_like(&self) -> Self {
        vec![0.0; self.len()]
    }
    fn add_scaled(&mut self, a: f64, x: &Self) {
        for (s, xi) in self.iter_mut().zip(x) {
            *s += a * xi;
        }
    }
}

/// Σ aᵢ pᵢ, or `None` if any input is invalid.
fn combine<T: Affine>(terms: &[(f64, &Option<T>)]) -> Option<T> {
    let first = terms.first()?.1.as_ref()?;
    let mut acc = first.zero_like();
    for (a, p) in terms {
        acc.add_scaled(*a, p.as_ref()?);
    }
    Some(acc)
}

/// Undirected edge key.
pub(crate) fn edge_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// A piece of a subdivision surface's control cage; see the module docs.
#[derive(Clone, Debug)]
pub(crate) struct Cage<T> {
    pub points: Vec<Option<T>>,
    pub faces: Vec<Vec<u32>>,
    pub complete: Vec<bool>,
    pub boundary: HashSet<(u32, u32)>,
}

/// Incidence inside a cage.
pub(crate) struct CageAdjacency {
    /// Directed edge (a, b) → the face that runs from a to b.
    pub directed: HashMap<(u32, u32), u32>,
    pub vertex_faces: Vec<Vec<u32>>,
    /// Number of true boundary edges at each vertex.
    pub boundary_edges: Vec<u8>,
}

/// The undirected edges of a cage and the incidences a refinement step needs.
struct CageEdges {
    edge_id: HashMap<(u32, u32), u32>,
    /// (a, b) with a < b (see `edge_key`), in order of first appearance
    edges: Vec<(u32, u32)>,
    edge_faces: Vec<Vec<u32>>,
    vertex_faces: Vec<Vec<u32>>,
    vertex_edges: Vec<Vec<u32>>,
}

impl<T: Affine> Cage<T> {
    pub fn adjacency(&self) -> CageAdjacency {
        let n = self.points.len();
        let mut directed = HashMap::with_capacity(4 * self.faces.len());
        let mut vertex_faces = vec![Vec::new(); n];
        for (fi, f) in self.faces.iter().enumerate() {
            for k in 0..f.len() {
                directed.insert((f[k], f[(k + 1) % f.len()]), fi as u32);
                vertex_faces[f[k] as usize].push(fi as u32);
            }
        }
        let mut boundary_edges = vec![0u8; n];
        for &(a, b) in &self.boundary {
            if directed.contains_key(&(a, b)) || directed.contains_key(&(b, a)) {
                boundary_edges[a as usize] += 1;
                boundary_edges[b as usize] += 1;
            }
        }
        CageAdjacency {
            directed,
            vertex_faces,
            boundary_edges,
        }
    }

    /// One Catmull–Clark step over every face of the cage.
    pub fn refine(&self) -> Cage<T> {
        let edges = self.edges();
        let face_pts = self.face_points();
        let edge_pts = self.edge_points(&edges, &face_pts);
        let vertex_pts = self.vertex_points(&edges, &face_pts);
        let faces = self.refined_faces(&edges);
        let (complete, boundary) = self.refined_flags(&edges);
        let mut points = vertex_pts;
        points.extend(edge_pts);
        points.extend(face_pts);
        Cage {
            points,
            faces,
            complete,
            boundary,
        }
    }

    /// The cage's undirected edges with their faces, in order of first appearance, and the
    /// faces and edges around each vertex.
    fn edges(&self) -> CageEdges {
        let nv = self.points.len();
        // undirected edges with their faces, in order of first appearance
        let mut edge_id: HashMap<(u32, u32), u32> = HashMap::new();
        let mut edges: Vec<(u32, u32)> = Vec::new();
        let mut edge_faces: Vec<Vec<u32>> = Vec::new();
        let mut vertex_faces = vec![Vec::new(); nv];
        let mut vertex_edges = vec![Vec::new(); nv];
        for (fi, f) in self.faces.iter().enumerate() {
            for k in 0..f.len() {
                let key = edge_key(f[k], f[(k + 1) % f.len()]);
                let e = *edge_id.entry(key).or_insert_with(|| {
                    edges.push(key);
                    edge_faces.push(Vec::new());
                    vertex_edges[key.0 as usize].push(edges.len() as u32 - 1);
                    vertex_edges[key.1 as usize].push(edges.len() as u32 - 1);
                    edges.len() as u32 - 1
                });
                edge_faces[e as usize].push(fi as u32);
                vertex_faces[f[k] as usize].push(fi as u32);
            }
        }
        CageEdges {
            edge_id,
            edges,
            edge_faces,
            vertex_faces,
            vertex_edges,
        }
    }

    /// The face points: each face's centroid.
    fn face_points(&self) -> Vec<Option<T>> {
        let p = &self.points;
        self.faces
            .iter()
            .map(|f| {
                let w = 1.0 / f.len() as f64;
                let terms: Vec<_> = f.iter().map(|&v| (w, &p[v as usize])).collect();
                combine(&terms)
            })
            .collect()
    }

    /// The edge points (`None` past a cut).
    fn edge_points(&self, e: &CageEdges, face_pts: &[Option<T>]) -> Vec<Option<T>> {
        let (edges, edge_faces) = (&e.edges, &e.edge_faces);
        let ne = edges.len();
        let p = &self.points;
        (0..ne)
            .map(|e| {
                let (a, b) = edges[e];
                let (pa, pb) = (&p[a as usize], &p[b as usize]);
                match edge_faces[e].as_slice() {
                    [f0, f1] => combine(&[
                        (0.25, pa),
                        (0.25, pb),
                        (0.25, &face_pts[*f0 as usize]),
                        (0.25, &face_pts[*f1 as usize]),
                    ]),
                    [_] if self.boundary.contains(&(a, b)) => combine(&[(0.5, pa), (0.5, pb)]),
                    _ => None,
                }
            })
            .collect()
    }

    /// The vertex points (`None` at an incomplete vertex).
    fn vertex_points(&self, e: &CageEdges, face_pts: &[Option<T>]) -> Vec<Option<T>> {
        let (edges, edge_faces) = (&e.edges, &e.edge_faces);
        let (vertex_faces, vertex_edges) = (&e.vertex_faces, &e.vertex_edges);
        let nv = self.points.len();
        let p = &self.points;
        (0..nv)
            .map(|v| {
                let pv = &p[v];
                if !self.complete[v] {
                    return None;
                }
                let faces = &vertex_faces[v];
                let inc = &vertex_edges[v];
                if faces.is_empty() {
                    return pv.clone();
                }
                let other = |e: u32| {
                    let (a, b) = edges[e as usize];
                    if a as usize == v {
                        b
                    } else {
                        a
                    }
                };
                let bnd: Vec<u32> = inc
                    .iter()
                    .copied()
                    .filter(|&e| edge_faces[e as usize].len() == 1)
                    .collect();
                if bnd.is_empty() {
                    let n = inc.len() as f64;
                    let mut terms = vec![(((n - 3.0) / n), pv)];
                    let wq = 1.0 / (n * faces.len() as f64);
                    for &f in faces {
                        terms.push((wq, &face_pts[f as usize]));
                    }
                    // 2R/n with R the mean of midpoints (v + w)/2: v gets 1/n in total.
                    terms.push((1.0 / n, pv));
                    let wr = 1.0 / (n * n);
                    for &e in inc {
                        terms.push((wr, &p[other(e) as usize]));
                    }
                    combine(&terms)
                } else if faces.len() == 1 {
                    pv.clone()
                } else {
                    // complete vertex: its single-face edges are true boundary edges (two of them)
                    let b0 = &p[other(bnd[0]) as usize];
                    let b1 = &p[other(bnd[bnd.len() - 1]) as usize];
                    combine(&[(0.125, b0), (0.75, pv), (0.125, b1)])
                }
            })
            .collect()
    }

    /// The refined faces: four quads per corner of each face, in the order of the points
    /// (vertex points, then edge points, then face points).
    fn refined_faces(&self, e: &CageEdges) -> Vec<Vec<u32>> {
        let (edge_id, ne) = (&e.edge_id, e.edges.len());
        let nv = self.points.len();
        let ep = |a: u32, b: u32| nv as u32 + edge_id[&edge_key(a, b)];
        let mut faces = Vec::with_capacity(4 * self.faces.len());
        for (fi, f) in self.faces.iter().enumerate() {
            let n = f.len();
            let fp = (nv + ne + fi) as u32;
            for k in 0..n {
                let c = f[k];
                let next = f[(k + 1) % n];
                let prev = f[(k + n - 1) % n];
                faces.push(vec![c, ep(c, next), fp, ep(prev, c)]);
            }
        }

        faces
    }

    /// Which refined points are complete, and the refined cage's true boundary edges.
    fn refined_flags(&self, e: &CageEdges) -> (Vec<bool>, HashSet<(u32, u32)>) {
        let (edges, edge_faces) = (&e.edges, &e.edge_faces);
        let ne = edges.len();
        let nv = self.points.len();
        let mut complete = self.complete.clone();
        complete
            .extend((0..ne).map(|e| edge_faces[e].len() == 2 || self.boundary.contains(&edges[e])));
        complete.extend(std::iter::repeat_n(true, self.faces.len()));

        let mut boundary = HashSet::new();
        for (e, &(a, b)) in edges.iter().enumerate() {
            if edge_faces[e].len() == 1 && self.boundary.contains(&(a, b)) {
                let m = nv as u32 + e as u32;
                boundary.insert(edge_key(a, m));
                boundary.insert(edge_key(m, b));
            }
        }

        (complete, boundary)
    }

    /// The cage made of every face that touches a corner of `face` (given in the vertex order
    /// wanted for it), with `face` as face 0 of the result.
    pub fn one_ring(&self, adj: &CageAdjacency, face_index: usize, face: &[u32]) -> Cage<T> {
        let ring = OneRing::gather(
            face_index as u32,
            face,
            |v| &adj.vertex_faces[v as usize],
            |f| &self.faces[f as usize],
        );
        let complete = ring
            .global
            .iter()
            .map(|&v| self.complete[v as usize] && ring.holds_all(&adj.vertex_faces[v as usize]))
            .collect();
        Cage {
            points: ring
                .global
                .iter()
                .map(|&v| self.points[v as usize].clone())
                .collect(),
            complete,
            boundary: ring.local_edges(&self.boundary),
            faces: ring.faces,
        }
    }
}

/// The faces around a face (every face touching one of its corners, the face itself first),
/// renumbered locally.
pub(crate) struct OneRing {
    /// Selected faces, by index in the source.
    pub selected: Vec<u32>,
    /// Source index of each local vertex.
    pub global: Vec<u32>,
    local: HashMap<u32, u32>,
    /// The selected faces in local vertex indices.
    pub faces: Vec<Vec<u32>>,
}

impl OneRing {
    /// Gathers the ring of `face` (its corners in the order wanted for local face 0).
    pub fn gather<'a>(
        face_index: u32,
        face: &[u32],
        vertex_faces: impl Fn(u32) -> &'a [u32],
        face_corners: impl Fn(u32) -> &'a [u32],
    ) -> Self {
        let mut selected = vec![face_index];
        for &v in face {
            for &f in vertex_faces(v) {
                if !selected.contains(&f) {
                    selected.push(f);
                }
            }
        }
        let mut local: HashMap<u32, u32> = HashMap::new();
        let mut global = Vec::new();
        let faces = selected
            .iter()
            .enumerate()
            .map(|(i, &f)| {
                let src = if i == 0 { face } else { face_corners(f) };
                src.iter()
                    .map(|&v| {
                        *local.entry(v).or_insert_with(|| {
                            global.push(v);
                            global.len() as u32 - 1
                        })
                    })
                    .collect()
            })
            .collect();
        Self {
            selected,
            global,
            local,
            faces,
        }
    }

    /// Whether every one of `faces` is in the ring.
    pub fn holds_all(&self, faces: &[u32]) -> bool {
        faces.iter().all(|f| self.selected.contains(f))
    }

    /// The edges of `edges` (source indices) between ring vertices, in local indices.
    pub fn local_edges(&self, edges: &HashSet<(u32, u32)>) -> HashSet<(u32, u32)> {
        edges
            .iter()
            .filter_map(|&(a, b)| Some(edge_key(*self.local.get(&a)?, *self.local.get(&b)?)))
            .collect()
    }
}

/// One uniform Catmull–Clark step on a whole mesh. Any polygons in, quads out; the limit surface
/// is unchanged. Vertex i of the input is vertex i of the output.
pub fn refine_uniform(mesh: &PolyMesh, topology: &Topology) -> PolyMesh {
    let cage = Cage {
        points: mesh.positions.iter().map(|&p| Some(p)).collect(),
        faces: mesh.faces.clone(),
        complete: vec![true; mesh.positions.len()],
        boundary: topology
            .edges
            .iter()
            .enumerate()
            .filter(|&(e, _)| topology.is_boundary_edge(e as u32))
            .map(|(_, &[a, b])| (a, b))
            .collect(),
    };
    let fine = cage.refine();
    PolyMesh::new(
        fine.points
            .into_iter()
            .map(|p| p.expect("every point of a whole mesh is complete"))
            .collect(),
        fine.faces,
    )
}
