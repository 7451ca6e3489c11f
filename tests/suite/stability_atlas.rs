//! The stability atlas in reduced size: every strategy with the backward-Euler fallback (and
//! every residual precision) must reach a stable equilibrium in every case, and the atlas must
//! tell methods apart. The full-size atlas is `cargo run --release --example stability_atlas`.

use kshell::atlas::{atlas, summary, to_markdown};

#[test]
fn no_strategy_with_the_fallback_fails() {
    let rows = atlas(true);
    eprintln!("{}\n{}", summary(&rows), to_markdown(&rows));
    // past any fabric (τ = 5 µm at 1.3e12 Pa) only the default strategy must cope: the trust
    // region stagnates at the first load factor there (measured, full size)
    for r in rows
        .iter()
        .filter(|r| r.case.beyond_fabrics() && r.method == "full-step")
    {
        assert!(r.converged && r.stable, "{}: {}", r.case.name(), r.note);
    }
    for r in rows
        .iter()
        .filter(|r| r.method != "plain Newton" && !r.case.beyond_fabrics())
    {
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
    // plain Newton fails somewhere, and says why in one line
    let failed: Vec<_> = rows
        .iter()
        .filter(|r| r.method == "plain Newton" && !r.converged)
        .collect();
    assert!(!failed.is_empty());
    for r in failed {
        assert!(
            ["indefinite", "line-search collapse", "stagnation", "domain"]
                .iter()
                .any(|k| r.note.contains(k)),
            "unexplained failure: {}",
            r.note
        );
        assert!(!r.note.contains('\n'));
    }
    // the chart draws every method
    let svg = kshell::atlas::to_svg(&rows).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("full-step"));
}
