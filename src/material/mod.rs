//! Constitutive laws: energy per unit rest volume ψ(Ẽ) of the Green strain in the warp/weft
//! frame, with its gradient (the second Piola–Kirchhoff stress) and Hessian (the tangent).
//!
//! Strains are (Ẽ₁₁, Ẽ₂₂, Ẽ₁₂) with tensor shear; 1 is the warp, 2 the weft. This module owns
//! the orthotropic St. Venant–Kirchhoff law (Clyde et al. 2017, Eq. 2 with every η linear) and
//! the material file; the paper's nonlinear η and the parameter derivatives the fitter needs
//! extend [`Law`].

pub mod arcsim;
pub mod bending;
mod eta;
pub mod file;
pub mod json;
mod orthotropic;

pub use bending::BendingRigidity;
pub use eta::Eta;
pub use file::{
    load_material, material_toml, parse_material, FabricMaterial, MaterialFileError, MODULUS_RANGE,
};
pub use orthotropic::{Cutoffs, Orthotropic, ParamResponse, ShearCoupling};

use nalgebra::{Matrix3, Vector3};

/// ψ, ∂ψ/∂Ẽ and ∂²ψ/∂Ẽ² at one strain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Response {
    pub psi: f64,
    pub stress: Vector3<f64>,
    pub tangent: Matrix3<f64>,
}

/// A strain at which the law cannot be evaluated (the solver shortens its step).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("material law undefined at strain {strain:?}")]
pub struct OutOfDomain {
    pub strain: [f64; 3],
}

/// A hyperelastic law of the in-plane Green strain.
pub trait Law: Send + Sync {
    fn response(&self, e: &Vector3<f64>) -> Result<Response, OutOfDomain>;

    /// Names of the law's parameters k, in the order of [`Law::param_response`].
    fn param_names(&self) -> Vec<String>;

    /// ∂ψ/∂k and ∂²ψ/∂Ẽ∂k for every parameter.
    fn param_response(&self, e: &Vector3<f64>) -> Result<ParamResponse, OutOfDomain>;

    /// The yarn part ψ_y(Ẽ₁₁, Ẽ₂₂) = ψ(Ẽ₁₁, Ẽ₂₂, 0) of a law whose rest ψ − ψ_y vanishes with
    /// its gradient at Ẽ₁₂ = 0 (both laws here: the warp, weft and a₁₂ terms against the shear
    /// term, which the optional tension–shear coupling lets depend on the yarn strains too):
    /// ψ at (Ẽ₁₁, Ẽ₂₂, 0) with the shear stress and the shear row and column of the tangent
    /// removed. What the selective reduced integration of
    /// [`crate::assembly::YarnRule::Centre`] evaluates once per face (the rest stays on the
    /// Gauss points).
    fn yarn_response(&self, e: &Vector3<f64>) -> Result<Response, OutOfDomain> {
        let mut r = self.response(&Vector3::new(e[0], e[1], 0.0))?;
        r.stress[2] = 0.0;
        for k in 0..3 {
            r.tangent[(2, k)] = 0.0;
            r.tangent[(k, 2)] = 0.0;
        }
        Ok(r)
    }

    /// max(a₁₁, a₂₂)/G₁₂ at zero strain, the ratio that decides [`crate::assembly::YarnRule::Auto`]
    /// (`None`: not an orthotropic law of yarns and shear; the full rule is kept).
    fn yarn_shear_ratio(&self) -> Option<f64> {
        None
    }

    /// [`Law::param_response`] of the yarn part [`Law::yarn_response`].
    fn yarn_param_response(&self, e: &Vector3<f64>) -> Result<ParamResponse, OutOfDomain> {
        let mut r = self.param_response(&Vector3::new(e[0], e[1], 0.0))?;
        for d in &mut r.dstress {
            d[2] = 0.0;
        }
        Ok(r)
    }
}

/// ψ = a₁₁/2 Ẽ₁₁² + a₁₂ Ẽ₁₁Ẽ₂₂ + a₂₂/2 Ẽ₂₂² + G₁₂ Ẽ₁₂² (Pa). Isotropic when a₁₁ = a₂₂ and
/// G₁₂ = a₁₁ − a₁₂ (Lamé: a₁₁ = λ + 2μ, a₁₂ = λ, G₁₂ = 2μ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrthotropicStvk {
    pub a11: f64,
    pub a22: f64,
    pub a12: f64,
    pub g12: f64,
}

impl OrthotropicStvk {
    /// The isotropic St. Venant–Kirchhoff law of Young's modulus `e` and Poisson ratio `nu`
    /// (plane stress constants, as thin shells use).
    pub fn isotropic(e: f64, nu: f64) -> Self {
        let a11 = e / (1.0 - nu * nu);
        let a12 = nu * a11;
        Self {
            a11,
            a22: a11,
            a12,
            g12: a11 - a12,
        }
    }

    fn tangent(&self) -> Matrix3<f64> {
        Matrix3::new(
            self.a11,
            self.a12,
            0.0,
            self.a12,
            self.a22,
            0.0,
            0.0,
            0.0,
            2.0 * self.g12,
        )
    }
}

impl Law for OrthotropicStvk {
    fn yarn_shear_ratio(&self) -> Option<f64> {
        (self.g12 > 0.0).then(|| self.a11.max(self.a22) / self.g12)
    }

    fn param_names(&self) -> Vec<String> {
        ["a11", "a22", "a12", "g12"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    fn param_response(&self, e: &Vector3<f64>) -> Result<ParamResponse, OutOfDomain> {
        Ok(ParamResponse {
            dpsi: vec![
                0.5 * e[0] * e[0],
                0.5 * e[1] * e[1],
                e[0] * e[1],
                e[2] * e[2],
            ],
            dstress: vec![
                Vector3::new(e[0], 0.0, 0.0),
                Vector3::new(0.0, e[1], 0.0),
                Vector3::new(e[1], e[0], 0.0),
                Vector3::new(0.0, 0.0, 2.0 * e[2]),
            ],
        })
    }

    fn response(&self, e: &Vector3<f64>) -> Result<Response, OutOfDomain> {
        let c = self.tangent();
        let stress = c * e;
        Ok(Response {
            psi: 0.5 * e.dot(&stress),
            stress,
            tangent: c,
        })
    }
}

/// Warp direction of a strip cut at `angle_deg` from the weft, axis along y.
pub fn warp_direction(angle_deg: f64) -> crate::Vec3 {
    let t = angle_deg.to_radians();
    [t.cos(), -t.sin(), 0.0]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stvk_energy_gradient_hessian_are_consistent() {
        let law = OrthotropicStvk {
            a11: 3.0e7,
            a22: 1.2e7,
            a12: 4.0e6,
            g12: 9.0e5,
        };
        let e = Vector3::new(0.03, -0.01, 0.02);
        let r = law.response(&e).unwrap();
        let want = 0.5 * 3.0e7 * 0.03f64.powi(2)
            + 4.0e6 * 0.03 * -0.01
            + 0.5 * 1.2e7 * 0.01f64.powi(2)
            + 9.0e5 * 0.02f64.powi(2);
        assert!((r.psi - want).abs() < 1e-9 * want);
        let h = 1e-7;
        for i in 0..3 {
            let mut ep = e;
            let mut em = e;
            ep[i] += h;
            em[i] -= h;
            let (rp, rm) = (law.response(&ep).unwrap(), law.response(&em).unwrap());
            assert!(((rp.psi - rm.psi) / (2.0 * h) - r.stress[i]).abs() < 1e-6 * r.stress.norm());
            for j in 0..3 {
                let fd = (rp.stress[j] - rm.stress[j]) / (2.0 * h);
                assert!((fd - r.tangent[(j, i)]).abs() < 1e-6 * 3e7);
            }
        }
    }

    #[test]
    fn isotropic_constants_follow_the_lame_convention() {
        let law = OrthotropicStvk::isotropic(1.0e6, 0.3);
        assert_eq!(law.a11, law.a22);
        assert!((law.g12 - (law.a11 - law.a12)).abs() < 1e-9);
        // plane stress: a11 = E/(1−ν²)
        assert!((law.a11 - 1.0e6 / 0.91).abs() < 1e-6);
    }
}
