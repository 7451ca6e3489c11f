//! Inflated StVK balloon from a subdivided cube against the analytic membrane relation
//! p = τ (a11 + a12)(λ² − 1)/(R λ). Run: `cargo run --release --example balloon`
use kshell::scene::sphere::Balloon;
fn main() {
    let target = 1.2; // stretch at which the analytic pressure is applied
    println!(
        "{:>6} {:>8} {:>12} {:>14}",
        "levels", "points", "stretch", "rel. error (λ−1)"
    );
    for levels in 1..=4 {
        let b = Balloon {
            radius: 1.0,
            thickness: 1e-3,
            young: 1e6,
            poisson: 0.3,
            levels,
        };
        let p = b.analytic_pressure(target);
        let (lambda, n) = b.run(p).unwrap();
        println!(
            "{:>6} {:>8} {:>12.8} {:>14.3e}",
            levels,
            n,
            lambda,
            (lambda - 1.0) / (target - 1.0) - 1.0
        );
    }
}
