//! The thickness stage (paper §5, stage 7): the bend tests' drape angles fit the thickness τ,
//! with a_ij and G12 scaled by τ⁰/τ so that the membrane stiffnesses a·τ, and so the tensile
//! fits, are kept (the bending rigidity goes as a·τ³/12).

use super::mesh_check::Linearised;
use super::optim::{minimize, Evaluation};
use super::rigs::Lab;
use super::uncertainty::ParamError;
use super::{to_evaluation, Context, FitError, FitStats, Fitted, Work};
use crate::dataset::BendTest;
use crate::material::{BendingRigidity, Orthotropic};
use crate::scene::{BendRig, CantileverBend, SceneError};
use rayon::prelude::*;

/// A cantilever's cache key: the test's width, overhang and angle, and its mesh.
pub(super) type BendKey = ([u64; 3], (usize, usize));

fn bend_key(b: &BendTest, mesh: (usize, usize)) -> BendKey {
    (
        [
            b.width.to_bits(),
            b.overhang.to_bits(),
            b.angle_deg.to_bits(),
        ],
        mesh,
    )
}

/// A cantilever mesh at a ladder level: at 8 × 12, 4 across and elements along of an eighth
/// of the width but at least 3.125 mm; both doubled per level. Elements twice as long (as the
/// tensile mesh) leave 0.5–1° of drape angle on the first level, 2–4 % of bending rigidity
/// (a 62.65 mm overhang drapes 41.50° on 4 × 10, 42.430° on 4 × 20 and on 8 × 20, 42.460°
/// on 4 × 40), and the mesh ladder's skip test looks at the strips only.
///
/// The along size is not tied to the width below 25 mm: how finely a cantilever must be cut
/// along depends on how it curves (its overhang against its bending length), not on how wide it
/// is. On a 2.5 × 75 mm strip draping 62.41° (`ks-fit bend --width 2.5 --overhang 75`,
/// a11 = 3e7 Pa, τ = 0.2 mm, 100 g/m²): 4 × 12 is 0.57° off 8 × 240, 4 × 24 0.016°, where
/// square elements need 4 × 120 and 8 × 240 (1.1 s and 4.3 s against 0.09 s and 0.19 s).
pub(super) fn bend_mesh(level: (usize, usize), bend: &BendTest) -> (usize, usize) {
    let f = level.0 as f64 / 8.0;
    let nx = ((4.0 * f).round() as usize).max(2);
    let along = (bend.width / 8.0).max(0.5 * crate::scene::BEND_ELEMENT);
    let ny = ((bend.overhang / along * f).round() as usize).max(4);
    (nx, ny)
}

impl Lab {
    /// The bend tests' cantilevers on a ladder level, set to material `m`:
    /// from the cache, warm from their last equilibria, or set up; hand them back with
    /// [`Lab::keep_bend_rigs`]. Set up anew, a stiff cantilever's first solve is a load
    /// ramp from the flat strip (the ratio-2e4 fit's 190 mm weft cantilever on 16 × 24's mesh
    /// takes 132 Newton iterations, about 6 s), which the cache spares each later thickness
    /// stage and mesh check.
    pub(super) fn bend_rigs(
        &mut self,
        ctx: &Context,
        m: &Fitted,
        bends: &[BendTest],
        level: (usize, usize),
    ) -> Result<Vec<BendRig>, FitError> {
        let mesh_level = self.meshes.bend_level(level);
        let mut out = Vec::with_capacity(bends.len());
        for b in bends {
            let mesh = bend_mesh(mesh_level, b);
            let mut rig = match self.bend_cache.remove(&bend_key(b, mesh)) {
                Some(rig) => rig,
                None => {
                    let mut bend = CantileverBend::new(b.width, b.overhang, b.angle_deg);
                    bend.yarn_rule = ctx.opts.yarn_rule; // a bend reads `auto` as the full rule
                    bend.mesh = mesh;
                    bend.solver.rtol = super::FIT_RTOL;
                    bend.solver.strategy = ctx.opts.strategy;
                    BendRig::new(&bend, &m.material(ctx.data)).map_err(|source| {
                        FitError::Scene {
                            stage: format!("setting up the {}° cantilever", b.angle_deg),
                            source,
                        }
                    })?
                }
            };
            rig.set_material(&m.law, m.thickness)
                .map_err(|source| FitError::Scene {
                    stage: format!("setting up the {}° cantilever", b.angle_deg),
                    source,
                })?;
            rig.set_bending(m.bending);
            out.push(rig);
        }
        Ok(out)
    }

    /// Puts the cantilevers of [`Lab::bend_rigs`] back into the cache, warm.
    pub(super) fn keep_bend_rigs(
        &mut self,
        bends: &[BendTest],
        level: (usize, usize),
        rigs: Vec<BendRig>,
    ) {
        let mesh_level = self.meshes.bend_level(level);
        for (b, rig) in bends.iter().zip(rigs) {
            self.bend_cache
                .insert(bend_key(b, bend_mesh(mesh_level, b)), rig);
        }
    }
}

/// The law and thickness at ln(τ/τ⁰) = `q` from material `m`: a_ij and G12 scaled by τ⁰/τ.
fn scaled(m: &Fitted, q: f64) -> (Orthotropic, f64) {
    let tau0 = m.thickness;
    let tau = tau0 * q.exp();
    let s = tau0 / tau;
    let mut law = m.law.clone();
    law.a11 *= s;
    law.a22 *= s;
    law.a12 *= s;
    law.g12 *= s;
    (law, tau)
}

/// A bend stage's linearisation and standard errors at its optimum p, of `names` at `values`.
pub(super) fn bend_evidence(
    seen: &super::uncertainty::Seen,
    p: &[f64],
    level: (usize, usize),
    names: &[&str],
    values: &[f64],
) -> (Option<Linearised>, Vec<ParamError>) {
    let linearised = super::uncertainty::at_optimum(seen, p)
        .map(|(_, j)| Linearised::bends(level, j, names, values));
    let errors = match super::uncertainty::at_optimum(seen, p) {
        Some((r, j)) => super::uncertainty::log_errors(names, values, j, r),
        None => Vec::new(),
    };
    (linearised, errors)
}

/// The cantilevers' drape angles after `set` (warm: a Newton step or two each), their work
/// recorded; `at` says at what, for an error.
pub(super) fn drape_angles(
    rigs: &mut [BendRig],
    stats: &mut FitStats,
    at: &str,
    set: impl Fn(&mut BendRig) -> Result<(), SceneError>,
) -> Result<Vec<f64>, FitError> {
    let mut angles = Vec::new();
    for rig in rigs {
        let pt = set(rig)
            .and_then(|_| rig.run(false))
            .map_err(|source| FitError::Scene {
                stage: format!("drape angles at {at}"),
                source,
            })?;
        angles.push(pt.drape_angle_deg);
        stats.record(Work::run(1, pt.report.iterations));
    }
    Ok(angles)
}

/// What a bend stage (the thickness, or the bends' own rigidities) found: the material at its
/// optimum, the drape angles there, its evidence, and its line for the log.
pub(super) struct BendFit {
    pub law: Orthotropic,
    pub thickness: f64,
    pub bending: Option<BendingRigidity>,
    /// the bend tests' drape angles at the optimum
    pub angles: Vec<f64>,
    /// the stage's linearisation at the optimum, for the mesh check
    pub linearised: Option<Linearised>,
    /// the standard errors of what it fitted
    pub errors: Vec<ParamError>,
    /// its progress line, and its name for the timings
    pub line: String,
    pub stage: &'static str,
}

/// Thickness from the bend tests, from material `m`: a_ij and G12 scaled by τ⁰/τ.
pub(super) fn thickness_stage(
    ctx: &Context,
    lab: &mut Lab,
    stats: &mut FitStats,
    m: &Fitted,
    level: (usize, usize),
) -> Result<BendFit, FitError> {
    let bends = &ctx.data.bend;
    let mut rigs = lab.bend_rigs(ctx, m, bends, level)?;
    let mut p = vec![0.0];
    let (mut evals, mut newton, mut seen) = (0, 0, super::uncertainty::Seen::new());
    let problem = |q: &[f64], jac: bool| -> Result<Evaluation, SceneError> {
        let (law, tau) = scaled(m, q[0]);
        let (mut r, mut j) = (Vec::new(), Vec::new());
        // the cantilevers are independent: solved side by side, gathered in order
        let runs: Vec<Result<crate::scene::BendPoint, SceneError>> = rigs
            .par_iter_mut()
            .map(|rig| {
                rig.set_material(&law, tau)?;
                rig.run(jac)
            })
            .collect();
        for (pt, b) in runs.into_iter().zip(bends) {
            let pt = pt?;
            evals += 1;
            newton += pt.report.iterations;
            r.push((pt.drape_angle_deg - b.drape_angle_deg) / b.drape_angle_deg);
            if jac {
                // d/d ln τ = τ ∂/∂τ − Σ a ∂/∂a over a11, a22, a12, g12
                let d = &pt.dangle;
                let dtau = tau * d[d.len() - 1]
                    - law.a11 * d[0]
                    - law.a22 * d[1]
                    - law.a12 * d[2]
                    - law.g12 * d[3];
                j.push(vec![dtau / b.drape_angle_deg]);
            }
        }
        let e = to_evaluation(r, j, 1, jac);
        seen.push((q.to_vec(), e.residuals.clone(), e.jacobian.clone()));
        Ok(e)
    };
    let opts = ctx.stage_options(level, 1e-14, bends.len());
    let rep = minimize(&mut p, &opts, problem).map_err(|source| FitError::Scene {
        stage: format!("thickness stage on {}×{}", level.0, level.1),
        source,
    })?;
    stats.record(Work::single_solves(evals, newton));
    let (mut law, tau) = scaled(m, p[0]);
    let (linearised, errors) = bend_evidence(&seen, &p, level, &["thickness_mm"], &[tau * 1e3]);
    // the drape angles at the accepted thickness (warm: a Newton step or two)
    let angles = drape_angles(&mut rigs, stats, "the fitted thickness", |rig| {
        rig.set_material(&law, tau)
    })?;
    lab.keep_bend_rigs(bends, level, rigs);
    // a known a12 is a known value: the scaling keeps a·τ, so restore the rule's a12
    if let super::map::A12Rule::Fixed(_) = ctx.a12 {
        ctx.a12.apply(&mut law);
    }
    let mesh = lab.meshes.bend_level(level);
    let line = format!(
        "thickness stage, mesh {}×{}: τ = {:.4} mm, rms relative angle error {:.3} % ({} evaluations, {})",
        mesh.0,
        mesh.1,
        tau * 1e3,
        100.0 * (rep.objective / bends.len() as f64).sqrt(),
        rep.evaluations,
        rep.stop
    );
    Ok(BendFit {
        law,
        thickness: tau,
        bending: m.bending,
        angles,
        linearised,
        errors,
        line,
        stage: "thickness",
    })
}
