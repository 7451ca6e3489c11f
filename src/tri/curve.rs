//! Nonlinear stiffness of one deformation component (Miguel et al. 2012 §4): the stress is
//! σ(ε) = k(ε) ε with k a cubic Hermite spline over equidistant control values on the strain
//! range [lo, hi] (tangents by central differences, one-sided at the ends) and held at its end
//! values outside it. One control value is the linear model. The energy density is
//! W(ε) = ∫₀^ε k(s) s ds, integrated piecewise by 3-point Gauss–Legendre, exact for the
//! quartic integrand of each spline piece.

/// k(ε) of one component, in the component's units (N/m for membrane strains, N·m for
/// curvatures).
#[derive(Clone, Debug, PartialEq)]
pub struct Stiffness {
    pub lo: f64,
    pub hi: f64,
    pub k: Vec<f64>,
}

/// Strains a spline piece at which [`Stiffness::stress_rises`] checks the tangent stiffness.
pub const TANGENT_SAMPLES: usize = 16;

/// A stiffness that cannot be used.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StiffnessError {
    #[error("a stiffness needs at least one control value")]
    Empty,
    #[error("stiffness control values must be finite and non-negative, got {0}")]
    Value(f64),
    #[error("the strain range of a spline must satisfy lo < hi, got [{0}, {1}]")]
    Range(f64, f64),
}

impl Stiffness {
    pub fn constant(k: f64) -> Self {
        Self {
            lo: 0.0,
            hi: 1.0,
            k: vec![k],
        }
    }

    /// Control values `k` spread evenly over [lo, hi].
    pub fn spline(lo: f64, hi: f64, k: Vec<f64>) -> Result<Self, StiffnessError> {
        if k.is_empty() {
            return Err(StiffnessError::Empty);
        }
        if let Some(&bad) = k.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(StiffnessError::Value(bad));
        }
        if k.len() > 1 && !(lo < hi && lo.is_finite() && hi.is_finite()) {
            return Err(StiffnessError::Range(lo, hi));
        }
        Ok(Self { lo, hi, k })
    }

    /// The stiffness at strain `e`: (k, dk/dε).
    pub fn at(&self, e: f64) -> (f64, f64) {
        let n = self.k.len();
        if n == 1 {
            return (self.k[0], 0.0);
        }
        if e <= self.lo {
            return (self.k[0], 0.0);
        }
        if e >= self.hi {
            return (self.k[n - 1], 0.0);
        }
        let h = (self.hi - self.lo) / (n - 1) as f64;
        let i = (((e - self.lo) / h) as usize).min(n - 2);
        let s = (e - self.lo) / h - i as f64;
        let m = |j: usize| {
            let (a, b) = (j.saturating_sub(1), (j + 1).min(n - 1));
            (self.k[b] - self.k[a]) / ((b - a) as f64 * h)
        };
        let (k0, k1, m0, m1) = (self.k[i], self.k[i + 1], h * m(i), h * m(i + 1));
        let (s2, s3) = (s * s, s * s * s);
        let k = (2.0 * s3 - 3.0 * s2 + 1.0) * k0
            + (s3 - 2.0 * s2 + s) * m0
            + (-2.0 * s3 + 3.0 * s2) * k1
            + (s3 - s2) * m1;
        let dk = (6.0 * s2 - 6.0 * s) * k0
            + (3.0 * s2 - 4.0 * s + 1.0) * m0
            + (-6.0 * s2 + 6.0 * s) * k1
            + (3.0 * s2 - 2.0 * s) * m1;
        (k, dk / h)
    }

    /// (W, W′ = σ, W″) at strain `e`.
    pub fn density(&self, e: f64) -> (f64, f64, f64) {
        let (k, dk) = self.at(e);
        if self.k.len() == 1 {
            return (0.5 * k * e * e, k * e, k);
        }
        (self.integral(e), k * e, k + dk * e)
    }

    /// ∫₀^e k(s) s ds, split at the range ends and the knots.
    fn integral(&self, e: f64) -> f64 {
        let n = self.k.len();
        let h = (self.hi - self.lo) / (n - 1) as f64;
        let (a, b) = if e >= 0.0 { (0.0, e) } else { (e, 0.0) };
        let mut cuts = vec![a];
        cuts.extend(
            (0..n)
                .map(|i| self.lo + i as f64 * h)
                .filter(|&t| t > a && t < b),
        );
        cuts.push(b);
        const NODES: [(f64, f64); 3] = [
            (-0.774_596_669_241_483_4, 5.0 / 9.0),
            (0.0, 8.0 / 9.0),
            (0.774_596_669_241_483_4, 5.0 / 9.0),
        ];
        let mut sum = 0.0;
        for w in cuts.windows(2) {
            let (mid, half) = (0.5 * (w[0] + w[1]), 0.5 * (w[1] - w[0]));
            for (t, wt) in NODES {
                let s = mid + half * t;
                sum += wt * half * self.at(s).0 * s;
            }
        }
        if e >= 0.0 {
            sum
        } else {
            -sum
        }
    }

    /// Whether the stress σ = k(ε) ε rises over the spline's range: its tangent stiffness
    /// dσ/dε = k + k′ε is positive at [`TANGENT_SAMPLES`] strains a piece, ends included.
    /// Outside the range k is constant, so σ rises there with the end value. A stress that
    /// falls as the strain grows is unstable: a strip under it splits into a stretched band
    /// and a slack one, whose mean force can follow a toe while no off-axis strip solves.
    pub fn stress_rises(&self) -> bool {
        let n = self.k.len();
        if n == 1 {
            return self.k[0] > 0.0;
        }
        let pieces = (n - 1) * TANGENT_SAMPLES;
        (0..=pieces).all(|j| {
            let e = self.lo + (self.hi - self.lo) * j as f64 / pieces as f64;
            self.density(e).2 > 0.0
        })
    }

    /// The stiffness scaled by `s` (every control value).
    pub fn scaled(&self, s: f64) -> Self {
        Self {
            k: self.k.iter().map(|k| k * s).collect(),
            ..self.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_is_half_k_e_squared() {
        let s = Stiffness::constant(3.0);
        let (w, dw, ddw) = s.density(0.2);
        assert!((w - 0.06).abs() < 1e-16 && (dw - 0.6).abs() < 1e-15 && ddw == 3.0);
    }

    /// W′ and W″ against central differences of W and W′, inside, across knots and outside
    /// the range, for a spline through uneven values.
    #[test]
    fn spline_derivatives_match_finite_differences() {
        let s = Stiffness::spline(-0.01, 0.05, vec![1.0, 2.0, 5.0, 4.0]).unwrap();
        for e in [-0.03, -0.005, 0.0, 0.013, 0.02, 0.031, 0.049, 0.07] {
            let h = 1e-6;
            let (_, d, dd) = s.density(e);
            let fd = (s.density(e + h).0 - s.density(e - h).0) / (2.0 * h);
            let fdd = (s.density(e + h).1 - s.density(e - h).1) / (2.0 * h);
            assert!((d - fd).abs() < 1e-9 * (1.0 + d.abs()), "{e}: {d} {fd}");
            assert!(
                (dd - fdd).abs() < 1e-5 * (1.0 + dd.abs()),
                "{e}: {dd} {fdd}"
            );
        }
        // the spline passes through its control values
        assert!((s.at(0.01).0 - 2.0).abs() < 1e-12 && (s.at(0.03).0 - 5.0).abs() < 1e-12);
    }

    /// A spline whose first value is nine times its next (a triangle-model fit of a long toe,
    /// `z0001-analytic`'s weft) lets the stress fall between them; the curve the same data
    /// would give without the toe's noise, rising from near zero, does not.
    #[test]
    fn a_stress_that_falls_with_strain_is_found() {
        let weft = vec![601214.8, 68085.6, 49938.4, 80154.9, 109795.6];
        let s = Stiffness::spline(0.0, 0.062, weft).unwrap();
        assert!(!s.stress_rises());
        // σ at 0.5 % strain above σ at 1.55 %
        assert!(s.density(0.005).1 > s.density(0.0155).1);
        let warp = vec![4456.6, 40473.8, 212980.5, 362248.4, 445661.0];
        assert!(Stiffness::spline(0.0, 0.062, warp).unwrap().stress_rises());
        assert!(Stiffness::constant(5.0).stress_rises());
        assert!(!Stiffness::constant(0.0).stress_rises());
        // a softening that keeps σ rising passes
        let soft = Stiffness::spline(0.0, 0.1, vec![100.0, 80.0, 60.0]).unwrap();
        assert!(soft.stress_rises());
    }

    #[test]
    fn bad_values_are_refused() {
        assert!(Stiffness::spline(0.0, 1.0, vec![]).is_err());
        assert!(Stiffness::spline(0.0, 1.0, vec![1.0, -1.0]).is_err());
        assert!(Stiffness::spline(1.0, 1.0, vec![1.0, 2.0]).is_err());
        assert!(Stiffness::spline(1.0, 1.0, vec![1.0]).is_ok());
    }
}
