//! Parameter sensitivities of the energy and of its gradient (the right-hand sides of the
//! fitter's equilibrium derivative, Clyde et al. 2017 Eq. 6), for either section law.

use super::{Sensitivities, ShellModel};
use crate::material::OutOfDomain;
use crate::shell::{StrainJet, YVec};
use crate::Vec3;
use nalgebra::Vector3;

/// Names of the bending rigidities' sensitivities, after the law's and the thickness's.
pub const BENDING_PARAMS: [&str; 3] = ["bending_warp", "bending_weft", "bending_twist"];

type Jets<'a> = (&'a StrainJet, &'a StrainJet);

/// Adds one point's terms (weight `da`, stencil `(idx, w)`) to the wanted sensitivities.
fn add_point(
    da: f64,
    (idx, w): (&[u32], &[[f64; 6]]),
    dey: &[f64],
    dgy: &[YVec],
    want: &impl Fn(usize) -> bool,
    energy: &mut [f64],
    gradient: &mut [Vec<Vec3>],
) {
    for j in 0..energy.len() {
        if !want(j) {
            continue;
        }
        energy[j] += da * dey[j];
        for (&i, wi) in idx.iter().zip(w) {
            for k in 0..5 {
                for c in 0..3 {
                    gradient[j][i as usize][c] += da * wi[k + 1] * dgy[j][3 * k + c];
                }
            }
        }
    }
}

/// Σ_k v_k ∇E_k: a strain-space vector pulled back to y.
fn pull_back(v: &Vector3<f64>, jet: &StrainJet) -> YVec {
    let mut out = YVec::zeros();
    for k in 0..3 {
        out += v[k] * jet.grad[k];
    }
    out
}

impl ShellModel {
    /// ∂E/∂k and ∂(∂E/∂x)/∂k at `x` for every parameter k of the law, then the thickness
    /// τ, then (bending of its own only) the rigidities B_warp, B_weft, B_twist: the fitter's
    /// right-hand sides, paper Eq. 6. With the thickness rule ξ_q = τ t_q / 2,
    /// w̃_q = τ w_q / 2, the τ-derivative is that of the quadrature actually used:
    /// ∂/∂τ Σ w̃ ψ(Ẽ_m + ξ Ẽ_b) = Σ (w̃/τ) ψ + Σ w̃ (ξ/τ) S·Ẽ_b.
    pub fn sensitivities(&self, x: &[Vec3]) -> Result<Sensitivities, OutOfDomain> {
        self.sensitivities_of(x, None)
    }

    /// [`ShellModel::sensitivities`] for the parameters marked true only (law parameters, then
    /// thickness, then rigidities; `None`: all); the others, and any past the mask, are left at zero.
    pub fn sensitivities_of(
        &self,
        x: &[Vec3],
        wanted: Option<&[bool]>,
    ) -> Result<Sensitivities, OutOfDomain> {
        let want = |j: usize| wanted.is_none_or(|w| w.get(j).copied().unwrap_or(false));
        let mut names = self.law.param_names();
        let nlaw = names.len();
        names.push("thickness".into());
        if self.bending.is_some() {
            names.extend(BENDING_PARAMS.iter().map(|s| s.to_string()));
        }
        let np = names.len();
        let nn = self.num_nodes();
        let mut energy = vec![0.0; np];
        let mut gradient = vec![vec![[0.0; 3]; nn]; np];
        // one point's terms, reused from point to point
        let mut dey = vec![0.0; np];
        let mut dgy = vec![YVec::zeros(); np];
        for q in 0..self.basis.num_points() {
            let (idx, w) = self.basis.stencil(q);
            let y = self.kinematics_at(q, x);
            let rest = &self.rest[q];
            let (m, b) = rest.strains(&y);
            let da = rest.d_area;
            dey.fill(0.0);
            dgy.fill(YVec::zeros());
            if self.bending.is_some() {
                self.own_bending_terms(&(&m, &b), nlaw, &want, &mut dey, &mut dgy)?;
            } else {
                self.paper_section_terms(&(&m, &b), nlaw, &want, &mut dey, &mut dgy)?;
            }
            if let Some(c) = &self.centres {
                self.yarn_terms(&m, -c.moved, nlaw, &want, &mut dey, &mut dgy)?;
            }
            add_point(da, (idx, w), &dey, &dgy, &want, &mut energy, &mut gradient);
        }
        let moved = self.centres.as_ref().map_or(1.0, |c| c.moved);
        for face in 0..self.basis.num_faces {
            let Some((idx, w, y, rest)) = self.centre_kinematics(face, x) else {
                break;
            };
            let (m, _) = rest.strains(&y);
            dey.fill(0.0);
            dgy.fill(YVec::zeros());
            self.yarn_terms(&m, moved, nlaw, &want, &mut dey, &mut dgy)?;
            add_point(
                rest.d_area,
                (idx, w),
                &dey,
                &dgy,
                &want,
                &mut energy,
                &mut gradient,
            );
        }
        Ok(Sensitivities {
            names,
            energy,
            gradient,
        })
    }

    /// `sign` × the terms of τ ψ_y(Ẽ_m), the yarn part that [`super::YarnRule::Centre`]
    /// moves from the Gauss points (−1) to the face centres (+1).
    fn yarn_terms(
        &self,
        m: &StrainJet,
        sign: f64,
        nlaw: usize,
        want: &impl Fn(usize) -> bool,
        dey: &mut [f64],
        dgy: &mut [YVec],
    ) -> Result<(), OutOfDomain> {
        let em = Vector3::from(m.value);
        let tau = sign * self.thickness;
        if (0..nlaw).any(want) {
            let pr = self.law.yarn_param_response(&em)?;
            for j in 0..nlaw {
                if want(j) {
                    dey[j] += tau * pr.dpsi[j];
                    dgy[j] += tau * pull_back(&pr.dstress[j], m);
                }
            }
        }
        if want(nlaw) {
            let r = self.law.yarn_response(&em)?;
            dey[nlaw] += sign * r.psi;
            dgy[nlaw] += sign * pull_back(&r.stress, m);
        }
        Ok(())
    }

    /// One point's terms under the paper's section (law parameters, then τ).
    fn paper_section_terms(
        &self,
        (m, b): &Jets,
        nlaw: usize,
        want: &impl Fn(usize) -> bool,
        dey: &mut [f64],
        dgy: &mut [YVec],
    ) -> Result<(), OutOfDomain> {
        let em = Vector3::from(m.value);
        let eb = Vector3::from(b.value);
        let tau = self.thickness;
        let any_law = (0..nlaw).any(want);
        for &(xi, wt) in &self.thickness_rule {
            let e = em + xi * eb;
            // G(ξ)ᵀ v = Σ_k v_k (∇Ẽm_k + ξ ∇Ẽb_k)
            let gt = |v: &Vector3<f64>| pull_back(v, m) + xi * pull_back(v, b);
            if any_law {
                let pr = self.law.param_response(&e)?;
                for j in 0..nlaw {
                    if want(j) {
                        dey[j] += wt * pr.dpsi[j];
                        dgy[j] += wt * gt(&pr.dstress[j]);
                    }
                }
            }
            if !want(nlaw) {
                continue;
            }
            let r = self.law.response(&e)?;
            let jt = nlaw;
            dey[jt] += wt / tau * r.psi + wt * xi / tau * r.stress.dot(&eb);
            dgy[jt] += (wt / tau) * gt(&r.stress)
                + (wt * xi / tau) * pull_back(&r.stress, b)
                + (wt * xi / tau) * gt(&(r.tangent * eb));
        }
        Ok(())
    }

    /// One point's terms with bending of its own: W = τ ψ(Ẽ_m) + ½ B_w κ₁₁² + ½ B_f κ₂₂² + B_t κ₁₂².
    fn own_bending_terms(
        &self,
        (m, b): &Jets,
        nlaw: usize,
        want: &impl Fn(usize) -> bool,
        dey: &mut [f64],
        dgy: &mut [YVec],
    ) -> Result<(), OutOfDomain> {
        let em = Vector3::from(m.value);
        let tau = self.thickness;
        let gm = |v: &Vector3<f64>| pull_back(v, m);
        if (0..nlaw).any(want) {
            let pr = self.law.param_response(&em)?;
            for j in 0..nlaw {
                if want(j) {
                    dey[j] += tau * pr.dpsi[j];
                    dgy[j] += tau * gm(&pr.dstress[j]);
                }
            }
        }
        if want(nlaw) {
            let r = self.law.response(&em)?;
            dey[nlaw] += r.psi;
            dgy[nlaw] += gm(&r.stress);
        }
        // ∂W/∂B = (½ κ₁₁², ½ κ₂₂², κ₁₂²); ∂(∂W/∂y)/∂B = (κ₁₁ ∇κ₁₁, κ₂₂ ∇κ₂₂, 2 κ₁₂ ∇κ₁₂)
        for (k, (scale, dscale)) in [(0.5, 1.0), (0.5, 1.0), (1.0, 2.0)].into_iter().enumerate() {
            let j = nlaw + 1 + k;
            if want(j) {
                let kv = b.value[k];
                dey[j] += scale * kv * kv;
                dgy[j] += (dscale * kv) * b.grad[k];
            }
        }
        Ok(())
    }
}
