//! The lab commands on the triangle models (`--model springs|soft-constraints|stvk-ds|xpbd`):
//! the same output as the shell's, with the parameters from the material file's `[model]`
//! table or from the shell law's zero-strain moduli (said on stderr).

use crate::auto::auto_bend;
use crate::lab_args::{describe, unstable_error, SceneArgs};
use kshell::fit::tri::TriFit;
use kshell::scene::{TriCantilever, TriTensile};
use kshell::tri::file::{load_tri, TriSource};
use kshell::tri::TriKind;
use std::path::Path;

/// Reads the parameters, saying where they come from.
pub fn source(kind: TriKind, material: &Path, command: &str) -> Result<TriSource, String> {
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
    let strip = TriTensile {
        solver: args.solver(),
        ..TriTensile::new(w, l, angle)
    };
    let run = |mesh: (usize, usize)| {
        let mat = src.material(kind, w / mesh.0 as f64)?;
        let strip = TriTensile {
            mesh,
            ..strip.clone()
        };
        strip.run(&mat, dl).map_err(|e| e.to_string())
    };
    let points = match args.mesh {
        Some(m) => {
            kshell::limits::check_mesh(&format!("--mesh {}x{}", m.0, m.1), m.0, m.1)?;
            run(m)?
        }
        None => crate::auto::auto_ladder((w, l), kind.name(), dl.len(), args, run)?,
    };
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

/// `ks-fit fit DATA --model M` for a triangle model: writes the `[model]` table and a `[fit]`
/// table of how well it reproduces every test, prints the per-test table; a fitted test that
/// does not solve, or whose error exceeds `max_error` (fraction; see
/// `kshell::fit::tri::verdict`), fails the fit (`Ok(false)`: exit 3).
pub fn fit(
    file: &Path,
    output: Option<&Path>,
    kind: TriKind,
    quiet: bool,
    force: bool,
    allow_outside: bool,
    max_error: f64,
) -> Result<bool, String> {
    use kshell::fit::tri::{fit_tri, TriFitOptions};
    let (data, warnings) =
        kshell::dataset::load_dataset_with(file, allow_outside).map_err(|e| e.to_string())?;
    let out = output.map(|p| p.to_path_buf()).unwrap_or_else(|| {
        std::path::PathBuf::from(format!(
            "{}-{}-fit.toml",
            data.name
                .replace(|c: char| !c.is_alphanumeric() && c != '-', "_"),
            kind.name()
        ))
    });
    let mut guard = crate::guard::Guard::new(force);
    guard.input(file);
    guard.dataset(&data);
    guard.file("-o", &out)?;
    for w in &warnings {
        eprintln!("ks-fit: {w}");
    }
    let mut progress = |line: &str| {
        if !quiet {
            eprintln!("ks-fit: fit: {} {line}", kind.name());
        }
    };
    let r = fit_tri(&data, &TriFitOptions::new(kind), &mut progress)?;
    let text = tri_fit_toml(&data.name, file, kind, &r);
    kshell::io::write_atomic(&out, text)
        .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    print_tri_fit(kind, &r);
    println!("wrote {}", out.display());
    Ok(tri_verdict(&r, max_error))
}

/// The fitted `[model]` table and the `[fit]` table of how well it reproduces every test.
fn tri_fit_toml(name: &str, file: &Path, kind: TriKind, r: &TriFit) -> String {
    use std::fmt::Write;
    let mut text = kshell::tri::file::tri_toml(name, &r.material);
    let _ = writeln!(
        text,
        "\n[fit]    # how this material was obtained; read past by ks-fit"
    );
    let _ = writeln!(text, "model = {:?}", kind.name());
    let _ = writeln!(text, "dataset = {:?}", file.display().to_string());
    let _ = writeln!(text, "seconds = {:.1}", r.seconds);
    let _ = writeln!(text, "evaluations = {}", r.evaluations);
    let _ = writeln!(text, "undetermined = {:?}", r.undetermined);
    let _ = writeln!(text, "notes = {:?}", r.notes);
    // a test that did not solve with the fitted parameters is `nan` (TOML's spelling)
    let num = kshell::io::toml_float;
    for t in &r.tests {
        let _ = writeln!(text, "\n[[fit.test]]\nkind = {:?}", t.kind);
        if t.angle_deg.is_finite() {
            let _ = writeln!(text, "angle_deg = {:?}", t.angle_deg);
        }
        if let Some(c) = &t.curve {
            let key = if t.shape.is_some() { "obj" } else { "curve" };
            let _ = writeln!(text, "{key} = {c:?}");
        }
        if let Some(e) = t.avg_rel_error {
            let _ = writeln!(text, "avg_rel_error = {}", num(e, 6));
        }
        if let Some((s, e)) = t.scale {
            let _ = writeln!(
                text,
                "repeat_scale = {}\navg_rel_error_scaled = {}",
                num(s, 6),
                num(e, 6)
            );
        }
        if let Some((a, g)) = t.drape_angle_deg {
            let _ = writeln!(
                text,
                "drape_angle_deg = {}\ntarget_drape_deg = {g}",
                num(a, 4)
            );
        }
        if let Some(s) = &t.shape {
            text.push_str(&shape_keys(s));
        }
        let _ = writeln!(
            text,
            "mesh = \"{}x{}\"\nfitted = {}",
            t.mesh.0, t.mesh.1, t.fitted
        );
    }
    text
}

/// The fit's notes and its per-test table on stdout.
fn print_tri_fit(kind: TriKind, r: &TriFit) {
    for n in &r.notes {
        println!("note: {n}");
    }
    if !r.undetermined.is_empty() {
        println!(
            "identifiability: NOT DETERMINED by the data (kept at the start): {}",
            r.undetermined.join(", ")
        );
    }
    println!(
        "{:<11} {:>7} {:<16} {:>14} {:>16} {:>8} {:>6}",
        "kind", "angle", "curve", "avg_rel_error", "drape_angle_deg", "mesh", "fitted"
    );
    for t in r.tests.iter().filter(|t| t.shape.is_none()) {
        println!(
            "{:<11} {:>7.1} {:<16} {:>14} {:>16} {:>8} {:>6}",
            t.kind,
            t.angle_deg,
            t.curve.as_deref().unwrap_or("-"),
            t.avg_rel_error
                .map_or("-".into(), |e| format!("{:.2} %", 100.0 * e)),
            t.drape_angle_deg
                .map_or("-".into(), |(a, g)| format!("{a:.2} ({g:.1})")),
            format!("{}x{}", t.mesh.0, t.mesh.1),
            if t.fitted { "yes" } else { "no" }
        );
    }
    print_shapes(&r.tests);
    println!(
        "fitted {} in {:.1} s: {} objective evaluations",
        kind.name(),
        r.seconds,
        r.evaluations
    );
}

/// Whether every fitted test solves and is within `max_error`; prints FIT FAILED otherwise.
fn tri_verdict(r: &TriFit, max_error: f64) -> bool {
    // a fitted test the final parameters do not solve is a failed fit, never a quiet pass
    let unsolved: Vec<String> = r
        .tests
        .iter()
        .filter(|t| {
            t.fitted
                && (t.avg_rel_error.is_some_and(|e| !e.is_finite())
                    || t.drape_angle_deg.is_some_and(|(a, _)| !a.is_finite())
                    || t.shape.as_ref().is_some_and(|s| !s.error.is_finite()))
        })
        .map(|t| match &t.shape {
            Some(s) => format!("shape {}", s.scene),
            None => format!("{} {}°", t.kind, t.angle_deg),
        })
        .collect();
    if !unsolved.is_empty() {
        println!(
            "FIT FAILED: {} do not solve with the fitted parameters (written as nan; the law is likely degenerate there, see the [model] table)",
            unsolved.join(", ")
        );
        return false;
    }
    let over = kshell::fit::tri::verdict::over(&r.tests, max_error);
    if !over.is_empty() {
        println!(
            "FIT FAILED: fitted tests above --max-error {:.1} %: {} (repeats are judged after their own force scale)",
            100.0 * max_error,
            over.join(", ")
        );
        return false;
    }
    true
}

/// The keys of one shape's `[[fit.test]]` entry after `kind` and `obj` (`nan` where the scene
/// did not solve).
pub fn shape_keys(s: &kshell::fit::shape_target::ShapeFit) -> String {
    let num = kshell::io::toml_float;
    let mut text = format!(
        "scene = {:?}\ndescriptor = {:?}\nrms_distance_mm = {}\nshape_error = {}\n",
        s.scene,
        s.descriptor,
        num(s.rms_distance * 1e3, 4),
        num(s.error, 6)
    );
    if let Some((f, g)) = s.force {
        text.push_str(&format!(
            "force_n = {}\ntarget_force_n = {g:?}\n",
            num(f, 6)
        ));
    }
    text
}

fn print_shapes(tests: &[kshell::fit::tri::TestFit]) {
    let rows: Vec<_> = tests
        .iter()
        .filter_map(|t| t.shape.as_ref().map(|s| (s, t.mesh.0, t.fitted)))
        .collect();
    print_shape_rows(&rows);
}

/// The shapes' table: scene, descriptor, rms distance, the descriptor's relative error, force,
/// mesh (faces each way), fitted.
pub fn print_shape_rows(rows: &[(&kshell::fit::shape_target::ShapeFit, usize, bool)]) {
    if rows.is_empty() {
        return;
    }
    println!(
        "{:<34} {:<10} {:>15} {:>11} {:>20} {:>8} {:>6}",
        "shape",
        "descriptor",
        "rms_distance_mm",
        "shape_error",
        "force_n (measured)",
        "mesh",
        "fitted"
    );
    for &(s, mesh, fitted) in rows {
        println!(
            "{:<34} {:<10} {:>15.3} {:>11} {:>20} {:>8} {:>6}",
            s.scene,
            s.descriptor,
            s.rms_distance * 1e3,
            format!("{:.2} %", 100.0 * s.error),
            s.force
                .map_or("-".into(), |(f, g)| format!("{f:.4} ({g:.4})")),
            format!("{mesh}x{mesh}"),
            if fitted { "yes" } else { "no" }
        );
    }
}
