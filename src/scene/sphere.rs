//! An inflated St. Venant–Kirchhoff balloon: a sphere built from a subdivided cube (eight
//! extraordinary vertices of valence 3 on every level), under a follower pressure.
//!
//! Analytic relation (derived here, membrane only): a sphere of radius R stretched uniformly to
//! λR has Green strain E = (λ² − 1)/2 in every tangent direction, energy per reference area
//! τ (a₁₁ + a₁₂) E² (isotropic, a₁₁ = a₂₂), and the pressure's potential −p (4/3)πR³λ³;
//! stationarity gives p = τ (a₁₁ + a₁₂)(λ² − 1) / (R λ). Bending adds a relative O((τ/R)²).
//!
//! The cage is the cube refined `levels` times with its control points projected onto the
//! sphere (so the limit surface lies slightly inside it; that geometric error is O(h²)). The six
//! face-centre points (the poles on the axes) may only move radially, which removes the rigid
//! motions without disturbing the symmetric inflation. The stretch is read as
//! λ = (V / V₀)^(1/3) from the enclosed volumes.

use super::{free_system, SceneError};
use crate::assembly::ShellModel;
use crate::material::OrthotropicStvk;
use crate::mesh::{shapes, Topology};
use crate::solve::{continuation, NewtonOptions};
use crate::subdiv::{refine_uniform, BasisOptions, BoundaryRule, LimitBasis};
use std::sync::Arc;

/// The balloon: radius, thickness, Young's modulus, Poisson ratio and refinement levels.
#[derive(Clone, Debug)]
pub struct Balloon {
    pub radius: f64,
    pub thickness: f64,
    pub young: f64,
    pub poisson: f64,
    pub levels: usize,
}

impl Balloon {
    /// Analytic pressure at stretch λ (membrane theory).
    pub fn analytic_pressure(&self, lambda: f64) -> f64 {
        let law = OrthotropicStvk::isotropic(self.young, self.poisson);
        self.thickness * (law.a11 + law.a12) * (lambda * lambda - 1.0) / (self.radius * lambda)
    }

    /// Inflates to pressure `p` and returns the stretch λ = (V/V₀)^(1/3) and the control-point
    /// count.
    pub fn run(&self, p: f64) -> Result<(f64, usize), SceneError> {
        let mut mesh = shapes::cube();
        for _ in 0..self.levels.max(1) {
            let t = Topology::build(&mesh).map_err(|e| SceneError::Input(e.to_string()))?;
            mesh = refine_uniform(&mesh, &t);
        }
        for q in &mut mesh.positions {
            let d = [q[0] - 0.5, q[1] - 0.5, q[2] - 0.5];
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            *q = d.map(|c| self.radius * c / n);
        }
        let basis = LimitBasis::new(
            &mesh,
            BasisOptions {
                boundary: BoundaryRule::Phantom,
                gauss_points: 4,
            },
        )?;
        let law = OrthotropicStvk::isotropic(self.young, self.poisson);
        let mut model =
            ShellModel::new(basis, [1.0, 0.3, 0.2], Arc::new(law), self.thickness, 1.0)?;
        let x0 = model.basis.control_points.clone();
        let nn = x0.len();
        let mut fixed = vec![false; 3 * nn];
        // the poles: points on the coordinate axes; hold their two tangential components
        for (v, q) in x0.iter().enumerate() {
            for axis in 0..3 {
                let others = [(axis + 1) % 3, (axis + 2) % 3];
                if others.iter().all(|&c| q[c].abs() < 1e-9 * self.radius) {
                    for c in others {
                        fixed[3 * v + c] = true;
                    }
                }
            }
        }
        if fixed.iter().filter(|f| **f).count() != 12 {
            return Err(SceneError::Input("internal: expected six poles".into()));
        }
        let system = free_system(&model, &fixed, Vec::new())?;
        let v0 = model.volume(&x0);
        let mut x = x0.clone();
        continuation(
            &mut model,
            &system,
            &mut x,
            &NewtonOptions::default(),
            1.0,
            |m, t, _| m.set_pressure(p * t),
        )
        .map_err(|(t, source)| SceneError::Solve {
            stage: format!("pressure factor {t:.4}"),
            source,
        })?;
        Ok(((model.volume(&x) / v0).cbrt(), nn))
    }
}
