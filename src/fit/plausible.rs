//! Laws the data determine and that behave: the checks every fitted η passes.
//!
//! - **Bounded exponents**: |α x̂| ≤ [`BETA_MAX`](super::map::BETA_MAX), built into the stage
//!   variables ([`super::map`]).
//! - **Negligible terms are dropped.** A term's share of η'(x) = Σ μᵢ(1 + x)^(αᵢ−1) over the
//!   exercised range [0, x̂] is at most |μᵢ| max(1, (1 + x̂)^(αᵢ−1)). Below [`NEGLIGIBLE`] (0.1 %
//!   of η'(0) = 1) the term changes no force by more than about that much, and a weight that
//!   small cannot be told from zero by curves that scatter by a percent: it is removed and its
//!   weight given to the largest term, so that Σμ = 1 (η'(0) = 1) still holds.
//! - **Rising stress**: the stress σ(E) = c η'(E²) E must rise wherever the law is its own
//!   (the material reader refuses a law whose stress falls inside its cut-offs, since a
//!   falling branch has no stable equilibrium). A higher degree whose stress peaks inside the
//!   exercised range is refused; if the kept law's still does, its cut-off is moved below the
//!   peak, so that past it the law continues on its rising tangent, with a note.

use super::map::{var_to_beta, Direction, StageMap};
use super::StrainRange;
use crate::material::{Eta, Orthotropic};

/// Largest share of η' a term may have over the exercised range and still be dropped.
pub const NEGLIGIBLE: f64 = 1e-3;

/// A term's largest share of η' over x ∈ [0, x̂].
fn share(mu: f64, alpha: f64, xhat: f64) -> f64 {
    mu.abs() * ((alpha - 1.0) * xhat.ln_1p()).exp().max(1.0)
}

/// Indices of the terms negligible over [0, x̂] (never all of them: the largest stays).
pub fn negligible_terms(eta: &Eta, xhat: f64) -> Vec<usize> {
    let shares: Vec<f64> = (0..eta.degree())
        .map(|i| share(eta.mu[i], eta.alpha[i], xhat))
        .collect();
    let largest = (0..shares.len())
        .max_by(|&a, &b| shares[a].total_cmp(&shares[b]))
        .unwrap_or(0);
    (0..shares.len())
        .filter(|&i| i != largest && shares[i] < NEGLIGIBLE)
        .collect()
}

/// Drops η's negligible terms (their weight goes to the largest term); returns how many.
pub fn drop_negligible(eta: &mut Eta, xhat: f64) -> usize {
    let gone = negligible_terms(eta, xhat);
    if gone.is_empty() {
        return 0;
    }
    let moved: f64 = gone.iter().map(|&i| eta.mu[i]).sum();
    let keep: Vec<usize> = (0..eta.degree()).filter(|i| !gone.contains(i)).collect();
    let mut mu: Vec<f64> = keep.iter().map(|&i| eta.mu[i]).collect();
    let alpha: Vec<f64> = keep.iter().map(|&i| eta.alpha[i]).collect();
    let big = (0..mu.len())
        .max_by(|&a, &b| mu[a].abs().total_cmp(&mu[b].abs()))
        .unwrap_or(0);
    mu[big] += moved;
    *eta = Eta { mu, alpha };
    gone.len()
}

/// The strain in (0, `e_max`] where η's stress stops rising, if it does (see
/// [`Eta::stress_peak`]).
pub fn stress_peak(eta: &Eta, e_max: f64) -> Option<f64> {
    (e_max > 0.0).then(|| eta.stress_peak(e_max)).flatten()
}

/// How far past the tested strain √x̂ a law's stress must keep rising for the shell to see
/// it uncut, as a multiple of √x̂: strips reach more than their nominal strain at the jaws'
/// corners, bias strips shear about twice the isotropic estimate, and Newton's iterates go
/// further still.
pub const PEAK_SEARCH: f64 = 4.0;

/// Share of a stress peak's strain at which a cut-off below it lies.
pub const BELOW_PEAK: f64 = 0.95;

/// Whether η's stiffest term (the largest exponent, a positive one) has a negative weight:
/// η' = Σ μᵢ(1 + x)^(αᵢ−1) then falls without bound as the strain grows, so the stress falls
/// past some strain and the energy drops without bound there (a sink that draws Newton's
/// iterates until the energy overflows).
pub fn falls_eventually(eta: &Eta) -> bool {
    let stiffest = (0..eta.degree()).max_by(|&a, &b| eta.alpha[a].total_cmp(&eta.alpha[b]));
    stiffest.is_some_and(|i| eta.alpha[i] > 0.0 && eta.mu[i] < 0.0)
}

/// The cut-off a law needs for its stress to rise up to it and its energy to stay bounded
/// (x̂: the largest tested value of η's argument): [`BELOW_PEAK`] of its stress peak within
/// [`PEAK_SEARCH`] √x̂, else [`PEAK_SEARCH`] √x̂ itself where its stiffest term falls; `None`
/// where the stress rises throughout.
pub fn fall_cutoff(eta: &Eta, xhat: f64) -> Option<f64> {
    let e_max = PEAK_SEARCH * xhat.sqrt();
    match stress_peak(eta, e_max) {
        Some(e) => Some(BELOW_PEAK * e),
        None => falls_eventually(eta).then_some(e_max),
    }
}

/// The fitter's side of the checks: which degree is plausible, the cut-offs below any stress
/// peak, and where a new term starts.
/// Why `law`'s η of `map` is not a plausible higher degree, if it is not: it lost a term as
/// negligible, or its stress stops rising inside the exercised range (`range`, else the
/// strain x̂ estimates) (see the module doc).
pub(super) fn implausible(
    law: &Orthotropic,
    map: StageMap,
    range: Option<&StrainRange>,
) -> Option<String> {
    let eta = map.eta(law);
    if !negligible_terms(eta, map.xhat).is_empty() {
        return Some("adds a term too small to matter".into());
    }
    let e_max = range.map_or(map.xhat.sqrt(), |r| exercised(map.dir, r));
    stress_peak(eta, e_max)
        .map(|e| format!("has its stress stop rising at strain {e:.4}, inside the tested range"))
}

/// `law`'s η of `dir` with the cut-off it acts under, and the cut-off's strain's name.
fn direction(law: &mut Orthotropic, dir: Direction) -> (&Eta, &mut (f64, f64), &'static str) {
    match dir {
        Direction::Warp => (&law.warp, &mut law.cutoffs.e11, "Ẽ11"),
        Direction::Weft => (&law.weft, &mut law.cutoffs.e22, "Ẽ22"),
        Direction::Shear => (&law.shear, &mut law.cutoffs.e12, "|Ẽ12|"),
    }
}

/// Moves `law`'s cut-off of `dir` below the strain where the fitted stress stops rising, if
/// that is inside it; the note that says so. The law then continues past it on its rising
/// tangent.
pub(super) fn keep_rising(law: &mut Orthotropic, dir: Direction) -> Option<String> {
    let (eta, cut, name) = direction(law, dir);
    let e_max = cut.0.abs().max(cut.1.abs());
    if !e_max.is_finite() {
        return None;
    }
    let e = stress_peak(eta, e_max)?;
    let to = 0.95 * e;
    *cut = (cut.0.max(-to), cut.1.min(to));
    Some(format!(
        "the fitted {} law's stress stops rising at strain {e:.4}, inside the strains the tests reach: cut-off {name} lowered to {to:.4}, past which the law goes on along its tangent",
        dir.name()
    ))
}

/// Cuts `law`'s η of `map`'s direction off at its [`fall_cutoff`] where it has one tighter
/// than its cut-offs; the note that says so. Past the cut-off the law goes on along its rising
/// tangent, so the shell's energy stays finite wherever its strips stray.
pub(super) fn cut_before_fall(law: &mut Orthotropic, map: StageMap) -> Option<String> {
    let (eta, cut, name) = direction(law, map.dir);
    let to = fall_cutoff(eta, map.xhat)?;
    if cut.0 >= -to && cut.1 <= to {
        return None;
    }
    *cut = (cut.0.max(-to), cut.1.min(to));
    Some(format!(
        "the {} law's stress stops rising within {PEAK_SEARCH} times the tested strain (or its stiffest term falls past it): cut-off {name} at {to:.4}, past which the law goes on along its tangent",
        map.dir.name()
    ))
}

/// The largest strain of `dir`'s component in a strain range.
pub(super) fn exercised(dir: Direction, range: &StrainRange) -> f64 {
    let (lo, hi) = range;
    match dir {
        Direction::Warp => hi[0],
        Direction::Weft => hi[1],
        Direction::Shear => hi[2].abs().max(lo[2].abs()),
    }
}

/// Where the shell's new term of degree d + 1 starts to bend: at the bootstrap candidate's
/// exponent farthest from every exponent the shell's degree-d law `prev` already has. A new
/// term bending where an old one does adds nothing the old one cannot, so the gradient
/// towards it vanishes and the stage stalls; the bootstrap's term order is arbitrary (two
/// equal optima differ by a swap), so its last term is no choice at all. On a degree-2 shear
/// law (μ = 0.7, 0.3; α = 1, 300): from β = 0.39, next to the shell's 0.53, the 45° strip
/// stalls at 3.6 %; from the bootstrap's other exponent, 0.11, it fits to 0.03 %.
pub(super) fn new_term_beta(map: StageMap, prev: &[f64], cand: &[f64]) -> f64 {
    let betas = |p: &[f64]| -> Vec<f64> {
        let (d, a) = (map.degree(p), map.first_alpha(p));
        p[a..a + d].iter().map(|&u| var_to_beta(u)).collect()
    };
    let old = betas(prev);
    let gap = |b: f64| {
        old.iter()
            .map(|o| (b - o).abs())
            .fold(f64::INFINITY, f64::min)
    };
    betas(cand)
        .into_iter()
        .max_by(|a, b| gap(*a).total_cmp(&gap(*b)))
        .unwrap_or(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tiny_weight_with_a_huge_exponent_is_not_negligible_but_a_tiny_share_is() {
        let xhat = 6.6e-3;
        // μ = 2.5e-8, α = 2168 (a degenerate fitted warp law): 4 % of η' at x̂
        let knee = Eta {
            mu: vec![1.0 - 2.5e-8, 2.5e-8],
            alpha: vec![78.0, 2168.0],
        };
        assert!(negligible_terms(&knee, xhat).is_empty());
        // μ = 1e-4 bending gently: 1e-4 × e^0.5 of η' at most
        let mut small = Eta {
            mu: vec![0.7, 1e-4, 0.3 - 1e-4],
            alpha: vec![1.0, 75.0, 150.0],
        };
        assert_eq!(negligible_terms(&small, xhat), vec![1]);
        let before: Vec<f64> = [1e-3, 3e-3, xhat]
            .iter()
            .map(|&x| small.eval(x).unwrap()[1])
            .collect();
        assert_eq!(drop_negligible(&mut small, xhat), 1);
        assert_eq!(small.degree(), 2);
        assert!((small.mu.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        // η' moves by about the dropped share at most
        for (x, b) in [1e-3, 3e-3, xhat].iter().zip(before) {
            let after = small.eval(*x).unwrap()[1];
            assert!((after - b).abs() <= 2.0 * NEGLIGIBLE * b, "x = {x}");
        }
        // the largest term always stays
        let mut one = Eta {
            mu: vec![1.0],
            alpha: vec![1.0],
        };
        assert_eq!(drop_negligible(&mut one, xhat), 0);
    }

    #[test]
    fn a_law_whose_stiffest_term_falls_is_cut_off_below_its_peak() {
        // the degree-2 warp law bootstrapped from F = k·e(1 + c·e) (k = 21 N/mm, c = 0.08/mm,
        // 6 mm on a 75 mm gauge): it fits the curve, and its stress peaks at Ẽ11 ≈ 0.12
        let xhat = (0.08f64 + 0.5 * 0.08 * 0.08).powi(2);
        let warp = Eta {
            mu: vec![1.0779676904322697, -0.07796769043226962],
            alpha: vec![62.179602374951884, 244.86231627930988],
        };
        assert!(falls_eventually(&warp));
        assert_eq!(
            stress_peak(&warp, xhat.sqrt()),
            None,
            "rises over the tests"
        );
        let peak = stress_peak(&warp, PEAK_SEARCH * xhat.sqrt()).expect("a peak past them");
        let cut = fall_cutoff(&warp, xhat).expect("a cut-off");
        assert_eq!(cut, BELOW_PEAK * peak);
        assert!(cut > xhat.sqrt() && cut < 0.2, "{cut}");
        // far out the stiffest term dominates: η' < 0, the energy heads for −∞ and overflows
        let [h, d1, _] = warp.eval(0.2).expect("finite at 45 % strain");
        assert!(d1 < 0.0 && h < 0.0, "{h} {d1}");
        assert_eq!(warp.eval(25.0), None);
        // the same law cut off there stays finite and its stress rising everywhere
        let mut law = crate::material::Orthotropic {
            a11: 1.9e8,
            a22: 1.2e8,
            a12: 0.6e8,
            g12: 6.5e6,
            warp,
            weft: Eta::linear(),
            shear: Eta::linear(),
            cutoffs: crate::material::Cutoffs::none(),
            coupling: None,
        };
        law.cutoffs.e11 = (-cut, cut);
        let s11 = |e: f64| {
            let r = crate::material::Law::response(&law, &nalgebra::Vector3::new(e, 0.0, 0.0));
            r.expect("finite").stress[0]
        };
        let mut last = 0.0;
        for e in [0.01, 0.05, 0.08, 0.12, 0.5, 5.0] {
            assert!(s11(e) > last, "stress at {e}: {} after {last}", s11(e));
            last = s11(e);
        }
        // laws that stiffen throughout are left as they are
        let stiff = Eta {
            mu: vec![0.4, 0.6],
            alpha: vec![8.5, 204.8],
        };
        assert!(!falls_eventually(&stiff));
        assert_eq!(fall_cutoff(&stiff, xhat), None);
        assert_eq!(fall_cutoff(&Eta::linear(), xhat), None);
    }

    #[test]
    fn stress_peaks_are_found_inside_the_range_only() {
        // σ ∝ (1 + E²)^(α−1) E with α = −100: dσ/dE = 0 where 1 + (2α − 1)E² = 0
        let soft = Eta {
            mu: vec![1.0],
            alpha: vec![-100.0],
        };
        let peak = (1.0f64 / 201.0).sqrt();
        let found = stress_peak(&soft, 0.2).expect("a peak at E ≈ 0.0705");
        assert!((found - peak).abs() < 1e-6 * peak, "{found} vs {peak}");
        assert_eq!(stress_peak(&soft, 0.9 * peak), None);
        assert_eq!(stress_peak(&Eta::linear(), 1.0), None);
    }
}
