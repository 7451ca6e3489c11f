//! Small measures the stages share: the axial Green strain of an elongation, how a point's
//! misfit enters the objective ([`Misfit`]), the shape error and mean errors of residuals, and
//! residual lists turned into an [`Evaluation`].

use super::optim::Evaluation;
use nalgebra::DMatrix;

/// Green strain along the axis at an elongation.
pub(super) fn green(dl: f64, length: f64) -> f64 {
    let l = 1.0 + dl / length;
    0.5 * (l * l - 1.0)
}

/// Which misfit of a point (model force F̂, measured F) the objective sums the squares of
/// (`ks-fit fit --objective`).
///
/// * `relative`: (F̂ − F)/F, the paper's (§5). Under a multiplicative scatter between repeats
///   (measured = s·true, s a strip's own force scale) its optimum is biased low: for one
///   curve shape the best model scale c minimises Σ (c/sᵢ − 1)², so c = Σ(1/sᵢ)/Σ(1/sᵢ²),
///   which weights the weakest repeat most (E[c] ≈ 1 − 2σ² for a scale scatter σ: −4.5 % at
///   σ = 0.15, and −27 % on the bundled denim's warp, whose three repeats lie at 0.62–1.15 of
///   the law that made them).
/// * `log`: ln(F̂/F). Symmetric in the scale: the optimum is the repeats' geometric mean
///   (E[c] ≈ 1 − σ²/2), and a repeat twice too strong pulls as hard as one half as strong.
///   Equal to the relative misfit to first order, so a single curve fitted to 1 % gets the
///   same law either way.
/// * `auto` (default): `log` when some angle has two or more fitted repeats (the scatter it
///   is there for), else `relative`: a fit with one curve per angle (the paper's protocol) is
///   the paper's, bit for bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Objective {
    #[default]
    Auto,
    Relative,
    Log,
}

/// The misfit a fit uses ([`Objective`] decided).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Misfit {
    #[default]
    Relative,
    Log,
}

/// The ratio of model force to data force below which the log misfit goes on along its tangent
/// at that ratio (a misfit of ln 0.1 = −2.30, a point 90 % low): finite and with a slope for
/// a model force that is zero or negative (a strip compressed in its toe, an interpolated
/// toe below zero), where ln(F̂/F) has none; above it the misfit is the logarithm exactly.
pub const LOG_TANGENT_BELOW: f64 = 0.1;

impl Misfit {
    /// The misfit of model force `model` against the data's force `data` (positive).
    pub fn of(self, model: f64, data: f64) -> f64 {
        match self {
            Self::Relative => (model - data) / data,
            Self::Log => {
                let q = model / data;
                if q >= LOG_TANGENT_BELOW {
                    q.ln()
                } else {
                    LOG_TANGENT_BELOW.ln() + (q - LOG_TANGENT_BELOW) / LOG_TANGENT_BELOW
                }
            }
        }
    }

    /// ∂misfit/∂model.
    pub fn slope(self, model: f64, data: f64) -> f64 {
        match self {
            Self::Relative => 1.0 / data,
            Self::Log => 1.0 / model.max(LOG_TANGENT_BELOW * data),
        }
    }

    /// The change of the misfit against `data` when the model force goes from `from` to `to`.
    pub fn change(self, from: f64, to: f64, data: f64) -> f64 {
        let floor = LOG_TANGENT_BELOW * data;
        match self {
            Self::Relative => (to - from) / data,
            Self::Log if from >= floor && to >= floor => (to / from).ln(),
            Self::Log => self.of(to, data) - self.of(from, data),
        }
    }

    /// The relative error F̂/F − 1 of a misfit.
    pub fn relative(self, misfit: f64) -> f64 {
        let knee = LOG_TANGENT_BELOW.ln();
        match self {
            Self::Relative => misfit,
            Self::Log if misfit >= knee => misfit.exp_m1(),
            Self::Log => LOG_TANGENT_BELOW * (1.0 + misfit - knee) - 1.0,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Relative => "relative",
            Self::Log => "log",
        }
    }
}

/// The misfit `objective` asks for on `prep`'s curves (see [`Objective`]).
pub(super) fn decide(objective: Objective, prep: &super::Prepared) -> Misfit {
    match objective {
        Objective::Relative => Misfit::Relative,
        Objective::Log => Misfit::Log,
        Objective::Auto => {
            let repeated = prep.strips.iter().any(|s| {
                s.curves
                    .iter()
                    .filter(|&&c| prep.curves[c].used_in_fit)
                    .count()
                    >= 2
            });
            if repeated {
                Misfit::Log
            } else {
                Misfit::Relative
            }
        }
    }
}

pub(super) fn to_evaluation(r: Vec<f64>, j: Vec<Vec<f64>>, n: usize, jac: bool) -> Evaluation {
    let jacobian = jac.then(|| {
        let mut m = DMatrix::zeros(r.len(), n);
        for (i, row) in j.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                m[(i, c)] = *v;
            }
        }
        m
    });
    Evaluation {
        residuals: r,
        jacobian,
    }
}

/// Shape misfit of a set of curves: each curve's mean |relative error| after its own best
/// force scale, averaged over the curves. `lens` are the curves' point counts and `rel`
/// their relative errors in order. Repeat-to-repeat scatter is mostly a scale (strip width,
/// yarn count per strip), which no law can fit; the degree of η is chosen on what is left.
pub(super) fn shape_error(lens: &[usize], rel: &[f64]) -> f64 {
    let mut k = 0;
    let mut sum = 0.0;
    for &n in lens {
        let q: Vec<f64> = rel[k..k + n].iter().map(|r| 1.0 + r).collect();
        k += n;
        let s = q.iter().sum::<f64>() / q.iter().map(|v| v * v).sum::<f64>().max(1e-300);
        sum += q.iter().map(|v| (s * v - 1.0).abs()).sum::<f64>() / n.max(1) as f64;
    }
    sum / lens.len().max(1) as f64
}

pub(super) fn mean_abs(r: &[f64]) -> f64 {
    r.iter().map(|v| v.abs()).sum::<f64>() / r.len().max(1) as f64
}

/// Mean |r| over the finite values only: the errors of a curve whose excluded points (a
/// saddle's, see `rigs::node_force`) are NaN.
pub(super) fn mean_abs_finite(r: &[f64]) -> f64 {
    let ok: Vec<f64> = r.iter().copied().filter(|v| v.is_finite()).collect();
    mean_abs(&ok)
}

#[cfg(test)]
mod tests {
    use super::Misfit;

    /// Each misfit's slope against a central difference, `relative` as its inverse, and
    /// `change` as the difference of two misfits.
    #[test]
    fn misfits_slopes_and_inverses() {
        for m in [Misfit::Relative, Misfit::Log] {
            // the last two on the log misfit's tangent (a model force 5 % of the data's,
            // and a negative one)
            for (model, data) in [(1.3, 1.0), (0.6, 2.0), (5.0, 4.9), (0.05, 1.0), (-0.3, 2.0)] {
                let h = 1e-6 * model;
                let fd = (m.of(model + h, data) - m.of(model - h, data)) / (2.0 * h);
                assert!(
                    (fd - m.slope(model, data)).abs() < 1e-8,
                    "{m:?} {model} {data}"
                );
                let rel = m.relative(m.of(model, data));
                assert!((rel - (model / data - 1.0)).abs() < 1e-14, "{m:?}");
                let ch = m.change(model, 1.1 * model, data);
                let diff = m.of(1.1 * model, data) - m.of(model, data);
                assert!((ch - diff).abs() < 1e-14, "{m:?}");
            }
        }
        // the log misfit and its slope are continuous where its tangent takes over
        let knee = super::LOG_TANGENT_BELOW;
        let (lo, hi) = (knee * (1.0 - 1e-12), knee * (1.0 + 1e-12));
        assert!((Misfit::Log.of(lo, 1.0) - Misfit::Log.of(hi, 1.0)).abs() < 1e-10);
        assert!((Misfit::Log.slope(lo, 1.0) / Misfit::Log.slope(hi, 1.0) - 1.0).abs() < 1e-10);
        // equal to first order, and symmetric in a scale only for the log
        assert!((Misfit::Log.of(1.001, 1.0) - Misfit::Relative.of(1.001, 1.0)).abs() < 1e-6);
        assert_eq!(Misfit::Log.of(2.0, 1.0), -Misfit::Log.of(1.0, 2.0));
        assert!(Misfit::Relative.of(2.0, 1.0) != -Misfit::Relative.of(1.0, 2.0));
    }
}
