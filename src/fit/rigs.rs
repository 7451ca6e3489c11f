//! The strips the fitter solves: set up once per strip and mesh level, kept warm between
//! evaluations, and their node forces interpolated to every measured point of the curves
//! measured on them.

use super::preprocess::interpolation_weights;
use super::refine::Doublings;
use super::{
    Context, FitError, FitOptions, FitStats, Fitted, RigKey, Work, FIT_RTOL, NEAR_ANGLE_DEG,
};
use crate::assembly::YarnRule;
use crate::material::Orthotropic;
use crate::scene::{SceneError, StripRig, TensileStrip};
use std::collections::HashMap;

/// A strip mesh at a ladder level: the level's 50 × 75 mm element size (h = 50 mm / NX) on the
/// strip, but at least NX/4 faces across (a 2 mm strip gets 2, 4, 8 across on the default
/// ladder, where the element size alone gives it 2 at every level) and elements at most 4
/// times longer than wide; at most 2000 along.
pub(super) fn strip_mesh(level: (usize, usize), width: f64, length: f64) -> (usize, usize) {
    let h = 0.05 / level.0 as f64;
    let across = ((width / h).round() as usize).max(level.0 / 4).max(2);
    let slender = (length * across as f64 / (4.0 * width)).ceil();
    let along = ((length / h).round().max(slender) as usize).clamp(2, 2000);
    (across, along)
}

/// Forces of a strip at its nodes.
type NodeSet = Vec<f64>;

/// Forces of a strip at its nodes and ∂F/∂k (law parameters, then thickness) when asked.
pub(super) type NodeForces = (Vec<f64>, Vec<Vec<f64>>);

/// A node's predicted force: NaN where its equilibrium is a saddle (the strip would wrinkle
/// there and the flat state's force is not what a lab measures), so that every measured point
/// interpolated from it is excluded, never silently compared.
pub(super) fn node_force(p: &crate::scene::TensilePoint) -> f64 {
    if p.report.stable {
        p.force
    } else {
        f64::NAN
    }
}

/// The virtual lab a fit keeps warm across its stages: the strips and cantilevers set up, the
/// node forces predicted, the yarn rule, and the meshes each test is solved on. It solves for
/// the material it is given, never for one of its own.
#[derive(Default)]
pub(super) struct Lab {
    /// strips already set up, warm
    rigs: HashMap<RigKey, StripRig>,
    /// cantilevers already set up, warm ([`Lab::bend_rigs`])
    pub(super) bend_cache: HashMap<super::thickness::BendKey, crate::scene::BendRig>,
    /// node forces already predicted, by strip and parameter bits
    predictions: HashMap<(RigKey, Vec<u64>), Vec<f64>>,
    /// the yarn rule of every solve, once decided ([`Lab::decide_yarns`])
    yarns: Option<YarnRule>,
    /// the yarn-to-shear ratio that sets new strips' β ([`Lab::pin_yarns`])
    yarn_ratio: Option<f64>,
    /// each test's mesh against the ladder's level ([`super::refine`])
    pub(super) meshes: Doublings,
}

impl Lab {
    /// A cold lab for `strips` strips, none refined.
    pub(super) fn new(strips: usize) -> Self {
        Self {
            meshes: Doublings::new(strips),
            ..Self::default()
        }
    }

    /// The yarn rule of every solve of the fit: `--yarn-rule`, with `auto` decided once by
    /// the law after the bootstrap ([`Lab::decide_yarns`]; the full rule until then).
    pub(super) fn yarns(&self) -> YarnRule {
        self.yarns.unwrap_or(YarnRule::Full)
    }

    /// A warm strip, if one is set up under `key`.
    pub(super) fn warm_rig(&self, key: &RigKey) -> Option<&StripRig> {
        self.rigs.get(key)
    }

    /// Pins the centre rule's β for the strips set up from now on to `law`'s yarn-to-shear
    /// ratio: at the start of each ladder level, so that one level's strips (and the checks
    /// and reports on it) share one discretisation, while a level after a first fit gets the
    /// β of a law near the answer, not the bootstrap's (on the ratio-2e4 fit of
    /// `paper_repro/stiff_fit` the bootstrap's ratio is far below the truth, and its β on
    /// every level biased G12 by −0.97 %).
    pub(super) fn pin_yarns(&mut self, law: &Orthotropic) {
        self.yarn_ratio = crate::material::Law::yarn_shear_ratio(law);
    }

    /// The rule of a strip cut at `angle`: the fit's, but `auto` keeps the full rule where
    /// the yarns run along the cage ([`YarnRule::for_strip`]).
    pub(super) fn strip_yarns(&self, opts: &FitOptions, angle: f64) -> YarnRule {
        if opts.yarn_rule.for_strip(angle) == YarnRule::Full {
            YarnRule::Full
        } else {
            self.yarns()
        }
    }

    /// Decides `--yarn-rule auto` by the bootstrapped `law`'s yarn-to-shear ratio, so that
    /// every strip of the fit shares one discretisation; the note that says so when the
    /// centre rule is chosen.
    pub(super) fn decide_yarns(&mut self, opts: &FitOptions, law: &Orthotropic) -> Option<String> {
        let ratio = crate::material::Law::yarn_shear_ratio(law);
        let rule = opts.yarn_rule.resolve(ratio);
        self.yarns = Some(rule);
        self.yarn_ratio = ratio;
        if rule != YarnRule::Centre {
            return None;
        }
        let why = match opts.yarn_rule {
            YarnRule::Auto => format!(
                " (--yarn-rule auto: yarn-to-shear stiffness ratio {:.0} at the bootstrap, above {:.0})",
                ratio.unwrap_or(f64::NAN),
                crate::assembly::CENTRE_FROM_RATIO
            ),
            _ => String::new(),
        };
        Some(format!(
            "yarn terms integrated on the face centres{why}: a membrane that does not lock on nearly inextensible yarns; mesh errors estimated at order {}",
            super::mesh_check::order(opts.grading, rule, ratio)
        ))
    }

    /// Strip `s` cut at `angle` on mesh `level` (its own, resolved) as the fit solves it:
    /// graded, with the lab's yarn rule and ratio, the fit's tolerance and strategy.
    pub(super) fn strip_scene(
        &self,
        ctx: &Context,
        s: usize,
        angle: f64,
        level: (usize, usize),
    ) -> TensileStrip {
        let strip = &ctx.prep.strips[s];
        let mut t = TensileStrip::new(strip.width, strip.length, angle);
        t.mesh = strip_mesh(level, strip.width, strip.length);
        t.grading = ctx.opts.grading;
        t.yarn_rule = self.strip_yarns(ctx.opts, angle);
        t.yarn_ratio = self.yarn_ratio;
        // forces to 1e-8 are far inside any fit's reach; 1e-10 made Newton crawl at round-off
        t.solver.rtol = FIT_RTOL;
        t.solver.strategy = ctx.opts.strategy;
        t
    }

    /// The rig of strip `s` cut at `angle` on a mesh level for material `m`: from the cache
    /// (warm) or set up; hand it back with [`Lab::keep_rig`].
    pub(super) fn strip_rig(
        &mut self,
        ctx: &Context,
        m: &Fitted,
        s: usize,
        angle: f64,
        level: (usize, usize),
    ) -> Result<(RigKey, StripRig), FitError> {
        let level = self.meshes.strip_level(s, level);
        let strip = &ctx.prep.strips[s];
        let key = ctx.rig_key(s, angle, level);
        if let Some(rig) = self.rigs.remove(&key) {
            return Ok((key, rig));
        }
        let t = self.strip_scene(ctx, s, angle, level);
        let mut rig = t
            .rig(&m.material(ctx.data), &strip.nodes)
            .map_err(|source| FitError::Scene {
                stage: format!("setting up the {angle}° strip"),
                source,
            })?;
        // a strip cut at a nearby angle (the misalignment grid) starts from the nearest such
        // strip's equilibria rather than from rest
        let nearest = self
            .rigs
            .iter()
            .filter(|(k, _)| k.0[..2] == key.0[..2] && k.1 == key.1 && k.2 == key.2)
            .map(|(k, r)| ((f64::from_bits(k.0[2]) - angle).abs(), r))
            .filter(|(d, _)| *d <= NEAR_ANGLE_DEG)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, other)) = nearest {
            rig.warm_from(other);
        }
        Ok((key, rig))
    }

    pub(super) fn keep_rig(&mut self, key: RigKey, mut rig: StripRig) {
        rig.set_wanted(None);
        self.rigs.insert(key, rig);
    }

    /// Node forces of strip `s` cut at `angle` on a mesh level for material `m` (no
    /// sensitivities), memoised by parameters; the solver's work goes to `stats`.
    pub(super) fn predict(
        &mut self,
        ctx: &Context,
        m: &Fitted,
        stats: &mut FitStats,
        (s, angle, level): (usize, f64, (usize, usize)),
    ) -> Result<Vec<f64>, FitError> {
        let (key, mut rig) = self.strip_rig(ctx, m, s, angle, level)?;
        let memo_key = (key.clone(), m.param_bits());
        if let Some(f) = self.predictions.get(&memo_key) {
            let f = f.clone();
            self.keep_rig(key, rig);
            return Ok(f);
        }
        let out = run_rig(&mut rig, &m.law, m, stats, false)
            .map(|r| r.0)
            .map_err(|source| FitError::Scene {
                stage: format!("predicting the {angle}° strip"),
                source,
            });
        self.keep_rig(key, rig);
        if let Ok(f) = &out {
            self.predictions.insert(memo_key, f.clone());
        }
        out
    }

    /// Node forces of several (strip, angle) pairs on a mesh level for material `m`, the
    /// strips solved side by side (independent solves, so the results are those of solving
    /// them one after another, bit for bit).
    pub(super) fn predict_many(
        &mut self,
        ctx: &Context,
        m: &Fitted,
        stats: &mut FitStats,
        jobs: &[(usize, f64)],
        level: (usize, usize),
    ) -> Result<Vec<Vec<f64>>, FitError> {
        let jobs: Vec<_> = jobs.iter().map(|&(s, angle)| (s, angle, level)).collect();
        self.predict_levels(ctx, m, stats, &jobs)
    }

    /// The same jobs on two mesh levels, solved in one batch ([`Lab::predict_levels`]): the
    /// forces on `a`, then on `b`.
    pub(super) fn predict_pair(
        &mut self,
        ctx: &Context,
        m: &Fitted,
        stats: &mut FitStats,
        jobs: &[(usize, f64)],
        (a, b): ((usize, usize), (usize, usize)),
    ) -> Result<(Vec<NodeSet>, Vec<NodeSet>), FitError> {
        let both: Vec<_> = [a, b]
            .iter()
            .flat_map(|&l| jobs.iter().map(move |&(s, angle)| (s, angle, l)))
            .collect();
        let mut on_a = self.predict_levels(ctx, m, stats, &both)?;
        let on_b = on_a.split_off(jobs.len());
        Ok((on_a, on_b))
    }

    /// [`Lab::predict_many`] with a mesh level per job: strips on two levels (an estimate's
    /// mesh and its half) solved in one batch, so that a long solve on one level keeps one core
    /// while the other takes the rest (the ratio-2e4 fit of `paper_repro/stiff_fit`: its
    /// wrinkling 67.5° strip takes 36 s on 16 × 24, its nine other solves of the first per-test
    /// sweep 21 s, and the sweep as one batch taken in order 37 s, against 39 s with the batch
    /// split in halves).
    pub(super) fn predict_levels(
        &mut self,
        ctx: &Context,
        m: &Fitted,
        stats: &mut FitStats,
        jobs: &[(usize, f64, (usize, usize))],
    ) -> Result<Vec<Vec<f64>>, FitError> {
        let bits = m.param_bits();
        let mut todo: Vec<(RigKey, StripRig, f64)> = Vec::new();
        for &(s, angle, level) in jobs {
            let (key, rig) = self.strip_rig(ctx, m, s, angle, level)?;
            if self.predictions.contains_key(&(key.clone(), bits.clone()))
                || todo.iter().any(|t| t.0 == key)
            {
                self.keep_rig(key, rig);
            } else {
                todo.push((key, rig, angle));
            }
        }
        let results = run_side_by_side(&mut todo, m);
        let mut failed = None;
        for ((key, rig, angle), r) in todo.into_iter().zip(results) {
            match r {
                Ok(pts) => {
                    let newton = pts.iter().map(|p| p.report.iterations).sum();
                    stats.record(Work::run(pts.len(), newton));
                    let f: Vec<f64> = pts.iter().map(node_force).collect();
                    self.predictions.insert((key.clone(), bits.clone()), f);
                }
                Err(source) => {
                    failed.get_or_insert(FitError::Scene {
                        stage: format!("predicting the {angle}° strip"),
                        source,
                    });
                }
            }
            self.keep_rig(key, rig);
        }
        if let Some(e) = failed {
            return Err(e);
        }
        jobs.iter()
            .map(|&job| self.predict(ctx, m, stats, job))
            .collect()
    }
}

/// Runs the strips of `todo` for material `m` side by side, taken in order by whichever thread
/// is free (not split in halves: two long solves next to each other go to different cores);
/// the results in `todo`'s order.
fn run_side_by_side(
    todo: &mut [(RigKey, StripRig, f64)],
    m: &Fitted,
) -> Vec<Result<Vec<crate::scene::TensilePoint>, SceneError>> {
    use rayon::prelude::*;
    let (law, tau, bending) = (&m.law, m.thickness, m.bending);
    let mut results: Vec<(usize, Result<Vec<crate::scene::TensilePoint>, SceneError>)> = todo
        .iter_mut()
        .enumerate()
        .par_bridge()
        .map(|(i, (_, rig, _))| {
            let run = rig.set_material(law, tau).and_then(|_| {
                rig.set_bending(bending);
                rig.run(false)
            });
            (i, run)
        })
        .collect();
    results.sort_by_key(|r| r.0);
    results.into_iter().map(|r| r.1).collect()
}

/// Runs a rig with `law` and `m`'s thickness and rigidities (forces, and ∂F/∂k when asked);
/// the solver's work goes to `stats`.
pub(super) fn run_rig(
    rig: &mut StripRig,
    law: &Orthotropic,
    m: &Fitted,
    stats: &mut FitStats,
    sens: bool,
) -> Result<NodeForces, SceneError> {
    rig.set_material(law, m.thickness)?;
    rig.set_bending(m.bending);
    let pts = rig.run(sens)?;
    let newton = pts.iter().map(|p| p.report.iterations).sum();
    stats.record(Work::run(pts.len(), newton));
    Ok((
        pts.iter().map(node_force).collect(),
        pts.into_iter().map(|p| p.dforce).collect(),
    ))
}

impl Context<'_> {
    /// The cache key of strip `s` cut at `angle` on the mesh of `level` (the strip's own).
    pub(super) fn rig_key(&self, s: usize, angle: f64, level: (usize, usize)) -> RigKey {
        let strip = &self.prep.strips[s];
        (
            [
                strip.width.to_bits(),
                strip.length.to_bits(),
                angle.to_bits(),
            ],
            level,
            strip.nodes.iter().map(|e| e.to_bits()).collect(),
        )
    }

    /// Mean |relative error| of curve `c`'s measured points against its `model` forces (NaN
    /// model forces, saddles, left out).
    pub(super) fn curve_fit_error(&self, c: usize, model: &[f64]) -> f64 {
        let r: Vec<f64> = self.prep.curves[c]
            .points
            .iter()
            .zip(model)
            .map(|(m, q)| (q - m.1) / m.1)
            .collect();
        super::mean_abs_finite(&r)
    }

    /// A curve's model forces at its points, interpolated from its strip's node forces.
    /// The model's force at every measured point of curve `c`, interpolated from the node
    /// forces: NaN where the interpolation uses a node with no force (a saddle, see
    /// [`node_force`]).
    pub(super) fn curve_forces(&self, c: usize, node_forces: &[f64]) -> Vec<f64> {
        let curve = &self.prep.curves[c];
        let nodes = &self.prep.strips[curve.strip].nodes;
        curve
            .points
            .iter()
            .map(|&(e, _)| {
                interpolation_weights(nodes, e)
                    .iter()
                    .map(|&(k, w)| w * node_forces[k])
                    .sum()
            })
            .collect()
    }
}

/// Residuals r = w m(F̂, F) of a curve (m the [`super::Misfit`]: (F̂ − F)/F or ln(F̂/F)), w =
/// 1/√n so that every curve counts alike, and their rows of ∂r/∂p from the nodes' ∂F/∂p.
pub(super) fn curve_residuals(
    misfit: super::Misfit,
    points: &[(f64, f64)],
    nodes: &[f64],
    node_forces: &[f64],
    node_dp: Option<&[Vec<f64>]>,
    out_r: &mut Vec<f64>,
    out_j: &mut Vec<Vec<f64>>,
) {
    let w = 1.0 / (points.len() as f64).sqrt();
    for &(e, f) in points {
        let weights = interpolation_weights(nodes, e);
        let model: f64 = weights.iter().map(|&(k, a)| a * node_forces[k]).sum();
        // a point interpolated from a saddle is excluded: no residual, no gradient
        let excluded = !model.is_finite();
        out_r.push(if excluded {
            0.0
        } else {
            w * misfit.of(model, f)
        });
        if let Some(d) = node_dp {
            let mut row = vec![0.0; d.first().map_or(0, |r| r.len())];
            if excluded {
                out_j.push(row);
                continue;
            }
            let slope = w * misfit.slope(model, f);
            for &(k, a) in &weights {
                for (r, v) in row.iter_mut().zip(&d[k]) {
                    *r += slope * a * v;
                }
            }
            out_j.push(row);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{curve_residuals, strip_mesh};

    /// A saddle's node (NaN force) excludes exactly the points interpolated from it: no
    /// residual, no gradient; every other point keeps its weighted relative error.
    #[test]
    fn points_interpolated_from_a_saddle_are_excluded() {
        let nodes: Vec<f64> = (1..=8).map(|k| k as f64).collect();
        let forces: Vec<f64> = nodes.iter().map(|e| 2.0 * e).collect();
        let dp: Vec<Vec<f64>> = nodes.iter().map(|e| vec![*e]).collect();
        let points: Vec<(f64, f64)> = [1.5, 2.5, 6.5, 7.5].iter().map(|&e| (e, 2.2 * e)).collect();
        let run = |forces: &[f64]| {
            let (mut r, mut j) = (Vec::new(), Vec::new());
            curve_residuals(
                super::super::Misfit::Relative,
                &points,
                &nodes,
                forces,
                Some(&dp),
                &mut r,
                &mut j,
            );
            (r, j)
        };
        let (r, j) = run(&forces);
        let w = 0.5; // 1/√4 points
        for (k, v) in r.iter().enumerate() {
            assert!((v - w * (2.0 / 2.2 - 1.0)).abs() < 1e-12, "point {k}: {v}");
            assert!(j[k][0] != 0.0);
        }
        let mut saddle = forces.clone();
        saddle[7] = f64::NAN;
        let (r2, j2) = run(&saddle);
        assert_eq!(r2.len(), 4);
        // the last point uses node 8; the first two do not
        assert_eq!((r2[3], j2[3][0]), (0.0, 0.0));
        assert_eq!(&r2[..2], &r[..2]);
        assert!(r2.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn narrow_strips_are_refined_across_with_the_ladder() {
        // the standard strip keeps the ladder's meshes
        assert_eq!(strip_mesh((8, 12), 0.05, 0.075), (8, 12));
        assert_eq!(strip_mesh((16, 24), 0.05, 0.075), (16, 24));
        // a 2 mm strip on a 75 mm gauge: 2, 4, 8 across, elements at most 4:1
        for (level, across) in [((8, 12), 2), ((16, 24), 4), ((32, 48), 8)] {
            let (nx, ny) = strip_mesh(level, 0.002, 0.075);
            assert_eq!(nx, across);
            assert!(
                0.075 / ny as f64 <= 4.0 * 0.002 / nx as f64 + 1e-12,
                "{nx}x{ny}"
            );
        }
    }
}
