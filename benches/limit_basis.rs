//! Limit-basis speed: `LimitBasis` set-up time and stencils evaluated per second, for a 32 × 48
//! strip (all regular and boundary faces) and for meshes with extraordinary vertices.
//!
//! Run: `cargo bench --bench limit_basis`. Prints the median, min and max over repeated runs
//! (the machine is shared: quote medians).

use kshell::mesh::{rectangular_grid, shapes, PolyMesh};
use kshell::subdiv::{BasisOptions, BoundaryRule, LimitBasis, LimitSurface};
use std::hint::black_box;
use std::time::Instant;

/// Median, min and max seconds of `runs` calls of `f`.
fn time<F: FnMut()>(runs: usize, mut f: F) -> (f64, f64, f64) {
    f(); // warm-up
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    (t[runs / 2], t[0], t[runs - 1])
}

fn main() {
    let cases: Vec<(&str, PolyMesh, usize)> = vec![
        ("grid 32x48", rectangular_grid(0.05, 0.075, 32, 48), 15),
        ("cube", shapes::cube(), 51),
        ("star5 (3 rings)", shapes::star(5, 3), 31),
        ("L-shape 3", shapes::l_shape(3), 31),
    ];
    println!(
        "{:<18} {:>6} {:>8} {:>10} {:>22} {:>14}",
        "mesh", "rule", "points", "setup ms", "(min..max)", "stencils/s"
    );
    for (name, mesh, runs) in &cases {
        for rule in [BoundaryRule::Phantom, BoundaryRule::Ghost] {
            let opts = BasisOptions {
                boundary: rule,
                gauss_points: 4,
            };
            let mut n = 0;
            let (med, min, max) = time(*runs, || {
                let b = LimitBasis::new(black_box(mesh), opts).unwrap();
                n = b.num_points();
                black_box(b);
            });
            println!(
                "{:<18} {:>6} {:>8} {:>10.3} {:>22} {:>14.0}",
                name,
                format!("{rule:?}").to_lowercase(),
                n,
                med * 1e3,
                format!("({:.3}..{:.3})", min * 1e3, max * 1e3),
                n as f64 / med
            );
        }
    }
    // single-point evaluation on an extraordinary face, near the vertex (deep refinement)
    let s = LimitSurface::new(&shapes::star(5, 3), BoundaryRule::Phantom).unwrap();
    for (u, v) in [(0.4, 0.6), (0.07, 0.07), (1e-3, 1e-3)] {
        let (med, _, _) = time(201, || {
            black_box(s.stencil(0, black_box(u), black_box(v)).unwrap());
        });
        println!(
            "one stencil on a valence-5 face at ({u}, {v}): {:.1} µs (median)",
            med * 1e6
        );
    }
}
