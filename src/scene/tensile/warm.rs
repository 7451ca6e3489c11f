//! Warm starts of a strip rig: its stored equilibria moved to new parameters (the tangent
//! ∂q/∂k, else the multi-secant through earlier equilibria), and starts taken from another
//! rig's equilibria (a nearby angle; points between another rig's).

use super::StripRig;
use crate::Vec3;

/// Earlier equilibria kept per point for the secant predictor (two do best; see
/// [`StripRig::warm_start`]).
pub(super) const SECANTS: usize = 2;

/// Weights c of the multi-secant predictor x ≈ x₁ + Σ c_j (x_j − x₁): the least-squares (minimum
/// norm) solution of Σ c_j (k_j − k₁) = k − k₁, each parameter relative to its largest size
/// among the points (a pseudo-inverse that drops directions under 1e-8 of the largest, so
/// nearly repeated points cannot blow the weights up). Exact for equilibria that depend
/// linearly on the parameters within the span of the earlier changes; first order otherwise.
fn secant_weights(k: &[f64], k1: &[f64], earlier: &[&[f64]]) -> Vec<f64> {
    let (n, m) = (k.len(), earlier.len());
    let scale: Vec<f64> = (0..n)
        .map(|p| {
            earlier
                .iter()
                .map(|e| e[p].abs())
                .fold(k1[p].abs(), f64::max)
                .max(f64::MIN_POSITIVE)
        })
        .collect();
    let s = nalgebra::DMatrix::from_fn(n, m, |p, j| (earlier[j][p] - k1[p]) / scale[p]);
    let d = nalgebra::DVector::from_fn(n, |p, _| (k[p] - k1[p]) / scale[p]);
    if d.iter().all(|v| *v == 0.0) {
        return vec![0.0; m];
    }
    let svd = s.svd(true, true);
    let top = svd.singular_values.iter().copied().fold(0.0, f64::max);
    match svd.solve(&d, 1e-8 * top) {
        Ok(c) if c.iter().all(|v| v.is_finite()) => c.iter().copied().collect(),
        _ => vec![0.0; m],
    }
}

/// Relative residual of a point's start above which the next point's warm start is first
/// compared with the predictor from the last equilibrium (from 1e-3, Newton needs three
/// or more iterations).
pub(super) const POOR_START: f64 = 1e-3;

impl StripRig {
    /// Whether the warm start `w` at elongation `dl` begins nearer balance (a smaller relative
    /// residual) than the predictor from the last equilibrium of this run (two gradient
    /// assemblies). After a large change of the parameters, or of a cut-off that the
    /// parameter tangent does not see, every stored equilibrium can be far off while the
    /// last point's, just solved, predicts the next to third order in the step (on the
    /// bundled cotton: stale warm starts at 1–4e-2 against predictors at 3e-5–1e-2; the
    /// choice saves about 14 % of the Newton iterations of the five bundled fits).
    pub(super) fn warm_beats_predictor(
        &mut self,
        w: &[Vec3],
        previous: &super::Last,
        before: Option<&(f64, Vec<Vec3>)>,
        dl: f64,
    ) -> bool {
        if previous.is_none() {
            return true;
        }
        let cold = self.predict(previous, before, dl);
        self.start_residual(dl, w) <= self.start_residual(dl, &cold)
    }

    /// Takes `other`'s equilibria as this rig's warm starts, where the two rigs share the
    /// mesh, the clamps and the elongations (strips cut at nearby angles: the angle changes
    /// only the material frame, not the control net). Returns whether they were taken. The
    /// parameter tangents are not taken: they belong to the other angle's equilibria.
    pub fn warm_from(&mut self, other: &StripRig) -> bool {
        let same = self.elongations == other.elongations
            && self.length == other.length
            && self.model.basis.control_points == other.model.basis.control_points
            && self.bottom_fixed == other.bottom_fixed
            && self.top_fixed == other.top_fixed;
        if !same {
            return false;
        }
        for (mine, theirs) in self.equilibria.iter_mut().zip(&other.equilibria) {
            if mine.is_none() {
                mine.clone_from(theirs);
            }
        }
        true
    }

    /// Takes as warm starts, where the two rigs share the mesh and the clamps, the equilibria
    /// of `other` (solved with the same material) interpolated in the elongation by the
    /// quadratic through three of its consecutive points around each of this rig's (the rest
    /// state ahead of its first): a start for points between another rig's, such as the
    /// fitter's interpolation check halfway between its nodes, where it saves 12–15 % of the
    /// Newton iterations of the linear interpolation between the two nearest on the
    /// bundled cotton and silk. Returns whether they were taken.
    pub fn warm_between(&mut self, other: &StripRig) -> bool {
        let same = self.length == other.length
            && self.model.basis.control_points == other.model.basis.control_points
            && self.bottom_fixed == other.bottom_fixed
            && self.top_fixed == other.top_fixed
            && other.equilibria.iter().all(Option::is_some);
        if !same || other.elongations.is_empty() {
            return false;
        }
        // the path known at the other rig's points, the rest state first
        let rest = &self.model.basis.control_points;
        let known: Vec<(f64, &Vec<Vec3>)> = std::iter::once((0.0, rest))
            .chain(
                other
                    .elongations
                    .iter()
                    .zip(&other.equilibria)
                    .map(|(&e, x)| (e, x.as_ref().expect("all"))),
            )
            .collect();
        for (i, &e) in self.elongations.iter().enumerate() {
            // the first known point at or past e (past the rest state)
            let k = 1 + other.elongations.partition_point(|&o| o < e);
            if k >= known.len() {
                return false;
            }
            // three consecutive known points around e (two where only two are known)
            let j0 = if k + 1 < known.len() {
                k - 1
            } else {
                k.saturating_sub(2)
            };
            let js: Vec<usize> = (j0..(j0 + 3).min(known.len())).collect();
            let w: Vec<f64> = js
                .iter()
                .map(|&a| {
                    js.iter()
                        .filter(|&&b| b != a)
                        .map(|&b| (e - known[b].0) / (known[a].0 - known[b].0))
                        .product()
                })
                .collect();
            self.equilibria[i] = Some(
                (0..rest.len())
                    .map(|n| {
                        std::array::from_fn(|c| {
                            js.iter()
                                .zip(&w)
                                .map(|(&j, wj)| wj * known[j].1[n][c])
                                .sum()
                        })
                    })
                    .collect(),
            );
            let k = k - 1;
            self.solved_params[i].clone_from(&other.solved_params[k]);
            self.tangents[i] = None;
            self.earlier[i].clear();
        }
        true
    }

    /// The start at point `i` from its stored equilibrium, moved to the current parameters:
    /// along ∂q/∂k where the last run computed it there (first order), else by the
    /// multi-secant through the earlier equilibria ([`secant_weights`]; a fitter's trials
    /// without sensitivities: space-mapped starts, line searches). Two earlier equilibria
    /// save the most Newton iterations on the five bundled fits (about 13 %; one or four
    /// save less), every fitted parameter within 2e-8. `None` ahead of the first solve.
    pub(super) fn warm_start(&self, i: usize) -> Option<Vec<Vec3>> {
        let mut x = self.equilibria[i].clone()?;
        if let Some((k0, dq)) = &self.tangents[i] {
            if k0.len() == self.params.len() {
                self.system.advance_along(&mut x, &self.params, k0, dq);
                return Some(x);
            }
        }
        let Some(k1) = &self.solved_params[i] else {
            return Some(x);
        };
        let earlier: Vec<&(Vec<Vec3>, Vec<f64>)> = self.earlier[i]
            .iter()
            .filter(|e| e.1.len() == k1.len())
            .collect();
        if k1.len() != self.params.len() || earlier.is_empty() {
            return Some(x);
        }
        let ks: Vec<&[f64]> = earlier.iter().map(|e| &e.1[..]).collect();
        let c = secant_weights(&self.params, k1, &ks);
        let x1 = x.clone();
        for (cj, (xj, _)) in c.iter().zip(earlier) {
            if *cj != 0.0 {
                for ((p, a), b) in x.iter_mut().zip(&x1).zip(xj) {
                    for d in 0..3 {
                        p[d] += cj * (b[d] - a[d]);
                    }
                }
            }
        }
        Some(x)
    }
}

#[cfg(test)]
mod tests {
    use super::secant_weights;
    use crate::material::{Cutoffs, Eta, FabricMaterial, Orthotropic};
    use crate::scene::tensile::TensileStrip;

    /// A linear orthotropic law with warp stiffness `a11`.
    /// The linear law at a11 = 2e8 Pa (yarn-to-shear ratio 50) and a 50 × 75 mm strip cut at
    /// 30° on a 4 × 6 cage.
    fn strip_at_30() -> (FabricMaterial, TensileStrip) {
        let m = FabricMaterial::paper("t", 0.1, 2e-4, linear_law(2e8));
        let mut t = TensileStrip::new(0.05, 0.075, 30.0);
        t.mesh = (4, 6);
        (m, t)
    }

    fn linear_law(a11: f64) -> Orthotropic {
        Orthotropic {
            a11,
            a22: 1e8,
            a12: 3e7,
            g12: 4e6,
            warp: Eta::linear(),
            weft: Eta::linear(),
            shear: Eta::linear(),
            cutoffs: Cutoffs::none(),
            coupling: None,
        }
    }

    /// A rig started between another rig's equilibria (same mesh, same material) reaches the
    /// same forces as one started from rest, in fewer Newton iterations.
    #[test]
    fn points_between_solved_ones_start_from_their_interpolation() {
        let m = FabricMaterial::paper("t", 0.1, 2e-4, linear_law(2e8));
        let mut t = TensileStrip::new(0.05, 0.075, 30.0);
        t.mesh = (4, 6);
        let nodes = [1e-3, 2e-3, 3e-3];
        let mids = [5e-4, 1.5e-3, 2.5e-3];
        let mut solved = t.rig(&m, &nodes).unwrap();
        solved.run(false).unwrap();
        let cold = t.rig(&m, &mids).unwrap().run(false).unwrap();
        let mut warm = t.rig(&m, &mids).unwrap();
        assert!(warm.warm_between(&solved));
        let warm = warm.run(false).unwrap();
        let its =
            |p: &[crate::scene::TensilePoint]| p.iter().map(|p| p.report.iterations).sum::<usize>();
        for (a, b) in warm.iter().zip(&cold) {
            assert!(
                (a.force - b.force).abs() <= 1e-7 * b.force.abs(),
                "{} vs {}",
                a.force,
                b.force
            );
        }
        assert!(its(&warm) < its(&cold), "{} vs {}", its(&warm), its(&cold));
        // another mesh is not taken
        t.mesh = (2, 3);
        assert!(!t.rig(&m, &mids).unwrap().warm_between(&solved));
    }

    /// After a change of the law that no tangent saw (every stored equilibrium far from
    /// balance), the points after the first start from the predictor where it is nearer
    /// balance: the forces are those of a rig run from rest, and the run takes fewer
    /// iterations than warm starts alone would. The start's residual is the solver's own
    /// first one.
    #[test]
    fn a_stale_warm_start_gives_way_to_the_predictor() {
        let law = linear_law;
        let (m, mut t) = strip_at_30();
        // the full rule, which `auto` does not take at these ratios (50 and 150): on the
        // centre rule this coarse strip's fourth point settles on neighbouring equilibria
        // 1.5e-4 apart from the two starts, which is not what this test is about
        t.yarn_rule = crate::assembly::YarnRule::Full;
        let nodes = [1e-3, 2e-3, 3e-3, 4e-3, 5e-3];
        let its =
            |p: &[crate::scene::TensilePoint]| p.iter().map(|p| p.report.iterations).sum::<usize>();
        let stale = |choose: bool| {
            let mut rig = t.rig(&m, &nodes).unwrap();
            rig.run(false).unwrap();
            rig.set_material(&law(6e8), 2e-4).unwrap();
            if !choose {
                // warm starts alone: solve each point from its stored equilibrium
                let mut total = 0;
                for i in 0..nodes.len() {
                    let x = rig.warm_start(i).unwrap();
                    let r0 = rig.start_residual(nodes[i], &x);
                    let (_, report, _) = rig.solve_at(nodes[i], x, 60).unwrap();
                    assert_eq!(report.initial_residual, Some(r0));
                    total += report.iterations;
                }
                return (Vec::new(), total);
            }
            let pts = rig.run(false).unwrap();
            let n = its(&pts);
            (pts, n)
        };
        let (chosen, n_chosen) = stale(true);
        let (_, n_warm) = stale(false);
        let mut fresh_material = m.clone();
        fresh_material.law = law(6e8);
        let fresh = t.rig(&fresh_material, &nodes).unwrap().run(false).unwrap();
        for (a, b) in chosen.iter().zip(&fresh) {
            assert!(
                (a.force - b.force).abs() <= 1e-7 * b.force.abs(),
                "{} vs {}",
                a.force,
                b.force
            );
        }
        assert!(n_chosen < n_warm, "{n_chosen} vs {n_warm}");
    }

    /// On a field linear in the parameters, x(k) = A k, the multi-secant predictor is exact for
    /// any change in the span of the earlier ones, and takes the least-squares part of one
    /// outside it; no change gives no move.
    #[test]
    fn the_secant_predictor_is_exact_on_a_linear_field() {
        let a = [[2.0, -1.0, 0.5], [0.3, 4.0, -2.0]];
        let x = |k: &[f64]| -> Vec<f64> {
            a.iter()
                .map(|r| r.iter().zip(k).map(|(p, q)| p * q).sum())
                .collect()
        };
        // parameters of very different sizes, as a stiffness beside an exponent
        let k1 = [1e6, 3.0, 0.2];
        let e1 = [1.1e6, 3.0, 0.2];
        let e2 = [1e6, 2.5, 0.25];
        let predict = |k: &[f64], earlier: &[&[f64]]| -> Vec<f64> {
            let c = secant_weights(k, &k1, earlier);
            let x1 = x(&k1);
            let mut p = x1.clone();
            for (cj, e) in c.iter().zip(earlier) {
                for ((pi, a), b) in p.iter_mut().zip(&x1).zip(x(e)) {
                    *pi += cj * (b - a);
                }
            }
            p
        };
        // a change in the span of the two earlier steps
        let k = [1e6 + 0.3e6, 3.0 - 0.2 * 0.5, 0.2 + 0.2 * 0.05];
        for (p, q) in predict(&k, &[&e1, &e2]).iter().zip(x(&k)) {
            assert!((p - q).abs() <= 1e-9 * q.abs().max(1.0), "{p} vs {q}");
        }
        // with the first earlier step only, the second direction is not known: the move is
        // the projection on the first
        let c = secant_weights(&k, &k1, &[&e1]);
        assert!((c[0] - 3.0).abs() < 1e-12, "{c:?}");
        assert_eq!(secant_weights(&k1, &k1, &[&e1, &e2]), vec![0.0, 0.0]);
        // a repeated earlier point adds nothing and blows nothing up
        let c = secant_weights(&k, &k1, &[&e1, &e1]);
        assert!(c.iter().all(|v| v.is_finite() && v.abs() < 10.0), "{c:?}");
    }

    /// A pinned yarn-to-shear ratio gives rigs set up for different laws one discretisation
    /// (the centre rule's β); unpinned, each rig's β follows its own law.
    #[test]
    fn a_pinned_yarn_ratio_gives_every_rig_one_discretisation() {
        let law = linear_law;
        let (m, mut t) = strip_at_30();
        t.yarn_ratio = crate::material::Law::yarn_shear_ratio(&law(2e8));
        let nodes = [1e-3, 2e-3];
        let mut rig = t.rig(&m, &nodes).unwrap();
        rig.set_material(&law(6e8), 2e-4).unwrap();
        let moved = rig.run(false).unwrap();
        let mut stiffer = m.clone();
        stiffer.law = law(6e8);
        let pinned = t.rig(&stiffer, &nodes).unwrap().run(false).unwrap();
        t.yarn_ratio = None;
        let own = t.rig(&stiffer, &nodes).unwrap().run(false).unwrap();
        for ((a, b), c) in moved.iter().zip(&pinned).zip(&own) {
            assert!(
                (a.force - b.force).abs() <= 1e-7 * b.force,
                "{} vs {}",
                a.force,
                b.force
            );
            assert!(
                (a.force - c.force).abs() > 1e-2 * c.force,
                "{} vs {}",
                a.force,
                c.force
            );
        }
    }
}
