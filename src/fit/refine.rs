//! Each test's mesh is its own. After the ladder:
//!
//! 1. every strip whose estimated discretisation error exceeds a third of its curves' fit error
//!    and 0.3 % is refined once more (faces doubled across and along, on top of the ladder's
//!    last level), and the stages whose fitted strips were refined are refitted warm from their
//!    optimum (with the joint sweep, the yarn stiffnesses fitted over a refined off-axis strip
//!    estimated 1 % or more off on its coarser mesh too), until every strip meets its tolerance;
//! 2. a fit whose mesh check fails on the material (a determined quantity of a stage moving by
//!    1 % or more) has the strip with the largest estimated mesh error among those the stage
//!    is fitted over (with the joint sweep, a yarn stage's own and the off-axis strips)
//!    refined and refitted, and is checked again (the bends likewise for the thickness or
//!    rigidities, or a drape angle moving by 0.1°);
//! 3. a fitted curve that the check moves by 0.3 % or more has its strip refined and refitted
//!    too, and the fit is checked again (the default, `--test-meshes strict`; with `own` such a
//!    curve is reported, not refined). Measured on the bundled fabrics
//!    (`paper_repro/fit_speed/strict.md`): it meets the curve criterion on all five, where
//!    `own` leaves four at 0.32–0.44 %, and lowers the estimated change of G12 from 0.84–0.90 %
//!    to 0.23–0.28 % on the three whose 45° strip it refines. It costs most on the cotton,
//!    whose 67.5° strip wrinkles on 32 × 48 (one point takes 160 Newton iterations of a wrinkle
//!    pattern crawling, its energy falling by 5e-7 of itself after the residual has reached
//!    8e-8): that fit takes about twice as long as with `own`, for a G12 that the refit would
//!    move by 0.06 % (under [`super::POLISH_XTOL`], so the step is not taken).
//!
//! A strip is doubled at most [`MAX_DOUBLINGS`] times and never past [`MAX_FACES`]; one left
//! above its tolerance keeps the report's warning, a check still failing keeps its own.
//!
//! The estimate is Richardson's: the strip's curves on its mesh against one with half the faces
//! each way, divided by 2^p − 1 with the cage's slowest measured order p
//! ([`super::mesh_check::order`]). A refined strip's half mesh is its previous one, already
//! solved, so each round costs one solve per refined strip plus the refits.

use super::map::StageMap;
use super::mesh_check::{MeshCheck, MESH_ANGLE_TOL_DEG, MESH_CURVE_TOL, MESH_PARAM_TOL};
use super::preprocess::Strip;
use super::rigs::strip_mesh;
use super::{FitError, Fitter, StageMode};
use crate::dataset::BendTest;
use std::time::Instant;

/// Each test's mesh (`fit --test-meshes`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum TestMeshes {
    /// every strip refined on its own until its mesh-error estimate meets its tolerance, and
    /// the strip that moves a stage in a failed mesh check refined too; a curve the check
    /// moves by 0.3 % is reported, not refined
    Own,
    /// as `own`, and the strip of a fitted curve that the mesh check moves by 0.3 % or more
    /// refined too, until the check passes (the default)
    #[default]
    Strict,
    /// every strip on the ladder's last level (the mesh check and warnings still report)
    Ladder,
}

impl TestMeshes {
    /// The flag value's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Own => "own",
            Self::Strict => "strict",
            Self::Ladder => "ladder",
        }
    }
}

/// The most times one strip's mesh is doubled beyond the ladder's last level.
pub const MAX_DOUBLINGS: u32 = 3;
/// A strip is not refined past this many faces: a 64 × 96 cage, the standard 50 × 75 mm strip
/// doubled twice from the 16 × 24 level (2.7 s a point, against 0.4 s on 32 × 48: the skewed
/// fabric of `paper_repro/off_axis` at 60°, 2 cores). A cap at 64 × 64 (4096) would stop that
/// strip on 32 × 48 with its curve moving by 0.48–0.49 % in the mesh check.
pub const MAX_FACES: usize = 6144;
/// The floor of a test's mesh tolerance (0.3 %, the mesh check's curve criterion).
pub(super) const MESH_FLOOR: f64 = MESH_CURVE_TOL;

/// The tolerance a curve's estimated mesh error must meet: a third of its fit error, and no
/// less than 0.3 %.
pub(super) fn mesh_tolerance(fit_error: f64) -> f64 {
    (fit_error / 3.0).max(MESH_FLOOR)
}

/// Richardson's estimate of a curve's discretisation error from its model forces on a mesh
/// (`fine`) and on half its faces each way (`rough`), at order `order`
/// ([`crate::converge::known_order_error`]).
pub(super) fn curve_mesh_error(fine: &[f64], rough: &[f64], order: f64) -> f64 {
    crate::converge::known_order_error(fine, rough, order)
}

/// One strip's verdict: its worst curve's estimated mesh error and that curve's tolerance.
struct StripCheck {
    estimate: f64,
    tolerance: f64,
}

/// Each test's mesh against the ladder's level: the doublings of every strip and of the
/// bends, which only this module's refinement adds to.
#[derive(Default)]
pub(super) struct Doublings {
    /// times each strip's mesh is doubled beyond the ladder's level
    strips: Vec<u32>,
    /// times the bends' meshes are doubled beyond it
    bends: u32,
    /// every strip on the ladder's level whatever its own doublings (cheap diagnostics)
    ladder: bool,
}

impl Doublings {
    /// None yet, for `strips` strips.
    pub(super) fn new(strips: usize) -> Self {
        Self {
            strips: vec![0; strips],
            ..Self::default()
        }
    }

    /// Strip `s`'s mesh level: the ladder's `level` with its faces doubled as the strip was.
    pub(super) fn strip_level(&self, s: usize, level: (usize, usize)) -> (usize, usize) {
        if self.ladder {
            return level;
        }
        let r = self.strips[s];
        (level.0 << r, level.1 << r)
    }

    /// Times strip `s` is doubled beyond the ladder's level.
    pub(super) fn of_strip(&self, s: usize) -> u32 {
        self.strips[s]
    }

    /// Whether any strip is doubled beyond the ladder's level.
    pub(super) fn any_strip(&self) -> bool {
        self.strips.iter().any(|&r| r > 0)
    }

    /// The bends' mesh level: the ladder's `level` with the faces doubled as the bends were.
    pub(super) fn bend_level(&self, level: (usize, usize)) -> (usize, usize) {
        (level.0 << self.bends, level.1 << self.bends)
    }

    /// Every strip on the ladder's level (`on`) or on its own mesh.
    pub(super) fn set_ladder(&mut self, on: bool) {
        self.ladder = on;
    }

    /// Whether every strip is on the ladder's level whatever its own doublings.
    pub(super) fn ladder(&self) -> bool {
        self.ladder
    }

    /// Whether the bends' cantilevers may be doubled once more on top of `last`.
    fn may_refine_bends(&self, bends: &[BendTest], last: (usize, usize)) -> bool {
        let l = self.bend_level(last);
        self.bends < MAX_DOUBLINGS
            && bends.iter().all(|b| {
                let (nx, ny) = super::thickness::bend_mesh((2 * l.0, 2 * l.1), b);
                nx * ny <= MAX_FACES
            })
    }

    /// Whether strip `s` may be doubled once more on top of `last`.
    fn may_refine(&self, strip: &Strip, s: usize, last: (usize, usize)) -> bool {
        if self.strips[s] >= MAX_DOUBLINGS {
            return false;
        }
        let l = self.strip_level(s, last);
        let (nx, ny) = strip_mesh((2 * l.0, 2 * l.1), strip.width, strip.length);
        nx * ny <= MAX_FACES
    }
}

/// Every strip's worst curve against its tolerance, solved on its mesh and on half of it at
/// the fitted material.
fn strip_checks(f: &mut Fitter, last: (usize, usize)) -> Result<Vec<StripCheck>, FitError> {
    let prep = &f.ctx.prep;
    let jobs: Vec<(usize, f64)> = (0..prep.strips.len())
        .map(|s| (s, prep.strips[s].angle_deg))
        .collect();
    let half = ((last.0 / 2).max(1), (last.1 / 2).max(1));
    let (fine, rough) = f
        .lab
        .predict_pair(&f.ctx, &f.fitted, &mut f.stats, &jobs, (last, half))?;
    let order = super::mesh_check::mesh_order(&f.lab, &f.ctx, &f.fitted);
    let mut out = Vec::new();
    for (s, strip) in prep.strips.iter().enumerate() {
        let mut worst = StripCheck {
            estimate: 0.0,
            tolerance: f64::INFINITY,
        };
        for &c in &strip.curves {
            let model = f.ctx.curve_forces(c, &fine[s]);
            let coarse = f.ctx.curve_forces(c, &rough[s]);
            let estimate = curve_mesh_error(&model, &coarse, order);
            let tolerance = mesh_tolerance(f.ctx.curve_fit_error(c, &model));
            if estimate / tolerance > worst.estimate / worst.tolerance {
                worst = StripCheck {
                    estimate,
                    tolerance,
                };
            }
        }
        out.push(worst);
    }
    Ok(out)
}

/// Whether strip `s` may be doubled once more on top of `last`.
fn may_refine(f: &Fitter, s: usize, last: (usize, usize)) -> bool {
    f.lab.meshes.may_refine(&f.ctx.prep.strips[s], s, last)
}

/// Refines every strip that misses its tolerance and refits the stages it belongs to (see the
/// module doc); `stages[k]` are stage k's fitted strips. Returns whether any strip is refined.
pub(super) fn refine_tests(
    f: &mut Fitter,
    maps: &[StageMap],
    sets: &mut super::StageSets,
    last: (usize, usize),
) -> Result<bool, FitError> {
    let mut any = false;
    loop {
        let t0 = Instant::now();
        f.journal
            .say("per-test meshes: every strip's mesh-error estimate");
        let checks = strip_checks(f, last)?;
        f.stats.time_stage("per-test meshes", t0);
        let todo: Vec<(usize, String)> = (0..checks.len())
            .filter(|&s| checks[s].estimate > checks[s].tolerance && may_refine(f, s, last))
            .map(|s| {
                let why = format!(
                    "estimated mesh error {:.2} % above its tolerance {:.2} %",
                    100.0 * checks[s].estimate,
                    100.0 * checks[s].tolerance
                );
                (s, why)
            })
            .collect();
        if todo.is_empty() {
            return Ok(any);
        }
        any = true;
        double_and_refit(f, maps, sets, last, &todo, &checks)?;
    }
}

/// After a failed mesh check, for the material's sake (a determined quantity of a stage moving
/// by 1 % or more: the strip with the largest estimated mesh error among those the stage is
/// fitted over, [`fitted_over`]; a thickness
/// or rigidity moving by 1 % or a drape angle by 0.1°: the bends; with `curves`, a fitted
/// curve moving by 0.3 %: its strip): doubles those meshes and refits. Without `curves` a
/// curve moving by 0.3 % alone refines nothing here; the check's warning reports it. Returns
/// whether any test is refined.
pub(super) fn refine_for_check(
    f: &mut Fitter,
    maps: &[StageMap],
    sets: &mut super::StageSets,
    last: (usize, usize),
    check: &MeshCheck,
    curves: bool,
) -> Result<bool, FitError> {
    let checks = strip_checks(f, last)?;
    let mut todo: Vec<(usize, String)> = Vec::new();
    for k in 0..sets.own.len() {
        // a stage that moves: the strip with the largest estimated mesh error among those its
        // stiffness is fitted over, alone (one strip usually carries the change: the 45° one
        // for the shear; the check then says whether the next is needed)
        let moved = check.stage_change(maps[k].dir);
        if moved >= MESH_PARAM_TOL && moved.is_finite() {
            let worst = fitted_over(sets, k)
                .iter()
                .copied()
                .filter(|&s| may_refine(f, s, last))
                .max_by(|&a, &b| checks[a].estimate.total_cmp(&checks[b].estimate));
            if let Some(s) = worst.filter(|&s| todo.iter().all(|t| t.0 != s)) {
                let why = format!(
                    "the mesh check moves the {} stage's stiffness by {:.2} %; the largest estimated mesh error of the strips it is fitted over, {:.2} %",
                    maps[k].dir.name(),
                    100.0 * moved,
                    100.0 * checks[s].estimate
                );
                todo.push((s, why));
            }
        }
    }
    // `strict`: a fitted curve moving by 0.3 % after the refit has its strip refined, unless
    // a stage's rule above already refines it
    if curves && check.curve_change >= MESH_FLOOR {
        let strip = f.ctx.prep.curves.iter().find_map(|c| {
            let label = f.ctx.data.tensile[c.test].curve.display().to_string();
            (label == check.curve).then_some(c.strip)
        });
        if let Some(s) = strip.filter(|&s| may_refine(f, s, last) && todo.iter().all(|t| t.0 != s))
        {
            let why = format!(
                "the mesh check moves its curve {} by {:.2} % after the refit; its estimated mesh error, {:.2} %",
                check.curve,
                100.0 * check.curve_change,
                100.0 * checks[s].estimate
            );
            todo.push((s, why));
        }
    }
    // the bends: a thickness or rigidity moving by 1 %, or a drape angle by 0.1°
    let bend_moved = check
        .changes
        .iter()
        .filter(|(n, _)| n.starts_with("thickness") || n.starts_with("bending_"))
        .map(|(_, c)| c.abs())
        .fold(0.0, f64::max);
    let angle_moved = check.angle_change_deg.unwrap_or(0.0);
    let bends = (bend_moved >= MESH_PARAM_TOL || angle_moved >= MESH_ANGLE_TOL_DEG)
        && f.lab.meshes.may_refine_bends(&f.ctx.data.bend, last);
    if todo.is_empty() && !bends {
        return Ok(false);
    }
    if bends {
        refine_bends(f, last, bend_moved, angle_moved);
    }
    double_and_refit(f, maps, sets, last, &todo, &checks)?;
    Ok(true)
}

/// The strips stage `k`'s stiffness is fitted over: with the joint sweep, a yarn stage's own
/// and every off-axis strip; otherwise its own. A yarn stage that the mesh check moves while
/// its own strips' mesh errors are 0.01 % moves through the sweep's off-axis strips, and
/// refining its own would not change it (`z0005-analytic` of the lab zoo: warp and weft
/// strips estimated 0.00–0.03 % off, its 30° strip 1346 %).
fn fitted_over(sets: &super::StageSets, k: usize) -> &[usize] {
    sets.joint
        .as_ref()
        .and_then(|j| j.get(k))
        .filter(|set| !set.is_empty())
        .unwrap_or(&sets.own[k])
}

/// Doubles the bends' cantilevers once more, with the note that says why (the check moves
/// their thickness or rigidity by `bend_moved`, their drape angles by `angle_moved` degrees).
fn refine_bends(f: &mut Fitter, last: (usize, usize), bend_moved: f64, angle_moved: f64) {
    let from = f.lab.meshes.bend_level(last);
    let note = format!(
        "per-test mesh: the bends refined from the {}x{} level's cantilevers to the {}x{} one's (the mesh check moves their thickness or rigidity by {:.2} %, their drape angles by {:.3}°)",
        from.0,
        from.1,
        2 * from.0,
        2 * from.1,
        100.0 * bend_moved,
        angle_moved
    );
    f.journal.say(&note);
    f.journal.note(note);
    f.lab.meshes.bends += 1;
}

/// Doubles the meshes of the strips in `todo` (each with the reason, for the notes), then
/// refits the first stage holding one of them and every later stage (they were fitted given
/// the earlier laws), then the bends, as each ladder level does. With the joint sweep, a yarn
/// stiffness fitted over a refined strip whose estimated mesh error on its coarser mesh
/// (`checks`) is [`MESH_PARAM_TOL`] or more is refitted too: the sweep then stands at the
/// refined meshes' optimum, not at a compromise with the coarser strip's discretisation error
/// (a strip off by less moves the stiffness by less than the mesh check's own criterion).
fn double_and_refit(
    f: &mut Fitter,
    maps: &[StageMap],
    sets: &mut super::StageSets,
    last: (usize, usize),
    todo: &[(usize, String)],
    checks: &[StripCheck],
) -> Result<(), FitError> {
    for (s, why) in todo {
        let strip = &f.ctx.prep.strips[*s];
        let l = f.lab.meshes.strip_level(*s, last);
        let from = strip_mesh(l, strip.width, strip.length);
        let to = strip_mesh((2 * l.0, 2 * l.1), strip.width, strip.length);
        let note = format!(
            "per-test mesh: the {}° strip refined from {}x{} to {}x{} ({why})",
            strip.angle_deg, from.0, from.1, to.0, to.1
        );
        f.journal.say(&note);
        f.journal.note(note);
        f.lab.meshes.strips[*s] += 1;
    }
    let stages = sets.own.clone();
    let refined = |set: &[usize]| set.iter().any(|s| todo.iter().any(|t| t.0 == *s));
    let first = (0..stages.len())
        .find(|&k| refined(&stages[k]))
        .unwrap_or(stages.len());
    for k in 0..stages.len() {
        if stages[k].is_empty() {
            continue;
        }
        if k >= first {
            f.journal.say(&format!(
                "{} stage refitted on its strips' own meshes",
                maps[k].dir.name()
            ));
            super::ladder::refit(f, maps[k], &stages[k], last, false, StageMode::Full)?;
        }
        // the joint sweep's yarn stiffness over a strip refined from a mesh off by 1 % or more
        let moved = |set: &[usize]| {
            set.iter()
                .any(|&s| todo.iter().any(|t| t.0 == s) && checks[s].estimate >= MESH_PARAM_TOL)
        };
        let joint_refined = sets
            .joint
            .as_ref()
            .and_then(|j| j.get(k))
            .is_some_and(|set| moved(set));
        if k >= first || joint_refined {
            super::joint::joint_stiffness(f, maps[k], k, sets, last)?;
        }
    }
    super::pipeline::bend_stage(f, last)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{curve_mesh_error, fitted_over, mesh_tolerance};

    #[test]
    fn a_yarn_stage_with_the_joint_sweep_is_fitted_over_the_off_axis_strips_too() {
        // strips: 0 warp, 1 weft, 2 and 3 off-axis; the weft's stiffness is known (no sweep)
        let own = vec![vec![0], vec![1], vec![2, 3]];
        let sets = crate::fit::StageSets {
            own: own.clone(),
            joint: Some(vec![vec![0, 2, 3], vec![]]),
        };
        assert_eq!(fitted_over(&sets, 0), &[0, 2, 3]);
        assert_eq!(fitted_over(&sets, 1), &[1]);
        assert_eq!(fitted_over(&sets, 2), &[2, 3]);
        let alone = crate::fit::StageSets { own, joint: None };
        assert_eq!(fitted_over(&alone, 0), &[0]);
    }

    #[test]
    fn the_tolerance_is_a_third_of_the_fit_error_and_at_least_the_floor() {
        assert_eq!(mesh_tolerance(0.0), 3e-3);
        assert_eq!(mesh_tolerance(0.03), 0.01);
    }

    #[test]
    fn the_estimate_is_richardsons() {
        // forces converging at order 2: F(h) = F* (1 + c h²), with h and 2h
        let (exact, c, h) = (10.0, 0.5, 0.1);
        let fine = [exact * (1.0 + c * h * h)];
        let rough = [exact * (1.0 + c * 4.0 * h * h)];
        let est = curve_mesh_error(&fine, &rough, 2.0);
        let truth = (fine[0] - exact) / fine[0];
        assert!((est - truth).abs() < 1e-3 * truth, "{est} vs {truth}");
    }
}
