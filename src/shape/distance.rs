//! Closest points on a triangulated surface: the position error of Miguel et al. 2012 between a
//! simulated sheet and a captured one, without asking the two meshes to match.
//!
//! The closest point on one triangle follows the Voronoi regions of its vertices, edges and
//! face (barycentric tests, as in Ericson, *Real-Time Collision Detection* §5.1.5). The search
//! over triangles skips any whose bounding box lies farther than the best point found so far;
//! a search costs O(triangles) box tests and far fewer triangle tests per point.

use super::ShapeMesh;
use crate::Vec3;

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// a + s (b − a) + t (c − a)
fn at(a: Vec3, b: Vec3, c: Vec3, s: f64, t: f64) -> Vec3 {
    [0, 1, 2].map(|k| a[k] + s * (b[k] - a[k]) + t * (c[k] - a[k]))
}

/// The point of triangle (a, b, c) closest to p.
pub fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return at(a, b, c, d1 / (d1 - d3), 0.0);
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return at(a, b, c, 0.0, d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0, 1, 2].map(|k| b[k] + w * (c[k] - b[k]));
    }
    let den = 1.0 / (va + vb + vc);
    at(a, b, c, vb * den, vc * den)
}

/// A target surface prepared for closest-point queries.
pub struct Surface<'a> {
    mesh: &'a ShapeMesh,
    boxes: Vec<(Vec3, Vec3)>,
}

impl<'a> Surface<'a> {
    pub fn new(mesh: &'a ShapeMesh) -> Self {
        let boxes = mesh
            .triangles
            .iter()
            .map(|t| {
                let p = t.map(|i| mesh.positions[i]);
                let lo = [0, 1, 2].map(|k| p[0][k].min(p[1][k]).min(p[2][k]));
                let hi = [0, 1, 2].map(|k| p[0][k].max(p[1][k]).max(p[2][k]));
                (lo, hi)
            })
            .collect();
        Self { mesh, boxes }
    }

    /// The closest point of the surface to p.
    pub fn closest(&self, p: Vec3) -> Vec3 {
        let mut best = (f64::INFINITY, p);
        for (t, (lo, hi)) in self.mesh.triangles.iter().zip(&self.boxes) {
            let gap: f64 = (0..3)
                .map(|k| (lo[k] - p[k]).max(p[k] - hi[k]).max(0.0).powi(2))
                .sum();
            if gap >= best.0 {
                continue;
            }
            let [a, b, c] = t.map(|i| self.mesh.positions[i]);
            let q = closest_on_triangle(p, a, b, c);
            let d = sub(p, q);
            let d2 = dot(d, d);
            if d2 < best.0 {
                best = (d2, q);
            }
        }
        best.1
    }

    /// p − closest(p) for every point.
    pub fn offsets(&self, points: &[Vec3]) -> Vec<Vec3> {
        points.iter().map(|&p| sub(p, self.closest(p))).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against a brute force over a fine sampling of the triangle.
    #[test]
    fn the_closest_point_matches_a_dense_sampling() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [1.0, 0.2, 0.1], [0.3, 0.9, -0.2]);
        let n = 400;
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 3.0 - 1.0
        };
        for _ in 0..40 {
            let p = [rnd(), rnd(), rnd()];
            let q = closest_on_triangle(p, a, b, c);
            let dq = dot(sub(p, q), sub(p, q));
            let mut best = f64::INFINITY;
            for i in 0..=n {
                for j in 0..=n - i {
                    let x = at(a, b, c, i as f64 / n as f64, j as f64 / n as f64);
                    best = best.min(dot(sub(p, x), sub(p, x)));
                }
            }
            // never farther than a sample, and within the sampling's resolution of the best
            assert!(dq <= best + 1e-12, "{p:?}: {dq} > {best}");
            assert!(best.sqrt() - dq.sqrt() < 4e-3, "{p:?}");
        }
    }

    #[test]
    fn a_point_above_a_plane_is_its_height_away() {
        let mut m = ShapeMesh::default();
        for j in 0..5 {
            for i in 0..5 {
                m.positions.push([i as f64, j as f64, 0.0]);
            }
        }
        for j in 0..4 {
            for i in 0..4 {
                let v = j * 5 + i;
                m.triangles.push([v, v + 1, v + 6]);
                m.triangles.push([v, v + 6, v + 5]);
            }
        }
        let s = Surface::new(&m);
        assert_eq!(s.offsets(&[[1.3, 2.7, 0.25]]), vec![[0.0, 0.0, 0.25]]);
        // beyond the edge: to the border
        let o = s.offsets(&[[5.0, 2.0, 0.0]])[0];
        assert!((o[0] - 1.0).abs() < 1e-12 && o[1].abs() < 1e-12);
    }
}
