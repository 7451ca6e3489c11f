//! The fit as its list of stages (Clyde et al. 2017 §5, extended): set-up, the homogeneous
//! bootstrap, the multiresolution ladder of shell stages, the shear from captured shapes, each
//! test's own mesh, the mesh check, and validation. Each stage is a function with its inputs
//! and outputs in its signature: it is given the material it starts from and returns its
//! optimum, which this module and the ladder apply to the [`Fitter`]'s material (`Fitted`);
//! it solves in the lab and writes notes, timings and progress to the record it is lent
//! ([`super::Bench`]).

use super::journal::Journal;
use super::map::{A12Rule, Direction, StageMap};
use super::measures::{self, Misfit, Objective};
use super::mesh_check::{MeshCheck, MeshCheckMode};
use super::refine::TestMeshes;
use super::{
    bending, coupling, is_determined, joint, ladder, poisson, preprocess, refine, rigs, stages,
    thickness, uncertainty, validation, Context, FitError, FitOptions, FitResult, FitStats, Fitted,
    Fitter,
};
use crate::dataset::{FabricDataset, Role};
use crate::material::{Cutoffs, Eta, Orthotropic};
use joint::StageSets;
use std::time::Instant;

/// Fits a dataset; progress lines go to `progress`.
pub fn fit(
    data: &FabricDataset,
    opts: &FitOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<FitResult, FitError> {
    check_options(opts)?;
    let start = Instant::now();
    let setup = set_up(data, opts)?;
    let mut f = Fitter::new(data, opts, progress, start, setup);
    let strips = fitted_strips(&f);
    let mut maps = stage_maps(&f, &strips);
    require_yarn_data(&f, &strips)?;
    let (law, shear_candidates) = stages::bootstrap_all(
        &f.ctx,
        &mut f.journal,
        &mut f.stats,
        &f.fitted,
        &maps,
        &strips,
    );
    f.fitted.law = law;
    if let Some(note) = f.lab.decide_yarns(opts, &f.fitted.law) {
        f.journal.note(note);
    }
    let mut sets = joint::stage_sets(opts, strips.clone(), &maps);
    let meshes = ladder::ladder(&mut f, &mut maps, &mut sets, &shear_candidates)?;
    if sets.joint.is_some() {
        f.journal.note(
            "joint sweep (--joint): the warp and weft stiffnesses refitted over the off-axis strips too, then the shear, on every mesh".into(),
        );
    }
    let last = *meshes.last().expect("one level at least");
    let shapes_fitted = shapes_then_bends(&mut f, &strips, last)?;
    let own_meshes = opts.test_meshes != TestMeshes::Ladder;
    if own_meshes && refine::refine_tests(&mut f, &maps, &mut sets, last)? {
        // the ladder's solved check is of the meshes ahead of the per-test refinement
        f.evidence.ladder_check = None;
    }
    let (uncertainty, mesh_check) = checked_meshes(&mut f, &maps, &mut sets, last)?;
    let t0 = Instant::now();
    let (mut bench, fitted) = f.bench();
    let tests = validation::outcomes(&mut bench, fitted, last)?;
    let (mut bench, fitted) = f.bench();
    let a12_dependence = poisson::a12_dependence(&mut bench, fitted, &strips, last)?;
    let identifiability =
        validation::identifiability(&f.ctx, &f.fitted, &strips, &uncertainty, &a12_dependence);
    if let Some(m) = &mesh_check {
        let (mut bench, fitted) = f.bench();
        bench.mesh_check_notes(fitted, last, m);
    }
    f.stats.time_stage("report", t0);
    closing_notes(&mut f);
    f.stats.seconds = f.journal.elapsed();
    let material = f.fitted.material(f.ctx.data);
    let yarn_rule = f.lab.yarns();
    let (notes, degree_log) = f.journal.finish();
    Ok(FitResult {
        material,
        method: format!("{:?}", opts.method).to_lowercase(),
        meshes,
        stats: f.stats,
        degree_log,
        notes,
        identifiability,
        a12_dependence,
        uncertainty,
        tests,
        max_error: opts.max_error,
        mesh_check,
        shapes_fitted,
        yarn_rule,
        shear_coupling: f.fitted.coupling,
        objective: f.ctx.prep.misfit,
        joint: sets.joint.is_some(),
        test_meshes: opts.test_meshes,
    })
}

/// Options no fit can run with.
fn check_options(opts: &FitOptions) -> Result<(), FitError> {
    if opts.ladder.is_empty() {
        return Err(FitError::Data("the mesh ladder is empty".into()));
    }
    if opts.max_degree == 0 {
        return Err(FitError::Data("--max-degree must be at least 1".into()));
    }
    Ok(())
}

/// What the fit starts from: the prepared curves and strips, the notes so far, the a12 rule
/// and whether the bends fit rigidities of their own.
pub(super) struct SetUp {
    pub prep: preprocess::Prepared,
    pub notes: Vec<String>,
    pub a12: A12Rule,
    pub own_bending: bool,
}

/// Prepares the curves (toe, repeats, roles, nodes), decides the misfit, the a12 rule and the
/// bending mode, and refuses bend tests without an areal density.
fn set_up(data: &FabricDataset, opts: &FitOptions) -> Result<SetUp, FitError> {
    let mut prep = preprocess::prepare(
        data,
        opts.paper_protocol,
        opts.repeats,
        opts.toe,
        opts.nodes,
    )?;
    prep.misfit = measures::decide(opts.objective, &prep);
    let mut notes = data.notes.clone();
    notes.extend(prep.notes.iter().cloned());
    if opts.objective == Objective::Auto && prep.misfit == Misfit::Log {
        notes.push(
            "objective: ln(F̂/F) per point (--objective auto: repeats are fitted together, and the relative error would weight the weakest repeat most; see --objective)".into(),
        );
    }
    let known = &data.known;
    let a12 = match (known.a12, known.poisson_12) {
        (Some(v), _) => A12Rule::Fixed(v),
        (None, Some(nu)) => A12Rule::Poisson(nu),
        _ => A12Rule::HalfMin,
    };
    let own_bending = bending::use_own_bending(opts.bending, &data.bend)?;
    if own_bending {
        notes.push(
            "bending of its own (--bending orthotropic): the bends fit the warp and weft flexural rigidities; the thickness only splits the strips' a·τ".into(),
        );
    }
    if data.bend.is_empty() && known.thickness.is_none() {
        notes.push(format!(
            "thickness not fitted (no bend tests): kept at the measured {:.3} mm",
            data.thickness * 1e3
        ));
    } else if !data.bend.is_empty() && data.areal_density.is_none() {
        return Err(FitError::Data(
            "bend tests need the areal density (areal_density_g_m2)".into(),
        ));
    }
    Ok(SetUp {
        prep,
        notes,
        a12,
        own_bending,
    })
}

impl<'a> Fitter<'a> {
    /// A fitter at the start: a linear law at the known values (or generic ones), the
    /// measured thickness, no stage run.
    fn new(
        data: &'a FabricDataset,
        opts: &'a FitOptions,
        progress: &'a mut dyn FnMut(&str),
        start: Instant,
        setup: SetUp,
    ) -> Self {
        let known = &data.known;
        let lab = rigs::Lab::new(setup.prep.strips.len());
        Fitter {
            lab,
            ctx: Context {
                data,
                opts,
                a12: setup.a12,
                prep: setup.prep,
                own_bending: setup.own_bending,
            },
            journal: Journal::new(progress, start, setup.notes),
            stats: FitStats::default(),
            fitted: Fitted {
                law: Orthotropic {
                    a11: known.a11.unwrap_or(1.0e8),
                    a22: known.a22.unwrap_or(1.0e8),
                    a12: 0.5e8,
                    g12: known.g12.unwrap_or(2.0e6),
                    warp: Eta::linear(),
                    weft: Eta::linear(),
                    shear: Eta::linear(),
                    cutoffs: Cutoffs::none(),
                    coupling: None,
                },
                thickness: known.thickness.unwrap_or(data.thickness),
                bending: None,
                coupling: coupling::CouplingOutcome::Off,
            },
            evidence: Default::default(),
        }
    }
}

/// The three stages' directions, in the order they run.
const DIRECTIONS: [Direction; 3] = [Direction::Warp, Direction::Weft, Direction::Shear];

/// The fitted strips of the warp, weft and shear stages.
fn fitted_strips(f: &Fitter) -> Vec<Vec<usize>> {
    DIRECTIONS.iter().map(|&d| f.ctx.stage_strips(d)).collect()
}

/// Each stage's variables over the law (see [`StageMap`]).
fn stage_maps(f: &Fitter, strips: &[Vec<usize>]) -> Vec<StageMap> {
    let known = &f.ctx.data.known;
    DIRECTIONS
        .iter()
        .zip(strips)
        .map(|(&dir, s)| StageMap {
            dir,
            xhat: f.ctx.xhat(dir, s),
            c_known: match dir {
                Direction::Warp => known.a11.is_some(),
                Direction::Weft => known.a22.is_some(),
                Direction::Shear => known.g12.is_some(),
            },
            a12: f.ctx.a12,
            coupling: false,
        })
        .collect()
}

/// Refuses a dataset with nothing to fit the yarn stiffness to.
fn require_yarn_data(f: &Fitter, strips: &[Vec<usize>]) -> Result<(), FitError> {
    let known = &f.ctx.data.known;
    let has_fit_tests = f.ctx.prep.curves.iter().any(|c| c.role == Role::Fit);
    if strips[0].is_empty() && strips[1].is_empty() && known.a11.is_none() && known.a22.is_none() {
        return Err(FitError::Data(if has_fit_tests {
            "no fitted warp (90°) or weft (0°) tensile test and no [known] a11_pa or a22_pa: nothing to fit the yarn stiffness to (a bias-only dataset needs the yarn stiffnesses in [known])".into()
        } else {
            "no fitted tensile test: nothing to fit (every test has role = \"validation\"?)".into()
        }));
    }
    Ok(())
}

/// Captured shapes fit the shear where no off-axis strip did; the bends' assumed twist follows
/// the new shear, so the bending (or thickness) stage runs again. Whether shapes fitted G12.
fn shapes_then_bends(
    f: &mut Fitter,
    strips: &[Vec<usize>],
    last: (usize, usize),
) -> Result<bool, FitError> {
    let data = f.ctx.data;
    let known = &data.known;
    let g12 = if strips[2].is_empty() && known.g12.is_none() {
        super::shapes::shapes_stage(&f.ctx, &mut f.journal, &mut f.stats, &f.fitted)?
    } else {
        None
    };
    let Some(g12) = g12 else { return Ok(false) };
    f.fitted.law.g12 = g12;
    bend_stage(f, last)?;
    Ok(true)
}

/// The bend stage on a mesh level, where the bends fit anything: the bends' own rigidities
/// (`--bending`), or the thickness unless it is known. Its optimum becomes the fitted
/// material and its evidence the fit's. Where the cantilevers do not solve with the law the
/// strips fitted (a law no cantilever holds), the bending stays as it was, the bends are
/// reported unsolved (their drape angles not a number, so the verdict counts them over any
/// limit) and a warning says why: the fit ends with its material and an honest verdict.
pub(super) fn bend_stage(f: &mut Fitter, level: (usize, usize)) -> Result<(), FitError> {
    let t0 = Instant::now();
    let data = f.ctx.data;
    let (ctx, lab, stats, m) = (&f.ctx, &mut f.lab, &mut f.stats, &f.fitted);
    let run = if ctx.own_bending {
        bending::bending_stage(ctx, lab, stats, m, level)
    } else if !data.bend.is_empty() && data.known.thickness.is_none() {
        thickness::thickness_stage(ctx, lab, stats, m, level)
    } else {
        return Ok(());
    };
    let fit = match run {
        Ok(fit) => fit,
        Err(e) if e.is_solve_failure() => {
            unsolved_bends(f, &e);
            let stage = if f.ctx.own_bending {
                "bending"
            } else {
                "thickness"
            };
            f.stats.time_stage(stage, t0);
            return Ok(());
        }
        Err(e) => return Err(e),
    };
    f.journal.drop_notes(UNSOLVED_BENDS);
    f.evidence.linearised.extend(fit.linearised);
    f.evidence.stage_errors = fit.errors;
    f.evidence.bend_angles = fit.angles;
    f.fitted.law = fit.law;
    f.fitted.thickness = fit.thickness;
    f.fitted.bending = fit.bending;
    f.journal.say(&fit.line);
    f.stats.time_stage(fit.stage, t0);
    Ok(())
}

/// How the warning about bends left unsolved begins (one such note at most, and none once a
/// later bend stage solves).
const UNSOLVED_BENDS: &str = "warning: the bends are not fitted";

/// The bends left unsolved by a bend stage that failed with `e`: their drape angles not a
/// number, the bend stage's evidence dropped (the mesh check then leaves the bends out), a
/// warning.
fn unsolved_bends(f: &mut Fitter, e: &FitError) {
    f.evidence.bend_angles = vec![f64::NAN; f.ctx.data.bend.len()];
    f.evidence.stage_errors.clear();
    f.evidence
        .linearised
        .retain(|l| !matches!(l.probe, super::mesh_check::Probe::Bends));
    let note = format!(
        "{UNSOLVED_BENDS} ({e}): the cantilevers do not solve with the law the strips fitted; the bending and thickness stay as they were and the bends are reported unsolved"
    );
    f.journal.say(&note);
    f.journal.drop_notes(UNSOLVED_BENDS);
    f.journal.note(note);
}

/// The final standard errors and the mesh check; a check that fails refines the strips of the
/// stages it would move, and the fit is checked again (with `--test-meshes` other than ladder).
fn checked_meshes(
    f: &mut Fitter,
    maps: &[StageMap],
    sets: &mut StageSets,
    last: (usize, usize),
) -> Result<(Vec<uncertainty::ParamError>, Option<MeshCheck>), FitError> {
    let opts = f.ctx.opts;
    let own_meshes = opts.test_meshes != TestMeshes::Ladder;
    let strict = opts.test_meshes == TestMeshes::Strict;
    let t0 = Instant::now();
    let mut uncertainty = f.evidence.final_uncertainty(&f.fitted.law);
    if opts.mesh_check == MeshCheckMode::Off {
        return Ok((uncertainty, None));
    }
    let mut check = match f.evidence.ladder_check.take() {
        Some(m) => Some(m),
        None => {
            let (mut bench, m) = f.bench();
            bench.mesh_check(m, last, opts.mesh_check, &|n| {
                is_determined(&uncertainty, n)
            })?
        }
    };
    f.stats.time_stage("mesh check", t0);
    while let Some(m) = check.as_ref().filter(|m| own_meshes && !m.passes()) {
        if !refine::refine_for_check(f, maps, sets, last, m, strict)? {
            break;
        }
        let t0 = Instant::now();
        uncertainty = f.evidence.final_uncertainty(&f.fitted.law);
        let (mut bench, m) = f.bench();
        check = bench.mesh_check(m, last, opts.mesh_check, &|n| {
            is_determined(&uncertainty, n)
        })?;
        f.stats.time_stage("mesh check", t0);
    }
    Ok((uncertainty, check))
}

/// The notes that close a fit (unstable equilibria left out of the objective).
fn closing_notes(f: &mut Fitter) {
    let t0 = Instant::now();
    if f.stats.unstable_solves > 0 {
        let n = f.stats.unstable_solves;
        f.journal.note(format!(
            "{n} strip equilibria of the tensile stages ended unstable (a saddle: the strip would wrinkle there); the measured points interpolated from them were excluded from the stage's objective (the curves' excluded_points count those of the final predictions)"
        ));
    }
    f.stats.time_stage("report", t0);
}

#[cfg(test)]
mod tests {
    use super::FitError;
    use crate::scene::SceneError;
    use crate::solve::SolveError;

    #[test]
    fn only_an_equilibrium_that_did_not_solve_is_a_solve_failure() {
        let solve = || SceneError::Solve {
            stage: "load factor 0.5900".into(),
            source: SolveError::NotConverged {
                iterations: 30,
                residual: 0.1,
                factorizations: 30,
            },
        };
        let scene = |source| FitError::Scene {
            stage: "bending stage on 16×24".into(),
            source,
        };
        assert!(scene(solve()).is_solve_failure());
        let stage = FitError::Stage {
            stage: "bias stage".into(),
            source: solve(),
            hint: String::new(),
        };
        assert!(stage.is_solve_failure());
        // a limit or bad input is not one: the fit must stop and say so
        assert!(
            !scene(SceneError::Input("mesh 9000x9000: too many faces".into())).is_solve_failure()
        );
        assert!(!FitError::Data("no fitted tensile test".into()).is_solve_failure());
    }
}
