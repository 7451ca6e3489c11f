//! The picture-frame shear test (Clyde et al. 2017 Figure 5, top): an L × L square whose four
//! edges a pin-jointed frame holds, warp and weft along the frame's arms, the frame sheared to γ.
//!
//! The frame maps a rest point X to F(γ) X with F = [[1, sin γ], [0, cos γ]]: the bottom arm
//! stays, the side arms turn by γ about their lower pins (the usual symmetric frame up to a
//! rigid turn, which changes no force). A sheet that follows the frame has the Green strain
//! Ẽ₁₁ = Ẽ₂₂ = 0, Ẽ₁₂ = sin γ / 2: pure shear. The frame's moment M = dW/dγ is the
//! reaction on the held edges; the shear force is F_s = M / (L cos γ) and the force along the
//! frame's pulled diagonal F = M / (L sin(α/2)), α = 90° − γ the corner angle (so F_s =
//! F / (2 cos(α/2)), the normalisation of Harrison, Clifford & Long 2004).

use super::sheet::{march, Sheet, SheetModel, SolveCounts};
use super::SceneError;
use crate::assembly::ShellModel;
use crate::material::FabricMaterial;
use crate::solve::{NewtonOptions, SolveReport};
use crate::tri::{TriMaterial, TriModel};
use crate::Vec3;

/// A picture-frame test set up to run.
#[derive(Clone, Debug)]
pub struct PictureFrame {
    /// m
    pub side: f64,
    /// final shear angle, degrees
    pub shear_deg: f64,
    /// equal angle steps (rows reported)
    pub steps: usize,
    /// faces each way
    pub mesh: usize,
    /// out-of-plane start offset, as a fraction of the side, and its pattern
    /// ([`Sheet::perturbation`]): a sheet in shear wrinkles, and a perfectly flat one stays on
    /// the flat (unstable) branch
    pub perturbation: f64,
    pub seed: u64,
    /// Hold every control point in the plane: the membrane response alone, which is the
    /// homogeneous shear above at every angle (a frame with anti-wrinkling plates). Off by
    /// default: a free sheet wrinkles, and carries less.
    pub in_plane: bool,
    pub solver: NewtonOptions,
}

/// One row of a frame test.
#[derive(Clone, Debug, PartialEq)]
pub struct FramePoint {
    pub shear_deg: f64,
    /// dW/dγ, N·m
    pub moment: f64,
    /// N
    pub shear_force: f64,
    /// N, along the pulled diagonal
    pub axial_force: f64,
    pub report: SolveReport,
}

/// A scene's final shape and what the solver did.
pub struct Deformed<M = ShellModel> {
    pub sheet: Sheet<M>,
    pub x: Vec<Vec3>,
    pub counts: SolveCounts,
    /// The final equilibrium's reduced Hessian is positive definite.
    pub stable: bool,
    /// The final solve.
    pub last: SolveReport,
}

impl<M> Deformed<M> {
    pub fn new(sheet: Sheet<M>, x: Vec<Vec3>, counts: SolveCounts, last: SolveReport) -> Self {
        Self {
            sheet,
            x,
            counts,
            stable: last.stable,
            last,
        }
    }
}

impl PictureFrame {
    pub fn new(side: f64, shear_deg: f64) -> Self {
        Self {
            side,
            shear_deg,
            steps: 8,
            mesh: 8,
            perturbation: 1e-3,
            seed: 0,
            in_plane: false,
            solver: NewtonOptions::default(),
        }
    }

    pub fn run(
        &self,
        material: &FabricMaterial,
    ) -> Result<(Vec<FramePoint>, Deformed), SceneError> {
        self.check()?;
        self.run_on(Sheet::new(material, self.side, self.mesh)?)
    }

    /// [`PictureFrame::run`] on a triangle model's sheet.
    pub fn run_tri(
        &self,
        material: &TriMaterial,
    ) -> Result<(Vec<FramePoint>, Deformed<TriModel>), SceneError> {
        self.check()?;
        self.run_on(Sheet::tri(material, self.side, self.mesh)?)
    }

    fn check(&self) -> Result<(), SceneError> {
        if !(self.shear_deg.is_finite() && self.shear_deg.abs() < 89.0) {
            return Err(SceneError::Input(format!(
                "shear angle must be within ±89°, got {}",
                crate::io::num(self.shear_deg)
            )));
        }
        Ok(())
    }

    fn run_on<M: SheetModel>(
        &self,
        sheet: Sheet<M>,
    ) -> Result<(Vec<FramePoint>, Deformed<M>), SceneError> {
        let held: Vec<usize> = sheet
            .boundary()
            .iter()
            .flat_map(|&v| 3 * v..3 * v + 3)
            .collect();
        let system = sheet.system(&held, self.in_plane)?;
        let rest = sheet.rest().to_vec();
        let lift = if self.in_plane {
            0.0
        } else {
            self.perturbation
        };
        let mut x = sheet.lifted(lift, self.seed);
        let gamma = |t: f64| (t * self.shear_deg).to_radians();
        let place = |t: f64, d: usize| {
            let (p, g) = (rest[d / 3], gamma(t));
            match d % 3 {
                0 => p[0] + p[1] * g.sin(),
                1 => p[1] * g.cos(),
                _ => 0.0,
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
                let g = gamma(t);
                // ∂(F X)/∂γ on the held DOFs
                let rate: Vec<(usize, f64)> = held
                    .iter()
                    .filter(|&&d| d % 3 < 2)
                    .map(|&d| {
                        let y = rest[d / 3][1];
                        (
                            d,
                            if d % 3 == 0 {
                                y * g.cos()
                            } else {
                                -y * g.sin()
                            },
                        )
                    })
                    .collect();
                let moment = sheet.reaction(x, &rate)?;
                let half = (std::f64::consts::FRAC_PI_2 - g) / 2.0;
                points.push(FramePoint {
                    shear_deg: g.to_degrees(),
                    moment,
                    shear_force: moment / (self.side * g.cos()),
                    axial_force: moment / (self.side * half.sin()),
                    report: report.clone(),
                });
                Ok(())
            },
        )?;
        Ok((points, Deformed::new(sheet, x, counts, last)))
    }
}
