//! The virtual lab (Clyde et al. 2017 §4): a tensile strip (ASTM D5035) and a cantilever bend
//! (ASTM D1388), each returning what the instrument measures.
//!
//! Angles are measured from the weft: 0° is a weft strip, 90° a warp strip, 45° bias. The strip's
//! axis is y; its weft direction is (sin θ, cos θ, 0) and its warp (cos θ, −sin θ, 0).

pub mod plate;
pub mod roof;
pub mod sphere;

use crate::assembly::{ModelError, ShellModel, STANDARD_GRAVITY};
use crate::material::FabricMaterial;
use crate::mesh::rectangular_grid;
use crate::solve::{
    continuation, newton, ContinuationReport, FreeSystem, NewtonOptions, Slave, SolveError,
    SolveReport,
};
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
    model: &ShellModel,
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
            "{name} must be a positive number, got {v:?}"
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
            "angle must be finite, got {angle_deg:?}"
        )));
    }
    crate::limits::check_mesh(&format!("mesh {nx}x{ny}"), nx, ny).map_err(SceneError::Input)?;
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
    let mut model = ShellModel::new(
        basis,
        warp_direction(angle_deg),
        Arc::new(material.law.clone()),
        material.thickness,
        material.areal_density,
    )?;
    model.set_bending(material.bending);
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

fn edge_clamp(
    model: &ShellModel,
    rule: BoundaryRule,
    (nx, ny): (usize, usize),
    (hx, hy): (f64, f64),
    row: i64,
    inward: i64,
    hold: Hold,
) -> Result<EdgeClamp, SceneError> {
    let x0 = &model.basis.control_points;
    let mut lattice = std::collections::HashMap::new();
    for (v, p) in x0.iter().enumerate() {
        lattice.insert(((p[0] / hx).round() as i64, (p[1] / hy).round() as i64), v);
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

/// Grid spacing of a strip mesh.
fn spacing(width: f64, length: f64, (nx, ny): (usize, usize)) -> (f64, f64) {
    (width / nx as f64, length / ny as f64)
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
    pub solver: NewtonOptions,
}

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
            solver: NewtonOptions::default(),
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
            self.width,
            self.length,
            self.angle_deg,
            self.mesh,
            self.boundary,
        )?;
        let nn = model.num_nodes();
        let h = spacing(self.width, self.length, self.mesh);
        let bottom = edge_clamp(&model, self.boundary, self.mesh, h, 0, 1, Hold::Position)?;
        let top = edge_clamp(
            &model,
            self.boundary,
            self.mesh,
            h,
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
            params: {
                let mut k = material.law.params();
                k.push(material.thickness);
                k
            },
            wanted: None,
            retry_iterations: None,
        })
    }
}

/// Newton iterations a warm-started strip solve may take before it restarts cold.
const WARM_ITERATIONS: usize = 12;

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
    params: Vec<f64>,
    /// which parameters' sensitivities to compute (all when `None`; the others come back 0)
    wanted: Option<Vec<bool>>,
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

    /// Takes `other`'s equilibria as this rig's warm starts, where the two rigs share the
    /// mesh, the clamps and the elongations (strips cut at nearby angles: the angle changes
    /// only the material frame, not the control net). Returns whether they were taken. The
    /// parameter tangents are not taken: they belong to the other angle's equilibria.
    pub fn warm_from(&mut self, other: &StripRig) -> bool {
        let same = self.elongations == other.elongations
            && self.length == other.length
            && self.model.basis.control_points == other.model.basis.control_points
            && self.bottom_fixed == other.bottom_fixed
            && self.top_fixed == other.top_fixed;
        if !same {
            return false;
        }
        for (mine, theirs) in self.equilibria.iter_mut().zip(&other.equilibria) {
            if mine.is_none() {
                mine.clone_from(theirs);
            }
        }
        true
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
        let rest = self.model.basis.control_points.clone();
        let mut grad = vec![[0.0; 3]; nn];
        let mut out = Vec::with_capacity(self.elongations.len());
        // the last equilibrium: elongation, positions, and ∂q/∂(elongation) there
        let mut previous: Option<(f64, Vec<Vec3>, Option<Vec<f64>>)> = None;
        for i in 0..self.elongations.len() {
            let dl = self.elongations[i];
            // predictor: the last equilibrium moved along its tangent to the new jaw position
            // (Euler continuation on the factorised tangent), or, where there is none (the
            // first point, an unstable equilibrium), stretched affinely
            type Last = Option<(f64, Vec<Vec3>, Option<Vec<f64>>)>;
            let cold = |system: &FreeSystem, previous: &Last| match previous {
                Some((current, x, Some(slope))) => {
                    let mut x = x.clone();
                    let step: Vec<f64> = slope.iter().map(|v| v * (dl - current)).collect();
                    system.advance(&mut x, &step);
                    x
                }
                _ => {
                    let (current, mut x) = previous
                        .as_ref()
                        .map_or((0.0, rest.clone()), |(c, x, _)| (*c, x.clone()));
                    let s = (self.length + dl) / (self.length + current);
                    for p in &mut x {
                        p[1] *= s;
                    }
                    x
                }
            };
            let warm = self.equilibria[i].as_ref().map(|x| {
                let mut x = x.clone();
                // first-order predictor along the parameter change
                if let Some((k0, dq)) = &self.tangents[i] {
                    if k0.len() == self.params.len() {
                        let mut d = vec![0.0; self.system.num_free];
                        for ((k, k0), dqj) in self.params.iter().zip(k0).zip(dq) {
                            let dk = k - k0;
                            if dk != 0.0 {
                                d.iter_mut().zip(dqj).for_each(|(a, b)| *a += dk * b);
                            }
                        }
                        self.system.advance(&mut x, &d);
                    }
                }
                x
            });
            let offsets: Vec<f64> = self
                .base
                .iter()
                .zip(&self.rate)
                .map(|(b, r)| b + r * dl)
                .collect();
            self.system.set_offsets(&offsets);
            let stage = || format!("elongation {:.4} mm", dl * 1e3);
            let solve = |mut x: Vec<Vec3>, max_iterations: usize| {
                for &d in &self.bottom_fixed {
                    x[d / 3][d % 3] = rest[d / 3][d % 3];
                }
                for &d in &self.top_fixed {
                    x[d / 3][d % 3] = rest[d / 3][d % 3] + if d % 3 == 1 { dl } else { 0.0 };
                }
                let opts = NewtonOptions {
                    max_iterations,
                    ..self.solver
                };
                crate::solve::newton_linearized(&self.model, &self.system, &mut x, &opts)
                    .map(|(report, lin)| (x, report, lin))
                    .map_err(|source| SceneError::Solve {
                        stage: stage(),
                        source,
                    })
            };
            // a warm start that needs many iterations has wandered off (parameters far from
            // the last run's): give up early and solve from the predictor instead
            let (x, report, lin) = match warm {
                Some(x) => match solve(x, self.solver.max_iterations.min(WARM_ITERATIONS)) {
                    Ok(r) => r,
                    Err(_) => solve(
                        cold(&self.system, &previous),
                        self.retry_iterations
                            .unwrap_or(self.solver.max_iterations)
                            .min(self.solver.max_iterations),
                    )?,
                },
                None => solve(cold(&self.system, &previous), self.solver.max_iterations)?,
            };
            let reaction_error = |e: crate::material::OutOfDomain| SceneError::Solve {
                stage: "reaction".into(),
                source: SolveError::StartOutOfDomain(e.to_string()),
            };
            self.model
                .assemble(&x, crate::assembly::Want::Gradient, Some(&mut grad), None)
                .map_err(reaction_error)?;
            let force: f64 = self
                .motion
                .iter()
                .map(|&(d, r)| r * grad[d / 3][d % 3])
                .sum();
            let slope = lin.as_ref().map(|l| self.elongation_tangent(l));
            let dforce = if sensitivities {
                let (df, dq) =
                    self.force_sensitivities(&x, lin)
                        .map_err(|source| SceneError::Solve {
                            stage: format!("sensitivities at {}", stage()),
                            source,
                        })?;
                self.tangents[i] = Some((self.params.clone(), dq));
                df
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
            self.equilibria[i] = Some(x.clone());
            previous = Some((dl, x, slope));
        }
        Ok(out)
    }

    /// ∂q/∂(elongation) at an equilibrium: with x = T q + x̄ and the jaw's motion u = ∂x̄/∂(dl)
    /// (the moving clamp's y DOFs, and the slaves' offset rates), K ∂q/∂(dl) = −Tᵀ H u.
    fn elongation_tangent(&self, lin: &crate::solve::Linearization) -> Vec<f64> {
        let nn = self.model.num_nodes();
        let mut u = vec![[0.0; 3]; nn];
        for &d in &self.top_fixed {
            if d % 3 == 1 {
                u[d / 3][1] = 1.0;
            }
        }
        for (s, r) in self.system.slaves().iter().zip(&self.rate) {
            u[s.dof / 3][s.dof % 3] = *r;
        }
        let mut hu = vec![[0.0; 3]; nn];
        lin.hessian.mul(&u, &mut hu);
        lin.solve_reduced(&self.system, &hu)
            .into_iter()
            .map(|v| -v)
            .collect()
    }

    /// ∂F/∂k and ∂q/∂k (reduced) for every parameter.
    #[allow(clippy::type_complexity)]
    fn force_sensitivities(
        &self,
        x: &[Vec3],
        lin: Option<crate::solve::Linearization>,
    ) -> Result<(Vec<f64>, Vec<Vec<f64>>), SolveError> {
        // an equilibrium that ended unstable (a wrinkling strip's saddle) gets the
        // sensitivities of a regularised tangent; the point's report says it is not stable
        let lin = match lin {
            Some(l) => l,
            None => crate::solve::Linearization::new_regularized(&self.model, &self.system, x)?.0,
        };
        let sens = self
            .model
            .sensitivities_of(x, self.wanted.as_deref())
            .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
        let mut r = vec![[0.0; 3]; x.len()];
        for &(d, c) in &self.motion {
            r[d / 3][d % 3] += c;
        }
        let mut hr = vec![[0.0; 3]; x.len()];
        lin.hessian.mul(&r, &mut hr);
        let lambda = lin.solve_reduced(&self.system, &hr);
        let mut dq = Vec::with_capacity(sens.gradient.len());
        let df = sens
            .gradient
            .iter()
            .enumerate()
            .map(|(j, dg)| {
                if self
                    .wanted
                    .as_ref()
                    .is_some_and(|w| w.get(j) != Some(&true))
                {
                    dq.push(vec![0.0; self.system.num_free]);
                    return 0.0;
                }
                let direct: f64 = self.motion.iter().map(|&(d, c)| c * dg[d / 3][d % 3]).sum();
                let reduced = self.system.reduced(dg);
                // ∂q/∂k = −K⁻¹ Tᵀ ∂g/∂k, kept for the next run's predictor
                dq.push(
                    lin.solve_reduced(&self.system, dg)
                        .iter()
                        .map(|v| -v)
                        .collect(),
                );
                direct - lambda.iter().zip(&reduced).map(|(a, b)| a * b).sum::<f64>()
            })
            .collect();
        Ok((df, dq))
    }
}

/// An ASTM D1388 cantilever (self-weight only) set up once for repeated runs with changing
/// material parameters: the fitter's forward model of a bend test. Each run starts from the
/// last equilibrium, falling back to a load ramp from the flat strip.
pub struct BendRig {
    bend: CantileverBend,
    model: ShellModel,
    system: FreeSystem,
    equilibrium: Option<Vec<Vec3>>,
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
    pub report: SolveReport,
}

/// A cantilever's model and platform clamp (see [`CantileverBend::clamped`]).
struct Clamped {
    model: ShellModel,
    fixed: Vec<bool>,
    clamp: EdgeClamp,
    edge: (usize, f64),
    tip: (usize, f64),
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
            edge,
            tip,
        })
    }

    /// Replaces the law and the thickness (mesh, clamp and warm start stay).
    pub fn set_material(
        &mut self,
        law: &crate::material::Orthotropic,
        thickness: f64,
    ) -> Result<(), SceneError> {
        self.model.law = Arc::new(law.clone());
        self.model.set_thickness(thickness)?;
        Ok(())
    }

    /// Replaces the bending rigidities (`None`: the paper's section).
    pub fn set_bending(&mut self, bending: Option<crate::material::BendingRigidity>) {
        self.model.set_bending(bending);
    }

    pub fn run(&mut self, sensitivities: bool) -> Result<BendPoint, SceneError> {
        let mut x = match &self.equilibrium {
            Some(x) => x.clone(),
            None => self.model.basis.control_points.clone(),
        };
        let warm = self.equilibrium.is_some();
        let solved = if warm {
            newton(&self.model, &self.system, &mut x, &self.bend.solver).ok()
        } else {
            None
        };
        let report = match solved {
            Some(r) => r,
            None => {
                x = self.model.basis.control_points.clone();
                let apply = |m: &mut ShellModel, t: f64, _: &[Vec3]| {
                    m.set_gravity([0.0, 0.0, -STANDARD_GRAVITY * t]);
                };
                let cont = continuation(
                    &mut self.model,
                    &self.system,
                    &mut x,
                    &self.bend.solver,
                    1.0,
                    apply,
                )
                .map_err(|(t, source)| SceneError::Solve {
                    stage: format!("load factor {t:.4}"),
                    source,
                })?;
                cont.last
            }
        };
        let surface = self.model.basis.surface();
        let stencil = |(face, u): (usize, f64), v: f64| {
            surface
                .stencil(face, u, v)
                .map_err(|e| SceneError::Basis(e.into()))
        };
        let (se, st) = (stencil(self.edge, 0.0)?, stencil(self.tip, 1.0)?);
        let (e, t) = (se.apply(&x).x(), st.apply(&x).x());
        let (dy, dz) = (t[1] - e[1], -(t[2] - e[2]));
        let angle = dz.atan2(dy).to_degrees();
        let dangle = if sensitivities {
            // ∂angle/∂x: through dy and dz at the tip (+) and the edge (−) point
            let r2 = dy * dy + dz * dz;
            let (ay, az) = (-dz / r2, dy / r2);
            let mut c = vec![[0.0; 3]; x.len()];
            for (s, sign) in [(&st, 1.0), (&se, -1.0)] {
                for (&i, w) in s.indices.iter().zip(&s.weights) {
                    c[i as usize][1] += sign * w[0] * ay;
                    c[i as usize][2] -= sign * w[0] * az;
                }
            }
            let fail = |source| SceneError::Solve {
                stage: "drape-angle sensitivities".into(),
                source,
            };
            let lin =
                crate::solve::Linearization::new(&self.model, &self.system, &x).map_err(fail)?;
            let lambda = lin.solve_reduced(&self.system, &c);
            let sens = self
                .model
                .sensitivities(&x)
                .map_err(|e| fail(SolveError::StartOutOfDomain(e.to_string())))?;
            sens.gradient
                .iter()
                .map(|dg| {
                    let reduced = self.system.reduced(dg);
                    -lambda.iter().zip(&reduced).map(|(a, b)| a * b).sum::<f64>() * 180.0
                        / std::f64::consts::PI
                })
                .collect()
        } else {
            Vec::new()
        };
        self.equilibrium = Some(x);
        Ok(BendPoint {
            drape_angle_deg: angle,
            dangle,
            report,
        })
    }
}

/// ASTM D1388 cantilever: a strip of `width` overhanging the platform edge by `overhang`, the
/// part on the platform clamped (the edge keeps its position and its horizontal slope; see
/// [`BoundaryRule`] for how each rule does it), sagging under gravity.
#[derive(Clone, Debug)]
pub struct CantileverBend {
    /// m
    pub width: f64,
    /// m
    pub overhang: f64,
    pub angle_deg: f64,
    pub mesh: (usize, usize),
    /// Default: ghost, whose clamp leaves the curvature at the edge free (see `EdgeClamp`);
    /// the phantom clamp forces it to zero and converges at about first order.
    pub boundary: BoundaryRule,
    /// Self-weight on (the ASTM test) or off.
    pub gravity: bool,
    /// Total dead force on the free edge, spread uniformly along it, N (zero for ASTM D1388).
    pub tip_force: Vec3,
    /// Total end moment about the x axis, N·m, following the rotation of the free edge
    /// (positive rolls the strip up towards +z; the edge angle is unwrapped between load steps,
    /// so the moment may turn it through more than half a turn).
    pub tip_moment: f64,
    /// Hold every control point's x coordinate (across the width): bending in the y–z plane
    /// only, as beam benchmarks assume. Off by default. Needed for an end moment beyond about
    /// 0.93 of the full circle: there the planar equilibrium under the fixed-axis moment is a
    /// saddle of the full 3-D problem (an out-of-plane twisting mode; measured on the Sze 3.2
    /// strip, 2 × 32), so an unconstrained solve leaves the plane.
    pub in_plane: bool,
    pub solver: NewtonOptions,
    /// Raise the load gradually (default); otherwise apply it all in one solve.
    pub continuation: bool,
}

/// The measured bend.
#[derive(Clone, Debug, PartialEq)]
pub struct BendResult {
    /// Chord angle from the platform edge to the free-end tip, below horizontal, degrees.
    pub drape_angle_deg: f64,
    /// Tip position (mid-width of the free edge), m.
    pub tip: Vec3,
    pub load_steps: usize,
    /// Newton iterations over all load steps (failed attempts included).
    pub iterations: usize,
    /// Numeric factorisations over all load steps (failed attempts included).
    pub factorizations: usize,
    pub report: SolveReport,
    /// For an in-plane solve ([`CantileverBend::in_plane`]): whether the end state is also
    /// stable once the x coordinates are let go (false: a saddle of the 3-D problem).
    pub stable_out_of_plane: Option<bool>,
}

/// Default element size of a cantilever mesh, m (as the 8 × 12 tensile mesh of a 50 × 75 mm
/// strip).
pub const BEND_ELEMENT: f64 = 6.25e-3;

impl CantileverBend {
    pub fn new(width: f64, overhang: f64, angle_deg: f64) -> Self {
        // elements of about 6.25 mm, at least 4 across; a narrow strip keeps 6.25 mm along
        // (how finely it must be cut along depends on its curvature, not its width)
        let nx = ((width / BEND_ELEMENT).round() as usize).max(4);
        let along = (width / nx as f64).max(BEND_ELEMENT);
        let ny = ((overhang / along).round() as usize).max(2);
        Self {
            width,
            overhang,
            angle_deg,
            mesh: (nx, ny),
            boundary: BoundaryRule::Ghost,
            gravity: true,
            tip_force: [0.0; 3],
            tip_moment: 0.0,
            in_plane: false,
            solver: NewtonOptions::default(),
            continuation: true,
        }
    }

    /// The model on its mesh with the platform clamp (edge position and slope held), the
    /// clamped DOFs marked, and the (face, u) of the mid-width points of the clamped edge
    /// (v = 0) and of the tip (v = 1): what a single run and the fitter's rig share.
    fn clamped(&self, material: &FabricMaterial) -> Result<Clamped, SceneError> {
        positive("width", self.width)?;
        positive("overhang", self.overhang)?;
        let (nx, ny) = self.mesh;
        if ny < 2 {
            return Err(SceneError::Input(
                "the cantilever mesh needs at least 2 rows".into(),
            ));
        }
        let model = build_model(
            material,
            self.width,
            self.overhang,
            self.angle_deg,
            self.mesh,
            self.boundary,
        )?;
        let h = spacing(self.width, self.overhang, self.mesh);
        let clamp = edge_clamp(
            &model,
            self.boundary,
            self.mesh,
            h,
            0,
            1,
            Hold::PositionAndSlope,
        )?;
        let mut fixed = vec![false; 3 * model.num_nodes()];
        for &d in &clamp.fixed {
            fixed[d] = true;
        }
        let mid = nx / 2;
        let u = if nx % 2 == 0 { 0.0 } else { 0.5 };
        Ok(Clamped {
            model,
            fixed,
            clamp,
            edge: (mid, u),
            tip: ((ny - 1) * nx + mid, u),
        })
    }

    pub fn run(&self, material: &FabricMaterial) -> Result<BendResult, SceneError> {
        let (nx, ny) = self.mesh;
        let Clamped {
            mut model,
            mut fixed,
            clamp,
            edge,
            tip,
        } = self.clamped(material)?;
        let nn = model.num_nodes();
        let clamp_slaves = clamp.slaves.clone();
        let mut slaves = clamp.slaves;
        if self.in_plane {
            for n in 0..nn {
                fixed[3 * n] = true;
            }
            // a ghost point's x is an affine function of held x coordinates: hold it as well
            slaves.retain(|s| s.dof % 3 != 0);
        }
        let system = free_system(&model, &fixed, slaves)?;
        let mut x = model.basis.control_points.clone();
        let tip_faces: Vec<usize> = ((ny - 1) * nx..ny * nx).collect();
        let per_length = self.tip_force.map(|f| f / self.width);
        let tip_load = model.edge_load(&tip_faces, 1.0, per_length);
        let g = if self.gravity { STANDARD_GRAVITY } else { 0.0 };
        let moment = self.tip_moment / self.width;
        if moment != 0.0 {
            model.set_edge_moment(&tip_faces, 1.0, 0.0);
        }
        let apply = |m: &mut ShellModel, t: f64, x: &[Vec3]| {
            m.set_gravity([0.0, 0.0, -g * t]);
            m.set_dead_load(tip_load.iter().map(|f| f.map(|c| c * t)).collect());
            m.update_edge_angles(x);
            m.scale_edge_moment(moment * t);
        };
        // an end moment turns the edge by up to a full circle: steps of at most 1/8 keep each
        // solve's rotation well below the half turn the angle is unwrapped over
        let max_step = if moment != 0.0 { 0.125 } else { 1.0 };
        let cont = if self.continuation {
            continuation(&mut model, &system, &mut x, &self.solver, max_step, apply).map_err(
                |(t, source)| SceneError::Solve {
                    stage: format!("load factor {t:.4}"),
                    source,
                },
            )?
        } else {
            let start = x.clone();
            apply(&mut model, 1.0, &start);
            let last = equilibrium(&model, &system, &mut x, &self.solver, || {
                "full load in one step".into()
            })?;
            ContinuationReport {
                steps: 1,
                iterations: last.iterations,
                factorizations: last.factorizations,
                last,
            }
        };
        let stable_out_of_plane = if self.in_plane {
            let mut fixed = vec![false; 3 * nn];
            for &d in &clamp.fixed {
                fixed[d] = true;
            }
            let full = free_system(&model, &fixed, clamp_slaves)?;
            Some(
                crate::solve::is_stable(&model, &full, &x).map_err(|source| SceneError::Solve {
                    stage: "out-of-plane stability check".into(),
                    source,
                })?,
            )
        } else {
            None
        };
        let surface = model.basis.surface();
        let eval = |(face, u): (usize, f64), v: f64| -> Result<Vec3, SceneError> {
            let s = surface
                .stencil(face, u, v)
                .map_err(|e| SceneError::Basis(e.into()))?;
            Ok(s.apply(&x).x())
        };
        let edge = eval(edge, 0.0)?;
        let tip = eval(tip, 1.0)?;
        let angle = (-(tip[2] - edge[2])).atan2(tip[1] - edge[1]).to_degrees();
        Ok(BendResult {
            drape_angle_deg: angle,
            tip,
            load_steps: cont.steps,
            iterations: cont.iterations,
            factorizations: cont.factorizations,
            report: cont.last,
            stable_out_of_plane,
        })
    }
}
