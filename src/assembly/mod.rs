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

mod cloth_model;
mod loads;
mod projection;
mod reduced;
mod section;
mod sensitivities;
pub use crate::model::{BlockMatrix, BlockPattern, Want};
pub use reduced::{YarnRule, CENTRE_FROM_RATIO};
pub use sensitivities::BENDING_PARAMS;

use crate::material::{BendingRigidity, Law, OutOfDomain};
use crate::quadrature::GaussLegendre;
use crate::shell::{kinematic_vector, RestError, RestPoint, YMat, YVec};
use crate::subdiv::LimitBasis;
use crate::Vec3;
use loads::EdgeMoment;
use nalgebra::{Matrix3, Vector3};
use reduced::{Centres, Part};
use section::Section;
use std::sync::Arc;

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
    /// The warp direction the rest frames were built with.
    warp: Vec3,
    /// The face centres carrying the yarn terms ([`YarnRule::Centre`]; `None`: the full rule).
    centres: Option<Centres>,
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
    #[error("yarn terms on face centres: {0}")]
    Centre(String),
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
            warp,
            centres: None,
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
        let part = if self.centres.is_some() {
            Part::LessYarn
        } else {
            Part::Whole
        };
        self.rest_point_terms(&self.rest[q], y, want, part)
    }

    /// Energy, gradient and Hessian with respect to y of `part` of the section at a point of
    /// rest frame `rest`.
    #[inline(always)]
    fn rest_point_terms(
        &self,
        rest: &RestPoint,
        y: &YVec,
        want: Want,
        part: Part,
    ) -> Result<(f64, YVec, Option<YMat>), OutOfDomain> {
        if want == Want::Energy {
            let (em, eb) = rest.strain_values(y);
            let e = self.section(&em, &eb, want, part)?.energy;
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
        } = self.section(&em, &eb, want, part)?;
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
        if want == Want::ProjectedHessian {
            cs = projection::psd_part(&cs);
            let mut h = gs.transpose() * (cs * gs);
            rest.add_tensile_membrane_hessian(&n, &mut h);
            return Ok((da * energy, da * g, Some(da * h)));
        }
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
        let want_h = hess.is_some() && want.hessian();
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
        let want_h = want.hessian() && !acc.blocks.is_empty();
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
            self.scatter(idx, w, local, n, &gy, hy, want, acc, s);
        }
        self.centre_terms(face, x, want, acc, s)?;
        if want_h {
            for (k, blk) in self.face_blocks[face].iter().zip(&s.local) {
                acc.blocks[*k as usize] += blk;
            }
        }
        Ok(())
    }

    /// Adds a point's y-gradient and y-Hessian, expanded through its stencil (`local`: the
    /// entries' positions in the face's `n` nodes), to the accumulator and the face block.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn scatter(
        &self,
        idx: &[u32],
        w: &[[f64; 6]],
        local: &[u16],
        n: usize,
        gy: &YVec,
        hy: Option<YMat>,
        want: Want,
        acc: &mut Accumulator,
        s: &mut FaceScratch,
    ) {
        let want_h = want.hessian() && !acc.blocks.is_empty();
        let want_g = want != Want::Energy && !acc.grad.is_empty();
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
                crate::material::warp_direction(30.0),
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
