//! The fabric commands of `ks-fit`: `fit` on the shell (a dataset to a material) and `check`
//! (what a dataset holds and what `fit` will do with it).

use crate::guard::{Guard, Marker};
use kshell::dataset::FabricDataset;
use kshell::fit::shape_target::{ShapeFit, ShapeTarget};
use kshell::io::{cell, shown};
use std::path::{Path, PathBuf};

/// What marks a folder as an earlier `--report`: a summary.txt that a report wrote.
const REPORT: Marker = Marker {
    file: "summary.txt",
    ours: kshell::fit::report::is_report_summary,
};

/// Where `fit` writes the material: `-o`, or `<dataset name>-fit.toml` in the current folder.
fn fit_output(output: Option<&Path>, name: &str) -> PathBuf {
    output.map(|p| p.to_path_buf()).unwrap_or_else(|| {
        PathBuf::from(format!(
            "{}-fit.toml",
            name.replace(|c: char| !c.is_alphanumeric() && c != '-', "_")
        ))
    })
}

/// Where `--report` goes and whether it draws the scenes.
pub struct ReportArgs<'a> {
    pub dir: &'a Path,
    /// Also solve and draw the three showcase scenes on the fitted material (`--scenes`).
    pub scenes: Option<&'a crate::render::ImageArgs>,
}

/// Runs `ks-fit fit` on the shell; `Ok(false)` when the fit missed `--max-error` on a fitted
/// test (the material and report are written all the same).
pub fn cmd_fit(
    file: &Path,
    output: Option<&Path>,
    report: Option<ReportArgs>,
    opts: &kshell::fit::FitOptions,
    quiet: bool,
    allow_outside: bool,
    force: bool,
) -> Result<bool, String> {
    use kshell::fit::{fit, report as fit_report};
    let (data, warnings) =
        kshell::dataset::load_dataset_with(file, allow_outside).map_err(|e| e.to_string())?;
    let out = fit_output(output, &data.name);
    let mut guard = Guard::new(force);
    guard.input(file);
    guard.dataset(&data);
    guard.file("-o", &out)?;
    if let Some(r) = &report {
        guard.folder("--report", r.dir, &REPORT)?;
    }
    for w in &warnings {
        eprintln!("ks-fit: {w}");
    }
    if !data.shapes.is_empty() {
        eprintln!(
            "ks-fit: {}: {} [[shape]] entr{} predicted by the fitted shell (validation), except that a picture-frame or corner-pull shape fits G12 where no off-axis strip does; the triangle models (--model springs|soft-constraints|stvk-ds|xpbd) fit the components no lab test determines",
            file.display(),
            data.shapes.len(),
            if data.shapes.len() == 1 { "y is" } else { "ies are" }
        );
    }
    let mut progress = |line: &str| {
        if !quiet {
            eprintln!("ks-fit: fit: {line}");
        }
    };
    let result = fit(&data, opts, &mut progress).map_err(|e| format!("fit failed: {e}"))?;
    let mut text = fit_report::fit_toml(&result, &file.display().to_string());
    let shapes = predict_shapes(&data, &result.material, &mut progress)?;
    // the shapes the shell fit fitted G12 to (see kshell::fit::shapes)
    let fitted = |t: &ShapeTarget| result.shapes_fitted && t.fitted() && t.shears();
    for (t, s) in &shapes {
        text.push_str(&format!(
            "\n[[fit.test]]\nkind = \"shape\"\nobj = {:?}\n{}mesh = \"{m}x{m}\"\nfitted = {}\n",
            t.test.obj.display().to_string(),
            crate::models::shape_keys(s),
            fitted(t),
            m = t.mesh
        ));
    }
    kshell::io::write_atomic(&out, text)
        .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    if let Some(r) = &report {
        write_fit_report(&result, r, file, &mut progress)?;
    }
    print_fit(&result, quiet);
    let rows: Vec<_> = shapes.iter().map(|(t, e)| (e, t.mesh, fitted(t))).collect();
    crate::models::print_shape_rows(&rows);
    println!("wrote {}", out.display());
    Ok(kshell::fit::verdict::verdict(&result, result.max_error).passed())
}

/// Writes `--report`: the CSV and SVG of every test, the scenes where asked, index.html.
fn write_fit_report(
    result: &kshell::fit::FitResult,
    r: &ReportArgs,
    file: &Path,
    progress: &mut dyn FnMut(&str),
) -> Result<(), String> {
    use kshell::fit::report as fit_report;
    let dir = r.dir;
    progress("writing the report (CSV and SVG of every test, index.html)");
    let mut files = fit_report::write_report(result, dir)
        .map_err(|e| format!("cannot write the report in {}: {e}", dir.display()))?;
    let (figures, notes) = match r.scenes {
        Some(args) => crate::sheets::report_figures(&result.material, args, progress),
        None => (Vec::new(), Vec::new()),
    };
    for n in &notes {
        eprintln!("ks-fit: fit: {n}");
    }
    let page = kshell::fit::html::fit_html(result, &file.display().to_string(), &figures);
    let index = dir.join("index.html");
    kshell::io::write_atomic(&index, page)
        .map_err(|e| format!("cannot write {}: {e}", index.display()))?;
    files.push(index.display().to_string());
    progress(&format!(
        "report: {} files in {}",
        files.len(),
        dir.display()
    ));
    Ok(())
}

/// The fit's notes, uncertainties, per-test table and timing on stdout.
fn print_fit(result: &kshell::fit::FitResult, quiet: bool) {
    use kshell::fit::report as fit_report;
    // the degree choice is shown as progress; print it here only when progress is off
    let shown = if quiet { &result.degree_log[..] } else { &[] };
    for line in shown.iter().chain(&result.notes) {
        println!("{line}");
    }
    for e in &result.uncertainty {
        println!(
            "uncertainty: {} = {:.5e}{} ({}{})",
            e.name,
            e.value,
            e.std_error
                .map(|s| format!(
                    " ± {s:.2e} ({:.1} %)",
                    100.0 * s / e.value.abs().max(1e-300)
                ))
                .unwrap_or_default(),
            match (e.basis, e.determined) {
                ("none", true) => "as many tests as parameters: no spread to estimate from",
                ("none", false) => "not estimable",
                (b, _) => b,
            },
            if e.determined {
                ""
            } else {
                "; NOT DETERMINED by the data"
            }
        );
    }
    for line in &result.identifiability {
        println!("identifiability: {line}");
    }
    print!("{}", fit_report::table(result));
    let stages: Vec<String> = result
        .stats
        .stage_seconds
        .iter()
        .map(|(s, t)| format!("{s} {t:.1} s"))
        .collect();
    println!(
        "fitted on {} in {:.1} s: {} objective evaluations, {} Newton iterations over {} equilibria ({})",
        result
            .meshes
            .iter()
            .map(|m| format!("{}x{}", m.0, m.1))
            .collect::<Vec<_>>()
            .join(" → ")
            + if result.notes.iter().any(|n| n.starts_with("per-test mesh:")) {
                " (some tests refined on meshes of their own)"
            } else {
                ""
            },
        result.stats.seconds,
        result.stats.evaluations,
        result.stats.newton_iterations,
        result.stats.equilibria,
        stages.join(", ")
    );
}

/// Each `[[shape]]` simulated with the fitted shell on the shape's mesh: a prediction
/// (validation), or the fitted shape's errors at the fit.
fn predict_shapes(
    data: &kshell::dataset::FabricDataset,
    material: &kshell::material::FabricMaterial,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<(ShapeTarget, ShapeFit)>, String> {
    let mut out = Vec::new();
    for sh in &data.shapes {
        let t = ShapeTarget::new(sh, 1)?;
        progress(&format!(
            "predicting the shape {} ({})",
            sh.obj.display(),
            sh.scene.describe()
        ));
        let e = t.errors_shell(material);
        out.push((t, e));
    }
    Ok(out)
}

/// The flags of `ks-fit check`.
#[derive(clap::Args)]
pub struct CheckArgs {
    /// The dataset's fabric.toml.
    file: PathBuf,
    /// Read curve files outside the dataset folder (absolute paths, `..`, symbolic links).
    #[arg(long)]
    allow_outside: bool,
}

/// Runs `ks-fit check`.
pub fn cmd_check(a: &CheckArgs) -> Result<(), String> {
    let file = a.file.as_path();
    let (data, warnings) =
        kshell::dataset::load_dataset_with(file, a.allow_outside).map_err(|e| e.to_string())?;
    print_dataset(file, &data);
    println!(
        "{:<8} {:>7} {:>9} {:>16} {:>7} {:>14} {:>12}  use",
        "kind", "angle", "width mm", "gauge/overhang", "points", "max elong mm", "max force N"
    );
    let mut info = Vec::new();
    // what `ks-fit fit` will do with each curve by default (no solves: roles, toes, repeats)
    let d = kshell::fit::FitOptions::default();
    let prep = kshell::fit::preprocess::prepare(&data, d.paper_protocol, d.repeats, d.toe, d.nodes);
    print_tensile(&data, &prep, &mut info);
    print_bends(&data, &mut info);
    let k = &data.known;
    for (name, v) in [
        ("a11_pa", k.a11),
        ("a22_pa", k.a22),
        ("a12_pa", k.a12),
        ("g12_pa", k.g12),
        ("thickness_mm", k.thickness.map(|t| t * 1e3)),
        ("poisson_12", k.poisson_12),
    ] {
        if let Some(v) = v {
            info.push(format!("known: {name} = {} (held by the fit)", shown(v)));
        }
    }
    let fitted_at = |a: f64| {
        data.tensile
            .iter()
            .any(|t| (t.angle_deg - a).abs() < 1e-9 && t.role(false) == kshell::dataset::Role::Fit)
    };
    let refusal = match &prep {
        Err(e) => Some(e.to_string()),
        Ok(_) if !fitted_at(90.0) && !fitted_at(0.0) && k.a11.is_none() && k.a22.is_none() => Some(
            "no fitted warp (90°) or weft (0°) tensile test and no [known] a11_pa or a22_pa".into(),
        ),
        Ok(_) => None,
    };
    for l in &info {
        println!("{l}");
    }
    for w in &warnings {
        println!("{w}");
    }
    println!(
        "valid{}{}",
        match warnings.len() {
            0 => String::new(),
            1 => " (1 warning)".into(),
            n => format!(" ({n} warnings)"),
        },
        refusal
            .map(|why| format!("; ks-fit fit would refuse it: {why}"))
            .unwrap_or_default()
    );
    Ok(())
}

/// The dataset's header lines: name, density, thickness, counts, shapes.
fn print_dataset(file: &Path, data: &FabricDataset) {
    println!("dataset: {}", file.display());
    println!("name: {}", data.name);
    match data.areal_density {
        Some(rho) => println!("areal density: {} g/m²", shown(rho * 1e3)),
        None => println!("areal density: not given"),
    }
    println!(
        "thickness: {} mm (measured; the fit's initial guess)",
        shown(data.thickness * 1e3)
    );
    println!(
        "tests: {} tensile, {} bend",
        data.tensile.len(),
        data.bend.len()
    );
    for sh in &data.shapes {
        println!(
            "shape: {} from {} ({} vertices, {} triangles, thinnest spread {} mm), descriptor {}{}; fitted by the triangle models (--model); the shell fit fits G12 to a frame or corner-pull shape where no off-axis strip does, and predicts it otherwise",
            sh.scene.describe(),
            sh.obj.display(),
            sh.target.positions.len(),
            sh.target.triangles.len(),
            cell(sh.target.thinnest_spread() * 1e3, 3),
            sh.descriptor.name(),
            sh.force.map_or(String::new(), |f| format!(", force {f} N")),
        );
    }
}

/// The tensile tests' rows, and the notes on them in `info`.
fn print_tensile(
    data: &FabricDataset,
    prep: &Result<kshell::fit::preprocess::Prepared, kshell::fit::FitError>,
    info: &mut Vec<String>,
) {
    // each test's prepared curve, found by its index (one pass, not one search per test)
    let mut prepared = vec![None; data.tensile.len()];
    if let Ok(p) = prep {
        for c in &p.curves {
            if let Some(slot) = prepared.get_mut(c.test) {
                *slot = Some(c);
            }
        }
    }
    for (i, t) in data.tensile.iter().enumerate() {
        let max_force = t.force.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let max_elong = t.elongation.last().copied().unwrap_or(0.0);
        let role = match t.role(false) {
            kshell::dataset::Role::Fit => "fitted",
            kshell::dataset::Role::Validation => "validation",
        };
        if t.role.is_none() && !t.is_fitted() {
            info.push(format!(
                "info: tensile {}° ({}) is not at 0, 45 or 90°: fitted by default, a validation test (predicted, not fitted) with --protocol paper or role = \"validation\"",
                t.angle_deg,
                t.curve.display()
            ));
        }
        let toe = prepared[i]
            .filter(|c| c.toe != 0.0)
            .map(|c| {
                format!(
                    ", toe {:.3} mm {}",
                    c.toe * 1e3,
                    if c.toe_auto { "detected" } else { "given" }
                )
            })
            .unwrap_or_default();
        println!(
            "{:<8} {:>7} {:>9} {:>16} {:>7} {:>14} {:>12}  {role} ({}{toe})",
            "tensile",
            t.angle_deg,
            shown(t.width * 1e3),
            shown(t.gauge_length * 1e3),
            t.elongation.len(),
            cell(max_elong * 1e3, 4),
            cell(max_force, 4),
            t.curve.display()
        );
    }
}

/// The bend tests' rows, and the note on the bending model in `info`.
fn print_bends(data: &FabricDataset, info: &mut Vec<String>) {
    let own_bending = data.bend.iter().any(|b| b.angle_deg == 90.0)
        && data.bend.iter().any(|b| b.angle_deg == 0.0);
    if own_bending {
        info.push(
            "bending: warp and weft bends present: fit fits their flexural rigidities of their own (the default; --bending paper fits one thickness instead)".into(),
        );
    }
    for b in &data.bend {
        let role = if own_bending {
            "fitted: bending rigidity"
        } else if data.known.thickness.is_some() {
            "predicted: thickness known"
        } else {
            "fitted"
        };
        println!(
            "{:<8} {:>7} {:>9} {:>16} {:>7} {:>14} {:>12}  {role} (drape {}°)",
            "bend",
            b.angle_deg,
            shown(b.width * 1e3),
            shown(b.overhang * 1e3),
            "-",
            "-",
            "-",
            b.drape_angle_deg
        );
    }
}
