//! Quasistatic equilibrium: Newton's method on the total energy over the free DOFs (Clyde et al.
//! 2017 §6).
//!
//! Clamped control points are Dirichlet values eliminated from the system; the reaction on them
//! is their entry of the energy gradient. Each Newton step solves H d = −g with faer's sparse
//! Cholesky, whose symbolic factorisation is computed once per constraint set
//! ([`FreeSystem`]) and reused for every numeric refactorisation. A non-positive pivot is met by
//! adding a growing multiple of the mean diagonal (a Levenberg shift) until the factorisation
//! succeeds; every solve's residual is checked. A backtracking line search on the energy keeps
//! each step a descent step, and halves steps that leave the law's domain.
//!
//! Converged means ‖g_free‖₂ ≤ `rtol` · (‖internal force over all DOFs‖₂ + ‖gravity load‖₂):
//! the out-of-balance force is a tiny fraction of the forces flowing through the structure; or
//! ‖g_free‖₂ ≤ 2 ε ‖diag K‖₂ ‖x‖∞, the round-off floor of the force evaluation (positions are
//! known to ε‖x‖∞; thin shells, whose stiffness spans ten decades, reach this floor first and
//! the report says so).

use crate::assembly::{BlockMatrix, ShellModel, Want};
use crate::Vec3;
use faer::prelude::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{MatMut, Side};
pub mod refine;

pub use refine::Precision;

use std::time::Instant;

const NOT_FREE: u32 = u32::MAX;

/// Relative residual below which a Newton iteration that no longer converges counts as having
/// reached the round-off floor (see [`newton`]).
const STALL_RTOL: f64 = 1e-6;

/// A DOF tied to free DOFs: x[dof] = Σ coef · x[master] + offset (an affine constraint solved
/// by elimination, e.g. a clamp acting through ghost control points).
#[derive(Clone, Debug, PartialEq)]
pub struct Slave {
    /// DOF index, 3 · node + component.
    pub dof: usize,
    /// (master DOF, coefficient); masters must be free DOFs.
    pub masters: Vec<(usize, f64)>,
    pub offset: f64,
}

/// The reduced Hessian Tᵀ H T over the free DOFs (x = T q + x̄ with fixed and slaved DOFs
/// eliminated) in compressed columns (lower triangle), with its symbolic Cholesky.
pub struct FreeSystem {
    /// Free index of each DOF (3·node + component), or `u32::MAX` when fixed or slaved.
    pub free_index: Vec<u32>,
    pub num_free: usize,
    /// For each DOF, the free DOFs it depends on and how (empty when fixed).
    map: Vec<Vec<(u32, f64)>>,
    slaves: Vec<Slave>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// values[pos] += coef · block[(r, c)] for each (pos, block, r, c, coef)
    contrib: Vec<(u32, u32, u8, u8, f64)>,
    diag: Vec<usize>,
    symbolic: SymbolicLlt<usize>,
}

/// The linear algebra could not be set up or failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SolveError {
    #[error("sparse factorisation set-up failed: {0}")]
    Setup(String),
    #[error("the material law is undefined at the starting configuration ({0})")]
    StartOutOfDomain(String),
    #[error(
        "Newton did not converge in {iterations} iterations (relative residual {residual:.3e})"
    )]
    NotConverged { iterations: usize, residual: f64 },
    #[error("the line search found no decrease of the energy (relative residual {residual:.3e})")]
    Stalled { residual: f64 },
    #[error("linear solve failed: {0}")]
    Linear(String),
    #[error("the Hessian is not positive definite (plain Newton has no fallback; relative residual {residual:.3e})")]
    Indefinite { residual: f64 },
}

impl FreeSystem {
    /// Builds the free-DOF structure for `fixed` (one flag per DOF).
    pub fn new(model: &ShellModel, fixed: &[bool]) -> Result<Self, SolveError> {
        Self::with_slaves(model, fixed, Vec::new())
    }

    /// Builds the free-DOF structure with fixed DOFs and affine constraints.
    pub fn with_slaves(
        model: &ShellModel,
        fixed: &[bool],
        slaves: Vec<Slave>,
    ) -> Result<Self, SolveError> {
        let p = &model.pattern;
        let ndof = 3 * p.num_nodes;
        if fixed.len() != ndof {
            return Err(SolveError::Setup(format!(
                "{} fixed flags for {ndof} DOFs",
                fixed.len()
            )));
        }
        let mut is_slave = vec![false; ndof];
        for s in &slaves {
            if s.dof >= ndof || fixed[s.dof] || is_slave[s.dof] {
                return Err(SolveError::Setup(format!(
                    "DOF {} cannot be slaved (out of range, fixed or slaved twice)",
                    s.dof
                )));
            }
            is_slave[s.dof] = true;
        }
        let mut free_index = vec![NOT_FREE; ndof];
        let mut num_free = 0;
        for d in 0..ndof {
            if !fixed[d] && !is_slave[d] {
                free_index[d] = num_free as u32;
                num_free += 1;
            }
        }
        let mut map: Vec<Vec<(u32, f64)>> = (0..ndof)
            .map(|d| match free_index[d] {
                NOT_FREE => Vec::new(),
                f => vec![(f, 1.0)],
            })
            .collect();
        for s in &slaves {
            let mut m = Vec::with_capacity(s.masters.len());
            for &(d, c) in &s.masters {
                match free_index.get(d) {
                    Some(&f) if f != NOT_FREE => m.push((f, c)),
                    _ => {
                        return Err(SolveError::Setup(format!(
                            "DOF {} is slaved to DOF {d}, which is not free",
                            s.dof
                        )))
                    }
                }
            }
            map[s.dof] = m;
        }
        // every (row, col, block, r, c, coef) of the lower triangle of Tᵀ H T
        let mut entries: Vec<(u32, u32, u32, u8, u8, f64)> = Vec::new();
        let mut visit = |s: usize, t: usize, k: usize, a: usize, b: usize| {
            for &(pr, cr) in &map[s] {
                for &(qc, cc) in &map[t] {
                    if pr >= qc {
                        entries.push((qc, pr, k as u32, a as u8, b as u8, cr * cc));
                    }
                }
            }
        };
        for i in 0..p.num_nodes {
            for k in p.row_ptr[i]..p.row_ptr[i + 1] {
                let j = p.col[k] as usize;
                for a in 0..3 {
                    for b in 0..3 {
                        visit(3 * i + a, 3 * j + b, k, a, b);
                        if i != j {
                            visit(3 * j + b, 3 * i + a, k, a, b);
                        }
                    }
                }
            }
        }
        entries.sort_unstable_by_key(|e| (e.0, e.1));
        let mut col_ptr = vec![0usize; num_free + 1];
        let mut row_idx = Vec::new();
        let mut contrib = Vec::with_capacity(entries.len());
        let mut diag = vec![0usize; num_free];
        let mut last: Option<(u32, u32)> = None;
        for &(col, row, k, a, b, coef) in &entries {
            if last != Some((col, row)) {
                row_idx.push(row as usize);
                col_ptr[col as usize + 1] = row_idx.len();
                if row == col {
                    diag[col as usize] = row_idx.len() - 1;
                }
                last = Some((col, row));
            }
            contrib.push(((row_idx.len() - 1) as u32, k, a, b, coef));
        }
        for c in 0..num_free {
            col_ptr[c + 1] = col_ptr[c + 1].max(col_ptr[c]);
        }
        let sym =
            SymbolicSparseColMatRef::new_checked(num_free, num_free, &col_ptr, None, &row_idx);
        let symbolic = SymbolicLlt::try_new(sym, Side::Lower)
            .map_err(|e| SolveError::Setup(format!("{e:?}")))?;
        Ok(Self {
            free_index,
            num_free,
            map,
            slaves,
            col_ptr,
            row_idx,
            contrib,
            diag,
            symbolic,
        })
    }

    /// Number of stored entries of the lower triangle.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// The affine constraints, in the order given.
    pub fn slaves(&self) -> &[Slave] {
        &self.slaves
    }

    /// Replaces the constraint offsets (one per slave, in order): moving a clamp does not
    /// change the pattern.
    pub fn set_offsets(&mut self, offsets: &[f64]) {
        for (s, &o) in self.slaves.iter_mut().zip(offsets) {
            s.offset = o;
        }
    }

    /// Sets every slaved DOF from its masters.
    pub fn apply_constraints(&self, x: &mut [Vec3]) {
        for s in &self.slaves {
            let v = s.offset
                + s.masters
                    .iter()
                    .map(|&(d, c)| c * x[d / 3][d % 3])
                    .sum::<f64>();
            x[s.dof / 3][s.dof % 3] = v;
        }
    }

    /// Reduced gradient Tᵀ g.
    fn reduce(&self, g: &[Vec3], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        for (dof, m) in self.map.iter().enumerate() {
            let gd = g[dof / 3][dof % 3];
            for &(f, c) in m {
                out[f as usize] += c * gd;
            }
        }
    }

    /// x ← x + α T d (free DOFs moved, slaves re-derived).
    fn step(&self, x: &mut [Vec3], d: &[f64], alpha: f64) {
        for (dof, &fi) in self.free_index.iter().enumerate() {
            if fi != NOT_FREE {
                x[dof / 3][dof % 3] += alpha * d[fi as usize];
            }
        }
        self.apply_constraints(x);
    }

    fn values(&self, h: &BlockMatrix, out: &mut Vec<f64>) {
        out.clear();
        out.resize(self.row_idx.len(), 0.0);
        for &(pos, k, r, c, coef) in &self.contrib {
            out[pos as usize] += coef * h.blocks[k as usize][(r as usize, c as usize)];
        }
    }

    /// Cholesky of the free matrix with `values`; `None` when a pivot is not positive.
    fn try_factor(&self, values: &[f64]) -> Result<Option<Llt<usize, f64>>, SolveError> {
        let sym = SymbolicSparseColMatRef::new_checked(
            self.num_free,
            self.num_free,
            &self.col_ptr,
            None,
            &self.row_idx,
        );
        match Llt::try_new_with_symbolic(
            self.symbolic.clone(),
            SparseColMatRef::new(sym, values),
            Side::Lower,
        ) {
            Ok(llt) => Ok(Some(llt)),
            Err(faer::sparse::linalg::LltError::Numeric(_)) => Ok(None),
            Err(e) => Err(SolveError::Linear(format!("{e:?}"))),
        }
    }

    /// The matrix in the form the refinement kernels read.
    fn sym_lower<'a>(&'a self, values: &'a [f64]) -> refine::SymLower<'a> {
        refine::SymLower {
            col_ptr: &self.col_ptr,
            row_idx: &self.row_idx,
            values,
        }
    }

    /// Lumped mass of each free DOF (for the backward-Euler metric).
    fn free_mass(&self, node_mass: &[f64]) -> Vec<f64> {
        let mut m = vec![0.0; self.num_free];
        for (dof, maps) in self.map.iter().enumerate() {
            for &(f, c) in maps {
                m[f as usize] += c.abs() * node_mass[dof / 3];
            }
        }
        m
    }
}

/// Newton settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonOptions {
    pub max_iterations: usize,
    /// Relative residual target (see the module docs).
    pub rtol: f64,
    /// Take backward-Euler steps when Newton cannot (indefinite Hessian, ascent direction,
    /// stagnation). Without it those cases are failures: that is plain Newton.
    pub fallback: bool,
    /// Arithmetic of the iterative-refinement residual.
    pub precision: Precision,
    /// Most refinement corrections per linear solve (0: none).
    pub refine_steps: usize,
    /// How a load is brought on ([`continuation`]) and how the first steps are accepted.
    pub strategy: Strategy,
    /// The first this-many Newton iterations take the full step wherever the energy is
    /// defined, even uphill (non-monotone: the energy line search would cut the first
    /// membrane-stretching step of a heavy cantilever to nothing); 0: always line-searched.
    pub full_steps: usize,
}

/// How [`continuation`] brings on a load.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Strategy {
    /// Load steps from 1/8, doubled after easy solves, halved after failed ones; each solve
    /// Newton with an energy line search and the backward-Euler fallback.
    Ramp,
    /// First the whole load at once by full-step Newton (at most [`FULL_STEP_ITERATIONS`]
    /// iterations, kept only if it converges to a stable equilibrium), then the ramp from the
    /// start if it did not. The default: on the seven of ten cantilevers of the example material
    /// (20–400 mm, 0° and 45°) that either strategy solves, and the heavy D1388 cantilever, it
    /// took 1448 Newton iterations where the ramp took 1774 (heavy cantilever at 4×16: 15
    /// against 108), drape angles equal to 1e-9; where full steps fail it costs 25 more.
    #[default]
    FullStep,
}

impl std::str::FromStr for Strategy {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "ramp" => Ok(Self::Ramp),
            "full-step" => Ok(Self::FullStep),
            _ => Err(format!(
                "unknown strategy '{s}' (expected ramp or full-step)"
            )),
        }
    }
}

/// Iteration budget of the full-step attempt (plain full-step Newton brings the heavy
/// ASTM D1388 cantilever from flat in 15).
pub const FULL_STEP_ITERATIONS: usize = 25;

impl Default for NewtonOptions {
    fn default() -> Self {
        Self {
            max_iterations: 60,
            rtol: 1e-10,
            fallback: true,
            precision: Precision::DoubleDouble,
            refine_steps: 4,
            strategy: Strategy::FullStep,
            full_steps: 0,
        }
    }
}

impl NewtonOptions {
    /// Newton with a line search and nothing else (loads ramped).
    pub fn plain() -> Self {
        Self {
            fallback: false,
            refine_steps: 0,
            strategy: Strategy::Ramp,
            ..Self::default()
        }
    }
}

/// Why backward Euler was used.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FallbackCounts {
    /// The Cholesky factorisation met a non-positive pivot (the Hessian is not positive definite).
    pub indefinite: usize,
    /// The Newton step was not a descent direction, or the line search found no decrease.
    pub ascent: usize,
    /// Three consecutive Newton steps lowered the energy by ≤ 0.1 % in all without the residual
    /// falling tenfold.
    pub stagnation: usize,
    /// The line search cut a Newton step below 1/8 (our addition to the paper's triggers).
    pub short_step: usize,
}

/// What a solve did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolveReport {
    /// Newton and backward-Euler iterations.
    pub iterations: usize,
    pub energy: f64,
    /// ‖g_free‖ / force scale at the end.
    pub residual: f64,
    pub factorizations: usize,
    /// Backward-Euler steps taken, and why the solver turned to them.
    pub backward_euler_steps: usize,
    pub fallbacks: FallbackCounts,
    /// Refinement corrections applied over all linear solves, and the precision used.
    pub refinement_steps: usize,
    pub precision: Precision,
    /// Line-search step halvings in total.
    pub backtracks: usize,
    pub assembly_seconds: f64,
    pub factor_seconds: f64,
    pub seconds: f64,
    /// Converged at the round-off floor of the force evaluation rather than by `rtol`.
    pub precision_limited: bool,
    /// The Hessian is positive definite at the solution (a stable equilibrium).
    pub stable: bool,
    /// Times an unstable equilibrium (a saddle) was perturbed and the solve continued.
    pub saddle_escapes: usize,
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Why the next step is a backward-Euler step.
enum Mode {
    Newton,
    BackwardEuler,
}

/// Solves for equilibrium from `x` (fixed DOFs keep their values, slaved ones follow), in place.
///
/// Each iteration assembles energy, gradient and Hessian and tests convergence. A Newton step
/// solves H d = −g (Cholesky, refined); a backward-Euler step solves (H + μM) d = −g, the
/// linearised minimiser of E(x) + μ/2 ‖x − x̂‖²_M (μ = 1/h², M the lumped mass), with μ raised
/// tenfold until the factorisation succeeds. Both are followed by a backtracking line search on
/// the energy. Backward Euler takes over when the Hessian is not positive definite, when the
/// Newton step is not a descent direction, when three Newton steps lower the energy by ≤ 0.1 %
/// without the residual falling tenfold (the paper's triggers), and when the line search cuts a
/// Newton step below 1/8. After each backward-Euler step Newton is tried again; h is adapted
/// like a trust region (μ ÷ 4 after a full step, × 4 after a cut one) and kept between uses.
/// The tangent of an equilibrium: the full Hessian H and the reduced K = Tᵀ H T, factorised
/// once so that any number of right-hand sides are solved on it (the sensitivity system of
/// Clyde et al. 2017, Eq. 6; constraints are eliminated, so no multipliers appear).
pub struct Linearization {
    pub hessian: BlockMatrix,
    values: Vec<f64>,
    llt: Llt<usize, f64>,
}

impl Linearization {
    /// Assembles and factorises at `x` (an equilibrium of `system`). Fails if K is not
    /// positive definite: a saddle has no unique sensitivity.
    pub fn new(model: &ShellModel, system: &FreeSystem, x: &[Vec3]) -> Result<Self, SolveError> {
        let (hessian, values) = Self::assemble(model, system, x)?;
        let llt = system.try_factor(&values)?.ok_or_else(|| {
            SolveError::Linear("the equilibrium's Hessian is not positive definite".into())
        })?;
        Ok(Self {
            hessian,
            values,
            llt,
        })
    }

    /// The full Hessian at `x` and the reduced K's values.
    fn assemble(
        model: &ShellModel,
        system: &FreeSystem,
        x: &[Vec3],
    ) -> Result<(BlockMatrix, Vec<f64>), SolveError> {
        let mut grad = vec![[0.0; 3]; model.num_nodes()];
        let mut hessian = BlockMatrix::zeros(model.pattern.clone());
        model
            .assemble(x, Want::Hessian, Some(&mut grad), Some(&mut hessian))
            .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
        let mut values = Vec::new();
        system.values(&hessian, &mut values);
        Ok((hessian, values))
    }

    /// As [`Linearization::new`], but where K is not positive definite (an equilibrium that
    /// ended on a saddle, or on the singular tangent of a wrinkling bifurcation) factorises
    /// K + σ D instead, D = diag K and σ = 1e-10, 1e-8, … 1e-4, the first that succeeds:
    /// sensitivities of a regularised tangent, for a minimiser's search direction only.
    /// Returns the linearization and σ (0 when none was needed).
    pub fn new_regularized(
        model: &ShellModel,
        system: &FreeSystem,
        x: &[Vec3],
    ) -> Result<(Self, f64), SolveError> {
        let (hessian, values) = Self::assemble(model, system, x)?;
        for sigma in [0.0, 1e-10, 1e-8, 1e-6, 1e-4] {
            let mut shifted = values.clone();
            for &k in &system.diag {
                shifted[k] += sigma * values[k].abs();
            }
            if let Some(llt) = system.try_factor(&shifted)? {
                return Ok((
                    Self {
                        hessian,
                        values: shifted,
                        llt,
                    },
                    sigma,
                ));
            }
        }
        Err(SolveError::Linear(
            "the equilibrium's Hessian is not positive definite, even shifted by 1e-4 of its diagonal".into(),
        ))
    }

    /// K⁻¹ Tᵀ g for a full-length vector g (one refinement step with an f64 residual).
    pub fn solve_reduced(&self, system: &FreeSystem, g: &[Vec3]) -> Vec<f64> {
        let nf = system.num_free;
        let mut rhs = vec![0.0; nf];
        system.reduce(g, &mut rhs);
        let mut d = rhs.clone();
        self.llt
            .solve_in_place(MatMut::from_column_major_slice_mut(&mut d, nf, 1));
        refine::refine(
            &system.sym_lower(&self.values),
            &rhs,
            &mut d,
            Precision::F64,
            1,
            |r| {
                self.llt
                    .solve_in_place(MatMut::from_column_major_slice_mut(r, nf, 1))
            },
        );
        d
    }
}

impl FreeSystem {
    /// x ← x + T d: free DOFs moved by d, slaved DOFs re-derived.
    pub fn advance(&self, x: &mut [Vec3], d: &[f64]) {
        self.step(x, d, 1.0);
    }

    /// Tᵀ g over the free DOFs, for a full-length vector g.
    pub fn reduced(&self, g: &[Vec3]) -> Vec<f64> {
        let mut out = vec![0.0; self.num_free];
        self.reduce(g, &mut out);
        out
    }
}

/// Whether `x` is a stable state of `system`: its reduced Hessian is positive definite (one
/// assembly and one Cholesky attempt; meaningful at an equilibrium).
pub fn is_stable(model: &ShellModel, system: &FreeSystem, x: &[Vec3]) -> Result<bool, SolveError> {
    let mut x = x.to_vec();
    system.apply_constraints(&mut x);
    let mut grad = vec![[0.0; 3]; model.num_nodes()];
    let mut hess = BlockMatrix::zeros(model.pattern.clone());
    model
        .assemble(&x, Want::Hessian, Some(&mut grad), Some(&mut hess))
        .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
    let mut values = Vec::new();
    system.values(&hess, &mut values);
    Ok(system.try_factor(&values)?.is_some())
}

pub fn newton(
    model: &ShellModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    opts: &NewtonOptions,
) -> Result<SolveReport, SolveError> {
    newton_linearized(model, system, x, opts).map(|r| r.0)
}

/// [`newton`], also handing back the factorised tangent at the solution when it is positive
/// definite (the stability check factorises it anyway): sensitivities then cost no further
/// assembly or factorisation.
pub fn newton_linearized(
    model: &ShellModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    opts: &NewtonOptions,
) -> Result<(SolveReport, Option<Linearization>), SolveError> {
    let t0 = Instant::now();
    let nn = model.num_nodes();
    let nf = system.num_free;
    let mut grad = vec![[0.0; 3]; nn];
    let mut hess = BlockMatrix::zeros(model.pattern.clone());
    let mut values = Vec::new();
    let mut report = SolveReport {
        precision: opts.precision,
        ..SolveReport::default()
    };
    let external = model.external_load();
    let external_scale = norm(&external.concat());
    let mass = system.free_mass(&model.lumped_mass());
    let mut trial = x.to_vec();
    let mut gf = vec![0.0; nf];
    let mut d = vec![0.0; nf];
    let mut mode = Mode::Newton;
    let mut mu = 0.0f64;
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut be_energy: Vec<f64> = Vec::new();
    // (energy, residual) after recent Newton steps, for the stagnation rule
    let mut history: Vec<(f64, f64)> = Vec::new();
    // a Newton step at a residual under STALL_RTOL found no use: the round-off floor
    let mut at_floor = false;
    system.apply_constraints(x);
    for it in 0..=opts.max_iterations {
        let ta = Instant::now();
        let energy = model
            .assemble(x, Want::Hessian, Some(&mut grad), Some(&mut hess))
            .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
        report.assembly_seconds += ta.elapsed().as_secs_f64();
        report.energy = energy;
        // internal force over all DOFs (gradient plus the external load) sets the scale
        let mut internal = 0.0;
        for (g, f) in grad.iter().zip(&external) {
            for c in 0..3 {
                internal += (g[c] + f[c]).powi(2);
            }
        }
        let scale = internal.sqrt() + external_scale;
        system.reduce(&grad, &mut gf);
        let gnorm = norm(&gf);
        report.residual = if scale > 0.0 { gnorm / scale } else { gnorm };
        report.iterations = it;
        // the round-off floor of the force evaluation: positions are known to ε‖x‖∞, so forces
        // to about ε‖diag K‖‖x‖∞ (measured: residuals stall at 0.15–0.3 of this)
        system.values(&hess, &mut values);
        let diag_norm = system
            .diag
            .iter()
            .map(|&k| values[k] * values[k])
            .sum::<f64>()
            .sqrt();
        let xmax = x.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let floor = 2.0 * f64::EPSILON * diag_norm * xmax;
        // the floor estimate can miss: an off-axis strip at 0.03 % strain stalled at 8.6e-9
        // (its strains are differences of O(1) metrics, good to ε/strain). A Newton step that
        // does not halve a residual already under STALL_RTOL, or one the line search cannot
        // use there, means Newton is at the floor: forces good to 1e-6 are far inside any
        // measurement
        let stalled = gnorm <= STALL_RTOL * scale
            && (at_floor
                || (matches!(mode, Mode::Newton)
                    && history.last().is_some_and(|&(_, r)| gnorm >= 0.5 * r)));
        if gnorm <= opts.rtol * scale || gnorm <= floor || gnorm == 0.0 || stalled {
            report.precision_limited = gnorm > opts.rtol * scale;
            // an equilibrium whose Hessian is not positive definite is a saddle (a flat strip in
            // compression, held there by its own symmetry): nudge it off and go on
            let llt = system.try_factor(&values)?;
            let stable = llt.is_some();
            if !stable && opts.fallback && report.saddle_escapes < 5 && it < opts.max_iterations {
                report.saddle_escapes += 1;
                perturb(system, x, &mut seed);
                mode = Mode::BackwardEuler;
                history.clear();
                continue;
            }
            report.stable = stable;
            report.seconds = t0.elapsed().as_secs_f64();
            let lin = llt.map(|llt| Linearization {
                hessian: hess,
                values,
                llt,
            });
            return Ok((report, lin));
        }
        if it == opts.max_iterations {
            break;
        }
        // stagnation: three Newton steps with ≤ 0.1 % energy drop and no tenfold residual drop
        // (not while full steps are taken: the energy may rise there by design)
        if let (Mode::Newton, true) = (&mode, history.len() >= 3 && it >= opts.full_steps) {
            let (e0, r0) = history[history.len() - 3];
            if e0 - energy <= 1e-3 * e0.abs() && gnorm > 0.1 * r0 && opts.fallback {
                report.fallbacks.stagnation += 1;
                mode = Mode::BackwardEuler;
                history.clear();
            }
        }
        let tf = Instant::now();
        let llt = match mode {
            Mode::Newton => match system.try_factor(&values)? {
                Some(llt) => llt,
                None => {
                    report.factorizations += 1;
                    if !opts.fallback {
                        return Err(SolveError::Indefinite {
                            residual: report.residual,
                        });
                    }
                    report.fallbacks.indefinite += 1;
                    mode = Mode::BackwardEuler;
                    history.clear();
                    backward_euler_factor(system, &mut values, &mass, &mut mu, &mut report)?
                }
            },
            Mode::BackwardEuler => {
                backward_euler_factor(system, &mut values, &mass, &mut mu, &mut report)?
            }
        };
        report.factorizations += 1;
        for (di, gi) in d.iter_mut().zip(&gf) {
            *di = -gi;
        }
        let rhs = d.clone();
        llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut d, nf, 1));
        if opts.refine_steps > 0 {
            let rep = refine::refine(
                &system.sym_lower(&values),
                &rhs,
                &mut d,
                opts.precision,
                opts.refine_steps,
                |r| llt.solve_in_place(MatMut::from_column_major_slice_mut(r, nf, 1)),
            );
            report.refinement_steps += rep.steps;
        }
        report.factor_seconds += tf.elapsed().as_secs_f64();
        let slope: f64 = d.iter().zip(&gf).map(|(a, b)| a * b).sum();
        let descent = slope < 0.0;
        // backtracking (Armijo) line search on the energy
        let mut accepted = None;
        let mut alpha = 1.0;
        if descent && it < opts.full_steps && matches!(mode, Mode::Newton) {
            trial.copy_from_slice(x);
            system.step(&mut trial, &d, 1.0);
            accepted = model.energy(&trial).ok().filter(|e| e.is_finite());
        }
        if descent && accepted.is_none() {
            for _ in 0..40 {
                trial.copy_from_slice(x);
                system.step(&mut trial, &d, alpha);
                if let Ok(e) = model.energy(&trial) {
                    // accept a decrease, or a change below round-off of the energy
                    if e <= energy + 1e-4 * alpha * slope
                        || (e - energy).abs() <= 1e-14 * energy.abs().max(f64::MIN_POSITIVE)
                    {
                        accepted = Some(e);
                        break;
                    }
                }
                alpha *= 0.5;
                report.backtracks += 1;
            }
        }
        match (accepted, &mode) {
            (Some(e), Mode::Newton) => {
                x.copy_from_slice(&trial);
                history.push((e, gnorm));
                be_energy.clear();
                // a Newton step the line search had to cut below 1/8 is not trusted: the
                // quadratic model is poor here (large rotations of a thin shell, say)
                if alpha < 0.125 && report.residual <= STALL_RTOL {
                    at_floor = true;
                } else if alpha < 0.125 && opts.fallback {
                    report.fallbacks.short_step += 1;
                    mode = Mode::BackwardEuler;
                    history.clear();
                }
            }
            (Some(e), Mode::BackwardEuler) => {
                x.copy_from_slice(&trial);
                report.backward_euler_steps += 1;
                // creeping towards a saddle: the Hessian stays indefinite (we are in backward
                // Euler because Newton's factorisation failed) while the energy no longer
                // moves; the symmetric state will not leave by itself, so nudge it
                be_energy.push(e);
                let n = be_energy.len();
                if n >= 8
                    && (be_energy[n - 8] - e).abs() <= 1e-7 * e.abs()
                    && report.saddle_escapes < 5
                {
                    report.saddle_escapes += 1;
                    perturb(system, x, &mut seed);
                    be_energy.clear();
                }
                // trust-region-like control of the step size h = 1/√μ: longer after a full
                // step, shorter after a cut one; then try Newton again (if the Hessian is still
                // indefinite the next factorisation sends us straight back, with this μ)
                if alpha == 1.0 {
                    mu *= 0.25;
                } else {
                    mu *= 4.0;
                }
                mode = Mode::Newton;
            }
            (None, Mode::Newton) if report.residual <= STALL_RTOL => at_floor = true,
            (None, Mode::Newton) => {
                if !opts.fallback {
                    return Err(SolveError::Stalled {
                        residual: report.residual,
                    });
                }
                report.fallbacks.ascent += 1;
                mode = Mode::BackwardEuler;
                history.clear();
            }
            (None, Mode::BackwardEuler) => {
                // a stiffer regularisation gives a shorter, safer step
                mu = if mu > 0.0 { 10.0 * mu } else { 1.0 };
            }
        }
    }
    Err(SolveError::NotConverged {
        iterations: opts.max_iterations,
        residual: report.residual,
    })
}

/// Moves every free DOF by a pseudo-random amount of 1e-6 of the body's size (deterministic).
fn perturb(system: &FreeSystem, x: &mut [Vec3], seed: &mut u64) {
    let (lo, hi) = x
        .iter()
        .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
            (
                std::array::from_fn(|c| lo[c].min(p[c])),
                std::array::from_fn(|c| hi[c].max(p[c])),
            )
        });
    let size = (0..3).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt();
    let mut d = vec![0.0; system.num_free];
    for v in d.iter_mut() {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        *v = ((*seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2e-6 * size;
    }
    system.step(x, &d, 1.0);
}

/// Factorises H + μM, raising μ tenfold until the factorisation succeeds. `values` comes back
/// holding H + μM.
fn backward_euler_factor(
    system: &FreeSystem,
    values: &mut [f64],
    mass: &[f64],
    mu: &mut f64,
    report: &mut SolveReport,
) -> Result<Llt<usize, f64>, SolveError> {
    let mean_diag =
        system.diag.iter().map(|&k| values[k].abs()).sum::<f64>() / system.diag.len().max(1) as f64;
    let mean_mass = mass.iter().sum::<f64>() / mass.len().max(1) as f64;
    if !mu.is_finite() || *mu <= 0.0 {
        // start where the mass term is a thousandth of the stiffness
        *mu = 1e-3 * mean_diag / mean_mass.max(f64::MIN_POSITIVE);
    }
    let mut applied = 0.0;
    for _ in 0..40 {
        for (&k, &m) in system.diag.iter().zip(mass) {
            values[k] += (*mu - applied) * m;
        }
        applied = *mu;
        if let Some(llt) = system.try_factor(values)? {
            return Ok(llt);
        }
        report.factorizations += 1;
        *mu *= 10.0;
    }
    Err(SolveError::Linear(
        "no backward-Euler step size makes the system positive definite".into(),
    ))
}

/// What a continuation did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContinuationReport {
    /// Load steps solved.
    pub steps: usize,
    /// Newton iterations over all attempts, failed ones included.
    pub iterations: usize,
    /// The last (full-load) solve.
    pub last: SolveReport,
}

/// Raises a load factor t from 0 to 1, `apply(model, t, x)` setting the load (x: the last
/// equilibrium), solving for equilibrium at each step. The first increment is min(1/8,
/// `max_step`); it doubles after an easy solve (≤ 12 Newton iterations), up to `max_step`, and
/// halves after a failed one. Each solve starts from the secant
/// prediction through the last two equilibria. On failure returns the load factor reached for
/// and the error. With [`Strategy::FullStep`] (and `max_step` 1) the whole load is tried first
/// by full-step Newton; its iterations count in the report whether it is kept or not.
pub fn continuation(
    model: &mut ShellModel,
    system: &FreeSystem,
    x: &mut Vec<Vec3>,
    solver: &NewtonOptions,
    max_step: f64,
    mut apply: impl FnMut(&mut ShellModel, f64, &[Vec3]),
) -> Result<ContinuationReport, (f64, SolveError)> {
    let opts = NewtonOptions {
        max_iterations: solver.max_iterations.min(30),
        ..*solver
    };
    let (mut factor, mut step) = (0.0f64, 0.125f64.min(max_step));
    let mut report = ContinuationReport::default();
    if solver.strategy == Strategy::FullStep && max_step >= 1.0 {
        apply(model, 1.0, x);
        let mut trial = x.clone();
        let full = NewtonOptions {
            max_iterations: FULL_STEP_ITERATIONS,
            full_steps: FULL_STEP_ITERATIONS,
            ..*solver
        };
        match newton(model, system, &mut trial, &full) {
            Ok(r) if r.stable => {
                *x = trial;
                report.steps = 1;
                report.iterations = r.iterations;
                report.last = r;
                return Ok(report);
            }
            Ok(r) => report.iterations += r.iterations,
            Err(_) => report.iterations += FULL_STEP_ITERATIONS,
        }
    }
    let mut previous: Option<(f64, Vec<Vec3>)> = None;
    while factor < 1.0 {
        let target = (factor + step).min(1.0);
        apply(model, target, x);
        let mut trial = x.clone();
        if let Some((f0, x0)) = &previous {
            let r = (target - factor) / (factor - f0);
            for (t, (a, b)) in trial.iter_mut().zip(x.iter().zip(x0)) {
                for c in 0..3 {
                    t[c] = a[c] + r * (a[c] - b[c]);
                }
            }
        }
        match newton(model, system, &mut trial, &opts) {
            Ok(r) => {
                previous = Some((factor, std::mem::replace(x, trial)));
                factor = target;
                report.steps += 1;
                report.iterations += r.iterations;
                if r.iterations <= 12 {
                    step = (2.0 * step).min(max_step);
                }
                report.last = r;
            }
            Err(e) => {
                report.iterations += opts.max_iterations;
                step *= 0.5;
                if step < 1e-4 {
                    apply(model, factor, x);
                    return Err((target, e));
                }
            }
        }
    }
    Ok(report)
}
