//! The ASTM D1388 cantilever bend test: [`CantileverBend`] (one run, also with a tip force or
//! moment for the beam benchmarks) and [`BendRig`] (set up once, run again with new material
//! parameters, with drape-angle sensitivities: the fitter's forward model).

use super::{
    build_model, edge_clamp, equilibrium, free_system, positive, EdgeClamp, Hold, SceneError,
};
use crate::assembly::{ShellModel, YarnRule, STANDARD_GRAVITY};
use crate::material::FabricMaterial;
use crate::mesh::Grading;
use crate::solve::{
    continuation, newton, ContinuationReport, FreeSystem, NewtonOptions, Slave, SolveError,
    SolveReport, Strategy,
};
use crate::subdiv::BoundaryRule;
use crate::Vec3;

mod rig;

pub use rig::{BendPoint, BendRig};

/// A cantilever's model and platform clamp (see [`CantileverBend::clamped`]).
struct Clamped {
    model: ShellModel,
    fixed: Vec<bool>,
    clamp: EdgeClamp,
    edge: (usize, f64),
    tip: (usize, f64),
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
    /// saddle of the full 3-D problem (an out-of-plane twisting mode, as on the Sze 3.2
    /// strip, 2 × 32), so an unconstrained solve leaves the plane.
    pub in_plane: bool,
    pub solver: NewtonOptions,
    /// Raise the load gradually (default); otherwise apply it all in one solve.
    pub continuation: bool,
    /// How the yarn terms are integrated ([`YarnRule::Auto`] by default, which is the full
    /// rule in a bend: [`YarnRule::for_bending`]).
    pub yarn_rule: YarnRule,
}

/// The bend as the instrument reads it.
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
            yarn_rule: YarnRule::Auto,
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
            (self.width, self.overhang),
            self.angle_deg,
            self.mesh,
            self.boundary,
            Grading::UNIFORM,
            (self.yarn_rule.for_bending(), None),
        )?;
        let clamp = edge_clamp(
            &model,
            self.boundary,
            self.mesh,
            (self.width, self.overhang),
            Grading::UNIFORM,
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
        // under its own weight alone: Newton from the elastica first
        let mut spent = (0, 0);
        let elastica = if self.gravity
            && self.tip_force == [0.0; 3]
            && moment == 0.0
            && self.solver.strategy == Strategy::FullStep
        {
            apply(&mut model, 1.0, &x);
            solve_from_elastica(&model, &system, self, &self.solver, &mut spent)
        } else {
            None
        };
        let mut cont = if let Some((y, last)) = elastica {
            x = y;
            ContinuationReport {
                steps: 1,
                iterations: last.iterations,
                factorizations: last.factorizations,
                last,
            }
        } else if self.continuation {
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
        cont.iterations += spent.0;
        cont.factorizations += spent.1;
        let stable_out_of_plane = if self.in_plane {
            Some(stable_out_of_plane(&model, &clamp.fixed, clamp_slaves, &x)?)
        } else {
            None
        };
        let (angle, tip) = drape_angle(&model, (edge, tip), &x)?;
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

/// Whether the in-plane equilibrium `x` is stable with the out-of-plane DOFs free too (only
/// the clamp's `fixed` DOFs held, its `slaves` following).
fn stable_out_of_plane(
    model: &ShellModel,
    clamp_fixed: &[usize],
    slaves: Vec<Slave>,
    x: &[Vec3],
) -> Result<bool, SceneError> {
    let nn = model.num_nodes();
    let mut fixed = vec![false; 3 * nn];
    for &d in clamp_fixed {
        fixed[d] = true;
    }
    let full = free_system(model, &fixed, slaves)?;
    crate::solve::is_stable(model, &full, x).map_err(|source| SceneError::Solve {
        stage: "out-of-plane stability check".into(),
        source,
    })
}

/// The drape angle (degrees) between the limit points at the clamped edge (v = 0) and the tip
/// (v = 1) of the strip at `x`, given as (face, u) each, and the tip's position.
fn drape_angle(
    model: &ShellModel,
    (edge, tip): ((usize, f64), (usize, f64)),
    x: &[Vec3],
) -> Result<(f64, Vec3), SceneError> {
    let surface = model.basis.surface();
    let eval = |(face, u): (usize, f64), v: f64| -> Result<Vec3, SceneError> {
        let s = surface
            .stencil(face, u, v)
            .map_err(|e| SceneError::Basis(e.into()))?;
        Ok(s.apply(x).x())
    };
    let edge = eval(edge, 0.0)?;
    let tip = eval(tip, 1.0)?;
    let angle = (-(tip[2] - edge[2])).atan2(tip[1] - edge[1]).to_degrees();
    Ok((angle, tip))
}

/// Iterations allowed to Newton from the elastica start; past them the load ramp takes over.
const ELASTICA_ITERATIONS: usize = 60;

/// Iterations allowed to a warm start; past them the elastica's start takes over (full-step
/// strategy): near parameters converge in 2–5, while a large step of the parameters (the
/// ratio-2e4 fit's thickness stage steps τ from 0.6 to 0.3 mm) converges faster from the
/// elastica (21 iterations) than from warm starts that fail.
const WARM_ITERATIONS: usize = 20;

/// A warp or weft strip bent onto the heavy elastica of its beam rigidity
/// ([`super::elastica`]): the bending of its own along that yarn, else the paper's section
/// a τ³/12 with a the law's small-strain stiffness along the yarn. `None` for other cuts: bending
/// couples to twist there, which the platform clamp holds, and no beam rigidity predicts the
/// droop (the example cotton at 45°, 50 mm: 21.0° where the free-twist beam says 44–70°);
/// under the phantom rule, whose clamp has two stable states (the heavy D1388 cantilever on
/// 4 × 32: 40.245° from flat, 41.786° from the elastica, both converged); and where the law has
/// no tangent at rest.
fn elastica_start(model: &ShellModel, bend: &CantileverBend) -> Option<Vec<Vec3>> {
    if !elastica_applies(model, bend) {
        return None;
    }
    let along_warp = bend.angle_deg == 90.0;
    let per_width = match model.bending() {
        Some(b) => b.at_angle(bend.angle_deg),
        None => {
            // the yarn's stiffness with the lateral strain held (a plate in cylindrical
            // bending): closer to a 25 mm strip held flat at the clamp than the beam's
            // a − a12²/a' (the example cotton's 100 mm weft strip drapes 59.6°; the elastica
            // starts at 59.1° and Newton takes 11 iterations, against 62.2° and 20)
            let c = model
                .law
                .response(&nalgebra::Vector3::zeros())
                .ok()?
                .tangent;
            let k = if along_warp { 0 } else { 1 };
            c[(k, k)] * model.thickness.powi(3) / 12.0
        }
    };
    let load = model.areal_density * STANDARD_GRAVITY * bend.width;
    let e = super::elastica::HeavyElastica::new(bend.overhang, load, per_width * bend.width)?;
    Some(e.bend(
        &model.basis.control_points,
        bend.overhang / bend.mesh.1 as f64,
    ))
}

/// Whether [`elastica_start`] has a start for this cantilever: a warp or weft cut under the
/// ghost rule.
fn elastica_applies(model: &ShellModel, bend: &CantileverBend) -> bool {
    (bend.angle_deg == 90.0 || bend.angle_deg == 0.0)
        && model.basis.options.boundary == BoundaryRule::Ghost
}

/// Newton at the full weight from [`elastica_start`], held to [`ELASTICA_ITERATIONS`]: the
/// equilibrium where it converges to a stable state; else `None`, with the iterations and
/// factorisations spent added to `spent`.
fn solve_from_elastica(
    model: &ShellModel,
    system: &FreeSystem,
    bend: &CantileverBend,
    solver: &NewtonOptions,
    spent: &mut (usize, usize),
) -> Option<(Vec<Vec3>, SolveReport)> {
    let mut x = elastica_start(model, bend)?;
    let opts = NewtonOptions {
        max_iterations: solver.max_iterations.min(ELASTICA_ITERATIONS),
        ..*solver
    };
    match newton(model, system, &mut x, &opts) {
        Ok(r) if r.stable => Some((x, r)),
        Ok(r) => {
            spent.0 += r.iterations;
            spent.1 += r.factorizations;
            None
        }
        Err(SolveError::NotConverged {
            iterations,
            factorizations,
            ..
        }) => {
            spent.0 += iterations;
            spent.1 += factorizations;
            None
        }
        Err(_) => None,
    }
}
