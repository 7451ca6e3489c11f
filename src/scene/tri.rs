//! The lab tests on the triangle models: the ASTM D5035 strip ([`TriTensile`]) and the ASTM
//! D1388 cantilever ([`TriCantilever`]), with the same geometry, angle convention (degrees
//! from the weft: 0° weft along the strip, 90° warp) and results as the shell's
//! [`crate::scene::TensileStrip`] and [`crate::scene::CantileverBend`].
//!
//! The grid runs along x (the strip's length) and across y; meshes are given as the shell's,
//! faces across × along. The strip's jaws hold the end rows of nodes; the cantilever's clamp
//! holds two columns of nodes (the platform edge and one cell behind it, which holds the
//! slope), so its grid is one cell longer than the overhang.

use super::{BendResult, SceneError, TensilePoint};
use crate::assembly::STANDARD_GRAVITY;
use crate::model::ClothModel;
use crate::solve::{continuation, newton, FreeSystem, NewtonOptions, SolveError};
use crate::tri::{TriGrid, TriKind, TriMaterial, TriModel};
use crate::Vec3;

/// Warp angle from the grid's x axis (the strip's length) of a strip cut at `angle_deg` from
/// the weft.
fn warp_angle(angle_deg: f64) -> f64 {
    (90.0 + angle_deg).to_radians()
}

/// The Springs model classifies its springs by grid direction (Miguel et al. 2012 simulate
/// yarn-aligned samples only): a strip cut off the yarns would have its "warp" springs at an
/// angle to the warp, so it is refused rather than simulated wrongly.
fn check_aligned(material: &TriMaterial, angle_deg: f64) -> Result<(), SceneError> {
    let r = angle_deg.rem_euclid(90.0);
    if material.kind == TriKind::Springs && r.min(90.0 - r) > 1e-9 {
        return Err(SceneError::Input(format!(
            "the springs model needs its grid along the yarns: strips at 0° or 90° (a multiple of 90°), got {angle_deg}°"
        )));
    }
    Ok(())
}

fn setup(e: SolveError) -> SceneError {
    SceneError::Solve {
        stage: "set-up".into(),
        source: e,
    }
}

fn check(name: &str, v: f64) -> Result<f64, SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(SceneError::Input(format!(
            "{name} must be a positive number, got {v:?}"
        )))
    }
}

/// A tensile strip on a triangle model.
#[derive(Clone, Debug)]
pub struct TriTensile {
    /// m
    pub width: f64,
    /// gauge length, m
    pub length: f64,
    pub angle_deg: f64,
    /// faces across × along
    pub mesh: (usize, usize),
    pub solver: NewtonOptions,
    /// Most Newton iterations a run may spend over all its elongations, sub-steps and failed
    /// attempts included (`None`: each solve's own `solver.max_iterations` only). A fitter's
    /// trial sets it: a trial stiffness at which the strip crawls through wrinkle patterns
    /// then fails in bounded time, and the fitter counts it as a failed trial.
    pub budget: Option<usize>,
}

impl TriTensile {
    pub fn new(width: f64, length: f64, angle_deg: f64) -> Self {
        Self {
            width,
            length,
            angle_deg,
            mesh: super::default_mesh(width, length),
            solver: NewtonOptions::default(),
            budget: None,
        }
    }

    /// Forces at each elongation (m, increasing), each solve started from the last
    /// equilibrium by [`TriTensile::predict`] (cut into 4 sub-steps when a solve fails).
    pub fn run(
        &self,
        material: &TriMaterial,
        elongations: &[f64],
    ) -> Result<Vec<TensilePoint>, SceneError> {
        let (w, l) = (
            check("width", self.width)?,
            check("gauge length", self.length)?,
        );
        check_aligned(material, self.angle_deg)?;
        let (across, along) = self.mesh;
        if across == 0 || along == 0 {
            return Err(SceneError::Input(
                "the mesh needs at least one face each way".into(),
            ));
        }
        let grid = TriGrid::rectangle(l, w, along, across);
        let model = TriModel::new(grid, material.clone(), warp_angle(self.angle_deg));
        let n = model.num_nodes();
        let moving: Vec<usize> = (0..n).filter(|&i| model.grid.rest[i][0] == l).collect();
        let mut fixed = vec![false; 3 * n];
        for i in 0..n {
            if model.grid.rest[i][0] == 0.0 || model.grid.rest[i][0] == l {
                fixed[3 * i..3 * i + 3].iter_mut().for_each(|f| *f = true);
            }
        }
        let system = FreeSystem::new(&model, &fixed).map_err(setup)?;
        let mut x = model.grid.positions();
        // the last equilibrium's elongation, and the one before it with its positions (the
        // secant predictor's other end)
        let mut last = 0.0;
        let mut before: Option<(f64, Vec<Vec3>)> = None;
        let mut left = self.budget.unwrap_or(usize::MAX);
        let mut out = Vec::with_capacity(elongations.len());
        for &dl in elongations {
            if !dl.is_finite() {
                return Err(SceneError::Input(format!(
                    "elongation must be finite, got {dl:?}"
                )));
            }
            let previous = x.clone();
            let report = self.step(
                (&model, &system),
                &mut x,
                (last, before.as_ref()),
                dl,
                &mut left,
            )?;
            before = Some((last, previous));
            last = dl;
            let mut g = vec![[0.0; 3]; n];
            model
                .assemble(&x, crate::assembly::Want::Gradient, Some(&mut g), None)
                .map_err(|e| SceneError::Solve {
                    stage: format!("elongation {:.4} mm", dl * 1e3),
                    source: SolveError::StartOutOfDomain(e.to_string()),
                })?;
            let force = moving.iter().map(|&i| g[i][0]).sum();
            out.push(TensilePoint {
                elongation: dl,
                force,
                report,
                dforce: Vec::new(),
            });
        }
        Ok(out)
    }

    /// From the equilibrium `x` at elongation `from` (`before`: the equilibrium preceding it)
    /// to the one at `to`, in one step or, where that fails, in 4 sub-steps, each started by
    /// [`TriTensile::predict`]; every Newton iteration is taken from `left`, and a solve that
    /// finds `left` spent fails as not converged.
    fn step(
        &self,
        (model, system): (&TriModel, &FreeSystem),
        x: &mut [Vec3],
        (from, before): (f64, Option<&(f64, Vec<Vec3>)>),
        to: f64,
        left: &mut usize,
    ) -> Result<crate::solve::SolveReport, SceneError> {
        let start = x.to_vec();
        let mut err = None;
        for parts in [1, 4] {
            x.copy_from_slice(&start);
            let mut back = before.map(|(e, p)| (*e, p.clone()));
            let mut report = None;
            for k in 1..=parts {
                let dl = from + (to - from) * k as f64 / parts as f64;
                let prev = from + (to - from) * (k - 1) as f64 / parts as f64;
                let here = x.to_vec();
                self.predict(model, x, (prev, back.as_ref()), dl);
                match self.solve(model, system, x, left) {
                    Ok(r) => report = Some(r),
                    Err(e) => {
                        err = Some(e);
                        report = None;
                        break;
                    }
                }
                back = Some((prev, here));
            }
            if let Some(r) = report {
                return Ok(r);
            }
        }
        Err(SceneError::Solve {
            stage: format!("elongation {:.4} mm", to * 1e3),
            source: err.expect("a failed step has an error"),
        })
    }

    /// Newton from `x` with at most `left` iterations, which it takes from `left`.
    fn solve(
        &self,
        model: &TriModel,
        system: &FreeSystem,
        x: &mut [Vec3],
        left: &mut usize,
    ) -> Result<crate::solve::SolveReport, SolveError> {
        let opts = NewtonOptions {
            max_iterations: self.solver.max_iterations.min(*left),
            ..self.solver
        };
        if opts.max_iterations == 0 {
            return Err(SolveError::NotConverged {
                iterations: 0,
                residual: f64::NAN,
                factorizations: 0,
            });
        }
        let result = newton(model, system, x, &opts);
        let spent = match &result {
            Ok(r) => r.iterations,
            Err(SolveError::NotConverged { iterations, .. }) => *iterations,
            Err(_) => opts.max_iterations,
        };
        *left = left.saturating_sub(spent.max(1));
        result
    }

    /// Moves the equilibrium `x` at elongation `from` to a start at `to`: along the secant
    /// through `before`, the equilibrium preceding it, or stretched affinely along the strip
    /// where there is none; the moving jaw is put at `to`. The secant carries the lateral
    /// contraction and wrinkles of the path, which grow with the elongation and which an
    /// affine stretch leaves Newton to rebuild at every step (stvk-ds cotton-like strips on
    /// 8 × 12: from 104 to 39 Newton iterations over five steps at 45°, 125 to 83 at 22.5°).
    fn predict(
        &self,
        model: &TriModel,
        x: &mut [Vec3],
        (from, before): (f64, Option<&(f64, Vec<Vec3>)>),
        to: f64,
    ) {
        let l = self.length;
        match before.filter(|b| b.0 < from) {
            Some((e0, x0)) => {
                let w = (to - from) / (from - e0);
                for (p, q) in x.iter_mut().zip(x0) {
                    for c in 0..3 {
                        p[c] += w * (p[c] - q[c]);
                    }
                }
            }
            None => {
                let s = (l + to) / (l + from);
                for p in x.iter_mut() {
                    p[0] *= s;
                }
            }
        }
        for (i, p) in x.iter_mut().enumerate() {
            if model.grid.rest[i][0] == l {
                *p = [l + to, model.grid.rest[i][1], 0.0];
            }
        }
    }
}

/// An ASTM D1388 cantilever on a triangle model.
#[derive(Clone, Debug)]
pub struct TriCantilever {
    /// m
    pub width: f64,
    /// m
    pub overhang: f64,
    pub angle_deg: f64,
    /// faces across × along the overhang
    pub mesh: (usize, usize),
    pub solver: NewtonOptions,
}

impl TriCantilever {
    /// The shell cantilever's default mesh (elements of about 6.25 mm).
    pub fn new(width: f64, overhang: f64, angle_deg: f64) -> Self {
        Self {
            width,
            overhang,
            angle_deg,
            mesh: super::CantileverBend::new(width, overhang, angle_deg).mesh,
            solver: NewtonOptions::default(),
        }
    }

    pub fn run(&self, material: &TriMaterial) -> Result<BendResult, SceneError> {
        let (w, l) = (
            check("width", self.width)?,
            check("overhang", self.overhang)?,
        );
        check_aligned(material, self.angle_deg)?;
        let (across, along) = self.mesh;
        if across == 0 || along < 2 {
            return Err(SceneError::Input(
                "the cantilever mesh needs at least 1 face across and 2 along".into(),
            ));
        }
        let a = l / along as f64;
        let grid = TriGrid::rectangle(l + a, w, along + 1, across);
        let mut model = TriModel::new(grid, material.clone(), warp_angle(self.angle_deg));
        let n = model.num_nodes();
        let g = &model.grid;
        let mut fixed = vec![false; 3 * n];
        for i in 0..n {
            if g.rest[i][0] <= a * (1.0 + 1e-12) {
                fixed[3 * i..3 * i + 3].iter_mut().for_each(|f| *f = true);
            }
        }
        // mid-width nodes of the platform edge (column 1) and of the tip
        let mids: Vec<usize> = if across % 2 == 0 {
            vec![across / 2]
        } else {
            vec![across / 2, across / 2 + 1]
        };
        let edge: Vec<usize> = mids.iter().map(|&j| g.node(1, j)).collect();
        let tip: Vec<usize> = mids.iter().map(|&j| g.node(along + 1, j)).collect();
        let system = FreeSystem::new(&model, &fixed).map_err(setup)?;
        let mut x = model.grid.positions();
        let apply = |m: &mut TriModel, t: f64, _: &[Vec3]| {
            m.set_gravity([0.0, 0.0, -STANDARD_GRAVITY * t]);
        };
        let cont = match continuation(&mut model, &system, &mut x, &self.solver, 1.0, apply) {
            Ok(c) => c,
            // ring-2 bending springs have no stiffness out of the flat plane, so every load
            // step starts singular: the whole load by the robust solver with a long budget
            Err(_) if material.kind == TriKind::Springs => {
                x = model.grid.positions();
                model.set_gravity([0.0, 0.0, -STANDARD_GRAVITY]);
                let opts = NewtonOptions {
                    max_iterations: 500,
                    ..self.solver
                };
                let last =
                    newton(&model, &system, &mut x, &opts).map_err(|source| SceneError::Solve {
                        stage: "full load (springs)".into(),
                        source,
                    })?;
                crate::solve::ContinuationReport {
                    steps: 1,
                    iterations: last.iterations,
                    factorizations: last.factorizations,
                    last,
                }
            }
            Err((t, source)) => {
                return Err(SceneError::Solve {
                    stage: format!("load factor {t:.4}"),
                    source,
                })
            }
        };
        let mean = |nodes: &[usize]| {
            let mut p = [0.0; 3];
            for &i in nodes {
                for c in 0..3 {
                    p[c] += x[i][c] / nodes.len() as f64;
                }
            }
            p
        };
        let (e, t) = (mean(&edge), mean(&tip));
        Ok(BendResult {
            drape_angle_deg: (-(t[2] - e[2])).atan2(t[0] - e[0]).to_degrees(),
            tip: t,
            load_steps: cont.steps,
            iterations: cont.iterations,
            factorizations: cont.factorizations,
            report: cont.last,
            stable_out_of_plane: None,
        })
    }
}
