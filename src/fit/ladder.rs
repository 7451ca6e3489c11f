//! The ladder of meshes (paper §5, "multiresolution"): the stages fitted coarse to fine, each
//! level started from the last. A level that doubles the last is first solved at the last fit:
//! those forces are the solved defect of the mesh check ([`super::mesh_check`]), whose
//! first-order refit says whether the level is needed at all (no determined parameter moving
//! by 1 %, no curve by 0.3 %) and which stages it would move (the others are not refitted).
//! A finer level at which a stage does not solve (a cantilever that the law fitted there
//! cannot hold, a strip from every fallback start) is not kept: the fit goes on from the last
//! level that solved, with a warning, and the mesh check reports what the finer level moves.

use super::map::StageMap;
use super::mesh_check::MeshCheck;
use super::stages::StageFit;
use super::{FitError, Fitter, StageMode, StageSets};

/// A stage whose determined quantities the last refinement moved by less than this is
/// not refitted on the finer level (a tenth of the mesh check's 1 %).
const STAGE_UNCHANGED: f64 = 1e-3;

/// The shell model, coarse to fine; returns the meshes fitted on. With the joint sweep
/// ([`super::Joint`]) the first level's staged fit is followed by the yarn stiffnesses over
/// their joint strips and the shear stage again; later levels refit each yarn stage's
/// stiffness over its joint strips after the stage itself.
pub(super) fn ladder(
    f: &mut Fitter,
    maps: &mut [StageMap],
    sets: &mut StageSets,
    shear_candidates: &[Vec<f64>],
) -> Result<Vec<(usize, usize)>, FitError> {
    let opts = f.ctx.opts;
    let own = sets.own.clone();
    let strips = &own[..];
    let all: Vec<usize> = strips.iter().flatten().copied().collect();
    let mut meshes = Vec::new();
    let mut previous: Option<Vec<f64>> = None;
    // the refit change solved between the last two levels (parameters and curves)
    let mut last_check: Option<MeshCheck> = None;
    for (li, &level) in opts.ladder.iter().enumerate() {
        let from = meshes.last().copied().unwrap_or(level);
        // is this level worth it? the last solved refit change, carried one level finer
        if let (Some(m), true) = (&last_check, li >= 2) {
            if skipped_by_estimate(f, m, from, level) {
                break;
            }
        }
        f.lab.pin_yarns(&f.fitted.law);
        if let Some(prev) = &previous {
            let (skip, check) = refinement_check(f, prev, &all, from, level)?;
            if let Some(note) = skip {
                f.journal.say(&note);
                f.journal.note(note);
                f.evidence.ladder_check = check;
                break;
            }
            last_check = check;
        }
        meshes.push(level);
        let kept = (f.fitted.clone(), f.evidence.level_mark());
        let check = last_check.as_ref();
        match level_stages(f, maps, sets, strips, (li, level), check, shear_candidates) {
            Ok(()) => {}
            Err(e) if li > 0 && e.is_solve_failure() => {
                meshes.pop();
                f.fitted = kept.0;
                f.evidence.restore(kept.1);
                f.evidence.ladder_check = last_check;
                let note = format!(
                    "warning: the {}×{} level is not kept ({e}): the fit stays on {}×{}, where every stage solved; the mesh check measures what the finer level would change",
                    level.0, level.1, from.0, from.1
                );
                f.journal.say(&note);
                f.journal.note(note);
                break;
            }
            Err(e) => return Err(e),
        }
        if li + 1 < opts.ladder.len() {
            previous = Some(fitted_forces(f, &all, level)?);
        }
    }
    Ok(meshes)
}

/// Every stage of one ladder level: the tensile stages, the joint sweep on the first level,
/// and the bend stage.
fn level_stages(
    f: &mut Fitter,
    maps: &mut [StageMap],
    sets: &mut StageSets,
    strips: &[Vec<usize>],
    (li, level): (usize, (usize, usize)),
    check: Option<&MeshCheck>,
    shear_candidates: &[Vec<f64>],
) -> Result<(), FitError> {
    fit_level(f, maps, sets, strips, (li, level), check, shear_candidates)?;
    if li == 0 && sets.joint.is_some() {
        // the joint sweep: each yarn stiffness over the strips it moves, then the shear given
        // them
        super::joint::joint_stiffness(f, maps[0], 0, sets, level)?;
        super::joint::joint_stiffness(f, maps[1], 1, sets, level)?;
        if !strips[2].is_empty() {
            f.journal
                .say("bias stage again, given the joint yarn stiffnesses");
            refit(f, maps[2], &strips[2], level, false, StageMode::Full)?;
        }
    }
    super::pipeline::bend_stage(f, level)
}

/// Whether the levels from `level` on are skipped (and said so): the last solved refit change
/// `m`, carried one level finer, passes.
fn skipped_by_estimate(
    f: &mut Fitter,
    m: &MeshCheck,
    from: (usize, usize),
    level: (usize, usize),
) -> bool {
    let estimate = m.next_level(super::mesh_check::mesh_order(&f.lab, &f.ctx, &f.fitted));
    if estimate.passes() {
        let note = format!(
            "meshes from {}×{} on skipped: estimated to change the {}×{} fit's {} by {:.2} % and its curves by {:.2} % (the last refinement changed them by {:.2} % and {:.2} %, carried at order {}; below {})",
            level.0, level.1, from.0, from.1, m.parameter,
            100.0 * estimate.change, 100.0 * estimate.curve_change,
            100.0 * m.change, 100.0 * m.curve_change, super::mesh_check::mesh_order(&f.lab, &f.ctx, &f.fitted),
            super::mesh_check::rules_in_words()
        );
        f.journal.say(&note);
        f.journal.note(note);
        return true;
    }
    false
}

/// What refining the fit on `from` to `level` changes: the fitted forces (`prev` on `from`,
/// over the strips `all`) and, for a doubling, the refit's parameter change, solved. Returns
/// the note skipping the levels from `level` on when the change is too small to refit for,
/// and the refit change.
fn refinement_check(
    f: &mut Fitter,
    prev: &[f64],
    all: &[usize],
    from: (usize, usize),
    level: (usize, usize),
) -> Result<(Option<String>, Option<MeshCheck>), FitError> {
    let opts = f.ctx.opts;
    let now = fitted_forces(f, all, level)?;
    let d: Vec<f64> = prev.iter().zip(&now).map(|(a, b)| (b - a) / b).collect();
    let change = super::mean_abs_finite(&d);
    f.journal.say(&format!(
        "the {}×{} fit's forces change by {:.3} % (mean) on {}×{}",
        from.0,
        from.1,
        100.0 * change,
        level.0,
        level.1
    ));
    // a doubling: the refit's parameter change, solved (the forces just solved
    // are the check's defect); otherwise the forces' change decides
    let check = if level == (2 * from.0, 2 * from.1) {
        let (mut bench, m) = f.bench();
        bench.refit_change(m, from)?
    } else {
        None
    };
    if let Some(m) = &check {
        f.journal.say(&format!(
            "refitting the {}×{} fit on {}×{} would change {} by {:.2} % and its curves by {:.2} % (first-order refit, measured)",
            from.0, from.1, level.0, level.1,
            if m.parameter.is_empty() { "no parameter" } else { &m.parameter },
            100.0 * m.change, 100.0 * m.curve_change
        ));
    }
    let skip = match &check {
        Some(m) => m.passes().then(|| {
            format!(
                "meshes from {}×{} on skipped: refitting the {}×{} fit on {}×{} would change {} by only {:.2} % and its curves by {:.2} % (first-order refit; below {})",
                level.0, level.1, from.0, from.1, level.0, level.1,
                if m.parameter.is_empty() { "no parameter" } else { &m.parameter },
                100.0 * m.change, 100.0 * m.curve_change,
                super::mesh_check::rules_in_words()
            )
        }),
        None => (change < opts.skip_tol).then(|| {
            format!(
                "meshes from {}×{} on skipped: they change the {}×{} fit's forces by only {:.3} % (below {:.2} %)",
                level.0, level.1, from.0, from.1, 100.0 * change, 100.0 * opts.skip_tol
            )
        }),
    };
    Ok((skip, check))
}

/// The tensile stages on one level (`li`-th of the ladder, mesh `level`): each direction's
/// stage unless the last refinement (`last_check`) left it unchanged; on the first level the
/// shear degree chosen on the shell and the coupling trial, and the cut-offs set.
fn fit_level(
    f: &mut Fitter,
    maps: &mut [StageMap],
    sets: &mut StageSets,
    strips: &[Vec<usize>],
    (li, level): (usize, (usize, usize)),
    last_check: Option<&MeshCheck>,
    shear_candidates: &[Vec<f64>],
) -> Result<(), FitError> {
    for k in 0..3 {
        if strips[k].is_empty() {
            continue;
        }
        // a stage the last refinement left unchanged is not refitted (its law stays)
        if let Some(moved) = last_check.map(|m| m.stage_change(maps[k].dir)) {
            if li > 0 && moved < STAGE_UNCHANGED {
                f.journal.say(&format!(
                    "{} stage not refitted on {}×{}: refining changed its stiffness and tangents by {:.3} % at most (below {:.2} %)",
                    maps[k].dir.name(), level.0, level.1, 100.0 * moved, 100.0 * STAGE_UNCHANGED
                ));
                continue;
            }
        }
        if li > 0 && k < 2 && sets.joint.as_ref().is_some_and(|j| !j[k].is_empty()) {
            // with the joint sweep a finer level refits the yarn stiffness over the joint
            // strips; η's shape stays the first level's (the mesh check measures it)
            super::joint::joint_stiffness(f, maps[k], k, sets, level)?;
            let note = super::plausible::keep_rising(&mut f.fitted.law, maps[k].dir);
            f.journal.law_note(note);
            continue;
        }
        let fit = if k == 2 && li == 0 && shear_candidates.len() > 1 {
            // the homogeneous strip models a clamped bias strip poorly: choose the shear
            // degree on the shell model itself
            let (mut bench, m) = f.bench();
            let fit = bench.shell_degree_ladder(m, maps[2], &strips[2], level, shear_candidates)?;
            f.fitted.law = fit.law.clone();
            fit
        } else {
            refit(f, maps[k], &strips[k], level, li == 0, StageMode::Full)?
        };
        let mut range = fit.range;
        if k == 2 && li == 0 {
            // then, with the degree chosen, whether the tension–shear coupling pays
            let (mut bench, m) = f.bench();
            let (map, stands, outcome) =
                bench.coupling_trial(m, maps[2], &strips[2], level, fit)?;
            maps[2] = map;
            range = stands.range;
            f.fitted.law = stands.law;
            f.fitted.coupling = outcome;
            super::joint::without_sweep_if_coupled(f, sets);
        }
        // cut-offs at 95 % of the largest strain the tests exercised, set on the first mesh
        if let Some((lo, hi)) = range {
            set_cutoff(f, k, lo, hi);
        }
        let note = super::plausible::keep_rising(&mut f.fitted.law, maps[k].dir);
        f.journal.law_note(note);
    }
    Ok(())
}

/// Forces of every fitted curve on a mesh level at the current material (for the
/// ladder's change measure).
fn fitted_forces(
    f: &mut Fitter,
    strips: &[usize],
    level: (usize, usize),
) -> Result<Vec<f64>, FitError> {
    let curves = fitted_curve_forces(f, strips, level)?;
    Ok(curves.into_iter().flat_map(|(_, forces)| forces).collect())
}

/// The fitted material's force at every point of each fitted curve of `strips` on `level`:
/// (curve, forces), curve by curve in strip order.
pub(super) fn fitted_curve_forces(
    f: &mut Fitter,
    strips: &[usize],
    level: (usize, usize),
) -> Result<Vec<(usize, Vec<f64>)>, FitError> {
    let jobs: Vec<(usize, f64)> = strips
        .iter()
        .map(|&s| (s, f.ctx.prep.strips[s].angle_deg))
        .collect();
    let nodes = f
        .lab
        .predict_many(&f.ctx, &f.fitted, &mut f.stats, &jobs, level)?;
    let mut out = Vec::new();
    for (&s, node) in strips.iter().zip(&nodes) {
        for c in f.ctx.used_curves(&[s]) {
            out.push((c, f.ctx.curve_forces(c, node)));
        }
    }
    Ok(out)
}

/// A tensile stage from the fitted material, its optimum applied to the material, and the
/// stage's cut-off kept below any stress peak ([`super::plausible::keep_rising`]): every
/// optimum applied (the ladder's, the joint sweep's shear again, a refined strip's refit) keeps
/// the law's stress rising up to its cut-off, as a material file must.
pub(super) fn refit(
    f: &mut Fitter,
    map: StageMap,
    strips: &[usize],
    level: (usize, usize),
    strain_range: bool,
    mode: StageMode,
) -> Result<StageFit, FitError> {
    let (mut bench, m) = f.bench();
    let fit = bench
        .shell_stage(m, map, strips, level, strain_range, mode)?
        .fitted()
        .expect("a stage that is not a trial always runs");
    f.fitted.law = fit.law.clone();
    let note = super::plausible::keep_rising(&mut f.fitted.law, map.dir);
    f.journal.law_note(note);
    Ok(fit)
}

/// Direction `k`'s cut-off at 95 % of the largest strain its tests exercised (`lo`, `hi`:
/// the strain range, Ẽ11, Ẽ22, Ẽ12), said.
fn set_cutoff(f: &mut Fitter, k: usize, lo: [f64; 3], hi: [f64; 3]) {
    let law = &mut f.fitted.law;
    let msg = match k {
        0 => {
            law.cutoffs.e11 = (0.0, 0.95 * hi[0]);
            format!("cut-off Ẽ11 ≤ {:.4}", law.cutoffs.e11.1)
        }
        1 => {
            law.cutoffs.e22 = (0.0, 0.95 * hi[1]);
            format!("cut-off Ẽ22 ≤ {:.4}", law.cutoffs.e22.1)
        }
        _ => {
            let e12 = 0.95 * hi[2].abs().max(lo[2].abs());
            law.cutoffs.e12 = (-e12, e12);
            format!("cut-off |Ẽ12| ≤ {e12:.4}")
        }
    };
    f.journal.say(&msg);
}
