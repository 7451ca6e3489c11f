//! The virtual lab (Clyde et al. 2017 §4): a tensile strip (ASTM D5035, `tensile.rs`) and a
//! cantilever bend (ASTM D1388, `cantilever.rs`), each returning what the instrument measures.
//! This module owns what they share: the model of a rectangular strip and the clamps. The
//! paper's showcase scenes (§6, Figures 1 and 5) live beside them on square sheets (`sheet.rs`):
//! the 1 m drape (`drape.rs`), the picture frame (`frame.rs`) and the corner pull
//! (`corner.rs`), with the deformed surface's export (`export.rs`).
//!
//! Angles are taken from the weft: 0° is a weft strip, 90° a warp strip, 45° bias. The strip's
//! axis is y; its weft direction is (sin θ, cos θ, 0) and its warp (cos θ, −sin θ, 0).

mod cantilever;
mod corner;
mod drape;
pub mod elastica;
pub mod export;
mod frame;
pub mod plate;
pub mod roof;
pub mod sheet;
pub mod sphere;
mod surface;
mod tensile;
pub mod tri;

pub use cantilever::{BendPoint, BendResult, BendRig, CantileverBend, BEND_ELEMENT};
pub use corner::{CornerPull, PullPoint};
pub use drape::{Drape, DrapeShape};
pub use frame::{Deformed, FramePoint, PictureFrame};
pub use tensile::{StripRig, TensilePoint, TensileStrip, STRIP_GRADING, STRIP_ITERATIONS};
pub use tri::{TriCantilever, TriTensile};

use crate::assembly::{ModelError, ShellModel, YarnRule};
pub use crate::material::warp_direction;
use crate::material::FabricMaterial;
use crate::mesh::{graded_grid, Grading};
use crate::solve::{newton, FreeSystem, NewtonOptions, Slave, SolveError, SolveReport};
use crate::subdiv::{BasisBuildError, BasisOptions, BoundaryRule, LimitBasis};
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

/// The free-DOF system of a scene, its set-up failure reported as a scene error.
fn free_system(
    model: &dyn crate::model::ClothModel,
    fixed: &[bool],
    slaves: Vec<Slave>,
) -> Result<FreeSystem, SceneError> {
    FreeSystem::with_slaves(model, fixed, slaves).map_err(|source| SceneError::Solve {
        stage: "set-up".into(),
        source,
    })
}

/// One equilibrium solve, its failure reported with `stage`.
fn equilibrium(
    model: &ShellModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    opts: &NewtonOptions,
    stage: impl FnOnce() -> String,
) -> Result<SolveReport, SceneError> {
    newton(model, system, x, opts).map_err(|source| SceneError::Solve {
        stage: stage(),
        source,
    })
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
            "{name} must be a positive number, got {v:?}"
        )))
    }
}

/// The shell of a `width` × `length` sheet whose warp lies at `angle_deg`, on an `nx` × `ny`
/// cage with the given boundary rule, grading and yarn rule (decided, and the centre rule's β
/// set, by the yarn-to-shear ratio `yarns.1`, or by the law's where that is `None`).
fn build_model(
    material: &FabricMaterial,
    (width, length): (f64, f64),
    angle_deg: f64,
    (nx, ny): (usize, usize),
    boundary: BoundaryRule,
    grading: Grading,
    yarns: (YarnRule, Option<f64>),
) -> Result<ShellModel, SceneError> {
    if !grading.is_valid() {
        return Err(SceneError::Input(format!(
            "mesh grading must be in [0, 1) each way, got {} across and {} along",
            crate::io::num(grading.across),
            crate::io::num(grading.along)
        )));
    }
    if !angle_deg.is_finite() {
        return Err(SceneError::Input(format!(
            "angle must be finite, got {angle_deg:?}"
        )));
    }
    crate::limits::check_mesh(&format!("mesh {nx}x{ny}"), nx, ny).map_err(SceneError::Input)?;
    if nx == 0 || ny == 0 {
        return Err(SceneError::Input(
            "the mesh needs at least one face each way".into(),
        ));
    }
    let mesh = graded_grid(width, length, nx, ny, grading);
    let basis = LimitBasis::new(
        &mesh,
        BasisOptions {
            boundary,
            gauss_points: 4,
        },
    )?;
    let mut model = ShellModel::new(
        basis,
        warp_direction(angle_deg),
        Arc::new(material.law.clone()),
        material.thickness,
        material.areal_density,
    )?;
    model.set_bending(material.bending);
    model.set_yarn_rule_at(yarns.0, yarns.1)?;
    Ok(model)
}

/// How a jaw holds the end of a strip.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Hold {
    /// The limit edge follows the jaw; the slope across it is free (tensile jaws).
    Position,
    /// The limit edge and the tangent across it keep their rest values (a clamp on a platform).
    PositionAndSlope,
}

/// Constraints holding the grid edge at row `row` (0 or ny) of a strip, the strip lying on the
/// side `inward` (+1 or −1) of it. With the phantom rule the limit edge is the boundary control
/// row, so holding it means fixing that row (and the next, for the slope, which also pins the
/// curvature across the edge to zero). With the ghost rule each column (ghost G, boundary P₀,
/// first interior P₁) satisfies (G + 4P₀ + P₁)/6 = edge and, for the slope, P₁ − G = rest value:
/// P₀ and G become affine functions of P₁, and the curvature G − 2P₀ + P₁ stays free.
struct EdgeClamp {
    /// DOFs held at rest position + shift.
    fixed: Vec<usize>,
    /// Affine constraints at zero shift.
    slaves: Vec<Slave>,
    /// ∂offset/∂shift component for each slave (the jaw moves along y only).
    offset_rate: Vec<f64>,
    /// ∂x_dof/∂(jaw displacement along y) at fixed masters: the reaction is Σ g · rate.
    motion: Vec<(usize, f64)>,
}

#[allow(clippy::too_many_arguments)]
fn edge_clamp(
    model: &ShellModel,
    rule: BoundaryRule,
    (nx, ny): (usize, usize),
    (width, length): (f64, f64),
    grading: Grading,
    row: i64,
    inward: i64,
    hold: Hold,
) -> Result<EdgeClamp, SceneError> {
    let x0 = &model.basis.control_points;
    let mut lattice = std::collections::HashMap::new();
    for (v, p) in x0.iter().enumerate() {
        // the cage line a control point sits on (ghosts included: the grading is odd about
        // each edge, so a reflected line is line −1 or n + 1)
        let i = Grading::inverse(grading.across, p[0] / width) * nx as f64;
        let j = Grading::inverse(grading.along, p[1] / length) * ny as f64;
        lattice.insert((i.round() as i64, j.round() as i64), v);
    }
    let node = |i: i64, j: i64| {
        lattice.get(&(i, j)).copied().ok_or_else(|| {
            SceneError::Input(format!("internal: no control point at lattice ({i}, {j})"))
        })
    };
    let mut clamp = EdgeClamp {
        fixed: Vec::new(),
        slaves: Vec::new(),
        offset_rate: Vec::new(),
        motion: Vec::new(),
    };
    let _ = ny;
    match rule {
        BoundaryRule::Phantom => {
            let rows: &[i64] = match hold {
                Hold::Position => &[0],
                Hold::PositionAndSlope => &[0, 1],
            };
            for &r in rows {
                for i in 0..=nx as i64 {
                    let v = node(i, row + r * inward)?;
                    clamp.fixed.extend(3 * v..3 * v + 3);
                    clamp.motion.push((3 * v + 1, 1.0));
                }
            }
        }
        BoundaryRule::Ghost => {
            for i in -1..=nx as i64 + 1 {
                let (g, p0, p1) = (
                    node(i, row - inward)?,
                    node(i, row)?,
                    node(i, row + inward)?,
                );
                for c in 0..3 {
                    let (xg, xp0, xp1) = (x0[g][c], x0[p0][c], x0[p1][c]);
                    let edge = (xg + 4.0 * xp0 + xp1) / 6.0;
                    let rate = if c == 1 { 1.5 } else { 0.0 };
                    match hold {
                        Hold::Position => {
                            clamp.slaves.push(Slave {
                                dof: 3 * p0 + c,
                                masters: vec![(3 * g + c, -0.25), (3 * p1 + c, -0.25)],
                                offset: 1.5 * edge,
                            });
                            clamp.offset_rate.push(rate);
                        }
                        Hold::PositionAndSlope => {
                            clamp.slaves.push(Slave {
                                dof: 3 * g + c,
                                masters: vec![(3 * p1 + c, 1.0)],
                                offset: xg - xp1,
                            });
                            clamp.offset_rate.push(0.0);
                            clamp.slaves.push(Slave {
                                dof: 3 * p0 + c,
                                masters: vec![(3 * p1 + c, -0.5)],
                                offset: xp0 + 0.5 * xp1,
                            });
                            clamp.offset_rate.push(rate);
                        }
                    }
                }
                clamp.motion.push((3 * p0 + 1, 1.5));
            }
        }
    }
    Ok(clamp)
}
