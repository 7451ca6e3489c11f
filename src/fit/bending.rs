//! The bending stage with bending of its own (`--bending orthotropic`, see
//! [`crate::material::bending`]): the bend tests' drape angles fit the warp and weft flexural
//! rigidities, and the twist rigidity when an off-axis (bias) cantilever exists, with the
//! membrane law and the thickness left as the tensile stages fitted them.
//!
//! This replaces the paper's thickness stage (§5, stage 7), in which one τ serves both bends
//! so that the warp/weft bending ratio is the tensile ratio. Starting values come from each
//! cantilever's bending length by the ASTM D1388 formula c = l (cos(θ/2) / (8 tan θ))^(1/3)
//! (Peirce; about 2 % off the heavy elastica), B = ρ g c³; the stage then fits the shell model's
//! own drape angles with exact sensitivities ∂θ/∂B.

use super::mesh_check::Linearised;
use super::optim::{minimize, Evaluation};
use super::rigs::Lab;
use super::thickness::{bend_evidence, drape_angles, BendFit};
use super::uncertainty::ParamError;
use super::{to_evaluation, Context, FitError, FitStats, Fitted, Work};
use crate::assembly::STANDARD_GRAVITY;
use crate::dataset::BendTest;
use crate::material::bending::{bias_ratio, twist_following};
use crate::material::{BendingRigidity, Orthotropic};
use crate::scene::{BendRig, SceneError};
use rayon::prelude::*;

/// How the bending is modelled (`fit --bending`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum BendingMode {
    /// Orthotropic when both a warp (90°) and a weft (0°) cantilever exist, else the paper's.
    #[default]
    Auto,
    /// The paper's model: one thickness, bending = τ³/12 × the membrane law.
    Paper,
    /// Rigidities of its own per direction, fitted to the bends.
    Orthotropic,
}

/// Which kind of cantilever a bend is: along the warp, the weft, or off-axis.
fn along(b: &BendTest, angle: f64) -> bool {
    (b.angle_deg - angle).abs() < 1e-9
}

/// Whether a dataset's bends are fitted with rigidities of their own under `mode`; an error
/// when orthotropic bending is asked for and the bends cannot determine it.
pub(super) fn use_own_bending(mode: BendingMode, bends: &[BendTest]) -> Result<bool, FitError> {
    let both = bends.iter().any(|b| along(b, 90.0)) && bends.iter().any(|b| along(b, 0.0));
    match mode {
        BendingMode::Paper => Ok(false),
        BendingMode::Auto => Ok(both),
        BendingMode::Orthotropic if both => Ok(true),
        BendingMode::Orthotropic => Err(FitError::Data(
            "--bending orthotropic needs a warp (90°) and a weft (0°) cantilever: they determine the two rigidities (use --bending paper to fit one thickness instead)".into(),
        )),
    }
}

/// Bending rigidity of a cantilever of overhang `l` draping `angle_deg`, by the D1388 formula.
fn d1388_rigidity(l: f64, angle_deg: f64, density: f64) -> f64 {
    let t = angle_deg.to_radians();
    let c = l * ((0.5 * t).cos() / (8.0 * t.tan())).cbrt();
    density * STANDARD_GRAVITY * c.powi(3)
}

/// Geometric mean of the D1388 rigidities of the bends cut at `angle`.
fn start_rigidity(bends: &[BendTest], angle: f64, density: f64) -> f64 {
    let logs: Vec<f64> = bends
        .iter()
        .filter(|b| along(b, angle))
        .map(|b| d1388_rigidity(b.overhang, b.drape_angle_deg, density).ln())
        .collect();
    (logs.iter().sum::<f64>() / logs.len().max(1) as f64).exp()
}

/// The D1388 rigidities of the warp and weft bends, the twist following them at the bias
/// `ratio`.
fn start_rigidities(bends: &[BendTest], density: f64, ratio: f64) -> BendingRigidity {
    let (w, f) = (
        start_rigidity(bends, 90.0, density),
        start_rigidity(bends, 0.0, density),
    );
    BendingRigidity {
        warp: w,
        weft: f,
        twist: twist_following(w, f, ratio),
    }
}

/// Warp and weft rigidities (and twist, with an off-axis bend) from the bend tests, from
/// material `m`.
pub(super) fn bending_stage(
    ctx: &Context,
    lab: &mut Lab,
    stats: &mut FitStats,
    m: &Fitted,
    level: (usize, usize),
) -> Result<BendFit, FitError> {
    let bends = &ctx.data.bend;
    let density = ctx.data.areal_density.unwrap_or(0.1);
    let ratio = bias_ratio(&m.law);
    let off_axis = bends.iter().any(|b| !along(b, 90.0) && !along(b, 0.0));
    let b0 = m
        .bending
        .unwrap_or_else(|| start_rigidities(bends, density, ratio));
    let mut rigs = lab.bend_rigs(ctx, m, bends, level)?;
    // p = ln(B/B⁰) for warp, weft and (off-axis bends only) twist
    let rigidity = Rigidity {
        b0,
        off_axis,
        ratio,
    };
    let n = rigidity.n();
    let law = m.law.clone();
    let mut p = vec![0.0; n];
    let opts = ctx.stage_options(level, 1e-14, bends.len());
    let mut problem = BendProblem {
        rigs: &mut rigs,
        bends,
        nlaw: law.params().len(),
        law,
        tau: m.thickness,
        rigidity,
        evals: 0,
        newton: 0,
        seen: super::uncertainty::Seen::new(),
    };
    let rep =
        minimize(&mut p, &opts, |q: &[f64], jac: bool| problem.eval(q, jac)).map_err(|source| {
            FitError::Scene {
                stage: format!("bending stage on {}×{}", level.0, level.1),
                source,
            }
        })?;
    let (evals, newton, seen) = (problem.evals, problem.newton, problem.seen);
    stats.record(Work::single_solves(evals, newton));
    let b = rigidity.at(&p);
    let (linearised, errors) = bending_errors(b, off_axis, &seen, &p, level);
    let angles = drape_angles(&mut rigs, stats, "the fitted rigidities", |rig| {
        rig.set_bending(Some(b));
        Ok(())
    })?;
    lab.keep_bend_rigs(bends, level, rigs);
    let line = format!(
        "bending stage, mesh {}×{}: B_warp = {:.4e}, B_weft = {:.4e}, B_twist = {:.4e} N·m ({}), rms relative angle error {:.3} % ({} evaluations, {})",
        lab.meshes.bend_level(level).0,
        lab.meshes.bend_level(level).1,
        b.warp,
        b.weft,
        b.twist,
        if off_axis { "fitted" } else { "assumed" },
        100.0 * (rep.objective / bends.len() as f64).sqrt(),
        rep.evaluations,
        rep.stop
    );
    Ok(BendFit {
        law: m.law.clone(),
        thickness: m.thickness,
        bending: Some(b),
        angles,
        linearised,
        errors,
        line,
        stage: "bending",
    })
}

/// The bending stage's linearisation and standard errors at its optimum p (rigidities `b`;
/// the twist assumed without an off-axis bend).
fn bending_errors(
    b: BendingRigidity,
    off_axis: bool,
    seen: &super::uncertainty::Seen,
    p: &[f64],
    level: (usize, usize),
) -> (Option<Linearised>, Vec<ParamError>) {
    let n = p.len();
    let names = ["bending_warp_n_m", "bending_weft_n_m", "bending_twist_n_m"];
    let values = [b.warp, b.weft, b.twist];
    let (linearised, mut errors) = bend_evidence(seen, p, level, &names[..n], &values[..n]);
    if !off_axis {
        errors.push(ParamError {
            name: names[2].into(),
            value: b.twist,
            std_error: None,
            basis: "assumed",
            determined: false,
        });
    }
    (linearised, errors)
}

/// The rigidities at the stage's variables p = ln(B/B⁰): warp, weft and, with an off-axis
/// bend, twist; without one the twist follows warp and weft at the bias ratio.
#[derive(Clone, Copy)]
struct Rigidity {
    b0: BendingRigidity,
    off_axis: bool,
    ratio: f64,
}

impl Rigidity {
    /// The number of variables.
    fn n(&self) -> usize {
        if self.off_axis {
            3
        } else {
            2
        }
    }

    fn at(&self, q: &[f64]) -> BendingRigidity {
        let b0 = self.b0;
        let (warp, weft) = (b0.warp * q[0].exp(), b0.weft * q[1].exp());
        let twist = if self.off_axis {
            b0.twist * q[2].exp()
        } else {
            twist_following(warp, weft, self.ratio)
        };
        BendingRigidity { warp, weft, twist }
    }
}

/// The bending stage's problem: the cantilevers solved at the rigidities of q, their relative
/// drape-angle errors and ∂/∂q, every evaluation remembered.
struct BendProblem<'a> {
    rigs: &'a mut Vec<BendRig>,
    bends: &'a [BendTest],
    law: Orthotropic,
    tau: f64,
    /// the law's parameter count (the rigidities' sensitivities follow its own)
    nlaw: usize,
    rigidity: Rigidity,
    evals: usize,
    newton: usize,
    seen: super::uncertainty::Seen,
}

impl BendProblem<'_> {
    fn eval(&mut self, q: &[f64], jac: bool) -> Result<Evaluation, SceneError> {
        let (law, tau, nlaw) = (&self.law, self.tau, self.nlaw);
        let (n, off_axis, ratio) = (
            self.rigidity.n(),
            self.rigidity.off_axis,
            self.rigidity.ratio,
        );
        let b = self.rigidity.at(q);
        let runs: Vec<Result<crate::scene::BendPoint, SceneError>> = self
            .rigs
            .par_iter_mut()
            .map(|rig| {
                rig.set_material(law, tau)?;
                rig.set_bending(Some(b));
                rig.run(jac)
            })
            .collect();
        let (mut r, mut j) = (Vec::new(), Vec::new());
        for (pt, t) in runs.into_iter().zip(self.bends) {
            let pt = pt?;
            self.evals += 1;
            self.newton += pt.report.iterations;
            r.push((pt.drape_angle_deg - t.drape_angle_deg) / t.drape_angle_deg);
            if jac {
                let d = &pt.dangle[nlaw + 1..nlaw + 4];
                let mut row = vec![b.warp * d[0], b.weft * d[1]];
                if off_axis {
                    row.push(b.twist * d[2]);
                } else {
                    // the twist follows warp and weft
                    let (tw, tf) = b.twist_rates(ratio);
                    row[0] += b.warp * tw * d[2];
                    row[1] += b.weft * tf * d[2];
                }
                j.push(row.iter().map(|v| v / t.drape_angle_deg).collect());
            }
        }
        let e = to_evaluation(r, j, n, jac);
        self.seen
            .push((q.to_vec(), e.residuals.clone(), e.jacobian.clone()));
        Ok(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_d1388_formula_gives_about_half_the_overhang_at_41_5_degrees() {
        // ASTM D1388: at θ = 41.5° the bending length is about half the overhang; Peirce's
        // formula gives 0.5093 l there (cos 20.75° / (8 tan 41.5°) = 0.1321, cube root), where
        // the heavy elastica has exactly l/2 at 41.4873°: the formula is a starting value only
        let b = d1388_rigidity(0.1, 41.5, 0.1);
        let c = (b / (0.1 * STANDARD_GRAVITY)).cbrt();
        assert!((c / 0.050932 - 1.0).abs() < 1e-5, "{c}");
    }

    #[test]
    fn orthotropic_bending_needs_warp_and_weft_bends() {
        let bend = |a: f64| BendTest {
            angle_deg: a,
            width: 0.025,
            overhang: 0.1,
            drape_angle_deg: 41.5,
        };
        let both = [bend(90.0), bend(0.0)];
        assert!(use_own_bending(BendingMode::Auto, &both).unwrap());
        assert!(!use_own_bending(BendingMode::Paper, &both).unwrap());
        assert!(!use_own_bending(BendingMode::Auto, &[bend(90.0)]).unwrap());
        assert!(use_own_bending(BendingMode::Orthotropic, &[bend(90.0), bend(45.0)]).is_err());
    }
}
