//! The shapes' stage of the shell fit: a captured shape (`[[shape]]`, fitted role) from a
//! scene that shears the sheet (the picture frame, the corner pull) fits G12 where no off-axis
//! strip does. Without one the shear law is linear and G12 its only parameter, assumed at 2 %
//! of the yarn stiffness ([`SHEAR_ASSUMED`]); every other parameter is the lab tests', so the
//! shapes move nothing else (a shape fits what no lab test determines, as in the triangle
//! models' fit).
//!
//! The objective is the sum of the shapes' squared residuals
//! ([`ShapeTarget::residuals_shell`]: positions or FFT descriptor, plus the frame's or the
//! clips' force where the lab measured it). A buckled sheet's shape jumps between branches of
//! wrinkles as the shear changes, so G12 is first scanned over factors 2^(j/2), j = −8…8, of
//! the assumed value, and the best bracket then narrowed by golden section on ln G12 to 0.1 %
//! (about 31 scene solves; 0.85 s each for the 12 × 12 frame).
//!
//! Wrinkles are a weak witness: their branch can change with the mesh (`tests/shape_fit.rs`
//! shows it). Where the shell reproduces no shape within [`SHAPE_TRUST`] at the
//! optimum, G12 is fitted to the measured forces alone (the picture frame is the lab's shear
//! test; its force converges with the mesh where the wrinkles do not), reusing the scan's
//! solves; without a measured force G12 stays assumed and a warning says why.

use super::journal::Journal;
use super::{Context, FitError, FitStats, Fitted, Work};
use crate::dataset::FabricDataset;
use crate::fit::shape_target::ShapeTarget;
use crate::fit::shape_target::SHAPE_TRUST;
use crate::material::FabricMaterial;
use std::collections::HashMap;
use std::time::Instant;

/// The note a fit without an off-axis test carries (its start says why G12 is not fitted).
pub const SHEAR_ASSUMED: &str = "shear not fitted (no off-axis test)";

/// Scan points each side of the start: factors 2^(j/2), j = −SCAN…SCAN.
const SCAN: i32 = 8;

/// Relative width of ln-G12 bracket at which the golden section stops (0.1 %).
const BRACKET: f64 = 1e-3;

/// What of the shapes' residuals the objective takes.
#[derive(Clone, Copy, PartialEq)]
enum Objective {
    /// Every residual: the descriptor's and the force's.
    Shapes,
    /// The measured forces only (the frame's shear force, the clips' pull).
    Forces,
}

/// The minimiser of `cost` over G12 = g0·e^u: the scan, then golden section on the best
/// bracket; returns (G12, cost there). `None` when no scan point has a finite cost.
fn minimise_ln(g0: f64, cost: &mut dyn FnMut(f64) -> f64) -> Option<(f64, f64)> {
    let step = 0.5 * std::f64::consts::LN_2;
    let scanned: Vec<(f64, f64)> = (-SCAN..=SCAN)
        .map(|j| {
            let u = j as f64 * step;
            (u, cost(g0 * u.exp()))
        })
        .collect();
    let best = *scanned.iter().min_by(|a, b| a.1.total_cmp(&b.1))?;
    if !best.1.is_finite() {
        return None;
    }
    let (mut a, mut b) = (best.0 - step, best.0 + step);
    let r = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
    let (mut fc, mut fd) = (cost(g0 * c.exp()), cost(g0 * d.exp()));
    while b - a > BRACKET {
        if fc <= fd {
            (b, d, fd) = (d, c, fc);
            c = b - r * (b - a);
            fc = cost(g0 * c.exp());
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + r * (b - a);
            fd = cost(g0 * d.exp());
        }
    }
    let (u, f) = if fc <= fd { (c, fc) } else { (d, fd) };
    let (u, f) = if f <= best.1 { (u, f) } else { best };
    Some((g0 * u.exp(), f))
}

/// G12 fitted to the fitted shapes that shear the sheet, from material `m`; `Ok(None)`
/// (nothing fitted) when there are none or the model reproduces neither their shapes nor a
/// measured force. The caller runs it only where no off-axis strip fitted the shear.
pub(super) fn shapes_stage(
    ctx: &Context,
    journal: &mut Journal,
    stats: &mut FitStats,
    m: &Fitted,
) -> Result<Option<f64>, FitError> {
    let t0 = Instant::now();
    let targets = shearing_targets(ctx.data)?;
    if targets.is_empty() {
        return Ok(None);
    }
    let g0 = m.law.g12;
    let mut scan = ShearScan {
        targets: &targets,
        g0,
        evaluations: 0,
        material: m.material(ctx.data),
        solved: Default::default(),
    };
    let Some((g12, f)) = scan.fit(Objective::Shapes) else {
        return Err(no_solve(g0));
    };
    let at_shapes = scan.errors(g12);
    let reproduced = at_shapes.iter().all(|e| *e < SHAPE_TRUST);
    let with_force = targets.iter().any(|t| t.test.force.is_some());
    let (g12, f, basis) = if reproduced {
        (g12, f, "shape(s) and force(s)")
    } else if with_force {
        // wrinkles are not the lab's: their branch can change with the mesh while the
        // frame's force does not (the shell's own 30° frame of a stiff-shear cotton on
        // 24 × 24 against 12 × 12: positions 181 % apart, forces 0.4 %)
        journal.note(format!(
            "the shell does not reproduce the captured shape(s) at any shear stiffness ({}: above {:.0} %; buckled wrinkles take another branch on this mesh), so G12 is fitted to the measured force(s) alone",
            describe(&targets, &at_shapes),
            100.0 * SHAPE_TRUST
        ));
        let Some((g, f)) = scan.fit(Objective::Forces) else {
            return Err(no_solve(g0));
        };
        (g, f, "measured force(s)")
    } else {
        journal.note(format!(
            "WARNING: the model does not reproduce the captured shape(s) at any shear stiffness ({}: above {:.0} %) and no force was measured: G12 stays assumed",
            describe(&targets, &at_shapes),
            100.0 * SHAPE_TRUST
        ));
        stats.record(Work {
            evaluations: scan.evaluations,
            ..Work::default()
        });
        stats.time_stage("shapes", t0);
        return Ok(None);
    };
    let evaluations = scan.evaluations;
    stats.record(Work {
        evaluations,
        ..Work::default()
    });
    let errors = scan.errors(g12);
    journal.say(&format!(
        "shapes stage: G12 = {g12:.4e} Pa from {} captured shape(s)' {basis} (assumed {g0:.4e} Pa), shape error {} ({evaluations} scene solves, objective {f:.3e})",
        targets.len(),
        describe(&targets, &errors)
    ));
    let edge = (SCAN as f64 * 0.5 * std::f64::consts::LN_2).exp() * (1.0 - BRACKET);
    if g12 >= g0 * edge || g12 <= g0 / edge {
        journal.note(format!(
            "WARNING: the fitted G12 lies at the end of the range searched ({}): the shape(s) may need a shear stiffness outside it",
            scan_range(g0)
        ));
    }
    journal.note(format!(
        "G12 = {g12:.4e} Pa fitted to {} captured shape(s)' {basis} (no off-axis strip determines the shear; the shear law stays linear)",
        targets.len()
    ));
    stats.time_stage("shapes", t0);
    Ok(Some(g12))
}

/// The dataset's fitted shapes whose scenes shear the sheet.
fn shearing_targets(data: &FabricDataset) -> Result<Vec<ShapeTarget>, FitError> {
    let mut targets = Vec::new();
    for sh in data.shapes.iter() {
        let t = ShapeTarget::new(sh, 1).map_err(FitError::Data)?;
        if t.fitted() && t.shears() {
            targets.push(t);
        }
    }
    Ok(targets)
}

/// The range of G12 the scan from `g0` searches, in words.
fn scan_range(g0: f64) -> String {
    let e = (SCAN as f64 * 0.5 * std::f64::consts::LN_2).exp();
    format!("{:.3e} to {:.3e} Pa", g0 / e, g0 * e)
}

/// The error of a scan that found no G12 whose scenes solve.
fn no_solve(g0: f64) -> FitError {
    FitError::Data(format!(
        "no shear stiffness from {} solves the captured shape(s)' scenes",
        scan_range(g0)
    ))
}

/// Each target's shape error `e`, with its OBJ file, in words.
fn describe(targets: &[ShapeTarget], e: &[f64]) -> String {
    targets
        .iter()
        .zip(e)
        .map(|(t, e)| format!("{} {:.1} %", t.test.obj.display(), 100.0 * e))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The shapes' scenes solved over G12 around `g0`, every solve's residuals kept by G12 (the
/// forces' scan reuses the shapes' solves).
struct ShearScan<'a> {
    targets: &'a [ShapeTarget],
    g0: f64,
    evaluations: usize,
    material: FabricMaterial,
    solved: HashMap<u64, Vec<Vec<f64>>>,
}

impl ShearScan<'_> {
    /// The G12 minimising the objective, and the objective there ([`minimise_ln`]).
    fn fit(&mut self, objective: Objective) -> Option<(f64, f64)> {
        let (targets, material) = (self.targets, &self.material);
        let (solved, evaluations) = (&mut self.solved, &mut self.evaluations);
        minimise_ln(self.g0, &mut |g12| {
            let rs = solved.entry(g12.to_bits()).or_insert_with(|| {
                let mut m = material.clone();
                m.law.g12 = g12;
                *evaluations += 1;
                targets.iter().map(|t| t.residuals_shell(&m)).collect()
            });
            let s: f64 = targets
                .iter()
                .zip(rs.iter())
                .flat_map(|(t, r)| {
                    let r = r.clone();
                    match (objective, t.test.force) {
                        (Objective::Shapes, _) => r,
                        (Objective::Forces, Some(_)) => r[r.len() - 1..].to_vec(),
                        (Objective::Forces, None) => Vec::new(),
                    }
                })
                .map(|r| r * r)
                .sum();
            if s.is_finite() {
                s
            } else {
                f64::INFINITY
            }
        })
    }

    /// Each target's shape error at G12 = `g12`.
    fn errors(&self, g12: f64) -> Vec<f64> {
        let mut m = self.material.clone();
        m.law.g12 = g12;
        self.targets
            .iter()
            .map(|t| t.errors_shell(&m).error)
            .collect()
    }
}
