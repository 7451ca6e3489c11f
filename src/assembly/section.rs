//! The section law: energy per unit rest area of a Gauss point as a function of its membrane
//! strain Ẽ_m and bending strain Ẽ_b (warp/weft frame), with the stress resultants and the
//! section tangent that Newton needs.
//!
//! - The paper's section (Clyde et al. 2017 §3): W = ∫ ψ(Ẽ_m + ξ Ẽ_b) dξ over ξ ∈ [−τ/2, τ/2],
//!   by a three-point Gauss–Legendre rule (exact for St. Venant–Kirchhoff, whose integrand is
//!   quadratic in ξ).
//! - Bending of its own ([`crate::material::bending`]): W = τ ψ(Ẽ_m) + ½ Ẽ_bᵀ D Ẽ_b with D the
//!   rigidities' diagonal tangent; one law evaluation per point, against the paper's three.
//! - Under [`super::YarnRule::Centre`] a Gauss point carries the section less τ ψ_y(Ẽ_m) and
//!   a face centre τ ψ_y(Ẽ_m) alone (see [`super::reduced`]).

use super::{Part, ShellModel, Want};
use crate::material::OutOfDomain;
use nalgebra::{Matrix3, Vector3};

/// W, n = ∂W/∂Ẽ_m, m = ∂W/∂Ẽ_b and the tangent blocks [[C₀, C₁], [C₁ᵀ, C₂]] (left at zero
/// unless the Hessian is wanted; n and m unless the gradient is).
pub(super) struct Section {
    pub energy: f64,
    pub n: Vector3<f64>,
    pub mo: Vector3<f64>,
    pub c0: Matrix3<f64>,
    pub c1: Matrix3<f64>,
    pub c2: Matrix3<f64>,
}

impl Section {
    fn zero() -> Self {
        Self {
            energy: 0.0,
            n: Vector3::zeros(),
            mo: Vector3::zeros(),
            c0: Matrix3::zeros(),
            c1: Matrix3::zeros(),
            c2: Matrix3::zeros(),
        }
    }
}

impl ShellModel {
    /// The response of `part` of the section at one point.
    #[inline(always)]
    pub(super) fn section(
        &self,
        em: &Vector3<f64>,
        eb: &Vector3<f64>,
        want: Want,
        part: Part,
    ) -> Result<Section, OutOfDomain> {
        let mut s = match part {
            Part::Whole => return self.whole_section(em, eb, want),
            Part::LessYarn => self.whole_section(em, eb, want)?,
            Part::Yarn => Section::zero(),
        };
        let moved = self.centres.as_ref().map_or(1.0, |c| c.moved);
        let sign = if part == Part::Yarn { moved } else { -moved };
        let tau = sign * self.thickness;
        let r = self.law.yarn_response(em)?;
        s.energy += tau * r.psi;
        if want != Want::Energy {
            s.n += tau * r.stress;
        }
        if want.hessian() {
            s.c0 += tau * r.tangent;
        }
        Ok(s)
    }

    /// The whole section's response at one point.
    #[inline(always)]
    fn whole_section(
        &self,
        em: &Vector3<f64>,
        eb: &Vector3<f64>,
        want: Want,
    ) -> Result<Section, OutOfDomain> {
        let mut s = Section::zero();
        if let Some(b) = &self.bending {
            let tau = self.thickness;
            let d = b.matrix();
            let r = self.law.response(em)?;
            let m = d * eb;
            s.energy = tau * r.psi + 0.5 * eb.dot(&m);
            if want != Want::Energy {
                s.n = tau * r.stress;
                s.mo = m;
            }
            if want.hessian() {
                s.c0 = tau * r.tangent;
                s.c2 = d;
            }
            return Ok(s);
        }
        for &(xi, w) in &self.thickness_rule {
            let r = self.law.response(&(em + xi * eb))?;
            s.energy += w * r.psi;
            if want != Want::Energy {
                s.n += w * r.stress;
                s.mo += w * xi * r.stress;
            }
            if want.hessian() {
                s.c0 += w * r.tangent;
                s.c1 += (w * xi) * r.tangent;
                s.c2 += (w * xi * xi) * r.tangent;
            }
        }
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::BlockMatrix;
    use crate::material::{BendingRigidity, OrthotropicStvk};
    use crate::mesh::rectangular_grid;
    use crate::subdiv::{BasisOptions, LimitBasis};
    use crate::Vec3;
    use std::sync::Arc;

    /// With St. Venant–Kirchhoff and a12 = 0 the paper's section is τ ψ(ε) + τ³/12 ψ(κ)
    /// exactly, which is bending of its own with B = τ³/12 (a11, a22, G12): energy, gradient
    /// and Hessian agree to round-off on a stretched, sheared and curved sheet.
    #[test]
    fn own_bending_reproduces_the_paper_section_for_stvk() {
        let (tau, law) = (
            1.8e-4,
            OrthotropicStvk {
                a11: 2.0e8,
                a22: 1.2e8,
                a12: 0.0,
                g12: 4.0e6,
            },
        );
        let mesh = rectangular_grid(0.05, 0.075, 4, 6);
        let basis = LimitBasis::new(&mesh, BasisOptions::default()).unwrap();
        let warp = crate::material::warp_direction(30.0);
        let mut model = ShellModel::new(basis, warp, Arc::new(law), tau, 0.1).unwrap();
        let x: Vec<Vec3> = model
            .basis
            .control_points
            .iter()
            .map(|p| {
                [
                    p[0] * 0.98 + 0.02 * p[1],
                    p[1] * 1.07,
                    2e-3 * (60.0 * p[0]).sin() + 1e-3 * (40.0 * p[1]).cos(),
                ]
            })
            .collect();
        let run = |m: &ShellModel| {
            let mut g = vec![[0.0; 3]; m.num_nodes()];
            let mut h = BlockMatrix::zeros(m.pattern.clone());
            let e = m
                .assemble(&x, Want::Hessian, Some(&mut g), Some(&mut h))
                .unwrap();
            (e, g, h)
        };
        let (e0, g0, h0) = run(&model);
        let k = tau.powi(3) / 12.0;
        model.set_bending(Some(BendingRigidity {
            warp: k * law.a11,
            weft: k * law.a22,
            twist: k * law.g12,
        }));
        let (e1, g1, h1) = run(&model);
        assert!((e1 - e0).abs() <= 1e-12 * e0.abs(), "{e0} {e1}");
        let gmax = g0.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
        for (a, b) in g0.iter().flatten().zip(g1.iter().flatten()) {
            assert!((a - b).abs() <= 1e-11 * gmax, "{a} {b}");
        }
        let hmax = h0.blocks.iter().fold(0.0f64, |a, b| a.max(b.amax()));
        for (a, b) in h0.blocks.iter().zip(&h1.blocks) {
            assert!((a - b).amax() <= 1e-11 * hmax);
        }
    }
}
