//! `ks-fit fit`: its flags, read into [`kshell::fit::FitOptions`] (whose defaults they show),
//! and the run, on the shell (`fabric::cmd_fit`) or a triangle model (`models::fit`).

use crate::flags::{
    grading_help, ladder_text, model_help, strategy_help, yarn_rule_help, Model, Protocol,
};
use crate::parse_grading;
use kshell::fit::{
    FitOptions, MAX_DEGREE, MAX_MISALIGN_DEG, MESH_ANGLE_TOL_DEG, MESH_CURVE_TOL, MESH_PARAM_TOL,
    NODES_RANGE, REFINE_DOUBLINGS, REFINE_MAX_FACES,
};
use std::path::PathBuf;

/// Largest `--max-error`, percent.
const MAX_ERROR_PERCENT: f64 = 1000.0;

/// A fraction as a percentage for the help texts (0.003 → "0.3").
fn pct(x: f64) -> String {
    format!("{}", (x * 1e6).round() / 1e4)
}

fn mesh_ladder_help() -> String {
    format!(
        "Meshes of a 50 × 75 mm strip, coarse to fine (other strips keep the element size). Where a level doubles the last, the last fit is solved on it first and the level is skipped (with the rest) when refitting would change no determined parameter by {} % and no curve by {} % (the mesh check's rule); other levels are skipped when they change the last fit's forces by under {} %. A stage the refinement leaves unchanged (under 0.1 %) is not refitted. The default stops at 16x24, where the mesh check finds about 1 % on graded cages; add 32x48 for a fit that meets the {} % rule everywhere, at about twice the time",
        pct(MESH_PARAM_TOL),
        pct(MESH_CURVE_TOL),
        pct(FitOptions::default().skip_tol),
        pct(MESH_PARAM_TOL),
    )
}

fn test_meshes_help() -> String {
    let (p, c, a) = (pct(MESH_PARAM_TOL), pct(MESH_CURVE_TOL), MESH_ANGLE_TOL_DEG);
    format!(
        "Each test's mesh: `strict` (after the ladder, every strip whose estimated mesh error is above a third of its fit error and {c} % is refined, faces doubled across and along, at most {REFINE_DOUBLINGS} times and to {REFINE_MAX_FACES} faces, and its stage refitted; so is the strip with the largest estimated mesh error among those a stage is fitted over (with the joint sweep, a yarn stage's own and the off-axis strips) where the mesh check would move the stage by {p} % or more, the strip of a fitted curve that the check moves by {c} % or more, and the bends where it would move a thickness or rigidity by {p} % or a drape angle by {a}°), `own` (as `strict` but a curve moving by {c} % alone is reported, not refined: faster where such a strip wrinkles; paper_repro/fit_speed/strict.md compares the two) or `ladder` (every strip on the ladder's last level). `[[fit.test]]` mesh names each test's real mesh"
    )
}

fn nodes_help() -> String {
    format!(
        "Elongation nodes per strip at which the model is solved (interpolated between by local quintics), {} to {}; a strip with no more distinct measured elongations than this is solved at them",
        NODES_RANGE.0, NODES_RANGE.1
    )
}

/// The flags of `ks-fit fit`.
#[derive(clap::Args)]
pub struct FitArgs {
    /// The dataset's fabric.toml.
    file: PathBuf,
    /// Fitted material file (default: <dataset name>-fit.toml in the current folder).
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
    /// Also write per-test CSVs of measured and fitted force, SVG plots, a summary and
    /// index.html (one self-contained page: material, uncertainties, every curve against the
    /// fit, errors, degrees, meshes, timings) here.
    #[arg(long)]
    report: Option<PathBuf>,
    /// With --report: also solve the drape, picture frame and corner pull on the fitted
    /// material (fixed meshes 16x16, 16x16, 20x20; about a minute or two) and put their
    /// GPU renders in index.html.
    #[arg(long, requires = "report")]
    scenes: bool,
    #[command(flatten)]
    image: crate::render::ImageArgs,
    #[arg(long, default_value_t = FitOptions::default().max_degree,
        help = format!("Highest polynomial degree of each η tried (lowest first), 1 to {MAX_DEGREE}"))]
    max_degree: usize,
    /// Use exactly this degree for every η rather than choosing (for comparisons). Each
    /// raised degree is fitted whatever its start finds; a law that comes out implausible
    /// (its stress stops rising in the tested range) or with a term too small to matter
    /// keeps the degree below, and the log says so.
    #[arg(long)]
    degree: Option<usize>,
    #[arg(long, default_value_t = ladder_text(&FitOptions::default().ladder), help = mesh_ladder_help())]
    mesh_ladder: String,
    /// Minimiser: hybrid (Gauss–Newton while it makes fast progress, BFGS updates after),
    /// bfgs or gauss-newton (also `gn`); every one uses a strong-Wolfe line search.
    #[arg(long, default_value = FitOptions::default().method.name())]
    method: kshell::fit::optim::Method,
    /// No progress lines.
    #[arg(long)]
    quiet: bool,
    /// Which tests are fitted: `all` (every angle unless its `role` says validation) or
    /// `paper` (0°, 45° and 90° fitted, the rest validation, as in Clyde et al. 2017).
    #[arg(long, value_enum, default_value_t = Protocol::of(FitOptions::default().paper_protocol))]
    protocol: Protocol,
    /// Toe compensation: `auto` (detect slack and preload, remove them, report `toe_mm`)
    /// or `none`; a test's own `toe_mm` key wins over both.
    #[arg(long, value_enum, default_value_t = FitOptions::default().toe)]
    toe: kshell::fit::ToeMode,
    /// Repeats fitted: `all` (each curve weighted alike) or `largest` (the paper's choice:
    /// the largest forces for warp and weft, the median for other angles).
    #[arg(long, value_enum, default_value_t = FitOptions::default().repeats)]
    repeat: kshell::fit::RepeatMode,
    #[arg(long, default_value_t = FitOptions::default().max_misalign_deg,
        help = format!("Bound of the misalignment diagnostic of validation runs, degrees in [0, {MAX_MISALIGN_DEG}] (0: off). The reported error is always the one at the nominal angle"))]
    max_misalign: f64,
    #[arg(long, default_value_t = FitOptions::default().nodes, help = nodes_help())]
    nodes: usize,
    #[arg(long, default_value_t = 100.0 * FitOptions::default().max_error,
        help = format!("Largest acceptable error of a fitted test, percent in (0, {MAX_ERROR_PERCENT}] (mean |relative error| of a curve, relative drape-angle error of a bend). Above it the fit still writes the material and report, prints FIT FAILED and exits with code 3"))]
    max_error: f64,
    /// Read curve files outside the dataset folder (absolute paths, `..`, symbolic links).
    #[arg(long)]
    allow_outside: bool,
    #[arg(long, default_value = FitOptions::default().strategy.name(),
        help = strategy_help(" of every strip and cantilever solve of the fit"))]
    strategy: kshell::solve::Strategy,
    /// Bending model: `orthotropic` (warp and weft flexural rigidities of their own, fitted
    /// to the bends, written as the material's [bending] table), `paper` (one thickness:
    /// bending = τ³/12 × the membrane law, so the warp/weft bending ratio is the tensile
    /// one) or `auto` (orthotropic when both a warp and a weft bend exist).
    #[arg(long, value_enum, default_value_t = FitOptions::default().bending)]
    bending: kshell::fit::BendingMode,
    /// Mesh check (`[fit]` mesh_change: how much refining the last level once more would
    /// change the fit): `coarse` (one solve of every fitted test on the mesh half as fine,
    /// carried to the finer one at order 2 on graded cages, 1.2 on uniform ones, 0.8 with the
    /// yarn terms on the face centres), `fine`
    /// (solved on the mesh twice as fine, at several times the cost) or `off`.
    /// Where the ladder stops because the next level is solved and not needed, that
    /// solved check is reported in its place (in either mode but `off`).
    #[arg(long, value_enum, default_value_t = FitOptions::default().mesh_check)]
    mesh_check: kshell::fit::MeshCheckMode,
    #[arg(long, value_parser = parse_grading, default_value_t = FitOptions::default().grading,
        help = grading_help("; the default crowds the cage at the clamped corners, where a bias strip's force converges slowly"))]
    grading: kshell::mesh::Grading,
    #[arg(long, value_enum, default_value_t = FitOptions::default().test_meshes, help = test_meshes_help())]
    test_meshes: kshell::fit::TestMeshes,
    #[arg(long, default_value = FitOptions::default().yarn_rule.name(),
        help = yarn_rule_help("; every solve of the fit, auto decided once from the bootstrapped law, and a note says so"))]
    yarn_rule: kshell::assembly::YarnRule,
    /// The tension–shear coupling of the law (the shear stiffness times
    /// exp(κ1·E11 + κ2·E22), written as [shear_coupling]): auto (tried once the shear
    /// degree is chosen when two or more off-axis angles are fitted; kept when it lowers
    /// the shear stage's shape error by 30 %, or its rms error by 30 % without raising the
    /// shape error, and keeps the law convex along the strips' strains), off (the paper's
    /// separable law) or on (kept whatever it gains, if convex).
    #[arg(long, value_enum, default_value_t = FitOptions::default().shear_coupling)]
    shear_coupling: kshell::fit::coupling::CouplingMode,
    /// Misfit of a point that the tensile stages sum the squares of: relative ((F̂ − F)/F,
    /// the paper's), log (ln(F̂/F): symmetric in a repeat's force scale, so repeats that
    /// scatter by a scale do not pull the law towards the weakest) or auto (log when an
    /// angle has two or more fitted repeats, else relative). `[fit] objective` says which.
    #[arg(long, value_enum, default_value_t = FitOptions::default().objective)]
    objective: kshell::fit::Objective,
    /// The joint sweep: after the first mesh's staged fit, the warp and weft stages are
    /// refitted over the off-axis strips too (which load the yarns), then the shear stage,
    /// and finer meshes fit each stage over those strips: on, off (the paper's staged
    /// fit) or auto (on unless --protocol paper, or where the tension–shear coupling is kept:
    /// its shear stage fits the yarn and shear terms together).
    #[arg(long, value_enum, default_value_t = FitOptions::default().joint)]
    joint: kshell::fit::Joint,
    #[arg(long, default_value = crate::flags::DEFAULT_MODEL,
        help = model_help(", fitted in Miguel et al. 2012's staged order on strips 8 cells (16 triangles) across (default output <dataset name>-<model>-fit.toml; the options above other than -o, --quiet, --max-error and --allow-outside are the shell's)"))]
    model: String,
}

/// `--max-error` (a percentage in (0, [`MAX_ERROR_PERCENT`]]) as a fraction.
pub fn max_error_fraction(percent: f64) -> Result<f64, String> {
    if percent.is_finite() && percent > 0.0 && percent <= MAX_ERROR_PERCENT {
        Ok(percent / 100.0)
    } else {
        Err(format!(
            "--max-error must be a percentage in (0, {MAX_ERROR_PERCENT}], got {percent:?}"
        ))
    }
}

/// The fit's settings from its flags, checked.
fn fit_options(a: &FitArgs) -> Result<FitOptions, String> {
    let max_error = max_error_fraction(a.max_error)?;
    let max_degree = a.degree.map_or(a.max_degree, |d| d.max(1));
    if max_degree == 0 || a.degree == Some(0) {
        return Err("degrees start at 1 (--max-degree, --degree)".into());
    }
    if max_degree > MAX_DEGREE || a.degree.is_some_and(|d| d > MAX_DEGREE) {
        return Err(format!(
            "degrees go up to {MAX_DEGREE} (--max-degree, --degree; the paper needed at most 5)"
        ));
    }
    if !(0.0..=MAX_MISALIGN_DEG).contains(&a.max_misalign) {
        return Err(format!(
            "--max-misalign must be in [0, {MAX_MISALIGN_DEG}] degrees, got {:?}",
            a.max_misalign
        ));
    }
    if !(NODES_RANGE.0..=NODES_RANGE.1).contains(&a.nodes) {
        return Err(format!(
            "--nodes must be in [{}, {}], got {}",
            NODES_RANGE.0, NODES_RANGE.1, a.nodes
        ));
    }
    let ladder = kshell::converge::parse_ladder(&a.mesh_ladder)
        .map_err(|e| format!("--mesh-ladder: {e}"))?;
    kshell::converge::check_ladder(&ladder, false).map_err(|e| format!("--mesh-ladder: {e}"))?;
    Ok(FitOptions {
        max_degree,
        fixed_degree: a.degree,
        ladder,
        method: a.method,
        paper_protocol: a.protocol == Protocol::Paper,
        toe: a.toe,
        repeats: a.repeat,
        max_misalign_deg: a.max_misalign,
        nodes: a.nodes,
        max_error,
        strategy: a.strategy,
        bending: a.bending,
        mesh_check: a.mesh_check,
        grading: a.grading,
        test_meshes: a.test_meshes,
        yarn_rule: a.yarn_rule,
        shear_coupling: a.shear_coupling,
        objective: a.objective,
        joint: a.joint,
        ..FitOptions::default()
    })
}

/// Runs `ks-fit fit`; `Ok(false)` when the fit missed `--max-error` on a fitted test.
pub fn run(a: &FitArgs, force: bool) -> Result<bool, String> {
    let model = Model::parse(&a.model);
    if model != Ok(Model::Kl) {
        let max_error = max_error_fraction(a.max_error)?;
        if let Model::Tri(kind) = model? {
            let o = a.output.as_deref();
            return crate::models::fit(
                &a.file,
                o,
                kind,
                a.quiet,
                force,
                a.allow_outside,
                max_error,
            );
        }
    }
    let opts = fit_options(a)?;
    let report = a.report.as_deref().map(|dir| crate::fabric::ReportArgs {
        dir,
        scenes: a.scenes.then_some(&a.image),
    });
    let o = a.output.as_deref();
    crate::fabric::cmd_fit(&a.file, o, report, &opts, a.quiet, a.allow_outside, force)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    /// `ks-fit fit` without flags runs the library's default settings.
    #[test]
    fn the_flags_default_to_the_librarys_options() {
        let cli = crate::Cli::try_parse_from(["ks-fit", "fit", "fabric.toml"]);
        let Ok(crate::Cli {
            command: crate::Command::Fit(args),
            ..
        }) = cli
        else {
            panic!("`ks-fit fit fabric.toml` does not parse");
        };
        let opts = fit_options(&args).map_err(|e| e.to_string());
        assert_eq!(
            opts.map(|o| format!("{o:?}")),
            Ok(format!("{:?}", FitOptions::default()))
        );
        assert_eq!(Model::parse(&args.model), Ok(Model::Kl));
    }
}
