//! Sze, Liu & Lo (2004) cantilevers under mesh refinement: test 3.1 (end shear, P L²/EI = 4)
//! and test 3.2 (end moment, the full circle at M = 2π EI / L, bent in its plane).
//!
//! `cargo run --release --example sze_cantilevers`

use kshell::material::{FabricMaterial, OrthotropicStvk};
use kshell::scene::CantileverBend;
use std::f64::consts::TAU;
use std::time::Instant;

fn sze() -> FabricMaterial {
    FabricMaterial {
        name: "sze".into(),
        areal_density: 1.0,
        thickness: 0.1,
        law: OrthotropicStvk::isotropic(1.2e6, 0.0).into(),
        bending: None,
    }
}

fn main() {
    let m = sze();
    let ladder = [4, 8, 16, 32, 64];

    // test 3.1: exact inextensible elastica (RK4 shooting; Mattiasson's tables) to 4 decimals
    let (ue, we) = (3.2894, 6.6996);
    let mut rows = Vec::new();
    let mut times = Vec::new();
    for &ny in &ladder {
        let mut bend = CantileverBend::new(1.0, 10.0, 90.0);
        bend.mesh = (2, ny);
        bend.gravity = false;
        bend.tip_force = [0.0, 0.0, 4.0];
        let t = Instant::now();
        let r = bend.run(&m).expect("tip-force cantilever");
        times.push(t.elapsed().as_secs_f64());
        let (u, w) = (10.0 - r.tip[1], r.tip[2]);
        rows.push((
            ny,
            u,
            w,
            ((u - ue).powi(2) + (w - we).powi(2)).sqrt() / 10.0,
        ));
    }
    print_with_times(
        "Test 3.1, end shear P = 4 (exact -u = 3.2894, w = 6.6996; 4 decimals)",
        &rows,
        &times,
    );

    // test 3.2: the inextensible arc θ = 2π M / M_max, and the arc our shell model gives exactly
    // (see `rollup_model_tip`)
    let (l, ei) = (12.0, 1.2e6 * 0.1f64.powi(3) / 12.0);
    let m_max = TAU * ei / l;
    for frac in [0.5, 1.0] {
        let theta = frac * TAU;
        let (ui, wi) = (
            l * (1.0 - theta.sin() / theta),
            l * (1.0 - theta.cos()) / theta,
        );
        let (ue, we) = rollup_model_tip(frac * m_max / ei, l, 0.1);
        let mut rows = Vec::new();
        let mut times = Vec::new();
        for &ny in &ladder {
            let mut bend = CantileverBend::new(1.0, l, 90.0);
            bend.mesh = (2, ny);
            bend.gravity = false;
            bend.in_plane = true;
            bend.tip_moment = frac * m_max;
            let t = Instant::now();
            let r = bend.run(&m).expect("roll-up");
            times.push(t.elapsed().as_secs_f64());
            let (u, w) = (l - r.tip[1], r.tip[2]);
            rows.push((ny, u, w, ((u - ue).powi(2) + (w - we).powi(2)).sqrt() / l));
        }
        print_with_times(
            &format!(
                "Test 3.2, end moment M = {frac} M_max, in plane (inextensible arc: -u = {ui:.5}, \
                 w = {wi:.5}; this model's exact arc: -u = {ue:.5}, w = {we:.5}, errors against it)"
            ),
            &rows,
            &times,
        );
    }

    // is the planar arc a stable state of the full 3-D problem under the fixed-axis moment?
    println!("Test 3.2 on 2 × 32: is the in-plane equilibrium stable in 3-D?");
    println!("| M / M_max | stable out of plane |");
    println!("|---|---|");
    for frac in [0.5, 0.9, 0.92, 0.93, 0.94, 0.95, 1.0] {
        let mut bend = CantileverBend::new(1.0, l, 90.0);
        bend.mesh = (2, 32);
        bend.gravity = false;
        bend.in_plane = true;
        bend.tip_moment = frac * m_max;
        let r = bend.run(&m).expect("roll-up");
        println!("| {frac} | {} |", r.stable_out_of_plane.unwrap_or(false));
    }
}

/// Tip (−u, w) of a strip of length `l` and thickness `h` (ν = 0) bent by an end moment
/// M = `q0` EI, solved exactly for this Kirchhoff–Love model rather than for an inextensible beam.
///
/// With λ the stretch and q = θ' the rotation per rest length, the bending strain is
/// b₂₂ = x,ss · n = q λ, so the energy per rest length is EA/8 (λ² − 1)² + EI/2 q² λ² and the
/// potential L (W − M q). Stationarity: EI q λ² = M and λ² = 1 − 2 EI q² / EA = 1 − h² q² / 6.
/// The strip shortens and over-rotates by a relative (hq)²/6 (4.6e-4 at the full circle).
fn rollup_model_tip(q0: f64, l: f64, h: f64) -> (f64, f64) {
    let mut q = q0;
    let mut lambda2 = 1.0;
    for _ in 0..50 {
        lambda2 = 1.0 - h * h * q * q / 6.0;
        q = q0 / lambda2;
    }
    let r = lambda2.sqrt() / q;
    (l - r * (q * l).sin(), r * (1.0 - (q * l).cos()))
}

fn print_with_times(title: &str, rows: &[(usize, f64, f64, f64)], times: &[f64]) {
    println!("{title}");
    println!("| mesh | -u_tip | w_tip | tip error / L | order | seconds |");
    println!("|---|---|---|---|---|---|");
    for (i, &(ny, u, w, err)) in rows.iter().enumerate() {
        let order = if i > 0 {
            format!("{:.2}", (rows[i - 1].3 / err).log2())
        } else {
            String::new()
        };
        println!(
            "| 2 × {ny} | {u:.5} | {w:.5} | {err:.2e} | {order} | {:.2} |",
            times[i]
        );
    }
    println!();
}
