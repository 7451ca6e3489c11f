//! The Ogden-like one-dimensional functions η of Clyde et al. (2017, Eq. 2):
//! η(x) = Σᵢ μᵢ/αᵢ ((x + 1)^αᵢ − 1), with their derivatives in x and in the parameters.

/// η(x) = Σ μᵢ/αᵢ ((x + 1)^αᵢ − 1).
#[derive(Clone, Debug, PartialEq)]
pub struct Eta {
    pub mu: Vec<f64>,
    pub alpha: Vec<f64>,
}

impl Eta {
    /// η(x) = x.
    pub fn linear() -> Self {
        Self {
            mu: vec![1.0],
            alpha: vec![1.0],
        }
    }

    pub fn degree(&self) -> usize {
        self.mu.len()
    }

    /// η, η', η'' at x ≥ 0 (`None` if not finite). (x + 1)^α − 1 is evaluated as
    /// expm1(α ln1p(x)), without the cancellation that would cost small strains their digits.
    pub(crate) fn eval(&self, x: f64) -> Option<[f64; 3]> {
        let b = x + 1.0;
        let l = x.ln_1p();
        let mut out = [0.0; 3];
        for (&m, &a) in self.mu.iter().zip(&self.alpha) {
            // α = 1 (the linear term) needs no transcendental functions
            let pm1 = if a == 1.0 { x } else { (a * l).exp_m1() };
            let p = pm1 + 1.0;
            out[0] += m / a * pm1;
            out[1] += m * p / b;
            out[2] += m * (a - 1.0) * p / (b * b);
        }
        out.iter().all(|v| v.is_finite()).then_some(out)
    }

    /// The first strain E in (0, `e_max`] at which the stress σ(E) = η'(E²)·E stops rising
    /// (dσ/dE = η'(E²) + 2E²η''(E²) ≤ 0, or not finite), on a grid of 1000 steps refined by
    /// bisection; `None` if it rises all the way. σ is odd in E, so this covers [−e_max, e_max].
    pub fn stress_peak(&self, e_max: f64) -> Option<f64> {
        let slope = |e: f64| {
            let x = e * e;
            self.eval(x)
                .map_or(f64::NAN, |[_, d1, d2]| d1 + 2.0 * x * d2)
        };
        let falls = |e: f64| slope(e).is_nan() || slope(e) <= 0.0;
        let n = 1000;
        let mut prev = 0.0;
        for i in 1..=n {
            let e = e_max * i as f64 / n as f64;
            if falls(e) {
                let (mut lo, mut hi) = (prev, e);
                for _ in 0..50 {
                    let mid = 0.5 * (lo + hi);
                    if falls(mid) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                return Some(hi);
            }
            prev = e;
        }
        None
    }

    /// (∂η, ∂η', ∂η'') with respect to each μᵢ, then each αᵢ.
    pub(crate) fn param_derivs(&self, x: f64) -> Vec<[f64; 3]> {
        let mut out = vec![[0.0; 3]; 2 * self.degree()];
        self.each_param_deriv(x, |i, v| out[i] = v);
        out
    }

    /// [`Eta::param_derivs`] handed out one by one as `(index, value)` without allocating
    /// (the sensitivity assembly calls it at every Gauss point).
    pub(crate) fn each_param_deriv(&self, x: f64, mut put: impl FnMut(usize, [f64; 3])) {
        let b = x + 1.0;
        let lb = x.ln_1p();
        let d = self.degree();
        for (j, (&m, &a)) in self.mu.iter().zip(&self.alpha).enumerate() {
            let pm1 = (a * lb).exp_m1();
            let p = pm1 + 1.0;
            put(j, [pm1 / a, p / b, (a - 1.0) * p / (b * b)]);
            put(
                d + j,
                [
                    m * (p * lb / a - pm1 / (a * a)),
                    m * p * lb / b,
                    m * p / (b * b) * (1.0 + (a - 1.0) * lb),
                ],
            );
        }
    }
}
