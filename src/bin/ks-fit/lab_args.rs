//! What the virtual-lab commands (`tensile`, `bend`, `converge`, `recommend`, the triangle
//! models' strips) share: the solve and mesh flags, argument checks in lab units, and the
//! one-line descriptions and errors of a solve.

use crate::flags::{boundary_help, grading_help, model_help, strategy_help, yarn_rule_help};
use crate::parse_mesh;
use kshell::assembly::YarnRule;
use kshell::solve::{NewtonOptions, Precision};
use kshell::subdiv::BoundaryRule;

/// `bend`'s default tolerance, degrees of drape angle.
pub const BEND_TOL_DEG: f64 = 0.05;
/// `tensile`'s default tolerance, relative force error.
pub const TENSILE_TOL: f64 = 0.003;

/// Options shared by the scene commands.
#[derive(clap::Args)]
pub struct SceneArgs {
    /// Faces across × along, e.g. 8x12 (default: the automatic choice, see --tol).
    #[arg(long, value_parser = parse_mesh)]
    pub mesh: Option<(usize, usize)>,
    #[arg(long, help = boundary_help(" (default: phantom for strips, ghost for cantilevers, the better of the two for each in paper_repro/convergence/heavy_cantilever.txt)"))]
    pub boundary: Option<BoundaryRule>,
    #[arg(long, value_parser = crate::parse_grading, help = grading_help(&format!("; tensile strips: default {} on the automatic mesh, 0 (uniform) with --mesh", kshell::scene::STRIP_GRADING)))]
    pub grading: Option<kshell::mesh::Grading>,
    #[arg(long, default_value = YarnRule::default().name(), help = yarn_rule_help("; a cantilever's auto is always full"))]
    pub yarn_rule: kshell::assembly::YarnRule,
    #[arg(long, allow_negative_numbers = true, help = tol_help())]
    pub tol: Option<f64>,
    /// Report each solve on stderr.
    #[arg(short, long)]
    pub verbose: bool,
    /// Residual arithmetic of the iterative refinement: f64, dd (double-double) or rug.
    #[arg(long, default_value = "dd")]
    precision: Precision,
    /// Plain Newton: no backward-Euler fallback and no refinement (for comparison).
    #[arg(long)]
    plain_newton: bool,
    #[arg(long, default_value = kshell::solve::Strategy::default().name(), help = strategy_help(" (for a cantilever: how its weight is brought on)"))]
    strategy: kshell::solve::Strategy,
    #[arg(long, default_value = crate::flags::DEFAULT_MODEL, help = model_help("; a triangle model reads the material file's [model] table, or converts the shell law's zero-strain moduli"))]
    pub model: String,
}

/// `--tol` of `tensile` and `bend`, with their defaults.
fn tol_help() -> String {
    format!(
        "Without --mesh, the error the automatic mesh must meet: for `bend` degrees of drape angle (default {BEND_TOL_DEG}; three meshes of elements about 6.25 mm, then twice and four times as fine), for `tensile` the relative force error over the curve (default {TENSILE_TOL}, i.e. {} %; graded cages from 4 faces across, doubled until one passes). Each mesh's error is estimated by Richardson extrapolation and the coarsest within it kept",
        (TENSILE_TOL * 1e6).round() / 1e4
    )
}

impl SceneArgs {
    /// The triangle model asked for (`None`: the shell), refusing the shell-only flags with it.
    pub fn tri_model(&self) -> Result<Option<kshell::tri::TriKind>, String> {
        let kind = match crate::flags::Model::parse(&self.model)? {
            crate::flags::Model::Kl => return Ok(None),
            crate::flags::Model::Tri(kind) => kind,
        };
        if self.boundary.is_some()
            || self.grading.is_some()
            || self.yarn_rule != kshell::assembly::YarnRule::Auto
        {
            return Err(format!(
                "--boundary and --grading apply to the kl model's limit surface (as does --yarn-rule), not to --model {}",
                self.model
            ));
        }
        Ok(Some(kind))
    }

    pub fn solver(&self) -> NewtonOptions {
        let base = if self.plain_newton {
            NewtonOptions::plain()
        } else {
            NewtonOptions {
                precision: self.precision,
                ..NewtonOptions::default()
            }
        };
        NewtonOptions {
            strategy: self.strategy,
            ..base
        }
    }
}

/// One line describing a solve, for --verbose.
pub fn describe(r: &kshell::solve::SolveReport) -> String {
    format!(
        "{} iterations ({} backward Euler: {} indefinite, {} ascent, {} stagnation, {} short steps), {} refinement steps ({:?}), residual {:.1e}{}{}{}, {}, {:.1} ms",
        r.iterations,
        r.backward_euler_steps,
        r.fallbacks.indefinite,
        r.fallbacks.ascent,
        r.fallbacks.stagnation,
        r.fallbacks.short_step,
        r.refinement_steps,
        r.precision,
        r.residual,
        if r.precision_limited { " (round-off floor)" } else { "" },
        if r.saddle_escapes > 0 { format!(", {} saddle escapes", r.saddle_escapes) } else { String::new() },
        if r.curvature_steps + r.convexified_steps > 0 {
            format!(
                ", {} negative-curvature and {} convexified steps",
                r.curvature_steps, r.convexified_steps
            )
        } else {
            String::new()
        },
        if r.stable { "stable" } else { "UNSTABLE (a saddle)" },
        r.seconds * 1e3
    )
}

/// Lengths the scene commands accept, mm: a strip from 0.1 mm (a yarn) to a 2 m sheet.
const MM_RANGE: (f64, f64) = (0.1, 2000.0);

/// Most elongation steps of `tensile` (each one an equilibrium solve).
pub const MAX_STEPS: usize = 10_000;

/// A positive number of millimetres up to the top of [`MM_RANGE`], in metres; a strip's
/// dimensions (not an elongation) are also at least its bottom.
pub fn mm(name: &str, v: f64) -> Result<f64, String> {
    let is_elongation = name == "to" || name == "elongation";
    if !(v.is_finite() && v > 0.0 && v <= MM_RANGE.1) {
        return Err(format!(
            "--{name} must be a positive number of millimetres up to {}, got {v:?}",
            MM_RANGE.1
        ));
    }
    if !is_elongation && v < MM_RANGE.0 {
        return Err(format!(
            "--{name} must be at least {} mm, got {v:?}",
            MM_RANGE.0
        ));
    }
    Ok(v * 1e-3)
}

/// A cut angle in [-360, 360] degrees.
pub fn angle_deg(v: f64) -> Result<f64, String> {
    if v.is_finite() && v.abs() <= 360.0 {
        Ok(v)
    } else {
        Err(format!("--angle must be in [-360, 360] degrees, got {v:?}"))
    }
}

/// The mesh, and every step's equilibrium the strip keeps (3 doubles a node), within
/// [`kshell::limits`]; `what` names the mesh's origin in the message.
pub fn check_strip_size(what: &str, (nx, ny): (usize, usize), steps: usize) -> Result<(), String> {
    let nodes = nx.saturating_add(3).saturating_mul(ny.saturating_add(3));
    let kept = steps.saturating_mul(nodes.saturating_mul(24)) / kshell::limits::BYTES_PER_FACE;
    kshell::limits::check_faces(
        &format!("{what} {nx}x{ny} with {steps} steps"),
        nx.saturating_mul(ny).saturating_add(kept),
    )
}

/// Exit 2 naming the saddles a scene ended on (their rows are printed, but they are not states
/// the fabric can hold: a small disturbance moves it elsewhere).
pub fn unstable_error(what: &str, at: &[String], pattern: &str) -> Result<(), String> {
    if at.is_empty() {
        return Ok(());
    }
    Err(format!(
        "{what} {} is unstable (a saddle of the energy: the strip buckles or wrinkles there); the printed value is not a stable state's (-v shows each solve)",
        pattern.replace("{}", &at.join(", "))
    ))
}
