//! The boundary-treatment measurement: the heavy cantilever (overhang = 2 × bending length,
//! exact chord angle 41.4873°) on refined meshes with the phantom and the ghost clamp.
//!
//! Run: `cargo run --release --example heavy_cantilever`

use kshell::assembly::STANDARD_GRAVITY;
use kshell::material::{FabricMaterial, OrthotropicStvk};
use kshell::scene::CantileverBend;
use kshell::subdiv::BoundaryRule;
use std::time::Instant;

fn main() {
    let (a11, tau, rho) = (1.0e8, 2.0e-4, 0.1);
    let m = FabricMaterial {
        name: "elastica".into(),
        areal_density: rho,
        thickness: tau,
        law: OrthotropicStvk {
            a11,
            a22: a11,
            a12: 0.0,
            g12: 1.0e6,
        }
        .into(),
        bending: None,
    };
    let c = (a11 * tau.powi(3) / 12.0 / (rho * STANDARD_GRAVITY)).cbrt();
    println!(
        "bending length c = {:.4} mm, overhang 2c = {:.4} mm, exact chord angle 41.4873°",
        c * 1e3,
        2e3 * c
    );
    println!(
        "{:<8} {:<8} {:>12} {:>10} {:>9}",
        "mesh", "rule", "angle (°)", "error (°)", "seconds"
    );
    for rule in [BoundaryRule::Phantom, BoundaryRule::Ghost] {
        for ny in [8, 16, 32, 64] {
            let mut bend = CantileverBend::new(0.025, 2.0 * c, 90.0);
            bend.mesh = (4, ny);
            bend.boundary = rule;
            let t0 = Instant::now();
            match bend.run(&m) {
                Ok(r) => println!(
                    "{:<8} {:<8} {:>12.5} {:>10.5} {:>9.2}",
                    format!("4x{ny}"),
                    format!("{rule:?}").to_lowercase(),
                    r.drape_angle_deg,
                    r.drape_angle_deg - 41.4873,
                    t0.elapsed().as_secs_f64()
                ),
                Err(e) => println!("4x{ny} {rule:?}: failed: {e}"),
            }
        }
    }
}
