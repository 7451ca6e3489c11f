//! A dense tessellation of a limit surface as one stencil per sample (Catmull–Clark limit
//! evaluation, `crate::subdiv`): `k` × `k` quads per cage face, samples welded where faces meet,
//! each quad split in two triangles. The table is laid out for the GPU kernel
//! `shaders/limit_eval.wgsl` (rows of control indices and f32 weights for x, x_u and x_v), and
//! [`Tessellation::evaluate_cpu`] is its oracle in f64.

use crate::subdiv::{deriv, BasisError, LimitStencil, LimitSurface};
use crate::Vec3;
use std::collections::HashMap;

/// Parameter step towards the face centre for the tangents of a sample where x_u × x_v vanishes
/// (the corner of an extraordinary vertex, where the parametrisation is singular).
const NUDGE: f64 = 1e-3;

/// One sample of the limit surface: position, the tangents its normal is taken from, unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub x: Vec3,
    pub xu: Vec3,
    pub xv: Vec3,
    pub normal: Vec3,
}

/// The stencil table of a tessellation, with texture coordinates and triangles.
#[derive(Clone, Debug)]
pub struct Tessellation {
    /// Row q of the table is `indices[offsets[q]..offsets[q + 1]]`.
    pub offsets: Vec<u32>,
    pub indices: Vec<u32>,
    /// Weights in x, x_u, x_v (and a zero, for 16-byte rows).
    pub weights: Vec<[f32; 4]>,
    /// Rest position (x, y) of each sample in metres: u along the warp, v along the weft.
    pub uv: Vec<[f32; 2]>,
    /// Counter-clockwise seen from the normal's side.
    pub triangles: Vec<[u32; 3]>,
    /// The same rows in f64, for the oracle.
    stencils: Vec<(LimitStencil, Option<LimitStencil>)>,
    num_controls: usize,
}

impl Tessellation {
    /// Samples `surface` `k` × `k` per face; `rest` (the control points at rest) welds samples
    /// and gives texture coordinates.
    pub fn new(surface: &LimitSurface, rest: &[Vec3], k: usize) -> Result<Self, BasisError> {
        let k = k.max(1);
        let uvs: Vec<[f64; 2]> = (0..=k)
            .flat_map(|b| (0..=k).map(move |a| [a as f64 / k as f64, b as f64 / k as f64]))
            .collect();
        let (lo, hi) = bounds(rest);
        let scale = (0..3)
            .map(|c| hi[c] - lo[c])
            .fold(0.0, f64::max)
            .max(1e-300);
        let key_scale = 1e7 * k as f64 / scale;
        let mut welded: HashMap<[i64; 3], u32> = HashMap::new();
        let mut stencils = Vec::new();
        let mut uv = Vec::new();
        let mut triangles = Vec::new();
        for face in 0..surface.num_faces() {
            let rows = face_stencils(surface, face, &uvs)?;
            let mut ids = Vec::with_capacity(uvs.len());
            for (s, st) in uvs.iter().zip(rows) {
                let r = st.apply(rest);
                let p = r.x();
                let key = p.map(|c| (c * key_scale).round() as i64);
                let next = stencils.len() as u32;
                let id = *welded.entry(key).or_insert(next);
                if id == next {
                    let singular = !tangents_ok(r.d[deriv::XU], r.d[deriv::XV]);
                    let nudged = if singular {
                        let t = [
                            s[0] + NUDGE * (0.5 - s[0]).signum(),
                            s[1] + NUDGE * (0.5 - s[1]).signum(),
                        ];
                        Some(surface.stencil(face, t[0], t[1])?)
                    } else {
                        None
                    };
                    stencils.push((st, nudged));
                    uv.push([p[0] as f32, p[1] as f32]);
                }
                ids.push(id);
            }
            for b in 0..k {
                for a in 0..k {
                    let at = |i: usize, j: usize| ids[j * (k + 1) + i];
                    let (p00, p10, p11, p01) =
                        (at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1));
                    triangles.push([p00, p10, p11]);
                    triangles.push([p00, p11, p01]);
                }
            }
        }
        let mut offsets = vec![0u32];
        let mut indices = Vec::new();
        let mut weights = Vec::new();
        for (st, nudged) in &stencils {
            let tangent = nudged.as_ref().unwrap_or(st);
            let mut row: Vec<(u32, [f32; 4])> = st
                .indices
                .iter()
                .zip(&st.weights)
                .map(|(&i, w)| (i, [w[deriv::X] as f32, 0.0, 0.0, 0.0]))
                .collect();
            for (&i, w) in tangent.indices.iter().zip(&tangent.weights) {
                let (wu, wv) = (w[deriv::XU] as f32, w[deriv::XV] as f32);
                match row.iter_mut().find(|(j, _)| *j == i) {
                    Some((_, r)) => {
                        r[1] = wu;
                        r[2] = wv;
                    }
                    None => row.push((i, [0.0, wu, wv, 0.0])),
                }
            }
            for (i, w) in row {
                indices.push(i);
                weights.push(w);
            }
            offsets.push(indices.len() as u32);
        }
        Ok(Self {
            offsets,
            indices,
            weights,
            uv,
            triangles,
            stencils,
            num_controls: rest.len(),
        })
    }

    pub fn num_points(&self) -> usize {
        self.uv.len()
    }

    /// Number of control points the stencils index.
    pub fn num_controls(&self) -> usize {
        self.num_controls
    }

    /// Positions and unit normals of every sample, in f64 from the f64 stencils (the GPU
    /// kernel's oracle).
    pub fn evaluate_cpu(&self, x: &[Vec3]) -> Vec<(Vec3, Vec3)> {
        self.samples_cpu(x)
            .into_iter()
            .map(|s| (s.x, s.normal))
            .collect()
    }

    /// Every sample in f64 with the tangents its normal comes from.
    pub fn samples_cpu(&self, x: &[Vec3]) -> Vec<Sample> {
        self.stencils
            .iter()
            .map(|(st, nudged)| {
                let p = st.apply(x);
                let t = nudged.as_ref().map_or(p, |n| n.apply(x));
                Sample {
                    x: p.x(),
                    xu: t.d[deriv::XU],
                    xv: t.d[deriv::XV],
                    normal: t.normal(),
                }
            })
            .collect()
    }

    /// For each sample, Σ |w| · max|x| over its row: the scale of its rounding error in f32.
    pub fn magnitudes(&self, x: &[Vec3]) -> Vec<[f64; 3]> {
        (0..self.num_points())
            .map(|q| {
                let (a, b) = (self.offsets[q] as usize, self.offsets[q + 1] as usize);
                let mut m = [0.0; 3];
                for k in a..b {
                    let xi = x[self.indices[k] as usize];
                    let s = xi[0].abs().max(xi[1].abs()).max(xi[2].abs());
                    for d in 0..3 {
                        m[d] += (self.weights[k][d] as f64).abs() * s;
                    }
                }
                m
            })
            .collect()
    }

    /// Length of the longest stencil row.
    pub fn max_row(&self) -> usize {
        self.offsets
            .windows(2)
            .map(|w| (w[1] - w[0]) as usize)
            .max()
            .unwrap_or(0)
    }
}

/// Parameter offset of a sample placed on an extraordinary vertex, where the limit surface has
/// no parametric evaluation: the position there differs from the vertex's limit point by about
/// 1e-9 of the face, far below f32 rounding.
const EV_OFFSET: f64 = 1e-9;

/// The stencils at `uvs` of one face, samples on an extraordinary vertex moved `EV_OFFSET`
/// towards the face centre.
fn face_stencils(
    surface: &LimitSurface,
    face: usize,
    uvs: &[[f64; 2]],
) -> Result<Vec<LimitStencil>, BasisError> {
    match surface.stencils(face, uvs) {
        Err(BasisError::AtExtraordinaryVertex { .. }) => uvs
            .iter()
            .map(|&[u, v]| match surface.stencil(face, u, v) {
                Err(BasisError::AtExtraordinaryVertex { .. }) => surface.stencil(
                    face,
                    u + EV_OFFSET * (0.5 - u).signum(),
                    v + EV_OFFSET * (0.5 - v).signum(),
                ),
                r => r,
            })
            .collect(),
        r => r,
    }
}

fn tangents_ok(a: Vec3, b: Vec3) -> bool {
    let n = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let la = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    let lb = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
    let ln = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    ln.is_finite() && ln > 1e-6 * la * lb && la * lb > 0.0
}

/// Smallest and largest coordinates of a point set.
pub fn bounds(x: &[Vec3]) -> (Vec3, Vec3) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in x {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::rectangular_grid;
    use crate::subdiv::BoundaryRule;

    #[test]
    fn a_flat_grid_tessellates_with_welded_samples_and_upward_normals() {
        let mesh = rectangular_grid(0.2, 0.1, 4, 2);
        let surface = LimitSurface::new(&mesh, BoundaryRule::Phantom).unwrap();
        let t = Tessellation::new(&surface, &mesh.positions, 3).unwrap();
        // 4 × 2 faces of 3 × 3 quads: (12 + 1) × (6 + 1) distinct samples
        assert_eq!(t.num_points(), 13 * 7);
        assert_eq!(t.triangles.len(), 2 * 9 * 8);
        for (p, n) in t.evaluate_cpu(&mesh.positions) {
            assert!(p[2].abs() < 1e-15 && (n[2] - 1.0).abs() < 1e-12);
        }
        assert_eq!(t.offsets.len(), t.num_points() + 1);
        assert_eq!(t.indices.len(), t.weights.len());
    }
}
