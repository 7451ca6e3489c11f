//! The Scordelis–Lo roof (Scordelis & Lo 1964; MacNeal & Harder 1985): a cylindrical shell
//! segment, R = 25, L = 50, spanning ±40°, t = 0.25, E = 4.32e8, ν = 0, loaded by 90 per unit
//! area (dead, vertical), on rigid diaphragms at its curved ends (u_y = u_z = 0 there), its
//! straight edges free. Kirchhoff–Love reference for the vertical displacement at the midpoint of
//! a free edge: 0.3006 (Kiendl, PhD thesis, TU München 2011); 0.3024 belongs to
//! shear-deformable elements.
//!
//! Discretisation: the ghost rule, the control lattice (ghosts included) placed on the cylinder
//! (the limit surface then approximates it to O(h²)); at each diaphragm every lattice row holds
//! (G + 4P₀ + P₁)/6 in y and z (the edge stays on the diaphragm, free to slide along x and to
//! rotate); the column on the mid-span symmetry plane holds x (removing the rigid slide). The
//! reference is linear, so the load is scaled by 1e-4 and the response scaled back.

use super::{equilibrium, free_system, SceneError};
use crate::assembly::ShellModel;
use crate::material::OrthotropicStvk;
use crate::mesh::rectangular_grid;
use crate::solve::{NewtonOptions, Slave};
use crate::subdiv::{BasisOptions, BoundaryRule, LimitBasis};
use std::collections::HashMap;
use std::sync::Arc;

/// The roof on `n_length` × `n_arc` faces.
#[derive(Clone, Debug)]
pub struct ScordelisLo {
    pub n_length: usize,
    pub n_arc: usize,
}

impl ScordelisLo {
    /// Vertical displacement (downward, linear response) at the midpoint of a free edge, and the
    /// number of free DOFs.
    pub fn run(&self) -> Result<(f64, usize), SceneError> {
        let (nx, nt) = (self.n_length, self.n_arc);
        if nx < 2 || nx % 2 != 0 || nt < 2 {
            return Err(SceneError::Input(
                "the roof needs an even number (≥ 2) of faces along and ≥ 2 around".into(),
            ));
        }
        let (r, l, half) = (25.0, 50.0, 40f64.to_radians());
        let (t, e, load) = (0.25, 4.32e8, 90.0);
        let factor = 1e-4;
        let g = 9.80665;
        // the parameter grid: x along the length, y ∈ [0, 1] across the arc
        let grid = rectangular_grid(l, 1.0, nx, nt);
        let mut basis = LimitBasis::new(
            &grid,
            BasisOptions {
                boundary: BoundaryRule::Ghost,
                gauss_points: 4,
            },
        )?;
        let (hx, hy) = (l / nx as f64, 1.0 / nt as f64);
        let index: Vec<(i64, i64)> = basis
            .control_points
            .iter()
            .map(|p| ((p[0] / hx).round() as i64, (p[1] / hy).round() as i64))
            .collect();
        for (p, &(i, j)) in basis.control_points.iter_mut().zip(&index) {
            let theta = -half + 2.0 * half * j as f64 / nt as f64;
            *p = [i as f64 * hx, r * theta.sin(), r * theta.cos()];
        }
        let lattice: HashMap<(i64, i64), usize> =
            index.iter().enumerate().map(|(v, &k)| (k, v)).collect();
        let node = |i: i64, j: i64| {
            lattice.get(&(i, j)).copied().ok_or_else(|| {
                SceneError::Input(format!("internal: no control point at ({i}, {j})"))
            })
        };
        let law = OrthotropicStvk::isotropic(e, 0.0);
        let mut model =
            ShellModel::new(basis, [1.0, 0.0, 0.0], Arc::new(law), t, factor * load / g)?;
        model.set_gravity([0.0, 0.0, -g]);
        let x0 = model.basis.control_points.clone();
        let nn = x0.len();
        let mut fixed = vec![false; 3 * nn];
        let mut slaves = Vec::new();
        let (ni, nj) = (nx as i64, nt as i64);
        for j in -1..=nj + 1 {
            for (g_i, p0_i, p1_i) in [(-1, 0, 1), (ni + 1, ni, ni - 1)] {
                let (gv, p0, p1) = (node(g_i, j)?, node(p0_i, j)?, node(p1_i, j)?);
                for c in 1..3 {
                    let edge = (x0[gv][c] + 4.0 * x0[p0][c] + x0[p1][c]) / 6.0;
                    slaves.push(Slave {
                        dof: 3 * p0 + c,
                        masters: vec![(3 * gv + c, -0.25), (3 * p1 + c, -0.25)],
                        offset: 1.5 * edge,
                    });
                }
            }
            fixed[3 * node(ni / 2, j)?] = true;
        }
        let system = free_system(&model, &fixed, slaves)?;
        let mut x = x0.clone();
        equilibrium(&model, &system, &mut x, &NewtonOptions::default(), || {
            "roof".into()
        })?;
        // midpoint of the free edge θ = +40°: face (nx/2, nt − 1) at (u, v) = (0, 1)
        let face = (nt - 1) * nx + nx / 2;
        let s = model
            .basis
            .surface()
            .stencil(face, 0.0, 1.0)
            .map_err(|e| SceneError::Basis(e.into()))?;
        let dz = s.apply(&x).x()[2] - s.apply(&x0).x()[2];
        Ok((-dz / factor, system.num_free))
    }
}
