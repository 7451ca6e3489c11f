//! Resource limits, checked before anything is allocated: a mesh's face count (a shell solve
//! holds about [`BYTES_PER_FACE`] per face: stencils, Hessian, factor) and the sizes a command
//! line can ask for. The face limit is process-wide so that every scene the library builds,
//! the fitter's included, is checked in the same place; `ks-fit --max-faces` raises it.
//!
//! The sizes of inputs are bounded here too, so that a file cannot make a command run for
//! hours in silence: points per curve, terms per η law, tests per dataset, rows per batch.

use std::sync::atomic::{AtomicUsize, Ordering};

/// Peak memory per face of a tensile solve, bytes. Measured as peak resident set size of
/// `ks-fit tensile --steps 1 --mesh 64x96` (6144 faces, 319 MB) and `--mesh 32x48` (1536 faces,
/// 95 MB): 52–62 KB per face.
pub const BYTES_PER_FACE: usize = 60_000;

/// Faces one mesh may have unless raised: about 6 GB at [`BYTES_PER_FACE`], twenty times the
/// 64 × 96 mesh, far beyond what a strip or cantilever of the lab needs to 0.1 %.
pub const DEFAULT_MAX_FACES: usize = 100_000;

/// Points of one tensile curve that a fit takes as they are: a fit costs about 10 ms per
/// point at degree 2, so a longer curve is thinned to the points that follow it within 0.1 %
/// of its force range (`crate::dataset`), with a warning saying how many were kept.
pub const MAX_CURVE_POINTS: usize = 1_000;

/// Points (rows of distinct elongation) one curve file may hold: a testing machine sampling
/// at 1 kHz for a quarter of an hour; a longer curve is refused at the row that passes it.
pub const MAX_CURVE_ROWS: usize = 1_000_000;

/// Terms (`mu`, `alpha` pairs) of one η law in a material file: the fitter uses up to 8, and
/// every term is evaluated at every quadrature point of every solve.
pub const MAX_LAW_TERMS: usize = 64;

/// Tests (`[[tensile]]`, `[[bend]]` and `[[shape]]` tables together) of one dataset: a lab's
/// full programme is tens; each fitted test costs the fit a solve per evaluation.
pub const MAX_DATASET_TESTS: usize = 1_000;

/// Fabrics (rows) of one batch manifest.
pub const MAX_BATCH_ROWS: usize = 100_000;

static MAX_FACES: AtomicUsize = AtomicUsize::new(DEFAULT_MAX_FACES);

/// Sets the process-wide face limit (at least 1).
pub fn set_max_faces(n: usize) {
    MAX_FACES.store(n.max(1), Ordering::Relaxed);
}

/// The process-wide face limit.
pub fn max_faces() -> usize {
    MAX_FACES.load(Ordering::Relaxed)
}

/// Checks a mesh of `nx × ny` faces (the product saturates, never overflows) before it is built.
pub fn check_mesh(what: &str, nx: usize, ny: usize) -> Result<(), String> {
    check_faces(what, nx.saturating_mul(ny))
}

/// Checks a mesh of `faces` faces before it is built.
pub fn check_faces(what: &str, faces: usize) -> Result<(), String> {
    let max = max_faces();
    if faces > max {
        let gb = faces.saturating_mul(BYTES_PER_FACE) as f64 / 1e9;
        return Err(format!(
            "{what}: {faces} faces is more than the limit of {max} (a shell solve on it would need about {gb:.1} GB); pass --max-faces to allow a larger mesh"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_checked_without_overflow() {
        assert!(check_mesh("strip", 8, 12).is_ok());
        assert!(check_mesh("strip", usize::MAX, usize::MAX).is_err());
        let e = check_mesh("strip", 1000, 1000).unwrap_err();
        assert!(
            e.contains("--max-faces") && e.contains("1000000 faces"),
            "{e}"
        );
    }
}
