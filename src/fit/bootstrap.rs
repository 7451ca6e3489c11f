//! The homogeneous-strain strip: a tensile strip whose strain is uniform, with uniaxial stress
//! along its axis (the transverse and shear stresses of the strip frame vanish). It costs a
//! few 3 × 3 solves per point, where a shell equilibrium costs a Newton solve of the cage, is
//! differentiated exactly, and gives the fitter its initial guesses and its degree choice
//! (Clyde et al. 2017 §5, "bootstrapping").
//!
//! With the strip strain e = (e_aa, e_tt, e_at) (axis, transverse, tensor shear) and L the
//! linear map to the warp/weft strain Ẽ = L e, the energy is W(e) = ψ(L e). For a prescribed
//! axial stretch λ, e_aa = (λ² − 1)/2 and z = (e_tt, e_at) solves ∂W/∂z = 0 by Newton. The
//! clamp force is F = w τ λ ∂W/∂e_aa (first Piola stress times the rest section). Parameter
//! derivatives follow from the implicit function theorem: dz/dk = −W_zz⁻¹ ∂²W/∂z∂k.

use crate::material::{Law, Orthotropic, OutOfDomain};
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

/// L: strip-frame strain (e_aa, e_tt, e_at) → warp/weft strain (Ẽ11, Ẽ22, Ẽ12), for a strip
/// whose axis makes `angle_deg` with the weft (warp = (cos θ, −sin θ), weft = (sin θ, cos θ)
/// in strip coordinates (transverse, axis); see [`crate::scene::warp_direction`]).
pub fn strip_to_material(angle_deg: f64) -> Matrix3<f64> {
    let t = angle_deg.to_radians();
    // components of warp (d1) and weft (d2) along the axis a and the transverse t
    let (d1a, d1t) = (-t.sin(), t.cos());
    let (d2a, d2t) = (t.cos(), t.sin());
    Matrix3::new(
        d1a * d1a,
        d1t * d1t,
        2.0 * d1a * d1t,
        d2a * d2a,
        d2t * d2t,
        2.0 * d2a * d2t,
        d1a * d2a,
        d1t * d2t,
        d1a * d2t + d1t * d2a,
    )
}

/// One point of a homogeneous curve.
#[derive(Clone, Debug, PartialEq)]
pub struct HomogeneousPoint {
    pub force: f64,
    /// ∂F/∂k for the law's parameters, then thickness (empty unless asked)
    pub dforce: Vec<f64>,
    /// the warp/weft strain at this point
    pub strain: [f64; 3],
}

/// Forces of a homogeneous strip (width, gauge length, thickness in m) at each elongation.
pub fn homogeneous_curve(
    law: &Orthotropic,
    angle_deg: f64,
    width: f64,
    length: f64,
    thickness: f64,
    elongations: &[f64],
    sensitivities: bool,
) -> Result<Vec<HomogeneousPoint>, OutOfDomain> {
    let l = strip_to_material(angle_deg);
    let mut z = Vector2::zeros();
    let mut out = Vec::with_capacity(elongations.len());
    for &dl in elongations {
        let lambda = 1.0 + dl / length;
        let eaa = 0.5 * (lambda * lambda - 1.0);
        let strain = |z: &Vector2<f64>| l * Vector3::new(eaa, z[0], z[1]);
        // Newton on ∂W/∂z = 0 (W is convex in z for a convex law)
        let mut converged = false;
        for _ in 0..100 {
            let r = law.response(&strain(&z))?;
            let g = l.transpose() * r.stress;
            let h = l.transpose() * r.tangent * l;
            let gz = Vector2::new(g[1], g[2]);
            let hz = Matrix2::new(h[(1, 1)], h[(1, 2)], h[(2, 1)], h[(2, 2)]);
            let scale = g[0].abs().max(1e-300);
            if gz.amax() <= 1e-13 * scale {
                converged = true;
                break;
            }
            let Some(inv) = hz.try_inverse() else { break };
            z -= inv * gz;
        }
        let e = strain(&z);
        if !converged {
            return Err(OutOfDomain {
                strain: [e[0], e[1], e[2]],
            });
        }
        let r = law.response(&e)?;
        let g = l.transpose() * r.stress;
        let area = width * thickness;
        let force = area * lambda * g[0];
        let dforce = if sensitivities {
            let h = l.transpose() * r.tangent * l;
            let hz = Matrix2::new(h[(1, 1)], h[(1, 2)], h[(2, 1)], h[(2, 2)]);
            let inv = hz.try_inverse().ok_or(OutOfDomain {
                strain: [e[0], e[1], e[2]],
            })?;
            let h0z = Vector2::new(h[(0, 1)], h[(0, 2)]);
            let pr = law.param_response(&e)?;
            let mut d: Vec<f64> = pr
                .dstress
                .iter()
                .map(|ds| {
                    let gk = l.transpose() * ds;
                    let dz = -(inv * Vector2::new(gk[1], gk[2]));
                    area * lambda * (gk[0] + h0z.dot(&dz))
                })
                .collect();
            d.push(force / thickness);
            d
        } else {
            Vec::new()
        };
        out.push(HomogeneousPoint {
            force,
            dforce,
            strain: [e[0], e[1], e[2]],
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Cutoffs, Eta};

    fn law() -> Orthotropic {
        Orthotropic {
            a11: 2.0e8,
            a22: 1.2e8,
            a12: 0.6e8,
            g12: 4.0e6,
            warp: Eta {
                mu: vec![0.6, 0.4],
                alpha: vec![1.0, 300.0],
            },
            weft: Eta {
                mu: vec![1.0],
                alpha: vec![50.0],
            },
            shear: Eta {
                mu: vec![0.7, 0.3],
                alpha: vec![1.0, 40.0],
            },
            cutoffs: Cutoffs::none(),
            coupling: None,
        }
    }

    #[test]
    fn warp_strip_of_a_linear_law_gives_the_condensed_modulus() {
        // uniaxial stress along the warp: S11 = (a11 − a12²/a22) E11
        let mut law = law();
        law.warp = Eta::linear();
        law.weft = Eta::linear();
        let (w, len, tau, dl) = (0.05, 0.075, 3e-4, 3e-3);
        let p = &homogeneous_curve(&law, 90.0, w, len, tau, &[dl], false).unwrap()[0];
        let lambda = 1.0 + dl / len;
        let e11 = 0.5 * (lambda * lambda - 1.0);
        let expected = w * tau * lambda * (law.a11 - law.a12 * law.a12 / law.a22) * e11;
        assert!(
            (p.force / expected - 1.0).abs() < 1e-12,
            "{} vs {expected}",
            p.force
        );
    }

    #[test]
    fn sensitivities_match_differences() {
        let law = law();
        let (w, len, tau) = (0.05, 0.075, 3e-4);
        let dls = [1e-3, 4e-3, 7e-3];
        for angle in [0.0, 22.5, 45.0, 90.0, 130.0] {
            let exact = homogeneous_curve(&law, angle, w, len, tau, &dls, true).unwrap();
            let k = law.params();
            for j in 0..=k.len() {
                let at = |s: f64| {
                    let mut l2 = law.clone();
                    let mut kk = k.clone();
                    let mut t2 = tau;
                    if j < k.len() {
                        kk[j] *= 1.0 + s;
                        l2.set_params(&kk);
                    } else {
                        t2 *= 1.0 + s;
                    }
                    homogeneous_curve(&l2, angle, w, len, t2, &dls, false).unwrap()
                };
                let h = 1e-6;
                let (p, m) = (at(h), at(-h));
                let kj = if j < k.len() { k[j] } else { tau };
                for i in 0..dls.len() {
                    let fd = (p[i].force - m[i].force) / (2.0 * h * kj);
                    let ex = exact[i].dforce[j];
                    let scale = exact[i].force.abs() / kj.abs();
                    assert!(
                        (ex - fd).abs() <= 1e-6 * scale,
                        "angle {angle}, parameter {j}, point {i}: {ex} vs {fd}"
                    );
                }
            }
        }
    }
}
