//! Bending of its own: flexural rigidities per direction in place of the paper's τ³/12 link to
//! the membrane law.
//!
//! In the paper's model (Clyde et al. 2017 §3) the bending energy is the membrane law
//! integrated through the thickness, so the warp/weft bending ratio is the tensile ratio and
//! one thickness serves both cantilevers; the paper's §7 names this as the model's limit and
//! its Table 4 misses drape angles by up to 17°. Real fabrics disagree: across published
//! cantilever data the warp/weft bending ratio spans about 0.6–3.8.
//!
//! Here the section energy is split into the membrane law at the mid-surface and a quadratic
//! bending energy with its own rigidities (N·m, flexural rigidity per unit width, what ASTM
//! D1388 reports as G = ρ g c³):
//!
//! W_b = ½ B_warp κ̃₁₁² + ½ B_weft κ̃₂₂² + B_twist κ̃₁₂²
//!
//! with κ̃ the bending strain in the warp/weft frame (tensor twist). W_b is convex exactly when
//! the three rigidities are positive. There is no bending Poisson coupling: a narrow strip's
//! anticlastic curvature is free, so a cantilever cut at φ from the warp has the beam rigidity
//! 1/B(φ) = cos⁴φ/B_warp + sin⁴φ/B_weft + 2 sin²φ cos²φ/B_twist.
//! For a St. Venant–Kirchhoff law with a12 = 0 the paper's section gives exactly this energy
//! with B_warp = τ³a11/12, B_weft = τ³a22/12, B_twist = τ³G12/12 (a test checks it).
//!
//! Cantilevers along the warp and the weft fix B_warp and B_weft; only an off-axis (bias)
//! cantilever fixes B_twist. Without one the twist is *assumed*: the bias beam compliance
//! relative to the mean of warp and weft is taken from the membrane law's small-strain
//! compliance at 45° (what the paper's model gives), so that a fabric soft in shear is soft in
//! twist too.

use super::Law;
use nalgebra::{Matrix3, Vector3};

/// Flexural rigidities per unit width, N·m (the energy above).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BendingRigidity {
    pub warp: f64,
    pub weft: f64,
    pub twist: f64,
}

/// Why rigidities could not be formed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BendingError {
    #[error("bending rigidities must be positive and finite, got {0:?}")]
    NotPositive(f64),
    #[error(
        "a bias rigidity of {bias:e} N·m is stiffer than warp ({warp:e}) and weft ({weft:e}) allow: need 4/B_bias > 1/B_warp + 1/B_weft"
    )]
    BiasTooStiff { warp: f64, weft: f64, bias: f64 },
}

fn positive(v: f64) -> Result<f64, BendingError> {
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(BendingError::NotPositive(v))
    }
}

/// ψ-compliance of uniaxial stress along φ (radians from the warp) of a stiffness matrix in the
/// (1, 2, tensor 12) convention: vᵀ C⁻¹ v with v = (cos²φ, sin²φ, 2 sinφ cosφ).
pub fn uniaxial_compliance(c: &Matrix3<f64>, phi: f64) -> Option<f64> {
    let (s, co) = phi.sin_cos();
    let v = Vector3::new(co * co, s * s, 2.0 * s * co);
    c.try_inverse().map(|ci| v.dot(&(ci * v)))
}

impl BendingRigidity {
    /// Rigidities from measured warp, weft and bias (45°) beam rigidities.
    pub fn from_bias(warp: f64, weft: f64, bias: f64) -> Result<Self, BendingError> {
        let (warp, weft, bias) = (positive(warp)?, positive(weft)?, positive(bias)?);
        // 1/B45 = (1/Bw + 1/Bf)/4 + 1/(2 Bt)
        let inv = 2.0 * (1.0 / bias - 0.25 * (1.0 / warp + 1.0 / weft));
        if inv <= 0.0 || !inv.is_finite() {
            return Err(BendingError::BiasTooStiff { warp, weft, bias });
        }
        Ok(Self {
            warp,
            weft,
            twist: 1.0 / inv,
        })
    }

    /// Rigidities from warp and weft with the twist assumed from `law` (module doc).
    pub fn following(warp: f64, weft: f64, law: &dyn Law) -> Result<Self, BendingError> {
        let (warp, weft) = (positive(warp)?, positive(weft)?);
        let ratio = bias_ratio(law);
        Ok(Self {
            warp,
            weft,
            twist: twist_following(warp, weft, ratio),
        })
    }

    /// The section's bending tangent in the (1, 2, tensor 12) convention: W_b = ½ κᵀ D κ.
    pub fn matrix(&self) -> Matrix3<f64> {
        Matrix3::from_diagonal(&Vector3::new(self.warp, self.weft, 2.0 * self.twist))
    }

    /// Beam rigidity of a strip cut at `angle_deg` from the weft (0° weft, 90° warp), N·m.
    pub fn at_angle(&self, angle_deg: f64) -> f64 {
        let phi = (90.0 - angle_deg).to_radians();
        let (s, c) = phi.sin_cos();
        let (s2, c2) = (s * s, c * c);
        1.0 / (c2 * c2 / self.warp + s2 * s2 / self.weft + 2.0 * s2 * c2 / self.twist)
    }

    /// ∂B_twist/∂B_warp and ∂B_twist/∂B_weft under [`twist_following`] at `ratio`.
    pub fn twist_rates(&self, ratio: f64) -> (f64, f64) {
        let k = (ratio - 0.5).max(MIN_EXCESS);
        let t2 = self.twist * self.twist;
        (
            t2 * k / (self.warp * self.warp),
            t2 * k / (self.weft * self.weft),
        )
    }
}

/// Smallest r − ½ used by [`twist_following`]: a law whose 45° compliance is below half the
/// warp/weft mean (shear far stiffer than the yarns, not a woven fabric) gets a stiff twist.
const MIN_EXCESS: f64 = 1e-3;

/// The membrane's 45° uniaxial compliance over the mean of its warp and weft compliances, at
/// zero strain (1 for an isotropic law with ν = 0; fabrics soft in shear: much more).
pub fn bias_ratio(law: &dyn Law) -> f64 {
    let c = match law.response(&Vector3::zeros()) {
        Ok(r) => r.tangent,
        Err(_) => return 1.0,
    };
    let at = |deg: f64| uniaxial_compliance(&c, deg.to_radians());
    match (at(45.0), at(0.0), at(90.0)) {
        (Some(b), Some(w), Some(f)) if w + f > 0.0 => b / (0.5 * (w + f)),
        _ => 1.0,
    }
}

/// B_twist such that 1/B(45°) = r·(1/B_warp + 1/B_weft)/2: 1/B_twist = (r − ½)(1/B_warp + 1/B_weft).
pub fn twist_following(warp: f64, weft: f64, ratio: f64) -> f64 {
    1.0 / ((ratio - 0.5).max(MIN_EXCESS) * (1.0 / warp + 1.0 / weft))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::OrthotropicStvk;

    #[test]
    fn bias_rigidity_round_trips_and_isotropy_is_recovered() {
        let b = BendingRigidity::from_bias(2e-5, 5e-6, 4e-6).unwrap();
        assert!((b.at_angle(45.0) / 4e-6 - 1.0).abs() < 1e-12);
        assert!((b.at_angle(90.0) / 2e-5 - 1.0).abs() < 1e-12);
        assert!((b.at_angle(0.0) / 5e-6 - 1.0).abs() < 1e-12);
        // isotropic ν = 0: a12 = 0, G12 = a11 in this energy; the rule gives B_twist = B
        let iso = OrthotropicStvk::isotropic(1e7, 0.0);
        let r = bias_ratio(&iso);
        assert!((r - 1.0).abs() < 1e-12, "{r}");
        let f = BendingRigidity::following(3e-6, 3e-6, &iso).unwrap();
        assert!((f.twist / 3e-6 - 1.0).abs() < 1e-12);
        assert!((f.at_angle(30.0) / 3e-6 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn twist_rates_match_differences() {
        let r = 7.5;
        let b = BendingRigidity {
            warp: 2e-5,
            weft: 6e-6,
            twist: twist_following(2e-5, 6e-6, r),
        };
        let (dw, df) = b.twist_rates(r);
        let h = 1e-10;
        let fw =
            (twist_following(2e-5 + h, 6e-6, r) - twist_following(2e-5 - h, 6e-6, r)) / (2.0 * h);
        let ff =
            (twist_following(2e-5, 6e-6 + h, r) - twist_following(2e-5, 6e-6 - h, r)) / (2.0 * h);
        assert!((dw / fw - 1.0).abs() < 1e-6, "{dw} {fw}");
        assert!((df / ff - 1.0).abs() < 1e-6, "{df} {ff}");
    }

    #[test]
    fn bad_rigidities_are_refused() {
        assert!(BendingRigidity::from_bias(-1.0, 1e-6, 1e-6).is_err());
        // a bias stiffer than the yarn directions allow without bending Poisson coupling
        assert!(matches!(
            BendingRigidity::from_bias(1e-6, 1e-6, 3e-6),
            Err(BendingError::BiasTooStiff { .. })
        ));
    }
}
