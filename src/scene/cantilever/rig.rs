//! [`BendRig`]: the cantilever bend set up once and run again with new material parameters,
//! warm-started from its last equilibrium, with drape-angle sensitivities by the adjoint of the
//! tangent (Clyde et al. 2017, Eq. 6): the fitter's forward model of a bend test.

use super::{elastica_applies, solve_from_elastica, CantileverBend, Clamped, WARM_ITERATIONS};
use crate::assembly::{ShellModel, STANDARD_GRAVITY};
use crate::material::FabricMaterial;
use crate::scene::free_system;
use crate::scene::SceneError;
use crate::solve::{
    continuation, newton, FreeSystem, NewtonOptions, SolveError, SolveReport, Strategy,
};
use crate::subdiv::LimitStencil;
use crate::Vec3;
use std::sync::Arc;

/// An ASTM D1388 cantilever (self-weight only) set up once for repeated runs with changing
/// material parameters: the fitter's forward model of a bend test. Each run starts from the
/// last equilibrium (moved along ∂q/∂k to the new parameters where the last run computed
/// sensitivities), held to `WARM_ITERATIONS` where the elastica can follow; then, for a warp or
/// weft cut under the full-step strategy, from the heavy elastica (`elastica_start`); then by a load ramp from the flat
/// strip.
pub struct BendRig {
    bend: CantileverBend,
    model: ShellModel,
    system: FreeSystem,
    equilibrium: Option<Vec<Vec3>>,
    /// the parameters (law, thickness, then the rigidities when the bending is its own) of
    /// the last equilibrium and ∂q/∂k there (reduced, one row per parameter), where the last
    /// run computed sensitivities: the next run starts from q + ∂q/∂k Δk
    tangent: Option<(Vec<f64>, Vec<Vec<f64>>)>,
    /// the law's parameters and the thickness of the current material
    material_params: Vec<f64>,
    /// the current parameters, in the order of `tangent` (set at each run)
    params: Vec<f64>,
    /// (face, u) of the mid-width point of the clamped edge (v = 0) and of the tip (v = 1)
    edge: (usize, f64),
    tip: (usize, f64),
}

/// A bend run with, when asked for, ∂angle/∂k (law parameters, then thickness, then the bending
/// rigidities when the bending is its own; degrees).
#[derive(Clone, Debug, PartialEq)]
pub struct BendPoint {
    pub drape_angle_deg: f64,
    pub dangle: Vec<f64>,
    /// the last solve's report, with the iterations and factorisations of every attempt
    /// (a warm start given up on, the load ramp's steps)
    pub report: SolveReport,
}

impl BendRig {
    pub fn new(bend: &CantileverBend, material: &FabricMaterial) -> Result<Self, SceneError> {
        let Clamped {
            mut model,
            fixed,
            clamp,
            edge,
            tip,
        } = bend.clamped(material)?;
        let system = free_system(&model, &fixed, clamp.slaves)?;
        model.set_gravity([0.0, 0.0, -STANDARD_GRAVITY]);
        Ok(Self {
            bend: bend.clone(),
            model,
            system,
            equilibrium: None,
            tangent: None,
            material_params: material
                .law
                .params()
                .into_iter()
                .chain([material.thickness])
                .collect(),
            params: Vec::new(),
            edge,
            tip,
        })
    }

    /// The current parameters: law, thickness, then the rigidities when the bending is its
    /// own (the order of the sensitivities).
    fn current_params(&self) -> Vec<f64> {
        let mut k = self.material_params.clone();
        if let Some(b) = self.model.bending() {
            k.extend([b.warp, b.weft, b.twist]);
        }
        k
    }

    /// The warm start: the last equilibrium, moved along ∂q/∂k to the current parameters
    /// where the last run left a tangent for as many parameters.
    fn warm_start(&self) -> Option<Vec<Vec3>> {
        let mut x = self.equilibrium.clone()?;
        if let Some((k0, dq)) = &self.tangent {
            if k0.len() == self.params.len() {
                self.system.advance_along(&mut x, &self.params, k0, dq);
            }
        }
        Some(x)
    }

    /// Replaces the law and the thickness (mesh, clamp and warm start stay).
    pub fn set_material(
        &mut self,
        law: &crate::material::Orthotropic,
        thickness: f64,
    ) -> Result<(), SceneError> {
        self.model.law = Arc::new(law.clone());
        self.model.set_thickness(thickness)?;
        self.material_params = law.params();
        self.material_params.push(thickness);
        Ok(())
    }

    /// Replaces the bending rigidities (`None`: the paper's section).
    pub fn set_bending(&mut self, bending: Option<crate::material::BendingRigidity>) {
        self.model.set_bending(bending);
    }

    pub fn run(&mut self, sensitivities: bool) -> Result<BendPoint, SceneError> {
        self.params = self.current_params();
        let start = self.warm_start();
        let warm = start.is_some();
        let mut x = start.unwrap_or_else(|| self.model.basis.control_points.clone());
        // Newton iterations (and factorisations) of a warm start given up on: counted in the
        // report with the ramp's, so that the fitter's counts are of all the work done
        let mut spent = (0, 0);
        let full_step = self.bend.solver.strategy == Strategy::FullStep;
        let solved = if warm {
            self.solve_warm(&mut x, full_step, &mut spent)
        } else {
            None
        };
        let mut from_elastica = (0, 0);
        let solved = solved.or_else(|| {
            if !full_step {
                return None;
            }
            let (y, r) = solve_from_elastica(
                &self.model,
                &self.system,
                &self.bend,
                &self.bend.solver,
                &mut from_elastica,
            )?;
            x = y;
            Some(r)
        });
        spent.0 += from_elastica.0;
        spent.1 += from_elastica.1;
        let mut report = match solved {
            Some(r) => r,
            None => self.ramp_from_flat(&mut x)?,
        };
        report.iterations += spent.0;
        report.factorizations += spent.1;
        let (angle, dangle) = self.drape_angle(&x, sensitivities)?;
        self.equilibrium = Some(x);
        Ok(BendPoint {
            drape_angle_deg: angle,
            dangle,
            report,
        })
    }

    /// Newton from the warm start `x`; `None` where it does not converge, the iterations and
    /// factorisations it spent then added to `spent`.
    fn solve_warm(
        &self,
        x: &mut [Vec3],
        full_step: bool,
        spent: &mut (usize, usize),
    ) -> Option<SolveReport> {
        // a warm start that needs more than a few iterations is further off than the elastica
        // (where there is none, the ramp from flat is dearer than letting the warm start run)
        let warm_opts = NewtonOptions {
            max_iterations: if full_step && elastica_applies(&self.model, &self.bend) {
                self.bend.solver.max_iterations.min(WARM_ITERATIONS)
            } else {
                self.bend.solver.max_iterations
            },
            ..self.bend.solver
        };
        match newton(&self.model, &self.system, x, &warm_opts) {
            Ok(r) => Some(r),
            Err(e) => {
                if let SolveError::NotConverged {
                    iterations,
                    factorizations,
                    ..
                } = e
                {
                    spent.0 = iterations;
                    spent.1 = factorizations;
                }
                None
            }
        }
    }

    /// The equilibrium by a gravity ramp from the flat strip, into `x`.
    fn ramp_from_flat(&mut self, x: &mut Vec<Vec3>) -> Result<SolveReport, SceneError> {
        *x = self.model.basis.control_points.clone();
        let apply = |m: &mut ShellModel, t: f64, _: &[Vec3]| {
            m.set_gravity([0.0, 0.0, -STANDARD_GRAVITY * t]);
        };
        let cont = continuation(
            &mut self.model,
            &self.system,
            x,
            &self.bend.solver,
            1.0,
            apply,
        )
        .map_err(|(t, source)| SceneError::Solve {
            stage: format!("load factor {t:.4}"),
            source,
        })?;
        Ok(SolveReport {
            iterations: cont.iterations,
            factorizations: cont.factorizations,
            ..cont.last
        })
    }

    /// The drape angle at the equilibrium `x` (degrees) and, where asked for, its sensitivities
    /// (keeping ∂q/∂k for the next run's start; else dropping it).
    fn drape_angle(
        &mut self,
        x: &[Vec3],
        sensitivities: bool,
    ) -> Result<(f64, Vec<f64>), SceneError> {
        let surface = self.model.basis.surface();
        let stencil = |(face, u): (usize, f64), v: f64| {
            surface
                .stencil(face, u, v)
                .map_err(|e| SceneError::Basis(e.into()))
        };
        let (se, st) = (stencil(self.edge, 0.0)?, stencil(self.tip, 1.0)?);
        let (e, t) = (se.apply(x).x(), st.apply(x).x());
        let (dy, dz) = (t[1] - e[1], -(t[2] - e[2]));
        let angle = dz.atan2(dy).to_degrees();
        let dangle = if sensitivities {
            self.angle_sensitivities(x, (&se, &st), (dy, dz))?
        } else {
            self.tangent = None;
            Vec::new()
        };
        Ok((angle, dangle))
    }

    /// ∂angle/∂k at the equilibrium `x` by the adjoint of the tangent, the angle taken
    /// between the edge and tip points of the stencils `se` and `st` ((dy, dz) apart); keeps
    /// ∂q/∂k for the next run's start.
    fn angle_sensitivities(
        &mut self,
        x: &[Vec3],
        (se, st): (&LimitStencil, &LimitStencil),
        (dy, dz): (f64, f64),
    ) -> Result<Vec<f64>, SceneError> {
        // ∂angle/∂x: through dy and dz at the tip (+) and the edge (−) point
        let r2 = dy * dy + dz * dz;
        let (ay, az) = (-dz / r2, dy / r2);
        let mut c = vec![[0.0; 3]; x.len()];
        for (s, sign) in [(st, 1.0), (se, -1.0)] {
            for (&i, w) in s.indices.iter().zip(&s.weights) {
                c[i as usize][1] += sign * w[0] * ay;
                c[i as usize][2] -= sign * w[0] * az;
            }
        }
        let fail = |source| SceneError::Solve {
            stage: "drape-angle sensitivities".into(),
            source,
        };
        let lin = crate::solve::Linearization::new(&self.model, &self.system, x).map_err(fail)?;
        let lambda = lin.solve_reduced(&self.system, &c);
        let sens = self
            .model
            .sensitivities(x)
            .map_err(|e| fail(SolveError::StartOutOfDomain(e.to_string())))?;
        let mut dq = Vec::with_capacity(sens.gradient.len());
        let dangle = sens
            .gradient
            .iter()
            .map(|dg| {
                let reduced = self.system.reduced(dg);
                // ∂q/∂k, kept for the next run's start
                dq.push(lin.parameter_tangent(&self.system, dg));
                -lambda.iter().zip(&reduced).map(|(a, b)| a * b).sum::<f64>() * 180.0
                    / std::f64::consts::PI
            })
            .collect();
        self.tangent = (dq.len() == self.params.len()).then(|| (self.params.clone(), dq));
        Ok(dangle)
    }
}
