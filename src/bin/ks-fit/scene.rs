//! The scene commands of `ks-fit`: `tensile` (a virtual ASTM D5035 strip), `bend` (a virtual
//! ASTM D1388 cantilever) and `converge` (a mesh-refinement study of either), with the checks
//! of their flags (lengths, angles, steps) made before anything is built.

use crate::flags::{boundary_help, grading_help, yarn_rule_help};
use crate::guard;
use crate::lab_args::{
    angle_deg, check_strip_size, describe, mm, unstable_error, SceneArgs, MAX_STEPS,
};
use clap::Subcommand;
use kshell::assembly::YarnRule;
use kshell::material::load_material;
use kshell::scene::{CantileverBend, TensileStrip};
use kshell::solve::NewtonOptions;
use kshell::subdiv::BoundaryRule;
use std::path::PathBuf;
use std::time::Instant;

/// The flags of `ks-fit bend`.
#[derive(clap::Args)]
pub struct BendArgs {
    /// Material file (TOML).
    #[arg(long)]
    pub material: PathBuf,
    /// Cut angle from the weft, degrees.
    #[arg(long, allow_negative_numbers = true)]
    pub angle: f64,
    /// Overhang past the platform edge, mm.
    #[arg(long, allow_negative_numbers = true)]
    pub overhang: f64,
    /// Strip width, mm.
    #[arg(long, allow_negative_numbers = true, default_value_t = 25.0)]
    pub width: f64,
    #[command(flatten)]
    pub solve: SceneArgs,
}

/// The flags of `ks-fit tensile`.
#[derive(clap::Args)]
pub struct TensileArgs {
    /// Material file (TOML).
    #[arg(long)]
    pub material: PathBuf,
    /// Cut angle from the weft, degrees (0 weft, 90 warp, 45 bias).
    #[arg(long, allow_negative_numbers = true)]
    pub angle: f64,
    /// Strip width, mm.
    #[arg(long, allow_negative_numbers = true)]
    pub width: f64,
    /// Gauge length, mm.
    #[arg(long, allow_negative_numbers = true)]
    pub length: f64,
    /// Final elongation, mm.
    #[arg(long, allow_negative_numbers = true)]
    pub to: f64,
    /// Number of equal elongation steps (rows printed).
    #[arg(long)]
    pub steps: usize,
    #[command(flatten)]
    pub solve: SceneArgs,
}

#[derive(Subcommand)]
pub enum ConvergeScene {
    /// QoI: the clamp force at the given elongation.
    Tensile {
        #[arg(long)]
        material: PathBuf,
        #[arg(long, allow_negative_numbers = true)]
        angle: f64,
        /// Strip width, mm.
        #[arg(long, allow_negative_numbers = true)]
        width: f64,
        /// Gauge length, mm.
        #[arg(long, allow_negative_numbers = true)]
        length: f64,
        /// Elongation at which the force is compared, mm.
        #[arg(long, allow_negative_numbers = true)]
        elongation: f64,
        #[command(flatten)]
        study: StudyArgs,
    },
    /// QoI: the drape angle.
    Bend {
        #[arg(long)]
        material: PathBuf,
        #[arg(long, allow_negative_numbers = true)]
        angle: f64,
        /// Overhang, mm.
        #[arg(long, allow_negative_numbers = true)]
        overhang: f64,
        /// Strip width, mm.
        #[arg(long, allow_negative_numbers = true, default_value_t = 25.0)]
        width: f64,
        #[command(flatten)]
        study: StudyArgs,
    },
}

#[derive(clap::Args)]
pub struct StudyArgs {
    /// Number of meshes in the default ladder (4×6, 8×12, … scaled to the aspect ratio).
    #[arg(long, default_value_t = 5)]
    levels: usize,
    /// Explicit ladder, e.g. 4x6,8x12,16x24 (each twice as fine as the last).
    #[arg(long)]
    mesh_ladder: Option<String>,
    /// Also name the coarsest mesh whose estimated relative error is below this.
    #[arg(long)]
    tol: Option<f64>,
    /// Write the table as CSV.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Write an SVG chart of error against DOFs and against time.
    #[arg(long)]
    plot: Option<PathBuf>,
    #[arg(long, help = boundary_help(" (default: the scene's own)"))]
    boundary: Option<BoundaryRule>,
    #[arg(long, value_parser = crate::parse_grading, help = grading_help("; tensile studies; default uniform"))]
    grading: Option<kshell::mesh::Grading>,
    #[arg(long, default_value = YarnRule::default().name(), help = yarn_rule_help(""))]
    yarn_rule: kshell::assembly::YarnRule,
}

pub fn cmd_tensile(
    material: &std::path::Path,
    angle: f64,
    width: f64,
    length: f64,
    to: f64,
    steps: usize,
    args: &SceneArgs,
) -> Result<(), String> {
    let (w, l, to) = (mm("width", width)?, mm("length", length)?, mm("to", to)?);
    let angle = angle_deg(angle)?;
    if to > 2.0 * l {
        return Err(format!(
            "--to {} mm is more than twice the gauge length (200 % strain)",
            to * 1e3
        ));
    }
    if !(1..=MAX_STEPS).contains(&steps) {
        return Err(format!("--steps must be in [1, {MAX_STEPS}], got {steps}"));
    }
    let dl: Vec<f64> = (1..=steps).map(|i| to * i as f64 / steps as f64).collect();
    if let Some(kind) = args.tri_model()? {
        return crate::models::tensile(kind, material, (w, l, angle), &dl, args);
    }
    let mat = load_material(material).map_err(|e| e.to_string())?;
    let mut strip = TensileStrip::new(w, l, angle);
    strip.grading = args.grading.unwrap_or(kshell::mesh::Grading::UNIFORM);
    strip.yarn_rule = args.yarn_rule;
    if let Some(b) = args.boundary {
        strip.boundary = b;
    }
    // the solver's options with the strip's own iteration budget (wrinkling takes time)
    strip.solver = NewtonOptions {
        max_iterations: strip.solver.max_iterations,
        ..args.solver()
    };
    let Some(m) = args.mesh else {
        crate::auto::tensile_tol(args)?;
        let points = crate::auto::auto_tensile(&strip, &mat, &dl, args)?;
        println!("elongation_mm,force_n");
        for p in &points {
            println!(
                "{},{}",
                kshell::io::num(p.elongation * 1e3),
                kshell::io::num(p.force)
            );
        }
        let saddles: Vec<String> = points
            .iter()
            .filter(|p| !p.report.stable)
            .map(|p| kshell::io::num(p.elongation * 1e3))
            .collect();
        return unstable_error(
            "the strip's equilibrium",
            &saddles,
            "at elongation(s) {} mm",
        );
    };
    strip.mesh = m;
    check_strip_size("--mesh", strip.mesh, steps)?;
    let mut rig = strip.rig(&mat, &dl).map_err(|e| e.to_string())?;
    println!("elongation_mm,force_n");
    let (start, mut shown) = (Instant::now(), 0.0);
    let mut saddles = Vec::new();
    let mut each = |p: &kshell::scene::TensilePoint| {
        if !p.report.stable {
            saddles.push(kshell::io::num(p.elongation * 1e3));
        }
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
        // a long curve says how far it has come every few seconds
        let t = start.elapsed().as_secs_f64();
        if t - shown > 5.0 {
            shown = t;
            eprintln!(
                "ks-fit: tensile: {:.4} of {:.4} mm after {t:.0} s",
                p.elongation * 1e3,
                to * 1e3
            );
        }
    };
    rig.run_each(false, &mut each).map_err(|e| e.to_string())?;
    unstable_error(
        "the strip's equilibrium",
        &saddles,
        "at elongation(s) {} mm",
    )
}

pub fn cmd_bend(
    material: &std::path::Path,
    angle: f64,
    overhang: f64,
    width: f64,
    args: &SceneArgs,
) -> Result<(), String> {
    let (w, l) = (mm("width", width)?, mm("overhang", overhang)?);
    let angle = angle_deg(angle)?;
    if let Some(kind) = args.tri_model()? {
        return crate::models::bend(kind, material, (w, l, angle), args);
    }
    let mat = load_material(material).map_err(|e| e.to_string())?;
    let mut bend = CantileverBend::new(w, l, angle);
    if let Some(m) = args.mesh {
        if m.1 < 2 {
            return Err("--mesh: a cantilever needs at least 2 faces along".into());
        }
        bend.mesh = m;
    }
    if let Some(b) = args.boundary {
        bend.boundary = b;
    }
    bend.yarn_rule = args.yarn_rule;
    bend.solver = args.solver();
    let r = match args.mesh {
        Some(_) => bend.run(&mat).map_err(|e| e.to_string())?,
        None => crate::auto::auto_bend(bend.mesh, args, |mesh| {
            CantileverBend {
                mesh,
                ..bend.clone()
            }
            .run(&mat)
            .map_err(|e| e.to_string())
        })?,
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
    println!("{},{}", overhang, r.drape_angle_deg);
    let saddle = if r.report.stable {
        vec![]
    } else {
        vec![kshell::io::num(overhang)]
    };
    unstable_error("the cantilever's equilibrium", &saddle, "at overhang {} mm")
}

impl ConvergeScene {
    fn study_args(&self) -> &StudyArgs {
        match self {
            ConvergeScene::Tensile { study, .. } | ConvergeScene::Bend { study, .. } => study,
        }
    }

    fn material(&self) -> &PathBuf {
        match self {
            ConvergeScene::Tensile { material, .. } | ConvergeScene::Bend { material, .. } => {
                material
            }
        }
    }

    /// The scene's aspect ratio (for the default ladder) and the chart's title, its
    /// dimensions checked.
    fn checked(&self) -> Result<(f64, String), String> {
        match self {
            ConvergeScene::Tensile {
                angle,
                width,
                length,
                elongation,
                ..
            } => {
                let (_, l, e) = (
                    mm("width", *width)?,
                    mm("length", *length)?,
                    mm("elongation", *elongation)?,
                );
                angle_deg(*angle)?;
                if e > 2.0 * l {
                    return Err(
                        "--elongation is more than twice the gauge length (200 % strain)".into(),
                    );
                }
                let title =
                    format!("tensile {angle}°, {width} x {length} mm, force at {elongation} mm");
                Ok((length / width, title))
            }
            ConvergeScene::Bend {
                angle,
                overhang,
                width,
                ..
            } => {
                mm("width", *width)?;
                mm("overhang", *overhang)?;
                angle_deg(*angle)?;
                let title = format!("cantilever {angle}°, {width} mm wide, overhang {overhang} mm");
                Ok((overhang / width, title))
            }
        }
    }
}

/// The study's ladder: `--mesh-ladder`, or `--levels` meshes of the scene's aspect ratio.
fn study_ladder(a: &StudyArgs, aspect: f64) -> Result<Vec<(usize, usize)>, String> {
    use kshell::converge::{default_ladder, parse_ladder, MAX_LEVELS};
    let ladder = match &a.mesh_ladder {
        Some(l) => parse_ladder(l).map_err(|e| format!("--mesh-ladder: {e}"))?,
        None => {
            if !(1..=MAX_LEVELS).contains(&a.levels) {
                return Err(format!(
                    "--levels must be in [1, {MAX_LEVELS}], got {}",
                    a.levels
                ));
            }
            default_ladder(aspect, a.levels)
        }
    };
    let flag = if a.mesh_ladder.is_some() {
        "--mesh-ladder"
    } else {
        "--levels"
    };
    kshell::converge::check_ladder(&ladder, true).map_err(|e| format!("{flag}: {e}"))?;
    Ok(ladder)
}

/// Degrees of freedom of a cage under a boundary rule.
fn dofs((nx, ny): (usize, usize), rule: BoundaryRule) -> usize {
    match rule {
        BoundaryRule::Phantom => 3 * (nx + 1) * (ny + 1),
        BoundaryRule::Ghost => 3 * (nx + 3) * (ny + 3),
    }
}

/// The scene solved on every mesh of the ladder, its QoI and DOFs.
fn run_study(
    scene: &ConvergeScene,
    ladder: &[(usize, usize)],
) -> Result<kshell::converge::Study, String> {
    use kshell::converge::study;
    let progress = |l: &kshell::converge::Level| {
        eprintln!(
            "ks-fit: {}x{} done: qoi {:.12e} in {:.2} s",
            l.mesh.0, l.mesh.1, l.qoi, l.seconds
        )
    };
    let mat = load_material(scene.material()).map_err(|e| e.to_string())?;
    let a = scene.study_args();
    let at = |mesh: (usize, usize), e: kshell::scene::SceneError| {
        format!("mesh {}x{}: {e}", mesh.0, mesh.1)
    };
    match scene {
        ConvergeScene::Tensile {
            angle,
            width,
            length,
            elongation,
            ..
        } => {
            let (w, l, e) = (
                mm("width", *width)?,
                mm("length", *length)?,
                mm("elongation", *elongation)?,
            );
            // steps of at most 5 % strain
            let n = ((e / l) / 0.05).ceil().max(1.0) as usize;
            let dl: Vec<f64> = (1..=n).map(|i| e * i as f64 / n as f64).collect();
            let solve = |mesh| {
                let mut strip = TensileStrip::new(w, l, *angle);
                strip.mesh = mesh;
                strip.grading = a.grading.unwrap_or(kshell::mesh::Grading::UNIFORM);
                strip.yarn_rule = a.yarn_rule;
                if let Some(b) = a.boundary {
                    strip.boundary = b;
                }
                let curve = strip.run(&mat, &dl).map_err(|e| at(mesh, e))?;
                let force = curve.last().map(|p| p.force).unwrap_or(0.0);
                Ok::<_, String>((force, dofs(mesh, strip.boundary)))
            };
            study(ladder, solve, progress)
        }
        ConvergeScene::Bend {
            angle,
            overhang,
            width,
            ..
        } => {
            let (w, l) = (mm("width", *width)?, mm("overhang", *overhang)?);
            let solve = |mesh: (usize, usize)| {
                let mut bend = CantileverBend::new(w, l, *angle);
                bend.mesh = (mesh.0, mesh.1.max(2));
                if let Some(b) = a.boundary {
                    bend.boundary = b;
                }
                bend.yarn_rule = a.yarn_rule;
                let r = bend.run(&mat).map_err(|e| at(mesh, e))?;
                Ok::<_, String>((r.drape_angle_deg, dofs(bend.mesh, bend.boundary)))
            };
            study(ladder, solve, progress)
        }
    }
}

pub fn cmd_converge(scene: ConvergeScene, force: bool) -> Result<(), String> {
    let study_args = scene.study_args();
    let (aspect, title) = scene.checked()?;
    let ladder = study_ladder(study_args, aspect)?;
    if let Some(t) = study_args.tol {
        if !(t.is_finite() && t > 0.0) {
            return Err(format!("--tol must be a positive number, got {t:?}"));
        }
    }
    let mut guard = guard::Guard::new(force);
    guard.input(scene.material());
    if let Some(p) = &study_args.csv {
        guard.file("--csv", p)?;
    }
    if let Some(p) = &study_args.plot {
        guard.file("--plot", p)?;
    }
    let result = run_study(&scene, &ladder)?;
    print!("{}", result.table());
    if let Some(t) = study_args.tol {
        let chosen = result.choose(t, kshell::converge::ErrorMeasure::Relative);
        match chosen {
            kshell::converge::Chosen::Met { index, .. } => {
                let l = &result.levels[index];
                println!(
                    "coarsest mesh with estimated error below {t:e}: {}x{} ({} DOFs, {:.2} s)",
                    l.mesh.0, l.mesh.1, l.dofs, l.seconds
                )
            }
            _ => println!("no mesh of this ladder has an estimated error below {t:e}"),
        }
    }
    if let Some(p) = &study_args.csv {
        kshell::io::write_atomic(p, result.csv())
            .map_err(|e| format!("{}: cannot write: {e}", p.display()))?;
    }
    if let Some(p) = &study_args.plot {
        let svg = result.svg(&title)?;
        kshell::io::write_atomic(p, svg)
            .map_err(|e| format!("{}: cannot write: {e}", p.display()))?;
    }
    Ok(())
}
