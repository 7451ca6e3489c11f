//! Recognising a regular face and gathering its 4 × 4 B-spline control grid.
//!
//! A face is a regular patch when each corner is an interior vertex with four faces, a boundary
//! vertex with two faces, or a corner with one face. Its grid holds the face's corners at
//! (1,1), (2,1), (2,2), (1,2) (i along u, j along v); the rest comes from the faces across its
//! sides and corners. Where a side lies on the boundary, the missing row is phantom:
//! P = 2·(boundary point) − (interior point), applied twice at a corner. Each grid entry is
//! therefore a short *recipe*: control indices with weights (one entry for a real point, two or
//! four for a phantom).
//!
//! Grid side s runs from corner s to corner s+1; its outward step is `OUT[s]`.

/// Where to look up neighbours: the whole mesh, or a local cage inside a refinement.
pub(crate) trait Neighbourhood {
    fn face(&self, f: u32) -> &[u32];
    /// The face that runs along the directed edge a → b, if any.
    fn face_along(&self, a: u32, b: u32) -> Option<u32>;
    /// Faces around `v`, and whether every one of them is known here.
    fn vertex_faces(&self, v: u32) -> (usize, bool);
    /// Number of true boundary edges at `v`.
    fn boundary_edges_at(&self, v: u32) -> usize;
    /// Whether the edge a–b is a true boundary edge.
    fn is_boundary_edge(&self, a: u32, b: u32) -> bool;
}

/// A weighted combination of control points.
pub(crate) type Recipe = Vec<(u32, f64)>;

const POS: [(usize, usize); 4] = [(1, 1), (2, 1), (2, 2), (1, 2)];
const OUT: [(isize, isize); 4] = [(0, -1), (1, 0), (0, 1), (-1, 0)];

fn step(p: (usize, usize), d: (isize, isize)) -> (usize, usize) {
    ((p.0 as isize + d.0) as usize, (p.1 as isize + d.1) as usize)
}

fn back(p: (usize, usize), d: (isize, isize)) -> (usize, usize) {
    step(p, (-d.0, -d.1))
}

/// `face` rotated to start with the directed edge a → b (quads only).
fn starting_with(face: &[u32], a: u32, b: u32) -> Option<[u32; 4]> {
    if face.len() != 4 {
        return None;
    }
    let k = face.iter().position(|&x| x == a)?;
    let r: [u32; 4] = std::array::from_fn(|i| face[(k + i) % 4]);
    (r[1] == b).then_some(r)
}

/// 2·p − q, merging repeated indices.
fn mirror(p: &Recipe, q: &Recipe) -> Recipe {
    let mut out: Recipe = p.iter().map(|&(i, w)| (i, 2.0 * w)).collect();
    for &(i, w) in q {
        match out.iter_mut().find(|e| e.0 == i) {
            Some(e) => e.1 -= w,
            None => out.push((i, -w)),
        }
    }
    out
}

/// The control grid (entry `4 j + i`) of `face` if it is a regular patch, else `None`.
pub(crate) fn regular_patch<N: Neighbourhood>(n: &N, face: u32) -> Option<[Recipe; 16]> {
    let f = n.face(face);
    if f.len() != 4 {
        return None;
    }
    for &a in f {
        let (nf, complete) = n.vertex_faces(a);
        let nb = n.boundary_edges_at(a);
        if !complete || !((nb == 0 && nf == 4) || (nb == 2 && nf <= 2)) {
            return None;
        }
    }
    let mut id: [[Option<u32>; 4]; 4] = [[None; 4]; 4];
    for s in 0..4 {
        id[POS[s].0][POS[s].1] = Some(f[s]);
    }
    let mut present = [false; 4];
    let mut expect: Vec<((usize, usize), u32)> = Vec::new();
    for s in 0..4 {
        let (a, b) = (f[s], f[(s + 1) % 4]);
        match n.face_along(b, a) {
            Some(g) => {
                let [_, _, x, y] = starting_with(n.face(g), b, a)?;
                let (px, py) = (step(POS[s], OUT[s]), step(POS[(s + 1) % 4], OUT[s]));
                id[px.0][px.1] = Some(x);
                id[py.0][py.1] = Some(y);
                present[s] = true;
                if n.boundary_edges_at(a) == 0 {
                    // the diagonal face at corner a, across the edge a–x of g
                    let h = n.face_along(x, a)?;
                    let [_, _, z, w] = starting_with(n.face(h), x, a)?;
                    let prev = OUT[(s + 3) % 4];
                    let c = step(step(POS[s], OUT[s]), prev);
                    id[c.0][c.1] = Some(w);
                    expect.push((step(POS[s], prev), z));
                }
            }
            None => {
                if !n.is_boundary_edge(a, b) {
                    return None;
                }
            }
        }
    }
    for (p, z) in expect {
        if id[p.0][p.1] != Some(z) {
            return None;
        }
    }
    let mut grid: [[Option<Recipe>; 4]; 4] = Default::default();
    for i in 0..4 {
        for j in 0..4 {
            grid[i][j] = id[i][j].map(|v| vec![(v, 1.0)]);
        }
    }
    let phantom = |grid: &[[Option<Recipe>; 4]; 4], at: (usize, usize), d: (isize, isize)| {
        let (p, q) = (&grid[at.0][at.1], &grid[back(at, d).0][back(at, d).1]);
        Some(mirror(p.as_ref()?, q.as_ref()?))
    };
    for s in 0..4 {
        if !present[s] {
            for corner in [POS[s], POS[(s + 1) % 4]] {
                let t = step(corner, OUT[s]);
                grid[t.0][t.1] = Some(phantom(&grid, corner, OUT[s])?);
            }
        }
    }
    for s in 0..4 {
        let prev = (s + 3) % 4;
        let c = step(step(POS[s], OUT[s]), OUT[prev]);
        if grid[c.0][c.1].is_some() {
            continue;
        }
        let p = if !present[s] {
            phantom(&grid, step(POS[s], OUT[prev]), OUT[s])?
        } else if !present[prev] {
            phantom(&grid, step(POS[s], OUT[s]), OUT[prev])?
        } else {
            return None;
        };
        grid[c.0][c.1] = Some(p);
    }
    let mut out: [Recipe; 16] = Default::default();
    for j in 0..4 {
        for i in 0..4 {
            out[4 * j + i] = grid[i][j].take()?;
        }
    }
    Some(out)
}
