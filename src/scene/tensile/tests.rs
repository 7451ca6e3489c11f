//! Tests of the strip rig's failure reports and iteration budget.

use super::TensileStrip;
use crate::material::{Cutoffs, Eta, FabricMaterial, Orthotropic};
use crate::scene::SceneError;
use crate::solve::SolveError;

/// A point that runs out of its budget reports the iterations of every attempt it made
/// (the first try, the sub-steps, the whole budget), not those of the last attempt alone.
#[test]
fn a_failed_point_counts_every_attempt() {
    let law = Orthotropic {
        a11: 2e8,
        a22: 1e8,
        a12: 3e7,
        g12: 4e5,
        warp: Eta::linear(),
        weft: Eta::linear(),
        shear: Eta::linear(),
        cutoffs: Cutoffs::none(),
        coupling: None,
    };
    let m = FabricMaterial::paper("t", 0.1, 2e-4, law);
    let mut t = TensileStrip::new(0.05, 0.075, 45.0);
    t.mesh = (4, 6);
    t.solver.max_iterations = 3;
    match t.run(&m, &[0.01]) {
        Err(SceneError::Solve {
            source: SolveError::NotConverged { iterations, .. },
            ..
        }) => assert!(iterations > 3, "{iterations}"),
        other => panic!("expected a point out of budget, got {other:?}"),
    }
    // the budget a strip is given by default solves it
    t.solver.max_iterations = super::STRIP_ITERATIONS;
    assert!(t.run(&m, &[0.01]).is_ok());
}
