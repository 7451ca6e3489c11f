//! Exact evaluation of the Catmull–Clark limit surface as stencils over the control points.
//!
//! A face whose four corners are regular (interior valence 4, or on the boundary with one or two
//! faces) is a bicubic uniform B-spline patch over its 4 × 4 one-ring, where missing boundary
//! rows are phantom points P = 2·(boundary) − (interior) (the B-spline form of the standard
//! Catmull–Clark boundary rules). Any other face is refined locally: its one-ring is subdivided
//! symbolically (each point a weight vector over the original one-ring), the quadrant holding the
//! evaluation point is kept with its new one-ring, and this repeats until the point lies in a
//! regular sub-patch. That sub-patch's B-spline weights times the composed subdivision matrices
//! are the exact limit stencil: no end-cap approximation, and each face may hold any number of
//! extraordinary vertices (each quadrant holds at most one after the first step). A point at
//! depth d needs d ≈ log₂(1/max(u, v)) steps near the vertex; the 4 × 4 Gauss points need at most
//! four. Only the extraordinary vertex itself, where the parametric derivatives do not exist, is
//! refused.
//!
//! Parametrisation: on face (c₀, c₁, c₂, c₃), u runs from c₀ to c₁ and v from c₀ to c₃, both in
//! [0, 1] (the convention of OpenSubdiv and most subdivision libraries).

use super::bspline::bicubic_weights;
use super::cage::{edge_key, Cage, CageAdjacency, OneRing};
use super::ghost::add_ghost_layer;
use super::patch::{regular_patch, Neighbourhood, Recipe};
use crate::mesh::{PolyMesh, Topology, TopologyError};
use crate::Vec3;
use std::collections::HashSet;

/// How the surface is closed off along a free edge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BoundaryRule {
    /// Missing rows are extrapolated, P = 2·boundary − interior. The limit boundary is the cubic
    /// B-spline of the boundary vertices, with zero curvature across it; corners interpolate.
    #[default]
    Phantom,
    /// A layer of ghost control points outside every boundary edge is added to the unknowns
    /// (placed where the phantom rule would put them). Boundary faces then see ordinary interior
    /// stencils, and the ghosts' positions are free to carry a clamp's slope.
    Ghost,
}

impl std::str::FromStr for BoundaryRule {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "phantom" => Ok(Self::Phantom),
            "ghost" => Ok(Self::Ghost),
            _ => Err(format!(
                "unknown boundary rule '{s}' (expected phantom or ghost)"
            )),
        }
    }
}

/// What kind of patch a face of the user's mesh is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FaceKind {
    /// Four interior valence-4 corners: one bicubic B-spline patch.
    Regular,
    /// Regular corners, some on the boundary (valence 2 or 3 there): a B-spline patch with
    /// phantom points.
    Boundary,
    /// At least one extraordinary corner: exact evaluation by local refinement.
    Extraordinary,
}

/// Why a limit evaluation could not be done.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BasisError {
    #[error("face {face} has {corners} corners; the limit basis needs an all-quad mesh (refine it once first)")]
    NotQuad { face: usize, corners: usize },
    #[error("face {face} does not exist: the mesh has {faces} faces (indices start at 0)")]
    NoSuchFace { face: usize, faces: usize },
    #[error("(u, v) = ({u}, {v}) lies outside the face's parameter square [0, 1]²")]
    OutsideFace { u: f64, v: f64 },
    #[error("(u, v) = ({u}, {v}) on face {face} is (or lies within 1e-18 of) an extraordinary vertex, where the limit surface has no parametric derivatives; evaluate at a nearby point")]
    AtExtraordinaryVertex { face: usize, u: f64, v: f64 },
    #[error("{0}")]
    Topology(#[from] TopologyError),
}

/// Index of each derivative in a stencil's weight row.
pub mod deriv {
    pub const X: usize = 0;
    pub const XU: usize = 1;
    pub const XV: usize = 2;
    pub const XUU: usize = 3;
    pub const XUV: usize = 4;
    pub const XVV: usize = 5;
}

/// The limit surface at one point as weights over control points: row k of `weights` holds, for
/// control point `indices[k]`, its weight in [x, x_u, x_v, x_uu, x_uv, x_vv]. Because the limit
/// surface is linear in the control points, these weights are also ∂(x, x_u, …)/∂(control point).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LimitStencil {
    pub indices: Vec<u32>,
    pub weights: Vec<[f64; 6]>,
}

/// Position and parametric derivatives of the limit surface at one point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LimitPoint {
    /// [x, x_u, x_v, x_uu, x_uv, x_vv]
    pub d: [Vec3; 6],
}

impl LimitPoint {
    pub fn x(&self) -> Vec3 {
        self.d[deriv::X]
    }
    /// Unit normal x_u × x_v / |x_u × x_v|.
    pub fn normal(&self) -> Vec3 {
        let (a, b) = (self.d[deriv::XU], self.d[deriv::XV]);
        let n = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        [n[0] / l, n[1] / l, n[2] / l]
    }
}

impl LimitStencil {
    /// Applies the stencil to control point positions.
    pub fn apply(&self, points: &[Vec3]) -> LimitPoint {
        let mut out = LimitPoint::default();
        for (&i, w) in self.indices.iter().zip(&self.weights) {
            let p = points[i as usize];
            for k in 0..6 {
                for c in 0..3 {
                    out.d[k][c] += w[k] * p[c];
                }
            }
        }
        out
    }
}

/// Many stencils in flat arrays: stencil q is rows `offsets[q]..offsets[q + 1]` of `indices`
/// and `weights`.
#[derive(Clone, Debug, PartialEq)]
pub struct StencilTable {
    pub offsets: Vec<u32>,
    pub indices: Vec<u32>,
    pub weights: Vec<[f64; 6]>,
}

impl Default for StencilTable {
    fn default() -> Self {
        Self::new()
    }
}

impl StencilTable {
    pub fn new() -> Self {
        Self {
            offsets: vec![0],
            indices: Vec::new(),
            weights: Vec::new(),
        }
    }

    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Stencil q as slices.
    pub fn row(&self, q: usize) -> (&[u32], &[[f64; 6]]) {
        let r = self.offsets[q] as usize..self.offsets[q + 1] as usize;
        (&self.indices[r.clone()], &self.weights[r])
    }

    /// Owned copy of stencil q.
    pub fn get(&self, q: usize) -> LimitStencil {
        let (i, w) = self.row(q);
        LimitStencil {
            indices: i.to_vec(),
            weights: w.to_vec(),
        }
    }
}

/// Deepest local refinement before a point is declared to sit on an extraordinary vertex.
const MAX_DEPTH: u32 = 60;

/// The limit surface of a quad control mesh, ready to evaluate anywhere on any face.
#[derive(Clone, Debug)]
pub struct LimitSurface {
    rule: BoundaryRule,
    cage: PolyMesh,
    topology: Topology,
    boundary: HashSet<(u32, u32)>,
    num_mesh_vertices: usize,
    num_mesh_faces: usize,
    kinds: Vec<FaceKind>,
    /// Control grid of each regular face of the mesh (`None`: evaluate by local refinement).
    patches: Vec<Option<[Recipe; 16]>>,
}

impl LimitSurface {
    /// Checks the mesh (manifold, all quads) and prepares evaluation under `rule`.
    pub fn new(mesh: &PolyMesh, rule: BoundaryRule) -> Result<Self, BasisError> {
        let topo = Topology::build(mesh)?;
        if let Some((face, f)) = mesh.faces.iter().enumerate().find(|(_, f)| f.len() != 4) {
            return Err(BasisError::NotQuad {
                face,
                corners: f.len(),
            });
        }
        let kinds = classify_faces(mesh, &topo);
        let (cage, topology) = match rule {
            BoundaryRule::Phantom => (mesh.clone(), topo),
            BoundaryRule::Ghost => {
                let ext = add_ghost_layer(mesh, &topo);
                let t = Topology::build(&ext)?;
                (ext, t)
            }
        };
        let boundary = topology
            .edges
            .iter()
            .enumerate()
            .filter(|&(e, _)| topology.is_boundary_edge(e as u32))
            .map(|(_, &[a, b])| (a, b))
            .collect();
        let patches = (0..mesh.num_faces() as u32)
            .map(|f| {
                regular_patch(
                    &MeshView {
                        mesh: &cage,
                        topo: &topology,
                    },
                    f,
                )
            })
            .collect();
        Ok(Self {
            rule,
            cage,
            topology,
            boundary,
            num_mesh_vertices: mesh.num_vertices(),
            num_mesh_faces: mesh.num_faces(),
            kinds,
            patches,
        })
    }

    pub fn rule(&self) -> BoundaryRule {
        self.rule
    }

    /// Control points the stencils index: the mesh's vertices, then any ghost points.
    pub fn control_points(&self) -> &[Vec3] {
        &self.cage.positions
    }

    /// The control cage the stencils refer to (the mesh, plus the ghost layer under
    /// [`BoundaryRule::Ghost`], whose faces come after the mesh's own).
    pub fn cage(&self) -> &PolyMesh {
        &self.cage
    }

    pub fn num_mesh_vertices(&self) -> usize {
        self.num_mesh_vertices
    }

    /// Faces that carry surface: the mesh's own (ghost faces carry none).
    pub fn num_faces(&self) -> usize {
        self.num_mesh_faces
    }

    pub fn face_kind(&self, face: usize) -> FaceKind {
        self.kinds[face]
    }

    pub fn face_kinds(&self) -> &[FaceKind] {
        &self.kinds
    }

    /// Stencils at several points of one face (sharing the local refinement work).
    pub fn stencils(&self, face: usize, uvs: &[[f64; 2]]) -> Result<Vec<LimitStencil>, BasisError> {
        let mut table = StencilTable::new();
        self.append_stencils(face, uvs, None, &mut table)?;
        Ok((0..uvs.len()).map(|q| table.get(q)).collect())
    }

    /// Appends the stencils at `uvs` of `face` to `table`, one entry per point. `bicubic`, when
    /// given, holds `bicubic_weights(u, v, 1)` for each of the `uvs` (a quadrature rule reuses it
    /// on every face).
    pub(crate) fn append_stencils(
        &self,
        face: usize,
        uvs: &[[f64; 2]],
        bicubic: Option<&[[[f64; 16]; 6]]>,
        table: &mut StencilTable,
    ) -> Result<(), BasisError> {
        if face >= self.num_mesh_faces {
            return Err(BasisError::NoSuchFace {
                face,
                faces: self.num_mesh_faces,
            });
        }
        for &[u, v] in uvs {
            if !(0.0..=1.0).contains(&u) || !(0.0..=1.0).contains(&v) {
                return Err(BasisError::OutsideFace { u, v });
            }
        }
        if let Some(patch) = &self.patches[face] {
            for (q, &[u, v]) in uvs.iter().enumerate() {
                match bicubic {
                    Some(w) => append_patch_stencil(patch, &w[q], table),
                    None => append_patch_stencil(patch, &bicubic_weights(u, v, 1.0), table),
                }
            }
            return Ok(());
        }
        let (cage, global) = self.face_cage(face);
        let pts: Vec<(usize, f64, f64)> = uvs
            .iter()
            .enumerate()
            .map(|(i, &[u, v])| (i, u, v))
            .collect();
        let mut dense: Vec<Option<[Vec<f64>; 6]>> = vec![None; uvs.len()];
        eval_in_cage(&cage, &pts, 0, &mut dense).map_err(|slot| {
            BasisError::AtExtraordinaryVertex {
                face,
                u: uvs[slot][0],
                v: uvs[slot][1],
            }
        })?;
        for d in dense {
            append_dense_stencil(&d.unwrap_or_default(), &global, table);
        }
        Ok(())
    }

    /// The stencil at one point.
    pub fn stencil(&self, face: usize, u: f64, v: f64) -> Result<LimitStencil, BasisError> {
        Ok(self.stencils(face, &[[u, v]])?.remove(0))
    }

    /// Position and derivatives at one point, for the cage's own control points.
    pub fn evaluate(&self, face: usize, u: f64, v: f64) -> Result<LimitPoint, BasisError> {
        Ok(self.stencil(face, u, v)?.apply(self.control_points()))
    }

    /// The cage of every face touching a corner of `face` (face 0 of the result), with each point
    /// a unit weight vector, and the global index of each local point.
    fn face_cage(&self, face: usize) -> (Cage<Vec<f64>>, Vec<u32>) {
        let ring = OneRing::gather(
            face as u32,
            &self.cage.faces[face],
            |v| &self.topology.vertex_faces[v as usize],
            |f| &self.cage.faces[f as usize],
        );
        let m = ring.global.len();
        let points = (0..m)
            .map(|i| {
                let mut e = vec![0.0; m];
                e[i] = 1.0;
                Some(e)
            })
            .collect();
        let complete = ring
            .global
            .iter()
            .map(|&v| ring.holds_all(&self.topology.vertex_faces[v as usize]))
            .collect();
        let boundary = ring.local_edges(&self.boundary);
        let global = ring.global.clone();
        (
            Cage {
                points,
                faces: ring.faces,
                complete,
                boundary,
            },
            global,
        )
    }
}

/// Regular / boundary / extraordinary, from the corners' valences.
fn classify_faces(mesh: &PolyMesh, topo: &Topology) -> Vec<FaceKind> {
    mesh.faces
        .iter()
        .map(|f| {
            let mut kind = FaceKind::Regular;
            for &v in f {
                let v = v as usize;
                let nf = topo.vertex_faces[v].len();
                if topo.on_boundary[v] {
                    if nf > 2 {
                        return FaceKind::Extraordinary;
                    }
                    kind = FaceKind::Boundary;
                } else if nf != 4 {
                    return FaceKind::Extraordinary;
                }
            }
            kind
        })
        .collect()
}

/// Dense local weights → sparse stencil over global indices, sorted by index, appended to
/// `table`. Only exact zeros are dropped (they are the structural zeros of the composed
/// subdivision matrices).
fn append_dense_stencil(dense: &[Vec<f64>; 6], global: &[u32], table: &mut StencilTable) {
    let mut rows: Vec<(u32, [f64; 6])> = (0..global.len())
        .filter_map(|i| {
            let w = std::array::from_fn(|k| dense[k].get(i).copied().unwrap_or(0.0));
            w.iter().any(|&x| x != 0.0).then_some((global[i], w))
        })
        .collect();
    rows.sort_by_key(|r| r.0);
    for (i, w) in rows {
        table.indices.push(i);
        table.weights.push(w);
    }
    table.offsets.push(table.indices.len() as u32);
}

/// A local cage seen through [`Neighbourhood`].
struct CageView<'a> {
    cage: &'a Cage<Vec<f64>>,
    adj: &'a CageAdjacency,
}

impl Neighbourhood for CageView<'_> {
    fn face(&self, f: u32) -> &[u32] {
        &self.cage.faces[f as usize]
    }
    fn face_along(&self, a: u32, b: u32) -> Option<u32> {
        self.adj.directed.get(&(a, b)).copied()
    }
    fn vertex_faces(&self, v: u32) -> (usize, bool) {
        (
            self.adj.vertex_faces[v as usize].len(),
            self.cage.complete[v as usize],
        )
    }
    fn boundary_edges_at(&self, v: u32) -> usize {
        self.adj.boundary_edges[v as usize] as usize
    }
    fn is_boundary_edge(&self, a: u32, b: u32) -> bool {
        self.cage.boundary.contains(&edge_key(a, b))
    }
}

/// The whole control cage seen through [`Neighbourhood`].
struct MeshView<'a> {
    mesh: &'a PolyMesh,
    topo: &'a Topology,
}

impl Neighbourhood for MeshView<'_> {
    fn face(&self, f: u32) -> &[u32] {
        &self.mesh.faces[f as usize]
    }
    fn face_along(&self, a: u32, b: u32) -> Option<u32> {
        let e = self.topo.edge_between(a, b)?;
        self.topo.edge_faces[e as usize]
            .iter()
            .copied()
            .filter(|&f| f != crate::mesh::NO_FACE)
            .find(|&f| {
                let face = &self.mesh.faces[f as usize];
                let k = face.iter().position(|&x| x == a).unwrap_or(0);
                face[(k + 1) % face.len()] == b
            })
    }
    fn vertex_faces(&self, v: u32) -> (usize, bool) {
        (self.topo.vertex_faces[v as usize].len(), true)
    }
    fn boundary_edges_at(&self, v: u32) -> usize {
        if self.topo.on_boundary[v as usize] {
            2
        } else {
            0
        }
    }
    fn is_boundary_edge(&self, a: u32, b: u32) -> bool {
        self.topo
            .edge_between(a, b)
            .is_some_and(|e| self.topo.is_boundary_edge(e))
    }
}

/// Appends the stencil of a regular patch for one set of bicubic weights (`w[d][c]`: derivative
/// d, grid entry c) to `table`: at most 16 control points, no allocation.
fn append_patch_stencil(patch: &[Recipe; 16], w: &[[f64; 16]; 6], table: &mut StencilTable) {
    let mut rows = [(0u32, [0.0f64; 6]); 16];
    let mut n = 0;
    for (c, recipe) in patch.iter().enumerate() {
        for &(i, a) in recipe {
            let k = match rows[..n].iter().position(|r| r.0 == i) {
                Some(k) => k,
                None => {
                    rows[n] = (i, [0.0; 6]);
                    n += 1;
                    n - 1
                }
            };
            for d in 0..6 {
                rows[k].1[d] += a * w[d][c];
            }
        }
    }
    let rows = &mut rows[..n];
    rows.sort_unstable_by_key(|r| r.0);
    for r in rows.iter().filter(|r| r.1.iter().any(|&x| x != 0.0)) {
        table.indices.push(r.0);
        table.weights.push(r.1);
    }
    table.offsets.push(table.indices.len() as u32);
}

/// The dense control grid of face 0 of a local cage, if it is a regular patch with valid points.
fn regular_grid(cage: &Cage<Vec<f64>>, adj: &CageAdjacency) -> Option<Vec<Vec<f64>>> {
    let patch = regular_patch(&CageView { cage, adj }, 0)?;
    patch
        .iter()
        .map(|recipe| {
            let mut acc: Option<Vec<f64>> = None;
            for &(i, a) in recipe {
                let p = cage.points[i as usize].as_ref()?;
                let acc = acc.get_or_insert_with(|| vec![0.0; p.len()]);
                for (s, x) in acc.iter_mut().zip(p) {
                    *s += a * x;
                }
            }
            acc
        })
        .collect()
}

/// Evaluates the points `(slot, u, v)` of face 0 of `cage` at refinement depth `depth`, writing
/// dense weights into `out[slot]`. On failure returns the slot of a point that reached
/// `MAX_DEPTH` (it sits on an extraordinary vertex).
fn eval_in_cage(
    cage: &Cage<Vec<f64>>,
    pts: &[(usize, f64, f64)],
    depth: u32,
    out: &mut [Option<[Vec<f64>; 6]>],
) -> Result<(), usize> {
    let adj = cage.adjacency();
    if let Some(grid) = regular_grid(cage, &adj) {
        let m = grid[0].len();
        let scale = (depth as f64).exp2();
        for &(slot, u, v) in pts {
            let w = bicubic_weights(u, v, scale);
            out[slot] = Some(std::array::from_fn(|k| {
                let mut acc = vec![0.0; m];
                for (c, row) in grid.iter().enumerate() {
                    let a = w[k][c];
                    if a != 0.0 {
                        for (s, x) in acc.iter_mut().zip(row) {
                            *s += a * x;
                        }
                    }
                }
                acc
            }));
        }
        return Ok(());
    }
    if depth >= MAX_DEPTH {
        return Err(pts[0].0);
    }
    let fine = cage.refine();
    let fine_adj = fine.adjacency();
    // quadrant k of the parent holds child face k (child of corner k); (i, j) is its offset
    for (k, (i, j)) in [(0usize, 0usize), (1, 0), (1, 1), (0, 1)]
        .into_iter()
        .enumerate()
    {
        let sub: Vec<(usize, f64, f64)> = pts
            .iter()
            .filter(|&&(_, u, v)| (u >= 0.5) as usize == i && (v >= 0.5) as usize == j)
            .map(|&(slot, u, v)| (slot, 2.0 * u - i as f64, 2.0 * v - j as f64))
            .collect();
        if sub.is_empty() {
            continue;
        }
        // child k is [vertex(c_k), edge, face, edge]; rotate it so that its u, v axes run
        // along the parent's
        let child = &fine.faces[k];
        let rot = (4 - k) % 4;
        let aligned: Vec<u32> = (0..4).map(|r| child[(rot + r) % 4]).collect();
        let next = fine.one_ring(&fine_adj, k, &aligned);
        eval_in_cage(&next, &sub, depth + 1, out)?;
    }
    Ok(())
}
