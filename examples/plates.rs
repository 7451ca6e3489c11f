//! Square-plate convergence: centre deflection factor w_c D / (q a⁴) under refinement.
//! References: simply supported 0.0040623527 (Navier series), clamped 0.001265319 (Taylor &
//! Govindjee 2004). Run: `cargo run --release --example plates`
use kshell::scene::plate::{SquarePlate, Support};
fn main() {
    // Navier series summed to m, n < 2001 (the usual quotation is 0.00406235)
    for (support, exact) in [
        (Support::Simple, 0.004_062_352_7),
        (Support::Clamped, 0.001_265_319),
    ] {
        println!("{support:?} (reference {exact})");
        println!(
            "{:>4} {:>8} {:>14} {:>12}",
            "n", "dofs", "factor", "rel. error"
        );
        for n in [4, 8, 16, 32, 64] {
            let plate = SquarePlate {
                side: 1.0,
                thickness: 0.01,
                young: 1.0e7,
                poisson: 0.3,
                n,
                support,
            };
            let r = plate.run(1e-4).unwrap();
            println!(
                "{:>4} {:>8} {:>14.9} {:>12.3e}",
                n,
                r.dofs,
                r.deflection_factor,
                r.deflection_factor / exact - 1.0
            );
        }
    }
}
