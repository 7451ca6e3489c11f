//! `ks-fit recommend`: the cheapest cloth model and mesh whose error in one lab test is below a
//! tolerance, with the table it chose from (`kshell::recommend`).

use crate::lab_args::mm;
use kshell::converge::{check_ladder, parse_ladder};
use kshell::material::{load_material, FabricMaterial};
use kshell::recommend::{compare_on, Comparison, LabTest};
use kshell::tri::file::{model_only, parse_tri, TriSource};
use kshell::tri::{TriMaterial, ZeroStrain};
use std::path::PathBuf;

/// Largest `--fits` material file read (as the dataset's TOML).
const MAX_FIT_BYTES: u64 = 16 << 20;

/// How far apart the mean drops of differently folded drapes lie: the example cotton's cowls
/// on 32² and 48², shell and triangle models, span 553.7–558.9 mm, and one 32² shell cowl lay
/// 0.36 % from the 48² one (`paper_repro/models/results.md`).
const DRAPE_BRANCH_SPREAD: f64 = 0.005;

/// `--tol`'s default: the largest relative error against the converged shell accepted.
const DEFAULT_TOL: f64 = 0.01;

#[derive(clap::Args)]
pub struct RecommendArgs {
    /// The shell material (TOML): the reference, and the triangle models' parameters where
    /// --fits gives none.
    #[arg(long)]
    material: PathBuf,
    /// The test to compare on: tensile, bend, drape, picture-frame or corner-pull. The drape
    /// is compared on its mean drop (how far the sheet's centre of mass hangs below the held
    /// corners): it has several stable equilibria, its meshes and models fold differently, and
    /// its fold depth has no converged value; the shell also runs it on 48 × 48, the reference.
    #[arg(long, value_parser = ["tensile", "bend", "drape", "picture-frame", "corner-pull"])]
    scene: String,
    /// Largest relative error against the converged shell accepted.
    #[arg(long, default_value_t = DEFAULT_TOL)]
    tol: f64,
    /// Cut angle from the weft, degrees (90 warp).
    #[arg(long, default_value_t = 90.0, allow_negative_numbers = true)]
    angle: f64,
    /// Strip or cantilever width, mm (default 50 for a strip, 25 for a cantilever).
    #[arg(long)]
    width: Option<f64>,
    /// Gauge length of a strip, mm.
    #[arg(long, default_value_t = 75.0)]
    length: f64,
    /// Elongation of a strip, mm (default 2 % of the gauge length).
    #[arg(long)]
    to: Option<f64>,
    /// Overhang of a cantilever, mm (default twice the bending length (B/(ρg))^⅓, about where
    /// D1388's 41.5° is reached, with B the material's warp rigidity for cuts within 45° of
    /// the warp and its weft rigidity otherwise).
    #[arg(long)]
    overhang: Option<f64>,
    /// Material files with a fitted triangle model's [model] table (from `ks-fit fit --model`),
    /// used for their models rather than converting the shell's moduli.
    #[arg(long, num_args = 1..)]
    fits: Vec<PathBuf>,
    /// Runs per model and mesh (the median time is kept; default 3, and 1 for the drape,
    /// whose runs take up to minutes each).
    #[arg(long)]
    repeats: Option<usize>,
    /// Picture frame: final shear angle, degrees, within ±80 (as `scene picture-frame`).
    #[arg(long, default_value_t = crate::sheets::FRAME_SHEAR_DEG, allow_negative_numbers = true)]
    shear_deg: f64,
    /// Corner pull: final stretch of the diagonal, percent (as `scene corner-pull`).
    #[arg(long, default_value_t = crate::sheets::CORNER_STRETCH_PERCENT, allow_negative_numbers = true)]
    stretch: f64,
    /// The mesh ladder every model runs, coarse to fine, e.g. 8x12,16x24,32x48 (square for the
    /// sheet scenes; each twice as fine as the last, as Richardson's extrapolation of the
    /// shell's reference assumes, except for the drape, whose reference is the shell on the
    /// finest). Default: the test's own three (8x12 to 32x48 for a strip, the cantilever's
    /// from its bending length, 8² to 32² for the frame and the drape, 10² to 40² for the
    /// corner pull), and for the drape the shell also on 48 × 48.
    #[arg(long)]
    meshes: Option<String>,
}

/// The `--fits` files' fitted triangle models.
fn read_fits(files: &[PathBuf]) -> Result<Vec<TriMaterial>, String> {
    let mut fitted = Vec::new();
    for f in files {
        let text =
            kshell::io::read_text(f, MAX_FIT_BYTES).map_err(|e| format!("{}: {e}", f.display()))?;
        let kind_name = model_only(&text).ok_or_else(|| {
            format!(
                "{}: --fits takes files with a [model] table and no shell law (the output of ks-fit fit --model)",
                f.display()
            )
        })?;
        let kind = kind_name
            .parse()
            .map_err(|e: String| format!("{}: {e}", f.display()))?;
        match parse_tri(&text, &f.display().to_string(), kind).map_err(|e| e.to_string())? {
            TriSource::Table(t) => fitted.push(t),
            TriSource::Shell(_) => unreachable!("model_only said it has a [model] table"),
        }
    }
    Ok(fitted)
}

/// The sheet scenes' test from their flags.
fn sheet_test(a: &RecommendArgs) -> Result<LabTest, String> {
    match a.scene.as_str() {
        "picture-frame" => {
            if !(a.shear_deg.is_finite() && a.shear_deg.abs() <= 80.0) {
                return Err(format!(
                    "--shear-deg must be within ±80 degrees, got {}",
                    kshell::io::num(a.shear_deg)
                ));
            }
            Ok(LabTest::Frame {
                shear_deg: a.shear_deg,
                side: 0.1,
            })
        }
        "corner-pull" => {
            if !(a.stretch > 0.0 && a.stretch <= 50.0) {
                return Err(format!(
                    "--stretch must be a percentage in (0, 50], got {}",
                    kshell::io::num(a.stretch)
                ));
            }
            Ok(LabTest::Corner {
                stretch: a.stretch / 100.0,
                side: 0.1,
            })
        }
        _ => Ok(LabTest::Drape {
            side: 1.0,
            span: 0.6,
        }),
    }
}

/// The test `--scene` names, from the flags (and the shell's bending length for a cantilever
/// without `--overhang`).
fn lab_test(a: &RecommendArgs, shell: &FabricMaterial) -> Result<LabTest, String> {
    let angle = crate::lab_args::angle_deg(a.angle)?;
    if a.scene == "tensile" {
        let width = mm("width", a.width.unwrap_or(50.0))?;
        let length = mm("length", a.length)?;
        let to = mm("to", a.to.unwrap_or(0.02 * a.length))?;
        if to > 2.0 * length {
            return Err(format!(
                "--to {} mm is more than twice the gauge length (200 % strain)",
                to * 1e3
            ));
        }
        return Ok(LabTest::Tensile {
            angle_deg: angle,
            width,
            length,
            elongation: to,
        });
    }
    if a.scene != "bend" {
        return sheet_test(a);
    }
    let width = mm("width", a.width.unwrap_or(25.0))?;
    let overhang = match a.overhang {
        Some(o) => mm("overhang", o)?,
        None => {
            let b = ZeroStrain::of(shell)?.bending;
            // the cut's angle from the weft folded into [0°, 90°]
            let from_weft = 90.0 - (angle.rem_euclid(180.0) - 90.0).abs();
            let rigidity = if from_weft >= 45.0 { b[0] } else { b[1] };
            let weight = shell.areal_density * kshell::assembly::STANDARD_GRAVITY;
            2.0 * (rigidity / weight).cbrt()
        }
    };
    Ok(LabTest::Bend {
        angle_deg: angle,
        width,
        overhang,
    })
}

/// The shell's meshes and every model's: `--meshes`, or the test's own.
type Ladders = (Vec<(usize, usize)>, Vec<(usize, usize)>);
fn ladders(a: &RecommendArgs, test: &LabTest) -> Result<Ladders, String> {
    let Some(text) = &a.meshes else {
        return Ok((test.shell_meshes(), test.meshes()));
    };
    let ladder = parse_ladder(text).map_err(|e| format!("--meshes: {e}"))?;
    let sheet = matches!(
        test,
        LabTest::Drape { .. } | LabTest::Frame { .. } | LabTest::Corner { .. }
    );
    if let Some(m) = ladder.iter().find(|m| sheet && m.0 != m.1) {
        return Err(format!(
            "--meshes: the {} sheet is square: {}x{} needs as many faces each way",
            a.scene, m.0, m.1
        ));
    }
    let drape = matches!(test, LabTest::Drape { .. });
    check_ladder(&ladder, !drape).map_err(|e| format!("--meshes: {e}"))?;
    Ok((ladder.clone(), ladder))
}

/// What the table's value is.
fn qoi_text(test: &LabTest) -> String {
    match *test {
        LabTest::Tensile { elongation, .. } => {
            format!("force at {:.3} mm (N)", elongation * 1e3)
        }
        LabTest::Bend { overhang, .. } => {
            format!("drape angle at {:.2} mm overhang (deg)", overhang * 1e3)
        }
        LabTest::Frame { shear_deg, .. } => {
            format!("picture frame's shear force at {shear_deg}° (N), 10 cm square")
        }
        LabTest::Corner { stretch, .. } => {
            format!(
                "corner pull's force at {} % (N), 10 cm square",
                100.0 * stretch
            )
        }
        LabTest::Drape { side, span } => format!(
            "drape's mean drop (mm): the centre of mass of a {} mm square below its corners held {} mm apart (fold patterns differ between meshes and models and are not compared)",
            side * 1e3,
            span * 1e3
        ),
    }
}

/// Runs `ks-fit recommend`; `Ok(false)` when no run meets the tolerance.
pub fn cmd_recommend(a: &RecommendArgs) -> Result<bool, String> {
    if !(a.tol > 0.0 && a.tol < 1.0) {
        return Err(format!(
            "--tol must be in (0, 1), got {}",
            kshell::io::num(a.tol)
        ));
    }
    let repeats = a.repeats.unwrap_or(if a.scene == "drape" { 1 } else { 3 });
    if repeats == 0 || repeats > 100 {
        return Err(format!("--repeats must be 1 to 100, got {repeats}"));
    }
    let shell = load_material(&a.material).map_err(|e| e.to_string())?;
    let fitted = read_fits(&a.fits)?;
    let test = lab_test(a, &shell)?;
    let (shell_meshes, meshes) = ladders(a, &test)?;
    if matches!(test, LabTest::Drape { .. }) && a.tol < DRAPE_BRANCH_SPREAD {
        eprintln!(
            "ks-fit: recommend: warning: --tol {} % is below the {} % by which differently folded drapes differ in their mean drop (measured): the table then compares branches, not models",
            100.0 * a.tol,
            100.0 * DRAPE_BRANCH_SPREAD
        );
    }
    let mut progress = |line: &str| eprintln!("ks-fit: recommend: {line}");
    let c = compare_on(
        &shell,
        &fitted,
        test,
        (&shell_meshes, &meshes),
        repeats,
        &mut progress,
    );
    for f in &c.failures {
        eprintln!("ks-fit: recommend: failed: {f}");
    }
    println!(
        "# {}: {}; reference {:.6} from {}",
        a.scene,
        qoi_text(&test),
        c.reference,
        c.reference_from
    );
    Ok(print_runs(&c, a.tol))
}

/// The table of runs, fastest first, and the recommendation; whether one meets `tol`.
fn print_runs(c: &Comparison, tol: f64) -> bool {
    println!("model,params,mesh,seconds,value,rel_error,within_tol");
    let mut runs = c.runs.clone();
    runs.sort_by(|x, y| x.seconds.total_cmp(&y.seconds));
    for r in &runs {
        println!(
            "{},{},{}x{},{:.4},{:.6},{:.3e},{}",
            r.model,
            r.params,
            r.mesh.0,
            r.mesh.1,
            r.seconds,
            r.value,
            r.error,
            if r.error <= tol { "yes" } else { "no" }
        );
    }
    if let Some(r) = c.cheapest_within(tol) {
        println!(
            "recommended: {} ({}) on {}x{}: error {:.2} % in {:.3} s (--tol {} %)",
            r.model,
            r.params,
            r.mesh.0,
            r.mesh.1,
            100.0 * r.error,
            r.seconds,
            100.0 * tol
        );
        return true;
    }
    let best = runs.iter().min_by(|x, y| x.error.total_cmp(&y.error));
    println!(
        "recommended: none meets --tol {} %{}",
        100.0 * tol,
        best.map_or(String::new(), |r| format!(
            "; the most accurate is {} ({}) on {}x{} at {:.2} %",
            r.model,
            r.params,
            r.mesh.0,
            r.mesh.1,
            100.0 * r.error
        ))
    );
    false
}
