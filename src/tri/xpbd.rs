//! XPBD (Macklin et al. 2016), run quasi-statically as Larionov et al. 2022 do, on the `xpbd`
//! model's constraints: per triangle the Green strains C = (E₁₁, E₂₂, 2E₁₂) with stiffness
//! α⁻¹ = A [[C₀₀, C₀₁, 0], [C₀₁, C₁₁, 0], [0, 0, C₂₂]] (one 3 × 3 block solve per triangle),
//! per hinge the dihedral angle C = θ with α⁻¹ = D l/h (the hinge energy of [`super::model`]).
//! Their potential ½ Cᵀ α⁻¹ C is [`TriModel`]'s energy, so Newton's equilibrium is the target.
//!
//! Each step predicts x̃ = x + Δt² M⁻¹ f (velocities dropped: quasi-static), then takes
//! Gauss–Seidel sweeps over the constraints: (∇C M⁻¹ ∇Cᵀ + α̃) Δλ = −C − α̃ λ, α̃ = α/Δt²,
//! x += M⁻¹ ∇Cᵀ Δλ. A step minimises ½‖x − x̃‖²_M/Δt² + U approximately; repeated steps
//! descend to a minimum of U − f·x. Cost per sweep: about 150 flops per triangle and 200 per
//! hinge, against Newton's assembly and factorisation; the price is the sweep count, which
//! grows with the stiffness ratio (the reason the solver comparison exists).

use super::model::{HingeEl, TriModel, Triangle};
use super::params::TriKind;
use crate::model::{ClothModel, Want};
use crate::Vec3;
use nalgebra::{Matrix3, Vector3};
use std::time::Instant;

/// XPBD settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct XpbdOptions {
    /// Quasi-static steps.
    pub steps: usize,
    /// Gauss–Seidel sweeps per step.
    pub sweeps: usize,
    /// s
    pub dt: f64,
}

impl Default for XpbdOptions {
    fn default() -> Self {
        Self {
            steps: 50,
            sweeps: 20,
            dt: 0.01,
        }
    }
}

/// What an XPBD run did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct XpbdReport {
    pub steps: usize,
    pub sweeps: usize,
    /// ‖∇(U − f·x)‖ over the free DOFs / max(‖f‖, ‖∇(U − f·x)‖ over all DOFs) at the end (the
    /// second: the reactions, when there is no load): the distance from equilibrium.
    pub residual: f64,
    pub seconds: f64,
}

/// The XPBD solver could not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum XpbdError {
    #[error("XPBD needs the xpbd model (linear orthotropic StVK and dihedral bending), got {0}")]
    Model(&'static str),
    #[error("the xpbd model's stiffnesses must be linear (one control value each)")]
    Nonlinear,
    #[error("the state left the model's domain (a degenerate triangle or hinge)")]
    Degenerate,
}

/// ∇θ of a hinge (x1, x2 on the edge, x3 and x4 opposite): the opposite vertices move along
/// their triangles' normals, ∇₃θ = −|e| n₃/|n₃|², ∇₄θ = −|e| n₄/|n₄|² (n unnormalised, twice
/// the area), and the edge nodes carry the negative of those, split by where each opposite
/// vertex projects on the edge (the gradient is translation- and rotation-free).
pub fn dihedral_gradient(p: [Vector3<f64>; 4]) -> [Vector3<f64>; 4] {
    let e = p[1] - p[0];
    let le2 = e.norm_squared();
    let le = le2.sqrt();
    let na = e.cross(&(p[2] - p[0]));
    let nb = (p[3] - p[0]).cross(&e);
    let g3 = -le / na.norm_squared() * na;
    let g4 = -le / nb.norm_squared() * nb;
    let (ta, tb) = ((p[2] - p[0]).dot(&e) / le2, (p[3] - p[0]).dot(&e) / le2);
    let g1 = -((1.0 - ta) * g3 + (1.0 - tb) * g4);
    let g2 = -(ta * g3 + tb * g4);
    [g1, g2, g3, g4]
}

/// Runs XPBD on `model` (kind xpbd) from `x`, with the DOFs `fixed` held (whole nodes: a node
/// with any DOF fixed is held entirely).
pub fn xpbd(
    model: &TriModel,
    fixed: &[bool],
    x: &mut [Vec3],
    opts: &XpbdOptions,
) -> Result<XpbdReport, XpbdError> {
    let t0 = Instant::now();
    let m = &model.material;
    if m.kind != TriKind::Xpbd {
        return Err(XpbdError::Model(m.kind.name()));
    }
    if m.curves.iter().any(|c| c.k.len() != 1) {
        return Err(XpbdError::Nonlinear);
    }
    let k = |i: usize| m.curves[i].k[0];
    let stiffness = Matrix3::new(k(0), m.coupling, 0.0, m.coupling, k(1), 0.0, 0.0, 0.0, k(2));
    let n = model.num_nodes();
    let w = inverse_masses(model, fixed);
    let force = model.external_load();
    let dt2 = opts.dt * opts.dt;
    // compliance blocks α̃ = (A K)⁻¹ / Δt² and hinge compliances h / (D l Δt²)
    let tri_alpha: Vec<Matrix3<f64>> = model
        .triangles
        .iter()
        .map(|t| {
            (stiffness * t.area)
                .try_inverse()
                .map_or(Matrix3::zeros(), |c| c / dt2)
        })
        .collect();
    let hinge_alpha: Vec<f64> = model
        .hinges
        .iter()
        .map(|h| {
            let d = k(h.mix.warp) * h.mix.c2 + k(h.mix.weft) * (1.0 - h.mix.c2);
            h.height / (d * h.length * dt2)
        })
        .collect();
    for _ in 0..opts.steps {
        for i in 0..n {
            if w[i] > 0.0 {
                for c in 0..3 {
                    x[i][c] += dt2 * w[i] * force[i][c];
                }
            }
        }
        let mut lt = vec![Vector3::zeros(); model.triangles.len()];
        let mut lh = vec![0.0; model.hinges.len()];
        for _ in 0..opts.sweeps {
            for (ti, t) in model.triangles.iter().enumerate() {
                project_triangle(t, &tri_alpha[ti], &mut lt[ti], &w, x)?;
            }
            for (hi, h) in model.hinges.iter().enumerate() {
                project_hinge(h, hinge_alpha[hi], &mut lh[hi], &w, x)?;
            }
        }
    }
    let residual = residual(model, fixed, &w, &force, x)?;
    Ok(XpbdReport {
        steps: opts.steps,
        sweeps: opts.steps * opts.sweeps,
        residual,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The inverse lumped mass of each node, 0 where the node is held.
fn inverse_masses(model: &TriModel, fixed: &[bool]) -> Vec<f64> {
    let n = model.num_nodes();
    let mass = model.lumped_mass();
    (0..n)
        .map(|i| {
            if fixed[3 * i..3 * i + 3].iter().any(|&f| f) {
                0.0
            } else {
                1.0 / mass[i]
            }
        })
        .collect()
}

fn v(p: Vec3) -> Vector3<f64> {
    Vector3::new(p[0], p[1], p[2])
}

/// One Gauss–Seidel update of a triangle's strain constraints (compliance block `alpha`,
/// multipliers `lambda`): a 3 × 3 block solve, then the nodes moved by M⁻¹ ∇Cᵀ Δλ.
fn project_triangle(
    t: &Triangle,
    alpha: &Matrix3<f64>,
    lambda: &mut Vector3<f64>,
    w: &[f64],
    x: &mut [Vec3],
) -> Result<(), XpbdError> {
    let p: [Vector3<f64>; 3] = t.nodes.map(|i| v(x[i as usize]));
    let wu = t.cu[0] * p[0] + t.cu[1] * p[1] + t.cu[2] * p[2];
    let wv = t.cv[0] * p[0] + t.cv[1] * p[1] + t.cv[2] * p[2];
    let c = Vector3::new(
        0.5 * (wu.norm_squared() - 1.0),
        0.5 * (wv.norm_squared() - 1.0),
        wu.dot(&wv),
    );
    // gradient rows per node: ∂C/∂x_a = [cu_a w_u; cv_a w_v; cu_a w_v + cv_a w_u]
    let grad = |a: usize| -> [Vector3<f64>; 3] {
        [t.cu[a] * wu, t.cv[a] * wv, t.cu[a] * wv + t.cv[a] * wu]
    };
    let mut s = *alpha;
    let gs: Vec<[Vector3<f64>; 3]> = (0..3).map(grad).collect();
    for (a, g) in gs.iter().enumerate() {
        let wa = w[t.nodes[a] as usize];
        for r in 0..3 {
            for q in 0..3 {
                s[(r, q)] += wa * g[r].dot(&g[q]);
            }
        }
    }
    let rhs = -c - alpha * *lambda;
    let dl = s.try_inverse().ok_or(XpbdError::Degenerate)? * rhs;
    *lambda += dl;
    for (a, g) in gs.iter().enumerate() {
        let i = t.nodes[a] as usize;
        let dx = w[i] * (g[0] * dl[0] + g[1] * dl[1] + g[2] * dl[2]);
        for q in 0..3 {
            x[i][q] += dx[q];
        }
    }
    Ok(())
}

/// One Gauss–Seidel update of a hinge's angle constraint (compliance `alpha`, multiplier
/// `lambda`).
fn project_hinge(
    h: &HingeEl,
    alpha: f64,
    lambda: &mut f64,
    w: &[f64],
    x: &mut [Vec3],
) -> Result<(), XpbdError> {
    let p: [Vector3<f64>; 4] = h.nodes.map(|i| v(x[i as usize]));
    let e = p[1] - p[0];
    let na = e.cross(&(p[2] - p[0]));
    let nb = (p[3] - p[0]).cross(&e);
    let c = (na.cross(&nb).dot(&e) / e.norm()).atan2(na.dot(&nb));
    let g = dihedral_gradient(p);
    let ww: f64 = (0..4)
        .map(|a| w[h.nodes[a] as usize] * g[a].norm_squared())
        .sum();
    let denom = ww + alpha;
    if !(denom > 0.0 && c.is_finite()) {
        return Err(XpbdError::Degenerate);
    }
    let dl = (-c - alpha * *lambda) / denom;
    *lambda += dl;
    for a in 0..4 {
        let i = h.nodes[a] as usize;
        for q in 0..3 {
            x[i][q] += w[i] * g[a][q] * dl;
        }
    }
    Ok(())
}

/// ‖g over the free DOFs‖ relative to the larger of ‖f‖ and ‖g‖ at `x`.
fn residual(
    model: &TriModel,
    fixed: &[bool],
    w: &[f64],
    force: &[Vec3],
    x: &[Vec3],
) -> Result<f64, XpbdError> {
    let n = model.num_nodes();
    let mut g = vec![[0.0; 3]; n];
    model
        .assemble(x, Want::Gradient, Some(&mut g), None)
        .map_err(|_| XpbdError::Degenerate)?;
    let free: f64 = (0..3 * n)
        .filter(|&d| !fixed[d] && w[d / 3] > 0.0)
        .map(|d| g[d / 3][d % 3].powi(2))
        .sum::<f64>()
        .sqrt();
    let norm = |v: &[Vec3]| v.iter().flatten().map(|c| c * c).sum::<f64>().sqrt();
    let scale = norm(force).max(norm(&g)).max(1e-300);
    Ok(free / scale)
}
