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
mod face_loop;
mod loads;
mod projection;
mod reduced;
mod section;
mod sensitivities;
pub use crate::model::{BlockMatrix, BlockPattern, Want};
pub use face_loop::CHUNKS;
pub use reduced::{YarnRule, CENTRE_FROM_RATIO};
pub use sensitivities::BENDING_PARAMS;

use crate::material::{BendingRigidity, Law, OutOfDomain};
use crate::quadrature::GaussLegendre;
use crate::shell::{kinematic_vector, RestError, RestPoint, YMat, YVec};
use crate::subdiv::LimitBasis;
use crate::Vec3;
use face_loop::{Accumulator, FaceScratch};
use loads::EdgeMoment;
use nalgebra::Vector3;
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
