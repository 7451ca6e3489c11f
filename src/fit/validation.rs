//! What the fit reports about itself: every curve predicted at its nominal cut angle (the
//! honest number, paper Tables 3 and 5), a misalignment diagnostic beside it for validation
//! runs (bounded by a lab's cutting tolerance, flagged when it sits on the bound), the
//! interpolation error of the model curves, and which material quantities the data
//! determine.
//!
//! Identifiability (small strain, homogeneous stress): a strip cut at θ from the warp has
//! 1/E(θ) = cos⁴θ/E1 + sin⁴θ/E2 + (1/G − 2ν12/E1) sin²θ cos²θ with E1 = a11 − a12²/a22,
//! E2 = a22 − a12²/a11, ν12 = a12/a22 and G = G12/2 (our shear term is G12 Ẽ12²). Strips at
//! any angles determine E1, E2 and the one combination 1/G − 2ν12/E1, each times the
//! thickness; a12 and G12 separately only through a measured Poisson ratio or a test beyond
//! strips.

use super::journal::Journal;
use super::map::A12Rule;
use super::poisson::A12_DEPENDENCE_TOL;
use super::preprocess::Curve;
use super::tolerances::INTERPOLATION_TOL;
use super::uncertainty::ParamError;
use super::{Bench, Context, FitError, Fitted, TestOutcome, Work};
use crate::dataset::Role;
use crate::scene::CantileverBend;

impl Bench<'_, '_> {
    /// Mean |relative error| of curve `c` with its strip cut at `angle` on a mesh level, and
    /// the model forces at its points.
    fn curve_error(
        &mut self,
        m: &Fitted,
        c: usize,
        angle: f64,
        level: (usize, usize),
    ) -> Result<(f64, Vec<f64>), FitError> {
        let s = self.ctx.prep.curves[c].strip;
        let node = self
            .lab
            .predict(self.ctx, m, self.stats, (s, angle, level))?;
        let model = self.ctx.curve_forces(c, &node);
        Ok((self.ctx.curve_fit_error(c, &model), model))
    }

    /// The misalignment Δθ ∈ [−m, m] (m = `max_misalign_deg`) that best explains curve `c`:
    /// its squared relative error on a grid of at most 1° (strips shared by every repeat),
    /// refined by the parabola through the best grid point and its neighbours.
    fn misalignment(&mut self, fm: &Fitted, c: usize, level: (usize, usize)) -> Option<f64> {
        let m = self.ctx.opts.max_misalign_deg;
        if m <= 0.0 {
            return None;
        }
        let n = (2.0 * m).ceil().max(2.0) as usize;
        let grid: Vec<f64> = (0..=n)
            .map(|k| -m + 2.0 * m * k as f64 / n as f64)
            .collect();
        let angle = self.ctx.prep.curves[c].angle_deg;
        let s = self.ctx.prep.curves[c].strip;
        // solve the grid's strips side by side; a failed one costs +∞ below
        let jobs: Vec<(usize, f64)> = grid.iter().map(|d| (s, angle + d)).collect();
        let _ = self
            .lab
            .predict_many(self.ctx, fm, self.stats, &jobs, level);
        let costs: Vec<f64> = grid
            .iter()
            .map(|&d| match self.curve_error(fm, c, angle + d, level) {
                Ok((_, model)) => self.ctx.prep.curves[c]
                    .points
                    .iter()
                    .zip(&model)
                    .map(|(p, q)| ((q - p.1) / p.1).powi(2))
                    .sum(),
                Err(_) => f64::INFINITY,
            })
            .collect();
        let k = (0..grid.len()).min_by(|&i, &j| costs[i].total_cmp(&costs[j]))?;
        if k == 0 || k + 1 == grid.len() {
            return Some(grid[k]);
        }
        let (l, mid, r) = (costs[k - 1], costs[k], costs[k + 1]);
        let curvature = l - 2.0 * mid + r;
        let h = grid[1] - grid[0];
        if !(curvature > 0.0 && curvature.is_finite()) {
            return Some(grid[k]);
        }
        Some((grid[k] - h * (0.5 * (r - l) / curvature).clamp(-1.0, 1.0)).clamp(-m, m))
    }

    /// Largest relative difference between each strip's interpolated model curve and solves
    /// halfway between its nodes (first mesh level; a strip refined on its own mesh there, as
    /// its nodes were), strips solved side by side: (error, angle) of the worst strip, `None`
    /// where every strip is solved at its measured points (nothing is interpolated).
    fn interpolation_error(&mut self, m: &Fitted) -> Result<Option<(f64, f64)>, FitError> {
        use rayon::prelude::*;
        let level = self.ctx.opts.ladder[0];
        let jobs: Vec<(usize, f64)> = (0..self.ctx.prep.strips.len())
            .filter(|&s| !self.ctx.prep.strips[s].at_points)
            .map(|s| (s, self.ctx.prep.strips[s].angle_deg))
            .collect();
        if jobs.is_empty() {
            return Ok(None);
        }
        let nodes = self
            .lab
            .predict_many(self.ctx, m, self.stats, &jobs, level)?;
        let material = m.material(self.ctx.data);
        let mut checks = Vec::new();
        for &(s, _) in &jobs {
            let strip = &self.ctx.prep.strips[s];
            let mut mids = Vec::new();
            let mut prev = 0.0;
            for &e in &strip.nodes {
                mids.push(0.5 * (prev + e));
                prev = e;
            }
            // on the mesh and the discretisation its nodes were solved on (a strip refined on
            // its own is compared with itself, not with the ladder's mesh, and a node rig set
            // up on an earlier ladder level keeps that level's centre-rule β: either
            // difference is discretisation error, not interpolation error)
            let own = self.lab.meshes.strip_level(s, level);
            let key = self.ctx.rig_key(s, strip.angle_deg, own);
            let node_rig = self.lab.warm_rig(&key);
            let mut t = self.lab.strip_scene(self.ctx, s, strip.angle_deg, own);
            if let Some(r) = node_rig {
                t.yarn_ratio = r.yarn_ratio();
            }
            let mut rig = t.rig(&material, &mids).map_err(|source| FitError::Scene {
                stage: format!("checking the {}° strip's interpolation", strip.angle_deg),
                source,
            })?;
            // started between the node equilibria just solved with the same material
            if let Some(nodes) = node_rig {
                rig.warm_between(nodes);
            }
            checks.push((s, mids, rig));
        }
        let solved: Vec<_> = checks
            .par_iter_mut()
            .map(|(_, _, rig)| rig.run(false))
            .collect();
        let mut worst = (0.0f64, 0.0);
        for (j, ((s, mids, _), run)) in checks.iter().zip(solved).enumerate() {
            let strip = &self.ctx.prep.strips[*s];
            let pts = run.map_err(|source| FitError::Scene {
                stage: format!("checking the {}° strip's interpolation", strip.angle_deg),
                source,
            })?;
            let newton = pts.iter().map(|p| p.report.iterations).sum();
            self.stats.record(Work::run(pts.len(), newton));
            for (&e, p) in mids.iter().zip(&pts) {
                let interp: f64 = super::preprocess::interpolation_weights(&strip.nodes, e)
                    .iter()
                    .map(|&(k, w)| w * nodes[j][k])
                    .sum();
                if p.force.abs() > 0.0 {
                    let r = ((interp - p.force) / p.force).abs();
                    if r > worst.0 {
                        worst = (r, strip.angle_deg);
                    }
                }
            }
        }
        Ok(Some(worst))
    }
}

/// Every test's outcome at the final mesh level.
pub(super) fn outcomes(
    bench: &mut Bench,
    m: &Fitted,
    last: (usize, usize),
) -> Result<Vec<TestOutcome>, FitError> {
    let mut tests = Vec::new();
    bench
        .journal
        .say("report: every curve at its nominal angle");
    let jobs: Vec<(usize, f64)> = (0..bench.ctx.prep.strips.len())
        .map(|s| (s, bench.ctx.prep.strips[s].angle_deg))
        .collect();
    bench
        .lab
        .predict_many(bench.ctx, m, bench.stats, &jobs, last)?;
    // each strip's discretisation error: the last level against one with half the faces
    // each way, at the slowest order measured on the cage (the 45° strip's clamped corners:
    // 2 graded, 1.2 uniform; `mesh_check::order`), so it errs on the large side for 0° and 90°
    let order = super::mesh_check::mesh_order(bench.lab, bench.ctx, m);
    let half = ((last.0 / 2).max(1), (last.1 / 2).max(1));
    bench.journal.say(&format!(
        "report: mesh-error estimate (every strip again on {}x{})",
        half.0, half.1
    ));
    let coarse = bench
        .lab
        .predict_many(bench.ctx, m, bench.stats, &jobs, half)
        .ok();
    for c in 0..bench.ctx.prep.curves.len() {
        tests.push(curve_outcome(bench, m, c, last, coarse.as_deref(), order)?);
    }
    interpolation_note(bench, m);
    for note in super::verdict::outlier_repeats(&tests) {
        bench.journal.note(note);
    }
    bend_outcomes(bench, m, last, &mut tests)?;
    Ok(tests)
}

/// The outcome of curve `c` on the last level; `coarse`: every strip's node forces on half
/// the faces, for its mesh-error estimate at convergence order `order`.
fn curve_outcome(
    bench: &mut Bench,
    m: &Fitted,
    c: usize,
    last: (usize, usize),
    coarse: Option<&[Vec<f64>]>,
    order: f64,
) -> Result<TestOutcome, FitError> {
    let curve = bench.ctx.prep.curves[c].clone();
    let data = bench.ctx.data;
    let t = &data.tensile[curve.test];
    let (err, model) = bench.curve_error(m, c, curve.angle_deg, last)?;
    let (scale, scaled) = repeat_scale(
        bench.journal,
        &curve,
        &t.curve.display().to_string(),
        &model,
    );
    let strip = &bench.ctx.prep.strips[curve.strip];
    let mesh = super::rigs::strip_mesh(
        bench.lab.meshes.strip_level(curve.strip, last),
        strip.width,
        strip.length,
    );
    let mesh_error = coarse.map(|nodes| {
        let rough = bench.ctx.curve_forces(c, &nodes[curve.strip]);
        super::refine::curve_mesh_error(&model, &rough, order)
    });
    if let Some(m) = mesh_error {
        if m > super::refine::mesh_tolerance(err) {
            bench.journal.note(format!(
                "warning: {} ({}°): estimated mesh error {:.2} % on {}x{} is above a third of its fit error ({:.2} %) and 0.3 %, after {} of at most {} doublings of its own mesh: refine the ladder (--mesh-ladder)",
                t.curve.display(),
                curve.angle_deg,
                100.0 * m,
                mesh.0,
                mesh.1,
                100.0 * err,
                bench.lab.meshes.of_strip(curve.strip),
                super::refine::MAX_DOUBLINGS
            ));
        }
    }
    let (misalign, aligned) =
        if curve.role == Role::Validation && bench.ctx.opts.max_misalign_deg > 0.0 {
            misalignment_check(bench, m, c, &curve, &t.curve.display().to_string(), last)?
        } else {
            (None, None)
        };
    Ok(TestOutcome {
        kind: match curve.role {
            Role::Fit => "tensile",
            Role::Validation => "validation",
        },
        angle_deg: curve.angle_deg,
        curve: Some(t.curve.display().to_string()),
        repeat: Some(curve.repeat),
        avg_rel_error: Some(err),
        drape_angle_deg: None,
        target_drape_deg: None,
        misalign_deg: misalign,
        avg_rel_error_aligned: aligned,
        repeat_scale: Some(scale),
        avg_rel_error_scaled: Some(scaled),
        toe: Some(curve.toe),
        mesh: Some(mesh),
        mesh_error_est: mesh_error,
        points: curve
            .points
            .iter()
            .zip(&model)
            .map(|(m, q)| (m.0, m.1, *q))
            .collect(),
        used_in_fit: curve.used_in_fit,
    })
}

/// The scale s with measured ≈ s·model over the curve's points, and the mean error left
/// after it; points where the model has no force (a saddle) are left out, with a note.
fn repeat_scale(journal: &mut Journal, curve: &Curve, name: &str, model: &[f64]) -> (f64, f64) {
    // q = model/measured; the scale s with measured ≈ s·model minimises Σ(s q − 1)²:
    // s = Σq/Σq²
    let q: Vec<f64> = curve
        .points
        .iter()
        .zip(model)
        .map(|(m, p)| p / m.1)
        .filter(|q| q.is_finite())
        .collect();
    let excluded = model.len() - q.len();
    if excluded > 0 {
        journal.note(format!(
            "warning: {name} ({}°): {excluded} of {} points excluded from its errors: the model's equilibrium there is a saddle (the flat strip would wrinkle), whose force is not what the test measures",
            curve.angle_deg,
            model.len()
        ));
    }
    let scale = q.iter().sum::<f64>() / q.iter().map(|v| v * v).sum::<f64>();
    let scaled = q.iter().map(|v| (scale * v - 1.0).abs()).sum::<f64>() / q.len() as f64;
    (scale, scaled)
}

/// A validation curve's misalignment diagnostic: the cut angle's offset that fits it best
/// and the error there, when found (noted when it sits on its bound).
fn misalignment_check(
    bench: &mut Bench,
    m: &Fitted,
    c: usize,
    curve: &Curve,
    name: &str,
    last: (usize, usize),
) -> Result<(Option<f64>, Option<f64>), FitError> {
    let (mut misalign, mut aligned) = (None, None);
    bench
        .journal
        .say(&format!("report: misalignment diagnostic of {name}"));
    // a diagnostic: on the first level's strips, whatever this one's own mesh
    bench.lab.meshes.set_ladder(true);
    let found = bench.misalignment(m, c, bench.ctx.opts.ladder[0]);
    bench.lab.meshes.set_ladder(false);
    if let Some(d) = found {
        let (e, _) = bench.curve_error(m, c, curve.angle_deg + d, last)?;
        misalign = Some(d);
        aligned = Some(e);
        let m = bench.ctx.opts.max_misalign_deg;
        if (d.abs() - m).abs() < 1e-9 {
            bench.journal.note(format!(
                "warning: validation {}° ({name}): the misalignment diagnostic sits on its ±{m}° bound: the model, not the cut, is likely off",
                curve.angle_deg,
            ));
        }
    }
    Ok((misalign, aligned))
}

/// The note on the model curves' interpolation between nodes (checked halfway between them).
fn interpolation_note(bench: &mut Bench, m: &Fitted) {
    let exact = bench.ctx.prep.strips.iter().filter(|s| s.at_points).count();
    if exact < bench.ctx.prep.strips.len() {
        bench
            .journal
            .say("report: interpolation check (solves halfway between the nodes)");
    }
    let at_points = if exact == 0 {
        String::new()
    } else {
        format!(
            "; {exact} of {} strips solved at their measured elongations (no more of them than nodes), not interpolated",
            bench.ctx.prep.strips.len()
        )
    };
    match bench.interpolation_error(m) {
        Ok(Some(worst)) => bench.journal.note(format!(
        "model curves solved at {} nodes per strip and interpolated: largest interpolation error {:.3} % ({}° strip, checked halfway between nodes on {}×{}{}){}{at_points}",
        bench.ctx.opts.nodes,
        100.0 * worst.0,
        worst.1,
        bench.ctx.opts.ladder[0].0,
        bench.ctx.opts.ladder[0].1,
        if bench.lab.meshes.any_strip() && !bench.lab.meshes.ladder() {
            ", strips refined on their own meshes there"
        } else {
            ""
        },
        if worst.0 > INTERPOLATION_TOL { "; warning: above 0.1 %, raise the node count" } else { "" }
    )),
        Ok(None) => bench.journal.note(
            "model curves solved at every measured elongation (no strip has more of them than nodes): nothing interpolated, no interpolation error".to_string(),
        ),
        Err(e) => bench.journal.note(format!("warning: the interpolation check could not be made: {e}")),
    }
}

/// The bend tests' outcomes, appended to `tests` (predicted on the last level first when the
/// thickness is known and nothing fits them).
fn bend_outcomes(
    bench: &mut Bench,
    m: &Fitted,
    last: (usize, usize),
    tests: &mut Vec<TestOutcome>,
) -> Result<(), FitError> {
    let data = bench.ctx.data;
    let mut angles = bench.evidence.bend_angles.clone();
    if angles.len() != data.bend.len() {
        // thickness known: the bends are predicted, not fitted
        angles.clear();
        for b in &data.bend {
            let mut bend = CantileverBend::new(b.width, b.overhang, b.angle_deg);
            bend.yarn_rule = bench.ctx.opts.yarn_rule; // a bend reads `auto` as the full rule
            bend.mesh = super::thickness::bend_mesh(bench.lab.meshes.bend_level(last), b);
            let r = bend
                .run(&m.material(bench.ctx.data))
                .map_err(|source| FitError::Scene {
                    stage: format!("predicting the {}° cantilever", b.angle_deg),
                    source,
                })?;
            angles.push(r.drape_angle_deg);
        }
    }
    let fitted = bench.ctx.own_bending || data.known.thickness.is_none();
    for (b, &angle) in data.bend.iter().zip(&angles) {
        tests.push(TestOutcome {
            kind: "bend",
            angle_deg: b.angle_deg,
            curve: None,
            repeat: None,
            avg_rel_error: None,
            drape_angle_deg: Some(angle),
            target_drape_deg: Some(b.drape_angle_deg),
            misalign_deg: None,
            avg_rel_error_aligned: None,
            repeat_scale: None,
            avg_rel_error_scaled: None,
            toe: None,
            mesh: None,
            mesh_error_est: None,
            points: Vec::new(),
            used_in_fit: fitted,
        });
    }
    Ok(())
}

/// Which quantities the data determined and which were assumed, with their values.
/// A quantity that strips were fitted to is still only "determined" where the fit's standard
/// errors say its parameter is (`uncertainty`: a stiffness the curves barely depend on, such as
/// the shear of wide off-axis strips whose yarns run from jaw to jaw, is not).
/// A quantity determined by strips whose forces depend on the assumed a12 (`a12_dependence`,
/// [`super::poisson`]) is determined only with that a12, and the line says by how much.
pub(super) fn identifiability(
    ctx: &Context,
    m: &Fitted,
    strips: &[Vec<usize>],
    uncertainty: &[ParamError],
    a12_dependence: &[Option<f64>; 3],
) -> Vec<String> {
    let l = &m.law;
    let tau = m.thickness;
    let e1 = l.a11 - l.a12 * l.a12 / l.a22;
    let e2 = l.a22 - l.a12 * l.a12 / l.a11;
    let nu12 = l.a12 / l.a22;
    let g = 0.5 * l.g12;
    let mut out = Vec::new();
    let source = |fitted: bool, known: bool, param: &str, k: usize| {
        let spread = uncertainty.iter().find(|e| e.name == param);
        if known {
            "known".to_string()
        } else if !fitted {
            "assumed".to_string()
        } else if let Some(e) = spread.filter(|e| !e.determined) {
            let relative = e.std_error.map_or("no estimate".to_string(), |s| {
                format!("± {:.0} %", 100.0 * s / e.value.abs())
            });
            format!("NOT DETERMINED by the data ({param} {relative}: the fitted curves barely depend on it)")
        } else if let Some(d) = a12_dependence[k].filter(|&d| d > A12_DEPENDENCE_TOL) {
            format!(
                "determined only with the assumed a12: with a12 = 0 and this value the {} strips' small-strain force moves by {:.1} % (their jaws hold the contraction; give [known] poisson_12 or a12_pa to pin it)",
                ["warp", "weft", "off-axis"][k],
                100.0 * d
            )
        } else {
            "determined".to_string()
        }
    };
    let k = &ctx.data.known;
    out.push(format!(
        "E1·τ = {:.5e} N/m (warp, small strain): {}",
        e1 * tau,
        source(!strips[0].is_empty(), k.a11.is_some(), "a11_pa", 0)
    ));
    out.push(format!(
        "E2·τ = {:.5e} N/m (weft, small strain): {}",
        e2 * tau,
        source(!strips[1].is_empty(), k.a22.is_some(), "a22_pa", 1)
    ));
    out.push(format!(
        "(1/G − 2ν12/E1)/τ = {:.5e} m/N (off-axis compliance, small strain): {}",
        (1.0 / g - 2.0 * nu12 / e1) / tau,
        source(!strips[2].is_empty(), k.g12.is_some(), "g12_pa", 2)
    ));
    out.push(match ctx.a12 {
        A12Rule::HalfMin => format!(
            "a12 = {:.4e} Pa (ν12 = {nu12:.3}): assumed, ½·min(a11, a22) (the paper's default); strips do not determine it: another a12 with G12 changed to keep 1/G − 2ν12/E1 fits them alike at small strain, so G12 = {:.4e} Pa is tied to this choice (give [known] poisson_12 or a12_pa to pin it)",
            l.a12, l.g12
        ),
        A12Rule::Poisson(nu) => format!(
            "a12 = {:.4e} Pa: from the known ν12 = {nu} (a12 = ν12·a22); G12 = {:.4e} Pa determined with it",
            l.a12, l.g12
        ),
        A12Rule::Fixed(v) => format!("a12 = {v:.4e} Pa: known; G12 = {:.4e} Pa determined with it", l.g12),
    });
    if let Some(b) = m.bending {
        let off_axis = ctx
            .data
            .bend
            .iter()
            .any(|t| (t.angle_deg - 90.0).abs() > 1e-9 && t.angle_deg.abs() > 1e-9);
        out.push(format!(
            "bending rigidities B_warp = {:.5e} N·m, B_weft = {:.5e} N·m: determined by the warp and weft bends (bending of its own; ratio {:.3} against the tensile E1/E2 = {:.3})",
            b.warp,
            b.weft,
            b.warp / b.weft,
            e1 / e2
        ));
        out.push(if off_axis {
            format!("twist rigidity B_twist = {:.5e} N·m: determined by the off-axis bends", b.twist)
        } else {
            format!(
                "twist rigidity B_twist = {:.5e} N·m: assumed (no off-axis bend): the 45° bending compliance follows the membrane's, relative to warp and weft",
                b.twist
            )
        });
    }
    out.extend(coupling_line(&m.coupling, l.coupling));
    out.push(thickness_line(ctx, m));
    out
}

/// What determined the thickness of material `m`.
fn thickness_line(ctx: &Context, m: &Fitted) -> String {
    if ctx.data.known.thickness.is_some() {
        format!("thickness τ = {:.4} mm: known", m.thickness * 1e3)
    } else if m.bending.is_some() {
        format!(
            "thickness τ = {:.4} mm: assumed (the measured value): with bending of its own it only splits the strips' a·τ",
            m.thickness * 1e3
        )
    } else if ctx.data.bend.is_empty() {
        format!(
            "thickness τ = {:.4} mm: assumed (the measured value; no bend tests): strips determine a·τ only",
            m.thickness * 1e3
        )
    } else {
        format!(
            "thickness τ = {:.4} mm: determined by the bends (bending rigidity a·τ³/12 with a·τ held)",
            m.thickness * 1e3
        )
    }
}

/// What the off-axis strips said of the tension–shear coupling: its `outcome`, `kappa` the
/// law's factors.
fn coupling_line(
    outcome: &super::coupling::CouplingOutcome,
    kappa: Option<crate::material::ShearCoupling>,
) -> Option<String> {
    use super::coupling::CouplingOutcome;
    match (outcome, kappa) {
        (CouplingOutcome::Kept { without, with }, Some(c)) => Some(format!(
            "tension–shear coupling κ1 = {:.4}, κ2 = {:.4}: determined by the off-axis strips at several angles (the shear stage's {without} without it, {with} with it; standard errors in [fit.uncertainty]), together with η4's exponents, which it trades off against along the strips' paths: what the strips pin down is each off-axis strip's stress (bias_stress_* in [fit.mesh_check])",
            c.warp, c.weft
        )),
        (CouplingOutcome::Rejected { why, .. }, _) => Some(format!(
            "tension–shear coupling: assumed absent (the separable law): tried and not kept, {why}"
        )),
        (CouplingOutcome::NotTried, _) => Some(
            "tension–shear coupling: assumed absent (the separable law): one off-axis angle cannot tell it from the shear law's own nonlinearity (fit two or more off-axis angles to test it)".to_string(),
        ),
        _ => None,
    }
}
