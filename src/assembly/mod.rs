//! Assembly of the total energy, its gradient and its sparse Hessian over all Gauss points.
//!
//! Total energy (Clyde et al. 2017 §3): E(x) = Σ_q dA_q ∫ ψ(Ẽ_m + ξ Ẽ_b) dξ − Σ_q dA_q ρ g·x_q,
//! the first term integrated through the thickness ξ ∈ [−τ/2, τ/2] with a Gauss–Legendre rule
//! (three points integrate St. Venant–Kirchhoff exactly: its integrand is quadratic in ξ), the
//! second the gravity potential of the areal density ρ over the rest area.
//!
//! Per Gauss point everything is first computed with respect to the 15-vector
//! y = (a₁, a₂, x,₁₁, x,₁₂, x,₂₂) (see [`crate::shell`]), then expanded to the control points
//! through the limit stencil: g_i = Σ_k W_ik g_k and H_ij = Σ_kl W_ik H_kl W_jl (3 × 3 blocks).
//! With n stencil points that expansion costs about 90 n(n+1)/2 + 450 n flops; for a regular
//! face (n = 16) some 20 000 flops per Gauss point, which is where assembly time goes.
//!
//! The Hessian lives in a [`BlockMatrix`]: 3 × 3 blocks on the node pairs (i ≤ j) that share a
//! Gauss point, a pattern built once per mesh.

mod section;
mod sensitivities;
pub use sensitivities::BENDING_PARAMS;

use crate::material::{BendingRigidity, Law, OutOfDomain};
use crate::quadrature::GaussLegendre;
use crate::shell::{kinematic_vector, RestError, RestPoint, YMat, YVec};
use crate::subdiv::LimitBasis;
use crate::Vec3;
use nalgebra::{Matrix3, Vector3};
use section::Section;
use std::sync::Arc;

/// Upper-triangular node-pair pattern in compressed rows: row i lists the nodes j ≥ i that share
/// a Gauss point with i.
#[derive(Clone, Debug)]
pub struct BlockPattern {
    pub num_nodes: usize,
    pub row_ptr: Vec<usize>,
    pub col: Vec<u32>,
}

impl BlockPattern {
    /// Pattern of every pair of nodes within one face's stencils.
    pub fn from_basis(basis: &LimitBasis) -> Self {
        let n = basis.control_points.len();
        let mut rows: Vec<Vec<u32>> = vec![Vec::new(); n];
        let npf = basis.points_per_face;
        let mut nodes: Vec<u32> = Vec::new();
        for face in 0..basis.num_faces {
            nodes.clear();
            for q in face * npf..(face + 1) * npf {
                nodes.extend_from_slice(basis.stencil(q).0);
            }
            nodes.sort_unstable();
            nodes.dedup();
            for (a, &i) in nodes.iter().enumerate() {
                rows[i as usize].extend_from_slice(&nodes[a..]);
            }
        }
        let mut row_ptr = vec![0];
        let mut col = Vec::new();
        for mut r in rows {
            r.sort_unstable();
            r.dedup();
            col.extend(r);
            row_ptr.push(col.len());
        }
        Self {
            num_nodes: n,
            row_ptr,
            col,
        }
    }

    /// Index of block (i, j), i ≤ j.
    pub fn find(&self, i: u32, j: u32) -> Option<usize> {
        let r = self.row_ptr[i as usize]..self.row_ptr[i as usize + 1];
        self.col[r.clone()]
            .binary_search(&j)
            .ok()
            .map(|k| r.start + k)
    }

    pub fn num_blocks(&self) -> usize {
        self.col.len()
    }
}

/// Symmetric matrix of 3 × 3 blocks on a [`BlockPattern`] (upper triangle stored).
#[derive(Clone, Debug)]
pub struct BlockMatrix {
    pub pattern: Arc<BlockPattern>,
    pub blocks: Vec<Matrix3<f64>>,
}

impl BlockMatrix {
    pub fn zeros(pattern: Arc<BlockPattern>) -> Self {
        let blocks = vec![Matrix3::zeros(); pattern.num_blocks()];
        Self { pattern, blocks }
    }

    pub fn fill_zero(&mut self) {
        self.blocks.iter_mut().for_each(|b| *b = Matrix3::zeros());
    }

    /// y = A x over all nodes.
    pub fn mul(&self, x: &[Vec3], y: &mut [Vec3]) {
        y.iter_mut().for_each(|v| *v = [0.0; 3]);
        let p = &self.pattern;
        for i in 0..p.num_nodes {
            for k in p.row_ptr[i]..p.row_ptr[i + 1] {
                let j = p.col[k] as usize;
                let b = &self.blocks[k];
                let xj = Vector3::from(x[j]);
                let yi = b * xj;
                for c in 0..3 {
                    y[i][c] += yi[c];
                }
                if j != i {
                    let yj = b.transpose() * Vector3::from(x[i]);
                    for c in 0..3 {
                        y[j][c] += yj[c];
                    }
                }
            }
        }
    }
}

/// What to assemble.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Want {
    Energy,
    Gradient,
    Hessian,
}

/// A shell discretised on a limit basis, with its rest state, law, thickness and loads.
pub struct ShellModel {
    pub basis: LimitBasis,
    pub rest: Vec<RestPoint>,
    pub law: Arc<dyn Law>,
    /// m
    pub thickness: f64,
    /// kg/m²
    pub areal_density: f64,
    /// m/s² (default (0, 0, −9.81) when gravity is on, zero otherwise)
    gravity: Vec3,
    /// Pa, acting along x_u × x_v (a follower load, potential −p V)
    pressure: f64,
    /// End moment about the x axis: (stencil of an edge point, weight × rest length element,
    /// reference angle) and the moment per unit length; potential −m ∫ θ ds with
    /// θ = atan2(x_v,z, x_v,y) unwrapped about the reference
    edge_moment: Option<EdgeMoment>,
    /// ∂E_gravity/∂x_i (constant)
    gravity_gradient: Vec<Vec3>,
    /// Dead loads on the control points, N
    dead_load: Vec<Vec3>,
    /// ∂E_external/∂x_i = gravity gradient − dead load (constant)
    external_gradient: Vec<Vec3>,
    /// (ξ, weight) through the thickness
    thickness_rule: Vec<(f64, f64)>,
    /// Bending of its own (`None`: the paper's section, the law through the thickness)
    bending: Option<BendingRigidity>,
    pub pattern: Arc<BlockPattern>,
    /// Sorted control points touched by each face's Gauss points.
    face_nodes: Vec<Vec<u32>>,
    /// Global block of each pair (a ≤ b) of a face's nodes, packed upper triangle.
    face_blocks: Vec<Vec<u32>>,
    /// Position of every stencil entry in its face's node list (aligned with the stencil table).
    local_index: Vec<u16>,
}

/// Edge points of an end moment (stencil, weight × rest length element, reference angle) and
/// the moment per unit length.
#[derive(Clone, Debug)]
struct EdgeMoment {
    points: Vec<(crate::subdiv::LimitStencil, f64, f64)>,
    per_length: f64,
}

/// The angle equal to `a` modulo 2π nearest to `reference`.
fn unwrap(a: f64, reference: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    a + tau * ((reference - a) / tau).round()
}

/// Parameter sensitivities of the energy and of its gradient.
#[derive(Clone, Debug)]
pub struct Sensitivities {
    /// The law's parameter names, then "thickness".
    pub names: Vec<String>,
    /// ∂E/∂k
    pub energy: Vec<f64>,
    /// ∂(∂E/∂x)/∂k, one array over the control points per parameter
    pub gradient: Vec<Vec<Vec3>>,
}

/// Number of fixed face groups assembled in parallel (fixed so that sums are reproducible).
pub const CHUNKS: usize = 8;

/// Per-group partial sums.
struct Accumulator {
    energy: f64,
    grad: Vec<Vec3>,
    blocks: Vec<Matrix3<f64>>,
}

/// Reused buffers of one face's Hessian.
#[derive(Default)]
struct FaceScratch {
    /// R_a = Σ_k W_ak H_k· per stencil node a, as 5 column-major 3 × 3 blocks
    r: Vec<[f64; 45]>,
    local: Vec<Matrix3<f64>>,
}

/// Setting up a model failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ModelError {
    #[error("Gauss point {point}: {source}")]
    Rest { point: usize, source: RestError },
    #[error("thickness must be positive and finite, got {0}")]
    Thickness(f64),
}

/// Standard gravity, m/s².
pub const STANDARD_GRAVITY: f64 = 9.80665;

impl ShellModel {
    /// A model whose rest shape is the basis's control points, with the warp direction `warp`
    /// (projected onto the rest tangent plane at every Gauss point).
    pub fn new(
        basis: LimitBasis,
        warp: Vec3,
        law: Arc<dyn Law>,
        thickness: f64,
        areal_density: f64,
    ) -> Result<Self, ModelError> {
        if !(thickness > 0.0 && thickness.is_finite()) {
            return Err(ModelError::Thickness(thickness));
        }
        let x = &basis.control_points;
        let rest = (0..basis.num_points())
            .map(|q| {
                let p = basis.limit_stencil(q).apply(x);
                RestPoint::new(&p.d, basis.quad_weight[q], warp)
                    .map_err(|source| ModelError::Rest { point: q, source })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let thickness_rule = GaussLegendre::new(3)
            .expect("3 is a valid rule")
            .through_thickness(thickness);
        let pattern = Arc::new(BlockPattern::from_basis(&basis));
        let npf = basis.points_per_face;
        let mut face_nodes = Vec::with_capacity(basis.num_faces);
        let mut face_blocks = Vec::with_capacity(basis.num_faces);
        let mut local_index = vec![0u16; basis.stencils.indices.len()];
        for face in 0..basis.num_faces {
            let mut nodes: Vec<u32> = (face * npf..(face + 1) * npf)
                .flat_map(|q| basis.stencil(q).0.iter().copied())
                .collect();
            nodes.sort_unstable();
            nodes.dedup();
            for q in face * npf..(face + 1) * npf {
                let off = basis.stencils.offsets[q] as usize;
                for (k, i) in basis.stencil(q).0.iter().enumerate() {
                    local_index[off + k] = nodes.binary_search(i).unwrap_or(0) as u16;
                }
            }
            let mut blocks = Vec::with_capacity(nodes.len() * (nodes.len() + 1) / 2);
            for (a, &i) in nodes.iter().enumerate() {
                for &j in &nodes[a..] {
                    blocks.push(pattern.find(i, j).unwrap_or(0) as u32);
                }
            }
            face_nodes.push(nodes);
            face_blocks.push(blocks);
        }
        let mut model = Self {
            face_nodes,
            face_blocks,
            local_index,
            gravity_gradient: vec![[0.0; 3]; basis.control_points.len()],
            dead_load: vec![[0.0; 3]; basis.control_points.len()],
            external_gradient: vec![[0.0; 3]; basis.control_points.len()],
            basis,
            rest,
            law,
            thickness,
            areal_density,
            gravity: [0.0; 3],
            pressure: 0.0,
            edge_moment: None,
            thickness_rule,
            bending: None,
            pattern,
        };
        model.set_gravity([0.0; 3]);
        Ok(model)
    }

    /// Sets the gravitational acceleration (m/s²), e.g. [0, 0, −9.80665], or zero.
    pub fn set_gravity(&mut self, g: Vec3) {
        self.gravity = g;
        let f = &mut self.gravity_gradient;
        f.iter_mut().for_each(|v| *v = [0.0; 3]);
        for (q, rest) in self.rest.iter().enumerate() {
            let (idx, w) = self.basis.stencil(q);
            for (&i, w) in idx.iter().zip(w) {
                for c in 0..3 {
                    f[i as usize][c] -= self.areal_density * rest.d_area * w[0] * g[c];
                }
            }
        }
        self.update_external();
    }

    /// Sets dead (fixed-direction) loads on the control points, N; `load.len()` must be the
    /// number of control points.
    pub fn set_dead_load(&mut self, load: Vec<Vec3>) {
        assert_eq!(load.len(), self.num_nodes(), "one load per control point");
        self.dead_load = load;
        self.update_external();
    }

    fn update_external(&mut self) {
        for ((e, g), f) in self
            .external_gradient
            .iter_mut()
            .zip(&self.gravity_gradient)
            .zip(&self.dead_load)
        {
            *e = std::array::from_fn(|c| g[c] - f[c]);
        }
    }

    /// Sets a pressure (Pa) on the side x_u × x_v points to. It follows the surface: its
    /// potential is −p V with V = ⅓ ∫ x·(x_u × x_v) du dv, the enclosed volume of a closed
    /// surface.
    pub fn set_pressure(&mut self, p: f64) {
        self.pressure = p;
    }

    pub fn pressure(&self) -> f64 {
        self.pressure
    }

    /// Puts a moment `per_length` (N·m/m) about the x axis on the limit curve v = `v` of
    /// `faces`, conjugate to the angle θ = atan2(x_v·e_z, x_v·e_y) of the tangent across that
    /// edge: its potential is −m ∫ θ ds, so it follows the rotation (a pure end moment rolls a
    /// strip into a circle). θ is single-valued for rotations below ±180°.
    pub fn set_edge_moment(&mut self, faces: &[usize], v: f64, per_length: f64) {
        let surface = self.basis.surface();
        let rule = GaussLegendre::new(4)
            .expect("4 is a valid rule")
            .on_interval(0.0, 1.0);
        let x = &self.basis.control_points;
        let mut points = Vec::new();
        for &face in faces {
            let uvs: Vec<[f64; 2]> = rule.iter().map(|&(u, _)| [u, v]).collect();
            let Ok(stencils) = surface.stencils(face, &uvs) else {
                continue;
            };
            for (s, &(_, w)) in stencils.into_iter().zip(&rule) {
                let t = s.apply(x).d[1];
                let ds = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
                let tv = s.apply(x).d[2];
                let theta = tv[2].atan2(tv[1]);
                points.push((s, w * ds, theta));
            }
        }
        self.edge_moment = Some(EdgeMoment { points, per_length });
    }

    /// Moves each edge point's reference angle to its (unwrapped) angle at `x`.
    pub fn update_edge_angles(&mut self, x: &[Vec3]) {
        if let Some(em) = &mut self.edge_moment {
            for (s, _, reference) in em.points.iter_mut() {
                let t = s.apply(x).d[2];
                *reference = unwrap(t[2].atan2(t[1]), *reference);
            }
        }
    }

    /// Scales the edge moment set by [`ShellModel::set_edge_moment`].
    pub fn scale_edge_moment(&mut self, per_length: f64) {
        if let Some(em) = &mut self.edge_moment {
            em.per_length = per_length;
        }
    }

    /// The edge moment's potential and, as asked, gradient and Hessian.
    fn edge_moment_terms(
        &self,
        x: &[Vec3],
        grad: Option<&mut [Vec3]>,
        hess: Option<&mut BlockMatrix>,
    ) -> f64 {
        let Some(EdgeMoment {
            points,
            per_length: m,
        }) = &self.edge_moment
        else {
            return 0.0;
        };
        let mut grad = grad;
        let mut hess = hess;
        let mut energy = 0.0;
        for (s, wds, reference) in points {
            let t = s.apply(x).d[2];
            let (ty, tz) = (t[1], t[2]);
            let r2 = ty * ty + tz * tz;
            let theta = unwrap(tz.atan2(ty), *reference);
            let c = -m * wds;
            energy += c * theta;
            // ∂θ/∂t = (0, −t_z, t_y)/ρ²; ∂²θ/∂t² in (y, z): [[2 t_y t_z, t_z² − t_y²], [., −2 t_y t_z]]/ρ⁴
            let dt = [0.0, -tz / r2, ty / r2];
            let r4 = r2 * r2;
            let h = Matrix3::new(
                0.0,
                0.0,
                0.0,
                0.0,
                2.0 * ty * tz / r4,
                (tz * tz - ty * ty) / r4,
                0.0,
                (tz * tz - ty * ty) / r4,
                -2.0 * ty * tz / r4,
            );
            if let Some(g) = grad.as_deref_mut() {
                for (&i, w) in s.indices.iter().zip(&s.weights) {
                    for k in 0..3 {
                        g[i as usize][k] += c * w[2] * dt[k];
                    }
                }
            }
            if let Some(hm) = hess.as_deref_mut() {
                for (a, (&i, wi)) in s.indices.iter().zip(&s.weights).enumerate() {
                    for (&j, wj) in s.indices[a..].iter().zip(&s.weights[a..]) {
                        if let Some(k) = hm.pattern.find(i, j) {
                            hm.blocks[k] += (c * wi[2] * wj[2]) * h;
                        }
                    }
                }
            }
        }
        energy
    }

    /// ⅓ ∫ x·(x_u × x_v) du dv over the limit surface (the enclosed volume when closed).
    pub fn volume(&self, x: &[Vec3]) -> f64 {
        (0..self.basis.num_points())
            .map(|q| {
                let p = self.basis.limit_stencil(q).apply(x);
                let (c, a, b) = (
                    Vector3::from(p.d[0]),
                    Vector3::from(p.d[1]),
                    Vector3::from(p.d[2]),
                );
                self.basis.quad_weight[q] * c.dot(&a.cross(&b)) / 3.0
            })
            .sum()
    }

    pub fn gravity(&self) -> Vec3 {
        self.gravity
    }

    /// Constant external force on each control point (gravity and dead loads).
    pub fn external_load(&self) -> Vec<Vec3> {
        self.external_gradient
            .iter()
            .map(|f| [-f[0], -f[1], -f[2]])
            .collect()
    }

    /// Consistent nodal loads of a force per unit rest length `per_length` (N/m) applied along
    /// the limit curve v = `v` (0 or 1) of `faces`.
    pub fn edge_load(&self, faces: &[usize], v: f64, per_length: Vec3) -> Vec<Vec3> {
        let surface = self.basis.surface();
        let rule = GaussLegendre::new(4)
            .expect("4 is a valid rule")
            .on_interval(0.0, 1.0);
        let x = &self.basis.control_points;
        let mut f = vec![[0.0; 3]; self.num_nodes()];
        for &face in faces {
            let uvs: Vec<[f64; 2]> = rule.iter().map(|&(u, _)| [u, v]).collect();
            let Ok(stencils) = surface.stencils(face, &uvs) else {
                continue;
            };
            for (s, &(_, w)) in stencils.iter().zip(&rule) {
                let ds = {
                    let t = s.apply(x).d[1];
                    (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt()
                };
                for (&i, wi) in s.indices.iter().zip(&s.weights) {
                    for c in 0..3 {
                        f[i as usize][c] += w * ds * wi[0] * per_length[c];
                    }
                }
            }
        }
        f
    }

    pub fn num_nodes(&self) -> usize {
        self.basis.control_points.len()
    }

    /// Energy, gradient and Hessian of one Gauss point with respect to y.
    #[inline(always)]
    fn point_terms(
        &self,
        q: usize,
        y: &YVec,
        want: Want,
    ) -> Result<(f64, YVec, Option<YMat>), OutOfDomain> {
        let rest = &self.rest[q];
        if want == Want::Energy {
            let (em, eb) = rest.strain_values(y);
            let e = self.section(&em, &eb, want)?.energy;
            return Ok((rest.d_area * e, YVec::zeros(), None));
        }
        let (m, b) = rest.strains(y);
        let em = Vector3::from(m.value);
        let eb = Vector3::from(b.value);
        let Section {
            energy,
            n,
            mo,
            c0,
            c1,
            c2,
        } = self.section(&em, &eb, want)?;
        let da = rest.d_area;
        let mut g = YVec::zeros();
        for k in 0..3 {
            g += n[k] * m.grad[k] + mo[k] * b.grad[k];
        }
        if want == Want::Gradient {
            return Ok((da * energy, da * g, None));
        }
        // Gᵀ C G with G (6 × 15) the membrane and bending strain gradients stacked and C the
        // 6 × 6 section tangent [[C₀, C₁], [C₁, C₂]]: 540 + 1350 multiply-adds
        let mut gs = nalgebra::SMatrix::<f64, 6, 15>::zeros();
        for k in 0..3 {
            gs.set_row(k, &m.grad[k].transpose());
            gs.set_row(k + 3, &b.grad[k].transpose());
        }
        let mut cs = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        cs.fixed_view_mut::<3, 3>(0, 0).copy_from(&c0);
        cs.fixed_view_mut::<3, 3>(0, 3).copy_from(&c1);
        cs.fixed_view_mut::<3, 3>(3, 0).copy_from(&c1.transpose());
        cs.fixed_view_mut::<3, 3>(3, 3).copy_from(&c2);
        let mut h = gs.transpose() * (cs * gs);
        // the stresses times the strains' own Hessians, formed once as a weighted sum
        rest.add_weighted_hessian(y, &n, &mo, &mut h);
        Ok((da * energy, da * g, Some(da * h)))
    }

    /// Assembles the energy and, as asked, the gradient (over all nodes, into `grad`) and the
    /// Hessian (into `hess`). Gravity and dead loads are included.
    ///
    /// Faces are processed in [`CHUNKS`] fixed contiguous groups in parallel, each group
    /// accumulating into its own arrays, which are then summed in group order: the result does
    /// not depend on the number of threads. Within a face, Gauss-point Hessians are summed into
    /// a dense face block first and scattered once.
    pub fn assemble(
        &self,
        x: &[Vec3],
        want: Want,
        grad: Option<&mut [Vec3]>,
        hess: Option<&mut BlockMatrix>,
    ) -> Result<f64, OutOfDomain> {
        use rayon::prelude::*;
        let nf = self.basis.num_faces;
        let chunks = CHUNKS.min(nf.max(1));
        let nn = self.num_nodes();
        let nb = self.pattern.num_blocks();
        let want_g = grad.is_some() && want != Want::Energy;
        let want_h = hess.is_some() && want == Want::Hessian;
        let parts: Vec<Result<Accumulator, OutOfDomain>> = (0..chunks)
            .into_par_iter()
            .map(|c| {
                let faces = c * nf / chunks..(c + 1) * nf / chunks;
                let mut acc = Accumulator {
                    energy: 0.0,
                    grad: if want_g {
                        vec![[0.0; 3]; nn]
                    } else {
                        Vec::new()
                    },
                    blocks: if want_h {
                        vec![Matrix3::zeros(); nb]
                    } else {
                        Vec::new()
                    },
                };
                self.faces_dispatch(faces, x, want, &mut acc)?;
                Ok(acc)
            })
            .collect();
        let mut energy: f64 = self
            .external_gradient
            .iter()
            .zip(x)
            .map(|(f, p)| f[0] * p[0] + f[1] * p[1] + f[2] * p[2])
            .sum();
        let mut grad = grad;
        let mut hess = hess;
        if let Some(g) = grad.as_deref_mut() {
            g.copy_from_slice(&self.external_gradient);
        }
        if let Some(h) = hess.as_deref_mut() {
            h.fill_zero();
        }
        energy += self.edge_moment_terms(
            x,
            if want_g { grad.as_deref_mut() } else { None },
            if want_h { hess.as_deref_mut() } else { None },
        );
        for part in parts {
            let part = part?;
            energy += part.energy;
            if let (Some(g), true) = (grad.as_deref_mut(), want_g) {
                for (a, b) in g.iter_mut().zip(&part.grad) {
                    for k in 0..3 {
                        a[k] += b[k];
                    }
                }
            }
            if let (Some(h), true) = (hess.as_deref_mut(), want_h) {
                for (a, b) in h.blocks.iter_mut().zip(&part.blocks) {
                    *a += b;
                }
            }
        }
        Ok(energy)
    }

    /// The follower pressure's share of Gauss point q: −p w/3 x·(x_u × x_v), its gradient and
    /// Hessian (the triple product is trilinear: ∂²/∂x∂x_u = −[x_v]×, ∂²/∂x∂x_v = [x_u]×,
    /// ∂²/∂x_u∂x_v = −[x]×).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn pressure_terms(
        &self,
        q: usize,
        x: &[Vec3],
        want_g: bool,
        want_h: bool,
        local: &[u16],
        n: usize,
        acc: &mut Accumulator,
        s: &mut FaceScratch,
    ) {
        let (idx, w) = self.basis.stencil(q);
        let mut d = [Vector3::zeros(); 3];
        for (&i, wi) in idx.iter().zip(w) {
            let p = Vector3::from(x[i as usize]);
            for k in 0..3 {
                d[k] += wi[k] * p;
            }
        }
        let [c, a, b] = d;
        let scale = -self.pressure * self.basis.quad_weight[q] / 3.0;
        acc.energy += scale * c.dot(&a.cross(&b));
        if want_g {
            let parts = [a.cross(&b), b.cross(&c), c.cross(&a)];
            for (&i, wi) in idx.iter().zip(w) {
                let g = wi[0] * parts[0] + wi[1] * parts[1] + wi[2] * parts[2];
                for k in 0..3 {
                    acc.grad[i as usize][k] += scale * g[k];
                }
            }
        }
        if want_h {
            let skew = |v: &Vector3<f64>| {
                Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)
            };
            let (sc, sa, sb) = (skew(&c), skew(&a), skew(&b));
            // B[k][l]: ∂²T/∂d_k∂d_l for d = (x, x_u, x_v)
            let z = Matrix3::zeros();
            let blocks = [[z, -sb, sa], [sb, z, -sc], [-sa, sc, z]];
            for ai in 0..idx.len() {
                let la = local[ai] as usize;
                for bi in ai..idx.len() {
                    let mut blk = Matrix3::zeros();
                    for k in 0..3 {
                        for l in 0..3 {
                            let f = w[ai][k] * w[bi][l];
                            if f != 0.0 && k != l {
                                blk += f * blocks[k][l];
                            }
                        }
                    }
                    let lb = local[bi] as usize;
                    s.local[la * n - la * (la + 1) / 2 + lb] += scale * blk;
                }
            }
        }
    }

    /// Adds the terms of `faces` to `acc`, with the face loop compiled for AVX2 + FMA when the
    /// CPU has them (checked at run time; the same operations in the same order, so the same
    /// results, about 1.4× faster on the Hessian) and for baseline x86-64 otherwise.
    fn faces_dispatch(
        &self,
        faces: std::ops::Range<usize>,
        x: &[Vec3],
        want: Want,
        acc: &mut Accumulator,
    ) -> Result<(), OutOfDomain> {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                // SAFETY: the CPU has the features `faces_avx2` was compiled for
                return unsafe { self.faces_avx2(faces, x, want, acc) };
            }
        }
        self.faces(faces, x, want, acc)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn faces_avx2(
        &self,
        faces: std::ops::Range<usize>,
        x: &[Vec3],
        want: Want,
        acc: &mut Accumulator,
    ) -> Result<(), OutOfDomain> {
        self.faces(faces, x, want, acc)
    }

    #[inline(always)]
    fn faces(
        &self,
        faces: std::ops::Range<usize>,
        x: &[Vec3],
        want: Want,
        acc: &mut Accumulator,
    ) -> Result<(), OutOfDomain> {
        let mut scratch = FaceScratch::default();
        for face in faces {
            self.face_terms(face, x, want, acc, &mut scratch)?;
        }
        Ok(())
    }

    /// Adds one face's energy, gradient and Hessian to `acc`.
    #[inline(always)]
    fn face_terms(
        &self,
        face: usize,
        x: &[Vec3],
        want: Want,
        acc: &mut Accumulator,
        s: &mut FaceScratch,
    ) -> Result<(), OutOfDomain> {
        let npf = self.basis.points_per_face;
        let nodes = &self.face_nodes[face];
        let n = nodes.len();
        let tri = n * (n + 1) / 2;
        let want_h = want == Want::Hessian && !acc.blocks.is_empty();
        let want_g = want != Want::Energy && !acc.grad.is_empty();
        if want_h {
            s.local.clear();
            s.local.resize(tri, Matrix3::zeros());
        }
        for q in face * npf..(face + 1) * npf {
            let (idx, w) = self.basis.stencil(q);
            let off = self.basis.stencils.offsets[q] as usize;
            let local = &self.local_index[off..off + idx.len()];
            let mut d = [[0.0; 3]; 6];
            for (&i, wi) in idx.iter().zip(w) {
                let p = x[i as usize];
                for k in 1..6 {
                    for c in 0..3 {
                        d[k][c] += wi[k] * p[c];
                    }
                }
            }
            let y = kinematic_vector(&d);
            let (e, gy, hy) = self.point_terms(q, &y, want)?;
            acc.energy += e;
            if self.pressure != 0.0 {
                self.pressure_terms(q, x, want_g, want_h, local, n, acc, s);
            }
            if want_g {
                for (&i, wi) in idx.iter().zip(w) {
                    for k in 0..5 {
                        for c in 0..3 {
                            acc.grad[i as usize][c] += wi[k + 1] * gy[3 * k + c];
                        }
                    }
                }
            }
            if let (true, Some(hy)) = (want_h, hy) {
                let m = idx.len();
                s.r.clear();
                s.r.resize(m, [0.0; 45]);
                // R_al = Σ_k W_ak H_kl  (3 × 3 blocks)
                // row k of 3 × 3 blocks of H_y, flattened: ht[k][9l + 3j + i] = H_y[3k + i, 3l + j]
                let mut ht = [[0.0f64; 45]; 5];
                for (k, row) in ht.iter_mut().enumerate() {
                    for l in 0..5 {
                        for j in 0..3 {
                            for i in 0..3 {
                                row[9 * l + 3 * j + i] = hy[(3 * k + i, 3 * l + j)];
                            }
                        }
                    }
                }
                // R_a = Σ_k W_ak H_k· : five length-45 multiply-adds per node
                for a in 0..m {
                    let mut r = [0.0f64; 45];
                    for k in 0..5 {
                        let c = w[a][k + 1];
                        for (x, h) in r.iter_mut().zip(&ht[k]) {
                            *x += c * h;
                        }
                    }
                    s.r[a] = r;
                }
                // H_ab = Σ_l R_al W_bl, into the face's packed upper triangle
                for a in 0..m {
                    let la = local[a] as usize;
                    let ra = &s.r[a];
                    for b in a..m {
                        let mut blk = [0.0f64; 9];
                        for l in 0..5 {
                            let c = w[b][l + 1];
                            for (x, r) in blk.iter_mut().zip(&ra[9 * l..9 * l + 9]) {
                                *x += c * r;
                            }
                        }
                        let lb = local[b] as usize;
                        // stencil and face node lists are both sorted, so la ≤ lb
                        let dst = &mut s.local[la * n - la * (la + 1) / 2 + lb];
                        for (x, v) in dst.as_mut_slice().iter_mut().zip(&blk) {
                            *x += v;
                        }
                    }
                }
            }
        }
        if want_h {
            for (k, blk) in self.face_blocks[face].iter().zip(&s.local) {
                acc.blocks[*k as usize] += blk;
            }
        }
        Ok(())
    }

    /// Lumped (row-sum) mass of each control point, kg: ρ Σ_q dA_q |W_q,i|. With a zero areal
    /// density the same distribution at 1 kg/m² (it then only serves as a metric).
    pub fn lumped_mass(&self) -> Vec<f64> {
        let rho = if self.areal_density > 0.0 {
            self.areal_density
        } else {
            1.0
        };
        let mut m = vec![0.0; self.num_nodes()];
        for (q, rest) in self.rest.iter().enumerate() {
            let (idx, w) = self.basis.stencil(q);
            for (&i, wi) in idx.iter().zip(w) {
                m[i as usize] += rho * rest.d_area * wi[0].abs();
            }
        }
        m
    }

    /// Changes the thickness (m), keeping everything else.
    pub fn set_thickness(&mut self, thickness: f64) -> Result<(), ModelError> {
        if !(thickness > 0.0 && thickness.is_finite()) {
            return Err(ModelError::Thickness(thickness));
        }
        self.thickness = thickness;
        self.thickness_rule = GaussLegendre::new(3)
            .expect("3 is a valid rule")
            .through_thickness(thickness);
        Ok(())
    }

    /// Gives the bending its own rigidities (`None`: the paper's section); see
    /// [`crate::material::bending`].
    pub fn set_bending(&mut self, bending: Option<BendingRigidity>) {
        self.bending = bending;
    }

    pub fn bending(&self) -> Option<BendingRigidity> {
        self.bending
    }

    /// The kinematic vector y of Gauss point `q` at positions `x` (its stencil applied to the
    /// derivatives only).
    fn kinematics_at(&self, q: usize, x: &[Vec3]) -> YVec {
        let (idx, w) = self.basis.stencil(q);
        let mut d = [[0.0; 3]; 6];
        for (&i, wi) in idx.iter().zip(w) {
            for k in 1..6 {
                for c in 0..3 {
                    d[k][c] += wi[k] * x[i as usize][c];
                }
            }
        }
        kinematic_vector(&d)
    }

    /// The smallest and largest membrane strain (Ẽ11, Ẽ22, Ẽ12, warp/weft frame) over the
    /// Gauss points at `x`: what a test actually exercised.
    pub fn membrane_strain_range(&self, x: &[Vec3]) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for q in 0..self.basis.num_points() {
            let (m, _) = self.rest[q].strain_values(&self.kinematics_at(q, x));
            for c in 0..3 {
                lo[c] = lo[c].min(m[c]);
                hi[c] = hi[c].max(m[c]);
            }
        }
        (lo, hi)
    }

    /// Total energy.
    pub fn energy(&self, x: &[Vec3]) -> Result<f64, OutOfDomain> {
        self.assemble(x, Want::Energy, None, None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::OrthotropicStvk;
    use crate::mesh::rectangular_grid;
    use crate::subdiv::BasisOptions;

    /// The AVX2 + FMA build of the face loop gives the baseline build's numbers bit for bit
    /// (no contraction into fused multiply-adds, no reordering).
    #[test]
    fn vectorised_face_loop_matches_the_baseline_bit_for_bit() {
        #[cfg(target_arch = "x86_64")]
        {
            if !(std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma"))
            {
                return;
            }
            let law = OrthotropicStvk {
                a11: 2.0e8,
                a22: 1.2e8,
                a12: 2.0e7,
                g12: 4.0e6,
            };
            let mesh = rectangular_grid(0.05, 0.075, 4, 6);
            let basis = LimitBasis::new(&mesh, BasisOptions::default()).unwrap();
            let model = ShellModel::new(
                basis,
                crate::scene::warp_direction(30.0),
                Arc::new(law),
                1.8e-4,
                0.1,
            )
            .unwrap();
            let x: Vec<Vec3> = model
                .basis
                .control_points
                .iter()
                .map(|p| [p[0] * 0.98, p[1] * 1.07, 2e-3 * (60.0 * p[0]).sin()])
                .collect();
            let nf = model.basis.num_faces;
            let fresh = || Accumulator {
                energy: 0.0,
                grad: vec![[0.0; 3]; model.num_nodes()],
                blocks: vec![Matrix3::zeros(); model.pattern.num_blocks()],
            };
            let (mut plain, mut fast) = (fresh(), fresh());
            model.faces(0..nf, &x, Want::Hessian, &mut plain).unwrap();
            // SAFETY: the features were detected above
            unsafe { model.faces_avx2(0..nf, &x, Want::Hessian, &mut fast) }.unwrap();
            assert!(plain.energy != 0.0);
            assert_eq!(plain.energy.to_bits(), fast.energy.to_bits());
            assert_eq!(plain.grad, fast.grad);
            assert_eq!(plain.blocks, fast.blocks);
        }
    }
}
