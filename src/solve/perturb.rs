//! Deterministic pseudo-random numbers and the small nudges that move a state off a symmetric
//! saddle, scaled by the body's size (the saddle escapes of the solvers of Clyde et al. 2017
//! §6).

use super::FreeSystem;
use crate::Vec3;

/// The diagonal of the bounding box of `x`.
pub(super) fn size(x: &[Vec3]) -> f64 {
    let (lo, hi) = x
        .iter()
        .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
            (
                std::array::from_fn(|c| lo[c].min(p[c])),
                std::array::from_fn(|c| hi[c].max(p[c])),
            )
        });
    (0..3).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt()
}

/// A pseudo-random number in [−1, 1) (xorshift; deterministic from `seed`).
pub(super) fn uniform(seed: &mut u64) -> f64 {
    *seed ^= *seed << 13;
    *seed ^= *seed >> 7;
    *seed ^= *seed << 17;
    ((*seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0
}

/// Moves every free DOF by a pseudo-random amount of 1e-6 of the body's size (deterministic).
pub(super) fn perturb(system: &FreeSystem, x: &mut [Vec3], seed: &mut u64) {
    let size = size(x);
    let d: Vec<f64> = (0..system.num_free)
        .map(|_| uniform(seed) * 1e-6 * size)
        .collect();
    system.step(x, &d, 1.0);
}
