//! The stages of the fit (paper §5): the homogeneous bootstrap with the degree choice and the
//! tensile stages on the shell model (the thickness stage is in `thickness.rs`, the ladder of
//! meshes in `ladder.rs`).

mod homogeneous;
mod problem;

pub(super) use homogeneous::bootstrap_all;

use super::map::StageMap;
use super::optim::OptimReport;
use super::surrogate::MappedStart;
use super::uncertainty::Seen;
use super::{Bench, FitError, Fitted, RigKey, StrainRange, Work};
use crate::material::Orthotropic;
use crate::scene::{SceneError, StripRig};
use problem::{fit_stage, screen_trial, stage_start, Counts, StageProblem};
use std::time::Instant;

/// What a tensile stage fits ([`Bench::shell_stage`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum StageMode {
    /// every variable of the stage's map
    Full,
    /// every variable, a trial screened at its space-mapped start: given up there unless the
    /// shape error has not risen above `shape` or the rms error already fell by the degree
    /// gain from `rms` (the coupling's trial, see [`super::coupling`])
    Screened { shape: f64, rms: f64 },
    /// every variable, a degree just raised: given up when its space-mapped start finds no
    /// better law
    Raise,
    /// every variable, a degree just raised, fitted whatever its space-mapped start finds
    /// (`--degree`: giving the raise up could leave the shear at degree 1 under
    /// `--degree 2`)
    RaiseAlways,
    /// every variable, a degree just raised, fitted by the shell's own iterations without
    /// the space-mapped start (the second start of a raise, see [`super::degrees`])
    RaiseDirect,
    /// the stiffness c alone, η's shape held (the joint sweep's yarn stages, see
    /// [`super::Joint`]); a known stiffness leaves nothing to fit
    Stiffness,
}

/// A tensile stage fitted: the law at its optimum, its shape error, its rms relative error
/// and, when asked, the strains its strips exercise there.
#[derive(Clone, Debug)]
pub(super) struct StageFit {
    pub law: Orthotropic,
    pub shape: f64,
    pub rms: f64,
    pub range: Option<StrainRange>,
}

/// How a tensile stage's run ends ([`Bench::shell_stage`]).
#[derive(Clone, Debug)]
pub(super) enum StageRun {
    Fitted(Box<StageFit>),
    /// a trial given up at its space-mapped start; a screened trial's shape and rms errors
    /// there when the screen gave it up
    GivenUp(Option<(f64, f64)>),
}

impl StageRun {
    /// The fit, `None` for a trial given up.
    pub(super) fn fitted(self) -> Option<StageFit> {
        match self {
            StageRun::Fitted(fit) => Some(*fit),
            StageRun::GivenUp(_) => None,
        }
    }
}

impl Bench<'_, '_> {
    /// One tensile stage on the shell model at one mesh level, over the stage's strips, from
    /// material `m` alone (`shell_stage` falls back from it, see [`super::fallback`]);
    /// returns the law and the shape error at the optimum ([`super::shape_error`]) and, when asked, the
    /// strain range the strips exercise there. On the first level the stage starts with
    /// space-mapped steps on the homogeneous strip ([`super::surrogate`]); a `raise`d degree
    /// whose mapped steps find no better law is given up (`None`): a bet that the shell's own
    /// iterations from a zero-weight term would not buy the degree gain either (on noise-free
    /// cotton they gain nothing in one iteration and 10 s; on the bundled fabrics, without the
    /// mapped start, degree 2 gains −3 to 23 % of shape error, never the 30 % needed). A finer
    /// level's stage takes the mapped steps only where its own Gauss–Newton step promises them
    /// work (below).
    pub(super) fn shell_stage_once(
        &mut self,
        m: &Fitted,
        map: StageMap,
        strips: &[usize],
        level: (usize, usize),
        strain_range: bool,
        mode: StageMode,
    ) -> Result<StageRun, FitError> {
        let stiffness_only = mode == StageMode::Stiffness && !map.c_known;
        let t0 = Instant::now();
        let mut sp = self.stage_problem(m, map, strips, level)?;
        let mut p = self.unsaturated_start(&m.law, map);
        let first_level = level == self.ctx.opts.ladder[0];
        let opts = self.ctx.stage_options(level, 1e-12, sp.ncurves);
        if let Some(given_up) = self.mapped_stage_start(&mut sp, &mut p, mode, opts.rel_decrease)? {
            self.stats.time_stage(map.dir.name(), t0);
            return Ok(given_up);
        }
        let stiffness_first = (first_level || stiffness_only) && !map.c_known;
        let (rep, dropped) = fit_stage(
            &mut sp,
            &self.ctx.prep,
            &mut p,
            &opts,
            stiffness_first,
            stiffness_only,
        )
        .map_err(stage_failed(map, level))?;
        self.stats.record(sp.counts.work());
        let mut law = m.law.clone();
        map.decode(&p, &mut law);
        let err = (rep.objective / sp.ncurves.max(1) as f64).sqrt();
        let shape = self.stage_optimum(&sp, &p, err, &law);
        let msg = self.stage_line(&sp, &p, (err, shape), &rep);
        self.journal.say(&msg);
        if dropped > 0 {
            self.journal.log_degree(format!(
                "{}: {dropped} term(s) dropped on {}×{}: under {:.1} % of η' over the tested range",
                map.dir.name(),
                level.0,
                level.1,
                100.0 * super::plausible::NEGLIGIBLE
            ));
        }
        let range = if strain_range {
            self.stage_strain_range(m, &law, map, &mut sp.rigs)?
        } else {
            None
        };
        for (key, rig) in sp.rigs {
            self.lab.keep_rig(key, rig);
        }
        self.stats.time_stage(map.dir.name(), t0);
        Ok(StageRun::Fitted(Box::new(StageFit {
            law,
            shape,
            rms: err,
            range,
        })))
    }

    /// A tensile stage's problem: the rigs of its strips on a mesh level, set up for the
    /// stage's map, with the strips' fitted curves, at material `m`.
    fn stage_problem<'s>(
        &mut self,
        m: &Fitted,
        map: StageMap,
        strips: &'s [usize],
        level: (usize, usize),
    ) -> Result<StageProblem<'s>, FitError> {
        let mut rigs = Vec::new();
        for &s in strips {
            let angle = self.ctx.prep.strips[s].angle_deg;
            let (key, mut rig) = self.lab.strip_rig(self.ctx, m, s, angle, level)?;
            rig.set_wanted(Some(map.wanted(&m.law)));
            rig.set_bending(m.bending);
            rigs.push((key, rig));
        }
        let curves: Vec<Vec<usize>> = strips.iter().map(|&s| self.ctx.used_curves(&[s])).collect();
        let ncurves: usize = curves.iter().map(Vec::len).sum();
        let lens: Vec<usize> = curves
            .iter()
            .flatten()
            .map(|&c| self.ctx.prep.curves[c].points.len())
            .collect();
        Ok(StageProblem {
            map,
            level,
            base: m.law.clone(),
            tau: m.thickness,
            strips,
            curves,
            ncurves,
            lens,
            rigs,
            counts: Counts::default(),
            seen: Seen::new(),
        })
    }

    /// The stage's first evaluation and space-mapped start from p (see [`stage_start`]);
    /// the run's end when the trial is given up there (a raised degree whose mapped steps kept
    /// no proposal, or a `screen`ed trial that gained too little), its work counted, its rigs
    /// kept and its note logged; `None` when the stage goes on.
    fn mapped_stage_start(
        &mut self,
        sp: &mut StageProblem,
        p: &mut Vec<f64>,
        mode: StageMode,
        rel_decrease: f64,
    ) -> Result<Option<StageRun>, FitError> {
        let (map, level) = (sp.map, sp.level);
        let fail = stage_failed(map, level);
        let first_level = level == self.ctx.opts.ladder[0];
        let stiffness_only = mode == StageMode::Stiffness && !map.c_known;
        // the stiffness alone needs no start from the homogeneous strip (it is one variable),
        // nor does a finer level's stage whose own Gauss–Newton step, from the Jacobian just
        // solved, is predicted to gain less than the stage asks of an iteration: it starts at
        // the coarser level's optimum, and there the mapped proposals of the bundled default
        // fits are all rejected (predicted gains 0.03–1.8 %; README, "Stages on the shell
        // model"), each a shell evaluation thrown away
        let direct = mode == StageMode::RaiseDirect;
        let rounds = |gn_gain: f64| {
            if direct || stiffness_only || (!first_level && gn_gain < rel_decrease) {
                0
            } else {
                8
            }
        };
        let predict = !first_level && !stiffness_only;
        let (m, rounds) = stage_start(sp, &self.ctx.prep, p, predict, rounds).map_err(fail)?;
        self.stats
            .record(Work::bootstrap(m.homogeneous_evaluations));
        let note = mapped_note(map, p, level, &m);
        // a trial screened at its mapped start: given up unless the shape error has not
        // risen or the rms error already fell by the degree gain there
        let screened = match mode {
            StageMode::Screened { shape, rms } => {
                let gain = self.ctx.opts.degree_gain;
                let s = (shape, rms);
                screen_trial(sp, &self.ctx.prep, p, m.after, s, gain).map_err(fail)?
            }
            _ => None,
        };
        if (mode == StageMode::Raise && m.kept == 0) || screened.is_some() {
            self.stats.record(sp.counts.work());
            self.journal.log_degree(note);
            for (key, rig) in std::mem::take(&mut sp.rigs) {
                self.lab.keep_rig(key, rig);
            }
            return Ok(Some(StageRun::GivenUp(screened)));
        }
        if rounds > 0 {
            self.journal.degree(note);
        }
        Ok(None)
    }

    /// The stage's start from `law`, the tension–shear coupling moved back from a saturated
    /// bound (and said so).
    fn unsaturated_start(&mut self, law: &Orthotropic, map: StageMap) -> Vec<f64> {
        let p = map.encode_start(law);
        if p != map.encode(law) {
            self.journal.say(&format!(
                "{}: the tension–shear coupling starts at {:.0} % of its bound, which it had reached (tanh is flat there, and the stage could not move it back)",
                map.dir.name(),
                100.0 * super::map::UNSATURATED
            ));
        }
        p
    }

    /// At the stage's optimum p: records the standard errors and the linearisation from the
    /// Jacobian computed there, and returns the shape error (`err`, the rms error, where p has
    /// no evaluation).
    fn stage_optimum(&mut self, sp: &StageProblem, p: &[f64], err: f64, law: &Orthotropic) -> f64 {
        let (map, lens) = (sp.map, &sp.lens[..]);
        let shape = sp
            .seen
            .iter()
            .rev()
            .find(|(q, _, _)| *q == p)
            .map_or(err, |(_, r, _)| {
                super::shape_error(
                    lens,
                    &super::surrogate::unweight(r, lens, self.ctx.prep.misfit),
                )
            });
        // standard errors at the optimum, from the Jacobian computed there
        if let Some((r, j)) = super::uncertainty::at_optimum(&sp.seen, p) {
            let errors = super::uncertainty::stage_errors(&map, p, j, r, lens, law);
            self.evidence
                .uncertainty
                .push((map.dir, p.to_vec(), errors));
            let tau = sp.tau;
            let offaxis = (map.coupling && law.coupling.is_some()).then(|| {
                super::uncertainty::offaxis_rows(&self.ctx.prep, law, tau, &map, p, sp.strips)
            });
            self.evidence
                .linearised
                .push(super::mesh_check::Linearised::tensile(
                    &map, p, law, sp.strips, sp.level, j, lens, offaxis,
                ));
        }
        shape
    }

    /// The stage's progress line at its optimum p: rms and shape errors, work done.
    fn stage_line(
        &self,
        sp: &StageProblem,
        p: &[f64],
        (err, shape): (f64, f64),
        rep: &OptimReport,
    ) -> String {
        let (map, level) = (sp.map, sp.level);
        format!(
            "{} stage ({}, {} curves), degree {}, mesh {}×{}: rms relative error {:.3} % (shape error {:.3} %) after {} iterations, {} evaluations, {} Newton iterations ({})",
            map.dir.name(),
            self.strip_labels(sp.strips, level).join(" "),
            sp.ncurves,
            map.degree(p),
            level.0,
            level.1,
            100.0 * err,
            100.0 * shape,
            rep.iterations,
            rep.evaluations,
            sp.counts.newton,
            rep.stop
        )
    }

    /// Each strip's angle, with its own mesh where it is refined beyond the level.
    fn strip_labels(&self, strips: &[usize], level: (usize, usize)) -> Vec<String> {
        strips
            .iter()
            .map(|&s| {
                let strip = &self.ctx.prep.strips[s];
                if self.lab.meshes.of_strip(s) == 0 {
                    format!("{}°", strip.angle_deg)
                } else {
                    let m = super::rigs::strip_mesh(
                        self.lab.meshes.strip_level(s, level),
                        strip.width,
                        strip.length,
                    );
                    format!("{}° on its own {}x{}", strip.angle_deg, m.0, m.1)
                }
            })
            .collect()
    }

    /// The strains the stage's strips exercise at `law` (with `m`'s thickness and bending).
    fn stage_strain_range(
        &mut self,
        m: &Fitted,
        law: &Orthotropic,
        map: StageMap,
        rigs: &mut [(RigKey, StripRig)],
    ) -> Result<Option<StrainRange>, FitError> {
        let mut range: Option<StrainRange> = None;
        for (_, rig) in rigs {
            super::rigs::run_rig(rig, law, m, self.stats, false).map_err(|source| {
                FitError::Scene {
                    stage: format!("{} strips at the fit", map.dir.name()),
                    source,
                }
            })?;
            if let Some((lo, hi)) = rig.strain_range() {
                let r = range.get_or_insert((lo, hi));
                for i in 0..3 {
                    r.0[i] = r.0[i].min(lo[i]);
                    r.1[i] = r.1[i].max(hi[i]);
                }
            }
        }
        Ok(range)
    }
}

/// The log line of a stage's space-mapped start `m` at p.
fn mapped_note(map: StageMap, p: &[f64], level: (usize, usize), m: &MappedStart) -> String {
    format!(
        "{}: degree {} on {}×{}: space-mapped start, objective {:.3e} -> {:.3e} ({} of {} proposals kept)",
        map.dir.name(),
        map.degree(p),
        level.0,
        level.1,
        m.before,
        m.after,
        m.kept,
        m.shell_solves
    )
}

/// The error of a tensile stage whose solve failed.
fn stage_failed(map: StageMap, level: (usize, usize)) -> impl Fn(SceneError) -> FitError + Copy {
    move |source| FitError::Scene {
        stage: format!("{} stage on {}×{}", map.dir.name(), level.0, level.1),
        source,
    }
}
