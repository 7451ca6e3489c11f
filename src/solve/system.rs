//! The free-DOF system: fixed DOFs and affine constraints (slaves) eliminated, the reduced
//! Hessian Tᵀ H T in compressed columns and its symbolic Cholesky, computed once per constraint
//! set and reused by every numeric factorisation.

use super::{refine, SolveError};
use crate::model::{BlockMatrix, BlockPattern, ClothModel};
use crate::Vec3;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::Side;

pub(super) const NOT_FREE: u32 = u32::MAX;

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
    pub(super) diag: Vec<usize>,
    symbolic: SymbolicLlt<usize>,
}

/// The free index of every DOF (`NOT_FREE` where `fixed` or `is_slave`), the number of free DOFs,
/// and each DOF's row of T: (free index, coefficient) pairs.
#[allow(clippy::type_complexity)]
fn free_map(
    fixed: &[bool],
    is_slave: &[bool],
    slaves: &[Slave],
    ndof: usize,
) -> Result<(Vec<u32>, usize, Vec<Vec<(u32, f64)>>), SolveError> {
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
    for s in slaves {
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
    Ok((free_index, num_free, map))
}

/// Every (col, row, block, r, c, coef) of the lower triangle of Tᵀ H T, H's blocks on the
/// pattern `p` and T's rows in `map`, sorted by (col, row).
fn reduced_entries(p: &BlockPattern, map: &[Vec<(u32, f64)>]) -> Vec<(u32, u32, u32, u8, u8, f64)> {
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
    entries
}

/// The compressed columns of the sorted `entries`: column pointers, row indices, each entry's
/// (stored position, block, r, c, coef), and the position of each diagonal entry.
#[allow(clippy::type_complexity)]
fn compress(
    entries: &[(u32, u32, u32, u8, u8, f64)],
    num_free: usize,
) -> (
    Vec<usize>,
    Vec<usize>,
    Vec<(u32, u32, u8, u8, f64)>,
    Vec<usize>,
) {
    let mut col_ptr = vec![0usize; num_free + 1];
    let mut row_idx = Vec::new();
    let mut contrib = Vec::with_capacity(entries.len());
    let mut diag = vec![0usize; num_free];
    let mut last: Option<(u32, u32)> = None;
    for &(col, row, k, a, b, coef) in entries {
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
    (col_ptr, row_idx, contrib, diag)
}

impl FreeSystem {
    /// Builds the free-DOF structure for `fixed` (one flag per DOF).
    pub fn new(model: &dyn ClothModel, fixed: &[bool]) -> Result<Self, SolveError> {
        Self::with_slaves(model, fixed, Vec::new())
    }

    /// Builds the free-DOF structure with fixed DOFs and affine constraints.
    pub fn with_slaves(
        model: &dyn ClothModel,
        fixed: &[bool],
        slaves: Vec<Slave>,
    ) -> Result<Self, SolveError> {
        let p = model.pattern();
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
        let (free_index, num_free, map) = free_map(fixed, &is_slave, &slaves, ndof)?;
        let entries = reduced_entries(p, &map);
        let (col_ptr, row_idx, contrib, diag) = compress(&entries, num_free);
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
    pub(super) fn reduce(&self, g: &[Vec3], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        for (dof, m) in self.map.iter().enumerate() {
            let gd = g[dof / 3][dof % 3];
            for &(f, c) in m {
                out[f as usize] += c * gd;
            }
        }
    }

    /// T d over every DOF: the free DOFs' values, each slave's combination of its masters', the
    /// clamped DOFs' zero (a motion, not a position: no offsets).
    pub(super) fn expand(&self, d: &[f64]) -> Vec<Vec3> {
        let mut out = vec![[0.0; 3]; self.map.len() / 3];
        for (dof, m) in self.map.iter().enumerate() {
            out[dof / 3][dof % 3] = m.iter().map(|&(f, c)| c * d[f as usize]).sum();
        }
        out
    }

    /// x ← x + α T d (free DOFs moved, slaves re-derived).
    pub(super) fn step(&self, x: &mut [Vec3], d: &[f64], alpha: f64) {
        for (dof, &fi) in self.free_index.iter().enumerate() {
            if fi != NOT_FREE {
                x[dof / 3][dof % 3] += alpha * d[fi as usize];
            }
        }
        self.apply_constraints(x);
    }

    pub(super) fn values(&self, h: &BlockMatrix, out: &mut Vec<f64>) {
        out.clear();
        out.resize(self.row_idx.len(), 0.0);
        for &(pos, k, r, c, coef) in &self.contrib {
            out[pos as usize] += coef * h.blocks[k as usize][(r as usize, c as usize)];
        }
    }

    /// Cholesky of the free matrix with `values`; `None` when a pivot is not positive.
    pub(super) fn try_factor(&self, values: &[f64]) -> Result<Option<Llt<usize, f64>>, SolveError> {
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
    pub(super) fn sym_lower<'a>(&'a self, values: &'a [f64]) -> refine::SymLower<'a> {
        refine::SymLower {
            col_ptr: &self.col_ptr,
            row_idx: &self.row_idx,
            values,
        }
    }

    /// Lumped mass of each free DOF (for the backward-Euler metric).
    pub(super) fn free_mass(&self, node_mass: &[f64]) -> Vec<f64> {
        let mut m = vec![0.0; self.num_free];
        for (dof, maps) in self.map.iter().enumerate() {
            for &(f, c) in maps {
                m[f as usize] += c.abs() * node_mass[dof / 3];
            }
        }
        m
    }

    /// x ← x + T d: free DOFs moved by d, slaved DOFs re-derived.
    pub fn advance(&self, x: &mut [Vec3], d: &[f64]) {
        self.step(x, d, 1.0);
    }

    /// Moves `x`, an equilibrium at parameters `k0`, to parameters `k` along its parameter
    /// tangent `dq` (∂q/∂k, reduced, one row per parameter): q + Σ (k − k0)_j ∂q/∂k_j.
    pub fn advance_along(&self, x: &mut [Vec3], k: &[f64], k0: &[f64], dq: &[Vec<f64>]) {
        let mut d = vec![0.0; self.num_free];
        for ((k, k0), dqj) in k.iter().zip(k0).zip(dq) {
            let dk = k - k0;
            if dk != 0.0 {
                d.iter_mut().zip(dqj).for_each(|(a, b)| *a += dk * b);
            }
        }
        self.advance(x, &d);
    }

    /// Tᵀ g over the free DOFs, for a full-length vector g.
    pub fn reduced(&self, g: &[Vec3]) -> Vec<f64> {
        let mut out = vec![0.0; self.num_free];
        self.reduce(g, &mut out);
        out
    }
}
