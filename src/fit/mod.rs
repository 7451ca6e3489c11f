//! Fitting a fabric's test data (Clyde et al. 2017 §5): the staged protocol and the
//! multiresolution ladder. [`fit`] (in `pipeline`) runs the stages in order; they live in
//! their own modules:
//! - [`preprocess`]: toe compensation, roles and repeats, the strips the model solves;
//! - [`map`]: a stage's variables and the law (and the a12 rule);
//! - `rigs`: the strips kept warm, their node forces and the interpolation to the points;
//! - `stages`, `degrees`: the homogeneous bootstrap, the shell stages; the shear degree;
//! - `ladder`: the mesh levels, and which of them (and which stages) the fit needs;
//! - `surrogate`: the homogeneous strip as the shell's cheap model, and the space-mapped
//!   start of every shell stage;
//! - `mesh_check`: how much refining the last level would change the fit (also the ladder's
//!   test of whether the next level is needed);
//! - `refine`: each test's own mesh, doubled until its estimated error meets its tolerance;
//! - `thickness`: the thickness from the bends;
//! - `validation`: predictions at the nominal angle, the misalignment diagnostic, the notes on
//!   what the data determine;
//! - [`report`]: files and tables;
//! - [`verdict`]: every test against the paper's Table 3 errors and `--max-error`.
//!
//! Objective (paper Eq. 3): the sum of squared relative errors of the tensile forces and the
//! drape angles, over every measured point of every repeat used, each curve weighted by
//! 1/√(its points) so that every curve counts alike. The model is solved at a few elongation
//! nodes per strip (Chebyshev–Lobatto: denser at both ends) and interpolated (local quintic)
//! to the measured points; the interpolation error is checked at the end against solves
//! between the nodes.
//! A strip whose curves have no more distinct measured elongations than nodes (a lab that
//! reports the force at a few elongations, a short synthetic curve) is solved at those
//! elongations themselves: its model forces are exact and it needs no interpolation check.
//! Stages: 1. warp (90°): a11 and η₁; 2. weft (0°): a22 and η₃; 3. the Ẽ11, Ẽ22 cut-offs at
//! 95 % of the largest strain exercised; 4. shear: G12 and η₄ from every other fitted angle
//! (45° alone in the paper's protocol); 5. the Ẽ12 cut-off likewise; 6. thickness from the
//! bend tests, with a_ij and G12 scaled by τ⁰/τ so that the membrane stiffnesses a·τ (and so
//! the tensile fits) are kept. Values in `[known]` are held throughout.
//!
//! Initial guesses and degrees come from the homogeneous-strain strip ([`bootstrap`]); degree
//! d + 1 starts from degree d's optimum with a new term of zero weight, so it can never end
//! worse, and is kept only when it lowers the shape error by the degree gain (30 %): the
//! penalty for its two extra parameters. (A likelihood criterion such as BIC would charge
//! 2 ln n per parameter for n points, a few percent of the error here, but it assumes
//! independent point errors, and a curve's errors are smooth along it: the 30 % rule charges
//! what an extra term buys on curves, not on points.) It must also be plausible
//! ([`plausible`]): exponents bounded, no negligible term, the stress rising over the tested
//! range; otherwise degree d is kept and the log says why.

mod bending;
pub mod bootstrap;
pub mod coupling;
mod degrees;
mod fallback;
pub mod html;
mod joint;
mod journal;
mod ladder;
pub mod map;
mod measures;
mod mesh_check;
pub mod optim;
mod options;
mod pipeline;
pub mod plausible;
pub mod poisson;
pub mod preprocess;
mod refine;
pub mod report;
mod rigs;
pub mod shape_target;
pub mod shapes;
mod stages;
pub use joint::Joint;
use joint::StageSets;
use stages::StageMode;
mod surrogate;
mod thickness;
pub mod toe;
mod tolerances;
pub mod tri;
pub mod uncertainty;
mod validation;
pub mod verdict;

use crate::dataset::FabricDataset;
use crate::material::{BendingRigidity, FabricMaterial, Orthotropic};
use crate::scene::SceneError;
pub use bending::BendingMode;
use map::{A12Rule, Direction};
use measures::{green, mean_abs, mean_abs_finite, shape_error, to_evaluation};
pub use measures::{Misfit, Objective};
pub use mesh_check::{
    MeshCheck, MeshCheckMode, MESH_ANGLE_TOL_DEG, MESH_CURVE_TOL, MESH_PARAM_TOL,
};
pub use options::{FitOptions, MAX_DEGREE, MAX_MISALIGN_DEG, NODES_RANGE};
pub use pipeline::fit;
use preprocess::{Prepared, Strip};
pub use preprocess::{RepeatMode, ToeMode};
pub use refine::{TestMeshes, MAX_DOUBLINGS as REFINE_DOUBLINGS, MAX_FACES as REFINE_MAX_FACES};
use std::time::Instant;
use tolerances::{FIT_RTOL, NEAR_ANGLE_DEG, POLISH_XTOL, TRIAL_RETRY_ITERATIONS};

/// The fit could not be done.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error("{0}")]
    Data(String),
    #[error("{stage}: {source}")]
    Scene { stage: String, source: SceneError },
    /// a stage that failed to solve from its start and from every fallback, with what to try
    #[error("{stage}: {source}; {hint}")]
    Stage {
        stage: String,
        source: SceneError,
        hint: String,
    },
}

impl FitError {
    /// Whether the error is an equilibrium that did not solve (in a scene or a stage), not bad
    /// data, a limit or a set-up that failed.
    pub fn is_solve_failure(&self) -> bool {
        matches!(
            self,
            FitError::Scene {
                source: SceneError::Solve { .. },
                ..
            } | FitError::Stage {
                source: SceneError::Solve { .. },
                ..
            }
        )
    }
}

/// One test's outcome.
#[derive(Clone, Debug)]
pub struct TestOutcome {
    /// "tensile" (a fitted-role strip), "bend" or "validation"
    pub kind: &'static str,
    pub angle_deg: f64,
    /// the CSV file (tensile and validation)
    pub curve: Option<String>,
    /// 1-based among the tests at this angle
    pub repeat: Option<usize>,
    /// mean |relative error| over the curve at the nominal angle (paper Table 3 / 5)
    pub avg_rel_error: Option<f64>,
    /// fitted drape angle (paper Table 4)
    pub drape_angle_deg: Option<f64>,
    pub target_drape_deg: Option<f64>,
    /// misalignment diagnostic of a validation run (within ±`max_misalign_deg`)
    pub misalign_deg: Option<f64>,
    /// mean |relative error| at the nominal angle + `misalign_deg`
    pub avg_rel_error_aligned: Option<f64>,
    /// the repeat's own force scale s (measured ≈ s × model, least squares in relative
    /// terms) and the mean |relative error| after it: how far this strip is from the fitted
    /// fabric as a whole (width, yarn count) and how well the law follows its shape
    pub repeat_scale: Option<f64>,
    pub avg_rel_error_scaled: Option<f64>,
    /// toe removed, m (negative: preload)
    pub toe: Option<f64>,
    /// the strip's real mesh on the last level (faces across × along)
    pub mesh: Option<(usize, usize)>,
    /// estimated discretisation error of the curve there (mean relative)
    pub mesh_error_est: Option<f64>,
    /// (elongation m, measured N, fitted N) at every point used
    pub points: Vec<(f64, f64, f64)>,
    pub used_in_fit: bool,
}

/// Where the time went.
#[derive(Clone, Debug, Default)]
pub struct FitStats {
    pub seconds: f64,
    /// shell-model evaluations (every run of a strip or cantilever)
    pub evaluations: usize,
    /// homogeneous-strip evaluations (each a few microseconds): the bootstrap and the
    /// space-mapped starts of the shell stages
    pub bootstrap_evaluations: usize,
    pub newton_iterations: usize,
    /// equilibria solved to get them: strip nodes and cantilevers, every run (the iterations
    /// one equilibrium takes, on average, are `newton_iterations` over this)
    pub equilibria: usize,
    /// equilibria of the tensile stages that ended unstable (saddles of wrinkling strips):
    /// the points interpolated from them are excluded from the objective
    pub unstable_solves: usize,
    /// (stage, seconds)
    pub stage_seconds: Vec<(String, f64)>,
    /// (stage, Newton iterations), in the order of `stage_seconds`: where the solver's work
    /// goes
    pub stage_iterations: Vec<(String, usize)>,
    /// `newton_iterations` at the last timed stage
    counted: usize,
}

/// Solver work done by one stage or run, which [`FitStats::record`] adds to the fit's totals:
/// the one place the counters change.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Work {
    /// shell-model evaluations (runs of a strip or cantilever)
    pub evaluations: usize,
    /// equilibria solved
    pub equilibria: usize,
    pub newton_iterations: usize,
    /// equilibria that ended unstable
    pub unstable: usize,
    /// homogeneous-strip evaluations
    pub bootstrap_evaluations: usize,
}

impl Work {
    /// One run that solved `equilibria` equilibria in `newton_iterations` iterations.
    pub fn run(equilibria: usize, newton_iterations: usize) -> Self {
        Self {
            evaluations: 1,
            equilibria,
            newton_iterations,
            ..Self::default()
        }
    }

    /// `evaluations` runs of one equilibrium each (cantilevers, minimiser evaluations).
    pub fn single_solves(evaluations: usize, newton_iterations: usize) -> Self {
        Self {
            evaluations,
            equilibria: evaluations,
            newton_iterations,
            ..Self::default()
        }
    }

    /// Homogeneous-strip evaluations only.
    pub fn bootstrap(evaluations: usize) -> Self {
        Self {
            bootstrap_evaluations: evaluations,
            ..Self::default()
        }
    }
}

impl FitStats {
    /// Adds the seconds since `t`, and the Newton iterations since the last timed stage, to
    /// `stage`.
    pub(crate) fn time_stage(&mut self, stage: &str, t: Instant) {
        let s = t.elapsed().as_secs_f64();
        let its = self.newton_iterations - self.counted;
        self.counted = self.newton_iterations;
        if let Some(e) = self.stage_seconds.iter_mut().find(|e| e.0 == stage) {
            e.1 += s;
        } else {
            self.stage_seconds.push((stage.to_string(), s));
        }
        if let Some(e) = self.stage_iterations.iter_mut().find(|e| e.0 == stage) {
            e.1 += its;
        } else {
            self.stage_iterations.push((stage.to_string(), its));
        }
    }

    /// Adds a stage's or a run's solver work to the totals.
    pub(crate) fn record(&mut self, w: Work) {
        self.evaluations += w.evaluations;
        self.equilibria += w.equilibria;
        self.newton_iterations += w.newton_iterations;
        self.unstable_solves += w.unstable;
        self.bootstrap_evaluations += w.bootstrap_evaluations;
    }
}

#[derive(Clone, Debug)]
pub struct FitResult {
    pub material: FabricMaterial,
    /// the minimiser's name
    pub method: String,
    pub meshes: Vec<(usize, usize)>,
    pub stats: FitStats,
    /// degree choice, one line per direction and degree tried
    pub degree_log: Vec<String>,
    /// what the fit leaves out and why, choices made
    pub notes: Vec<String>,
    /// what the data determine and what is assumed
    pub identifiability: Vec<String>,
    /// how much the warp, weft and off-axis strips' forces move with a12 = 0 at the same
    /// small-strain quantities ([`poisson`]); `None` where not checked
    pub a12_dependence: [Option<f64>; 3],
    /// standard errors of the fitted parameters at the optimum, last mesh level
    pub uncertainty: Vec<uncertainty::ParamError>,
    pub tests: Vec<TestOutcome>,
    /// the `max_error` the fit is asked for (the table's `verdict` column reads it)
    pub max_error: f64,
    /// how much one more mesh refinement would change the fit (`None`: not run)
    pub mesh_check: Option<MeshCheck>,
    /// whether the captured shapes that shear the sheet fitted G12 ([`shapes`])
    pub shapes_fitted: bool,
    /// how the strips integrated the yarn terms (`Full` or `Centre`: `auto` as decided)
    pub yarn_rule: crate::assembly::YarnRule,
    /// what became of the tension–shear coupling (`--shear-coupling`)
    pub shear_coupling: coupling::CouplingOutcome,
    /// the misfit the tensile stages minimised (`--objective`, auto as decided)
    pub objective: Misfit,
    /// whether the yarn stages were fitted over the off-axis strips too (`--joint`, as decided)
    pub joint: bool,
    /// each test's mesh (`--test-meshes`)
    pub test_meshes: TestMeshes,
}

/// Smallest and largest membrane strain (Ẽ11, Ẽ22, Ẽ12) a test exercised.
type StrainRange = ([f64; 3], [f64; 3]);

/// ([width, rest length, angle] bits, mesh level, node bits) of a cached strip.
type RigKey = ([u64; 3], (usize, usize), Vec<u64>);

/// Whether the data determine a parameter (unknown names count as determined).
fn is_determined(uncertainty: &[uncertainty::ParamError], name: &str) -> bool {
    uncertainty
        .iter()
        .find(|e| e.name == name)
        .is_none_or(|e| e.determined)
}

/// What the stages leave at their optima for the standard errors ([`uncertainty`]) and the
/// mesh check ([`mesh_check`]).
#[derive(Default)]
struct Evidence {
    /// every tensile stage's standard errors, with its variables at the optimum
    pub(super) uncertainty: Vec<(Direction, Vec<f64>, Vec<uncertainty::ParamError>)>,
    /// the thickness or bending stage's standard errors (last level)
    pub(super) stage_errors: Vec<uncertainty::ParamError>,
    /// every stage's linearisation at its optimum, for the mesh check
    pub(super) linearised: Vec<mesh_check::Linearised>,
    /// the refit change the ladder solves at its last level when it stops there (the finer
    /// level solved): the final mesh check, solved rather than estimated
    pub(super) ladder_check: Option<MeshCheck>,
    /// drape angles of the bend tests at the last thickness or bending stage's result
    pub(super) bend_angles: Vec<f64>,
}

/// The material being fitted: the stages' optima, applied in the order the stages run.
#[derive(Clone)]
struct Fitted {
    law: Orthotropic,
    thickness: f64,
    /// the bends' own rigidities (`--bending`), once fitted
    bending: Option<BendingRigidity>,
    /// what the tension–shear coupling's trial decided ([`coupling`])
    coupling: coupling::CouplingOutcome,
}

impl Fitted {
    /// The fabric's material with these values.
    fn material(&self, data: &FabricDataset) -> FabricMaterial {
        FabricMaterial {
            name: data.name.clone(),
            areal_density: data.areal_density.unwrap_or(0.1),
            thickness: self.thickness,
            law: self.law.clone(),
            bending: self.bending,
        }
    }

    /// The parameters (law, thickness, rigidities): a prediction's memo key.
    fn param_bits(&self) -> Vec<u64> {
        let mut p = self.law.params();
        p.push(self.thickness);
        if let Some(b) = self.bending {
            p.extend([b.warp, b.weft, b.twist]);
        }
        p.iter().map(|v| v.to_bits()).collect()
    }
}

/// What the evidence held before a ladder level, to go back to where the level is not kept.
struct LevelMark {
    records: (usize, usize),
    stage_errors: Vec<uncertainty::ParamError>,
    bend_angles: Vec<f64>,
}

impl Evidence {
    /// The evidence before a ladder level ([`Evidence::restore`]).
    fn level_mark(&self) -> LevelMark {
        LevelMark {
            records: self.marks(),
            stage_errors: self.stage_errors.clone(),
            bend_angles: self.bend_angles.clone(),
        }
    }

    /// Back to the evidence of `mark`: the records of the level after it dropped.
    fn restore(&mut self, mark: LevelMark) {
        self.uncertainty.truncate(mark.records.0);
        self.linearised.truncate(mark.records.1);
        self.stage_errors = mark.stage_errors;
        self.bend_angles = mark.bend_angles;
    }

    /// How many standard errors and linearisations the stages have left: a trial's records
    /// are those past these marks.
    fn marks(&self) -> (usize, usize) {
        (self.uncertainty.len(), self.linearised.len())
    }

    /// Every fitted parameter's standard error at the final `law`: each tensile stage's last
    /// run at the law's final degree (stiffnesses rescaled with the thickness stage's τ⁰/τ),
    /// then the thickness or bending stage's.
    fn final_uncertainty(&self, law: &Orthotropic) -> Vec<uncertainty::ParamError> {
        let mut out = Vec::new();
        for dir in [Direction::Warp, Direction::Weft, Direction::Shear] {
            let (eta, c) = match dir {
                Direction::Warp => (&law.warp, law.a11),
                Direction::Weft => (&law.weft, law.a22),
                Direction::Shear => (&law.shear, law.g12),
            };
            let found = self.uncertainty.iter().rev().find(|(d, _, errors)| {
                *d == dir
                    && errors.iter().filter(|e| e.name.contains("_alpha_")).count() == eta.degree()
            });
            if let Some((_, _, errors)) = found {
                for e in errors {
                    let mut e = e.clone();
                    if e.name.ends_with("_pa") && e.value > 0.0 {
                        e.std_error = e.std_error.map(|s| s * c / e.value);
                        e.value = c;
                    }
                    out.push(e);
                }
            }
        }
        out.extend(self.stage_errors.iter().cloned());
        out
    }
}

/// What every stage reads and none changes: the dataset, the options and what set-up decided.
struct Context<'a> {
    data: &'a FabricDataset,
    opts: &'a FitOptions,
    /// the rule that sets a12 from the other stiffnesses (or holds it)
    a12: A12Rule,
    /// the prepared curves and strips
    prep: Prepared,
    /// the bends fit rigidities of their own (`--bending`) rather than the thickness
    own_bending: bool,
}

/// What a stage works with: the context it reads, the lab it solves in, the record it writes
/// to and the evidence it leaves. Not the fitted material: a stage is given the material it
/// starts from and returns its optimum, which the pipeline applies.
struct Bench<'f, 'a> {
    ctx: &'f Context<'a>,
    lab: &'f mut rigs::Lab,
    journal: &'f mut journal::Journal<'a>,
    stats: &'f mut FitStats,
    evidence: &'f mut Evidence,
}

/// The fitter's working state, its parts each with one owner: the context is set up once;
/// the material is written only where the pipeline and the ladder apply a stage's optimum;
/// the lab's caches only by the lab, each test's mesh doublings only by `refine`; the evidence
/// by the stages that leave it; the journal and the stats are the one record every stage
/// writes to.
struct Fitter<'a> {
    ctx: Context<'a>,
    /// progress lines, notes and the degree log
    journal: journal::Journal<'a>,
    stats: FitStats,
    /// the material being fitted
    fitted: Fitted,
    /// what the stages leave for the standard errors and the mesh check
    evidence: Evidence,
    /// the virtual lab kept warm across stages: strips, cantilevers, predictions, yarn rule
    lab: rigs::Lab,
}

impl<'a> Fitter<'a> {
    /// The bench the stages work at, and the fitted material beside it.
    fn bench(&mut self) -> (Bench<'_, 'a>, &Fitted) {
        let bench = Bench {
            ctx: &self.ctx,
            lab: &mut self.lab,
            journal: &mut self.journal,
            stats: &mut self.stats,
            evidence: &mut self.evidence,
        };
        (bench, &self.fitted)
    }
}

impl Context<'_> {
    /// A stage's minimiser settings on a mesh level, `n` residual groups (curves or bends):
    /// the first level fits; finer levels start from the last level's fit and only polish it
    /// (at most 5 iterations, stopping when one gains under 5 % or the next would move every
    /// variable by less than [`POLISH_XTOL`]).
    fn stage_options(&self, level: (usize, usize), gtol: f64, n: usize) -> optim::OptimOptions {
        let (max_iterations, rel_decrease) = if level == self.opts.ladder[0] {
            (self.opts.max_iterations, self.opts.rel_decrease)
        } else {
            (
                self.opts.max_iterations.min(5),
                self.opts.rel_decrease.max(0.05),
            )
        };
        optim::OptimOptions {
            method: self.opts.method,
            max_iterations,
            rel_decrease,
            gtol,
            target: n as f64 * self.opts.fit_tol.powi(2),
            max_step: 0.5,
            xtol: if level == self.opts.ladder[0] {
                0.0
            } else {
                POLISH_XTOL
            },
        }
    }

    /// The fitted strips of a stage: warp (90°), weft (0°) or shear (every other angle).
    fn stage_strips(&self, dir: Direction) -> Vec<usize> {
        let is = |a: f64, b: f64| (a - b).abs() < 1e-9;
        (0..self.prep.strips.len())
            .filter(|&s| {
                let strip = &self.prep.strips[s];
                let a = strip.angle_deg;
                let ok = match dir {
                    Direction::Warp => is(a, 90.0),
                    Direction::Weft => is(a, 0.0),
                    Direction::Shear => !is(a, 90.0) && !is(a, 0.0),
                };
                ok && strip
                    .curves
                    .iter()
                    .any(|&c| self.prep.curves[c].used_in_fit)
            })
            .collect()
    }

    /// The curves of `strips` the fit uses.
    fn used_curves(&self, strips: &[usize]) -> Vec<usize> {
        strips
            .iter()
            .flat_map(|&s| self.prep.strips[s].curves.iter().copied())
            .filter(|&c| self.prep.curves[c].used_in_fit)
            .collect()
    }

    /// Largest value of a stage's η argument over its strips (x̂ of [`StageMap`]), from the
    /// largest Green strain e along a strip: e² for the yarns, (e/2)² for the shear (a strip
    /// at 45° of an isotropic sheet). Bias strips of fabrics shear more, as a trellis (the
    /// bundled ones reach Ẽ12 ≈ 1.1 e), so the shear's exponent bound is looser over the range
    /// actually reached; e² there loses the good degree-2 optimum of the homogeneous strip's
    /// bootstrap (1.7 % against 0.11 % on a noise-free degree-2 shear).
    fn xhat(&self, dir: Direction, strips: &[usize]) -> f64 {
        let e = strips
            .iter()
            .map(|&s| {
                let st: &Strip = &self.prep.strips[s];
                green(st.nodes.last().copied().unwrap_or(0.0), st.length)
            })
            .fold(0.0, f64::max);
        match (dir, e > 0.0) {
            (_, false) => 1e-2,
            (Direction::Shear, true) => 0.25 * e * e,
            (_, true) => e * e,
        }
    }
}
