//! The stability atlas in reduced size: the full solver (backward-Euler fallback and refined
//! linear solves, every residual precision) must reach a stable equilibrium in every case.
//! The full-size atlas is `cargo run --release --example stability_atlas`.

use kshell::atlas::{atlas, to_markdown};

#[test]
fn the_full_solver_never_fails() {
    let rows = atlas(true);
    eprintln!("{}", to_markdown(&rows));
    for r in rows.iter().filter(|r| r.method.starts_with("full")) {
        assert!(
            r.converged,
            "{} with {}: {}",
            r.case.name(),
            r.method,
            r.note
        );
        assert!(
            r.stable,
            "{} with {}: converged to a saddle",
            r.case.name(),
            r.method
        );
    }
    // and the atlas can tell methods apart: plain Newton fails somewhere
    assert!(rows
        .iter()
        .any(|r| r.method == "plain Newton" && !r.converged));
}
