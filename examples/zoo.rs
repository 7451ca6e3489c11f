//! The fabric zoo (`paper_repro/zoo/`): writes a seeded zoo of plausible fabrics as datasets
//! and a batch manifest, and summarises a `ks-fit batch` run of it against the truth.
//!
//! ```text
//! cargo run --release --example zoo -- generate DIR [--count N] [--seed S] [--models-every K] [--clean]
//! ks-fit batch DIR/manifest.csv --out DIR/fits
//! cargo run --release --example zoo -- summary DIR > DIR/summary.md
//! ```
//! Generation is resumable: a fabric whose `fabric.toml` exists is not built again. `--clean`
//! writes only the law fabrics, without the lab's artefacts (noise, scatter, misalignment,
//! slack, preload, kN), one curve per angle: whether the fit recovers the truth.

use kshell::fit::poisson::A12_DEPENDENCE_TOL;
use kshell::material::{load_material, FabricMaterial};
use kshell::synth::zoo::{build, draw, Export, Source, ZooFabric, STRIP_TOL};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[path = "zoo/best_law.rs"]
mod best_law;
#[path = "zoo/failures.rs"]
mod failures;

/// The triangle models a zoo fabric is also fitted with, every `--models-every` fabrics.
const TRI_MODELS: [&str; 4] = ["springs", "soft-constraints", "stvk-ds", "xpbd"];

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let flag = |name: &str, default: u64| -> u64 {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .map(|v| {
                v.parse()
                    .unwrap_or_else(|_| fail(&format!("{name}: not a number: {v}")))
            })
            .unwrap_or(default)
    };
    let dir = args.get(1).map(PathBuf::from);
    let result = match (args.first().map(String::as_str), dir) {
        (Some("generate"), Some(dir)) => generate(
            &dir,
            flag("--count", 20) as usize,
            flag("--seed", 58),
            flag("--models-every", 10) as usize,
            args.iter().any(|a| a == "--clean"),
        ),
        (Some("summary"), Some(dir)) => summary(&dir).map(|s| print!("{s}")),
        _ => Err(
            "usage: zoo generate DIR [--count N] [--seed S] [--models-every K] [--clean] | zoo summary DIR"
                .into(),
        ),
    };
    if let Err(e) = result {
        fail(&e);
    }
}

fn fail(msg: &str) -> ! {
    eprintln!("zoo: error: {msg}");
    std::process::exit(2)
}

/// One line of `zoo.csv`: what the fabric is and how its lab tested it.
fn describe(f: &ZooFabric) -> String {
    let p = &f.protocol;
    let families = match &f.source {
        Source::Law(m) => format!(
            "law degrees {}/{}/{} by {}",
            m.law.warp.degree(),
            m.law.weft.degree(),
            m.law.shear.degree(),
            f.lab.map_or("shell", |k| k.name())
        ),
        Source::Analytic {
            warp, weft, bias, ..
        } => format!("{}/{}/{}", warp.name(), weft.name(), bias.name()),
    };
    let export = match p.export {
        Export::Newtons => "N",
        Export::KiloNewtonsHeader => "kN header",
        Export::KiloNewtonsScaled => "kN force_scale",
    };
    format!(
        "{},{},{},{},{},{:.3},{},{},{:.3},{:.3},{},{},{}",
        f.name,
        families,
        p.angles.len(),
        p.repeats,
        p.points,
        p.max_strain,
        p.strip.0 * 1e3,
        p.strip.1 * 1e3,
        p.slack * 1e3,
        p.preload * 1e3,
        export,
        p.bends,
        p.bias_only
    )
}

const ZOO_HEADER: &str = "fabric,source,angles,repeats,points,max_strain,width_mm,gauge_mm,slack_mm,preload_mm,export,bends,bias_only,built";

fn generate(dir: &Path, count: usize, seed: u64, every: usize, clean: bool) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut fabrics: Vec<ZooFabric> = (0..count).map(|i| draw(seed, i)).collect();
    if clean {
        fabrics.retain(|f| matches!(f.source, Source::Law(_)));
        for f in &mut fabrics {
            f.protocol = f.protocol.clean();
        }
    }
    let built: Vec<String> = fabrics
        .par_iter()
        .map(|f| match write_fabric(dir, f) {
            Ok(()) => "yes".to_string(),
            Err(e) => {
                eprintln!("zoo: {}: not built: {e}", f.name);
                format!("\"no: {}\"", e.replace('"', "'"))
            }
        })
        .collect();
    let what = if clean {
        "law fabrics without artefacts"
    } else {
        "fabrics"
    };
    let mut index = format!("# zoo of {count} draws, {what}, seed {seed}\n{ZOO_HEADER}\n");
    // the shell fits first, then the triangle models' (slower, on fewer fabrics)
    let mut manifest = String::from("fabric,dataset,model\n");
    let mut tri_rows = String::new();
    for (i, (f, b)) in fabrics.iter().zip(&built).enumerate() {
        let _ = writeln!(index, "{},{b}", describe(f));
        if b != "yes" {
            continue;
        }
        let _ = writeln!(manifest, "{0},{0}/fabric.toml,", f.name);
        if every > 0 && i % every < 2 {
            for m in TRI_MODELS {
                let _ = writeln!(tri_rows, "{0}-{m},{0}/fabric.toml,{m}", f.name);
            }
        }
    }
    manifest += &tri_rows;
    write(&dir.join("zoo.csv"), &index)?;
    write(&dir.join("manifest.csv"), &manifest)
}

fn write(path: &Path, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
}

fn write_fabric(dir: &Path, f: &ZooFabric) -> Result<(), String> {
    let folder = dir.join(&f.name);
    if folder.join("fabric.toml").exists() {
        return Ok(());
    }
    let t0 = std::time::Instant::now();
    let z = build(f, &mut |_| {}).map_err(|e| e.to_string())?;
    let tmp = dir.join(format!(".{}.tmp", f.name));
    let _ = std::fs::remove_dir_all(&tmp);
    let comment = format!("fabric-zoo dataset {} ({})", f.name, describe(f));
    z.write(&tmp, &comment)
        .map_err(|e| format!("{}: {e}", tmp.display()))?;
    std::fs::rename(&tmp, &folder).map_err(|e| e.to_string())?;
    eprintln!(
        "zoo: {} built in {:.1} s",
        f.name,
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}

/// One fitted row of the batch summary.
struct Fit {
    fabric: String,
    model: String,
    zoo_name: String,
    status: String,
    passed: bool,
    wall: f64,
    error: String,
    verdict: String,
    has_material: bool,
}

/// Each manifest row's (fabric, zoo fabric, model).
fn read_manifest(dir: &Path) -> Result<Vec<(String, String, String)>, String> {
    let path = dir.join("manifest.csv");
    let mut rd = csv::Reader::from_path(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut rows = Vec::new();
    for row in rd.records() {
        let row = row.map_err(|e| e.to_string())?;
        let get = |c: usize| row.get(c).unwrap_or("").to_string();
        let zoo = get(1).trim_end_matches("/fabric.toml").to_string();
        let model = if get(2).is_empty() {
            "kl".into()
        } else {
            get(2)
        };
        rows.push((get(0), zoo, model));
    }
    Ok(rows)
}

fn read_fits(dir: &Path) -> Result<Vec<Fit>, String> {
    let manifest = read_manifest(dir)?;
    let path = dir.join("fits/summary.csv");
    let mut rd = csv::Reader::from_path(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let head = rd.headers().map_err(|e| e.to_string())?.clone();
    let col = |name: &str| head.iter().position(|h| h == name).unwrap_or(usize::MAX);
    let (c_fab, c_st, c_pass, c_wall, c_err, c_verdict) = (
        col("fabric"),
        col("status"),
        col("passed"),
        col("wall_seconds"),
        col("error"),
        col("verdict"),
    );
    let mut fits = Vec::new();
    for row in rd.records() {
        let row = row.map_err(|e| e.to_string())?;
        let get = |c: usize| row.get(c).unwrap_or("").to_string();
        let fabric = get(c_fab);
        let Some((_, zoo_name, model)) = manifest.iter().find(|r| r.0 == fabric).cloned() else {
            continue;
        };
        fits.push(Fit {
            has_material: dir
                .join("fits")
                .join(&fabric)
                .join("material.toml")
                .exists(),
            model: model.to_string(),
            zoo_name,
            status: get(c_st),
            passed: get(c_pass) == "true",
            wall: get(c_wall).parse().unwrap_or(f64::NAN),
            error: get(c_err),
            verdict: get(c_verdict),
            fabric,
        });
    }
    Ok(fits)
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// What strips and bends determine (the fit's identifiability lines): the small-strain
/// uniaxial stiffnesses per width E1·τ = (a11 − a12²/a22)·τ and E2·τ, the off-axis compliance
/// (1/G12 − 2ν12/E1)/τ with ν12 = a12/a22, and the warp and weft rigidities.
fn quantities(m: &FabricMaterial) -> [f64; 5] {
    let t = m.thickness;
    let l = &m.law;
    let e1 = l.a11 - l.a12 * l.a12 / l.a22;
    let e2 = l.a22 - l.a12 * l.a12 / l.a11;
    let compliance = (1.0 / l.g12 - 2.0 * (l.a12 / l.a22) / e1) / t;
    let (bw, bf) = match m.bending {
        Some(b) => (b.warp, b.weft),
        None => (l.a11 * t.powi(3) / 12.0, l.a22 * t.powi(3) / 12.0),
    };
    [e1 * t, e2 * t, compliance, bw, bf]
}

const QUANTITIES: [&str; 5] = [
    "E1·τ (small strain)",
    "E2·τ (small strain)",
    "off-axis compliance (1/G − 2ν12/E1)/τ",
    "B warp",
    "B weft",
];

fn summary(dir: &Path) -> Result<String, String> {
    let fits = read_fits(dir)?;
    let mut s = String::from("# Fabric zoo: summary\n\n");
    let _ = writeln!(
        s,
        "Made by `cargo run --release --example zoo -- summary {}` from `fits/summary.csv`.\n",
        dir.display()
    );
    let pending = fits.iter().filter(|f| f.status == "pending").count();
    let _ = writeln!(
        s,
        "{} fits run, {pending} not yet run (left out below).\n",
        fits.len() - pending
    );
    s += "| model | fits | ended with a material | passed (within the asked error) | wall median s | wall 90th pct s |\n|---|---|---|---|---|---|\n";
    let run: Vec<&Fit> = fits.iter().filter(|f| f.status != "pending").collect();
    for model in std::iter::once("kl").chain(TRI_MODELS) {
        let rows: Vec<&Fit> = run.iter().copied().filter(|f| f.model == model).collect();
        if rows.is_empty() {
            continue;
        }
        let n = rows.len() as f64;
        let ended = rows.iter().filter(|f| f.has_material).count() as f64;
        let passed = rows.iter().filter(|f| f.passed).count() as f64;
        let mut walls: Vec<f64> = rows
            .iter()
            .map(|f| f.wall)
            .filter(|w| w.is_finite())
            .collect();
        let _ = writeln!(
            s,
            "| {model} | {} | {:.0} % | {:.0} % | {:.1} | {:.1} |",
            rows.len(),
            100.0 * ended / n,
            100.0 * passed / n,
            percentile(&mut walls, 0.5),
            percentile(&mut walls, 0.9)
        );
    }
    s += &truth_table(dir, &fits);
    let analytic: Vec<(String, PathBuf)> = fits
        .iter()
        .filter(|f| f.model == "kl" && f.has_material && f.zoo_name.ends_with("-analytic"))
        .map(|f| {
            let material = dir.join("fits").join(&f.fabric).join("material.toml");
            (f.fabric.clone(), material)
        })
        .collect();
    if !analytic.is_empty() {
        s += &best_law::table(dir, &analytic);
    }
    let failed: Vec<(String, String, String)> = run
        .iter()
        .filter(|f| f.has_material && !f.passed)
        .map(|f| (f.fabric.clone(), f.model.clone(), f.verdict.clone()))
        .collect();
    s += &failures::section(&dir.join("fits"), &failed);
    s += &unbuilt(dir);
    s += "\n## Fits that ended without a material\n\n";
    for f in run.iter().filter(|f| !f.has_material) {
        let _ = writeln!(s, "* {} ({}, {}): {}", f.fabric, f.model, f.status, f.error);
    }
    Ok(s)
}

/// The zoo's fabrics the virtual lab could not measure (`zoo.csv`'s `built` column).
fn unbuilt(dir: &Path) -> String {
    let text = std::fs::read_to_string(dir.join("zoo.csv")).unwrap_or_default();
    let rows: Vec<&str> = text.lines().filter(|l| l.contains(",\"no: ")).collect();
    let mut s = format!(
        "\n## Fabrics not built\n\n{} of the drawn fabrics could not be measured by the virtual lab (so are not fitted):\n\n",
        rows.len()
    );
    for r in rows {
        let name = r.split(',').next().unwrap_or("");
        let why = r
            .split_once(",\"no: ")
            .map_or("", |w| w.1.trim_end_matches('"'));
        let _ = writeln!(s, "* {name}: {why}");
    }
    s
}

/// The shell fits of law fabrics against their truth: |fitted/true − 1| per quantity.
fn truth_table(dir: &Path, fits: &[Fit]) -> String {
    let mut errors: Vec<Vec<(f64, String)>> = vec![Vec::new(); QUANTITIES.len()];
    let mut undetermined: Vec<Vec<String>> = vec![Vec::new(); QUANTITIES.len()];
    let mut with_a12: Vec<Vec<String>> = vec![Vec::new(); QUANTITIES.len()];
    let mut unconverged = String::new();
    let mut unloadable = String::new();
    for f in fits.iter().filter(|f| f.model == "kl" && f.has_material) {
        // data off the law by more than the lab's tolerance have no truth to recover
        if let Some(why) = lab_unconverged(&dir.join(&f.zoo_name)) {
            let _ = writeln!(unconverged, "* {}: {why}", f.fabric);
            continue;
        }
        let truth = dir.join(&f.zoo_name).join("truth.toml");
        if !truth.exists() {
            continue;
        }
        let fitted = dir.join("fits").join(&f.fabric).join("material.toml");
        let (t, m) = match (load_material(&truth), load_material(&fitted)) {
            (Ok(t), Ok(m)) => (t, m),
            (Err(e), _) | (_, Err(e)) => {
                let _ = writeln!(unloadable, "* {}: {e}", f.fabric);
                continue;
            }
        };
        // what the data can determine: no rigidities without bends, no yarns where they are known
        let dataset = std::fs::read_to_string(dir.join(&f.zoo_name).join("fabric.toml"));
        let dataset = dataset.unwrap_or_default();
        let bends = dataset.contains("[[bend]]");
        let known = dataset.contains("[known]");
        // and what the fit's own standard errors call determined ([fit.uncertainty])
        let said = fit_determined(&dir.join("fits").join(&f.fabric).join("material.toml"));
        for (k, (a, b)) in quantities(&m).iter().zip(quantities(&t)).enumerate() {
            let (determined, param) = match k {
                0 => (!known, "a11_pa"),
                1 => (!known, "a22_pa"),
                2 => (true, "g12_pa"),
                _ => (bends, ""),
            };
            if !determined {
                continue;
            }
            let error = (a / b - 1.0).abs();
            match said(param) {
                Said::Determined => errors[k].push((error, f.fabric.clone())),
                Said::NotDetermined => undetermined[k].push(f.fabric.clone()),
                Said::WithA12 => {
                    with_a12[k].push(format!("{} ({:.1} %)", f.fabric, 100.0 * error));
                }
            }
        }
    }
    let mut s = String::from("\n## Law fabrics: fitted against the truth (shell)\n\n");
    s += "|fitted/true − 1| of what strips and bends determine, over every ended fit: the rigidities where the dataset has bends, the yarns where `[known]` does not give them.\n\n";
    s += "| quantity | fits | within 2 % | median | 90th pct | worst (fabric) |\n|---|---|---|---|---|---|\n";
    for (name, e) in QUANTITIES.iter().zip(&mut errors) {
        if e.is_empty() {
            continue;
        }
        let within = e.iter().filter(|x| x.0 <= 0.02).count();
        let worst = e
            .iter()
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .cloned()
            .unwrap_or_default();
        let mut v: Vec<f64> = e.iter().map(|x| x.0).collect();
        let _ = writeln!(
            s,
            "| {name} | {} | {:.0} % | {:.2} % | {:.2} % | {:.1} % ({}) |",
            e.len(),
            100.0 * within as f64 / e.len() as f64,
            100.0 * percentile(&mut v, 0.5),
            100.0 * percentile(&mut v, 0.9),
            100.0 * worst.0,
            worst.1
        );
    }
    for (name, fabrics) in QUANTITIES.iter().zip(&undetermined) {
        if !fabrics.is_empty() {
            let _ = writeln!(
                s,
                "\n{name}: left out where the fit reports it NOT DETERMINED by the data: {}",
                fabrics.join(", ")
            );
        }
    }
    for (name, fabrics) in QUANTITIES.iter().zip(&with_a12) {
        if !fabrics.is_empty() {
            let _ = writeln!(
                s,
                "\n{name}: left out where the fit reports it determined only with the assumed a12 (its strips' small-strain force moves by more than {:.0} % with a12 = 0; |fitted/true − 1| in brackets): {}",
                100.0 * A12_DEPENDENCE_TOL,
                fabrics.join(", ")
            );
        }
    }
    if !unloadable.is_empty() {
        let _ = write!(
            s,
            "\nLeft out above: fitted law fabrics whose truth or fitted material file does not load:\n\n{unloadable}"
        );
    }
    if !unconverged.is_empty() {
        let _ = write!(
            s,
            "\nLeft out above: fitted law fabrics whose strips the virtual lab could not solve to its \
             tolerance ({:.1} % of the end force) on its finest mesh, so whose curves are a mesh's, \
             not the law's:\n\n{unconverged}",
            100.0 * STRIP_TOL
        );
    }
    s
}

/// What a fit says of a parameter's quantity.
#[derive(PartialEq)]
enum Said {
    Determined,
    /// `[fit.uncertainty]` calls it not determined
    NotDetermined,
    /// determined only with the assumed a12 (`a12_dependence_*` above its tolerance)
    WithA12,
}

/// What the fitted material file says of parameter `name`'s quantity: its `[fit.uncertainty]`
/// entry (determined for a name it does not list, or an empty name), then the `[fit]`
/// `a12_dependence_*` of the strips that determine it.
fn fit_determined(material: &Path) -> impl Fn(&str) -> Said {
    let doc: Option<toml::Table> = std::fs::read_to_string(material)
        .ok()
        .and_then(|t| t.parse().ok());
    move |name: &str| {
        let fit = doc.as_ref().and_then(|d| d.get("fit"));
        let determined = fit
            .and_then(|f| f.get("uncertainty"))
            .and_then(|u| u.get(name))
            .and_then(|e| e.get("determined"))
            .and_then(|d| d.as_bool())
            .unwrap_or(true);
        let strips = match name {
            "a11_pa" => "warp",
            "a22_pa" => "weft",
            "g12_pa" => "off_axis",
            _ => "",
        };
        let dependence = fit
            .and_then(|f| f.get(format!("a12_dependence_{strips}")))
            .and_then(|d| d.as_float())
            .unwrap_or(0.0);
        if !determined {
            Said::NotDetermined
        } else if dependence > A12_DEPENDENCE_TOL {
            Said::WithA12
        } else {
            Said::Determined
        }
    }
}

/// Why a law fabric's curves are not the converged law's (`lab.csv`: an angle whose
/// estimated error is above [`STRIP_TOL`] or unknown), or `None`.
fn lab_unconverged(folder: &Path) -> Option<String> {
    let text = std::fs::read_to_string(folder.join("lab.csv")).ok()?;
    let worst: Vec<String> = text
        .lines()
        .skip(1)
        .filter_map(|row| {
            let cols: Vec<&str> = row.split(',').collect();
            let (angle, mesh, error) = (cols.first()?, cols.get(1)?, cols.get(2)?);
            match error.parse::<f64>() {
                Ok(e) if e < STRIP_TOL => None,
                Ok(e) => Some(format!("{angle}° {:.2} % on {mesh}", 100.0 * e)),
                Err(_) => Some(format!("{angle}° no estimate (not monotone) on {mesh}")),
            }
        })
        .collect();
    (!worst.is_empty()).then(|| worst.join(", "))
}
