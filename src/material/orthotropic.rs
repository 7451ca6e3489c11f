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
mod tests;
