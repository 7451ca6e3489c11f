//! Named sample cages (the shapes shipped in `meshes/`, and test fixtures).

use super::PolyMesh;
use std::f64::consts::PI;

/// The unit cube [0, 1]³, faces outward: every vertex has valence 3.
pub fn cube() -> PolyMesh {
    let positions = (0..8)
        .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
        .collect();
    let faces = vec![
        vec![0, 2, 3, 1], // z = 0, normal −z
        vec![4, 5, 7, 6], // z = 1
        vec![0, 1, 5, 4], // y = 0
        vec![2, 6, 7, 3], // y = 1
        vec![0, 4, 6, 2], // x = 0
        vec![1, 3, 7, 5], // x = 1
    ];
    PolyMesh::new(positions, faces)
}

/// A fan of `sectors` quad grids (each `n` × `n` faces) around a centre vertex, spanning
/// `angle` radians; with `angle` = 2π the fan closes and the centre is an interior vertex of
/// valence `sectors`, otherwise it is a boundary vertex with `sectors` faces. Radius 1, gently
/// curved (z = 0.15 (x² − 0.6 y²) + 0.05 x y) so that derivatives are not trivially zero.
pub fn fan(sectors: usize, angle: f64, n: usize) -> PolyMesh {
    let closed = (angle - 2.0 * PI).abs() < 1e-12;
    let spokes = if closed { sectors } else { sectors + 1 };
    let dir = |k: usize| {
        let a = angle * k as f64 / sectors as f64;
        [a.cos(), a.sin()]
    };
    let lift = |x: f64, y: f64| [x, y, 0.15 * (x * x - 0.6 * y * y) + 0.05 * x * y];
    let h = 1.0 / n as f64;
    let mut positions = vec![lift(0.0, 0.0)];
    // spoke k, point i (1..=n)
    let spoke_start = positions.len();
    for k in 0..spokes {
        let d = dir(k);
        for i in 1..=n {
            let r = i as f64 * h;
            positions.push(lift(r * d[0], r * d[1]));
        }
    }
    let spoke = |k: usize, i: usize| (spoke_start + (k % spokes) * n + i - 1) as u32;
    // interior points of sector k: (i, j), 1..=n each
    let inner_start = positions.len();
    for k in 0..sectors {
        let (a, b) = (dir(k), dir(k + 1));
        for j in 1..=n {
            for i in 1..=n {
                let (s, t) = (i as f64 * h, j as f64 * h);
                positions.push(lift(s * a[0] + t * b[0], s * a[1] + t * b[1]));
            }
        }
    }
    let id = |k: usize, i: usize, j: usize| -> u32 {
        match (i, j) {
            (0, 0) => 0,
            (i, 0) => spoke(k, i),
            (0, j) => spoke(k + 1, j),
            (i, j) => (inner_start + k * n * n + (j - 1) * n + (i - 1)) as u32,
        }
    };
    let mut faces = Vec::new();
    for k in 0..sectors {
        for j in 0..n {
            for i in 0..n {
                faces.push(vec![
                    id(k, i, j),
                    id(k, i + 1, j),
                    id(k, i + 1, j + 1),
                    id(k, i, j + 1),
                ]);
            }
        }
    }
    PolyMesh::new(positions, faces)
}

/// A closed star: an interior vertex of valence `valence` in a disc of `n` rings of quads.
pub fn star(valence: usize, n: usize) -> PolyMesh {
    fan(valence, 2.0 * PI, n)
}

/// An L-shaped flat plate of 3 `n` × `n` blocks (2n × 2n with the top-right block removed): the
/// re-entrant corner is a boundary vertex with three faces, an extraordinary boundary vertex.
pub fn l_shape(n: usize) -> PolyMesh {
    let m = 2 * n;
    let id = |i: usize, j: usize| (j * (m + 1) + i) as u32;
    let positions = (0..=m)
        .flat_map(|j| (0..=m).map(move |i| [i as f64 / n as f64, j as f64 / n as f64, 0.0]))
        .collect();
    let mut faces = Vec::new();
    for j in 0..m {
        for i in 0..m {
            if i >= n && j >= n {
                continue;
            }
            faces.push(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    // drop the vertices of the removed block's interior and outer edges
    let mut mesh = PolyMesh::new(positions, faces);
    compact(&mut mesh);
    mesh
}

/// Removes vertices used by no face, renumbering the rest in order.
pub fn compact(mesh: &mut PolyMesh) {
    let mut used = vec![false; mesh.positions.len()];
    for f in &mesh.faces {
        for &v in f {
            used[v as usize] = true;
        }
    }
    let mut map = vec![u32::MAX; used.len()];
    let mut positions = Vec::new();
    for (v, &u) in used.iter().enumerate() {
        if u {
            map[v] = positions.len() as u32;
            positions.push(mesh.positions[v]);
        }
    }
    for f in &mut mesh.faces {
        for v in f.iter_mut() {
            *v = map[*v as usize];
        }
    }
    mesh.positions = positions;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Topology;

    fn valences(m: &PolyMesh) -> Vec<(u32, bool)> {
        let t = Topology::build(m).unwrap();
        (0..m.num_vertices())
            .map(|v| (t.valence[v], t.on_boundary[v]))
            .collect()
    }

    #[test]
    fn shapes_have_the_advertised_extraordinary_vertices() {
        assert!(valences(&cube()).iter().all(|&(v, b)| v == 3 && !b));
        for val in [3, 5, 6] {
            let v = valences(&star(val, 3));
            assert_eq!(v[0], (val as u32, false));
            assert!(v[1..].iter().all(|&(v, b)| v == 4 || b));
        }
        let f = valences(&fan(3, PI, 2));
        assert_eq!(f[0], (4, true)); // 3 faces, 4 edges, on the boundary
        let l = l_shape(2);
        assert_eq!(l.num_faces(), 12);
        let t = Topology::build(&l).unwrap();
        let reentrant = (0..l.num_vertices())
            .filter(|&v| t.on_boundary[v] && t.vertex_faces[v].len() == 3)
            .count();
        assert_eq!(reentrant, 1);
    }
}
