//! The stability atlas: hard quasistatic problems, each solved by every strategy of the solver
//! (and the refinement precisions), recording iterations, factorisations, time and who
//! converges, with a one-line account of what happened (Clyde et al. 2017 §6 motivate the
//! fallback and the refinement; this shows where each is needed). Written by
//! `cargo run --release --example stability_atlas` into `paper_repro/stability/`, and run in
//! reduced size by `tests/stability_atlas.rs`.

mod cases;
mod chart;
mod table;

pub use cases::{stiffening, Case};
pub use chart::to_svg;
pub use table::{explain, summary, to_csv, to_markdown};

use crate::solve::{NewtonOptions, Precision, Strategy};

/// A way of solving.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Method {
    pub name: &'static str,
    pub options: NewtonOptions,
}

/// Iteration budget of every method in the atlas (per solve).
pub const BUDGET: usize = 500;

/// The methods compared: plain Newton, each strategy of the solver as `--strategy` sets it (with
/// the backward-Euler fallback and double-double refinement), and the default strategy with the
/// other refinement precisions. All have the same iteration budget per solve.
pub fn methods() -> Vec<Method> {
    let base = NewtonOptions {
        max_iterations: BUDGET,
        ..NewtonOptions::default()
    };
    let mut out = vec![Method {
        name: "plain Newton",
        options: NewtonOptions {
            max_iterations: BUDGET,
            ..NewtonOptions::plain()
        },
    }];
    for (name, strategy) in Strategy::ALL {
        out.push(Method {
            name,
            options: NewtonOptions { strategy, ..base },
        });
    }
    for (name, precision) in [
        ("full-step, f64 refinement", Precision::F64),
        ("full-step, rug-113 refinement", Precision::Rug(113)),
    ] {
        out.push(Method {
            name,
            options: NewtonOptions { precision, ..base },
        });
    }
    out
}

/// One row of the atlas.
#[derive(Clone, Debug)]
pub struct Row {
    pub case: Case,
    pub method: &'static str,
    pub converged: bool,
    pub residual: f64,
    pub iterations: usize,
    pub factorizations: usize,
    /// Load steps of a cantilever's continuation (strips: the elongation steps).
    pub load_steps: usize,
    pub backward_euler_steps: usize,
    pub refinement_steps: usize,
    /// The final equilibrium has a positive definite Hessian (not a saddle).
    pub stable: bool,
    pub saddle_escapes: usize,
    pub seconds: f64,
    /// A cantilever's drape angle, degrees (the heavy cases' exact answer is 41.4873°).
    pub drape_angle_deg: Option<f64>,
    /// What happened, in one line: why it failed, or which fallbacks a success needed.
    pub note: String,
}

/// The whole atlas.
pub fn atlas(reduced: bool) -> Vec<Row> {
    let mut rows = Vec::new();
    for case in Case::all() {
        for m in methods() {
            rows.push(case.run(&m, reduced));
        }
    }
    rows
}
