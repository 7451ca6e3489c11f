//! Fitting a triangle model to a lab dataset, in Miguel et al. 2012's staged order (§5): warp
//! and weft stretch from the yarn-direction strips, shear from the off-axis strips, warp and
//! weft bending from the cantilevers, then one more pass over shear and bending; after the
//! linear pass each membrane component's stiffness k(ε) gains spline control points (2, 3, 5)
//! while that lowers the stage's residual by at least 1 % (their subdivision rule).
//!
//! Each stage is a small damped Gauss–Newton (Levenberg–Marquardt) on the logarithms of its
//! control values, with forward-difference Jacobians: a stage has one to five parameters and
//! the triangle models' forward runs are cheap. The tests of a residual, the Jacobian's
//! columns and a scan's trials are independent runs, solved side by side and collected in
//! order (the fit is the same to the bit on one thread). Residuals are relative: a strip's force error
//! over the measured force (floored at 2 % of the curve's largest), a cantilever's drape-angle
//! error over the target angle. Every fitted curve is thinned to at most
//! [`TriFitOptions::points`] elongations.
//!
//! The starting point comes from the data alone: secant moduli of the yarn and 45° strips,
//! ASTM D1388's bending rigidity B = ρ g c³ of each cantilever, converted as
//! [`TriMaterial::from_zero_strain`] does. What the data cannot determine is kept at that start
//! and named in [`TriFit::undetermined`].

use crate::assembly::STANDARD_GRAVITY;
use crate::dataset::{FabricDataset, Role};
use crate::fit::shape_target::{ShapeFit, ShapeTarget};
use crate::scene::{TriCantilever, TriTensile};
use crate::tri::curve::Stiffness;
use crate::tri::params::{TriKind, TriMaterial, ZeroStrain};
use std::time::Instant;

mod minimise;
mod shapes;
mod stages;
pub mod verdict;

pub use crate::fit::shape_target::SHAPE_TRUST;
pub use minimise::SPLINE_FLOOR;
use shapes::shape_stage;
use stages::{StageSets, TriRun};

/// Fit settings.
#[derive(Clone, Debug)]
pub struct TriFitOptions {
    pub kind: TriKind,
    /// Faces across a strip (along: the same element size).
    pub strip_faces: usize,
    /// Cantilever meshes are the default ones times this.
    pub bend_refine: usize,
    /// Elongations per fitted curve, at most.
    pub points: usize,
    /// Most spline control values per membrane component.
    pub max_controls: usize,
}

impl TriFitOptions {
    pub fn new(kind: TriKind) -> Self {
        Self {
            kind,
            strip_faces: 8,
            bend_refine: 2,
            points: 5,
            max_controls: 5,
        }
    }
}

/// How well the fitted model reproduces one test.
#[derive(Clone, Debug)]
pub struct TestFit {
    pub kind: &'static str,
    pub angle_deg: f64,
    pub curve: Option<String>,
    /// Mean |relative force error| over the curve's points (tensile).
    pub avg_rel_error: Option<f64>,
    /// The curve's own force scale (measured ≈ s·model) and its mean |relative error| after it
    /// (tensile; [`verdict::repeat_scale`]).
    pub scale: Option<(f64, f64)>,
    /// (simulated, target) drape angle, degrees (bend).
    pub drape_angle_deg: Option<(f64, f64)>,
    pub mesh: (usize, usize),
    pub fitted: bool,
    /// A captured shape's errors.
    pub shape: Option<ShapeFit>,
}

/// A fitted triangle model.
#[derive(Clone, Debug)]
pub struct TriFit {
    pub material: TriMaterial,
    pub tests: Vec<TestFit>,
    /// Components the data do not determine (kept at the starting value).
    pub undetermined: Vec<&'static str>,
    pub notes: Vec<String>,
    pub evaluations: usize,
    pub seconds: f64,
}

/// One residual source: a thinned tensile curve or a cantilever.
#[derive(Clone, Debug)]
enum Target {
    Strip {
        strip: TriTensile,
        elongation: Vec<f64>,
        force: Vec<f64>,
        floor: f64,
        curve: String,
        fitted: bool,
    },
    Bend {
        bend: TriCantilever,
        angle: f64,
    },
    Shape(Box<ShapeTarget>),
}

impl Target {
    fn angle_deg(&self) -> f64 {
        match self {
            Target::Strip { strip, .. } => strip.angle_deg,
            Target::Bend { bend, .. } => bend.angle_deg,
            Target::Shape(_) => f64::NAN,
        }
    }

    /// Relative residuals (a failed solve: NaN, which the minimiser rejects).
    fn residuals(&self, m: &TriMaterial) -> Vec<f64> {
        match self {
            Target::Strip {
                strip,
                elongation,
                force,
                floor,
                ..
            } => match strip.run(m, elongation) {
                Ok(p) => p
                    .iter()
                    .zip(force)
                    .map(|(p, f)| (p.force - f) / f.abs().max(*floor))
                    .collect(),
                Err(_) => vec![f64::NAN; force.len()],
            },
            Target::Bend { bend, angle } => match bend.run(m) {
                Ok(r) => vec![(r.drape_angle_deg - angle) / angle],
                Err(_) => vec![f64::NAN],
            },
            Target::Shape(s) => s.residuals(m),
        }
    }
}

/// Is `a` (degrees from the weft) along a yarn: 0 weft, 90 warp.
fn near(a: f64, b: f64) -> bool {
    let d = (a - b).rem_euclid(180.0);
    d.min(180.0 - d) < 1e-6
}

/// ASTM D1388 (Peirce 1930): the bending length c from the overhang l and the drape angle θ,
/// c = l · (cos(θ/2) / (8 tan θ))^(1/3) (l/2 at the standard 41.5°), and the rigidity
/// B = ρ g c³ (N·m).
pub fn astm_rigidity(overhang: f64, angle_deg: f64, areal_density: f64) -> f64 {
    let t = angle_deg.to_radians();
    let c = overhang * ((0.5 * t).cos() / (8.0 * t.tan())).cbrt();
    areal_density * STANDARD_GRAVITY * c * c * c
}

/// Fits `opts.kind` to `data`, saying each stage through `progress`.
pub fn fit_tri(
    data: &FabricDataset,
    opts: &TriFitOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<TriFit, String> {
    let t0 = Instant::now();
    let density = data
        .areal_density
        .ok_or("the dataset has no areal_density_g_m2: the cantilevers need the weight")?;
    let mut notes = vec![
        "no toe (slack, preload) compensation and every repeat fitted alike in triangle-model fits"
            .to_string(),
    ];
    let targets = tri_targets(data, opts)?;
    let start = starting_moduli(data, density)?;
    let cell = data.bend.first().map_or(0.003, |b| {
        b.width / (TriCantilever::new(b.width, b.overhang, 0.0).mesh.0 * opts.bend_refine) as f64
    });
    let mut material = TriMaterial::from_zero_strain(
        opts.kind,
        &start.moduli,
        density,
        cell,
        crate::tri::file::SPRING_CURVATURE,
    );
    material.coupling = 0.0;
    let mut undetermined = start.undetermined.clone();
    if opts.kind == TriKind::Springs {
        undetermined.push("shear");
        notes.push("the springs model is simulated on yarn-aligned strips only: off-axis strips were not fitted, its shear is the start value".into());
    }
    if opts.kind == TriKind::Xpbd {
        undetermined.push("coupling");
        notes.push(
            "xpbd: the Poisson coupling C01 is held at 0 (strip forces hardly depend on it)".into(),
        );
    }
    let sets = StageSets::new(&targets, opts.kind);
    let stages = sets.stages(opts.kind);
    let mut run = TriRun {
        targets: &targets,
        opts,
        evaluations: 0,
    };
    for &st in &stages {
        run.run_stage(&mut material, st, st.1 < 3, progress);
    }
    let whole = run.repeat_passes(&mut material, &stages, &sets.lab, &mut notes, progress);
    // warp and weft bending together: the diagonal hinges tie them
    if !sets.bend_warp.is_empty() && !sets.bend_weft.is_empty() {
        run.bending_together(&mut material, &sets, whole, &mut notes, progress);
    }
    let mut evaluations = run.evaluations;
    // last: a buckled sheet's shape jumps to another branch of wrinkles when a stiffness moves
    // by a few percent, so nothing may move after it
    let shapes_fitted = shape_stage(
        &mut material,
        &targets,
        &mut undetermined,
        &mut notes,
        &mut evaluations,
        progress,
    );
    if opts.kind != TriKind::Springs {
        undetermined.push("bend_diag");
        notes.push("bend_diag is the geometric mean of bend_warp and bend_weft: warp and weft cantilevers do not determine it".into());
    }
    finite(&material)?;
    let tests = report(&targets, &material, shapes_fitted);
    Ok(TriFit {
        material,
        tests,
        undetermined,
        notes,
        evaluations,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Newton iterations a fitted strip may spend per elongation it is fitted at, over all its
/// elongations together: half of what one failed step and its four sub-steps may take at
/// the strip solver's 60 a solve. A trial stiffness at which the strip crawls through wrinkle
/// patterns fails within it, as a failed trial. On the bundled cotton's off-axis strips the
/// trials that solve take 80–190 Newton iterations over their five elongations; 60 a point
/// failed some of them and changed the shear fit.
pub const TRIAL_ITERATIONS: usize = 150;

/// The fit's targets: the tensile curves (thinned to `opts.points`; the springs model's on
/// yarn-aligned strips only), the cantilevers and the captured shapes.
fn tri_targets(data: &FabricDataset, opts: &TriFitOptions) -> Result<Vec<Target>, String> {
    let mut targets = Vec::new();
    for t in &data.tensile {
        if opts.kind == TriKind::Springs && !(near(t.angle_deg, 0.0) || near(t.angle_deg, 90.0)) {
            continue;
        }
        let across = opts.strip_faces;
        let along = ((across as f64 * t.gauge_length / t.width).round() as usize).max(1);
        let mut strip = TriTensile::new(t.width, t.gauge_length, t.angle_deg);
        strip.mesh = (across, along);
        let fmax = t.force.iter().fold(0.0f64, |a, f| a.max(f.abs()));
        let n = t.elongation.len();
        let take = opts.points.min(n.saturating_sub(1)).max(1);
        let idx: Vec<usize> = (1..=take).map(|k| (k * (n - 1)).div_ceil(take)).collect();
        strip.budget = Some(TRIAL_ITERATIONS * take);
        targets.push(Target::Strip {
            strip,
            elongation: idx.iter().map(|&i| t.elongation[i]).collect(),
            force: idx.iter().map(|&i| t.force[i]).collect(),
            floor: 0.02 * fmax,
            curve: t.curve.display().to_string(),
            fitted: t.role != Some(Role::Validation),
        });
    }
    for b in &data.bend {
        let mut bend = TriCantilever::new(b.width, b.overhang, b.angle_deg);
        bend.mesh = (
            bend.mesh.0 * opts.bend_refine,
            bend.mesh.1 * opts.bend_refine,
        );
        targets.push(Target::Bend {
            bend,
            angle: b.drape_angle_deg,
        });
    }
    for sh in &data.shapes {
        targets.push(Target::Shape(Box::new(ShapeTarget::new(sh, opts.points)?)));
    }
    Ok(targets)
}

/// Refuses a fitted material with a stiffness or coupling that is not a finite number (or a
/// negative stiffness): such a value is never written into a material file.
fn finite(m: &TriMaterial) -> Result<(), String> {
    use crate::tri::params::COMPONENTS;
    for (name, curve) in COMPONENTS.iter().zip(&m.curves) {
        if let Some(v) = curve.k.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(format!(
                "the {} fit ended with {name} = {v}: no material written",
                m.kind.name()
            ));
        }
    }
    if !m.coupling.is_finite() {
        return Err(format!(
            "the {} fit ended with coupling = {}: no material written",
            m.kind.name(),
            m.coupling
        ));
    }
    Ok(())
}

pub(super) fn tie_diagonal(m: &mut TriMaterial) {
    let g = (m.curves[3].k[0] * m.curves[4].k[0]).sqrt();
    m.curves[5] = Stiffness::constant(g);
}

/// The starting moduli, and what the data left unknown.
struct Start {
    moduli: ZeroStrain,
    undetermined: Vec<&'static str>,
}

fn starting_moduli(data: &FabricDataset, density: f64) -> Result<Start, String> {
    let secant = |angle: f64| -> Option<f64> {
        let v: Vec<f64> = data
            .tensile
            .iter()
            .filter(|t| near(t.angle_deg, angle) && t.elongation.len() > 1)
            .filter_map(|t| {
                let i = t.elongation.len() - 1;
                let e = t.elongation[i] / t.gauge_length;
                (e > 0.0).then(|| t.force[i] / (e * t.width))
            })
            .filter(|k| k.is_finite() && *k > 0.0)
            .collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    let mut undetermined = Vec::new();
    let ew = secant(90.0).ok_or("no warp (90°) strip to fit the warp stretch")?;
    let ef = secant(0.0).ok_or("no weft (0°) strip to fit the weft stretch")?;
    let e45 = secant(45.0).unwrap_or_else(|| {
        undetermined.push("shear");
        0.1 * ew.min(ef)
    });
    let rigidity = |angle: f64| -> Option<f64> {
        let v: Vec<f64> = data
            .bend
            .iter()
            .filter(|b| near(b.angle_deg, angle))
            .map(|b| astm_rigidity(b.overhang, b.drape_angle_deg, density))
            .collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    let (bw, bf) = match (rigidity(90.0), rigidity(0.0)) {
        (Some(w), Some(f)) => (w, f),
        (Some(w), None) => {
            undetermined.push("bend_weft");
            (w, w)
        }
        (None, Some(f)) => {
            undetermined.push("bend_warp");
            (f, f)
        }
        (None, None) => {
            undetermined.extend(["bend_warp", "bend_weft"]);
            (1e-5, 1e-5)
        }
    };
    let ks = {
        let v = 1.0 / (4.0 / e45 - 1.0 / ew - 1.0 / ef);
        if v > 0.0 && v.is_finite() {
            v
        } else {
            0.05 * ew.min(ef)
        }
    };
    let tangent = nalgebra::Matrix3::new(ew, 0.0, 0.0, 0.0, ef, 0.0, 0.0, 0.0, 4.0 * ks);
    Ok(Start {
        moduli: ZeroStrain {
            uniaxial: [ew, ef, e45],
            tangent,
            bending: [bw, bf, (bw * bf).sqrt()],
        },
        undetermined,
    })
}

/// Every test's error under the fitted material (validation strips and shapes included).
fn report(targets: &[Target], m: &TriMaterial, shapes_fitted: bool) -> Vec<TestFit> {
    let mut out = Vec::new();
    for t in targets {
        match t {
            Target::Strip {
                strip,
                force,
                curve,
                fitted,
                ..
            } => {
                let r = t.residuals(m);
                out.push(TestFit {
                    kind: "tensile",
                    angle_deg: strip.angle_deg,
                    curve: Some(curve.clone()),
                    avg_rel_error: Some(
                        r.iter().map(|v| v.abs()).sum::<f64>() / force.len() as f64,
                    ),
                    scale: verdict::repeat_scale(&r),
                    drape_angle_deg: None,
                    mesh: strip.mesh,
                    fitted: *fitted,
                    shape: None,
                });
            }
            Target::Bend { bend, angle } => {
                let sim = bend.run(m).map_or(f64::NAN, |r| r.drape_angle_deg);
                out.push(TestFit {
                    kind: "bend",
                    angle_deg: bend.angle_deg,
                    curve: None,
                    avg_rel_error: None,
                    scale: None,
                    drape_angle_deg: Some((sim, *angle)),
                    mesh: bend.mesh,
                    fitted: true,
                    shape: None,
                });
            }
            Target::Shape(s) => out.push(TestFit {
                kind: "shape",
                angle_deg: f64::NAN,
                curve: Some(s.test.obj.display().to_string()),
                avg_rel_error: None,
                scale: None,
                drape_angle_deg: None,
                mesh: (s.mesh, s.mesh),
                fitted: shapes_fitted && s.fitted(),
                shape: Some(s.errors(m)),
            }),
        }
    }
    out
}
