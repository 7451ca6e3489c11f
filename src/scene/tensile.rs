//! The ASTM D5035 strip tensile test: [`TensileStrip`] (one run) and [`StripRig`] (set up once,
//! run again with new material parameters, with force sensitivities: the fitter's forward model).

use super::{build_model, default_mesh, edge_clamp, free_system, positive, Hold, SceneError};
use crate::assembly::{ShellModel, YarnRule};
use crate::material::FabricMaterial;
use crate::mesh::Grading;
use crate::solve::{FreeSystem, NewtonOptions, Slave, SolveError, SolveReport};
use crate::subdiv::BoundaryRule;
use crate::Vec3;
use std::sync::Arc;

mod attempts;
mod point;
mod tangents;
mod warm;

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
    /// control lines crowded towards the jaws and the free edges ([`Grading`]; uniform by
    /// default)
    pub grading: Grading,
    pub solver: NewtonOptions,
    /// How the yarn terms are integrated ([`YarnRule::Auto`] by default: on the face centres
    /// for nearly inextensible yarns, whose bias strips lock on the full rule).
    pub yarn_rule: YarnRule,
    /// The yarn-to-shear ratio that decides `Auto` and sets the centre rule's β (`None`: the
    /// law's when the strip is set up). A fit pins it, so that every strip it builds, at any
    /// stage, has one discretisation.
    pub yarn_ratio: Option<f64>,
}

/// The strip cage grading (`--grading 0.8,0.8`): control lines crowded towards the jaws and
/// the free edges, edge cells 1/9 of the middle ones. The corners where a jaw meets a free edge
/// are singular, and a bias strip's force converges slowly there on uniform cages
/// (`cargo run --release --example graded_strip`, example cotton, 50 × 75 mm at 45° pulled
/// 3.75 mm, reference 5.90 N by Richardson): uniform 16×24 is 4.6 % off and converges at
/// order 1.3 (32×48: 2.0 %); graded 16×24 is 1.0 % off and converges at order 2.1–2.4
/// (32×48: 0.3 %), at the same cost per solve. At 90° the 16×24 error drops from 2.5e-4 to
/// 1.6e-5. The default of `fit --grading` and of `tensile` on its automatic mesh;
/// `tensile --mesh`, `converge tensile` and `synth` stay uniform by default. A raised degree
/// of the bias stage starts from a space-mapped point (`fit::surrogate`), which the graded
/// cages need to keep the stage from stalling.
pub const STRIP_GRADING: Grading = Grading {
    across: 0.8,
    along: 0.8,
};

/// One point of a virtual tensile curve.
#[derive(Clone, Debug, PartialEq)]
pub struct TensilePoint {
    /// m
    pub elongation: f64,
    /// N, the axial clamp reaction
    pub force: f64,
    pub report: SolveReport,
    /// ∂force/∂k (law parameters, then thickness) when asked for, else empty
    pub dforce: Vec<f64>,
}

impl TensileStrip {
    pub fn new(width: f64, length: f64, angle_deg: f64) -> Self {
        Self {
            width,
            length,
            angle_deg,
            mesh: default_mesh(width, length),
            boundary: BoundaryRule::Phantom,
            grading: Grading::UNIFORM,
            solver: NewtonOptions {
                max_iterations: STRIP_ITERATIONS,
                ..NewtonOptions::default()
            },
            yarn_rule: YarnRule::Auto,
            yarn_ratio: None,
        }
    }

    /// Forces at each elongation (m, increasing), each solve started from the last equilibrium
    /// stretched affinely to the new clamp position.
    pub fn run(
        &self,
        material: &FabricMaterial,
        elongations: &[f64],
    ) -> Result<Vec<TensilePoint>, SceneError> {
        self.rig(material, elongations)?.run(false)
    }

    /// As [`TensileStrip::run`], each point also carrying ∂force/∂k when asked for.
    pub fn run_with_sensitivities(
        &self,
        material: &FabricMaterial,
        elongations: &[f64],
        sensitivities: bool,
    ) -> Result<Vec<TensilePoint>, SceneError> {
        self.rig(material, elongations)?.run(sensitivities)
    }

    /// The strip set up once for repeated runs at the same elongations with changing material
    /// parameters (the fitter's forward model).
    pub fn rig(
        &self,
        material: &FabricMaterial,
        elongations: &[f64],
    ) -> Result<StripRig, SceneError> {
        positive("width", self.width)?;
        positive("gauge length", self.length)?;
        if let Some(dl) = elongations.iter().find(|d| !d.is_finite()) {
            return Err(SceneError::Input(format!(
                "elongation must be finite, got {dl:?}"
            )));
        }
        let (_, ny) = self.mesh;
        let model = build_model(
            material,
            (self.width, self.length),
            self.angle_deg,
            self.mesh,
            self.boundary,
            self.grading,
            (self.yarn_rule.for_strip(self.angle_deg), self.yarn_ratio),
        )?;
        let nn = model.num_nodes();
        let side = (self.width, self.length);
        let bottom = edge_clamp(
            &model,
            self.boundary,
            self.mesh,
            side,
            self.grading,
            0,
            1,
            Hold::Position,
        )?;
        let top = edge_clamp(
            &model,
            self.boundary,
            self.mesh,
            side,
            self.grading,
            ny as i64,
            -1,
            Hold::Position,
        )?;
        let mut fixed = vec![false; 3 * nn];
        for &d in bottom.fixed.iter().chain(&top.fixed) {
            fixed[d] = true;
        }
        let slaves: Vec<Slave> = bottom.slaves.iter().chain(&top.slaves).cloned().collect();
        let base: Vec<f64> = slaves.iter().map(|s| s.offset).collect();
        let rate: Vec<f64> = std::iter::repeat_n(0.0, bottom.slaves.len())
            .chain(top.offset_rate.iter().copied())
            .collect();
        let system = free_system(&model, &fixed, slaves)?;
        Ok(StripRig {
            length: self.length,
            solver: self.solver,
            model,
            system,
            bottom_fixed: bottom.fixed,
            top_fixed: top.fixed,
            motion: top.motion,
            base,
            rate,
            elongations: elongations.to_vec(),
            equilibria: vec![None; elongations.len()],
            tangents: vec![None; elongations.len()],
            earlier: vec![Vec::new(); elongations.len()],
            spent: 0,
            spent_factorizations: 0,
            stopped_at: None,
            solved_params: vec![None; elongations.len()],
            params: {
                let mut k = material.law.params();
                k.push(material.thickness);
                k
            },
            wanted: None,
            retry_iterations: None,
            yarn_ratio: self
                .yarn_ratio
                .or_else(|| crate::material::Law::yarn_shear_ratio(&material.law)),
        })
    }
}

/// Newton iterations a strip's point may take in all (its cheap attempts, sub-steps and the
/// whole budget of [`StripRig::solve_cold`]): thin off-axis strips wrinkle, and the
/// backward-Euler fallback needs time to settle them. The fit and the virtual lab share it;
/// the solver's general default (60) is too short here (`ks-fit tensile --mesh 32x48 --to 7.5
/// --steps 5` on the bundled fitted cotton and silk at 22.5° and 67.5° stops at 4.5 or 6 mm in
/// six of eight cases with it, at relative residuals of 9e-6–4e-4).
pub const STRIP_ITERATIONS: usize = 500;

/// Newton iterations a warm-started strip solve may take; past them it restarts cold.
const WARM_ITERATIONS: usize = 12;

/// The largest move of any control-point coordinate a predictor may make, in gauge lengths.
const MAX_PREDICTED_MOVE: f64 = 1.0;

/// The last equilibrium of a run: elongation, positions, and ∂q/∂(elongation) there (`None`
/// where it is unstable).
type Last = Option<(f64, Vec<Vec3>, Option<Vec<f64>>)>;

/// An equilibrium with its solver report and linearisation.
type Equilibrium = (Vec<Vec3>, SolveReport, Option<crate::solve::Linearization>);
type Solved = Result<Equilibrium, SceneError>;

/// The parameters (law, then thickness) of an equilibrium and ∂q/∂k there, one row per
/// parameter.
type ParameterTangent = (Vec<f64>, Vec<Vec<f64>>);

/// A tensile strip ready to be run again and again: model, constraints and the last
/// equilibrium at every elongation, which warm-starts the next run.
pub struct StripRig {
    length: f64,
    pub solver: NewtonOptions,
    /// Iterations allowed to the cold solve that follows a failed warm start (`None`: the
    /// solver's own limit). A fitter probing trial parameters sets a lower one: a trial whose
    /// equilibrium is that hard to reach is better rejected (its line search steps back) than
    /// crept up on by hundreds of backward-Euler steps.
    pub retry_iterations: Option<usize>,
    model: ShellModel,
    system: FreeSystem,
    bottom_fixed: Vec<usize>,
    top_fixed: Vec<usize>,
    /// (DOF, rate): the pulled clamp's DOFs and how fast each moves with the elongation
    motion: Vec<(usize, f64)>,
    base: Vec<f64>,
    rate: Vec<f64>,
    elongations: Vec<f64>,
    equilibria: Vec<Option<Vec<Vec3>>>,
    /// per point: the parameters (law, then thickness) of its equilibrium and ∂q/∂k there,
    /// which predict the equilibrium for new parameters (q + ∂q/∂k Δk)
    tangents: Vec<Option<ParameterTangent>>,
    /// per point: up to [`warm::SECANTS`] equilibria preceding the stored one, newest first,
    /// with their parameters (law, then thickness), for the secant predictor where no tangent
    /// is at hand (see [`StripRig::warm_start`])
    earlier: Vec<Vec<(Vec<Vec3>, Vec<f64>)>>,
    /// Newton iterations of attempts given up on since the last solved point (a warm
    /// start that does not converge, sub-steps): added to the point's report, so that counts
    /// of iterations are of all the work done
    spent: usize,
    /// the factorisations of those attempts
    spent_factorizations: usize,
    /// where the last attempt given up on stopped: (elongation, iterate), for resuming it
    stopped_at: Option<(f64, Vec<Vec3>)>,
    /// per point: the parameters of the stored equilibrium
    solved_params: Vec<Option<Vec<f64>>>,
    params: Vec<f64>,
    /// which parameters' sensitivities to compute (all when `None`; the others come back 0)
    wanted: Option<Vec<bool>>,
    /// the yarn-to-shear ratio the strip's discretisation is set up with (the centre rule's
    /// β); it stays when the material changes
    yarn_ratio: Option<f64>,
}

impl StripRig {
    /// Replaces the law and the thickness (the mesh, clamps and warm starts stay).
    pub fn set_material(
        &mut self,
        law: &crate::material::Orthotropic,
        thickness: f64,
    ) -> Result<(), SceneError> {
        self.model.law = Arc::new(law.clone());
        self.model.set_thickness(thickness)?;
        self.params = law.params();
        self.params.push(thickness);
        Ok(())
    }

    /// Replaces the bending rigidities (`None`: the paper's section).
    pub fn set_bending(&mut self, bending: Option<crate::material::BendingRigidity>) {
        self.model.set_bending(bending);
    }

    /// Restricts the sensitivities to the parameters marked true (law parameters, then
    /// thickness); the others are reported as 0. `None`: all.
    pub fn set_wanted(&mut self, wanted: Option<Vec<bool>>) {
        self.wanted = wanted;
    }

    /// Smallest and largest membrane strain (warp/weft frame) of the last run's equilibrium at
    /// the largest elongation.
    pub fn strain_range(&self) -> Option<([f64; 3], [f64; 3])> {
        let x = self.equilibria.last()?.as_ref()?;
        Some(self.model.membrane_strain_range(x))
    }

    pub fn elongations(&self) -> &[f64] {
        &self.elongations
    }

    /// The yarn-to-shear ratio that set up this strip's discretisation ([`TensileStrip`]'s
    /// `yarn_ratio`, or its first law's): a strip built with it solves on the same one.
    pub fn yarn_ratio(&self) -> Option<f64> {
        self.yarn_ratio
    }

    /// Forces at every elongation; with `sensitivities`, also ∂force/∂k for the law's
    /// parameters and then the thickness (adjoint form of Clyde et al. 2017, Eq. 6: with
    /// F = rᵀg(x, k) and K λ = Tᵀ H r, dF/dk = rᵀ ∂g/∂k − λᵀ Tᵀ ∂g/∂k; one solve per point
    /// whatever the number of parameters).
    pub fn run(&mut self, sensitivities: bool) -> Result<Vec<TensilePoint>, SceneError> {
        self.run_each(sensitivities, &mut |_| {})
    }

    /// As [`StripRig::run`], handing each point to `each` as soon as it is solved (a long
    /// curve's rows are printed as they come).
    pub fn run_each(
        &mut self,
        sensitivities: bool,
        each: &mut dyn FnMut(&TensilePoint),
    ) -> Result<Vec<TensilePoint>, SceneError> {
        let nn = self.model.num_nodes();
        let mut grad = vec![[0.0; 3]; nn];
        let mut out = Vec::with_capacity(self.elongations.len());
        // the last equilibrium: elongation, positions, and ∂q/∂(elongation) there
        let mut previous: Last = None;
        // the equilibrium preceding `previous` (elongation, positions): the predictor's curvature
        let mut before: Option<(f64, Vec<Vec3>)> = None;
        // the last point did not start from a good warm start: this one's is compared with
        // the predictor from the last equilibrium first
        let mut doubt = false;
        // a stored equilibrium of this run turned out a saddle for the new parameters (it is
        // flat where the strip now wrinkles): the later points' stored ones are on the same
        // lost branch, and the predictor from the wrinkled state just solved is taken in their
        // place (on the bundled cotton such a warm start spends 11–12 iterations, mostly
        // escaping the saddle)
        let mut lost_branch = false;
        for i in 0..self.elongations.len() {
            let started = std::time::Instant::now();
            let dl = self.elongations[i];
            let (x, mut report, lin) = self.solve_point(
                i,
                dl,
                (&previous, before.as_ref()),
                &mut doubt,
                &mut lost_branch,
            )?;
            report.iterations += std::mem::take(&mut self.spent);
            report.factorizations += std::mem::take(&mut self.spent_factorizations);
            // the point's time is that of all its attempts, as its iterations are (the last
            // attempt's alone understated a wrinkling point's several times over)
            report.seconds = started.elapsed().as_secs_f64();
            let force = self.reaction(&x, lin.as_ref(), &mut grad)?;
            let slope = lin.as_ref().map(|l| self.elongation_tangent(l));
            let dforce = if sensitivities {
                self.point_sensitivities(i, dl, &x, lin, &mut report)?
            } else {
                self.tangents[i] = None;
                Vec::new()
            };
            let point = TensilePoint {
                elongation: dl,
                force,
                report,
                dforce,
            };
            each(&point);
            out.push(point);
            self.keep_equilibrium(i, &x);
            before = previous.map(|p| (p.0, p.1));
            previous = Some((dl, x, slope));
        }
        Ok(out)
    }

    /// The predictor at elongation `dl`: the last equilibrium moved along its tangent to the
    /// new jaw position (Euler continuation on the factorised tangent), plus, where the
    /// preceding equilibrium `before` is known, the quadratic term of the path through the two
    /// (x(e) = x₁ + (e − e₁) x₁′ + c (e − e₁)², c from x₀ at e₀: what Euler misses over the last
    /// step, scaled by the square of the step ratio); or, where there is no tangent (the
    /// first point, an unstable equilibrium), stretched affinely.
    fn predict(&self, previous: &Last, before: Option<&(f64, Vec<Vec3>)>, dl: f64) -> Vec<Vec3> {
        // a tangent from a nearly singular Hessian (a strip at the edge of buckling) can move
        // the cage by far more than the strip's size: such a start is worthless (an energy of
        // 1e241 J and forces that overflow), so the affine stretch replaces it
        let sane = |slope: &[f64], h: f64| {
            slope
                .iter()
                .all(|v| v.is_finite() && (v * h).abs() <= MAX_PREDICTED_MOVE * self.length)
        };
        match previous {
            Some((current, x1, Some(slope))) if sane(slope, dl - current) => {
                let mut x = x1.clone();
                let step: Vec<f64> = slope.iter().map(|v| v * (dl - current)).collect();
                self.system.advance(&mut x, &step);
                if let Some((e0, x0)) =
                    before.filter(|b| b.0 < *current && sane(slope, current - b.0))
                {
                    let h = current - e0;
                    let mut back = x1.clone();
                    let step: Vec<f64> = slope.iter().map(|v| -v * h).collect();
                    self.system.advance(&mut back, &step);
                    let w = ((dl - current) / h).powi(2);
                    for ((p, a), b) in x.iter_mut().zip(x0).zip(&back) {
                        for c in 0..3 {
                            p[c] += w * (a[c] - b[c]);
                        }
                    }
                }
                x
            }
            _ => {
                let (current, mut x) = previous.as_ref().map_or(
                    (0.0, self.model.basis.control_points.clone()),
                    |(c, x, _)| (*c, x.clone()),
                );
                let s = (self.length + dl) / (self.length + current);
                for p in &mut x {
                    p[1] *= s;
                }
                x
            }
        }
    }

    /// A point that failed, with the Newton iterations of all its attempts (warm start, cheap
    /// attempts, sub-steps, the whole budget) in place of the last attempt's alone, which
    /// would understate the work (a strip that has spent its 60 would say "did not converge in
    /// 20"). The attempts stay counted in `spent`, for the next point solved (a fitter's counts).
    fn point_failure(&self, e: SceneError) -> SceneError {
        let total = self.spent;
        match e {
            SceneError::Solve {
                stage,
                source:
                    SolveError::NotConverged {
                        residual,
                        factorizations,
                        iterations,
                    },
            } => SceneError::Solve {
                stage,
                source: SolveError::NotConverged {
                    iterations: total.max(iterations),
                    residual,
                    factorizations,
                },
            },
            e => e,
        }
    }

    /// Sets the constraints of elongation `dl` and puts the clamped DOFs of `x` there.
    fn place(&mut self, dl: f64, x: &mut [Vec3]) {
        let offsets: Vec<f64> = self
            .base
            .iter()
            .zip(&self.rate)
            .map(|(b, r)| b + r * dl)
            .collect();
        self.system.set_offsets(&offsets);
        let rest = &self.model.basis.control_points;
        for &d in &self.bottom_fixed {
            x[d / 3][d % 3] = rest[d / 3][d % 3];
        }
        for &d in &self.top_fixed {
            x[d / 3][d % 3] = rest[d / 3][d % 3] + if d % 3 == 1 { dl } else { 0.0 };
        }
    }

    /// The relative residual of the start `x` at elongation `dl` (one gradient assembly;
    /// infinite where the law is undefined there).
    fn start_residual(&mut self, dl: f64, x: &[Vec3]) -> f64 {
        let mut x = x.to_vec();
        self.place(dl, &mut x);
        crate::solve::relative_residual(&self.model, &self.system, &x).unwrap_or(f64::INFINITY)
    }

    /// The energy of the start `x` at elongation `dl` (infinite where the law is undefined).
    fn start_energy(&mut self, dl: f64, x: &[Vec3]) -> f64 {
        let mut x = x.to_vec();
        self.place(dl, &mut x);
        self.system.apply_constraints(&mut x);
        self.model.energy(&x).unwrap_or(f64::INFINITY)
    }

    /// The equilibrium at elongation `dl` from the start `x`.
    fn solve_at(&mut self, dl: f64, mut x: Vec<Vec3>, max_iterations: usize) -> Solved {
        self.place(dl, &mut x);
        let opts = NewtonOptions {
            max_iterations,
            ..self.solver
        };
        let solved = crate::solve::newton_linearized(&self.model, &self.system, &mut x, &opts);
        if let Err(SolveError::NotConverged {
            iterations,
            factorizations,
            ..
        }) = &solved
        {
            self.spent += iterations;
            self.spent_factorizations += factorizations;
            self.stopped_at = Some((dl, x.clone()));
        }
        solved
            .map(|(report, lin)| (x, report, lin))
            .map_err(|source| SceneError::Solve {
                stage: format!("elongation {:.4} mm", dl * 1e3),
                source,
            })
    }
}

#[cfg(test)]
mod tests;
