//! The ghost-row boundary treatment: an extra layer of control points outside the boundary.
//!
//! Every boundary edge gets a ghost quad on its outer side; every corner (a boundary vertex with a
//! single face) gets a diagonal ghost quad as well. Ghost points start where the phantom rule
//! would put them (2·boundary − interior, and 4v − 2a − 2b + d at a corner), so the initial limit
//! surface on a regular boundary equals the phantom one, but they are ordinary control points:
//! a solver may move them, which lets a clamp prescribe the slope across an edge. A boundary
//! vertex with k ≥ 2 faces gets one ghost, 2v − (mean of its interior neighbours), and becomes an
//! interior vertex of valence k + 2 (extraordinary unless k = 2).

use crate::mesh::{PolyMesh, Topology};
use std::collections::HashMap;

/// Returns `mesh` with the ghost layer appended (ghost vertices after the mesh's, ghost faces
/// after the mesh's). The mesh must be an all-quad manifold described by `topo`.
pub(crate) fn add_ghost_layer(mesh: &PolyMesh, topo: &Topology) -> PolyMesh {
    let mut positions = mesh.positions.clone();
    let mut faces = mesh.faces.clone();
    let nv = mesh.num_vertices();
    let new_point = |p: [f64; 3], positions: &mut Vec<[f64; 3]>| {
        positions.push(p);
        positions.len() as u32 - 1
    };
    let lin = |terms: &[(f64, u32)]| {
        let mut p = [0.0; 3];
        for &(a, v) in terms {
            for c in 0..3 {
                p[c] += a * mesh.positions[v as usize][c];
            }
        }
        p
    };
    // neighbours of each vertex across interior edges
    let mut interior_nbrs: Vec<Vec<u32>> = vec![Vec::new(); nv];
    for (e, &[a, b]) in topo.edges.iter().enumerate() {
        if !topo.is_boundary_edge(e as u32) {
            interior_nbrs[a as usize].push(b);
            interior_nbrs[b as usize].push(a);
        }
    }
    let mut shared: HashMap<u32, u32> = HashMap::new();
    // (corner vertex, neighbour along the edge) -> ghost of the corner across that edge
    let mut per_edge: HashMap<(u32, u32), u32> = HashMap::new();
    for v in 0..nv as u32 {
        let vf = &topo.vertex_faces[v as usize];
        if !topo.on_boundary[v as usize] || vf.is_empty() {
            continue;
        }
        if vf.len() >= 2 {
            let nbrs = &interior_nbrs[v as usize];
            let w = 1.0 / nbrs.len() as f64;
            let mut terms = vec![(2.0, v)];
            terms.extend(nbrs.iter().map(|&n| (-w, n)));
            let g = new_point(lin(&terms), &mut positions);
            shared.insert(v, g);
        } else {
            let f = &mesh.faces[vf[0] as usize];
            let k = f.iter().position(|&x| x == v).unwrap_or(0);
            let (a, d, b) = (f[(k + 1) % 4], f[(k + 2) % 4], f[(k + 3) % 4]);
            let g_va = new_point(lin(&[(2.0, v), (-1.0, b)]), &mut positions);
            let g_vb = new_point(lin(&[(2.0, v), (-1.0, a)]), &mut positions);
            let c = new_point(
                lin(&[(4.0, v), (-2.0, a), (-2.0, b), (1.0, d)]),
                &mut positions,
            );
            per_edge.insert((v, a), g_va);
            per_edge.insert((v, b), g_vb);
            faces.push(vec![v, g_vb, c, g_va]);
        }
    }
    let ghost = |v: u32, along: u32| -> u32 {
        shared
            .get(&v)
            .or_else(|| per_edge.get(&(v, along)))
            .copied()
            .unwrap_or(v)
    };
    for (e, &[p, q]) in topo.edges.iter().enumerate() {
        if !topo.is_boundary_edge(e as u32) {
            continue;
        }
        let f = &mesh.faces[topo.edge_faces[e][0] as usize];
        let k = f.iter().position(|&x| x == p).unwrap_or(0);
        // direction a -> b as the face runs along the edge
        let (a, b) = if f[(k + 1) % f.len()] == q {
            (p, q)
        } else {
            (q, p)
        };
        faces.push(vec![b, a, ghost(a, b), ghost(b, a)]);
    }
    PolyMesh::new(positions, faces)
}
