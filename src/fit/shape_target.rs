//! A captured shape (`[[shape]]` of the dataset) as residuals of the triangle-model fit, and
//! as a prediction of a fitted shell: the scene it was captured in is run on the model's own
//! sheet, and the simulated surface is compared with the captured one by the chosen
//! descriptor ([`crate::shape`]), plus the boundary force when the lab measured it (Larionov
//! et al. 2022 fit both). A shell's surface is its limit surface sampled 2 × 2 per face.
//!
//! Residuals are scaled so that a shape weighs like one fitted curve of `points` points:
//! positions give p_i − closest(p_i) over the target's thinnest spread, times √(points / nodes),
//! so their sum of squares is points × (rms distance / spread)²; the FFT descriptor's residuals
//! ([`Spectrum::residuals`]) times √points; the force one relative residual.

use crate::dataset::{Descriptor, Role, ShapeScene, ShapeTest};
use crate::material::FabricMaterial;
use crate::scene::export::{lattice_surface, sample, SurfaceMesh};
use crate::scene::{CornerPull, Drape, FramePoint, PictureFrame, PullPoint, SceneError};
use crate::shape::distance::Surface;
use crate::shape::fft::Spectrum;
use crate::shape::ShapeMesh;
use crate::tri::TriMaterial;

/// Grid of the FFT descriptor, cells each way.
pub const FFT_GRID: usize = 32;

/// Samples of the shell's limit surface along each face edge.
const SHELL_SAMPLES: usize = 2;

/// Largest relative shape error at the optimum that a fit (shell or triangle model) trusts:
/// beyond it the model has not found the captured shape (another branch of wrinkles, or
/// another kind of sheet).
pub const SHAPE_TRUST: f64 = 0.25;

/// A captured shape prepared for the fit.
#[derive(Clone, Debug)]
pub struct ShapeTarget {
    pub test: ShapeTest,
    /// Faces each way of the model's sheet.
    pub mesh: usize,
    /// Steps of the scene's motion.
    pub steps: usize,
    /// The target's thinnest spread, m.
    pub spread: f64,
    spectrum: Option<Spectrum>,
    points: usize,
}

/// How well a model reproduces a shape.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeFit {
    /// The scene in one line.
    pub scene: String,
    pub descriptor: &'static str,
    /// rms distance of the simulated vertices to the captured surface, m.
    pub rms_distance: f64,
    /// The descriptor's relative error: rms distance over the target's spread (positions), or
    /// the spectra's relative difference (fft).
    pub error: f64,
    /// (simulated, measured) boundary force, N.
    pub force: Option<(f64, f64)>,
}

impl ShapeTarget {
    /// `points`: the weight of one fitted curve, in residuals.
    pub fn new(test: &ShapeTest, points: usize) -> Result<Self, String> {
        let mesh = test.mesh.unwrap_or(match test.scene {
            ShapeScene::PictureFrame { .. } => 12,
            // the clips sit on cage lines at multiples of 10
            ShapeScene::CornerPull { .. } => 20,
            ShapeScene::Drape { .. } => 16,
        });
        let spectrum = match test.descriptor {
            Descriptor::Fft => Some(Spectrum::of_mesh(&test.target, FFT_GRID)?),
            Descriptor::Positions => None,
        };
        let spread = test.target.thinnest_spread();
        if spread.is_nan() || spread <= 0.0 {
            return Err(format!(
                "shape {}: the captured surface is flat; a position error needs a shape with some depth",
                test.obj.display()
            ));
        }
        Ok(Self {
            test: test.clone(),
            mesh,
            steps: 8,
            spread,
            spectrum,
            points: points.max(1),
        })
    }

    pub fn fitted(&self) -> bool {
        self.test.role != Some(Role::Validation)
    }

    /// Components of [`TriMaterial::curves`] the scene exercises: the frame shears the sheet
    /// and bends it in wrinkles; the corner pull does everything; a drape is bending under
    /// weight (its membrane hardly stretches).
    pub fn exercised(&self) -> &'static [usize] {
        match self.test.scene {
            ShapeScene::PictureFrame { .. } => &[2, 3, 4],
            ShapeScene::CornerPull { .. } => &[0, 1, 2, 3, 4],
            ShapeScene::Drape { .. } => &[3, 4],
        }
    }

    /// The model's final surface and boundary force.
    fn simulate(&self, m: &TriMaterial) -> Result<(ShapeMesh, Option<f64>), SceneError> {
        self.run_scene(
            &|f| {
                f.run_tri(m)
                    .map(|(p, d)| (p, lattice_surface(&d.sheet, &d.x)))
            },
            &|c| {
                c.run_tri(m)
                    .map(|(p, d)| (p, lattice_surface(&d.sheet, &d.x)))
            },
            &|r| r.run_tri(m).map(|d| lattice_surface(&d.1.sheet, &d.1.x)),
        )
    }

    /// The shell's final limit surface (2 × 2 samples a face) and boundary force.
    fn simulate_shell(&self, m: &FabricMaterial) -> Result<(ShapeMesh, Option<f64>), SceneError> {
        self.run_scene(
            &|f| {
                f.run(m)
                    .and_then(|(p, d)| Ok((p, sample(&d.sheet, &d.x, SHELL_SAMPLES)?)))
            },
            &|c| {
                c.run(m)
                    .and_then(|(p, d)| Ok((p, sample(&d.sheet, &d.x, SHELL_SAMPLES)?)))
            },
            &|r| {
                r.run(m)
                    .and_then(|d| sample(&d.1.sheet, &d.1.x, SHELL_SAMPLES))
            },
        )
    }

    /// Sets up the scene and runs it by the given runner.
    #[allow(clippy::type_complexity)]
    fn run_scene(
        &self,
        frame_run: &dyn Fn(&PictureFrame) -> Result<(Vec<FramePoint>, SurfaceMesh), SceneError>,
        corner_run: &dyn Fn(&CornerPull) -> Result<(Vec<PullPoint>, SurfaceMesh), SceneError>,
        drape_run: &dyn Fn(&Drape) -> Result<SurfaceMesh, SceneError>,
    ) -> Result<(ShapeMesh, Option<f64>), SceneError> {
        let (mesh, steps) = (self.mesh, self.steps);
        let (surface, force) = match self.test.scene {
            ShapeScene::PictureFrame { side, shear_deg } => {
                let frame = PictureFrame {
                    mesh,
                    steps,
                    ..PictureFrame::new(side, shear_deg)
                };
                let (points, s) = frame_run(&frame)?;
                (s, points.last().map(|p| p.shear_force))
            }
            ShapeScene::CornerPull { side, stretch } => {
                let pull = CornerPull {
                    mesh,
                    steps,
                    ..CornerPull::new(side, stretch)
                };
                let (points, s) = corner_run(&pull)?;
                (s, points.last().map(|p| p.force))
            }
            ShapeScene::Drape { side, span } => {
                let drape = Drape {
                    side,
                    span,
                    mesh,
                    steps,
                    ..Drape::new()
                };
                (drape_run(&drape)?, None)
            }
        };
        Ok((surface.to_shape(), force))
    }

    /// Residuals (see the module doc); a failed solve gives NaN, which the minimiser rejects.
    pub fn residuals(&self, m: &TriMaterial) -> Vec<f64> {
        self.residuals_of(self.simulate(m), 1)
    }

    /// The residuals of the shell material `m` on this shape, on the shape's mesh.
    pub fn residuals_shell(&self, m: &FabricMaterial) -> Vec<f64> {
        self.residuals_of(self.simulate_shell(m), SHELL_SAMPLES)
    }

    /// Whether the scene exercises the in-plane shear (the frame and the corner pull).
    pub fn shears(&self) -> bool {
        self.exercised().contains(&2)
    }

    /// The residuals of a simulated surface with `per_face` samples along each face edge.
    fn residuals_of(
        &self,
        run: Result<(ShapeMesh, Option<f64>), SceneError>,
        per_face: usize,
    ) -> Vec<f64> {
        let nodes = (per_face * self.mesh + 1).pow(2);
        let len = match &self.spectrum {
            Some(s) => 3 * (0..FFT_GRID * FFT_GRID).filter(|&i| s.kept(i)).count(),
            None => 3 * nodes,
        } + usize::from(self.test.force.is_some());
        let Ok((surface, force)) = run else {
            return vec![f64::NAN; len];
        };
        let mut r = match &self.spectrum {
            Some(target) => match Spectrum::of_mesh(&surface, FFT_GRID) {
                Ok(s) => {
                    let w = (self.points as f64).sqrt();
                    s.residuals(target).into_iter().map(|v| v * w).collect()
                }
                Err(_) => vec![f64::NAN; len - usize::from(self.test.force.is_some())],
            },
            None => {
                let w = (self.points as f64 / nodes as f64).sqrt() / self.spread;
                Surface::new(&self.test.target)
                    .offsets(&surface.positions)
                    .into_iter()
                    .flat_map(|o| o.map(|v| v * w))
                    .collect()
            }
        };
        if let Some(f) = self.test.force {
            r.push(force.map_or(f64::NAN, |s| (s - f) / f));
        }
        debug_assert_eq!(r.len(), len);
        r
    }

    /// The errors of `m` on this shape (NaN where the scene does not solve).
    pub fn errors(&self, m: &TriMaterial) -> ShapeFit {
        self.errors_of(self.simulate(m))
    }

    /// The errors of the shell material `m` on this shape, on the shape's mesh (NaN where the
    /// scene does not solve).
    pub fn errors_shell(&self, m: &FabricMaterial) -> ShapeFit {
        self.errors_of(self.simulate_shell(m))
    }

    fn errors_of(&self, run: Result<(ShapeMesh, Option<f64>), SceneError>) -> ShapeFit {
        let mut out = ShapeFit {
            scene: self.test.scene.describe(),
            descriptor: self.test.descriptor.name(),
            rms_distance: f64::NAN,
            error: f64::NAN,
            force: self.test.force.map(|f| (f64::NAN, f)),
        };
        let Ok((surface, force)) = run else {
            return out;
        };
        let offsets = Surface::new(&self.test.target).offsets(&surface.positions);
        let n = offsets.len().max(1) as f64;
        out.rms_distance = (offsets
            .iter()
            .map(|o| o[0] * o[0] + o[1] * o[1] + o[2] * o[2])
            .sum::<f64>()
            / n)
            .sqrt();
        out.error = match &self.spectrum {
            Some(t) => Spectrum::of_mesh(&surface, FFT_GRID).map_or(f64::NAN, |s| {
                s.residuals(t).iter().map(|v| v * v).sum::<f64>().sqrt()
            }),
            None => out.rms_distance / self.spread,
        };
        if let (Some(f), Some(s)) = (self.test.force, force) {
            out.force = Some((s, f));
        }
        out
    }
}
