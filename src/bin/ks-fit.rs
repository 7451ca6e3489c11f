//! `ks-fit`: the kshell command line.
//!
//! Every user error is one line on stderr starting with `ks-fit: error:` and exit code 2.

use clap::{Parser, Subcommand};
use kshell::material::load_material;
use kshell::mesh::{read_obj, shapes, write_obj, PolyMesh, Topology};
use kshell::scene::{CantileverBend, TensileStrip};
use kshell::solve::{NewtonOptions, Precision};
use kshell::subdiv::{refine_uniform, BoundaryRule, FaceKind, LimitBasis, LimitSurface};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "ks-fit",
    version,
    about = "Simulation-ready cloth materials from standard fabric lab tests"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Summarise a quad control mesh (OBJ), or evaluate its Catmull–Clark limit surface.
    Mesh {
        /// Wavefront OBJ file.
        file: PathBuf,
        /// Print the limit position and its first and second derivatives at one point as CSV.
        /// FACE is the 0-based face index in the file; u runs from the face's first vertex
        /// towards its second, v from its first towards its last, both in [0, 1].
        #[arg(long, num_args = 3, value_names = ["FACE", "U", "V"], allow_negative_numbers = true)]
        limit: Option<Vec<String>>,
        /// Boundary treatment: `phantom` (extrapolated rows) or `ghost` (ghost control points).
        #[arg(long, default_value = "phantom")]
        boundary: BoundaryRule,
        /// Apply N uniform Catmull–Clark steps before anything else.
        #[arg(long, default_value_t = 0)]
        subdivide: usize,
        /// Write the (possibly refined) mesh to this OBJ file.
        #[arg(long)]
        write: Option<PathBuf>,
    },
    /// Virtual ASTM D5035 strip test: prints CSV `elongation_mm,force_n`.
    Tensile {
        /// Material file (TOML).
        #[arg(long)]
        material: PathBuf,
        /// Cut angle from the weft, degrees (0 weft, 90 warp, 45 bias).
        #[arg(long, allow_negative_numbers = true)]
        angle: f64,
        /// Strip width, mm.
        #[arg(long)]
        width: f64,
        /// Gauge length, mm.
        #[arg(long)]
        length: f64,
        /// Final elongation, mm.
        #[arg(long)]
        to: f64,
        /// Number of equal elongation steps (rows printed).
        #[arg(long)]
        steps: usize,
        #[command(flatten)]
        solve: SceneArgs,
    },
    /// Virtual ASTM D1388 cantilever: prints CSV `overhang_mm,drape_angle_deg`.
    Bend {
        /// Material file (TOML).
        #[arg(long)]
        material: PathBuf,
        /// Cut angle from the weft, degrees.
        #[arg(long, allow_negative_numbers = true)]
        angle: f64,
        /// Overhang past the platform edge, mm.
        #[arg(long)]
        overhang: f64,
        /// Strip width, mm.
        #[arg(long, default_value_t = 25.0)]
        width: f64,
        #[command(flatten)]
        solve: SceneArgs,
    },
    /// Mesh-refinement study of a virtual test: table of QoI, Richardson estimate, observed
    /// order; optionally the coarsest mesh meeting a tolerance, CSV and an SVG chart.
    Converge {
        #[command(subcommand)]
        scene: ConvergeScene,
    },
    /// Run the built-in demonstration: the limit basis on the bundled sample shapes.
    Demo,
    /// Fit a fabric dataset: writes the fitted material (TOML, with a [fit] table of how well
    /// it reproduces every test) and prints the per-test table; progress on stderr.
    Fit {
        /// The dataset's fabric.toml.
        file: PathBuf,
        /// Fitted material file (default: <dataset name>-fit.toml in the current folder).
        #[arg(short = 'o', long = "output")]
        output: Option<PathBuf>,
        /// Also write per-test CSVs of measured and fitted force, SVG plots and a summary here.
        #[arg(long)]
        report: Option<PathBuf>,
        /// Highest polynomial degree of each η tried (lowest first).
        #[arg(long, default_value_t = 3)]
        max_degree: usize,
        /// Use exactly this degree for every η instead of choosing (for comparisons).
        #[arg(long)]
        degree: Option<usize>,
        /// Meshes of a 50 × 75 mm strip, coarse to fine (other strips keep the element size);
        /// later levels are skipped when the last one changed the forces by under 0.2 %.
        #[arg(long, default_value = "8x12,16x24,32x48")]
        mesh_ladder: String,
        /// Minimiser: hybrid (Gauss–Newton while it makes fast progress, BFGS updates after),
        /// bfgs or gauss-newton; every one uses a strong-Wolfe line search.
        #[arg(long, default_value = "hybrid")]
        method: kshell::fit::optim::Method,
        /// No progress lines.
        #[arg(long)]
        quiet: bool,
        /// Which tests are fitted: `all` (every angle unless its `role` says validation) or
        /// `paper` (0°, 45° and 90° fitted, the rest validation, as in Clyde et al. 2017).
        #[arg(long, default_value = "all", value_parser = ["all", "paper"])]
        protocol: String,
        /// Toe compensation: `auto` (detect slack and preload, remove them, report `toe_mm`)
        /// or `none`; a test's own `toe_mm` key wins over both.
        #[arg(long, value_enum, default_value = "auto")]
        toe: kshell::fit::ToeMode,
        /// Repeats fitted: `all` (each curve weighted alike) or `largest` (the paper's choice:
        /// the largest forces for warp and weft, the median for other angles).
        #[arg(long, value_enum, default_value = "all")]
        repeat: kshell::fit::RepeatMode,
        /// Bound of the misalignment diagnostic of validation runs, degrees (0: off). The
        /// reported error is always the one at the nominal angle.
        #[arg(long, default_value_t = 2.0)]
        max_misalign: f64,
        /// Elongation nodes per strip at which the model is solved (interpolated between).
        #[arg(long, default_value_t = 12)]
        nodes: usize,
    },
    /// Check a fabric dataset (fabric.toml and its CSV curves): print a summary of every test
    /// and what the fit will do with it, then any warnings; exit 2 on an error.
    Check {
        /// The dataset's fabric.toml.
        file: PathBuf,
    },
    /// Write a synthetic dataset from a material through the virtual lab: tensile strips at
    /// 90, 0, 45, 22.5 and 67.5 degrees, and the warp and weft cantilevers at 41.5 degrees.
    Synth {
        /// Material file (TOML).
        #[arg(long)]
        material: PathBuf,
        /// Output folder (fabric.toml and the curves).
        #[arg(long)]
        out: PathBuf,
        /// Largest engineering strain of the tensile curves.
        #[arg(long, allow_negative_numbers = true, default_value_t = 0.1)]
        max_strain: f64,
        /// Points per tensile curve.
        #[arg(long, default_value_t = 20)]
        points: usize,
        /// Curves per tensile angle.
        #[arg(long, default_value_t = 1)]
        repeats: usize,
        /// Relative force noise: each repeat scaled by 1 + REL·z, each point by 1 + REL/10·z.
        #[arg(long, allow_negative_numbers = true, default_value_t = 0.0)]
        noise: f64,
        /// Standard deviation of each repeat's cut angle, degrees.
        #[arg(long, allow_negative_numbers = true, default_value_t = 0.0)]
        misalign: f64,
        /// Seed of the noise.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Tensile strip mesh, faces across × along.
        #[arg(long, value_parser = parse_mesh, default_value = "16x24")]
        mesh: (usize, usize),
    },
}

/// Options shared by the scene commands.
#[derive(clap::Args)]
struct SceneArgs {
    /// Faces across × along, e.g. 8x12 (default: the scene's own: 8 across for a strip,
    /// elements of about 6.25 mm for a cantilever).
    #[arg(long, value_parser = parse_mesh)]
    mesh: Option<(usize, usize)>,
    /// Boundary treatment of the limit surface: phantom or ghost (default: phantom for strips,
    /// ghost for cantilevers, as measured in the README).
    #[arg(long)]
    boundary: Option<BoundaryRule>,
    /// Report each solve on stderr.
    #[arg(short, long)]
    verbose: bool,
    /// Residual arithmetic of the iterative refinement: f64, dd (double-double) or rug.
    #[arg(long, default_value = "dd")]
    precision: Precision,
    /// Plain Newton: no backward-Euler fallback and no refinement (for comparison).
    #[arg(long)]
    plain_newton: bool,
}

impl SceneArgs {
    fn solver(&self) -> NewtonOptions {
        if self.plain_newton {
            NewtonOptions::plain()
        } else {
            NewtonOptions {
                precision: self.precision,
                ..NewtonOptions::default()
            }
        }
    }
}

#[derive(Subcommand)]
enum ConvergeScene {
    /// QoI: the clamp force at the given elongation.
    Tensile {
        #[arg(long)]
        material: PathBuf,
        #[arg(long, allow_negative_numbers = true)]
        angle: f64,
        /// Strip width, mm.
        #[arg(long)]
        width: f64,
        /// Gauge length, mm.
        #[arg(long)]
        length: f64,
        /// Elongation at which the force is compared, mm.
        #[arg(long)]
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
        #[arg(long)]
        overhang: f64,
        /// Strip width, mm.
        #[arg(long, default_value_t = 25.0)]
        width: f64,
        #[command(flatten)]
        study: StudyArgs,
    },
}

#[derive(clap::Args)]
struct StudyArgs {
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
    /// Boundary treatment of the limit surface: phantom or ghost (default: the scene's own).
    #[arg(long)]
    boundary: Option<BoundaryRule>,
}

/// One line describing a solve, for --verbose.
fn describe(r: &kshell::solve::SolveReport) -> String {
    format!(
        "{} iterations ({} backward Euler: {} indefinite, {} ascent, {} stagnation, {} short steps), {} refinement steps ({:?}), residual {:.1e}{}{}, {:.1} ms",
        r.iterations,
        r.backward_euler_steps,
        r.fallbacks.indefinite,
        r.fallbacks.ascent,
        r.fallbacks.stagnation,
        r.fallbacks.short_step,
        r.refinement_steps,
        r.precision,
        r.residual,
        if r.precision_limited { " (round-off floor)" } else { "" },
        if r.saddle_escapes > 0 { format!(", {} saddle escapes", r.saddle_escapes) } else { String::new() },
        r.seconds * 1e3
    )
}

/// "NXxNY" → (NX, NY), both at least 1.
fn parse_mesh(s: &str) -> Result<(usize, usize), String> {
    match kshell::converge::parse_ladder(s)?.as_slice() {
        [one] => Ok(*one),
        _ => Err(format!("a mesh looks like 8x12, got '{s}'")),
    }
}

/// A positive, finite number of millimetres, in metres.
fn mm(name: &str, v: f64) -> Result<f64, String> {
    if v.is_finite() && v > 0.0 {
        Ok(v * 1e-3)
    } else {
        Err(format!(
            "--{name} must be a positive number of millimetres, got {v}"
        ))
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Mesh {
            file,
            limit,
            boundary,
            subdivide,
            write,
        } => cmd_mesh(
            &file,
            limit.as_deref(),
            boundary,
            subdivide,
            write.as_deref(),
        ),
        Command::Tensile {
            material,
            angle,
            width,
            length,
            to,
            steps,
            solve,
        } => cmd_tensile(&material, angle, width, length, to, steps, &solve),
        Command::Bend {
            material,
            angle,
            overhang,
            width,
            solve,
        } => cmd_bend(&material, angle, overhang, width, &solve),
        Command::Converge { scene } => cmd_converge(scene),
        Command::Demo => cmd_demo(),
        Command::Check { file } => cmd_check(&file),
        Command::Fit {
            file,
            output,
            report,
            max_degree,
            degree,
            mesh_ladder,
            method,
            quiet,
            protocol,
            toe,
            repeat,
            max_misalign,
            nodes,
        } => fit_options(
            degree.map_or(max_degree, |d| d.max(1)),
            degree,
            &mesh_ladder,
            method,
            &protocol,
            toe,
            repeat,
            max_misalign,
            nodes,
        )
        .and_then(|opts| cmd_fit(&file, output.as_deref(), report.as_deref(), &opts, quiet)),
        Command::Synth {
            material,
            out,
            max_strain,
            points,
            repeats,
            noise,
            misalign,
            seed,
            mesh,
        } => cmd_synth(
            &material,
            &out,
            &kshell::synth::SynthOptions {
                max_strain,
                points,
                repeats,
                noise,
                misalign_deg: misalign,
                seed,
                mesh,
            },
        ),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("ks-fit: error: {msg}");
            ExitCode::from(2)
        }
    }
}

fn refine(mesh: &PolyMesh) -> PolyMesh {
    // the mesh was checked when it was read; refinement keeps it manifold
    match Topology::build(mesh) {
        Ok(t) => refine_uniform(mesh, &t),
        Err(_) => mesh.clone(),
    }
}

fn cmd_mesh(
    file: &std::path::Path,
    limit: Option<&[String]>,
    rule: BoundaryRule,
    subdivide: usize,
    write: Option<&std::path::Path>,
) -> Result<(), String> {
    let name = file.display().to_string();
    let obj = read_obj(file).map_err(|e| e.to_string())?;
    let mut mesh = obj.mesh;
    for _ in 0..subdivide {
        mesh = refine(&mesh);
    }
    let mut notes = Vec::new();
    if !mesh.is_all_quads() {
        notes.push(format!(
            "the mesh has {} non-quad faces: one Catmull–Clark step turned it into quads; face indices refer to the refined mesh",
            mesh.faces.iter().filter(|f| f.len() != 4).count()
        ));
        mesh = refine(&mesh);
    }
    if let Some(out) = write {
        let text = write_obj(&mesh, &format!("written by ks-fit from {name}"));
        std::fs::write(out, text).map_err(|e| format!("{}: cannot write: {e}", out.display()))?;
    }
    let surface = LimitSurface::new(&mesh, rule).map_err(|e| format!("{name}: {e}"))?;
    match limit {
        Some(args) => {
            let face: usize = args[0].parse().map_err(|_| {
                format!(
                    "--limit: FACE must be a face index (0, 1, …), got '{}'",
                    args[0]
                )
            })?;
            let uv: Vec<f64> = args[1..]
                .iter()
                .map(|a| {
                    a.parse::<f64>().map_err(|_| {
                        format!("--limit: U and V must be numbers in [0, 1], got '{a}'")
                    })
                })
                .collect::<Result<_, _>>()?;
            let p = surface
                .evaluate(face, uv[0], uv[1])
                .map_err(|e| format!("{name}: {e}"))?;
            for n in &notes {
                eprintln!("ks-fit: note: {n}");
            }
            println!("x,y,z,xu,yu,zu,xv,yv,zv,xuu,yuu,zuu,xuv,yuv,zuv,xvv,yvv,zvv");
            let row: Vec<String> = p.d.iter().flatten().map(|x| format!("{x:?}")).collect();
            println!("{}", row.join(","));
        }
        None => {
            println!("mesh: {name}");
            for n in &notes {
                println!("note: {n}");
            }
            print_summary(&mesh, &surface);
        }
    }
    Ok(())
}

fn cmd_tensile(
    material: &std::path::Path,
    angle: f64,
    width: f64,
    length: f64,
    to: f64,
    steps: usize,
    args: &SceneArgs,
) -> Result<(), String> {
    let mat = load_material(material).map_err(|e| e.to_string())?;
    let (w, l, to) = (mm("width", width)?, mm("length", length)?, mm("to", to)?);
    if steps == 0 {
        return Err("--steps must be at least 1".into());
    }
    if !angle.is_finite() {
        return Err(format!("--angle must be a number of degrees, got {angle}"));
    }
    let mut strip = TensileStrip::new(w, l, angle);
    if let Some(m) = args.mesh {
        strip.mesh = m;
    }
    if let Some(b) = args.boundary {
        strip.boundary = b;
    }
    strip.solver = args.solver();
    let dl: Vec<f64> = (1..=steps).map(|i| to * i as f64 / steps as f64).collect();
    let curve = strip.run(&mat, &dl).map_err(|e| e.to_string())?;
    println!("elongation_mm,force_n");
    for p in &curve {
        println!("{},{}", p.elongation * 1e3, p.force);
        if args.verbose {
            eprintln!(
                "elongation {:.4} mm: {}",
                p.elongation * 1e3,
                describe(&p.report)
            );
        }
    }
    Ok(())
}

fn cmd_bend(
    material: &std::path::Path,
    angle: f64,
    overhang: f64,
    width: f64,
    args: &SceneArgs,
) -> Result<(), String> {
    let mat = load_material(material).map_err(|e| e.to_string())?;
    let (w, l) = (mm("width", width)?, mm("overhang", overhang)?);
    if !angle.is_finite() {
        return Err(format!("--angle must be a number of degrees, got {angle}"));
    }
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
    bend.solver = args.solver();
    let r = bend.run(&mat).map_err(|e| e.to_string())?;
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
    Ok(())
}

fn cmd_converge(scene: ConvergeScene) -> Result<(), String> {
    use kshell::converge::{default_ladder, parse_ladder, study};
    let (study_args, aspect, title) = match &scene {
        ConvergeScene::Tensile {
            study,
            width,
            length,
            angle,
            elongation,
            ..
        } => (
            study,
            length / width,
            format!("tensile {angle}°, {width} x {length} mm, force at {elongation} mm"),
        ),
        ConvergeScene::Bend {
            study,
            width,
            overhang,
            angle,
            ..
        } => (
            study,
            overhang / width,
            format!("cantilever {angle}°, {width} mm wide, overhang {overhang} mm"),
        ),
    };
    if !aspect.is_finite() || aspect <= 0.0 {
        return Err("width and length/overhang must be positive".into());
    }
    let ladder = match &study_args.mesh_ladder {
        Some(l) => parse_ladder(l).map_err(|e| format!("--mesh-ladder: {e}"))?,
        None => {
            if study_args.levels == 0 {
                return Err("--levels must be at least 1".into());
            }
            default_ladder(aspect, study_args.levels)
        }
    };
    if let Some(t) = study_args.tol {
        if !(t.is_finite() && t > 0.0) {
            return Err(format!("--tol must be a positive number, got {t}"));
        }
    }
    let dofs = |(nx, ny): (usize, usize), rule: BoundaryRule| match rule {
        BoundaryRule::Phantom => 3 * (nx + 1) * (ny + 1),
        BoundaryRule::Ghost => 3 * (nx + 3) * (ny + 3),
    };
    let progress = |l: &kshell::converge::Level| {
        eprintln!(
            "ks-fit: {}x{} done: qoi {:.12e} in {:.2} s",
            l.mesh.0, l.mesh.1, l.qoi, l.seconds
        )
    };
    let result = match &scene {
        ConvergeScene::Tensile {
            material,
            angle,
            width,
            length,
            elongation,
            study: a,
        } => {
            let mat = load_material(material).map_err(|e| e.to_string())?;
            let (w, l, e) = (
                mm("width", *width)?,
                mm("length", *length)?,
                mm("elongation", *elongation)?,
            );
            // steps of at most 5 % strain
            let n = ((e / l) / 0.05).ceil().max(1.0) as usize;
            let dl: Vec<f64> = (1..=n).map(|i| e * i as f64 / n as f64).collect();
            study(
                &ladder,
                |mesh| {
                    let mut strip = TensileStrip::new(w, l, *angle);
                    strip.mesh = mesh;
                    if let Some(b) = a.boundary {
                        strip.boundary = b;
                    }
                    let curve = strip
                        .run(&mat, &dl)
                        .map_err(|e| format!("mesh {}x{}: {e}", mesh.0, mesh.1))?;
                    Ok::<_, String>((
                        curve.last().map(|p| p.force).unwrap_or(0.0),
                        dofs(mesh, strip.boundary),
                    ))
                },
                progress,
            )?
        }
        ConvergeScene::Bend {
            material,
            angle,
            overhang,
            width,
            study: a,
        } => {
            let mat = load_material(material).map_err(|e| e.to_string())?;
            let (w, l) = (mm("width", *width)?, mm("overhang", *overhang)?);
            study(
                &ladder,
                |mesh| {
                    let mut bend = CantileverBend::new(w, l, *angle);
                    bend.mesh = (mesh.0, mesh.1.max(2));
                    if let Some(b) = a.boundary {
                        bend.boundary = b;
                    }
                    let r = bend
                        .run(&mat)
                        .map_err(|e| format!("mesh {}x{}: {e}", mesh.0, mesh.1))?;
                    Ok::<_, String>((r.drape_angle_deg, dofs(bend.mesh, bend.boundary)))
                },
                progress,
            )?
        }
    };
    print!("{}", result.table());
    if let Some(t) = study_args.tol {
        match result.pick(t) {
            Some(l) => println!(
                "coarsest mesh with estimated error below {t:e}: {}x{} ({} DOFs, {:.2} s)",
                l.mesh.0, l.mesh.1, l.dofs, l.seconds
            ),
            None => println!("no mesh of this ladder has an estimated error below {t:e}"),
        }
    }
    if let Some(p) = &study_args.csv {
        std::fs::write(p, result.csv())
            .map_err(|e| format!("{}: cannot write: {e}", p.display()))?;
    }
    if let Some(p) = &study_args.plot {
        let svg = result.svg(&title)?;
        std::fs::write(p, svg).map_err(|e| format!("{}: cannot write: {e}", p.display()))?;
    }
    Ok(())
}

fn print_summary(mesh: &PolyMesh, surface: &LimitSurface) {
    let Ok(topo) = Topology::build(mesh) else {
        return;
    };
    println!("vertices: {}", mesh.num_vertices());
    println!("faces: {}", mesh.num_faces());
    println!("boundary edges: {}", topo.num_boundary_edges());
    let count = |k: FaceKind| surface.face_kinds().iter().filter(|&&x| x == k).count();
    println!(
        "faces by kind: regular {}, boundary {}, extraordinary {}",
        count(FaceKind::Regular),
        count(FaceKind::Boundary),
        count(FaceKind::Extraordinary)
    );
    let mut interior: BTreeMap<u32, usize> = BTreeMap::new();
    let mut boundary: BTreeMap<u32, usize> = BTreeMap::new();
    for v in 0..mesh.num_vertices() {
        if topo.vertex_faces[v].is_empty() {
            continue;
        }
        let map = if topo.on_boundary[v] {
            &mut boundary
        } else {
            &mut interior
        };
        *map.entry(topo.valence[v]).or_default() += 1;
    }
    let list = |m: &BTreeMap<u32, usize>| {
        if m.is_empty() {
            "none".to_string()
        } else {
            m.iter()
                .map(|(v, n)| format!("{v} ({n})"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    println!(
        "valences present: interior {}; boundary {}",
        list(&interior),
        list(&boundary)
    );
    let isolated = topo.isolated_vertices();
    if isolated > 0 {
        println!("isolated vertices (in no face): {isolated}");
    }
}

fn cmd_demo() -> Result<(), String> {
    println!("kshell demo: the exact Catmull–Clark limit basis, then the virtual lab");
    println!(
        "(4 × 4 Gauss points per face; every stencil computed once, as the shell FEM will use it)"
    );
    println!();
    println!(
        "{:<22} {:>6} {:>16} {:>8} {:>12} {:>9} {:>14}",
        "shape", "faces", "reg/bnd/extra", "points", "stencil avg", "setup ms", "limit area"
    );
    let strip = kshell::mesh::rectangular_grid(0.05, 0.075, 8, 12);
    let cases: Vec<(&str, PolyMesh)> = vec![
        ("strip 50x75 mm, 8x12", strip.clone()),
        ("cube (valence 3)", shapes::cube()),
        ("star (valence 5)", shapes::star(5, 3)),
        ("L-shape (boundary EV)", shapes::l_shape(3)),
    ];
    for (name, mesh) in &cases {
        let t0 = Instant::now();
        let basis = LimitBasis::new(mesh, Default::default()).map_err(|e| e.to_string())?;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let k = &basis.face_kinds;
        let count = |x: FaceKind| k.iter().filter(|&&y| y == x).count();
        let (mean, _) = basis.stencil_sizes();
        println!(
            "{:<22} {:>6} {:>16} {:>8} {:>12.1} {:>9.2} {:>14.6e}",
            name,
            basis.num_faces,
            format!(
                "{}/{}/{}",
                count(FaceKind::Regular),
                count(FaceKind::Boundary),
                count(FaceKind::Extraordinary)
            ),
            basis.num_points(),
            mean,
            ms,
            basis.area(&basis.control_points)
        );
    }
    let basis = LimitBasis::new(&strip, Default::default()).map_err(|e| e.to_string())?;
    let area = basis.area(&basis.control_points);
    println!();
    println!(
        "check: the strip's limit surface is exactly its 50 × 75 mm rectangle: area {:.10e} m² (relative error {:.1e})",
        area,
        (area / 3.75e-3 - 1.0).abs()
    );
    let cube = LimitBasis::new(&shapes::cube(), Default::default()).map_err(|e| e.to_string())?;
    println!(
        "the unit cube's limit surface encloses {:.6} of the cube's volume",
        cube.enclosed_volume(&cube.control_points)
    );

    // the virtual lab on the bundled example material
    let text = include_str!("../../examples/materials/cotton.toml");
    let mat = kshell::material::parse_material(text, "examples/materials/cotton.toml")
        .map_err(|e| e.to_string())?;
    println!();
    println!(
        "virtual lab, material '{}' (examples/materials/cotton.toml): 50 x 75 mm strips, 8 x 12 mesh",
        mat.name
    );
    println!(
        "{:<14} {:>12} {:>12} {:>12}",
        "strip", "F @ 2.5 %", "F @ 5 %", "F @ 10 %"
    );
    for (name, angle) in [
        ("weft (0°)", 0.0),
        ("bias (45°)", 45.0),
        ("warp (90°)", 90.0),
    ] {
        let t0 = Instant::now();
        let curve = TensileStrip::new(0.05, 0.075, angle)
            .run(&mat, &[0.001875, 0.00375, 0.0075])
            .map_err(|e| e.to_string())?;
        println!(
            "{:<14} {:>10.3} N {:>10.3} N {:>10.3} N   ({:.0} ms)",
            name,
            curve[0].force,
            curve[1].force,
            curve[2].force,
            t0.elapsed().as_secs_f64() * 1e3
        );
    }
    for (name, angle) in [("warp", 90.0), ("weft", 0.0)] {
        let t0 = Instant::now();
        let r = CantileverBend::new(0.025, 0.06, angle)
            .run(&mat)
            .map_err(|e| e.to_string())?;
        println!(
            "cantilever, {name}, 25 mm wide, 60 mm overhang: drape angle {:.2}° ({:.0} ms)",
            r.drape_angle_deg,
            t0.elapsed().as_secs_f64() * 1e3
        );
    }
    Ok(())
}

/// The fit's settings from its flags, checked.
#[allow(clippy::too_many_arguments)]
fn fit_options(
    max_degree: usize,
    fixed_degree: Option<usize>,
    mesh_ladder: &str,
    method: kshell::fit::optim::Method,
    protocol: &str,
    toe: kshell::fit::ToeMode,
    repeats: kshell::fit::RepeatMode,
    max_misalign: f64,
    nodes: usize,
) -> Result<kshell::fit::FitOptions, String> {
    if max_degree == 0 || fixed_degree == Some(0) {
        return Err("degrees start at 1 (--max-degree, --degree)".into());
    }
    if !(0.0..=15.0).contains(&max_misalign) {
        return Err(format!(
            "--max-misalign must be in [0, 15] degrees, got {max_misalign}"
        ));
    }
    if !(4..=200).contains(&nodes) {
        return Err(format!("--nodes must be in [4, 200], got {nodes}"));
    }
    let ladder =
        kshell::converge::parse_ladder(mesh_ladder).map_err(|e| format!("--mesh-ladder: {e}"))?;
    Ok(kshell::fit::FitOptions {
        max_degree,
        fixed_degree,
        ladder,
        method,
        paper_protocol: protocol == "paper",
        toe,
        repeats,
        max_misalign_deg: max_misalign,
        nodes,
        ..kshell::fit::FitOptions::default()
    })
}

fn cmd_fit(
    file: &std::path::Path,
    output: Option<&std::path::Path>,
    report: Option<&std::path::Path>,
    opts: &kshell::fit::FitOptions,
    quiet: bool,
) -> Result<(), String> {
    use kshell::fit::{fit, report as fit_report};
    let (data, warnings) = kshell::dataset::load_dataset(file).map_err(|e| e.to_string())?;
    for w in &warnings {
        eprintln!("ks-fit: {w}");
    }
    let mut progress = |line: &str| {
        if !quiet {
            eprintln!("ks-fit: fit: {line}");
        }
    };
    let result = fit(&data, opts, &mut progress).map_err(|e| format!("fit failed: {e}"))?;
    let out = output.map(|p| p.to_path_buf()).unwrap_or_else(|| {
        PathBuf::from(format!(
            "{}-fit.toml",
            data.name
                .replace(|c: char| !c.is_alphanumeric() && c != '-', "_")
        ))
    });
    let text = fit_report::fit_toml(&result, &file.display().to_string());
    std::fs::write(&out, text).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    if let Some(dir) = report {
        let files = fit_report::write_report(&result, dir)
            .map_err(|e| format!("cannot write the report in {}: {e}", dir.display()))?;
        if !quiet {
            eprintln!(
                "ks-fit: fit: report: {} files in {}",
                files.len(),
                dir.display()
            );
        }
    }
    for line in result.degree_log.iter().chain(&result.notes) {
        println!("{line}");
    }
    for line in &result.identifiability {
        println!("identifiability: {line}");
    }
    print!("{}", fit_report::table(&result));
    let stages: Vec<String> = result
        .stats
        .stage_seconds
        .iter()
        .map(|(s, t)| format!("{s} {t:.1} s"))
        .collect();
    println!(
        "fitted on {} in {:.1} s: {} objective evaluations, {} Newton iterations ({})",
        result
            .meshes
            .iter()
            .map(|m| format!("{}x{}", m.0, m.1))
            .collect::<Vec<_>>()
            .join(" → "),
        result.stats.seconds,
        result.stats.evaluations,
        result.stats.newton_iterations,
        stages.join(", ")
    );
    println!("wrote {}", out.display());
    Ok(())
}

fn cmd_check(file: &std::path::Path) -> Result<(), String> {
    let (data, warnings) = kshell::dataset::load_dataset(file).map_err(|e| e.to_string())?;
    println!("dataset: {}", file.display());
    println!("name: {}", data.name);
    match data.areal_density {
        Some(rho) => println!("areal density: {} g/m²", rho * 1e3),
        None => println!("areal density: not given"),
    }
    println!(
        "thickness: {} mm (measured; the fit's initial guess)",
        data.thickness * 1e3
    );
    println!(
        "tests: {} tensile, {} bend",
        data.tensile.len(),
        data.bend.len()
    );
    println!(
        "{:<8} {:>7} {:>9} {:>16} {:>7} {:>14} {:>12}  use",
        "kind", "angle", "width mm", "gauge/overhang", "points", "max elong mm", "max force N"
    );
    let mut info = Vec::new();
    // what `ks-fit fit` will do with each curve by default (no solves: roles, toes, repeats)
    use kshell::fit::preprocess::{prepare, RepeatMode, ToeMode};
    let prep = prepare(&data, false, RepeatMode::All, ToeMode::Auto, 12);
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
        let toe = match &prep {
            Ok(p) => p
                .curves
                .iter()
                .find(|c| c.test == i)
                .filter(|c| c.toe != 0.0)
                .map(|c| {
                    format!(
                        ", toe {:.3} mm {}",
                        c.toe * 1e3,
                        if c.toe_auto { "detected" } else { "given" }
                    )
                })
                .unwrap_or_default(),
            Err(_) => String::new(),
        };
        println!(
            "{:<8} {:>7} {:>9} {:>16} {:>7} {:>14.4} {:>12.4}  {role} ({}{toe})",
            "tensile",
            t.angle_deg,
            t.width * 1e3,
            t.gauge_length * 1e3,
            t.elongation.len(),
            max_elong * 1e3,
            max_force,
            t.curve.display()
        );
    }
    for b in &data.bend {
        let role = if data.known.thickness.is_some() {
            "predicted: thickness known"
        } else {
            "fitted"
        };
        println!(
            "{:<8} {:>7} {:>9} {:>16} {:>7} {:>14} {:>12}  {role} (drape {}°)",
            "bend",
            b.angle_deg,
            b.width * 1e3,
            b.overhang * 1e3,
            "-",
            "-",
            "-",
            b.drape_angle_deg
        );
    }
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
            info.push(format!("known: {name} = {v} (held by the fit)"));
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

fn cmd_synth(
    material: &std::path::Path,
    out: &std::path::Path,
    opts: &kshell::synth::SynthOptions,
) -> Result<(), String> {
    let mat = load_material(material).map_err(|e| e.to_string())?;
    let mut progress = |line: &str| eprintln!("ks-fit: synth: {line}");
    let data = kshell::synth::synthesize(&mat, opts, &mut progress).map_err(|e| e.to_string())?;
    let comment = format!(
        "SYNTHETIC dataset written by ks-fit synth from the material {}\n\
         options: --max-strain {} --points {} --repeats {} --noise {} --misalign {} --seed {} --mesh {}x{}\n\
         tensile strips 50 x 75 mm; cantilevers 25 mm wide at the overhang giving 41.5 degrees",
        material.display(),
        opts.max_strain,
        opts.points,
        opts.repeats,
        opts.noise,
        opts.misalign_deg,
        opts.seed,
        opts.mesh.0,
        opts.mesh.1
    );
    kshell::dataset::write_dataset_with_comment(out, &data, &comment)
        .map_err(|e| format!("{}: cannot write the dataset: {e}", out.display()))?;
    println!(
        "wrote {} ({} tensile curves, {} bend tests)",
        out.join("fabric.toml").display(),
        data.tensile.len(),
        data.bend.len()
    );
    Ok(())
}
