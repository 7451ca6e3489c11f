//! Square plates under uniform load, the linear Kirchhoff plate benchmarks: simply supported
//! (Navier's series: w_c = 0.00406235 q a⁴/D) and clamped (Taylor & Govindjee 2004:
//! w_c = 0.001265319 q a⁴/D). The load is small enough for the response to be linear, and the
//! in-plane control coordinates are held (bending alone is tested).
//!
//! Boundary conditions on the transverse coordinate z of the control grid (i, j), i, j indexing
//! the lattice of spacing a/n:
//! * simply supported, phantom rule: the boundary rows and columns fixed at z = 0. The limit
//!   edge is that row and the phantom rule gives zero curvature across it, which is exactly
//!   M_n = 0 on a straight supported edge;
//! * clamped, ghost rule: across each edge z₋₁ = z₁ and z₀ = −z₁/2 (edge value and slope zero,
//!   curvature free), applied as a tensor product at the corners: z_ij = f(i) f(j) z_m(i)m(j)
//!   with m(−1) = m(0) = 1, f(−1) = 1, f(0) = −½, and mirrored at the far edges.

use super::{build_model, equilibrium, free_system, SceneError};
use crate::assembly::YarnRule;
use crate::material::{FabricMaterial, OrthotropicStvk};
use crate::mesh::Grading;
use crate::solve::{NewtonOptions, Slave};
use crate::subdiv::BoundaryRule;

/// How the plate's edges are held.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Support {
    Simple,
    Clamped,
}

/// A square plate of side `side` with `n` × `n` faces.
#[derive(Clone, Debug)]
pub struct SquarePlate {
    pub side: f64,
    pub thickness: f64,
    pub young: f64,
    pub poisson: f64,
    pub n: usize,
    pub support: Support,
}

/// Result of a plate solve.
#[derive(Clone, Debug, PartialEq)]
pub struct PlateResult {
    /// Centre deflection divided by q a⁴ / D.
    pub deflection_factor: f64,
    pub dofs: usize,
}

impl SquarePlate {
    /// Solves under the uniform pressure `q` (Pa) and returns the centre deflection factor.
    pub fn run(&self, q: f64) -> Result<PlateResult, SceneError> {
        let n = self.n;
        if n < 2 {
            return Err(SceneError::Input(
                "a plate needs at least 2 × 2 faces".into(),
            ));
        }
        let (a, t, e, nu) = (self.side, self.thickness, self.young, self.poisson);
        let d = e * t.powi(3) / (12.0 * (1.0 - nu * nu));
        // the load as self-weight: ρ g = q
        let g = 9.80665;
        let material = FabricMaterial {
            name: "plate".into(),
            areal_density: q / g,
            thickness: t,
            law: OrthotropicStvk::isotropic(e, nu).into(),
            bending: None,
        };
        let rule = match self.support {
            Support::Simple => BoundaryRule::Phantom,
            Support::Clamped => BoundaryRule::Ghost,
        };
        let mut model = build_model(
            &material,
            (a, a),
            90.0,
            (n, n),
            rule,
            Grading::UNIFORM,
            (YarnRule::Full, None),
        )?;
        model.set_gravity([0.0, 0.0, -g]);
        let x0 = model.basis.control_points.clone();
        let h = a / n as f64;
        let lattice: std::collections::HashMap<(i64, i64), usize> = x0
            .iter()
            .enumerate()
            .map(|(v, p)| (((p[0] / h).round() as i64, (p[1] / h).round() as i64), v))
            .collect();
        let nn = x0.len();
        let mut fixed = vec![false; 3 * nn];
        let mut slaves = Vec::new();
        for v in 0..nn {
            fixed[3 * v] = true;
            fixed[3 * v + 1] = true;
        }
        let ni = n as i64;
        match self.support {
            Support::Simple => {
                for (&(i, j), &v) in &lattice {
                    if i == 0 || j == 0 || i == ni || j == ni {
                        fixed[3 * v + 2] = true;
                    }
                }
            }
            Support::Clamped => {
                // (image index, factor) of a lattice index under the clamp
                let image = |k: i64| match k {
                    -1 => (1, 1.0),
                    0 => (1, -0.5),
                    k if k == ni => (ni - 1, -0.5),
                    k if k == ni + 1 => (ni - 1, 1.0),
                    k => (k, 1.0),
                };
                for (&(i, j), &v) in &lattice {
                    let ((mi, fi), (mj, fj)) = (image(i), image(j));
                    if (mi, mj) == (i, j) {
                        continue;
                    }
                    let m = lattice.get(&(mi, mj)).copied().ok_or_else(|| {
                        SceneError::Input(format!("internal: no control point at ({mi}, {mj})"))
                    })?;
                    slaves.push(Slave {
                        dof: 3 * v + 2,
                        masters: vec![(3 * m + 2, fi * fj)],
                        offset: 0.0,
                    });
                }
            }
        }
        let system = free_system(&model, &fixed, slaves)?;
        let mut x = x0.clone();
        equilibrium(&model, &system, &mut x, &NewtonOptions::default(), || {
            "plate".into()
        })?;
        // centre of the limit surface: a corner of the four middle faces (n even) or the middle
        // of the middle face (n odd)
        let (face, u) = if n % 2 == 0 {
            ((n / 2) * n + n / 2, 0.0)
        } else {
            ((n / 2) * n + n / 2, 0.5)
        };
        let s = model
            .basis
            .surface()
            .stencil(face, u, u)
            .map_err(|e| SceneError::Basis(e.into()))?;
        let w = -s.apply(&x).x()[2];
        Ok(PlateResult {
            deflection_factor: w * d / (q * a.powi(4)),
            dofs: system.num_free,
        })
    }
}
