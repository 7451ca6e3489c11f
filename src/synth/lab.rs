//! The model a synthetic dataset is made with: the subdivision shell (the default) or one of
//! the triangle models of [`crate::tri`], so that a fit can be checked on data another
//! discretisation made (a different mesh, a different energy, bending and Poisson behaviour the
//! fitted model does not share).

use crate::material::FabricMaterial;
use crate::scene::{CantileverBend, SceneError, TensileStrip};
use crate::scene::{TriCantilever, TriTensile};
use crate::tri::file::{TriSource, SPRING_CURVATURE};
use crate::tri::TriKind;

/// A model of the fabric the virtual lab runs.
#[derive(Clone, Debug)]
pub enum LabModel {
    Shell(FabricMaterial),
    Tri {
        kind: TriKind,
        source: TriSource,
        /// What the dataset records of the fabric (a `[model]` table has no thickness of its
        /// own: the caller gives one, e.g. the file's `thickness_mm`).
        name: String,
        thickness: f64,
    },
}

impl LabModel {
    pub fn name(&self) -> &str {
        match self {
            LabModel::Shell(m) => &m.name,
            LabModel::Tri { name, .. } => name,
        }
    }

    pub fn thickness(&self) -> f64 {
        match self {
            LabModel::Shell(m) => m.thickness,
            LabModel::Tri { thickness, .. } => *thickness,
        }
    }

    /// kg/m²
    pub fn areal_density(&self) -> f64 {
        match self {
            LabModel::Shell(m) => m.areal_density,
            LabModel::Tri { source, .. } => match source {
                TriSource::Table(t) => t.areal_density,
                TriSource::Shell(m) => m.areal_density,
            },
        }
    }

    /// The model's name as `--model` spells it.
    pub fn model_name(&self) -> &'static str {
        match self {
            LabModel::Shell(_) => "kl",
            LabModel::Tri { kind, .. } => kind.name(),
        }
    }

    /// A flexural rigidity (N·m) to start the overhang search from, for a cut at `angle`.
    pub fn rigidity_guess(&self, angle: f64) -> f64 {
        let shell = |m: &FabricMaterial| match &m.bending {
            Some(b) => b.at_angle(angle),
            None => {
                let a = if angle >= 45.0 { m.law.a11 } else { m.law.a22 };
                a * m.thickness.powi(3) / 12.0
            }
        };
        match self {
            LabModel::Shell(m) => shell(m),
            LabModel::Tri { kind, source, .. } => match source {
                TriSource::Shell(m) => shell(m),
                TriSource::Table(t) => {
                    let c = if angle >= 45.0 { 3 } else { 4 };
                    let k = t.curves[c].at(0.0).0;
                    if *kind == TriKind::Springs {
                        // k = 36 B / (κ² a⁴) on a cell a (TriMaterial::equivalent); a of the
                        // default cantilever mesh, about 6 mm
                        let a: f64 = 6e-3;
                        k * SPRING_CURVATURE.powi(2) * a.powi(4) / 36.0
                    } else {
                        k
                    }
                }
            },
        }
    }

    /// A strip's force at each elongation and whether every equilibrium is stable.
    pub fn strip(
        &self,
        (width, gauge, angle): (f64, f64, f64),
        mesh: (usize, usize),
        (grading, yarns): (crate::mesh::Grading, crate::assembly::YarnRule),
        elongations: &[f64],
    ) -> Result<Vec<(f64, bool)>, SceneError> {
        match self {
            LabModel::Shell(m) => {
                let mut strip = TensileStrip::new(width, gauge, angle);
                strip.mesh = mesh;
                strip.grading = grading;
                strip.yarn_rule = yarns;
                let curve = strip.run(m, elongations)?;
                Ok(curve.iter().map(|p| (p.force, p.report.stable)).collect())
            }
            LabModel::Tri { kind, source, .. } => {
                let mut strip = TriTensile::new(width, gauge, angle);
                strip.mesh = mesh;
                strip.solver.max_iterations = crate::scene::STRIP_ITERATIONS;
                let mat = source
                    .material(*kind, width / mesh.0 as f64)
                    .map_err(SceneError::Input)?;
                let curve = strip.run(&mat, elongations)?;
                Ok(curve.iter().map(|p| (p.force, p.report.stable)).collect())
            }
        }
    }

    /// A cantilever's drape angle (degrees) at `overhang` on `mesh`, and whether it is stable.
    pub fn cantilever(
        &self,
        (width, overhang, angle): (f64, f64, f64),
        mesh: (usize, usize),
    ) -> Result<(f64, bool), SceneError> {
        match self {
            LabModel::Shell(m) => {
                let mut bend = CantileverBend::new(width, overhang, angle);
                bend.mesh = mesh;
                let r = bend.run(m)?;
                Ok((r.drape_angle_deg, r.report.stable))
            }
            LabModel::Tri { kind, source, .. } => {
                let mut bend = TriCantilever::new(width, overhang, angle);
                bend.mesh = mesh;
                let mat = source
                    .material(*kind, width / mesh.0 as f64)
                    .map_err(SceneError::Input)?;
                let r = bend.run(&mat)?;
                Ok((r.drape_angle_deg, r.report.stable))
            }
        }
    }
}
