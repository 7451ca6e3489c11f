//! The lab commands on the triangle models (`--model springs|soft-constraints|stvk-ds|xpbd`):
//! the same output as the shell's, with the parameters from the material file's `[model]`
//! table or from the shell law's zero-strain moduli (said on stderr).

use crate::scene::{auto_bend, describe, unstable_error, SceneArgs};
use kshell::tri::file::{load_tri, TriSource};
use kshell::tri::{TriCantilever, TriKind, TriTensile};
use std::path::Path;

/// Reads the parameters, saying where they come from.
fn source(kind: TriKind, material: &Path, command: &str) -> Result<TriSource, String> {
    let s = load_tri(material, kind).map_err(|e| e.to_string())?;
    if let TriSource::Shell(_) = s {
        eprintln!(
            "ks-fit: {command}: {} parameters converted from the shell law's zero-strain moduli (no [model] table in {})",
            kind.name(),
            material.display()
        );
    }
    Ok(s)
}

/// `ks-fit tensile --model M`: the strip's force at each elongation (m).
pub fn tensile(
    kind: TriKind,
    material: &Path,
    (w, l, angle): (f64, f64, f64),
    dl: &[f64],
    args: &SceneArgs,
) -> Result<(), String> {
    let src = source(kind, material, "tensile")?;
    let mut strip = TriTensile::new(w, l, angle);
    if let Some(m) = args.mesh {
        strip.mesh = m;
    }
    kshell::limits::check_mesh(
        &format!("--mesh {}x{}", strip.mesh.0, strip.mesh.1),
        strip.mesh.0,
        strip.mesh.1,
    )?;
    strip.solver = args.solver();
    let mat = src.material(kind, w / strip.mesh.0 as f64)?;
    let points = strip.run(&mat, dl).map_err(|e| e.to_string())?;
    println!("elongation_mm,force_n");
    let mut saddles = Vec::new();
    for p in &points {
        println!(
            "{},{}",
            kshell::io::num(p.elongation * 1e3),
            kshell::io::num(p.force)
        );
        if args.verbose {
            eprintln!(
                "elongation {:.4} mm: {}",
                p.elongation * 1e3,
                describe(&p.report)
            );
        }
        if !p.report.stable {
            saddles.push(kshell::io::num(p.elongation * 1e3));
        }
    }
    unstable_error(
        "the strip's equilibrium",
        &saddles,
        "at elongation(s) {} mm",
    )
}

/// `ks-fit bend --model M`: the drape angle, on the automatic mesh unless --mesh is given.
pub fn bend(
    kind: TriKind,
    material: &Path,
    (w, l, angle): (f64, f64, f64),
    args: &SceneArgs,
) -> Result<(), String> {
    let src = source(kind, material, "bend")?;
    let mut c = TriCantilever::new(w, l, angle);
    c.solver = args.solver();
    let run = |mesh: (usize, usize)| {
        kshell::limits::check_mesh(&format!("mesh {}x{}", mesh.0, mesh.1), mesh.0, mesh.1)?;
        let mat = src.material(kind, w / mesh.0 as f64)?;
        TriCantilever { mesh, ..c.clone() }
            .run(&mat)
            .map_err(|e| e.to_string())
    };
    let r = match args.mesh {
        Some(m) => run(m)?,
        None => auto_bend(c.mesh, args, run)?,
    };
    if args.verbose {
        eprintln!(
            "{} load steps, {} iterations in all; last solve: {}",
            r.load_steps,
            r.iterations,
            describe(&r.report)
        );
    }
    println!("overhang_mm,drape_angle_deg");
    println!("{},{}", l * 1e3, r.drape_angle_deg);
    let saddle = if r.report.stable {
        vec![]
    } else {
        vec![kshell::io::num(l * 1e3)]
    };
    unstable_error("the cantilever's equilibrium", &saddle, "at overhang {} mm")
}
