//! Accuracy against time across mesh levels for a tensile strip, a cantilever and a plate, in
//! one chart (paper_repro/convergence/accuracy_vs_time.svg) and one CSV. Errors are against each
//! scene's own Richardson estimate (strip, cantilever) or the published value (clamped plate).
//! Run: `cargo run --release --example convergence_chart`

use kshell::converge::{default_ladder, study, Study};
use kshell::material::parse_material;
use kshell::scene::plate::{SquarePlate, Support};
use kshell::scene::{CantileverBend, TensileStrip};
use plotters::prelude::*;
use std::fmt::Write;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mat = parse_material(
        include_str!("materials/cotton.toml"),
        "examples/materials/cotton.toml",
    )?;
    let tensile = study(
        &default_ladder(1.5, 5),
        |mesh| {
            let mut s = TensileStrip::new(0.05, 0.075, 90.0);
            s.mesh = mesh;
            let f = s.run(&mat, &[0.00375])?[0].force;
            Ok::<_, kshell::scene::SceneError>((f, 3 * (mesh.0 + 1) * (mesh.1 + 1)))
        },
        |l| eprintln!("tensile {}x{}: {:.3} s", l.mesh.0, l.mesh.1, l.seconds),
    )?;
    let bend = study(
        &default_ladder(2.4, 4),
        |mesh| {
            let mut b = CantileverBend::new(0.025, 0.06, 90.0);
            b.mesh = mesh;
            let a = b.run(&mat)?.drape_angle_deg;
            Ok::<_, kshell::scene::SceneError>((a, 3 * (mesh.0 + 3) * (mesh.1 + 3)))
        },
        |l| eprintln!("cantilever {}x{}: {:.3} s", l.mesh.0, l.mesh.1, l.seconds),
    )?;
    let mut plate = study(
        &[(4, 4), (8, 8), (16, 16), (32, 32), (64, 64)],
        |(n, _)| {
            let r = SquarePlate {
                side: 1.0,
                thickness: 0.01,
                young: 1e7,
                poisson: 0.3,
                n,
                support: Support::Clamped,
            }
            .run(1e-4)?;
            Ok::<_, kshell::scene::SceneError>((r.deflection_factor, r.dofs))
        },
        |l| eprintln!("plate {}x{}: {:.3} s", l.mesh.0, l.mesh.1, l.seconds),
    )?;
    // the plate's error is against the published value (Taylor & Govindjee 2004)
    for l in &mut plate.levels {
        l.est_error = Some((l.qoi / 0.001_265_319 - 1.0).abs());
    }
    let scenes: [(&str, &Study, RGBColor); 3] = [
        ("warp strip, force at 5 %", &tensile, BLUE),
        ("cantilever, drape angle", &bend, RED),
        ("clamped plate, centre deflection", &plate, GREEN),
    ];
    let mut csv = String::from("scene,mesh,dofs,seconds,qoi,est_error\n");
    for (name, s, _) in &scenes {
        for l in &s.levels {
            writeln!(
                csv,
                "\"{name}\",{}x{},{},{},{:e},{}",
                l.mesh.0,
                l.mesh.1,
                l.dofs,
                l.seconds,
                l.qoi,
                l.est_error.map(|e| format!("{e:e}")).unwrap_or_default()
            )?;
        }
    }
    std::fs::create_dir_all("paper_repro/convergence")?;
    std::fs::write("paper_repro/convergence/accuracy_vs_time.csv", &csv)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 520)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "accuracy against time across mesh levels",
                ("sans-serif", 18),
            )
            .margin(14)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d((1e-3f64..100.0).log_scale(), (1e-9f64..1.0).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("wall time (s)")
            .y_desc("relative error")
            .draw()?;
        for (name, s, color) in scenes {
            let pts: Vec<(f64, f64)> = s
                .levels
                .iter()
                .filter_map(|l| {
                    l.est_error
                        .filter(|e| *e > 0.0)
                        .map(|e| (l.seconds.max(1e-3), e))
                })
                .collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), color))?
                .label(name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE)
            .border_style(BLACK)
            .draw()?;
        root.present()?;
    }
    std::fs::write("paper_repro/convergence/accuracy_vs_time.svg", svg)?;
    print!("{csv}");
    Ok(())
}
