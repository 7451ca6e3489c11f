//! The drape of Clyde et al. 2017 §6 (Figure 1): an L × L sheet (1 m) hanging under gravity from
//! its two top corners, which are brought from L apart to `span` (60 cm) apart.
//!
//! The sheet's rest state is the xy plane (warp along x); it hangs in the xz plane, its top edge
//! at z = 0 between the corners and a rest point (X, Y) at (X, 0, Y − L). Its weight comes on
//! first (load continuation, corners L apart, the sheet flat); then a small out-of-plane offset
//! w is added ([`super::sheet::Sheet::perturbation`]; a sheet whose corners come together
//! buckles, and the offset picks the branch) and the corners move together in equal steps. The corners
//! are pins: with the phantom rule the corner control point is the limit corner.
//!
//! The sheet has several stable equilibria; the run is deterministic for a given seed, and the
//! solver's stability check (positive definite reduced Hessian, saddles escaped) says whether
//! the one returned is stable.

use super::frame::Deformed;
use super::sheet::{march, Sheet, SheetModel};
use super::SceneError;
use crate::assembly::STANDARD_GRAVITY;
use crate::material::FabricMaterial;
use crate::solve::{continuation, ContinuationReport, NewtonOptions, SolveReport};
use crate::tri::{TriMaterial, TriModel};
use crate::Vec3;

/// A drape set up to run.
#[derive(Clone, Debug)]
pub struct Drape {
    /// m
    pub side: f64,
    /// final distance between the held corners, m
    pub span: f64,
    /// steps of the corners' approach
    pub steps: usize,
    /// faces each way
    pub mesh: usize,
    /// out-of-plane start offset as a fraction of the side, and its pattern
    pub perturbation: f64,
    pub seed: u64,
    pub solver: NewtonOptions,
}

/// What a drape measures, m (from the limit surface sampled 4 × 4 per face).
#[derive(Clone, Debug, PartialEq)]
pub struct DrapeShape {
    /// How far the lowest point hangs below the corners.
    pub drop: f64,
    /// Front-to-back extent (along y, across the plane of the corners): the depth of the folds.
    pub depth: f64,
    /// Side-to-side extent (along x).
    pub width: f64,
    /// How far the sheet's centre of mass hangs below the corners: Σ wᵢ zᵢ / Σ wᵢ over the
    /// nodes' weights wᵢ (the consistent gravity load; lumped for a triangle model, which is
    /// exact for its linear interpolation), i.e. the drape's potential energy per unit weight.
    /// Unlike the fold depth, this is the same on the different branches a drape can take.
    pub mean_drop: f64,
    /// The last solve.
    pub report: SolveReport,
}

impl Drape {
    pub fn new() -> Self {
        Self {
            side: 1.0,
            span: 0.6,
            steps: 8,
            mesh: 8,
            perturbation: 1e-2,
            seed: 0,
            solver: NewtonOptions::default(),
        }
    }

    pub fn run(&self, material: &FabricMaterial) -> Result<(DrapeShape, Deformed), SceneError> {
        self.check()?;
        self.run_on(Sheet::new(material, self.side, self.mesh)?)
    }

    /// [`Drape::run`] on a triangle model's sheet.
    pub fn run_tri(
        &self,
        material: &TriMaterial,
    ) -> Result<(DrapeShape, Deformed<TriModel>), SceneError> {
        self.check()?;
        self.run_on(Sheet::tri(material, self.side, self.mesh)?)
    }

    fn check(&self) -> Result<(), SceneError> {
        if !(self.span.is_finite() && self.span > 0.0 && self.span <= self.side) {
            return Err(SceneError::Input(format!(
                "the corners' span must be in (0, side], got {} m for a {} m sheet",
                crate::io::num(self.span),
                crate::io::num(self.side)
            )));
        }
        Ok(())
    }

    fn run_on<M: SheetModel>(
        &self,
        mut sheet: Sheet<M>,
    ) -> Result<(DrapeShape, Deformed<M>), SceneError> {
        let (n, l) = (self.mesh, self.side);
        let corners = [sheet.node(0, n), sheet.node(n, n)];
        let held: Vec<usize> = corners.iter().flat_map(|&v| 3 * v..3 * v + 3).collect();
        let system = sheet.system(&held, false)?;
        let bump = sheet.perturbation(self.seed);
        // the weight comes on with the sheet flat (an in-plane problem); the offset is added
        // ahead of the corners' move: on a vertical sheet with no load the turn about the line
        // of the pins costs nothing, and a curved start makes Newton crawl (16 × 16 fails at
        // a load factor of 1e-4)
        let mut x: Vec<Vec3> = sheet.rest().iter().map(|p| [p[0], 0.0, p[1] - l]).collect();
        let mut counts = super::sheet::SolveCounts::default();
        let weight = self.hang(&mut sheet, &system, &mut x)?;
        counts.steps += weight.steps.max(1);
        counts.iterations += weight.iterations;
        counts.factorizations += weight.factorizations;
        counts.backward_euler_steps += weight.last.backward_euler_steps;
        counts.fallbacks = weight.last.fallbacks.clone();
        counts.curvature_steps += weight.last.curvature_steps;
        counts.convexified_steps += weight.last.convexified_steps;
        for (p, b) in x.iter_mut().zip(&bump) {
            p[1] += self.perturbation * l * b;
        }
        let inward = (l - self.span) / 2.0;
        let place = |t: f64, d: usize| {
            let sign = if d / 3 == corners[0] { 1.0 } else { -1.0 };
            let start = if d / 3 == corners[0] { 0.0 } else { l };
            match d % 3 {
                0 => start + sign * t * inward,
                _ => 0.0,
            }
        };
        let (more, last) = march(
            &sheet.model,
            &system,
            &mut x,
            self.steps,
            &self.solver,
            &held,
            place,
            |_, _, _| Ok(()),
        )?;
        counts.merge(&more);
        let shape = measure(&sheet, &x, last.clone())?;
        Ok((shape, Deformed::new(sheet, x, counts, last)))
    }
}

impl Default for Drape {
    fn default() -> Self {
        Self::new()
    }
}

impl Drape {
    /// Brings the weight on: the whole load by Newton with the backward-Euler fallback (a
    /// pseudo-time relaxation where the Hessian is indefinite: the flat sheet's top edge is in
    /// compression between the pins), then, if that fails, load continuation.
    fn hang<M: SheetModel>(
        &self,
        sheet: &mut Sheet<M>,
        system: &crate::solve::FreeSystem,
        x: &mut Vec<Vec3>,
    ) -> Result<ContinuationReport, SceneError> {
        sheet.model.set_gravity([0.0, 0.0, -STANDARD_GRAVITY]);
        let mut trial = x.clone();
        if let Ok(last) = crate::solve::newton(&sheet.model, system, &mut trial, &self.solver) {
            *x = trial;
            return Ok(ContinuationReport {
                steps: 1,
                iterations: last.iterations,
                factorizations: last.factorizations,
                last,
            });
        }
        let apply = |m: &mut M, t: f64, _: &[Vec3]| {
            m.set_gravity([0.0, 0.0, -STANDARD_GRAVITY * t]);
        };
        continuation(&mut sheet.model, system, x, &self.solver, 1.0, apply).map_err(
            |(t, source)| SceneError::Solve {
                stage: format!("weight at load factor {t:.4}"),
                source,
            },
        )
    }
}

fn measure<M: SheetModel>(
    sheet: &Sheet<M>,
    x: &[Vec3],
    report: SolveReport,
) -> Result<DrapeShape, SceneError> {
    let samples = M::surface(sheet, x, 4)?;
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &samples.positions {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    // the centre of mass from the nodes' weights (gravity along −z)
    let (moment, total) = sheet
        .model
        .external_load()
        .iter()
        .zip(x)
        .fold((0.0, 0.0), |(m, w), (f, p)| (m + f[2] * p[2], w + f[2]));
    Ok(DrapeShape {
        drop: -lo[2],
        depth: hi[1] - lo[1],
        width: hi[0] - lo[0],
        mean_drop: if total != 0.0 {
            -moment / total
        } else {
            f64::NAN
        },
        report,
    })
}
