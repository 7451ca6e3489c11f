//! The orthotropic hyperelastic law of Clyde, Teran & Tamstorf (2017, Eq. 2):
//!
//! ψ = a₁₁/2 η₁(Ẽ₁₁²) + a₁₂ η₂(Ẽ₁₁Ẽ₂₂) + a₂₂/2 η₃(Ẽ₂₂²) + G₁₂ η₄(Ẽ₁₂²),
//! η_j(x) = Σᵢ μ_ji/α_ji ((x + 1)^α_ji − 1), Σᵢ μ_ji = 1, so η(0) = 0 and η'(0) = 1.
//!
//! η₂ is linear (the coupling a₁₂ Ẽ₁₁Ẽ₂₂ is not fitted). Every other term is a function of one
//! strain component, f(e) = c/2 · η(e²) with c = a₁₁, a₂₂ or 2G₁₂, so the law is a sum of
//! one-dimensional terms plus a bilinear coupling. That makes the cut-offs simple and exact:
//! outside the box Ẽ_ij ∈ [min, max] each term is replaced by its second-order Taylor polynomial
//! about the nearest valid strain, f(e_c) + f'(e_c) δ + ½ f''(e_c) δ², which is the Taylor
//! expansion of ψ itself about the nearest point of the box (the coupling is already quadratic)
//! and keeps ψ twice continuously differentiable.
//!
//! Parameters, in [`Orthotropic::names`] order: a11, a22, a12, g12, then μ and α of warp
//! (η₁), weft (η₃) and shear (η₄), then the coupling's κ₁, κ₂ when there is one. The μ are
//! reported as independent; a fitter that keeps Σμ = 1 applies its own chain rule.
//!
//! **Tension–shear coupling** (optional, [`ShearCoupling`]; not in the paper). The separable
//! law gives every off-axis strip the same shear response at equal Ẽ₁₂, whatever the yarn
//! strains beside it; woven fabrics shear more stiffly or more softly under yarn tension
//! (friction and yarn flattening at the crossings). The coupled law multiplies the shear term:
//!
//! ψ = a₁₁/2 η₁ + a₁₂ Ẽ₁₁Ẽ₂₂ + a₂₂/2 η₃ + G₁₂ η₄(Ẽ₁₂²) · g₁(Ẽ₁₁) g₂(Ẽ₂₂), g_i(e) = exp(κ_i e),
//!
//! so the shear stiffness at yarn strains (Ẽ₁₁, Ẽ₂₂) is G₁₂ exp(κ₁Ẽ₁₁ + κ₂Ẽ₂₂) (κ < 0: shear
//! softens as the yarns stretch). At Ẽ₁₂ = 0 the factor multiplies zero with zero slope, so the
//! warp and weft strips and every small-strain modulus are those of the separable law: only
//! off-axis strips at finite strain see κ. The yarn part ψ(Ẽ₁₁, Ẽ₂₂, 0) is unchanged, which is
//! what the centre rule of the yarn terms needs. **Cut-offs:** each g_i is continued past the
//! Ẽ_ii cut-offs by its quadratic Taylor polynomial, exp(κe_c)(1 + κδ + κ²δ²/2) > 0, and η₄'s
//! term as above; a product of C² factors is C², and g stays positive. **Convexity:** with
//! h = G₁₂η₄(Ẽ₁₂²) the coupled term's Hessian in (Ẽ₁₂, Ẽ₁₁) has determinant
//! g²κ₁²(h h'' − h'²) < 0 (for η₄ linear, −2κ₁²G₁₂²Ẽ₁₂²g²): the term alone is not convex, and
//! the law is convex while the yarn stiffness outweighs it, a₁₁ ≳ G₁₂ κ₁² Ẽ₁₂² g (for the
//! linear terms exactly: a₁₁ + h κ₁² g > h'² κ₁² g / h''); likewise a₂₂ with κ₂. Fabrics have
//! a₁₁/G₁₂ of 10–10⁴ and Ẽ₁₂ ≲ 0.2, so |κ| up to about 10–100 keeps that margin; a fitter
//! checks the tangent over the exercised strains ([`Orthotropic::tangent_positive`]).

use super::{Eta, Law, OutOfDomain, Response};
use nalgebra::{Matrix3, Vector3};

mod params;
pub use params::ParamResponse;

/// Strain cut-offs (Green strain, warp/weft frame): each component is valid in [min, max];
/// ±∞ where there is none.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cutoffs {
    pub e11: (f64, f64),
    pub e22: (f64, f64),
    pub e12: (f64, f64),
}

impl Cutoffs {
    pub fn none() -> Self {
        let all = (f64::NEG_INFINITY, f64::INFINITY);
        Self {
            e11: all,
            e22: all,
            e12: all,
        }
    }
}

/// The tension–shear coupling of the module doc: the shear term times
/// exp(κ₁Ẽ₁₁ + κ₂Ẽ₂₂) (κ dimensionless, per unit Green strain).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShearCoupling {
    /// κ₁ (warp strain)
    pub warp: f64,
    /// κ₂ (weft strain)
    pub weft: f64,
}

/// The Clyde et al. law with its cut-offs (and the optional coupling).
#[derive(Clone, Debug, PartialEq)]
pub struct Orthotropic {
    pub a11: f64,
    pub a22: f64,
    pub a12: f64,
    pub g12: f64,
    pub warp: Eta,
    pub weft: Eta,
    pub shear: Eta,
    pub cutoffs: Cutoffs,
    /// `None`: the paper's separable law
    pub coupling: Option<ShearCoupling>,
}

/// g(e) = exp(κ e) inside `range`, its quadratic Taylor polynomial outside: (g, g', g'') and
/// their derivatives in κ, (∂g, ∂g').
fn factor(kappa: f64, range: (f64, f64), e: f64) -> ([f64; 3], [f64; 2]) {
    let ec = e.clamp(range.0, range.1);
    let d = e - ec;
    let x = (kappa * ec).exp();
    let g = x * (1.0 + kappa * d + 0.5 * kappa * kappa * d * d);
    let g1 = x * kappa * (1.0 + kappa * d);
    let g2 = x * kappa * kappa;
    let dg = ec * g + x * (d + kappa * d * d);
    let dg1 = ec * g1 + x * (1.0 + 2.0 * kappa * d);
    ([g, g1, g2], [dg, dg1])
}

/// One one-dimensional term f(e) = c/2 η(e²) with its derivatives in e (and in parameters).
struct Term<'a> {
    c: f64,
    eta: &'a Eta,
    range: (f64, f64),
}

impl Term<'_> {
    /// f, f', f'' at e (with the Taylor extension outside `range`).
    fn eval(&self, e: f64) -> Option<[f64; 3]> {
        let ec = e.clamp(self.range.0, self.range.1);
        let d = e - ec;
        let x = ec * ec;
        let [h, h1, h2] = self.eta.eval(x)?;
        let f = 0.5 * self.c * h;
        let f1 = self.c * ec * h1;
        let f2 = self.c * (h1 + 2.0 * x * h2);
        Some([f + f1 * d + 0.5 * f2 * d * d, f1 + f2 * d, f2])
    }
}

impl Orthotropic {
    fn terms(&self) -> [Term<'_>; 3] {
        [
            Term {
                c: self.a11,
                eta: &self.warp,
                range: self.cutoffs.e11,
            },
            Term {
                c: self.a22,
                eta: &self.weft,
                range: self.cutoffs.e22,
            },
            Term {
                c: 2.0 * self.g12,
                eta: &self.shear,
                range: self.cutoffs.e12,
            },
        ]
    }

    /// Names of the parameters, in the order of [`ParamResponse`].
    pub fn names(&self) -> Vec<String> {
        let mut n: Vec<String> = ["a11", "a22", "a12", "g12"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        for (name, eta) in [
            ("warp", &self.warp),
            ("weft", &self.weft),
            ("shear", &self.shear),
        ] {
            for i in 0..eta.degree() {
                n.push(format!("{name}.mu[{i}]"));
            }
            for i in 0..eta.degree() {
                n.push(format!("{name}.alpha[{i}]"));
            }
        }
        if self.coupling.is_some() {
            n.push("coupling.warp".into());
            n.push("coupling.weft".into());
        }
        n
    }

    /// Current parameter values, in [`Orthotropic::names`] order.
    /// The length of [`Orthotropic::params`].
    pub fn num_params(&self) -> usize {
        let etas = self.warp.degree() + self.weft.degree() + self.shear.degree();
        4 + 2 * etas + if self.coupling.is_some() { 2 } else { 0 }
    }

    pub fn params(&self) -> Vec<f64> {
        let mut k = vec![self.a11, self.a22, self.a12, self.g12];
        for eta in [&self.warp, &self.weft, &self.shear] {
            k.extend(&eta.mu);
            k.extend(&eta.alpha);
        }
        if let Some(c) = self.coupling {
            k.extend([c.warp, c.weft]);
        }
        k
    }

    /// Sets the parameters from a vector in [`Orthotropic::names`] order.
    pub fn set_params(&mut self, k: &[f64]) {
        self.a11 = k[0];
        self.a22 = k[1];
        self.a12 = k[2];
        self.g12 = k[3];
        let mut at = 4;
        for eta in [&mut self.warp, &mut self.weft, &mut self.shear] {
            let d = eta.degree();
            eta.mu.copy_from_slice(&k[at..at + d]);
            eta.alpha.copy_from_slice(&k[at + d..at + 2 * d]);
            at += 2 * d;
        }
        if let Some(c) = &mut self.coupling {
            c.warp = k[at];
            c.weft = k[at + 1];
        }
    }

    /// The coupling's factors g₁(Ẽ₁₁), g₂(Ẽ₂₂) with their κ-derivatives (`None` without one).
    fn factors(&self, e: &Vector3<f64>) -> Option<[([f64; 3], [f64; 2]); 2]> {
        self.coupling.map(|c| {
            [
                factor(c.warp, self.cutoffs.e11, e[0]),
                factor(c.weft, self.cutoffs.e22, e[1]),
            ]
        })
    }

    /// Whether the tangent is positive definite at every corner and midpoint of the strain
    /// box `lo`–`hi` (each component at its low, middle and high value, 27 points): the
    /// convexity a coupled law must keep over the strains a fit exercised.
    pub fn tangent_positive(&self, lo: [f64; 3], hi: [f64; 3]) -> bool {
        let at = |i: usize, k: usize| lo[i] + 0.5 * k as f64 * (hi[i] - lo[i]);
        (0..27).all(|n| {
            let e = Vector3::new(at(0, n % 3), at(1, (n / 3) % 3), at(2, n / 9));
            self.response(&e)
                .is_ok_and(|r| r.tangent.cholesky().is_some())
        })
    }
}

impl From<super::OrthotropicStvk> for Orthotropic {
    fn from(s: super::OrthotropicStvk) -> Self {
        Self {
            a11: s.a11,
            a22: s.a22,
            a12: s.a12,
            g12: s.g12,
            warp: Eta::linear(),
            weft: Eta::linear(),
            shear: Eta::linear(),
            cutoffs: Cutoffs::none(),
            coupling: None,
        }
    }
}

impl Law for Orthotropic {
    /// The zero-strain moduli (η'(0) = 1): max(a₁₁, a₂₂)/G₁₂.
    fn yarn_shear_ratio(&self) -> Option<f64> {
        (self.g12 > 0.0).then(|| self.a11.max(self.a22) / self.g12)
    }

    fn param_names(&self) -> Vec<String> {
        self.names()
    }

    fn param_response(&self, e: &Vector3<f64>) -> Result<ParamResponse, OutOfDomain> {
        self.sensitivities(e)
    }

    fn response(&self, e: &Vector3<f64>) -> Result<Response, OutOfDomain> {
        let bad = || OutOfDomain {
            strain: [e[0], e[1], e[2]],
        };
        let mut psi = self.a12 * e[0] * e[1];
        let mut stress = Vector3::new(self.a12 * e[1], self.a12 * e[0], 0.0);
        let mut tangent = Matrix3::zeros();
        tangent[(0, 1)] = self.a12;
        tangent[(1, 0)] = self.a12;
        let terms = self.terms();
        for (k, term) in terms[..2].iter().enumerate() {
            let [f, f1, f2] = term.eval(e[k]).ok_or_else(bad)?;
            psi += f;
            stress[k] += f1;
            tangent[(k, k)] += f2;
        }
        let [f, f1, f2] = terms[2].eval(e[2]).ok_or_else(bad)?;
        match self.factors(e) {
            None => {
                psi += f;
                stress[2] += f1;
                tangent[(2, 2)] += f2;
            }
            Some([(g1, _), (g2, _)]) => {
                // f(Ẽ₁₂) g₁(Ẽ₁₁) g₂(Ẽ₂₂)
                psi += f * g1[0] * g2[0];
                stress += Vector3::new(f * g1[1] * g2[0], f * g1[0] * g2[1], f1 * g1[0] * g2[0]);
                let c = Matrix3::new(
                    f * g1[2] * g2[0],
                    f * g1[1] * g2[1],
                    f1 * g1[1] * g2[0],
                    f * g1[1] * g2[1],
                    f * g1[0] * g2[2],
                    f1 * g1[0] * g2[1],
                    f1 * g1[1] * g2[0],
                    f1 * g1[0] * g2[1],
                    f2 * g1[0] * g2[0],
                );
                tangent += c;
            }
        }
        if !psi.is_finite() {
            return Err(bad());
        }
        Ok(Response {
            psi,
            stress,
            tangent,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::OrthotropicStvk;

    fn sample() -> Orthotropic {
        Orthotropic {
            a11: 3.0e7,
            a22: 1.5e7,
            a12: 4.0e6,
            g12: 1.0e6,
            warp: Eta {
                mu: vec![0.7, 0.3],
                alpha: vec![1.0, 12.0],
            },
            weft: Eta {
                mu: vec![1.0],
                alpha: vec![4.0],
            },
            shear: Eta {
                mu: vec![1.4, -0.4],
                alpha: vec![2.0, -3.0],
            },
            cutoffs: Cutoffs {
                e11: (0.0, 0.12),
                e22: (0.0, 0.15),
                e12: (-0.2, 0.2),
            },
            coupling: None,
        }
    }

    /// The sample law with a tension–shear coupling of either sign.
    fn coupled() -> Orthotropic {
        Orthotropic {
            coupling: Some(ShearCoupling {
                warp: -9.0,
                weft: 6.0,
            }),
            ..sample()
        }
    }

    /// Strains inside the box, outside it on either side, and on each face.
    fn strains() -> Vec<Vector3<f64>> {
        vec![
            Vector3::new(0.05, 0.08, 0.1),
            Vector3::new(0.2, 0.1, -0.05),
            Vector3::new(-0.03, 0.3, 0.35),
            Vector3::new(0.11, -0.02, -0.3),
            Vector3::new(0.07, 0.04, 0.0),
        ]
    }

    #[test]
    fn the_parameter_count_is_that_of_the_parameters() {
        for law in [
            sample(),
            coupled(),
            Orthotropic::from(OrthotropicStvk {
                a11: 1.0,
                a22: 2.0,
                a12: 0.5,
                g12: 0.3,
            }),
        ] {
            assert_eq!(law.num_params(), law.params().len());
            assert_eq!(law.num_params(), law.names().len());
        }
    }

    #[test]
    fn linear_eta_is_stvk_exactly() {
        let s = OrthotropicStvk {
            a11: 3.0e7,
            a22: 1.2e7,
            a12: 4.0e6,
            g12: 9.0e5,
        };
        let o: Orthotropic = s.into();
        for e in strains() {
            let (a, b) = (s.response(&e).unwrap(), o.response(&e).unwrap());
            assert!(
                (a.psi - b.psi).abs() <= 4e-16 * a.psi.abs().max(1.0),
                "{} vs {}",
                a.psi,
                b.psi
            );
            assert!((a.stress - b.stress).norm() <= 4e-16 * a.stress.norm().max(1.0));
            assert!((a.tangent - b.tangent).norm() <= 1e-9);
        }
    }

    #[test]
    fn strain_derivatives_match_differences_inside_and_outside_the_box() {
        for law in [sample(), coupled()] {
            strain_derivatives_match(&law);
        }
    }

    fn strain_derivatives_match(law: &Orthotropic) {
        let h = 1e-7;
        for e in strains() {
            let r = law.response(&e).unwrap();
            for i in 0..3 {
                let (mut ep, mut em) = (e, e);
                ep[i] += h;
                em[i] -= h;
                let (p, m) = (law.response(&ep).unwrap(), law.response(&em).unwrap());
                let fd = (p.psi - m.psi) / (2.0 * h);
                assert!(
                    (fd - r.stress[i]).abs() <= 1e-6 * r.stress.norm(),
                    "stress {i} at {e:?}"
                );
                for j in 0..3 {
                    let fd = (p.stress[j] - m.stress[j]) / (2.0 * h);
                    let scale = r.tangent.norm();
                    assert!(
                        (fd - r.tangent[(j, i)]).abs() <= 1e-6 * scale,
                        "tangent ({j},{i}) at {e:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn parameter_derivatives_match_differences() {
        for law in [sample(), coupled()] {
            parameter_derivatives_match(&law);
        }
    }

    fn parameter_derivatives_match(law: &Orthotropic) {
        let k0 = law.params();
        let names = law.names();
        assert_eq!(names.len(), k0.len());
        for e in strains() {
            let pr = law.sensitivities(&e).unwrap();
            for (j, name) in names.iter().enumerate() {
                // fourth-order differences with a step large enough to keep ψ's round-off out
                let h = 1e-4 * k0[j].abs().max(1e-3);
                let at = |t: f64| {
                    let mut k = k0.clone();
                    k[j] += t;
                    let mut l = law.clone();
                    l.set_params(&k);
                    l.response(&e).unwrap()
                };
                let (p2, p, m, m2) = (at(2.0 * h), at(h), at(-h), at(-2.0 * h));
                let d4 = |f: &dyn Fn(&Response) -> f64| {
                    (-f(&p2) + 8.0 * f(&p) - 8.0 * f(&m) + f(&m2)) / (12.0 * h)
                };
                // differences carry ~ε ψ / h ≈ 1e-12 ψ/|k| of noise: derivatives below 1e-5 ψ/|k| are
                // checked to that absolute level, all others to 1e-6 relative
                let r0 = law.response(&e).unwrap();
                let kscale = k0[j].abs().max(1e-3);
                let fd = d4(&|r| r.psi);
                let scale = pr.dpsi[j].abs().max(1e-5 * r0.psi.abs() / kscale);
                assert!(
                    (fd - pr.dpsi[j]).abs() <= 1e-6 * scale,
                    "∂ψ/∂{name} at {e:?}: {fd} vs {}",
                    pr.dpsi[j]
                );
                let fds = Vector3::from_fn(|i, _| d4(&|r| r.stress[i]));
                let sscale = pr.dstress[j].norm().max(1e-5 * r0.stress.norm() / kscale);
                assert!(
                    (fds - pr.dstress[j]).norm() <= 1e-6 * sscale,
                    "∂S/∂{name} at {e:?}: {fds:?} vs {:?}",
                    pr.dstress[j]
                );
            }
        }
    }

    #[test]
    fn value_gradient_and_hessian_are_continuous_across_each_cutoff() {
        for law in [sample(), coupled()] {
            continuous_across_cutoffs(&law);
        }
    }

    fn continuous_across_cutoffs(law: &Orthotropic) {
        let faces = [
            (0, 0.12),
            (0, 0.0),
            (1, 0.15),
            (1, 0.0),
            (2, 0.2),
            (2, -0.2),
        ];
        for (k, at) in faces {
            let mut e = Vector3::new(0.05, 0.07, 0.03);
            let eps = 1e-9;
            e[k] = at - eps;
            let a = law.response(&e).unwrap();
            e[k] = at + eps;
            let b = law.response(&e).unwrap();
            assert!(
                (a.psi - b.psi).abs() <= 1e-6 * a.psi.abs(),
                "ψ at component {k} = {at}"
            );
            assert!(
                (a.stress - b.stress).norm() <= 1e-6 * a.stress.norm(),
                "S at {k} = {at}"
            );
            assert!(
                (a.tangent - b.tangent).norm() <= 1e-6 * a.tangent.norm(),
                "C at {k} = {at}"
            );
        }
    }

    /// The law separates into the yarn part and the shear term: ψ − ψ_y depends on Ẽ₁₂ alone
    /// (inside and outside the cut-off box), and the yarn part carries no shear.
    #[test]
    fn the_yarn_part_leaves_the_shear_term_alone() {
        let law = sample();
        for e in strains() {
            let (r, y) = (law.response(&e).unwrap(), law.yarn_response(&e).unwrap());
            let s = law.response(&Vector3::new(0.0, 0.0, e[2])).unwrap();
            assert!(
                (r.psi - y.psi - s.psi).abs() <= 1e-12 * r.psi.abs(),
                "{e:?}"
            );
            assert!((r.stress - y.stress - s.stress).amax() <= 1e-9 * r.stress.amax());
            let mut shear = Matrix3::zeros();
            shear[(2, 2)] = s.tangent[(2, 2)];
            assert!((r.tangent - y.tangent - shear).amax() <= 1e-9 * r.tangent.amax());
            assert_eq!(y.stress[2], 0.0);
            let (p, py) = (
                law.param_response(&e).unwrap(),
                law.yarn_param_response(&e).unwrap(),
            );
            let ps = law.param_response(&Vector3::new(0.0, 0.0, e[2])).unwrap();
            for j in 0..p.dpsi.len() {
                let scale = p.dpsi[j].abs().max(p.dstress[j].amax()).max(1e-30);
                assert!((p.dpsi[j] - py.dpsi[j] - ps.dpsi[j]).abs() <= 1e-9 * scale);
                assert!((p.dstress[j] - py.dstress[j] - ps.dstress[j]).amax() <= 1e-9 * scale);
            }
        }
    }

    /// The coupling leaves the yarns alone (the warp and weft strips, and the centre rule's
    /// yarn part), scales the shear stiffness by exp(κ₁Ẽ₁₁ + κ₂Ẽ₂₂) inside the box, and
    /// names its two parameters last.
    #[test]
    fn the_coupling_scales_the_shear_stiffness_and_nothing_else() {
        let (plain, law) = (sample(), coupled());
        for e in strains() {
            let (a, b) = (
                plain.yarn_response(&e).unwrap(),
                law.yarn_response(&e).unwrap(),
            );
            assert_eq!(a, b, "{e:?}");
            // on the yarn axes only the shear stiffness differs
            let y = Vector3::new(e[0], e[1], 0.0);
            let (a, b) = (plain.response(&y).unwrap(), law.response(&y).unwrap());
            assert_eq!((a.psi, a.stress), (b.psi, b.stress));
            let (mut ta, mut tb) = (a.tangent, b.tangent);
            ta[(2, 2)] = 0.0;
            tb[(2, 2)] = 0.0;
            assert_eq!(ta, tb);
        }
        let e = Vector3::new(0.05, 0.08, 1e-4);
        let (a, b) = (plain.response(&e).unwrap(), law.response(&e).unwrap());
        let want = (-9.0 * 0.05 + 6.0 * 0.08f64).exp();
        let ratio = b.tangent[(2, 2)] / a.tangent[(2, 2)];
        assert!((ratio - want).abs() < 1e-12 * want, "{ratio} vs {want}");
        let names = law.names();
        assert_eq!(
            &names[names.len() - 2..],
            ["coupling.warp", "coupling.weft"]
        );
        let mut back = sample();
        back.coupling = Some(ShearCoupling {
            warp: 0.0,
            weft: 0.0,
        });
        back.set_params(&law.params());
        assert_eq!(back, law);
        // a zero coupling is the separable law
        back.set_params(&[&plain.params()[..], &[0.0, 0.0]].concat());
        for e in strains() {
            assert_eq!(back.response(&e).unwrap(), plain.response(&e).unwrap());
        }
    }

    /// Convex while the yarns outweigh the coupled shear term (module doc): the sample's
    /// κ = −9, 6 keep the tangent positive over the box; κ = 300 does not.
    #[test]
    fn the_convexity_check_sees_a_coupling_too_strong_for_the_yarns() {
        let (lo, hi) = ([0.0, 0.0, -0.1], [0.1, 0.1, 0.1]);
        assert!(sample().tangent_positive(lo, hi));
        assert!(coupled().tangent_positive(lo, hi));
        let mut strong = coupled();
        strong.coupling = Some(ShearCoupling {
            warp: 300.0,
            weft: 0.0,
        });
        assert!(!strong.tangent_positive(lo, hi));
    }

    #[test]
    fn shear_sign_does_not_matter() {
        for law in [sample(), coupled()] {
            shear_sign_does_not_matter_for(&law);
        }
    }

    fn shear_sign_does_not_matter_for(law: &Orthotropic) {
        for e in strains() {
            let f = Vector3::new(e[0], e[1], -e[2]);
            let (a, b) = (law.response(&e).unwrap(), law.response(&f).unwrap());
            assert!((a.psi - b.psi).abs() <= 1e-14 * a.psi.abs());
        }
    }
}
