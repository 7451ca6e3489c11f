//! The law's parameter sensitivities, ∂ψ/∂k and ∂²ψ/∂Ẽ∂k at one strain (the fitter's
//! right-hand sides, Clyde et al. 2017 Eq. 6): each term's rows for its stiffness, μ's and
//! α's, extended past the cut-offs as the term itself is, and the coupling's κ's.

use super::{Orthotropic, OutOfDomain, Term};
use nalgebra::Vector3;

/// Parameter sensitivities of the law at one strain.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamResponse {
    /// ∂ψ/∂k
    pub dpsi: Vec<f64>,
    /// ∂²ψ/∂Ẽ∂k
    pub dstress: Vec<Vector3<f64>>,
}

impl Term<'_> {
    /// (∂f/∂k, ∂f'/∂k) for k = c, then each μ, then each α, handed to `row(index, value)`
    /// without allocating (this runs at every Gauss point of every sensitivity assembly);
    /// `None` where a value is not finite.
    fn param_eval(&self, e: f64, mut row: impl FnMut(usize, [f64; 2])) -> Option<()> {
        let ec = e.clamp(self.range.0, self.range.1);
        let d = e - ec;
        let x = ec * ec;
        let [h, h1, h2] = self.eta.eval(x)?;
        // (∂f, ∂f', ∂f'') at e_c for each parameter, then the Taylor extension
        let mut finite = true;
        let mut put = |i: usize, [a, b, c]: [f64; 3]| {
            let v = [a + b * d + 0.5 * c * d * d, b + c * d];
            finite &= v[0].is_finite() && v[1].is_finite();
            row(i, v);
        };
        put(0, [0.5 * h, ec * h1, h1 + 2.0 * x * h2]);
        let c = self.c;
        self.eta.each_param_deriv(x, |i, [g, g1, g2]| {
            put(i + 1, [0.5 * c * g, c * ec * g1, c * (g1 + 2.0 * x * g2)])
        });
        finite.then_some(())
    }
}

impl Orthotropic {
    /// ∂ψ/∂k and ∂²ψ/∂Ẽ∂k for every parameter.
    pub(super) fn sensitivities(&self, e: &Vector3<f64>) -> Result<ParamResponse, OutOfDomain> {
        let bad = || OutOfDomain {
            strain: [e[0], e[1], e[2]],
        };
        let n = self.num_params();
        let mut dpsi = vec![0.0; n];
        let mut dstress = vec![Vector3::zeros(); n];
        // a12: ψ₂ = a12 e11 e22
        dpsi[2] = e[0] * e[1];
        dstress[2] = Vector3::new(e[1], e[0], 0.0);
        let terms = self.terms();
        // the stiffness of each term: a11, a22, then G12 (c = 2 G12, so ∂/∂G12 = 2 ∂/∂c)
        let stiff_index = [0usize, 1, 3];
        let stiff_factor = [1.0, 1.0, 2.0];
        let mut at = 4;
        let factors = self.factors(e);
        // (∂f, ∂f') of a term's parameter → (∂ψ, ∂S): the shear term's times the coupling
        let spread = |comp: usize, [df, df1]: [f64; 2]| -> (f64, Vector3<f64>) {
            match (comp, &factors) {
                (2, Some([(g1, _), (g2, _)])) => (
                    df * g1[0] * g2[0],
                    Vector3::new(df * g1[1] * g2[0], df * g1[0] * g2[1], df1 * g1[0] * g2[0]),
                ),
                _ => {
                    let mut v = Vector3::zeros();
                    v[comp] = df1;
                    (df, v)
                }
            }
        };
        // parameter blocks are ordered warp, weft, shear = components 0, 1, 2
        for (comp, term) in terms.iter().enumerate() {
            let s = stiff_index[comp];
            term.param_eval(e[comp], |i, r| {
                let (p, v) = spread(comp, r);
                if i == 0 {
                    dpsi[s] += stiff_factor[comp] * p;
                    dstress[s] += stiff_factor[comp] * v;
                } else {
                    (dpsi[at + i - 1], dstress[at + i - 1]) = (p, v);
                }
            })
            .ok_or_else(bad)?;
            at += 2 * term.eta.degree();
        }
        if let Some([(g1, dg1), (g2, dg2)]) = factors {
            let [f, f1, _] = terms[2].eval(e[2]).ok_or_else(bad)?;
            // κ₁: ∂/∂κ₁ of f g₁ g₂, and of its strain gradient
            dpsi[at] = f * dg1[0] * g2[0];
            dstress[at] = Vector3::new(f * dg1[1] * g2[0], f * dg1[0] * g2[1], f1 * dg1[0] * g2[0]);
            dpsi[at + 1] = f * g1[0] * dg2[0];
            dstress[at + 1] =
                Vector3::new(f * g1[1] * dg2[0], f * g1[0] * dg2[1], f1 * g1[0] * dg2[0]);
        }
        Ok(ParamResponse { dpsi, dstress })
    }
}
