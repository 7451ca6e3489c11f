//! The corner pull (Clyde et al. 2017 Figure 5, bottom; Miguel et al. 2012): an L × L square
//! pulled apart along one diagonal by clips on two opposite corners, the rest of its edges free.
//!
//! Each clip is a c × c square at its corner that holds the fabric under it (every control
//! point whose rest position lies in it follows the clip rigidly). A point pin would be a
//! singular load: in a membrane the force at a given pin displacement falls to zero,
//! logarithmically, as the mesh is refined; a clip of finite size has a converged force. The
//! clips at (0, 0) and (L, L) move apart along the diagonal by δ in all (each by δ/2); the
//! force is dW/dδ, the reaction of the held points.

use super::frame::Deformed;
use super::sheet::{march, Sheet, SheetModel};
use super::SceneError;
use crate::material::FabricMaterial;
use crate::solve::{NewtonOptions, SolveReport};
use crate::tri::{TriMaterial, TriModel};
use crate::Vec3;

/// A corner pull set up to run.
#[derive(Clone, Debug)]
pub struct CornerPull {
    /// m
    pub side: f64,
    /// final stretch of the diagonal, δ / (L√2)
    pub stretch: f64,
    /// side of each corner clip, m
    pub clip: f64,
    pub steps: usize,
    /// faces each way
    pub mesh: usize,
    /// out-of-plane start offset as a fraction of the side, and its pattern (see
    /// [`Sheet::perturbation`])
    pub perturbation: f64,
    pub seed: u64,
    /// Hold every control point in the plane: the membrane response alone, no wrinkles.
    pub in_plane: bool,
    pub solver: NewtonOptions,
}

/// One row of a corner pull.
#[derive(Clone, Debug, PartialEq)]
pub struct PullPoint {
    /// δ, m
    pub displacement: f64,
    /// dW/dδ, N
    pub force: f64,
    pub report: SolveReport,
}

impl CornerPull {
    pub fn new(side: f64, stretch: f64) -> Self {
        Self {
            side,
            stretch,
            clip: side / 10.0,
            steps: 8,
            mesh: 10,
            perturbation: 1e-3,
            seed: 0,
            in_plane: false,
            solver: NewtonOptions::default(),
        }
    }

    pub fn run(&self, material: &FabricMaterial) -> Result<(Vec<PullPoint>, Deformed), SceneError> {
        self.check()?;
        self.run_on(Sheet::new(material, self.side, self.mesh)?)
    }

    /// [`CornerPull::run`] on a triangle model's sheet.
    pub fn run_tri(
        &self,
        material: &TriMaterial,
    ) -> Result<(Vec<PullPoint>, Deformed<TriModel>), SceneError> {
        self.check()?;
        self.run_on(Sheet::tri(material, self.side, self.mesh)?)
    }

    fn check(&self) -> Result<(), SceneError> {
        if !(self.stretch.is_finite() && self.stretch > 0.0 && self.stretch < 1.0) {
            return Err(SceneError::Input(format!(
                "stretch must be in (0, 1), got {}",
                crate::io::num(self.stretch)
            )));
        }
        super::positive("clip", self.clip)?;
        if self.clip >= self.side / 2.0 {
            return Err(SceneError::Input(format!(
                "the clips ({} mm) must be smaller than half the side ({} mm)",
                self.clip * 1e3,
                self.side * 1e3
            )));
        }
        Ok(())
    }

    fn run_on<M: SheetModel>(
        &self,
        sheet: Sheet<M>,
    ) -> Result<(Vec<PullPoint>, Deformed<M>), SceneError> {
        let rest = sheet.rest().to_vec();
        let (l, c, tol) = (self.side, self.clip, 1e-9 * self.side);
        // +1: the clip at (L, L), moving along +d; −1: the clip at (0, 0)
        let side_of = |p: &Vec3| {
            let inside = |a: f64, b: f64| (a..=b).contains(&p[0]) && (a..=b).contains(&p[1]);
            if inside(-tol, c + tol) {
                -1.0
            } else if inside(l - c - tol, l + tol) {
                1.0
            } else {
                0.0
            }
        };
        let held: Vec<usize> = (0..rest.len())
            .filter(|&v| side_of(&rest[v]) != 0.0)
            .flat_map(|v| 3 * v..3 * v + 3)
            .collect();
        let system = sheet.system(&held, self.in_plane)?;
        let lift = if self.in_plane {
            0.0
        } else {
            self.perturbation
        };
        let mut x = sheet.lifted(lift, self.seed);
        let total = self.stretch * l * std::f64::consts::SQRT_2;
        let unit = std::f64::consts::FRAC_1_SQRT_2;
        // ∂x/∂δ of each held DOF: ±½ along the diagonal
        let rate: Vec<(usize, f64)> = held
            .iter()
            .filter(|&&d| d % 3 < 2)
            .map(|&d| (d, 0.5 * unit * side_of(&rest[d / 3])))
            .collect();
        let place = |t: f64, d: usize| {
            let p = rest[d / 3];
            match d % 3 {
                2 => 0.0,
                c => p[c] + t * total * 0.5 * unit * side_of(&p),
            }
        };
        let mut points = Vec::new();
        let (counts, last) = march(
            &sheet.model,
            &system,
            &mut x,
            self.steps,
            &self.solver,
            &held,
            place,
            |t, x, report| {
                points.push(PullPoint {
                    displacement: t * total,
                    force: sheet.reaction(x, &rate)?,
                    report: report.clone(),
                });
                Ok(())
            },
        )?;
        Ok((points, Deformed::new(sheet, x, counts, last)))
    }
}
