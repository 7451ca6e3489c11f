//! Graded cages against the 45° strip's slow convergence: the clamped corners of a bias strip
//! are singular, and on uniform cages its force converges at order 1.2–1.3
//! (`paper_repro/convergence/tensile_45.txt`). Crowding the control lines towards the jaws and
//! the free edges (`Grading`) puts the elements where the error is.
//!
//! Run: `cargo run --release --example graded_strip [ANGLE]` (default 45°): the example
//! cotton material, a 50 × 75 mm strip pulled 3.75 mm, force on a ladder of meshes for each
//! grading, with differences to the next mesh and the Richardson estimate from the last three.

use kshell::material::load_material;
use kshell::mesh::Grading;
use kshell::scene::TensileStrip;
use std::path::Path;
use std::time::Instant;

fn main() {
    let angle: f64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(45.0);
    let m = load_material(Path::new("examples/materials/cotton.toml")).expect("example material");
    let ladder = [(4, 6), (8, 12), (16, 24), (32, 48)];
    let gradings = [
        (0.0, 0.0),
        (0.5, 0.5),
        (0.8, 0.0),
        (0.8, 0.8),
        (0.9, 0.9),
        (0.95, 0.95),
    ];
    println!("angle {angle}°, 50 × 75 mm, elongation 3.75 mm, force in N");
    println!("grading (across, along)   mesh     force            seconds   diff_next");
    for (gx, gy) in gradings {
        let mut forces = Vec::new();
        let mut times = Vec::new();
        for &mesh in &ladder {
            let mut t = TensileStrip::new(0.05, 0.075, angle);
            t.mesh = mesh;
            t.grading = Grading {
                across: gx,
                along: gy,
            };
            let t0 = Instant::now();
            let r = t.run(&m, &[3.75e-3]).expect("solve");
            times.push(t0.elapsed().as_secs_f64());
            forces.push(r[0].force);
        }
        for (k, &mesh) in ladder.iter().enumerate() {
            let diff = forces
                .get(k + 1)
                .map_or("-".to_string(), |f| format!("{:+.3e}", f - forces[k]));
            println!(
                "({gx:.2}, {gy:.2})             {:>2}x{:<3}   {:.9}   {:7.3}   {diff}",
                mesh.0, mesh.1, forces[k], times[k]
            );
        }
        let n = forces.len();
        let (a, b, c) = (forces[n - 3], forces[n - 2], forces[n - 1]);
        let ratio = (b - a) / (c - b);
        let p = ratio.abs().log2();
        let extrapolated = c + (c - b) / (2f64.powf(p) - 1.0);
        println!(
            "   observed order {p:.2}, Richardson {extrapolated:.6}, finest's estimated error {:.2e}",
            ((c - extrapolated) / extrapolated).abs()
        );
    }
}
