//! `ks-fit scene drape|picture-frame|corner-pull`: the paper's showcase scenes (Clyde et al.
//! 2017 Figures 1 and 5) on a fitted material, each on the cheapest mesh whose estimated
//! discretisation error meets `--tol`, with the deformed surface written as OBJ and PLY, the
//! quantities of interest as CSV, and `scene.toml` saying what was run and how well.

use crate::flags::Model;
use crate::guard::Guard;
use crate::scene_shape::{SceneMaterial, Shape, SCENE, SCENE_TOML_MARK};
use clap::Subcommand;
use kshell::converge::{analyse, Chosen, ErrorMeasure, Level};
use kshell::material::{load_material, FabricMaterial};
use kshell::scene::{CornerPull, Drape, PictureFrame, SceneError};
use kshell::solve::NewtonOptions;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `picture-frame --shear-deg`'s default (also `recommend`'s): the final shear angle, degrees.
pub const FRAME_SHEAR_DEG: f64 = 40.0;
/// `corner-pull --stretch`'s default (also `recommend`'s): the diagonal's final stretch, %.
pub const CORNER_STRETCH_PERCENT: f64 = 10.0;

/// `--tol`'s default: the relative discretisation error the automatic mesh must meet.
const SCENE_TOL: f64 = 0.01;

/// Newton and backward-Euler iterations allowed per equilibrium solve of a showcase scene.
const SCENE_ITERATIONS: usize = 500;

/// Options every showcase scene takes.
#[derive(clap::Args)]
pub struct ShowArgs {
    /// Material file (TOML), e.g. the output of `ks-fit fit`.
    #[arg(long)]
    material: PathBuf,
    /// Folder for shape.obj, shape.ply, the scene's CSV and scene.toml (default: the scene's
    /// name in the current folder).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Relative discretisation error the automatic mesh must meet (Richardson estimate over
    /// three meshes, each twice as fine as the last; the coarsest that meets it is kept).
    #[arg(long, default_value_t = SCENE_TOL)]
    tol: f64,
    /// Force one mesh, faces each way ("16" or "16x16"; the sheets are square): no ladder.
    #[arg(long, value_parser = parse_square)]
    mesh: Option<usize>,
    /// Steps of the scene's motion (rows of its CSV).
    #[arg(long, default_value_t = 8)]
    steps: usize,
    /// Pattern of the small out-of-plane start offset that picks a branch where the sheet
    /// buckles: 0 the lowest mode, any other value a pseudo-random mix of low modes.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    #[arg(long, default_value = kshell::solve::Strategy::default().name(), help = crate::flags::strategy_help(" of every equilibrium (the load brought on is only the drape's weight; see the stability atlas)"))]
    strategy: kshell::solve::Strategy,
    #[arg(long, default_value = crate::flags::DEFAULT_MODEL, help = crate::flags::model_help("; a triangle model on the same sheet as a grid of n × n cells split by one diagonal, with the file's [model] table or the shell law converted at each mesh's cell size"))]
    model: String,
    /// Also report the solver's counts of the chosen mesh on stderr (each mesh of the ladder
    /// is reported anyway).
    #[arg(short, long)]
    verbose: bool,
    /// No scene.png (it is drawn on the GPU; without one the scene says so and goes on).
    #[arg(long)]
    no_image: bool,
    #[command(flatten)]
    image: crate::render::ImageArgs,
}

#[derive(Subcommand)]
pub enum ShowScene {
    /// A 1 m × 1 m sheet hanging under gravity from its two top corners, brought 60 cm apart
    /// (Figure 1). QoI: the depth of its folds (front-to-back extent).
    Drape {
        #[command(flatten)]
        args: ShowArgs,
    },
    /// A 10 cm × 10 cm square held along its four edges by a hinged frame sheared to
    /// `--shear-deg`, warp and weft along the arms (Figure 5, top). Prints the frame's shear
    /// force against angle. QoI: the shear force at the final angle.
    PictureFrame {
        #[command(flatten)]
        args: ShowArgs,
        /// Final shear angle, degrees.
        #[arg(long, default_value_t = FRAME_SHEAR_DEG, allow_negative_numbers = true)]
        shear_deg: f64,
    },
    /// A 10 cm × 10 cm square pulled along one diagonal by 1 cm clips on two corners to
    /// `--stretch` percent of the diagonal (Figure 5, bottom). Prints force against
    /// displacement. QoI: the force at the final stretch.
    CornerPull {
        #[command(flatten)]
        args: ShowArgs,
        /// Final stretch of the diagonal, percent.
        #[arg(long, default_value_t = CORNER_STRETCH_PERCENT, allow_negative_numbers = true)]
        stretch: f64,
    },
}

fn parse_square(s: &str) -> Result<usize, String> {
    let (a, b) = s.split_once(['x', 'X']).unwrap_or((s, s));
    let bad = || format!("a sheet mesh looks like 16 or 16x16 (faces each way), got '{s}'");
    let (a, b) = (
        a.trim().parse::<usize>().map_err(|_| bad())?,
        b.trim().parse::<usize>().map_err(|_| bad())?,
    );
    if a != b {
        return Err(format!(
            "the scene sheets are square: the mesh needs as many faces each way, got '{s}'"
        ));
    }
    if a == 0 {
        return Err(bad());
    }
    Ok(a)
}

/// One scene solved on one mesh.
struct Run {
    qoi: f64,
    /// the scene's CSV (header and rows)
    csv: String,
    shape: Shape,
    seconds: f64,
}

impl ShowScene {
    fn args(&self) -> &ShowArgs {
        match self {
            ShowScene::Drape { args }
            | ShowScene::PictureFrame { args, .. }
            | ShowScene::CornerPull { args, .. } => args,
        }
    }

    fn name(&self) -> &'static str {
        match self {
            ShowScene::Drape { .. } => "drape",
            ShowScene::PictureFrame { .. } => "picture-frame",
            ShowScene::CornerPull { .. } => "corner-pull",
        }
    }

    /// The automatic ladder's coarsest mesh (the corner clips are 1/10 of the side: a
    /// multiple of 10 puts them on cage lines).
    fn base_mesh(&self) -> usize {
        match self {
            ShowScene::CornerPull { .. } => 10,
            _ => 8,
        }
    }

    fn qoi_name(&self) -> &'static str {
        match self {
            ShowScene::Drape { .. } => "fold depth (mm)",
            ShowScene::PictureFrame { .. } => "shear force at the final angle (N)",
            ShowScene::CornerPull { .. } => "force at the final stretch (N)",
        }
    }

    fn check(&self) -> Result<(), String> {
        let a = self.args();
        if !(a.tol.is_finite() && a.tol > 0.0 && a.tol < 1.0) {
            return Err(format!("--tol must be in (0, 1), got {:?}", a.tol));
        }
        if a.steps == 0 || a.steps > 1000 {
            return Err(format!("--steps must be 1 to 1000, got {}", a.steps));
        }
        match self {
            ShowScene::PictureFrame { shear_deg, .. }
                if !(shear_deg.is_finite() && shear_deg.abs() <= 80.0) =>
            {
                Err(format!(
                    "--shear-deg must be within ±80 degrees, got {shear_deg:?}"
                ))
            }
            ShowScene::CornerPull { stretch, .. } if !(*stretch > 0.0 && *stretch <= 50.0) => Err(
                format!("--stretch must be a percentage in (0, 50], got {stretch:?}"),
            ),
            _ => Ok(()),
        }
    }

    fn run(&self, material: &SceneMaterial, mesh: usize) -> Result<Run, SceneError> {
        let a = self.args();
        let kind = match self {
            ShowScene::Drape { .. } => Kind::Drape,
            ShowScene::PictureFrame { shear_deg, .. } => Kind::Frame(*shear_deg),
            ShowScene::CornerPull { stretch, .. } => Kind::Corner(*stretch),
        };
        run_kind(kind, material, mesh, a.steps, a.seed, a.strategy)
    }
}

/// A showcase scene with its own parameter: the frame's final shear (degrees), the corner
/// pull's final stretch (percent).
#[derive(Clone, Copy, Debug)]
enum Kind {
    Drape,
    Frame(f64),
    Corner(f64),
}

/// Solves one scene on one mesh.
fn run_kind(
    kind: Kind,
    material: &SceneMaterial,
    mesh: usize,
    steps: usize,
    seed: u64,
    strategy: kshell::solve::Strategy,
) -> Result<Run, SceneError> {
    // wrinkling and folding sheets spend long stretches in backward-Euler relaxation: a
    // budget of 60 iterations per solve fails a 10 % corner pull on 20 × 20
    let solver = NewtonOptions {
        max_iterations: SCENE_ITERATIONS,
        strategy,
        ..NewtonOptions::default()
    };
    let t0 = Instant::now();
    let (qoi, csv, shape) = match kind {
        Kind::Drape => {
            let drape = Drape {
                mesh,
                steps,
                seed,
                solver,
                ..Drape::new()
            };
            let (s, shape) = match (material, material.tri(drape.side / mesh as f64)?) {
                (_, Some(t)) => drape
                    .run_tri(&t)
                    .map(|(s, d)| (s, Shape::Tri(Box::new(d))))?,
                (SceneMaterial::Shell(m), None) => {
                    drape.run(m).map(|(s, d)| (s, Shape::Shell(Box::new(d))))?
                }
                _ => unreachable!("a triangle material has parameters"),
            };
            let csv = format!(
                "drop_mm,depth_mm,width_mm,mean_drop_mm\n{:.4},{:.4},{:.4},{:.4}\n",
                s.drop * 1e3,
                s.depth * 1e3,
                s.width * 1e3,
                s.mean_drop * 1e3
            );
            (s.depth * 1e3, csv, shape)
        }
        Kind::Frame(shear_deg) => {
            let frame = PictureFrame {
                mesh,
                steps,
                seed,
                solver,
                ..PictureFrame::new(0.1, shear_deg)
            };
            let (points, shape) = match (material, material.tri(frame.side / mesh as f64)?) {
                (_, Some(t)) => frame
                    .run_tri(&t)
                    .map(|(p, d)| (p, Shape::Tri(Box::new(d))))?,
                (SceneMaterial::Shell(m), None) => {
                    frame.run(m).map(|(p, d)| (p, Shape::Shell(Box::new(d))))?
                }
                _ => unreachable!("a triangle material has parameters"),
            };
            let mut csv = String::from("shear_angle_deg,shear_force_n,axial_force_n\n");
            for p in &points {
                let _ = writeln!(
                    csv,
                    "{:.4},{:.6e},{:.6e}",
                    p.shear_deg, p.shear_force, p.axial_force
                );
            }
            (points.last().map_or(0.0, |p| p.shear_force), csv, shape)
        }
        Kind::Corner(stretch) => {
            let pull = CornerPull {
                mesh,
                steps,
                seed,
                solver,
                ..CornerPull::new(0.1, stretch / 100.0)
            };
            let (points, shape) = match (material, material.tri(pull.side / mesh as f64)?) {
                (_, Some(t)) => pull
                    .run_tri(&t)
                    .map(|(p, d)| (p, Shape::Tri(Box::new(d))))?,
                (SceneMaterial::Shell(m), None) => {
                    pull.run(m).map(|(p, d)| (p, Shape::Shell(Box::new(d))))?
                }
                _ => unreachable!("a triangle material has parameters"),
            };
            let mut csv = String::from("displacement_mm,force_n\n");
            for p in &points {
                let _ = writeln!(csv, "{:.4},{:.6e}", p.displacement * 1e3, p.force);
            }
            (points.last().map_or(0.0, |p| p.force), csv, shape)
        }
    };
    Ok(Run {
        qoi,
        csv,
        shape,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// How the mesh was chosen, for the report.
struct Choice {
    mesh: usize,
    why: String,
    est_error: Option<f64>,
    ladder: Vec<Level>,
}

/// Warns where the picture frame shears a shell past its law's measured range.
fn warn_past_shear_cutoff(scene: &ShowScene, material: &SceneMaterial) {
    if let (ShowScene::PictureFrame { shear_deg, .. }, SceneMaterial::Shell(material)) =
        (scene, material)
    {
        // a sheet that follows the frame has Ẽ₁₂ = sin γ / 2 (wrinkles only relieve it)
        let e12 = shear_deg.to_radians().sin().abs() / 2.0;
        let limit = material.law.cutoffs.e12.1;
        if e12 > limit {
            eprintln!(
                "ks-fit: warning: the frame shears the sheet to Ẽ12 = {e12:.3}, past the material's shear cut-off {limit:.3} (the end of its measured range): the response there is the law's extrapolation"
            );
        }
    }
}

pub fn cmd_scene(scene: ShowScene, force: bool) -> Result<(), String> {
    scene.check()?;
    let a = scene.args();
    let material = match Model::parse(&a.model)? {
        Model::Kl => SceneMaterial::Shell(load_material(&a.material).map_err(|e| e.to_string())?),
        Model::Tri(kind) => {
            SceneMaterial::Tri(kind, crate::models::source(kind, &a.material, "scene")?)
        }
    };
    warn_past_shear_cutoff(&scene, &material);
    let out = a.out.clone().unwrap_or_else(|| PathBuf::from(scene.name()));
    let mut guard = Guard::new(force);
    guard.input(&a.material);
    guard.folder("--out", &out, &SCENE)?;
    let t0 = Instant::now();
    let fail = |mesh: usize, e: SceneError| format!("{} on {mesh}x{mesh}: {e}", scene.name());
    let (run, choice) = match a.mesh {
        Some(n) => {
            let run = scene.run(&material, n).map_err(|e| fail(n, e))?;
            let why = "forced by --mesh (no error estimate)".to_string();
            (
                run,
                Choice {
                    mesh: n,
                    why,
                    est_error: None,
                    ladder: Vec::new(),
                },
            )
        }
        None => {
            let mut runs = Vec::new();
            for k in 0..3 {
                let n = scene.base_mesh() << k;
                let run = scene.run(&material, n).map_err(|e| fail(n, e))?;
                // one line per mesh: the ladder's last mesh can take minutes
                eprintln!(
                    "ks-fit: scene: {n}x{n}: {} = {:.6}, {:.2} s, {} solver iterations, stable {}",
                    scene.qoi_name(),
                    run.qoi,
                    run.seconds,
                    run.shape.counts().iterations,
                    run.shape.stable()
                );
                runs.push((n, run));
            }
            choose(&scene, a.tol, runs)
        }
    };
    if a.verbose {
        let c = run.shape.counts();
        eprintln!(
            "ks-fit: scene: {} solves ({} cut into sub-steps), {} iterations, {} factorisations, {} backward-Euler, {} negative-curvature and {} convexified steps, {} saddle escapes; {:.2} s assembling, {:.2} s factorising",
            c.steps, c.cut_steps, c.iterations, c.factorizations, c.backward_euler_steps,
            c.curvature_steps, c.convexified_steps, c.saddle_escapes, c.assembly_seconds, c.factor_seconds
        );
    }
    write_outputs(&scene, &out, &run, &choice, t0.elapsed().as_secs_f64())?;
    print!("{}", run.csv);
    eprintln!(
        "ks-fit: scene: {} on {m}x{m} ({}); stable: {}; wrote {}",
        scene.name(),
        choice.why,
        if run.shape.stable() { "yes" } else { "NO" },
        out.display(),
        m = choice.mesh
    );
    Ok(())
}

/// The coarsest run whose Richardson error estimate is below `tol`, else the finest.
fn choose(scene: &ShowScene, tol: f64, runs: Vec<(usize, Run)>) -> (Run, Choice) {
    let levels: Vec<Level> = runs
        .iter()
        .map(|(n, r)| Level::solved((*n, *n), 3 * r.shape.x().len(), r.seconds, r.qoi))
        .collect();
    let study = analyse(levels);
    let chosen = study.choose(tol, ErrorMeasure::Relative);
    let n = runs[chosen.index(runs.len())].0;
    let est_error = chosen.error();
    let why = match chosen {
        Chosen::Met { error: e, .. } => format!(
            "automatic: the coarsest of {} whose estimated error in the {} is below --tol {}: {:.2} %",
            ladder_text(&study.levels),
            scene.qoi_name(),
            tol,
            100.0 * e
        ),
        Chosen::NotMet { error: e } => format!(
            "automatic: WARNING no mesh of {} meets --tol {}; the finest, estimated error {:.2} %",
            ladder_text(&study.levels),
            tol,
            100.0 * e
        ),
        Chosen::NoEstimate => format!(
            "automatic: WARNING the ladder {} does not converge monotonically, no error estimate; the finest",
            ladder_text(&study.levels)
        ),
    };
    let run = runs.into_iter().find(|r| r.0 == n).map(|r| r.1);
    let choice = Choice {
        mesh: n,
        why,
        est_error,
        ladder: study.levels,
    };
    (run.expect("the picked mesh was run"), choice)
}

fn ladder_text(levels: &[Level]) -> String {
    let m: Vec<String> = levels
        .iter()
        .map(|l| format!("{}x{}", l.mesh.0, l.mesh.1))
        .collect();
    m.join(", ")
}

fn write_outputs(
    scene: &ShowScene,
    out: &Path,
    run: &Run,
    choice: &Choice,
    seconds: f64,
) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| format!("--out {}: {e}", out.display()))?;
    let d = &run.shape;
    let surface = d
        .surface()
        .map_err(|e| format!("sampling the surface: {e}"))?;
    let m = choice.mesh;
    let comment = format!(
        "ks-fit scene {} on {m}x{m}, material {}\nunits: metres; texture u along the warp, v along the weft (metres of fabric)",
        scene.name(),
        scene.args().material.display()
    );
    let c = d.counts();
    let mut toml = format!(
        "{SCENE_TOML_MARK}{name}\nscene = \"{name}\"\nmaterial = {material}\nmodel = {model}\nmesh = \"{m}x{m}\"\nmesh_choice = {why}\nqoi = {qoi_name}\nqoi_value = {qoi}\n",
        name = scene.name(),
        material = kshell::io::toml_string(&scene.args().material.display().to_string()),
        model = kshell::io::toml_string(&scene.args().model),
        why = kshell::io::toml_string(&choice.why),
        qoi_name = kshell::io::toml_string(scene.qoi_name()),
        qoi = run.qoi,
    );
    match choice.est_error {
        Some(e) => {
            let _ = writeln!(toml, "estimated_error = {e:.3e}");
        }
        None => toml.push_str("# estimated_error: not estimated (one mesh)\n"),
    }
    let _ = write!(
        toml,
        "stable = {}\nseconds = {:.3}\nseconds_chosen_mesh = {:.3}\nseed = {}\n\n[solver]\nstrategy = \"{}\"\nsteps = {}\ncut_steps = {}\niterations = {}\nfactorizations = {}\nbackward_euler_steps = {}\nsaddle_escapes = {}\nassembly_seconds = {:.3}\nfactor_seconds = {:.3}\n",
        d.stable(), seconds, run.seconds, scene.args().seed, scene.args().strategy.name(), c.steps, c.cut_steps, c.iterations,
        c.factorizations, c.backward_euler_steps, c.saddle_escapes, c.assembly_seconds,
        c.factor_seconds
    );
    for l in &choice.ladder {
        let _ = write!(
            toml,
            "\n[[ladder]]\nmesh = \"{}x{}\"\nqoi = {}\nseconds = {:.3}\n",
            l.mesh.0, l.mesh.1, l.qoi, l.seconds
        );
        if let Some(e) = l.est_error {
            let _ = writeln!(toml, "estimated_error = {e:.3e}");
        }
    }
    let files = [
        ("shape.obj".to_string(), surface.obj(&comment)),
        ("shape.ply".to_string(), surface.ply(&comment)),
        (format!("{}.csv", scene.name()), run.csv.clone()),
        ("scene.toml".to_string(), toml),
    ];
    for (name, text) in files {
        let p = out.join(&name);
        kshell::io::write_atomic(&p, text).map_err(|e| format!("writing {}: {e}", p.display()))?;
    }
    if !scene.args().no_image {
        let p = out.join("scene.png");
        match picture(d, m, &scene.args().image) {
            Ok((png, what)) => {
                kshell::io::write_atomic(&p, png)
                    .map_err(|e| format!("writing {}: {e}", p.display()))?;
                eprintln!("ks-fit: scene: {what}");
            }
            Err(e) => eprintln!("ks-fit: scene: no scene.png ({e}); the shapes are written"),
        }
    }
    Ok(())
}

/// The picture of a scene's final state, as PNG, and what was drawn.
fn picture(
    d: &Shape,
    mesh: usize,
    args: &crate::render::ImageArgs,
) -> Result<(Vec<u8>, String), String> {
    let renderer = kshell::render::Renderer::new().map_err(|e| e.to_string())?;
    let (image, what) = d.picture(&renderer, mesh, &args.options())?;
    let png = image.png().map_err(|e| e.to_string())?;
    Ok((
        png,
        format!("scene.png {}x{}: {what}", image.width, image.height),
    ))
}

/// Meshes of the report's scene pictures: fixed, so that a report costs a predictable time (the
/// corner pull's clips sit on cage lines at multiples of 10).
const REPORT_MESHES: [(Kind, usize, &str, &str); 3] = [
    (
        Kind::Drape,
        16,
        "drape",
        "a 1 m sheet held by two corners brought 60 cm apart (on 16x16 the sheet locks into an arch; the folds of Figure 1 need 32x32)",
    ),
    (Kind::Frame(40.0), 16, "picture frame", "a 10 cm square sheared 40°"),
    (
        Kind::Corner(10.0),
        20,
        "corner pull",
        "a 10 cm square stretched 10 % along a diagonal",
    ),
];

/// The three showcase scenes on `material`, drawn for a fit's report (8 steps, seed 0, the
/// meshes of `REPORT_MESHES`). A scene that fails, or a missing GPU, is a note instead.
pub fn report_figures(
    material: &FabricMaterial,
    args: &crate::render::ImageArgs,
    progress: &mut dyn FnMut(&str),
) -> (Vec<kshell::fit::html::Figure>, Vec<String>) {
    let renderer = match kshell::render::Renderer::new() {
        Ok(r) => r,
        Err(e) => return (Vec::new(), vec![format!("no scene pictures: {e}")]),
    };
    let (mut figures, mut notes) = (Vec::new(), Vec::new());
    for (kind, mesh, title, what) in REPORT_MESHES {
        progress(&format!("scene {title} on {mesh}x{mesh}"));
        let shell = SceneMaterial::Shell(material.clone());
        let drawn = run_kind(kind, &shell, mesh, 8, 0, Default::default())
            .map_err(|e| e.to_string())
            .and_then(|run| {
                let (image, _) = run.shape.picture(&renderer, mesh, &args.options())?;
                let png = image.png().map_err(|e| e.to_string())?;
                Ok((run, png))
            });
        match drawn {
            Ok((run, png)) => figures.push(kshell::fit::html::Figure {
                title: title.to_string(),
                caption: format!(
                    "{what}; {mesh}x{mesh} mesh (fixed, no error estimate: ks-fit scene chooses and checks one), {:.1} s, equilibrium {}",
                    run.seconds,
                    if run.shape.stable() { "stable" } else { "NOT stable" }
                ),
                png,
            }),
            Err(e) => notes.push(format!("scene {title}: not drawn: {e}")),
        }
    }
    (figures, notes)
}
