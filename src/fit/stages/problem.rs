//! A tensile stage's problem on the shell model: its strips' rigs solved at the stage's
//! variables, residuals and Jacobians gathered curve by curve, every evaluation remembered;
//! and the steps of the stage that act on it (the space-mapped start, the screen of a trial,
//! the fit with its stiffness-alone first step, the drop of negligible terms).

use crate::fit::map::StageMap;
use crate::fit::optim::{minimize, Evaluation, Method, OptimOptions, OptimReport};
use crate::fit::preprocess::Prepared;
use crate::fit::rigs::curve_residuals;
use crate::fit::surrogate::{mapped_start, MappedStart};
use crate::fit::uncertainty::Seen;
use crate::fit::{to_evaluation, RigKey, TRIAL_RETRY_ITERATIONS};
use crate::material::Orthotropic;
use crate::scene::{SceneError, StripRig};
use rayon::prelude::*;

/// Work counted over a stage's evaluations.
#[derive(Default)]
pub(in crate::fit) struct Counts {
    pub evals: usize,
    pub newton: usize,
    pub unstable: usize,
    pub solved: usize,
}

impl Counts {
    /// The solver work these counts record.
    pub fn work(&self) -> super::Work {
        super::Work {
            evaluations: self.evals,
            equilibria: self.solved,
            newton_iterations: self.newton,
            unstable: self.unstable,
            bootstrap_evaluations: 0,
        }
    }
}

/// A tensile stage's strips on one mesh level, solved at the variables q over the law `base`
/// (the map's variables decoded into it) and the thickness `tau`.
pub(in crate::fit) struct StageProblem<'a> {
    pub map: StageMap,
    pub level: (usize, usize),
    pub base: Orthotropic,
    pub tau: f64,
    pub strips: &'a [usize],
    /// the fitted curves of each strip, their number and their point counts (in order)
    pub curves: Vec<Vec<usize>>,
    pub ncurves: usize,
    pub lens: Vec<usize>,
    pub rigs: Vec<(RigKey, StripRig)>,
    pub counts: Counts,
    /// every evaluation's variables and residuals, for the shape error at the optimum
    pub seen: Seen,
}

impl StageProblem<'_> {
    /// Residuals (and the Jacobian with `jac`) at q; `prep` holds the strips and curves.
    pub fn eval(
        &mut self,
        prep: &Prepared,
        q: &[f64],
        jac: bool,
    ) -> Result<Evaluation, SceneError> {
        // a point already solved (the start, evaluated for the mapped steps and then by the
        // minimiser) is not solved again
        if let Some((_, r, j)) = self
            .seen
            .iter()
            .rev()
            .find(|(x, _, j)| x == q && (j.is_some() || !jac))
        {
            return Ok(Evaluation {
                residuals: r.clone(),
                jacobian: if jac { j.clone() } else { None },
            });
        }
        let (map, tau) = (self.map, self.tau);
        let mut law = self.base.clone();
        map.decode(q, &mut law);
        let (mut r, mut j) = (Vec::new(), Vec::new());
        // the strips are independent: solved side by side, residuals gathered in order
        let retry = (self.counts.evals > 0).then_some(TRIAL_RETRY_ITERATIONS);
        let runs: Vec<Result<Vec<crate::scene::TensilePoint>, SceneError>> = self
            .rigs
            .par_iter_mut()
            .map(|(_, rig)| {
                rig.set_material(&law, tau)?;
                // the stage's first evaluation must succeed; later ones are trials
                rig.retry_iterations = retry;
                let pts = rig.run(jac);
                rig.retry_iterations = None;
                pts
            })
            .collect();
        for ((pts, &s), cs) in runs.into_iter().zip(self.strips).zip(&self.curves) {
            let pts = pts.map_err(|e| match e {
                SceneError::Solve { stage, source } => SceneError::Solve {
                    stage: format!("the {}° strip's {stage}", prep.strips[s].angle_deg),
                    source,
                },
                other => other,
            })?;
            self.counts.newton += pts.iter().map(|p| p.report.iterations).sum::<usize>();
            self.counts.solved += pts.len();
            self.counts.unstable += pts.iter().filter(|p| !p.report.stable).count();
            let forces: Vec<f64> = pts.iter().map(crate::fit::rigs::node_force).collect();
            let d: Vec<Vec<f64>> = if jac {
                pts.iter().map(|p| map.chain(q, &law, &p.dforce)).collect()
            } else {
                Vec::new()
            };
            for &c in cs {
                let nodes = &prep.strips[s].nodes;
                let dp = jac.then_some(&d[..]);
                curve_residuals(
                    prep.misfit,
                    &prep.curves[c].points,
                    nodes,
                    &forces,
                    dp,
                    &mut r,
                    &mut j,
                );
            }
        }
        self.counts.evals += 1;
        let e = to_evaluation(r, j, q.len(), jac);
        self.seen
            .push((q.to_vec(), e.residuals.clone(), e.jacobian.clone()));
        Ok(e)
    }
}

/// The stage's start from p: its first evaluation there, with sensitivities (the strips'
/// parameter tangents then predict the first trial's equilibria, and the minimiser's first
/// evaluation is this one), then `rounds(gain)` space-mapped steps from the homogeneous strip
/// ([`mapped_start`]), `gain` being the Gauss–Newton gain predicted at p where `predict`
/// (1 elsewhere). Returns the mapped start and its rounds.
pub(in crate::fit) fn stage_start(
    sp: &mut StageProblem,
    prep: &Prepared,
    p: &mut Vec<f64>,
    predict: bool,
    rounds: impl Fn(f64) -> usize,
) -> Result<(MappedStart, usize), SceneError> {
    let e0 = sp.eval(prep, p, true)?;
    let gn_gain = match &e0.jacobian {
        Some(j) if predict => crate::fit::optim::gauss_newton_gain(j, &e0.residuals),
        _ => 1.0,
    };
    let r0 = e0.residuals;
    let flat: Vec<usize> = sp.curves.iter().flatten().copied().collect();
    let rounds = rounds(gn_gain);
    let (base, tau, map) = (sp.base.clone(), sp.tau, sp.map);
    let mut shell = |q: &[f64]| sp.eval(prep, q, false).ok().map(|e| e.residuals);
    let m = mapped_start(prep, &base, tau, map, &flat, p, r0, rounds, &mut shell);
    Ok((m, rounds))
}

/// A trial screened at its mapped start p: the shape error and rms error there when the trial
/// is given up (the shape error has risen above `shape0` and the rms error, from the mapped
/// objective `after`, has not fallen by `degree_gain` below `rms0`).
pub(in crate::fit) fn screen_trial(
    sp: &mut StageProblem,
    prep: &Prepared,
    p: &[f64],
    after: f64,
    (shape0, rms0): (f64, f64),
    degree_gain: f64,
) -> Result<Option<(f64, f64)>, SceneError> {
    let r = sp.eval(prep, p, false)?.residuals;
    let lens = &sp.lens;
    let shape = crate::fit::shape_error(
        lens,
        &crate::fit::surrogate::unweight(&r, lens, prep.misfit),
    );
    let rms = (after / sp.ncurves.max(1) as f64).sqrt();
    let out = shape > shape0 && rms > degree_gain * rms0;
    Ok(out.then_some((shape, rms)))
}

/// The stage's fit from its start p: with `stiffness_first`, the stiffness c alone first
/// (and only, with `stiffness_only`), then every variable; a term of η too small to matter
/// is dropped at the optimum. Returns the minimiser's report and the terms dropped.
pub(in crate::fit) fn fit_stage(
    sp: &mut StageProblem,
    prep: &Prepared,
    p: &mut Vec<f64>,
    opts: &OptimOptions,
    stiffness_first: bool,
    stiffness_only: bool,
) -> Result<(OptimReport, usize), SceneError> {
    let mut stiffness_rep = None;
    if stiffness_first {
        let rep = fit_stiffness(sp, prep, p, opts)?;
        if stiffness_only {
            stiffness_rep = Some(rep);
        }
    }
    let mut rep = match stiffness_rep {
        Some(rep) => rep,
        None => minimize(p, opts, |q: &[f64], jac: bool| sp.eval(prep, q, jac))?,
    };
    // a term too small to matter is dropped, and the optimum re-evaluated without it
    let dropped = drop_negligible_terms(sp, prep, p, &mut rep)?;
    Ok((rep, dropped))
}

/// Fits the stiffness c (p[0]) alone, the rest of p held: the homogeneous strip misjudges
/// clamped strips' stiffness (most at 45°, where the jaws stop the strip from shearing
/// freely).
fn fit_stiffness(
    sp: &mut StageProblem,
    prep: &Prepared,
    p: &mut [f64],
    opts: &OptimOptions,
) -> Result<OptimReport, SceneError> {
    let rest = p[1..].to_vec();
    let mut scale = vec![p[0]];
    let one = OptimOptions {
        method: Method::GaussNewton,
        max_iterations: 10,
        rel_decrease: 1e-2,
        ..*opts
    };
    let rep = minimize(&mut scale, &one, |q: &[f64], jac: bool| {
        let mut full = vec![q[0]];
        full.extend(&rest);
        let e = sp.eval(prep, &full, jac)?;
        Ok::<_, SceneError>(Evaluation {
            residuals: e.residuals,
            jacobian: e.jacobian.map(|j| j.columns(0, 1).into_owned()),
        })
    })?;
    p[0] = scale[0];
    Ok(rep)
}

/// Drops the terms of η at p too small to matter and re-evaluates the optimum without them
/// (p and the report's objective updated); returns how many were dropped.
fn drop_negligible_terms(
    sp: &mut StageProblem,
    prep: &Prepared,
    p: &mut Vec<f64>,
    rep: &mut OptimReport,
) -> Result<usize, SceneError> {
    let map = sp.map;
    let mut law = sp.base.clone();
    map.decode(p, &mut law);
    let mut eta = map.eta(&law).clone();
    let dropped = crate::fit::plausible::drop_negligible(&mut eta, map.xhat);
    if dropped > 0 {
        *map.eta_mut(&mut law) = eta;
        *p = map.encode(&law);
        let e = sp.eval(prep, p, true)?;
        rep.objective = e.objective();
    }
    Ok(dropped)
}
