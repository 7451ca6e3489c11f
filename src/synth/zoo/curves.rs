//! Curves a lab sees that the paper's law did not make, and the artefacts of a lab record.

use super::Rng;

/// One analytic force–strain family; `stiffness` is the small- or large-strain slope per
/// width, N/m, and F = stiffness · width · f(ε) for strain ε.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Family {
    /// f = ε (1 + c ε): the newcomer's F = k·e·(1 + c·e)
    Quadratic { stiffness: f64, c: f64 },
    /// slope 1 to a knee at ε_k, then `ratio` times steeper, joined over a width δ
    Knee {
        stiffness: f64,
        knee: f64,
        ratio: f64,
    },
    /// f = (exp(b ε) − 1) / b: exponential stiffening
    Exponential { stiffness: f64, b: f64 },
    /// a long toe: f = ε² / (2 ε_t) up to ε_t, then ε − ε_t/2 (crimp taken up)
    Toe { stiffness: f64, toe: f64 },
}

/// The knee's rounding, in strain.
const KNEE_WIDTH: f64 = 0.003;

impl Family {
    /// A family drawn uniformly, with its stiffness per width `stiffness` (N/m).
    pub(super) fn draw(rng: &mut Rng, stiffness: f64) -> Self {
        match rng.int(0, 3) {
            0 => Family::Quadratic {
                stiffness,
                c: rng.between(2.0, 30.0),
            },
            1 => Family::Knee {
                stiffness,
                knee: rng.between(0.01, 0.05),
                ratio: rng.between(2.0, 6.0),
            },
            2 => Family::Exponential {
                stiffness,
                b: rng.between(5.0, 40.0),
            },
            _ => Family::Toe {
                stiffness,
                toe: rng.between(0.01, 0.04),
            },
        }
    }

    /// The force (N) of a strip `width` wide (m) at strain `e` ≥ 0.
    pub fn force(&self, width: f64, e: f64) -> f64 {
        let f = match *self {
            Family::Quadratic { c, .. } => e * (1.0 + c * e),
            Family::Knee { knee, ratio, .. } => {
                let x = (e - knee) / KNEE_WIDTH;
                let softplus = if x > 30.0 { x } else { x.exp().ln_1p() };
                let at_zero = (-knee / KNEE_WIDTH).exp().ln_1p();
                e + (ratio - 1.0) * KNEE_WIDTH * (softplus - at_zero)
            }
            Family::Exponential { b, .. } => (b * e).exp_m1() / b,
            Family::Toe { toe, .. } => {
                if e < toe {
                    e * e / (2.0 * toe)
                } else {
                    e - toe / 2.0
                }
            }
        };
        self.stiffness() * width * f
    }

    pub fn stiffness(&self) -> f64 {
        match *self {
            Family::Quadratic { stiffness, .. }
            | Family::Knee { stiffness, .. }
            | Family::Exponential { stiffness, .. }
            | Family::Toe { stiffness, .. } => stiffness,
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            Family::Quadratic { .. } => "quadratic",
            Family::Knee { .. } => "knee",
            Family::Exponential { .. } => "exponential",
            Family::Toe { .. } => "toe",
        }
    }
}

/// Monotone cubic interpolation (Fritsch & Carlson 1980) of (xs, ys) at `x`, xs increasing:
/// the lab's dense record between the virtual lab's solved points, without overshoot.
pub fn pchip(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    let n = xs.len();
    if n == 1 {
        return ys[0];
    }
    let k = xs.partition_point(|&v| v <= x).clamp(1, n - 1) - 1;
    let slope = |i: usize| (ys[i + 1] - ys[i]) / (xs[i + 1] - xs[i]);
    let tangent = |i: usize| -> f64 {
        if i == 0 {
            return slope(0);
        }
        if i == n - 1 {
            return slope(n - 2);
        }
        let (a, b) = (slope(i - 1), slope(i));
        if a * b <= 0.0 {
            0.0
        } else {
            let (h0, h1) = (xs[i] - xs[i - 1], xs[i + 1] - xs[i]);
            let (w0, w1) = (2.0 * h1 + h0, h1 + 2.0 * h0);
            (w0 + w1) / (w0 / a + w1 / b)
        }
    };
    let h = xs[k + 1] - xs[k];
    let t = ((x - xs[k]) / h).clamp(0.0, 1.0);
    let (t2, t3) = (t * t, t * t * t);
    (2.0 * t3 - 3.0 * t2 + 1.0) * ys[k]
        + (t3 - 2.0 * t2 + t) * h * tangent(k)
        + (-2.0 * t3 + 3.0 * t2) * ys[k + 1]
        + (t3 - t2) * h * tangent(k + 1)
}
