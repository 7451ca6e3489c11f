//! A failed solve written out so that it can be reproduced with any other sparse solver: the
//! reduced tangent K = Tᵀ H T over the free DOFs (both triangles, Matrix Market coordinate
//! `real general`, through nalgebra-sparse's writer), the reduced residual g = Tᵀ ∇E as an
//! n × 1 Matrix Market matrix, and the positions, all at the solve's last iterate.
//!
//! Every Newton-family solve dumps itself on failure when the environment variable
//! `KSHELL_DUMP_FAILED` names a folder (e.g. `KSHELL_DUMP_FAILED=dumps cargo run --release
//! --example stability_atlas`): one sub-folder `failed-<pid>-<k>` per failure.

use super::{FreeSystem, SolveError};
use crate::model::{BlockMatrix, ClothModel, Want};
use crate::Vec3;
use nalgebra_sparse::io::save_to_matrix_market_str;
use nalgebra_sparse::CooMatrix;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Numbers the dumps of this process.
static DUMPS: AtomicUsize = AtomicUsize::new(0);

/// The reduced tangent and residual at `x`, as (K over both triangles, g).
pub fn reduced_system(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &[Vec3],
) -> Result<(CooMatrix<f64>, Vec<f64>), String> {
    let mut grad = vec![[0.0; 3]; x.len()];
    let mut hess = BlockMatrix::zeros(model.pattern().clone());
    model
        .assemble(x, Want::Hessian, Some(&mut grad), Some(&mut hess))
        .map_err(|e| e.to_string())?;
    let mut values = Vec::new();
    system.values(&hess, &mut values);
    let n = system.num_free;
    let lower = system.sym_lower(&values);
    let mut k = CooMatrix::new(n, n);
    for j in 0..n {
        for p in lower.col_ptr[j]..lower.col_ptr[j + 1] {
            let i = lower.row_idx[p];
            k.push(i, j, values[p]);
            if i != j {
                k.push(j, i, values[p]);
            }
        }
    }
    let g = system.reduced(&grad);
    Ok((k, g))
}

/// Writes K.mtx, g.mtx, x.csv and what.txt (the error, sizes and norms) into a new folder under
/// `dir`; returns the folder.
pub fn dump_system(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &[Vec3],
    what: &str,
    dir: &Path,
) -> Result<PathBuf, String> {
    let (k, g) = reduced_system(model, system, x)?;
    let n = g.len();
    let folder = dir.join(format!(
        "failed-{}-{}",
        std::process::id(),
        DUMPS.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&folder).map_err(|e| format!("{}: {e}", folder.display()))?;
    let mut gm = CooMatrix::new(n, 1);
    for (i, v) in g.iter().enumerate() {
        gm.push(i, 0, *v);
    }
    let mut xs = String::from("node,x_m,y_m,z_m\n");
    for (i, p) in x.iter().enumerate() {
        xs += &format!("{i},{:e},{:e},{:e}\n", p[0], p[1], p[2]);
    }
    let gnorm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
    let info = format!(
        "{what}\nnodes {}\nfree DOFs {n}\nnonzeros of K (both triangles) {}\n|g| {gnorm:e}\n\
         K.mtx: the reduced tangent (Matrix Market coordinate real general)\n\
         g.mtx: the reduced gradient of the total energy, {n} x 1 (a Newton step solves K d = -g)\n\
         x.csv: node positions, m\n",
        x.len(),
        k.nnz()
    );
    for (name, text) in [
        ("K.mtx", save_to_matrix_market_str(&k)),
        ("g.mtx", save_to_matrix_market_str(&gm)),
        ("x.csv", xs),
        ("what.txt", info),
    ] {
        let p = folder.join(name);
        crate::io::write_atomic(&p, text).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    Ok(folder)
}

/// The hook every solve calls on failure: dumps when `KSHELL_DUMP_FAILED` is set, saying where
/// on stderr (a dump that fails is said too; it never changes the solve's own error).
pub(super) fn on_failure(model: &dyn ClothModel, system: &FreeSystem, x: &[Vec3], e: &SolveError) {
    let Some(dir) = std::env::var_os("KSHELL_DUMP_FAILED") else {
        return;
    };
    match dump_system(
        model,
        system,
        x,
        &format!("solve failed: {e}"),
        Path::new(&dir),
    ) {
        Ok(f) => eprintln!("kshell: failed solve written to {}", f.display()),
        Err(m) => eprintln!("kshell: could not write the failed solve: {m}"),
    }
}
