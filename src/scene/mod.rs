//! The virtual lab (Clyde et al. 2017 §4): a tensile strip (ASTM D5035) and a cantilever bend
//! (ASTM D1388), each returning what the instrument measures.
//!
//! Angles are measured from the weft: 0° is a weft strip, 90° a warp strip, 45° bias. The strip's
//! axis is y; its weft direction is (sin θ, cos θ, 0) and its warp (cos θ, −sin θ, 0).

use crate::assembly::{ModelError, ShellModel, STANDARD_GRAVITY};
use crate::material::FabricMaterial;
use crate::mesh::rectangular_grid;
use crate::solve::{newton, FreeSystem, NewtonOptions, SolveError, SolveReport};
use crate::subdiv::{BasisBuildError, BasisOptions, BoundaryRule, LimitBasis, LimitSurface};
use crate::Vec3;
use std::sync::Arc;

/// A virtual test could not be run.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{0}")]
    Input(String),
    #[error(transparent)]
    Basis(#[from] BasisBuildError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("equilibrium solve failed at {stage}: {source}")]
    Solve { stage: String, source: SolveError },
}

/// Warp direction of a strip cut at `angle_deg` from the weft, axis along y.
pub fn warp_direction(angle_deg: f64) -> Vec3 {
    let t = angle_deg.to_radians();
    [t.cos(), -t.sin(), 0.0]
}

/// Default quad counts for a strip: 8 across, square-ish elements along (8 × 12 on 50 × 75 mm).
pub fn default_mesh(width: f64, length: f64) -> (usize, usize) {
    (8, ((8.0 * length / width).round() as usize).max(1))
}

fn positive(name: &str, v: f64) -> Result<f64, SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(SceneError::Input(format!(
            "{name} must be a positive number, got {v}"
        )))
    }
}

fn build_model(
    material: &FabricMaterial,
    width: f64,
    length: f64,
    angle_deg: f64,
    (nx, ny): (usize, usize),
    boundary: BoundaryRule,
) -> Result<ShellModel, SceneError> {
    if !angle_deg.is_finite() {
        return Err(SceneError::Input(format!(
            "angle must be finite, got {angle_deg}"
        )));
    }
    if nx == 0 || ny == 0 {
        return Err(SceneError::Input(
            "the mesh needs at least one face each way".into(),
        ));
    }
    let mesh = rectangular_grid(width, length, nx, ny);
    let basis = LimitBasis::new(
        &mesh,
        BasisOptions {
            boundary,
            gauss_points: 4,
        },
    )?;
    Ok(ShellModel::new(
        basis,
        warp_direction(angle_deg),
        Arc::new(material.law),
        material.thickness,
        material.areal_density,
    )?)
}

/// ASTM D5035 strip: width × gauge length, clamped along both ends, one clamp pulled along y.
#[derive(Clone, Debug)]
pub struct TensileStrip {
    /// m
    pub width: f64,
    /// gauge length, m
    pub length: f64,
    pub angle_deg: f64,
    pub mesh: (usize, usize),
    pub boundary: BoundaryRule,
}

/// One point of a virtual tensile curve.
#[derive(Clone, Debug, PartialEq)]
pub struct TensilePoint {
    /// m
    pub elongation: f64,
    /// N, the axial clamp reaction
    pub force: f64,
    pub report: SolveReport,
}

impl TensileStrip {
    pub fn new(width: f64, length: f64, angle_deg: f64) -> Self {
        Self {
            width,
            length,
            angle_deg,
            mesh: default_mesh(width, length),
            boundary: BoundaryRule::Phantom,
        }
    }

    /// Forces at each elongation (m, increasing), each solve started from the last equilibrium
    /// stretched affinely to the new clamp position.
    pub fn run(
        &self,
        material: &FabricMaterial,
        elongations: &[f64],
    ) -> Result<Vec<TensilePoint>, SceneError> {
        positive("width", self.width)?;
        positive("gauge length", self.length)?;
        let (nx, ny) = self.mesh;
        let model = build_model(
            material,
            self.width,
            self.length,
            self.angle_deg,
            self.mesh,
            self.boundary,
        )?;
        let nn = model.num_nodes();
        // the jaws hold the end rows of the grid: with the phantom rule the limit edge is that row
        let bottom: Vec<usize> = (0..=nx).collect();
        let top: Vec<usize> = (0..=nx).map(|i| ny * (nx + 1) + i).collect();
        let mut fixed = vec![false; 3 * nn];
        for &v in bottom.iter().chain(&top) {
            fixed[3 * v..3 * v + 3].iter_mut().for_each(|f| *f = true);
        }
        let system = FreeSystem::new(&model, &fixed).map_err(|source| SceneError::Solve {
            stage: "set-up".into(),
            source,
        })?;
        let mut x = model.basis.control_points.clone();
        let mut grad = vec![[0.0; 3]; nn];
        let mut current = 0.0;
        let mut out = Vec::with_capacity(elongations.len());
        for &dl in elongations {
            if !dl.is_finite() {
                return Err(SceneError::Input(format!(
                    "elongation must be finite, got {dl}"
                )));
            }
            let s = (self.length + dl) / (self.length + current);
            for p in &mut x {
                p[1] *= s;
            }
            for &v in &top {
                x[v][1] = self.length + dl;
            }
            for &v in &bottom {
                x[v][1] = 0.0;
            }
            let report =
                newton(&model, &system, &mut x, &NewtonOptions::default()).map_err(|source| {
                    SceneError::Solve {
                        stage: format!("elongation {:.4} mm", dl * 1e3),
                        source,
                    }
                })?;
            model
                .assemble(&x, crate::assembly::Want::Gradient, Some(&mut grad), None)
                .map_err(|e| SceneError::Solve {
                    stage: "reaction".into(),
                    source: SolveError::StartOutOfDomain(e.to_string()),
                })?;
            let force: f64 = top.iter().map(|&v| grad[v][1]).sum();
            out.push(TensilePoint {
                elongation: dl,
                force,
                report,
            });
            current = dl;
        }
        Ok(out)
    }
}

/// ASTM D1388 cantilever: a strip of `width` overhanging the platform edge by `overhang`, the
/// part on the platform clamped (the first two control rows fixed flat, which holds the edge
/// position and its slope), sagging under gravity.
#[derive(Clone, Debug)]
pub struct CantileverBend {
    /// m
    pub width: f64,
    /// m
    pub overhang: f64,
    pub angle_deg: f64,
    pub mesh: (usize, usize),
    pub boundary: BoundaryRule,
}

/// The measured bend.
#[derive(Clone, Debug, PartialEq)]
pub struct BendResult {
    /// Chord angle from the platform edge to the free-end tip, below horizontal, degrees.
    pub drape_angle_deg: f64,
    /// Tip position (mid-width of the free edge), m.
    pub tip: Vec3,
    pub load_steps: usize,
    pub report: SolveReport,
}

impl CantileverBend {
    pub fn new(width: f64, overhang: f64, angle_deg: f64) -> Self {
        // elements of about 6.25 mm, as the 8 × 12 tensile mesh, at least 4 across
        let nx = ((width / 6.25e-3).round() as usize).max(4);
        let ny = ((overhang / (width / nx as f64)).round() as usize).max(2);
        Self {
            width,
            overhang,
            angle_deg,
            mesh: (nx, ny),
            boundary: BoundaryRule::Phantom,
        }
    }

    pub fn run(&self, material: &FabricMaterial) -> Result<BendResult, SceneError> {
        positive("width", self.width)?;
        positive("overhang", self.overhang)?;
        let (nx, ny) = self.mesh;
        if ny < 2 {
            return Err(SceneError::Input(
                "the cantilever mesh needs at least 2 rows".into(),
            ));
        }
        let mut model = build_model(
            material,
            self.width,
            self.overhang,
            self.angle_deg,
            self.mesh,
            self.boundary,
        )?;
        let nn = model.num_nodes();
        let mut fixed = vec![false; 3 * nn];
        for v in 0..2 * (nx + 1) {
            fixed[3 * v..3 * v + 3].iter_mut().for_each(|f| *f = true);
        }
        let system = FreeSystem::new(&model, &fixed).map_err(|source| SceneError::Solve {
            stage: "set-up".into(),
            source,
        })?;
        let mut x = model.basis.control_points.clone();
        // gravity continuation: raise the load factor, halving the increment when a solve fails;
        // each solve starts from a secant prediction through the last two equilibria
        let (mut factor, mut step, mut steps) = (0.0f64, 0.125f64, 0usize);
        let opts = NewtonOptions {
            max_iterations: 30,
            ..NewtonOptions::default()
        };
        let mut last = SolveReport::default();
        let mut previous: Option<(f64, Vec<Vec3>)> = None;
        while factor < 1.0 {
            let target = (factor + step).min(1.0);
            model.set_gravity([0.0, 0.0, -STANDARD_GRAVITY * target]);
            let mut trial = x.clone();
            if let Some((f0, x0)) = &previous {
                let r = (target - factor) / (factor - f0);
                for (t, (a, b)) in trial.iter_mut().zip(x.iter().zip(x0)) {
                    for c in 0..3 {
                        t[c] = a[c] + r * (a[c] - b[c]);
                    }
                }
            }
            match newton(&model, &system, &mut trial, &opts) {
                Ok(r) => {
                    previous = Some((factor, std::mem::replace(&mut x, trial)));
                    factor = target;
                    steps += 1;
                    // grow the increment while solves stay easy
                    if r.iterations <= 12 {
                        step *= 2.0;
                    }
                    last = r;
                }
                Err(source) => {
                    step *= 0.5;
                    if step < 1e-4 {
                        return Err(SceneError::Solve {
                            stage: format!("gravity factor {target:.4}"),
                            source,
                        });
                    }
                }
            }
        }
        let surface = LimitSurface::new(
            &rectangular_grid(self.width, self.overhang, nx, ny),
            self.boundary,
        )
        .map_err(|e| SceneError::Basis(e.into()))?;
        let mid = nx / 2;
        let (face_edge, u_edge) = if nx % 2 == 0 { (mid, 0.0) } else { (mid, 0.5) };
        let eval = |face: usize, u: f64, v: f64| -> Result<Vec3, SceneError> {
            let s = surface
                .stencil(face, u, v)
                .map_err(|e| SceneError::Basis(e.into()))?;
            Ok(s.apply(&x).x())
        };
        let edge = eval(face_edge, u_edge, 0.0)?;
        let tip = eval((ny - 1) * nx + face_edge, u_edge, 1.0)?;
        let angle = (-(tip[2] - edge[2])).atan2(tip[1] - edge[1]).to_degrees();
        Ok(BendResult {
            drape_angle_deg: angle,
            tip,
            load_steps: steps,
            report: last,
        })
    }
}
