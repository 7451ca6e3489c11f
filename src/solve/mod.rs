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
//! the Newton correction is below the floating-point resolution of the coordinates
//! (‖d‖∞ ≤ 8 ε ‖x‖∞), when the residual left is round-off in the force evaluation itself
//! (thin shells under tiny loads reach this floor first; the report says so).

use crate::assembly::{BlockMatrix, ShellModel, Want};
use crate::Vec3;
use faer::prelude::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{MatMut, Side};
use std::time::Instant;

const NOT_FREE: u32 = u32::MAX;

/// The free-DOF Hessian in compressed columns (lower triangle) with its symbolic Cholesky.
pub struct FreeSystem {
    /// Free index of each DOF (3·node + component), or `u32::MAX` when fixed.
    pub free_index: Vec<u32>,
    pub num_free: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// (block, row in block, column in block) feeding each value
    src: Vec<(u32, u8, u8)>,
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
}

impl FreeSystem {
    /// Builds the free-DOF structure for `fixed` (one flag per DOF).
    pub fn new(model: &ShellModel, fixed: &[bool]) -> Result<Self, SolveError> {
        let p = &model.pattern;
        let ndof = 3 * p.num_nodes;
        assert_eq!(fixed.len(), ndof, "one fixed flag per DOF");
        let mut free_index = vec![NOT_FREE; ndof];
        let mut num_free = 0;
        for d in 0..ndof {
            if !fixed[d] {
                free_index[d] = num_free as u32;
                num_free += 1;
            }
        }
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        let mut src = Vec::new();
        let mut diag = Vec::with_capacity(num_free);
        for j in 0..p.num_nodes {
            for b in 0..3 {
                let c = free_index[3 * j + b];
                if c == NOT_FREE {
                    continue;
                }
                for k in p.row_ptr[j]..p.row_ptr[j + 1] {
                    let i = p.col[k] as usize;
                    for a in 0..3 {
                        let r = free_index[3 * i + a];
                        if r == NOT_FREE || r < c {
                            continue;
                        }
                        if r == c {
                            diag.push(row_idx.len());
                        }
                        row_idx.push(r as usize);
                        // entry (row: node i comp a, col: node j comp b) = block(j, i)[(b, a)]
                        src.push((k as u32, b as u8, a as u8));
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let sym =
            SymbolicSparseColMatRef::new_checked(num_free, num_free, &col_ptr, None, &row_idx);
        let symbolic = SymbolicLlt::try_new(sym, Side::Lower)
            .map_err(|e| SolveError::Setup(format!("{e:?}")))?;
        Ok(Self {
            free_index,
            num_free,
            col_ptr,
            row_idx,
            src,
            diag,
            symbolic,
        })
    }

    /// Number of stored entries of the lower triangle.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    fn values(&self, h: &BlockMatrix, out: &mut Vec<f64>) {
        out.clear();
        out.extend(
            self.src
                .iter()
                .map(|&(k, r, c)| h.blocks[k as usize][(r as usize, c as usize)]),
        );
    }

    /// Factorises the free Hessian, shifting its diagonal until it is positive definite.
    /// Returns the factor and the shift used.
    fn factor(&self, values: &mut [f64]) -> Result<(Llt<usize, f64>, f64), SolveError> {
        let sym = SymbolicSparseColMatRef::new_checked(
            self.num_free,
            self.num_free,
            &self.col_ptr,
            None,
            &self.row_idx,
        );
        let mean_diag =
            self.diag.iter().map(|&k| values[k].abs()).sum::<f64>() / self.diag.len().max(1) as f64;
        let mut shift = 0.0;
        for attempt in 0..40 {
            if attempt > 0 {
                let next = if shift == 0.0 {
                    1e-8 * mean_diag
                } else {
                    10.0 * shift
                };
                for &k in &self.diag {
                    values[k] += next - shift;
                }
                shift = next;
            }
            match Llt::try_new_with_symbolic(
                self.symbolic.clone(),
                SparseColMatRef::new(sym, values),
                Side::Lower,
            ) {
                Ok(llt) => return Ok((llt, shift)),
                Err(faer::sparse::linalg::LltError::Numeric(_)) => continue,
                Err(e) => return Err(SolveError::Linear(format!("{e:?}"))),
            }
        }
        Err(SolveError::Linear(
            "the Hessian stayed indefinite under every diagonal shift".into(),
        ))
    }

    /// y = A x with the stored lower triangle (symmetric product).
    fn sym_mul(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        for c in 0..self.num_free {
            for k in self.col_ptr[c]..self.col_ptr[c + 1] {
                let r = self.row_idx[k];
                y[r] += values[k] * x[c];
                if r != c {
                    y[c] += values[k] * x[r];
                }
            }
        }
    }
}

/// Newton settings.
#[derive(Clone, Copy, Debug)]
pub struct NewtonOptions {
    pub max_iterations: usize,
    /// Relative residual target (see the module docs).
    pub rtol: f64,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        Self {
            max_iterations: 60,
            rtol: 1e-10,
        }
    }
}

/// What a solve did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolveReport {
    pub iterations: usize,
    pub energy: f64,
    /// ‖g_free‖ / force scale at the end.
    pub residual: f64,
    pub factorizations: usize,
    /// Newton steps whose Hessian needed a diagonal shift.
    pub shifted_steps: usize,
    /// Line-search step halvings in total.
    pub backtracks: usize,
    pub assembly_seconds: f64,
    pub factor_seconds: f64,
    pub seconds: f64,
    /// Converged because the Newton step fell below the resolution of the coordinates (the
    /// residual cannot be computed more accurately in double precision), not by `rtol`.
    pub precision_limited: bool,
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Solves for equilibrium from `x` (fixed DOFs keep their values), in place.
pub fn newton(
    model: &ShellModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    opts: &NewtonOptions,
) -> Result<SolveReport, SolveError> {
    let t0 = Instant::now();
    let nn = model.num_nodes();
    let nf = system.num_free;
    let mut grad = vec![[0.0; 3]; nn];
    let mut hess = BlockMatrix::zeros(model.pattern.clone());
    let mut values = Vec::new();
    let mut report = SolveReport::default();
    let gravity_scale = norm(&model.gravity_load().concat());
    let gravity = model.gravity_load();
    let mut trial = x.to_vec();
    let mut gf = vec![0.0; nf];
    let mut d = vec![0.0; nf];
    let mut check = vec![0.0; nf];
    for it in 0..=opts.max_iterations {
        let ta = Instant::now();
        let energy = model
            .assemble(x, Want::Hessian, Some(&mut grad), Some(&mut hess))
            .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
        report.assembly_seconds += ta.elapsed().as_secs_f64();
        report.energy = energy;
        // internal force over all DOFs (gradient minus the gravity term) sets the scale
        let mut internal = 0.0;
        for (g, f) in grad.iter().zip(&gravity) {
            for c in 0..3 {
                internal += (g[c] + f[c]).powi(2);
            }
        }
        let scale = internal.sqrt() + gravity_scale;
        for (dof, &fi) in system.free_index.iter().enumerate() {
            if fi != NOT_FREE {
                gf[fi as usize] = grad[dof / 3][dof % 3];
            }
        }
        let gnorm = norm(&gf);
        report.residual = if scale > 0.0 { gnorm / scale } else { gnorm };
        report.iterations = it;
        if gnorm <= opts.rtol * scale || gnorm == 0.0 {
            report.seconds = t0.elapsed().as_secs_f64();
            return Ok(report);
        }
        if it == opts.max_iterations {
            break;
        }
        system.values(&hess, &mut values);
        let tf = Instant::now();
        let (llt, shift) = system.factor(&mut values)?;
        report.factorizations += 1;
        if shift > 0.0 {
            report.shifted_steps += 1;
        }
        for (di, gi) in d.iter_mut().zip(&gf) {
            *di = -gi;
        }
        llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut d, nf, 1));
        // residual check, with one step of refinement when it is poor
        system.sym_mul(&values, &d, &mut check);
        let res: f64 = check
            .iter()
            .zip(&gf)
            .map(|(a, g)| (a + g).powi(2))
            .sum::<f64>()
            .sqrt();
        if res > 1e-8 * gnorm {
            let mut corr: Vec<f64> = check.iter().zip(&gf).map(|(a, g)| -(a + g)).collect();
            llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut corr, nf, 1));
            for (di, ci) in d.iter_mut().zip(&corr) {
                *di += ci;
            }
        }
        report.factor_seconds += tf.elapsed().as_secs_f64();
        // a step below the floating-point resolution of the coordinates cannot improve them:
        // the residual left is round-off in the forces
        let xmax = x.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let dmax = d.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if dmax <= 8.0 * f64::EPSILON * xmax {
            report.precision_limited = true;
            report.seconds = t0.elapsed().as_secs_f64();
            return Ok(report);
        }
        let slope: f64 = d.iter().zip(&gf).map(|(a, b)| a * b).sum();
        if slope.is_nan() || slope >= 0.0 {
            return Err(SolveError::Stalled {
                residual: report.residual,
            });
        }
        // backtracking (Armijo) line search
        let mut alpha = 1.0;
        let mut accepted = false;
        for _ in 0..40 {
            trial.copy_from_slice(x);
            for (dof, &fi) in system.free_index.iter().enumerate() {
                if fi != NOT_FREE {
                    trial[dof / 3][dof % 3] += alpha * d[fi as usize];
                }
            }
            if let Ok(e) = model.energy(&trial) {
                // accept a decrease, or a change below round-off of the energy (final steps)
                if e <= energy + 1e-4 * alpha * slope
                    || (e - energy).abs() <= 1e-14 * energy.abs().max(f64::MIN_POSITIVE)
                {
                    accepted = true;
                    break;
                }
            }
            alpha *= 0.5;
            report.backtracks += 1;
        }
        if !accepted {
            return Err(SolveError::Stalled {
                residual: report.residual,
            });
        }
        x.copy_from_slice(&trial);
    }
    Err(SolveError::NotConverged {
        iterations: opts.max_iterations,
        residual: report.residual,
    })
}
