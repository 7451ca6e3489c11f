//! The joint sweep (`ks-fit fit --joint`; README, Fitting, item 3, "Repeats that scatter").
//!
//! The staged fit (paper §5) takes the warp law from the warp strips alone and the weft law
//! from the weft strips, then the shear from the off-axis strips with the yarns held. But an
//! off-axis strip loads the yarns too (a 67.5° strip mostly the warp), so with repeats that
//! scatter the off-axis strips inherit whatever scale the yarn repeats happened to have, and
//! the shear stage cannot correct it. The sweep refits each yarn stiffness over its own and
//! every off-axis strip (η's shape held: the axial strips determine it), then the shear stage:
//! block coordinate descent on the whole objective, each block over every curve it moves. One
//! sweep reaches the joint optimum (two and four move a11 by 0.5 % more, `tests/joint.rs`).

use super::map::StageMap;
use super::{FitError, FitOptions, Fitter, StageMode};

/// Whether the sweep runs (`ks-fit fit --joint`; see the module doc). On the bundled denim the
/// warp repeats lie at 0.62–1.15 of the law that made them, and without the sweep the fitted
/// 67.5° strip falls 35 % below all three of its repeats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Joint {
    /// on, except under `--protocol paper` (the paper's staged fit, as published)
    #[default]
    Auto,
    On,
    Off,
}

/// The strips each stage fits: its own (warp 90°, weft 0°, shear every other angle) and, with
/// the joint sweep, those each yarn stage's stiffness is refitted over (its own and every
/// off-axis strip; none where the stiffness is known).
pub(super) struct StageSets {
    pub own: Vec<Vec<usize>>,
    pub joint: Option<Vec<Vec<usize>>>,
}

/// The stage sets of a fit from its own strips per stage (warp, weft, shear): the yarn stages'
/// joint sets when the sweep runs (`opts.joint`; it needs an off-axis strip and a yarn stage
/// with a stiffness to fit).
pub(super) fn stage_sets(opts: &FitOptions, own: Vec<Vec<usize>>, maps: &[StageMap]) -> StageSets {
    let on = match opts.joint {
        Joint::On => true,
        Joint::Off => false,
        Joint::Auto => !opts.paper_protocol,
    };
    let fits = |k: usize| !own[k].is_empty() && !maps[k].c_known;
    let joint = (on && !own[2].is_empty() && (0..2).any(fits)).then(|| {
        (0..2)
            .map(|k| {
                if fits(k) {
                    own[k].iter().chain(&own[2]).copied().collect()
                } else {
                    Vec::new()
                }
            })
            .collect()
    });
    StageSets { own, joint }
}

/// Under `--joint auto`, no sweep once the tension–shear coupling is kept: κ ties the shear
/// to the yarn strains, so the yarn and shear blocks are strongly coupled and one sweep of
/// block coordinate descent lands far from their joint optimum, while the coupled shear
/// stage has already fitted them together. Measured on `paper_repro/off_axis` (strips made
/// from a coupled law, κ = −15 each way, on 32 × 48): with the sweep κ came back at −20.3 and
/// −18.8, G12 +0.9 %, a11 +1.4 % and the curves' mean error 0.64 %; without it −16.3 and
/// −15.4, +0.2 %, +0.5 % and 0.23 % (the sweep lowered the 8 × 12 objective, but on 16 × 24
/// its yarn passes, started from the coarse shear law, left the shear stage at 0.68 % rms
/// where the staged refit reached 0.34 %).
pub(super) fn without_sweep_if_coupled(f: &mut Fitter, sets: &mut StageSets) {
    let kept = matches!(
        f.fitted.coupling,
        super::coupling::CouplingOutcome::Kept { .. }
    );
    if kept && sets.joint.is_some() && f.ctx.opts.joint == Joint::Auto {
        sets.joint = None;
        let note = "joint sweep not run (--joint auto): the tension–shear coupling was kept, and its shear stage fits the yarn and shear terms together (--joint on forces the sweep)".to_string();
        f.journal.say(&note);
        f.journal.note(note);
    }
}

/// The joint sweep's pass of yarn stage `k` ([`super::Joint`]): its stiffness again over
/// its own and every off-axis strip, η's shape held. Nothing without the sweep, for the
/// shear, or for a known stiffness.
///
/// The sweep places the stiffness among the yarn strips' repeats; it is not kept where it puts
/// the model farther outside the band of their force scales than `--max-error` (the verdict's
/// own measure of a repeat's distance from the model), which would fail the strips the stage
/// fits best on its own: a law that cannot follow the off-axis curves' shapes would pay for
/// them with its yarns (on the fabric zoo's `z0005-analytic`, 44 times the force of weft
/// strips that the weft stage alone fits to 0.2 %). The stiffness is then refitted over its own
/// strips, and the stage's joint set is emptied: no sweep of that yarn on later meshes.
pub(super) fn joint_stiffness(
    f: &mut Fitter,
    map: StageMap,
    k: usize,
    sets: &mut StageSets,
    level: (usize, usize),
) -> Result<(), FitError> {
    let Some(strips) = sets.joint.as_ref().and_then(|j| j.get(k)).cloned() else {
        return Ok(());
    };
    if strips.is_empty() {
        return Ok(());
    }
    f.journal.say(&format!(
        "{} stiffness again over every strip it moves (the joint sweep)",
        map.dir.name()
    ));
    let before = f.fitted.law.clone();
    super::ladder::refit(f, map, &strips, level, false, StageMode::Stiffness)?;
    let own = sets.own[k].clone();
    let scales = curve_scales(f, &own, level)?;
    let outside = super::verdict::repeat_error(0.0, &scales);
    if scales.is_empty() || outside <= f.ctx.opts.max_error {
        return Ok(());
    }
    let note = format!(
        "joint sweep: the {0} stiffness fitted over the off-axis strips too puts the model {1:.1} % outside the band of the {0} strips' force scales, more than --max-error {2:.0} %: not kept, the {0} stiffness refitted over its own strips, and no {0} sweep on the finer meshes (the law cannot follow the off-axis strips with the yarns their own strips give)",
        map.dir.name(),
        100.0 * outside,
        100.0 * f.ctx.opts.max_error
    );
    f.journal.say(&note);
    f.journal.note(note);
    f.fitted.law = before;
    super::ladder::refit(f, map, &own, level, false, StageMode::Stiffness)?;
    // a refused sweep is not tried again: the law's shapes, not the mesh, keep it from the
    // off-axis strips (z0001-analytic of the lab zoo: refused on every one of 12 refits, 45–61 %)
    if let Some(set) = sets.joint.as_mut().and_then(|j| j.get_mut(k)) {
        set.clear();
    }
    Ok(())
}

/// The force scale s of each fitted curve of `strips` against the fitted material on `level`
/// (measured ≈ s·model, as the verdict scales a repeat: [`super::verdict::force_scale`]).
fn curve_scales(
    f: &mut Fitter,
    strips: &[usize],
    level: (usize, usize),
) -> Result<Vec<f64>, FitError> {
    let mut out = Vec::new();
    for (c, model) in super::ladder::fitted_curve_forces(f, strips, level)? {
        let q: Vec<f64> = f.ctx.prep.curves[c]
            .points
            .iter()
            .zip(&model)
            .map(|(m, p)| p / m.1)
            .filter(|q| q.is_finite())
            .collect();
        if !q.is_empty() {
            out.push(super::verdict::force_scale(&q).0);
        }
    }
    Ok(out)
}
