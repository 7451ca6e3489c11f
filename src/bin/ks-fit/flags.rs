//! The flags several commands take (`--yarn-rule`, `--grading`, `--strategy`, `--boundary`,
//! `--model`): one help text each, with the command's own remark appended, and the values
//! read from the library's constants so that the help says what the code does.

use kshell::assembly::CENTRE_FROM_RATIO;
use kshell::tri::TriKind;

/// `--yarn-rule`: how the yarn terms are integrated; `context` ends the sentence.
pub fn yarn_rule_help(context: &str) -> String {
    format!(
        "How the yarn (warp, weft, a12) terms are integrated: full (4 × 4 Gauss points per face), centre (also `center`; one point per face: a membrane that does not lock when the yarns are nearly inextensible and cross the cage) or auto (centre above a yarn-to-shear ratio max(a11, a22)/G12 of {CENTRE_FROM_RATIO}, below which the two are the same{context})"
    )
}

/// `--grading`: the strip cage's grading; `context` ends the sentence.
pub fn grading_help(context: &str) -> String {
    format!(
        "Strip cage grading towards the free edges and the jaws, \"across,along\", each in [0, 1): edge cells (1 − a)/(1 + a) of the middle ones (0: uniform; {} makes a bias strip's force 4–6 times more accurate on the same mesh, at order 2 where uniform cages converge at 1.2){context}",
        kshell::scene::STRIP_GRADING
    )
}

/// `--strategy`: how each equilibrium is solved and its load brought on.
pub fn strategy_help(context: &str) -> String {
    format!(
        "Solver strategy{context}: `full-step` (the whole load by full-step Newton first, the ramp if that fails), `ramp` (load steps from 1/8, each solve line-searched), `trust-region` (every solve by trust-region Newton on the factorised Hessian, the whole load first) or `adaptive` (load steps sized from the predictor's error); each Newton solve has the energy line search and the backward-Euler fallback"
    )
}

/// `--boundary`: the limit surface's boundary treatment; `context` ends the sentence.
pub fn boundary_help(context: &str) -> String {
    format!(
        "Boundary treatment of the limit surface: `phantom` (extrapolated rows) or `ghost` (ghost control points){context}"
    )
}

/// `--model`: the cloth model; `context` ends the sentence.
pub fn model_help(context: &str) -> String {
    let tri: Vec<&str> = TriKind::ALL.iter().map(|(n, _)| *n).collect();
    format!(
        "Cloth model: kl (the subdivision shell, Clyde et al. 2017) or a triangle model ({}: Miguel et al. 2012's three and Larionov et al. 2022's energy){context}",
        tri.join(", ")
    )
}

/// `--model`'s default, the subdivision shell (also the batch manifest's empty `model` cell).
pub const DEFAULT_MODEL: &str = "kl";

/// The cloth model a command runs, from `--model` (checked where the command starts, so that
/// an unknown model reads `--model: unknown model …` like every other user error).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// The subdivision shell.
    Kl,
    /// A triangle model.
    Tri(TriKind),
}

impl Model {
    /// `--model`'s value, or the error naming the flag.
    pub fn parse(s: &str) -> Result<Model, String> {
        match s {
            DEFAULT_MODEL => Ok(Model::Kl),
            m => m
                .parse()
                .map(Model::Tri)
                .map_err(|e| format!("--model: {e}")),
        }
    }
}

/// `--protocol`: which tests are fitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Protocol {
    // every angle unless its `role` says validation
    All,
    // 0°, 45° and 90° fitted, the rest validation
    Paper,
}

impl Protocol {
    pub fn of(paper: bool) -> Protocol {
        if paper {
            Protocol::Paper
        } else {
            Protocol::All
        }
    }
}

/// A mesh ladder as `--mesh-ladder` takes it: "8x12,16x24".
pub fn ladder_text(ladder: &[(usize, usize)]) -> String {
    let levels: Vec<String> = ladder.iter().map(|m| format!("{}x{}", m.0, m.1)).collect();
    levels.join(",")
}
