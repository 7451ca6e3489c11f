//! Gauss–Legendre quadrature: n × n tensor rules on a face's parameter square and 1-D rules
//! through the shell thickness.
//!
//! Nodes are the roots of the Legendre polynomial Pₙ, found by Newton's method from Tricomi's
//! initial guesses; weights wᵢ = 2 / ((1 − xᵢ²) Pₙ'(xᵢ)²). An n-point rule integrates
//! polynomials of degree 2n − 1 exactly.

/// Largest rule we offer; 8 points integrate degree 15 exactly, far beyond what a bicubic
/// shell integrand needs.
pub const MAX_POINTS: usize = 8;

/// An n-point Gauss–Legendre rule on [-1, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct GaussLegendre {
    pub nodes: Vec<f64>,
    pub weights: Vec<f64>,
}

/// Asked for a rule we do not offer.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("Gauss–Legendre rule with {0} points: choose 1 to {MAX_POINTS}")]
pub struct BadOrder(pub usize);

impl GaussLegendre {
    pub fn new(n: usize) -> Result<Self, BadOrder> {
        if n == 0 || n > MAX_POINTS {
            return Err(BadOrder(n));
        }
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        for i in 0..n {
            // roots in decreasing order; Tricomi's guess
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            for _ in 0..100 {
                let (p, d) = legendre(n, x);
                let dx = p / d;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let (_, dp) = legendre(n, x);
            nodes[n - 1 - i] = x;
            weights[n - 1 - i] = 2.0 / ((1.0 - x * x) * dp * dp);
        }
        Ok(Self { nodes, weights })
    }

    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The rule mapped to [a, b]: (node, weight) pairs.
    pub fn on_interval(&self, a: f64, b: f64) -> Vec<(f64, f64)> {
        let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(|(&x, &w)| (mid + half * x, half * w))
            .collect()
    }

    /// The n × n tensor rule on the unit square: ([u, v], weight), u fastest.
    pub fn on_unit_square(&self) -> Vec<([f64; 2], f64)> {
        let line = self.on_interval(0.0, 1.0);
        let mut out = Vec::with_capacity(line.len() * line.len());
        for &(v, wv) in &line {
            for &(u, wu) in &line {
                out.push(([u, v], wu * wv));
            }
        }
        out
    }

    /// The rule through a shell of thickness `tau`: ξ ∈ [−τ/2, τ/2].
    pub fn through_thickness(&self, tau: f64) -> Vec<(f64, f64)> {
        self.on_interval(-0.5 * tau, 0.5 * tau)
    }
}

/// Pₙ(x) and Pₙ'(x) by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
        p0 = p1;
        p1 = p2;
    }
    let p = if n == 0 { 1.0 } else { p1 };
    let d = if n == 0 {
        0.0
    } else {
        n as f64 * (x * p - p0) / (x * x - 1.0)
    };
    (p, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_monomials_exactly_up_to_degree_2n_minus_1() {
        for n in 1..=MAX_POINTS {
            let g = GaussLegendre::new(n).unwrap();
            for deg in 0..2 * n {
                let q: f64 = g
                    .on_interval(0.0, 1.0)
                    .iter()
                    .map(|&(x, w)| w * x.powi(deg as i32))
                    .sum();
                let exact = 1.0 / (deg as f64 + 1.0);
                assert!((q - exact).abs() < 1e-14, "n={n} deg={deg}: {q} vs {exact}");
            }
            // Degree 2n is not exact, and its error is the textbook one (Abramowitz & Stegun
            // 25.4.30 on [0, 1] with f = x^2n): (n!)⁴ / ((2n + 1) ((2n)!)²).
            let deg = 2 * n;
            let q: f64 = g
                .on_interval(0.0, 1.0)
                .iter()
                .map(|&(x, w)| w * x.powi(deg as i32))
                .sum();
            let fact = |k: usize| (1..=k).map(|i| i as f64).product::<f64>();
            let predicted = fact(n).powi(4) / ((deg as f64 + 1.0) * fact(deg).powi(2));
            let err = 1.0 / (deg as f64 + 1.0) - q;
            assert!(
                (err / predicted - 1.0).abs() < 1e-5,
                "n={n}: {err} vs {predicted}"
            );
        }
    }

    #[test]
    fn known_two_and_three_point_rules() {
        // Abramowitz & Stegun 25.4.29: ±1/√3 with weight 1; 0, ±√(3/5) with 8/9, 5/9.
        let g = GaussLegendre::new(2).unwrap();
        assert!((g.nodes[1] - 1.0 / 3f64.sqrt()).abs() < 1e-15);
        assert!((g.weights[0] - 1.0).abs() < 1e-15);
        let g = GaussLegendre::new(3).unwrap();
        assert!(g.nodes[1].abs() < 1e-15);
        assert!((g.nodes[2] - 0.6f64.sqrt()).abs() < 1e-15);
        assert!((g.weights[1] - 8.0 / 9.0).abs() < 1e-15);
    }

    #[test]
    fn square_and_thickness_rules() {
        let g = GaussLegendre::new(4).unwrap();
        let sq = g.on_unit_square();
        assert_eq!(sq.len(), 16);
        let area: f64 = sq.iter().map(|p| p.1).sum();
        assert!((area - 1.0).abs() < 1e-15);
        // ∫∫ u³ v² = 1/12
        let m: f64 = sq.iter().map(|([u, v], w)| w * u.powi(3) * v * v).sum();
        assert!((m - 1.0 / 12.0).abs() < 1e-15);
        // ∫ ξ² dξ over [−τ/2, τ/2] = τ³/12 (the bending moment of inertia)
        let tau = 1.8e-4;
        let i2: f64 = g
            .through_thickness(tau)
            .iter()
            .map(|(x, w)| w * x * x)
            .sum();
        assert!((i2 / (tau.powi(3) / 12.0) - 1.0).abs() < 1e-13);
        assert_eq!(GaussLegendre::new(0), Err(BadOrder(0)));
        assert_eq!(GaussLegendre::new(9), Err(BadOrder(9)));
    }
}
