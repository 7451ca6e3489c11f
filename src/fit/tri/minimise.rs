//! The minimisers of the triangle-model fit: residuals of a set of tests, a damped
//! Gauss–Newton on log stiffness with forward-difference Jacobians, spline refinement, and a
//! coarse scan for misfits that jump (buckled shapes).

use super::{tie_diagonal, Target};
use crate::tri::curve::Stiffness;
use crate::tri::{TriKind, TriMaterial};

/// The rms of the residuals of `set`.
pub(super) fn cost(
    m: &TriMaterial,
    set: &[usize],
    targets: &[Target],
    evaluations: &mut usize,
) -> (f64, Vec<f64>) {
    *evaluations += 1;
    use rayon::prelude::*;
    // the tests are independent: solved side by side, collected in order
    let r: Vec<f64> = set
        .par_iter()
        .map(|&i| targets[i].residuals(m))
        .collect::<Vec<_>>()
        .concat();
    (
        (r.iter().map(|v| v * v).sum::<f64>() / r.len().max(1) as f64).sqrt(),
        r,
    )
}

/// Fits component `c` on the targets `set`: linear first, then (with `controls`, the most
/// control values) with 2, 3 and 5 control values over the strains the set reaches while each
/// lowers the rms by ≥ 1 %. Says each iteration through `say`. Returns the final rms.
pub(super) fn stage(
    m: &mut TriMaterial,
    c: usize,
    set: &[usize],
    targets: &[Target],
    evaluations: &mut usize,
    controls: Option<usize>,
    say: &mut dyn FnMut(&str),
) -> f64 {
    let mut best = levenberg_marquardt(m, &[c], set, targets, evaluations, say);
    // a fit within 0.01 % has nothing left for control points to explain
    let Some(max_controls) = controls.filter(|_| best >= 1e-4) else {
        return best;
    };
    let reach = set
        .iter()
        .filter_map(|&i| match &targets[i] {
            Target::Strip {
                strip, elongation, ..
            } => elongation.last().map(|e| e / strip.length),
            _ => None,
        })
        .fold(0.0f64, f64::max);
    if reach <= 0.0 {
        return best;
    }
    for n in [2, 3, 5].into_iter().filter(|&n| n <= max_controls) {
        let old = m.curves[c].clone();
        let Some(finer) = refined(&old, reach, n) else {
            break;
        };
        m.curves[c] = finer;
        let mut tagged = |line: &str| say(&format!("{n} control values, {line}"));
        let cost = levenberg_marquardt(m, &[c], set, targets, evaluations, &mut tagged);
        if cost < 0.99 * best {
            best = cost;
        } else {
            m.curves[c] = old;
            break;
        }
    }
    best
}

/// The stiffness `old` resampled at `n` equidistant strains over [0, `reach`], each value
/// kept at [`SPLINE_FLOOR`] of the largest at least: a cubic Hermite spline with
/// central-difference tangents overshoots between uneven values and can dip below zero there
/// (values 1, 1, 100 give −5.2 halfway between the first two), and a spline refuses negative
/// values. `None` where no value is finite and positive, or where the resampled stress does
/// not rise ([`Stiffness::stress_rises`]).
pub(super) fn refined(old: &Stiffness, reach: f64, n: usize) -> Option<Stiffness> {
    let mut k: Vec<f64> = (0..n)
        .map(|j| old.at(reach * j as f64 / (n.max(2) - 1) as f64).0)
        .collect();
    let top = k
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    if top <= 0.0 {
        return None;
    }
    for v in k.iter_mut() {
        if v.is_nan() || *v < SPLINE_FLOOR * top {
            *v = SPLINE_FLOOR * top;
        }
    }
    Stiffness::spline(0.0, reach, k)
        .ok()
        .filter(|s| s.stress_rises())
}

/// Smallest control value of a spline as a fraction of its largest: a stiffness that falls a
/// hundredfold inside the tested range is no fabric's, and one near zero leaves a mode without
/// stiffness (a stvk-ds fit of 4-point curves drove a shear spline's first value to 2.5e-5 N/m
/// from about 400, and no cantilever solved after it).
pub const SPLINE_FLOOR: f64 = 1e-2;

/// Multiplies control value `j` (over the components `comps`, in order) by `f`, keeping the
/// diagonal hinge tied to the warp and weft bending and every value at least [`SPLINE_FLOOR`]
/// of its spline's largest.
pub(super) fn scale_value(m: &mut TriMaterial, comps: &[usize], mut j: usize, f: f64) {
    for &c in comps {
        let n = m.curves[c].k.len();
        if j < n {
            m.curves[c].k[j] *= f;
            let top = m.curves[c].k.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for v in m.curves[c].k.iter_mut() {
                if v.abs() < SPLINE_FLOOR * top {
                    *v = SPLINE_FLOOR * top;
                }
            }
            if (c == 3 || c == 4) && m.kind != TriKind::Springs {
                tie_diagonal(m);
            }
            return;
        }
        j -= n;
    }
}

/// Most Gauss–Newton iterations of one [`levenberg_marquardt`] run.
const LM_ITERATIONS: usize = 20;

/// Most damped trials of one Gauss–Newton iteration before it gives up.
const LM_TRIALS: usize = 10;

/// Largest move of a log control value in one trial: a factor e^0.7 ≈ 2.
const LM_MAX_STEP: f64 = 0.7;

/// Relative drop of the rms below which an accepted step ends the run.
const LM_GAIN: f64 = 1e-4;

/// Damped Gauss–Newton on log k of the control values of the components `comps`, each trial
/// moving a value by at most a factor e^0.7 ≈ 2 (a much softer cantilever than the last takes
/// long to solve, and the tied warp and weft bending are nearly collinear where the diagonal
/// hinges carry the bend, which makes undamped steps long). Says each iteration's rms error
/// through `say`.
pub(super) fn levenberg_marquardt(
    m: &mut TriMaterial,
    comps: &[usize],
    set: &[usize],
    targets: &[Target],
    evaluations: &mut usize,
    say: &mut dyn FnMut(&str),
) -> f64 {
    let lm = Lm {
        comps,
        set,
        targets,
    };
    let (mut rms, mut r) = cost(m, set, targets, evaluations);
    // a start at which a test does not solve has no Jacobian: the scale of the stage's
    // component at which every test solves and fits best is the start instead
    if !rms.is_finite() && comps.len() == 1 {
        scan(m, comps[0], set, targets, evaluations, say);
        (rms, r) = cost(m, set, targets, evaluations);
    }
    let mut lambda = 1e-3;
    for it in 1..=LM_ITERATIONS {
        let Some(jac) = lm.jacobian(m, &r, evaluations) else {
            break;
        };
        let mut tell = |line: &str| say(&format!("iteration {it}: {line}"));
        let state = (&mut rms, &mut r);
        let improved = lm.damped_step(m, &jac, state, &mut lambda, evaluations, &mut tell);
        say(&format!(
            "iteration {it}: rms error {:.2} % over {} test(s), {} evaluation(s) so far",
            100.0 * rms,
            set.len(),
            evaluations
        ));
        if !improved {
            break;
        }
    }
    rms
}

/// One Gauss–Newton problem: the control values of `comps` fitted to the targets `set`.
struct Lm<'a> {
    comps: &'a [usize],
    set: &'a [usize],
    targets: &'a [Target],
}

impl Lm<'_> {
    /// Whether every fitted component's stress rises with its strain
    /// ([`Stiffness::stress_rises`]): a trial whose stress falls is rejected before it is
    /// solved.
    fn stress_rises(&self, m: &TriMaterial) -> bool {
        self.comps.iter().all(|&c| m.curves[c].stress_rises())
    }

    /// The forward-difference Jacobian of the residuals `r` at `m` in log k, one column per
    /// control value (`None` where a column is not finite).
    fn jacobian(
        &self,
        m: &TriMaterial,
        r: &[f64],
        evaluations: &mut usize,
    ) -> Option<Vec<Vec<f64>>> {
        let n: usize = self.comps.iter().map(|&c| m.curves[c].k.len()).sum();
        let h: f64 = 1e-4;
        // the Jacobian's columns are independent runs: solved side by side (a stage of one
        // test, like a shape or a cantilever, has no other parallelism), collected in order
        let jac: Vec<Vec<f64>> = {
            use rayon::prelude::*;
            (0..n)
                .into_par_iter()
                .map(|j| {
                    let mut t = m.clone();
                    scale_value(&mut t, self.comps, j, h.exp());
                    let (_, rt) = cost(&t, self.set, self.targets, &mut 0);
                    rt.iter().zip(r).map(|(x, y)| (x - y) / h).collect()
                })
                .collect()
        };
        *evaluations += n;
        (!jac.iter().flatten().any(|v| !v.is_finite())).then_some(jac)
    }

    /// Trials of the damped step from `m` (rms error and residuals `state`), raising the
    /// damping `lambda` fourfold after each rejected one (said through `say`); the first that
    /// lowers the rms is taken into `m` and `state`. Whether it lowered the rms by more than
    /// [`LM_GAIN`].
    fn damped_step(
        &self,
        m: &mut TriMaterial,
        jac: &[Vec<f64>],
        (rms, r): (&mut f64, &mut Vec<f64>),
        lambda: &mut f64,
        evaluations: &mut usize,
        say: &mut dyn FnMut(&str),
    ) -> bool {
        let n = jac.len();
        for trial in 1..=LM_TRIALS {
            let mut a = nalgebra::DMatrix::<f64>::zeros(n, n);
            let mut b = nalgebra::DVector::<f64>::zeros(n);
            for p in 0..n {
                b[p] = -jac[p].iter().zip(r.iter()).map(|(x, y)| x * y).sum::<f64>();
                for q in 0..n {
                    a[(p, q)] = jac[p].iter().zip(&jac[q]).map(|(x, y)| x * y).sum::<f64>();
                }
                a[(p, p)] *= 1.0 + *lambda;
                a[(p, p)] += 1e-12;
            }
            let Some(step) = a.lu().solve(&b) else {
                return false;
            };
            let mut t = m.clone();
            for j in 0..n {
                let d = step[j].clamp(-LM_MAX_STEP, LM_MAX_STEP);
                scale_value(&mut t, self.comps, j, d.exp());
            }
            if !self.stress_rises(&t) {
                *lambda *= 4.0;
                say(&format!(
                    "trial {trial} rejected (its stress falls as the strain grows), damping raised"
                ));
                continue;
            }
            let (trms, tr) = cost(&t, self.set, self.targets, evaluations);
            if trms < *rms {
                let gain = (*rms - trms) / *rms;
                *m = t;
                (*rms, *r) = (trms, tr);
                *lambda = (*lambda / 4.0).max(1e-9);
                return gain > LM_GAIN;
            }
            *lambda *= 4.0;
            say(&format!(
                "trial {trial} rejected (rms error {:.2} % against {:.2} %), damping raised",
                100.0 * trms,
                100.0 * *rms
            ));
        }
        false
    }
}

/// Scales component `c` (all its control values) by the factor of 2^(j/2), j = −8…8, that
/// fits the targets `set` best: a buckled sheet's shape jumps between branches of wrinkles as
/// a stiffness changes, so its misfit is discontinuous and a local method started on another
/// branch stalls (a frame's positions error from stvk-ds: 5 % at the true shear, 63 % at 1.05
/// times it, 205 % at 1.18 times, 126 % at a quarter). A misfit that is not finite (a test
/// that does not solve) is worse than any finite one, so a start at which a test fails moves
/// to the best factor at which all solve (a springs cantilever at its converted bending
/// stiffness hangs too far to solve and solves at four times it).
pub(super) fn scan(
    m: &mut TriMaterial,
    c: usize,
    set: &[usize],
    targets: &[Target],
    evaluations: &mut usize,
    say: &mut dyn FnMut(&str),
) {
    use rayon::prelude::*;
    let mut best = (cost(m, set, targets, evaluations).0, 1.0);
    // the trials are independent: run side by side, compared in order
    let factors: Vec<f64> = (-8..=8)
        .filter(|&j| j != 0)
        .map(|j| 2f64.powf(j as f64 / 2.0))
        .collect();
    // in rounds of one trial a thread, each said, so that a scan whose trials solve slowly
    // is not silent for all sixteen
    let mut trials: Vec<f64> = Vec::with_capacity(factors.len());
    for round in factors.chunks(rayon::current_num_threads().max(1)) {
        let m = &*m;
        let rms: Vec<f64> = round
            .par_iter()
            .map(|&f| {
                let mut t = m.clone();
                for v in t.curves[c].k.iter_mut() {
                    *v *= f;
                }
                if (c == 3 || c == 4) && t.kind != TriKind::Springs {
                    tie_diagonal(&mut t);
                }
                cost(&t, set, targets, &mut 0).0
            })
            .collect();
        trials.extend(rms);
        say(&format!(
            "scan: {} of {} factors tried",
            trials.len(),
            factors.len()
        ));
    }
    *evaluations += factors.len();
    for (&f, &rms) in factors.iter().zip(&trials) {
        if rms < best.0 || (rms.is_finite() && !best.0.is_finite()) {
            best = (rms, f);
        }
    }
    for v in m.curves[c].k.iter_mut() {
        *v *= best.1;
    }
    if (c == 3 || c == 4) && m.kind != TriKind::Springs {
        tie_diagonal(m);
    }
    say(&format!(
        "scan: scaled by {:.3}, rms error {:.2} % over {} test(s)",
        best.1,
        100.0 * best.0,
        set.len()
    ));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tri::Stiffness;

    #[test]
    fn a_refined_spline_keeps_its_values_positive_and_its_stress_rising() {
        // 1, 1, 100 over 8 %: the Hermite spline dips to −5.19 at 2 %, which a spline refuses
        let old = Stiffness::spline(0.0, 0.08, vec![1.0, 1.0, 100.0]).unwrap();
        assert!(
            (old.at(0.02).0 + 5.1875).abs() < 1e-12,
            "{}",
            old.at(0.02).0
        );
        let raw: Vec<f64> = (0..5).map(|j| old.at(0.02 * j as f64).0).collect();
        assert!(Stiffness::spline(0.0, 0.08, raw).is_err());
        // held at 1 % of the largest value, the resampled values 1, 1, 1, 44.3, 100 still dip
        // below zero between the third and the fourth: no refinement
        assert!(!old.stress_rises());
        assert!(refined(&old, 0.08, 5).is_none());
        // a stiffening whose stress rises resamples to its own values
        let old = Stiffness::spline(0.0, 0.08, vec![1.0, 2.0, 4.0]).unwrap();
        let finer = refined(&old, 0.08, 5).unwrap();
        assert_eq!(finer.k.len(), 5);
        assert!(finer.stress_rises());
        for j in 0..5 {
            assert_eq!(finer.k[j], old.at(0.02 * j as f64).0);
        }
        // a stiffness with nothing positive to sample refines to nothing
        assert!(refined(&Stiffness::constant(0.0), 0.08, 3).is_none());
    }

    /// The bundled cotton's warp cantilever (25 × 59.7 mm, 8 × 20 faces) on the springs
    /// material its fit reached: at the converted bending stiffness the cantilever hangs too far
    /// to solve, so the stage has no Jacobian there; it starts where the cantilever solves and
    /// fits the drape angle. Six minutes on two cores (each failing solve runs its 500 Newton
    /// iterations), so CI leaves it out: `cargo test --lib -- --ignored a_stage_whose_start`.
    #[test]
    #[ignore = "six minutes on two cores; run with --ignored"]
    fn a_stage_whose_start_does_not_solve_starts_where_it_does() {
        use crate::scene::TriCantilever;
        let s = |k: Vec<f64>| Stiffness::spline(0.0, 0.08, k).unwrap();
        let mut m = TriMaterial {
            kind: TriKind::Springs,
            curves: [
                s(vec![90343.4, 29075.4, 34338.3, 42835.6, 60949.8]),
                s(vec![49038.7, 16052.2, 17954.2, 18884.3, 22342.6]),
                Stiffness::constant(9205.2),
                Stiffness::constant(1079.97),
                Stiffness::constant(2038.74),
                Stiffness::constant(839.14),
            ],
            coupling: 0.0,
            areal_density: 0.1036,
        };
        let mut bend = TriCantilever::new(0.025, 0.059_733_386_365_888, 90.0);
        bend.mesh = (8, 20);
        let targets = [Target::Bend { bend, angle: 41.5 }];
        assert!(cost(&m, &[0], &targets, &mut 0).0.is_nan());
        let rms = levenberg_marquardt(&mut m, &[3], &[0], &targets, &mut 0, &mut |_| {});
        assert!(rms < 0.01, "rms {rms}, bend_warp {:?}", m.curves[3].k);
        assert!(m.curves[3].k[0] > 1079.97, "{:?}", m.curves[3].k);
    }

    /// The stvk-ds weft stage with up to five control values, fitted to one 25 × 75 mm weft
    /// strip pulled to `force` (N) at 0.935, 1.863, 2.794, 3.722 and 4.650 mm, from
    /// `z0001-analytic`'s points; returns the rms error and the fitted weft stiffness.
    fn weft_stage(force: Vec<f64>) -> (f64, Stiffness) {
        use crate::scene::TriTensile;
        let mut strip = TriTensile::new(0.025, 0.075, 0.0);
        strip.mesh = (8, 24);
        strip.budget = Some(150 * 5);
        let elongation = vec![
            0.935209e-3,
            1.862995e-3,
            2.794493e-3,
            3.722279e-3,
            4.650066e-3,
        ];
        let fmax = force.iter().fold(0.0f64, |a, f| a.max(*f));
        let targets = [Target::Strip {
            strip,
            elongation,
            floor: 0.02 * fmax,
            force,
            curve: "a0-1.csv".into(),
            fitted: true,
        }];
        let c = |k: f64| Stiffness::constant(k);
        let mut m = TriMaterial {
            kind: TriKind::StvkDs,
            curves: [c(4.0e5), c(1.2e5), c(48.0), c(1e-4), c(1.5e-4), c(1.3e-4)],
            coupling: 0.0,
            areal_density: 0.35,
        };
        let rms = stage(&mut m, 1, &[0], &targets, &mut 0, Some(5), &mut |_| {});
        (rms, m.curves[1].clone())
    }

    /// A long toe (`z0001-analytic`'s weft: the force's secant stiffness grows 28-fold from
    /// 1.2 % to 6.2 % strain) is fitted by a stiffness that rises from near zero as the data's
    /// secant does.
    #[test]
    fn a_toe_is_fitted_with_a_stress_that_rises() {
        let (rms, k) = weft_stage(vec![1.374766, 19.9109, 60.71734, 120.4689, 189.4895]);
        assert!(k.stress_rises(), "{k:?}");
        assert!(k.k.len() > 1 && k.k[0] < k.k[k.k.len() - 1], "{k:?}");
        assert!(rms < 0.1, "rms {rms}, {k:?}");
    }

    /// A curve whose force dips (60 N, then 45 N) is best followed by a stress that falls: the
    /// strip then splits into a stretched and a slack band. Such trials are refused, and the
    /// fitted stress rises (without the rule the stage ends at a spline whose stress falls).
    #[test]
    fn a_curve_that_dips_is_fitted_with_a_stress_that_rises() {
        let (rms, k) = weft_stage(vec![30.0, 60.0, 45.0, 75.0, 100.0]);
        assert!(k.stress_rises(), "{k:?}");
        assert!(rms.is_finite(), "{k:?}");
    }

    #[test]
    fn a_spline_value_cannot_fall_below_the_floor() {
        let s = |k: Vec<f64>| Stiffness::spline(0.0, 0.1, k).unwrap();
        let mut m = TriMaterial {
            kind: TriKind::StvkDs,
            curves: [
                s(vec![100.0, 200.0, 400.0]),
                Stiffness::constant(1.0),
                Stiffness::constant(1.0),
                Stiffness::constant(1.0),
                Stiffness::constant(1.0),
                Stiffness::constant(1.0),
            ],
            coupling: 0.0,
            areal_density: 0.1,
        };
        // the first value scaled down 1e6 times stops at 1 % of the largest
        scale_value(&mut m, &[0], 0, 1e-6);
        assert_eq!(m.curves[0].k, vec![4.0, 200.0, 400.0]);
        // scaling the largest up lifts the floor with it
        scale_value(&mut m, &[0], 2, 100.0);
        assert_eq!(m.curves[0].k, vec![400.0, 400.0, 40000.0]);
        // an ordinary step is untouched
        scale_value(&mut m, &[0], 1, 2.0);
        assert_eq!(m.curves[0].k, vec![400.0, 800.0, 40000.0]);
    }
}
