//! The mesh check: how much the fitted parameters and curves would change if the last mesh
//! level were refined once more (`[fit]` `mesh_change`).
//!
//! Refitting on the finer mesh would cost the whole last level again, several times over. The
//! check instead takes one Gauss–Newton step of that refit from the fitted parameters, stage
//! by stage, as the fit itself is staged: every fitted strip and bend is solved once on the
//! finer mesh at the fitted material, giving the change Δr of the stage's residuals r (the
//! weighted relative force errors, or the relative drape-angle errors) that the refinement
//! causes; at the optimum Jᵀr = 0, so the refit moves the stage's variables by
//!
//! δ = −(JᵀJ)⁻¹ Jᵀ Δr
//!
//! to first order, with J the stage's Jacobian at the optimum (already computed for the
//! standard errors), and the physical parameters by G δ (G = their Jacobian in the variables).
//! The fitted curves then change by Δr + J δ (relative, per point, unweighted). This is the
//! defect correction of multigrid read backwards: the fine level's defect Δr, carried into the
//! coarse level's linearisation. It is exact for a linear model and, like any first-order
//! estimate, trustworthy while the change is small, which is the case it is there to certify;
//! a large estimate says "refine", whatever its exact size.
//!
//! `mesh_change` is the largest relative change of a parameter the data determine (see
//! [`super::uncertainty`]): an undetermined exponent can move by any amount without any curve
//! noticing, and the curves' change says that.

mod notes;

use super::rigs::Lab;
use super::{Bench, Context, FitError, Fitted, Work};
use crate::material::{BendingRigidity, Orthotropic};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// A mesh-independent fit moves no determined parameter by this much (relative) or more on
/// the finer mesh: 1 %.
pub const MESH_PARAM_TOL: f64 = 0.01;
/// ... and no fitted curve by this much (mean relative force change) or more: 0.3 %.
pub const MESH_CURVE_TOL: f64 = 3e-3;
/// ... and no drape angle by this many degrees or more: 0.1°.
pub const MESH_ANGLE_TOL_DEG: f64 = 0.1;

/// The parameter and curve rules in words, as the notes print them ("1 % and 0.3 %").
pub(super) fn rules_in_words() -> String {
    format!(
        "{:.0} % and {:.1} %",
        100.0 * MESH_PARAM_TOL,
        100.0 * MESH_CURVE_TOL
    )
}

/// Where the check solves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum MeshCheckMode {
    /// no check
    Off,
    /// on the mesh half as fine as the last level, the defect carried to the next finer
    /// mesh at the order p of [`order`]: Δr(L → 2L) = −Δr(L → L/2)/2^p (Richardson)
    #[default]
    Coarse,
    /// on the mesh twice as fine as the last level: solved there, several times the cost
    Fine,
}

/// Convergence order the coarse check assumes for the strips' residuals: the slowest measured
/// on the fit's strips, so that the estimate errs on the large side. Graded cages
/// ([`crate::scene::STRIP_GRADING`]): 2 (the 45° strip converges at 2.1–2.6 on them, `cargo
/// run --release --example graded_strip`; with the yarn terms on the face centres at 2.0 from
/// 16 × 24 to 64 × 96 at yarn-to-shear ratios of 50 and 200,
/// `paper_repro/convergence/stiff_bias/yarn_rules.md`); uniform cages: 1.2 (the 45° strip's
/// clamped corners, `paper_repro/convergence/tensile_45.txt`: 1.2–1.3). Nearly inextensible
/// yarns on the face centres ([`crate::assembly::YarnRule::Centre`] at a yarn-to-shear
/// `ratio` of [`STIFF_FROM_RATIO`] or more, or unknown): 0.8 (a ratio-1000 bias strip
/// converges at 0.6–0.9 on graded cages, `paper_repro/convergence/stiff_bias`).
pub fn order(
    grading: crate::mesh::Grading,
    yarns: crate::assembly::YarnRule,
    ratio: Option<f64>,
) -> f64 {
    let stiff = ratio.is_none_or(|r| r >= STIFF_FROM_RATIO);
    if yarns == crate::assembly::YarnRule::Centre && stiff {
        0.8
    } else if grading.across >= 0.5 && grading.along >= 0.5 {
        2.0
    } else {
        1.2
    }
}

/// The yarn-to-shear ratio from which [`order`] takes the slow order of nearly inextensible
/// yarns: the order is 2.0 up to 200, 0.6–0.9 at 1000.
pub const STIFF_FROM_RATIO: f64 = 200.0;

/// What a stage fitted, for the check.
#[derive(Clone, Debug)]
pub(super) enum Probe {
    /// a tensile stage over these strips (each strip's used curves, in order)
    Tensile(Vec<usize>),
    /// the thickness or bending stage over the bend tests
    Bends,
}

/// A stage's linearisation at its optimum.
#[derive(Clone, Debug)]
pub(super) struct Linearised {
    pub probe: Probe,
    /// the stage's direction (tensile) or `None` (bends)
    pub dir: Option<super::map::Direction>,
    pub level: (usize, usize),
    /// ∂r/∂p
    pub j: DMatrix<f64>,
    /// points per curve (one per bend)
    pub lens: Vec<usize>,
    /// the physical parameters (then, for a tensile stage, its law's tangent stiffness
    /// across the tested range), their values and ∂/∂p
    pub names: Vec<String>,
    pub values: Vec<f64>,
    pub dg: DMatrix<f64>,
    /// which of them `mesh_change` covers: not η's μ and α one by one, which trade off
    /// against each other where only their sum is tested (the tangents cover them), nor a
    /// coupled shear's factors exp(κ ê), which trade off against η₄'s stiffening along the
    /// strips' paths (the off-axis stresses of [`super::uncertainty::offaxis_rows`] cover them)
    pub counts: Vec<bool>,
}

impl Linearised {
    /// A tensile stage's, at its optimum `p`; `offaxis`: a coupled shear stage's off-axis
    /// stresses ([`super::uncertainty::offaxis_rows`]).
    #[allow(clippy::too_many_arguments)]
    pub fn tensile(
        map: &super::map::StageMap,
        p: &[f64],
        law: &crate::material::Orthotropic,
        strips: &[usize],
        level: (usize, usize),
        j: &DMatrix<f64>,
        lens: &[usize],
        offaxis: Option<(Vec<String>, Vec<f64>, DMatrix<f64>)>,
    ) -> Self {
        let (mut names, mut values, dg) = super::uncertainty::physical_rows(map, p, law);
        let (rn, rv, rg) = super::uncertainty::response_rows(map, p, law);
        let mut counts: Vec<bool> = names.iter().map(|n| n.ends_with("_pa")).collect();
        counts.extend(rn.iter().map(|n| !n.contains("_coupling_factor_")));
        names.extend(rn);
        values.extend(rv);
        let (on, ov, og) =
            offaxis.unwrap_or_else(|| (Vec::new(), Vec::new(), DMatrix::zeros(0, 0)));
        counts.extend(on.iter().map(|_| true));
        names.extend(on);
        values.extend(ov);
        let rows = [dg.nrows(), rg.nrows(), og.nrows()];
        let mut all = DMatrix::zeros(rows.iter().sum(), dg.ncols());
        all.rows_mut(0, rows[0]).copy_from(&dg);
        all.rows_mut(rows[0], rows[1]).copy_from(&rg);
        if rows[2] > 0 {
            all.rows_mut(rows[0] + rows[1], rows[2]).copy_from(&og);
        }
        Self {
            probe: Probe::Tensile(strips.to_vec()),
            dir: Some(map.dir),
            level,
            j: j.clone(),
            lens: lens.to_vec(),
            names,
            values,
            dg: all,
            counts,
        }
    }

    /// The thickness or bending stage's: parameters fitted as logarithms.
    pub fn bends(level: (usize, usize), j: &DMatrix<f64>, names: &[&str], values: &[f64]) -> Self {
        Self {
            probe: Probe::Bends,
            dir: None,
            level,
            j: j.clone(),
            lens: vec![1; j.nrows()],
            names: names.iter().map(|n| n.to_string()).collect(),
            values: values.to_vec(),
            dg: DMatrix::from_diagonal(&DVector::from_column_slice(values)),
            counts: vec![true; values.len()],
        }
    }
}

/// The check's outcome.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshCheck {
    /// the finer mesh the check is about (of a 50 × 75 mm strip)
    pub mesh: (usize, usize),
    /// the mesh it solved on: `mesh` itself, or the one half as fine as the last level
    pub solved_on: (usize, usize),
    /// largest relative change of a determined stiffness, thickness, rigidity or tangent
    /// stiffness of the law across the tested range, and its name
    pub change: f64,
    pub parameter: String,
    /// every counted quantity's signed relative change
    pub changes: Vec<(String, f64)>,
    /// largest relative change of η's μ and α one by one (not part of `change`), and which
    pub law_change: f64,
    pub law_parameter: String,
    /// largest mean relative change of a fitted curve, and which (file name)
    pub curve_change: f64,
    pub curve: String,
    /// largest change of a fitted drape angle after the refit, degrees (bends only)
    pub angle_change_deg: Option<f64>,
}

/// δ = −(JᵀJ)⁻¹ Jᵀ Δr, or `None` where JᵀJ is singular.
fn gauss_newton_step(j: &DMatrix<f64>, dr: &[f64]) -> Option<DVector<f64>> {
    let dr = DVector::from_column_slice(dr);
    let jtj = j.transpose() * j;
    let rhs = -(j.transpose() * dr);
    jtj.cholesky().map(|c| c.solve(&rhs))
}

impl MeshCheck {
    /// A check about `mesh`, solved on `solved_on`, with nothing changed yet.
    fn empty(mesh: (usize, usize), solved_on: (usize, usize)) -> Self {
        MeshCheck {
            mesh,
            solved_on,
            change: 0.0,
            parameter: String::new(),
            changes: Vec::new(),
            law_change: 0.0,
            law_parameter: String::new(),
            curve_change: 0.0,
            curve: String::new(),
            angle_change_deg: None,
        }
    }

    /// Takes in a stage's curves after its refit, Δr + J δ (unweighted, curve by curve):
    /// the largest mean change of a tensile curve (`labels` name them), the largest drape
    /// angle change of a bend (`scale`: the target angles).
    fn curves_after(
        &mut self,
        lin: &Linearised,
        dr: &[f64],
        delta: &DVector<f64>,
        labels: &[String],
        scale: &[f64],
    ) {
        let after = DVector::from_column_slice(dr) + &lin.j * delta;
        let mut k = 0;
        for (c, &n) in lin.lens.iter().enumerate() {
            let w = match lin.probe {
                Probe::Tensile(_) => 1.0 / (n as f64).sqrt(),
                Probe::Bends => 1.0,
            };
            let mean = after.rows(k, n).iter().map(|v| v.abs()).sum::<f64>() / (w * n as f64);
            match lin.probe {
                Probe::Tensile(_) if mean > self.curve_change => {
                    self.curve_change = mean;
                    self.curve = labels[c].clone();
                }
                Probe::Bends => {
                    let deg = mean * scale[c];
                    let a = self.angle_change_deg.get_or_insert(0.0);
                    *a = a.max(deg);
                }
                _ => {}
            }
            k += n;
        }
    }

    /// Takes in every parameter's relative change (name, change, counted in `change`).
    fn take_changes(&mut self, changes: Vec<(String, f64, bool)>) {
        // the thickness stage rescales every membrane stiffness by τ⁰/τ (a·τ kept): to first
        // order their relative changes lose the thickness's
        let tau = changes
            .iter()
            .find(|c| c.0 == "thickness_mm")
            .map_or(0.0, |c| c.1);
        for (name, rel, counted) in changes {
            let rel = if name.ends_with("_pa") || name.contains("_tangent_at_") {
                rel - tau
            } else {
                rel
            };
            if counted && rel.abs() > self.change {
                self.change = rel.abs();
                self.parameter = name.clone();
            }
            if !counted && rel.abs() > self.law_change {
                self.law_change = rel.abs();
                self.law_parameter = name.clone();
            }
            self.changes.push((name, rel));
        }
    }

    /// The criterion of a mesh-independent fit: no determined parameter moves by 1 %, no
    /// fitted curve by 0.3 %, no drape angle by 0.1°.
    pub fn passes(&self) -> bool {
        self.change < MESH_PARAM_TOL
            && self.curve_change < MESH_CURVE_TOL
            && self.angle_change_deg.is_none_or(|a| a < MESH_ANGLE_TOL_DEG)
    }

    /// The largest change of a stage's determined quantities (its stiffness and its law's
    /// tangent stiffness across the tested range, as the membrane's a·τ).
    pub(super) fn stage_change(&self, dir: super::map::Direction) -> f64 {
        use super::map::Direction;
        let (stiffness, prefix) = match dir {
            Direction::Warp => ("a11_pa", "warp_"),
            Direction::Weft => ("a22_pa", "weft_"),
            Direction::Shear => ("g12_pa", "bias_"),
        };
        // the stage's own change: the thickness's rescaling of a (a·τ kept) added back, as
        // the stage fits a·τ; a stage the check did not see counts as changed
        let tau = self
            .changes
            .iter()
            .find(|(n, _)| n == "thickness_mm")
            .map_or(0.0, |(_, c)| *c);
        self.changes
            .iter()
            .filter(|(n, _)| {
                n == stiffness
                    || (n.starts_with(prefix)
                        && (n.contains("_tangent_at_") || n.contains("_stress_")))
            })
            // the off-axis stresses are forces: the thickness's rescaling never entered them
            .map(|(n, c)| {
                if n.contains("_stress_") {
                    c.abs()
                } else {
                    (c + tau).abs()
                }
            })
            .reduce(f64::max)
            .unwrap_or(f64::INFINITY)
    }

    /// The same check carried one level finer at convergence order `q` (every change
    /// divided by 2^q).
    pub fn next_level(&self, q: f64) -> Self {
        let k = 2f64.powf(-q);
        let mut m = self.clone();
        m.mesh = (2 * self.mesh.0, 2 * self.mesh.1);
        m.change *= k;
        m.law_change *= k;
        m.curve_change *= k;
        m.angle_change_deg = m.angle_change_deg.map(|a| a * k);
        for c in &mut m.changes {
            c.1 *= k;
        }
        m
    }
}

/// The convergence order the fit's estimates of its strips' mesh errors assume ([`order`] for
/// its grading, the lab's yarn rule and the fitted law's yarn-to-shear ratio).
pub(super) fn mesh_order(lab: &Lab, ctx: &Context, m: &Fitted) -> f64 {
    let ratio = crate::material::Law::yarn_shear_ratio(&m.law);
    order(ctx.opts.grading, lab.yarns(), ratio)
}

impl Bench<'_, '_> {
    /// The tensile stages' latest linearisations at `law`'s final degrees, then the bend
    /// stage's, all on `level`.
    fn final_linearisations(&self, law: &Orthotropic, level: (usize, usize)) -> Vec<Linearised> {
        use super::map::Direction;
        let mut out = Vec::new();
        for dir in [Direction::Warp, Direction::Weft, Direction::Shear] {
            let degree = match dir {
                Direction::Warp => law.warp.degree(),
                Direction::Weft => law.weft.degree(),
                Direction::Shear => law.shear.degree(),
            };
            // the stage's linearisation on `level`, or on the coarser level of its last fit
            // (a stage the ladder did not refit)
            let found = self.evidence.linearised.iter().rev().find(|l| {
                l.dir == Some(dir)
                    && l.level.0 <= level.0
                    && l.names.iter().filter(|n| n.contains("_alpha_")).count() == degree
            });
            out.extend(found.cloned());
        }
        let bends = self.evidence.linearised.iter().rev();
        out.extend(
            bends
                .filter(|l| matches!(l.probe, Probe::Bends) && l.level == level)
                .take(1)
                .cloned(),
        );
        out
    }

    /// Drape angles of every bend test on `level` at material `m`.
    fn drape_angles(&mut self, m: &Fitted, level: (usize, usize)) -> Result<Vec<f64>, FitError> {
        let data = self.ctx.data;
        let mut rigs = self.lab.bend_rigs(self.ctx, m, &data.bend, level)?;
        let (law, tau, bending): (_, _, Option<BendingRigidity>) =
            (m.law.clone(), m.thickness, m.bending);
        let runs: Vec<_> = rigs
            .par_iter_mut()
            .map(|rig| {
                rig.set_material(&law, tau)?;
                rig.set_bending(bending);
                rig.run(false)
                    .map(|p| (p.drape_angle_deg, p.report.iterations))
            })
            .collect();
        self.stats.record(Work {
            evaluations: runs.len(),
            ..Work::default()
        });
        self.lab.keep_bend_rigs(&data.bend, level, rigs);
        let runs: Vec<(f64, usize)> =
            runs.into_iter()
                .collect::<Result<Vec<_>, _>>()
                .map_err(|source| FitError::Scene {
                    stage: format!("mesh check: the cantilevers on {}×{}", level.0, level.1),
                    source,
                })?;
        self.stats.record(Work {
            evaluations: 0,
            equilibria: runs.len(),
            newton_iterations: runs.iter().map(|r| r.1).sum(),
            ..Work::default()
        });
        Ok(runs.into_iter().map(|r| r.0).collect())
    }

    /// The refit change of material `m` from `from` to the mesh twice as fine, solved there
    /// (the ladder's test of whether that level is needed); `None` when no stage has a
    /// linearisation.
    pub(super) fn refit_change(
        &mut self,
        m: &Fitted,
        from: (usize, usize),
    ) -> Result<Option<MeshCheck>, FitError> {
        let errors = self.evidence.final_uncertainty(&m.law);
        let determined = |name: &str| {
            errors
                .iter()
                .find(|e| e.name == name)
                .is_none_or(|e| e.determined)
        };
        self.mesh_check(m, from, MeshCheckMode::Fine, &determined)
    }

    /// The mesh check of material `m` fitted on `last` (see the module doc); `determined`
    /// says which parameters count.
    pub(super) fn mesh_check(
        &mut self,
        m: &Fitted,
        last: (usize, usize),
        mode: MeshCheckMode,
        determined: &dyn Fn(&str) -> bool,
    ) -> Result<Option<MeshCheck>, FitError> {
        let lins = self.final_linearisations(&m.law, last);
        let coarse = ((last.0 / 2).max(1), (last.1 / 2).max(1));
        if lins.is_empty() || mode == MeshCheckMode::Off || coarse == last {
            return Ok(None);
        }
        let finer = (2 * last.0, 2 * last.1);
        // the defect towards the solved mesh, and the factor that makes it the one to `finer`
        let (solved_on, factor) = match mode {
            MeshCheckMode::Fine => (finer, 1.0),
            _ => (coarse, -(2f64.powf(-mesh_order(self.lab, self.ctx, m)))),
        };
        self.journal.say(&format!(
            "mesh check: every fitted strip and bend again on {}x{}",
            solved_on.0, solved_on.1
        ));
        let mut out = MeshCheck::empty(finer, solved_on);
        // (name, relative change, counted in `change`)
        let mut changes: Vec<(String, f64, bool)> = Vec::new();
        for lin in &lins {
            let (dr, labels, scale) = match &lin.probe {
                Probe::Tensile(strips) => self.tensile_defect(m, strips, last, solved_on)?,
                Probe::Bends => self.bend_defect(m, lin, solved_on, factor, &changes)?,
            };
            let dr: Vec<f64> = match lin.probe {
                Probe::Tensile(_) => dr.iter().map(|v| factor * v).collect(),
                Probe::Bends => dr,
            };
            if dr.len() != lin.j.nrows() {
                continue;
            }
            let Some(delta) = gauss_newton_step(&lin.j, &dr) else {
                continue;
            };
            let dphys = &lin.dg * &delta;
            for (k, name) in lin.names.iter().enumerate() {
                let rel = dphys[k] / lin.values[k];
                let counted = lin.counts[k] && determined(name);
                if rel.is_finite() && (counted || !lin.counts[k]) {
                    changes.push((name.clone(), rel, lin.counts[k]));
                }
            }
            out.curves_after(lin, &dr, &delta, &labels, &scale);
        }
        out.take_changes(changes);
        Ok(Some(out))
    }

    /// Δr of the bends' relative drape-angle errors from the last level to `solved_on` (times
    /// `factor`), with a label per bend and the target angles; a thickness stage's carries the
    /// membrane stiffnesses' `changes` so far (the tensile stages move a·τ).
    #[allow(clippy::type_complexity)]
    fn bend_defect(
        &mut self,
        m: &Fitted,
        lin: &Linearised,
        solved_on: (usize, usize),
        factor: f64,
        changes: &[(String, f64, bool)],
    ) -> Result<(Vec<f64>, Vec<String>, Vec<f64>), FitError> {
        let at_last = self.evidence.bend_angles.clone();
        let fine = self.drape_angles(m, solved_on)?;
        let targets: Vec<f64> = self
            .ctx
            .data
            .bend
            .iter()
            .map(|b| b.drape_angle_deg)
            .collect();
        let mut dr: Vec<f64> = (0..fine.len())
            .map(|k| factor * (fine[k] - at_last[k]) / targets[k])
            .collect();
        if lin.names == ["thickness_mm"] {
            // the paper's section: a bend's rigidity is (a·τ)·τ²/12, and the tensile
            // stages move a·τ; J is ∂r/∂ln τ at fixed a·τ, i.e. 2 ∂r/∂ln B
            let of = |key: &str| changes.iter().find(|c| c.0 == key).map_or(0.0, |c| c.1);
            let (warp, weft) = (of("a11_pa"), of("a22_pa"));
            for (k, b) in self.ctx.data.bend.iter().enumerate().take(dr.len()) {
                let moved = if (b.angle_deg - 90.0).abs() < 1e-9 {
                    warp
                } else if b.angle_deg.abs() < 1e-9 {
                    weft
                } else {
                    0.5 * (warp + weft)
                };
                dr[k] += 0.5 * lin.j[(k, 0)] * moved;
            }
        }
        let labels = self
            .ctx
            .data
            .bend
            .iter()
            .map(|b| format!("bend {}°", b.angle_deg));
        Ok((dr, labels.collect(), targets))
    }

    /// Δr of the tensile residuals over `strips` from `last` to `finer` at material `m`, with
    /// a label per curve and the curves' point counts.
    #[allow(clippy::type_complexity)]
    fn tensile_defect(
        &mut self,
        m: &Fitted,
        strips: &[usize],
        last: (usize, usize),
        finer: (usize, usize),
    ) -> Result<(Vec<f64>, Vec<String>, Vec<f64>), FitError> {
        let jobs: Vec<(usize, f64)> = strips
            .iter()
            .map(|&s| (s, self.ctx.prep.strips[s].angle_deg))
            .collect();
        let (coarse, fine) =
            self.lab
                .predict_pair(self.ctx, m, self.stats, &jobs, (last, finer))?;
        let (mut dr, mut labels) = (Vec::new(), Vec::new());
        for (i, &s) in strips.iter().enumerate() {
            for c in self.ctx.used_curves(&[s]) {
                let (a, b) = (
                    self.ctx.curve_forces(c, &coarse[i]),
                    self.ctx.curve_forces(c, &fine[i]),
                );
                let points = &self.ctx.prep.curves[c].points;
                let w = 1.0 / (points.len() as f64).sqrt();
                for ((pt, fa), fb) in points.iter().zip(&a).zip(&b) {
                    // a point excluded on either mesh (a saddle) has no defect to carry
                    let d = w * self.ctx.prep.misfit.change(*fa, *fb, pt.1);
                    dr.push(if d.is_finite() { d } else { 0.0 });
                }
                let test = self.ctx.prep.curves[c].test;
                labels.push(self.ctx.data.tensile[test].curve.display().to_string());
            }
        }
        Ok((dr, labels, Vec::new()))
    }
}

#[cfg(test)]
mod tests;
