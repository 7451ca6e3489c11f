//! The homogeneous bootstrap, the fit's first stage: each direction's degree and initial
//! guess from the homogeneous-strain strip (cheap: a few microseconds an evaluation), from the
//! starting law; the shear's degree candidates for the shell's own degree ladder.

use crate::fit::journal::Journal;
use crate::fit::map::{beta_to_var, Direction, StageMap};
use crate::fit::plausible;
use crate::fit::surrogate::homogeneous_fit;
use crate::fit::{Context, FitStats, Fitted, Work};
use crate::material::Orthotropic;
use rayon::prelude::*;
use std::time::Instant;

/// What the bootstrap reads (the context, the thickness its strips take) and records into.
struct Bootstrap<'b, 'j> {
    ctx: &'b Context<'b>,
    journal: &'b mut Journal<'j>,
    stats: &'b mut FitStats,
    tau: f64,
}

/// Bootstrap from the material `start`: degrees and initial guesses from the homogeneous
/// strip for every direction with fitted strips, defaults (with notes) for the others. The
/// bootstrapped law, and the shear's fit at every degree tried (index d − 1).
pub(in crate::fit) fn bootstrap_all(
    ctx: &Context,
    journal: &mut Journal,
    stats: &mut FitStats,
    start: &Fitted,
    maps: &[StageMap],
    strips: &[Vec<usize>],
) -> (Orthotropic, Vec<Vec<f64>>) {
    let mut b = Bootstrap {
        ctx,
        journal,
        stats,
        tau: start.thickness,
    };
    let mut law = start.law.clone();
    let t0 = Instant::now();
    b.journal.say("bootstrap on the homogeneous-strain strip");
    let mut shear_candidates = Vec::new();
    for k in 0..2 {
        let curves = b.ctx.used_curves(&strips[k]);
        if !curves.is_empty() {
            let (q, _) = b.direction(&law, maps[k], &curves);
            maps[k].decode(&q, &mut law);
        }
    }
    let known = &b.ctx.data.known;
    match (strips[0].is_empty(), strips[1].is_empty()) {
        (true, false) if known.a11.is_none() => {
            law.a11 = law.a22;
            law.warp = law.weft.clone();
            b.journal
                .note("warp not fitted (no 90° test): taken equal to the weft".into());
        }
        (false, true) if known.a22.is_none() => {
            law.a22 = law.a11;
            law.weft = law.warp.clone();
            b.journal
                .note("weft not fitted (no 0° test): taken equal to the warp".into());
        }
        (true, true) => b.journal.note(
            "warp and weft not fitted (no 0° or 90° test): a11 and a22 as given in [known], linear"
                .into(),
        ),
        _ => {}
    }
    // a yarn law whose stress stops rising a little past the tests (a `--degree` the
    // bootstrap kept whatever it does, a softening degree 1) is cut off below that
    for map in &maps[..2] {
        let note = plausible::cut_before_fall(&mut law, *map);
        b.journal.law_note(note);
    }
    b.ctx.a12.apply(&mut law);
    // the homogeneous strip shears freely where a clamped strip cannot: away from 45° (where
    // the two agree best) it misjudges the strip badly (a shape error of 12–18 % over 22.5°,
    // 45° and 67.5° on the bundled fabrics, with starts the shell could not solve), so the
    // shear is bootstrapped on the strips closest to 45° only; the shell stages use them all
    let shear = b.ctx.used_curves(&nearest_45(b.ctx, &strips[2]));
    if !shear.is_empty() {
        let (q, all) = b.direction(&law, maps[2], &shear);
        maps[2].decode(&q, &mut law);
        shear_candidates = all;
    } else if b.ctx.data.known.g12.is_none() {
        law.g12 = 0.02 * law.a11.min(law.a22);
        let g12 = law.g12;
        b.journal.note(format!(
            "{}: linear, G12 = 2 % of min(a11, a22) = {g12:.4e} Pa",
            crate::fit::shapes::SHEAR_ASSUMED
        ));
    }
    b.stats.time_stage("bootstrap", t0);
    (law, shear_candidates)
}

/// The strips among `bias` cut nearest to 45°.
fn nearest_45(ctx: &Context, bias: &[usize]) -> Vec<usize> {
    let nearest = bias
        .iter()
        .map(|&s| (ctx.prep.strips[s].angle_deg - 45.0).abs())
        .fold(f64::INFINITY, f64::min);
    bias.iter()
        .copied()
        .filter(|&s| (ctx.prep.strips[s].angle_deg - 45.0).abs() <= nearest + 1e-9)
        .collect()
}

impl Bootstrap<'_, '_> {
    /// The secant stiffness of curve `c` at its last point, as the stiffness a stage of
    /// `map` starts degree 1 from.
    fn secant(&self, map: StageMap, c: usize) -> f64 {
        let curve = &self.ctx.prep.curves[c];
        let s = &self.ctx.prep.strips[curve.strip];
        let (dl, f) = *curve.points.last().expect("a curve with points");
        let lambda = 1.0 + dl / s.length;
        let secant = f / (s.width * self.tau * lambda * crate::fit::green(dl, s.length));
        match map.dir {
            Direction::Shear => 0.25 * secant,
            _ => secant,
        }
    }

    /// Bootstrap fits of one direction from several starts on the homogeneous strip over the
    /// stage's curves, side by side (independent fits; the first start with the least mean
    /// relative error wins, as one after another): (p, mean relative error, shape error).
    fn best(
        &mut self,
        law: &Orthotropic,
        map: StageMap,
        curves: &[usize],
        starts: Vec<Vec<f64>>,
    ) -> Option<(Vec<f64>, f64, f64)> {
        let (prep, tau) = (&self.ctx.prep, self.tau);
        let fits: Vec<_> = starts
            .into_par_iter()
            .map(|p0| homogeneous_fit(prep, law, tau, map, curves, p0, None))
            .collect();
        let mut best: Option<(Vec<f64>, f64, f64)> = None;
        for fit in fits.into_iter().flatten() {
            self.stats.record(Work::bootstrap(fit.evaluations));
            if best.as_ref().is_none_or(|b| fit.error < b.1) {
                best = Some((fit.p, fit.error, fit.shape));
            }
        }
        best
    }

    /// Degree choice and initial guess of one direction on the homogeneous strip. Degree
    /// d + 1 starts from degree d's optimum (among other starts), so it never ends worse.
    /// Returns the chosen degree's variables and every degree's fit (index d − 1).
    fn direction(
        &mut self,
        law: &Orthotropic,
        map: StageMap,
        curves: &[usize],
    ) -> (Vec<f64>, Vec<Vec<f64>>) {
        let starts = first_starts(map, self.secant(map, curves[0]));
        let Some(mut chosen) = self.best(law, map, curves, starts) else {
            return (map.encode(law), Vec::new());
        };
        let mut all = vec![chosen.0.clone()];
        self.journal.log_degree(format!(
            "{}: degree 1, mean relative error {:.3} %, shape error {:.3} % (homogeneous strip)",
            map.dir.name(),
            100.0 * chosen.1,
            100.0 * chosen.2
        ));
        let fixed = self.ctx.opts.fixed_degree;
        for degree in 2..=fixed.unwrap_or(self.ctx.opts.max_degree) {
            if fixed.is_none() && chosen.2 <= self.ctx.opts.degree_good {
                self.journal.degree(format!(
                    "{}: degree {} kept: error below {:.2} %",
                    map.dir.name(),
                    degree - 1,
                    100.0 * self.ctx.opts.degree_good
                ));
                break;
            }
            let starts = raised_starts(map, all.last().expect("degree 1"), degree);
            let Some(candidate) = self.best(law, map, curves, starts) else {
                break;
            };
            if fixed.is_none() {
                let mut raised = law.clone();
                map.decode(&candidate.0, &mut raised);
                let why = plausible::implausible(&raised, map, None);
                if let Some(why) = why {
                    self.journal.log_degree(format!(
                        "{}: degree {} kept: degree {degree} {why} (homogeneous strip)",
                        map.dir.name(),
                        degree - 1
                    ));
                    break;
                }
            }
            self.journal.log_degree(format!(
                "{}: degree {degree}, mean relative error {:.3} %, shape error {:.3} % (homogeneous strip)",
                map.dir.name(),
                100.0 * candidate.1,
                100.0 * candidate.2
            ));
            all.push(candidate.0.clone());
            let gains = fixed.is_some() || candidate.2 <= self.ctx.opts.degree_gain * chosen.2;
            if gains && fixed.is_none() && yarn_law_falls(law, map, &candidate.0) {
                self.journal.log_degree(format!(
                    "{}: degree {} kept: degree {degree} has a negative weight on its stiffest term, so its stress falls just past the tested strain (homogeneous strip)",
                    map.dir.name(),
                    degree - 1
                ));
                break;
            }
            if gains {
                chosen = candidate;
            } else {
                self.journal.degree(format!(
                    "{}: degree {} kept: degree {degree} lowers the shape error by less than {:.0} %",
                    map.dir.name(),
                    degree - 1,
                    100.0 * (1.0 - self.ctx.opts.degree_gain)
                ));
                break;
            }
        }
        (chosen.0, all)
    }
}

/// Starts of degree 1: the first curve's secant stiffness `c0` (unless known) at a few bends.
fn first_starts(map: StageMap, c0: f64) -> Vec<Vec<f64>> {
    [1e-3, 1.0, 5.0]
        .iter()
        .map(|&beta| {
            if map.c_known {
                vec![beta_to_var(beta)]
            } else {
                vec![c0.ln(), beta_to_var(beta)]
            }
        })
        .collect()
}

/// Starts of degree `degree` from degree d's variables `prev`: the new term at a few bends
/// and weights.
fn raised_starts(map: StageMap, prev: &[f64], degree: usize) -> Vec<Vec<f64>> {
    let mut starts = Vec::new();
    for mu_new in [0.0, 0.3, -0.3, 0.7] {
        for beta_new in [0.5, 2.0, 4.0, 5.5] {
            let mut p = map.raise(prev, beta_new);
            let o = usize::from(!map.c_known);
            p[o + degree - 2] = mu_new;
            starts.push(p);
        }
    }
    starts
}

/// Whether the yarn law of `map` at the bootstrap's variables p falls eventually
/// ([`plausible::falls_eventually`]): its stress then falls a little past the
/// tested strain, where the shell's strips reach at the jaws' corners, and their solves
/// fail. The shear's degree is chosen again on the shell ([`crate::fit::degrees`]), where such
/// a raise that fails to solve keeps the lower degree.
fn yarn_law_falls(law: &Orthotropic, map: StageMap, p: &[f64]) -> bool {
    let mut law = law.clone();
    map.decode(p, &mut law);
    map.dir != Direction::Shear && plausible::falls_eventually(map.eta(&law))
}
