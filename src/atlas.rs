//! The stability atlas: hard quasistatic problems, each solved by every method, recording who
//! converges (Clyde et al. 2017 §6 motivate the fallback and the refinement; this shows where
//! each is needed). Written by `cargo run --release --example stability_atlas` into
//! `paper_repro/stability/`, and run in reduced size by `tests/stability_atlas.rs`.

use crate::material::{Cutoffs, Eta, FabricMaterial, Orthotropic};
use crate::scene::{CantileverBend, TensileStrip};
use crate::solve::{NewtonOptions, Precision, SolveReport};
use std::fmt::Write;
use std::time::Instant;

/// A way of solving.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Method {
    pub name: &'static str,
    pub options: NewtonOptions,
}

/// Iteration budget of every method in the atlas (per solve).
pub const BUDGET: usize = 500;

/// The methods compared, from plain Newton to the full solver, all with the same iteration
/// budget.
pub fn methods() -> Vec<Method> {
    let base = NewtonOptions {
        max_iterations: BUDGET,
        ..NewtonOptions::default()
    };
    let full = |precision| NewtonOptions { precision, ..base };
    vec![
        Method {
            name: "plain Newton",
            options: NewtonOptions {
                max_iterations: BUDGET,
                ..NewtonOptions::plain()
            },
        },
        Method {
            name: "Newton + backward Euler",
            options: NewtonOptions {
                refine_steps: 0,
                ..base
            },
        },
        Method {
            name: "full, f64 refinement",
            options: full(Precision::F64),
        },
        Method {
            name: "full, double-double refinement",
            options: full(Precision::DoubleDouble),
        },
        Method {
            name: "full, rug-113 refinement",
            options: full(Precision::Rug(113)),
        },
        Method {
            name: "non-monotone: 25 full steps, then full (dd)",
            options: NewtonOptions {
                full_steps: crate::solve::FULL_STEP_ITERATIONS,
                ..full(Precision::DoubleDouble)
            },
        },
    ]
}

/// One hard problem.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Case {
    /// 45° strip of a stiffening law (degree 3), pulled to 30 % strain in three steps.
    BiasStiffening30,
    /// ASTM cantilever with the whole of gravity applied in one solve.
    CantileverFullGravity,
    /// τ = 0.05 mm, a11 / G12 = 1e4, bias strip to 5 % in one step.
    ThinStiffWarpSoftShear,
    /// Warp strip to 20 % whose strain crosses the 5 % cut-off during the solve.
    CutoffCrossing,
}

impl Case {
    pub fn all() -> [Case; 4] {
        [
            Case::BiasStiffening30,
            Case::CantileverFullGravity,
            Case::ThinStiffWarpSoftShear,
            Case::CutoffCrossing,
        ]
    }

    pub fn name(&self) -> &'static str {
        match self {
            Case::BiasStiffening30 => "bias strip, degree-3 stiffening law, to 30 %",
            Case::CantileverFullGravity => "cantilever, full gravity in one step",
            Case::ThinStiffWarpSoftShear => "thin (0.05 mm), a11/G12 = 1e4, bias to 5 %",
            Case::CutoffCrossing => "warp strip crossing its 5 % cut-off, to 20 %",
        }
    }
}

/// One row of the atlas.
#[derive(Clone, Debug)]
pub struct Row {
    pub case: Case,
    pub method: &'static str,
    pub converged: bool,
    pub residual: f64,
    pub iterations: usize,
    pub backward_euler_steps: usize,
    pub refinement_steps: usize,
    /// The final equilibrium has a positive definite Hessian (not a saddle).
    pub stable: bool,
    pub saddle_escapes: usize,
    pub seconds: f64,
    pub note: String,
}

fn stiffening() -> FabricMaterial {
    let stiff = Eta {
        mu: vec![0.6, 0.3, 0.1],
        alpha: vec![1.0, 6.0, 14.0],
    };
    FabricMaterial {
        name: "stiffening".into(),
        areal_density: 0.15,
        thickness: 2.0e-4,
        law: Orthotropic {
            a11: 1.0e8,
            a22: 6.0e7,
            a12: 1.0e7,
            g12: 1.5e6,
            warp: stiff.clone(),
            weft: stiff.clone(),
            shear: stiff,
            cutoffs: Cutoffs::none(),
        },
    }
}

/// Runs one case with one method; `reduced` uses coarse meshes (for CI).
pub fn run(case: Case, method: &Method, reduced: bool) -> Row {
    let t0 = Instant::now();
    let mut row = Row {
        case,
        method: method.name,
        converged: false,
        residual: f64::NAN,
        iterations: 0,
        backward_euler_steps: 0,
        refinement_steps: 0,
        stable: false,
        saddle_escapes: 0,
        seconds: 0.0,
        note: String::new(),
    };
    let absorb = |row: &mut Row, r: &SolveReport| {
        row.residual = r.residual;
        row.iterations += r.iterations;
        row.backward_euler_steps += r.backward_euler_steps;
        row.refinement_steps += r.refinement_steps;
        row.saddle_escapes += r.saddle_escapes;
        row.stable = r.stable;
    };
    let strip_mesh = if reduced { (4, 6) } else { (16, 24) };
    let outcome: Result<(), String> = match case {
        Case::BiasStiffening30 | Case::ThinStiffWarpSoftShear | Case::CutoffCrossing => {
            let (material, angle, steps): (FabricMaterial, f64, Vec<f64>) = match case {
                Case::BiasStiffening30 => (stiffening(), 45.0, vec![0.1, 0.2, 0.3]),
                Case::ThinStiffWarpSoftShear => {
                    let mut m = stiffening();
                    m.thickness = 5.0e-5;
                    m.law = Orthotropic::from(crate::material::OrthotropicStvk {
                        a11: 1.0e9,
                        a22: 1.0e8,
                        a12: 1.0e7,
                        g12: 1.0e5,
                    });
                    (m, 45.0, vec![0.05])
                }
                _ => {
                    let mut m = stiffening();
                    m.law.cutoffs = Cutoffs {
                        e11: (0.0, 0.05),
                        e22: (0.0, 0.05),
                        e12: (-0.05, 0.05),
                    };
                    (m, 90.0, vec![0.2])
                }
            };
            let mut strip = TensileStrip::new(0.05, 0.075, angle);
            strip.mesh = strip_mesh;
            strip.solver = method.options;
            let dl: Vec<f64> = steps.iter().map(|s| s * 0.075).collect();
            strip
                .run(&material, &dl)
                .map(|curve| {
                    for p in &curve {
                        absorb(&mut row, &p.report);
                    }
                })
                .map_err(|e| e.to_string())
        }
        Case::CantileverFullGravity => {
            let mut m = stiffening();
            m.law = Orthotropic::from(crate::material::OrthotropicStvk {
                a11: 1.0e8,
                a22: 6.0e7,
                a12: 0.0,
                g12: 1.5e6,
            });
            let mut bend = CantileverBend::new(0.025, 0.09, 90.0);
            bend.mesh = if reduced { (4, 12) } else { (4, 32) };
            bend.solver = method.options;
            bend.continuation = false;
            bend.run(&m)
                .map(|r| absorb(&mut row, &r.report))
                .map_err(|e| e.to_string())
        }
    };
    row.seconds = t0.elapsed().as_secs_f64();
    match outcome {
        Ok(()) => row.converged = true,
        Err(e) => row.note = e,
    }
    row
}

/// The whole atlas.
pub fn atlas(reduced: bool) -> Vec<Row> {
    let mut rows = Vec::new();
    for case in Case::all() {
        for m in methods() {
            rows.push(run(case, &m, reduced));
        }
    }
    rows
}

/// CSV with header `case,method,converged,stable,relative_residual,iterations,backward_euler_steps,refinement_steps,saddle_escapes,seconds,note`.
pub fn to_csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "case,method,converged,stable,relative_residual,iterations,backward_euler_steps,refinement_steps,saddle_escapes,seconds,note\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "\"{}\",\"{}\",{},{},{:e},{},{},{},{},{:.3},\"{}\"",
            r.case.name(),
            r.method,
            r.converged,
            r.stable,
            r.residual,
            r.iterations,
            r.backward_euler_steps,
            r.refinement_steps,
            r.saddle_escapes,
            r.seconds,
            r.note.replace('"', "'")
        );
    }
    s
}

/// A Markdown table of the same.
pub fn to_markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "| case | method | converged | stable | relative residual | iterations | backward-Euler steps | refinement steps | saddle escapes | seconds |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2} |",
            r.case.name(),
            r.method,
            if r.converged { "yes" } else { "**no**" },
            match (r.converged, r.stable) {
                (false, _) => "–",
                (true, true) => "yes",
                (true, false) => "**saddle**",
            },
            if r.converged {
                format!("{:.1e}", r.residual)
            } else {
                "–".into()
            },
            r.iterations,
            r.backward_euler_steps,
            r.refinement_steps,
            r.saddle_escapes,
            r.seconds
        );
    }
    s
}
