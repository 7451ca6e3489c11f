//! Square sheets for the paper's showcase scenes (Clyde et al. 2017 §6, Figures 1 and 5): the
//! model of an L × L square of fabric, warp along x and weft along y in its rest state (the xy
//! plane), on a uniform n × n cage with the phantom boundary rule; a deterministic
//! out-of-plane perturbation that picks a branch where a sheet buckles; and [`march`], which
//! drives the held control points along a path in steps.
//!
//! With the phantom rule each boundary control row *is* the limit edge (the phantom row
//! 2P₀ − P₁ makes (G + 4P₀ + P₁)/6 = P₀), and the limit surface is affine-invariant, so holding
//! a boundary row at A·X + b holds the limit edge at exactly A·X + b.

use super::surface::SurfaceMesh;
use super::{build_model, SceneError};
use crate::assembly::{ShellModel, Want, YarnRule};
use crate::material::FabricMaterial;
use crate::mesh::Grading;
use crate::model::ClothModel;
use crate::solve::{newton, FallbackCounts, FreeSystem, NewtonOptions, SolveError, SolveReport};
use crate::subdiv::BoundaryRule;
use crate::tri::{TriGrid, TriMaterial, TriModel};
use crate::Vec3;
use std::collections::HashMap;

/// What a scene needs of a cloth model beyond the solver's contract: a settable gravity and
/// its deformed surface as a welded quad mesh (for the shapes written and drawn, and the
/// drape's measures). The subdivision shell and the triangle models are both sheets.
pub trait SheetModel: ClothModel + Sized {
    fn set_gravity(&mut self, g: Vec3);
    /// The surface at node positions `x`: the shell's limit surface sampled `k` × `k` per
    /// cage face; a triangle model's nodes, one quad per grid cell (`k` unused).
    fn surface(sheet: &Sheet<Self>, x: &[Vec3], k: usize) -> Result<SurfaceMesh, SceneError>;
}

impl SheetModel for ShellModel {
    fn set_gravity(&mut self, g: Vec3) {
        ShellModel::set_gravity(self, g)
    }
    fn surface(sheet: &Sheet<Self>, x: &[Vec3], k: usize) -> Result<SurfaceMesh, SceneError> {
        sample(sheet, x, k)
    }
}

impl SheetModel for TriModel {
    fn set_gravity(&mut self, g: Vec3) {
        TriModel::set_gravity(self, g)
    }
    fn surface(sheet: &Sheet<Self>, x: &[Vec3], _k: usize) -> Result<SurfaceMesh, SceneError> {
        Ok(lattice_surface(sheet, x))
    }
}

/// An L × L square of fabric, warp along x, on an n × n cage (the shell) or grid (a triangle
/// model).
pub struct Sheet<M = ShellModel> {
    pub model: M,
    /// m
    pub side: f64,
    /// faces each way
    pub n: usize,
    /// node of each lattice point (i, j), row-major in j
    nodes: Vec<usize>,
    /// rest position of every node (the shell's cage has phantom-free rows only on the
    /// lattice; a triangle grid is the lattice)
    rest: Vec<Vec3>,
}

impl Sheet<ShellModel> {
    pub fn new(material: &FabricMaterial, side: f64, n: usize) -> Result<Self, SceneError> {
        super::positive("sheet side", side)?;
        let model = build_model(
            material,
            (side, side),
            0.0,
            (n, n),
            BoundaryRule::Phantom,
            Grading::UNIFORM,
            (YarnRule::Auto.for_bending(), None),
        )?;
        let rest = model.basis.control_points.clone();
        Self::from_parts(model, side, n, rest)
    }
}

impl Sheet<TriModel> {
    /// The sheet on a triangle model (Miguel et al. 2012's grid: each cell split by one
    /// diagonal), warp along x.
    pub fn tri(material: &TriMaterial, side: f64, n: usize) -> Result<Self, SceneError> {
        super::positive("sheet side", side)?;
        if n == 0 {
            return Err(SceneError::Input(
                "the sheet needs at least one face each way".into(),
            ));
        }
        // the same --max-faces as the shell's sheet (cells; each holds two triangles)
        crate::limits::check_mesh(&format!("mesh {n}x{n}"), n, n).map_err(SceneError::Input)?;
        let model = TriModel::new(TriGrid::rectangle(side, side, n, n), material.clone(), 0.0);
        let rest: Vec<Vec3> = model.grid.rest.iter().map(|p| [p[0], p[1], 0.0]).collect();
        Self::from_parts(model, side, n, rest)
    }
}

impl<M> Sheet<M> {
    /// The sheet of `model`, whose nodes rest at `rest`, found on the lattice.
    fn from_parts(model: M, side: f64, n: usize, rest: Vec<Vec3>) -> Result<Self, SceneError> {
        let nodes = lattice(&rest, side, n)?;
        Ok(Self {
            model,
            side,
            n,
            nodes,
            rest,
        })
    }
}

/// The node at each lattice point (i, j) · side / n, row-major in j.
fn lattice(rest: &[Vec3], side: f64, n: usize) -> Result<Vec<usize>, SceneError> {
    let h = side / n as f64;
    let mut nodes = vec![usize::MAX; (n + 1) * (n + 1)];
    for (v, p) in rest.iter().enumerate() {
        let (i, j) = ((p[0] / h).round(), (p[1] / h).round());
        let on = (p[0] - i * h).abs() < 1e-9 * side && (p[1] - j * h).abs() < 1e-9 * side;
        if on && (0.0..=n as f64).contains(&i) && (0.0..=n as f64).contains(&j) {
            nodes[j as usize * (n + 1) + i as usize] = v;
        }
    }
    if nodes.contains(&usize::MAX) {
        return Err(SceneError::Input(
            "internal: a lattice node of the sheet has no control point".into(),
        ));
    }
    Ok(nodes)
}

impl<M: SheetModel> Sheet<M> {
    /// The node at lattice point (i, j), rest position (i, j) · side / n.
    pub fn node(&self, i: usize, j: usize) -> usize {
        self.nodes[j * (self.n + 1) + i]
    }

    /// Control points of the four edges, each once.
    pub fn boundary(&self) -> Vec<usize> {
        let n = self.n;
        (0..=n)
            .flat_map(|j| (0..=n).map(move |i| (i, j)))
            .filter(|&(i, j)| i == 0 || j == 0 || i == n || j == n)
            .map(|(i, j)| self.node(i, j))
            .collect()
    }

    pub fn rest(&self) -> &[Vec3] {
        &self.rest
    }

    /// An out-of-plane offset per control point, zero on the boundary rows: the lowest mode
    /// sin(πX/L) sin(πY/L) with seed 0, otherwise a pseudo-random sum of the modes
    /// sin(mπX/L) sin(kπY/L), m, k ≤ 3, from `seed`; largest value 1.
    pub fn perturbation(&self, seed: u64) -> Vec<f64> {
        let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
        let mut next = || {
            // xorshift64*: plenty for choosing a handful of mode amplitudes
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64 * 2.0
                - 1.0
        };
        let mut modes = vec![(1.0, 1.0, 1.0)];
        if seed != 0 {
            modes = (1..=3)
                .flat_map(|m| (1..=3).map(move |k| (m as f64, k as f64)))
                .map(|(m, k)| (m, k, next()))
                .collect();
        }
        let pi = std::f64::consts::PI;
        let w: Vec<f64> = self
            .rest()
            .iter()
            .map(|p| {
                let (s, t) = (p[0] / self.side, p[1] / self.side);
                let inside = (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t);
                let shape: f64 = modes
                    .iter()
                    .map(|(m, k, c)| c * (m * pi * s).sin() * (k * pi * t).sin())
                    .sum();
                if inside {
                    shape
                } else {
                    0.0
                }
            })
            .collect();
        let top = w.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        w.iter().map(|v| v / top.max(f64::MIN_POSITIVE)).collect()
    }

    /// The free system with the DOFs `held` (and, when `in_plane`, every z) fixed.
    pub(crate) fn system(&self, held: &[usize], in_plane: bool) -> Result<FreeSystem, SceneError> {
        let mut fixed = vec![false; 3 * self.rest().len()];
        held.iter().for_each(|&d| fixed[d] = true);
        if in_plane {
            fixed.iter_mut().skip(2).step_by(3).for_each(|f| *f = true);
        }
        super::free_system(&self.model, &fixed, Vec::new())
    }

    /// The rest state lifted along z by `amplitude` × side × [`Sheet::perturbation`]`(seed)`.
    pub fn lifted(&self, amplitude: f64, seed: u64) -> Vec<Vec3> {
        let w = self.perturbation(seed);
        self.rest()
            .iter()
            .zip(&w)
            .map(|(p, w)| [p[0], p[1], amplitude * self.side * w])
            .collect()
    }

    /// dW/dq: Σ rate · ∂E/∂x over the held DOFs whose motion per unit q is `rate` (the
    /// generalised force the holders exert along q).
    pub fn reaction(&self, x: &[Vec3], rate: &[(usize, f64)]) -> Result<f64, SceneError> {
        let mut grad = vec![[0.0; 3]; x.len()];
        self.model
            .assemble(x, Want::Gradient, Some(&mut grad), None)
            .map_err(|e| SceneError::Solve {
                stage: "reaction".into(),
                source: SolveError::StartOutOfDomain(e.to_string()),
            })?;
        Ok(rate.iter().map(|&(d, r)| r * grad[d / 3][d % 3]).sum())
    }
}

/// Work done by the solver over a scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolveCounts {
    /// Equilibrium solves kept (load or motion steps, sub-steps included).
    pub steps: usize,
    /// Steps that failed and were cut into sub-steps.
    pub cut_steps: usize,
    pub iterations: usize,
    pub factorizations: usize,
    pub backward_euler_steps: usize,
    pub saddle_escapes: usize,
    /// Why backward Euler is used, over the kept solves.
    pub fallbacks: FallbackCounts,
    pub curvature_steps: usize,
    /// Steps on the convexified Hessian (after negative-curvature steps).
    pub convexified_steps: usize,
    /// Seconds in assembly and in factorisation, kept solves only.
    pub assembly_seconds: f64,
    pub factor_seconds: f64,
}

impl SolveCounts {
    /// Adds another run's counts.
    pub fn merge(&mut self, o: &SolveCounts) {
        self.steps += o.steps;
        self.cut_steps += o.cut_steps;
        self.iterations += o.iterations;
        self.factorizations += o.factorizations;
        self.backward_euler_steps += o.backward_euler_steps;
        self.saddle_escapes += o.saddle_escapes;
        add_fallbacks(&mut self.fallbacks, &o.fallbacks);
        self.curvature_steps += o.curvature_steps;
        self.convexified_steps += o.convexified_steps;
        self.assembly_seconds += o.assembly_seconds;
        self.factor_seconds += o.factor_seconds;
    }

    /// Adds one kept solve.
    pub fn add(&mut self, r: &SolveReport) {
        self.iterations += r.iterations;
        self.factorizations += r.factorizations;
        self.backward_euler_steps += r.backward_euler_steps;
        self.saddle_escapes += r.saddle_escapes;
        add_fallbacks(&mut self.fallbacks, &r.fallbacks);
        self.curvature_steps += r.curvature_steps;
        self.convexified_steps += r.convexified_steps;
        self.assembly_seconds += r.assembly_seconds;
        self.factor_seconds += r.factor_seconds;
    }
}

fn add_fallbacks(a: &mut FallbackCounts, b: &FallbackCounts) {
    a.indefinite += b.indefinite;
    a.ascent += b.ascent;
    a.stagnation += b.stagnation;
    a.short_step += b.short_step;
}

/// Drives the held DOFs along `place(t, dof)` (their position at path parameter t) from t = 0
/// to 1 in `steps` equal steps, each solved from the secant prediction through the last two
/// equilibria. A step that fails is cut into 2, 4, then 8 sub-steps. `each(t, x, report)` sees
/// every equilibrium of the main steps. Returns the counts and the last solve's report.
#[allow(clippy::too_many_arguments)]
pub(crate) fn march(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &mut Vec<Vec3>,
    steps: usize,
    solver: &NewtonOptions,
    held: &[usize],
    place: impl Fn(f64, usize) -> f64,
    mut each: impl FnMut(f64, &[Vec3], &SolveReport) -> Result<(), SceneError>,
) -> Result<(SolveCounts, SolveReport), SceneError> {
    let mut counts = SolveCounts::default();
    let mut last = SolveReport::default();
    let mut previous: Option<(f64, Vec<Vec3>)> = None;
    let mut t = 0.0;
    for k in 1..=steps.max(1) {
        let target = k as f64 / steps.max(1) as f64;
        let mut solved = None;
        let mut error = None;
        for pieces in [1usize, 2, 4, 8] {
            let (mut t_here, mut x_here, mut prev_here) = (t, x.clone(), previous.clone());
            let mut kept = Vec::new();
            let mut ok = true;
            for p in 1..=pieces {
                let tp = t + (target - t) * p as f64 / pieces as f64;
                let mut trial = x_here.clone();
                if let Some((t0, x0)) = &prev_here {
                    let r = (tp - t_here) / (t_here - t0);
                    for (a, b) in trial.iter_mut().zip(x0) {
                        let now = *a;
                        *a = std::array::from_fn(|c| now[c] + r * (now[c] - b[c]));
                    }
                }
                for &d in held {
                    trial[d / 3][d % 3] = place(tp, d);
                }
                match newton(model, system, &mut trial, solver) {
                    Ok(report) => {
                        kept.push(report);
                        prev_here = Some((t_here, std::mem::replace(&mut x_here, trial)));
                        t_here = tp;
                    }
                    Err(source) => {
                        error.get_or_insert(SceneError::Solve {
                            stage: format!("path parameter {tp:.4}"),
                            source,
                        });
                        ok = false;
                        break;
                    }
                }
            }
            if ok {
                counts.cut_steps += usize::from(pieces > 1);
                solved = Some((x_here, prev_here, kept));
                break;
            }
        }
        let Some((x_new, prev_new, kept)) = solved else {
            return Err(error.unwrap_or_else(|| SceneError::Input("no step solved".into())));
        };
        for r in &kept {
            counts.add(r);
            counts.steps += 1;
        }
        last = kept.last().cloned().unwrap_or_default();
        *x = x_new;
        previous = prev_new;
        t = target;
        each(t, x, &last)?;
    }
    Ok((counts, last))
}

/// Samples the limit surface of `sheet` at control points `x`, `k` × `k` quads per cage face.
pub fn sample(sheet: &Sheet<ShellModel>, x: &[Vec3], k: usize) -> Result<SurfaceMesh, SceneError> {
    let k = k.max(1);
    let surface = sheet.model.basis.surface();
    let rest = sheet.rest();
    let uvs: Vec<[f64; 2]> = (0..=k)
        .flat_map(|b| (0..=k).map(move |a| [a as f64 / k as f64, b as f64 / k as f64]))
        .collect();
    let mut out = SurfaceMesh::default();
    let mut welded: HashMap<(i64, i64), usize> = HashMap::new();
    let key_scale = 1e6 * k as f64 * sheet.n as f64 / sheet.side;
    for face in 0..surface.num_faces() {
        let stencils = surface
            .stencils(face, &uvs)
            .map_err(|e| SceneError::Basis(e.into()))?;
        let mut ids = Vec::with_capacity(uvs.len());
        for s in &stencils {
            let r = s.apply(rest).x();
            let key = (
                (r[0] * key_scale).round() as i64,
                (r[1] * key_scale).round() as i64,
            );
            let id = *welded.entry(key).or_insert_with(|| {
                let p = s.apply(x);
                out.positions.push(p.x());
                out.normals.push(p.normal());
                out.uv.push([r[0], r[1]]);
                out.positions.len() - 1
            });
            ids.push(id);
        }
        for b in 0..k {
            for a in 0..k {
                let at = |i: usize, j: usize| ids[j * (k + 1) + i];
                out.quads
                    .push([at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)]);
            }
        }
    }
    Ok(out)
}

/// A triangle model's sheet as a surface: its nodes, one quad per grid cell (the quad's
/// diagonal is the renderer's, not necessarily the model's), unit normals averaged from the
/// cells around each node, texture coordinates the rest positions.
pub fn lattice_surface<M: SheetModel>(sheet: &Sheet<M>, x: &[Vec3]) -> SurfaceMesh {
    let n = sheet.n;
    let mut out = SurfaceMesh::default();
    let id = |i: usize, j: usize| j * (n + 1) + i;
    for j in 0..=n {
        for i in 0..=n {
            let v = sheet.node(i, j);
            out.positions.push(x[v]);
            let r = sheet.rest()[v];
            out.uv.push([r[0], r[1]]);
        }
    }
    let mut normals = vec![[0.0; 3]; out.positions.len()];
    for j in 0..n {
        for i in 0..n {
            let q = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
            let p = |k: usize| out.positions[q[k]];
            let (a, b) = (sub(p(2), p(0)), sub(p(3), p(1)));
            let c = [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ];
            for &v in &q {
                (0..3).for_each(|k| normals[v][k] += c[k]);
            }
            out.quads.push(q);
        }
    }
    out.normals = normals
        .into_iter()
        .map(|v| {
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if l > 0.0 {
                [v[0] / l, v[1] / l, v[2] / l]
            } else {
                [0.0, 0.0, 1.0]
            }
        })
        .collect();
    out
}

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
