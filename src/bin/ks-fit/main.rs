//! `ks-fit`: the kshell command line.
//!
//! Every user error is one line on stderr starting with `ks-fit: error:` and exit code 2.

mod auto;
mod batch;
mod export;
mod fabric;
mod fit;
mod flags;
mod guard;
mod lab_args;
mod lock;
mod mesh;
mod models;
mod recommend;
mod render;
mod scene;
mod scene_shape;
mod sheets;
mod synth;

use clap::{Parser, Subcommand};
use fabric::cmd_check;
use mesh::{cmd_demo, cmd_mesh};
use scene::{cmd_bend, cmd_converge, cmd_tensile, ConvergeScene};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "ks-fit",
    version,
    about = "Simulation-ready cloth materials from standard fabric lab tests"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Write outputs even where they would replace an input file, a dataset or a folder that
    /// holds other files (outputs are always written to a temporary file and renamed).
    #[arg(long, global = true)]
    force: bool,
    /// Largest mesh (faces) any command builds; a shell solve needs about 60 KB per face.
    #[arg(long, global = true, default_value_t = kshell::limits::DEFAULT_MAX_FACES)]
    max_faces: usize,
}

#[derive(Subcommand)]
enum Command {
    /// Summarise a quad control mesh (OBJ), or evaluate its Catmull–Clark limit surface.
    Mesh(mesh::MeshArgs),
    /// Virtual ASTM D5035 strip test: prints CSV `elongation_mm,force_n`.
    Tensile(scene::TensileArgs),
    /// Virtual ASTM D1388 cantilever: prints CSV `overhang_mm,drape_angle_deg`.
    Bend(scene::BendArgs),
    /// Mesh-refinement study of a virtual test: table of QoI, Richardson estimate, observed
    /// order; optionally the coarsest mesh meeting a tolerance, CSV and an SVG chart.
    Converge {
        #[command(subcommand)]
        scene: ConvergeScene,
    },
    /// The paper's showcase scenes on a material: drape, picture-frame or corner-pull. Writes
    /// the deformed surface (OBJ, PLY), the scene's CSV and scene.toml to --out; prints the CSV.
    Scene {
        #[command(subcommand)]
        scene: sheets::ShowScene,
    },
    /// The cheapest cloth model and mesh for one lab test: the shell and every triangle model
    /// (converted from the material, or fitted: --fits) on three meshes each, timed, their
    /// error against the converged shell; prints the table (CSV) and the recommendation. Exit
    /// code 3 when no run meets --tol.
    Recommend {
        #[command(flatten)]
        args: recommend::RecommendArgs,
    },
    /// Render a shape (OBJ, e.g. a scene's shape.obj) to PNG on the GPU (a software Vulkan
    /// driver such as Mesa's lavapipe will do): the cloth with its warp (red) and weft (blue)
    /// lines where the file has texture coordinates in metres of fabric, lit from above.
    /// Several shapes are drawn side by side at one scale, --image each.
    Render(render::RenderArgs),
    /// Write a material in another simulator's format: `arcsim` (the JSON material of Wang et
    /// al. 2011 that ARCSim reads; warp on u, weft on v). Prints how closely the format
    /// reproduces the law's stress on uniaxial stretches up to --max-strain.
    Export(export::ExportArgs),
    /// Run the built-in demonstration: the limit basis on the bundled sample shapes, then
    /// virtual tensile and cantilever tests of the example material.
    Demo,
    /// Fit a library of fabrics listed in a manifest CSV: each fabric's material, report, log
    /// and status in OUT/<fabric>/, summary.csv and index.html in OUT, rewritten as fabrics
    /// finish; resumable (a fabric done with unchanged inputs is skipped); side by side with
    /// --jobs, or as a Slurm job array (--slurm, --task, --collect). Exit 3 when a fabric
    /// fails, fails its fit (--max-error) or is not run.
    Batch(batch::BatchArgs),
    /// Fit a fabric dataset: writes the fitted material (TOML, with a [fit] table of how well
    /// it reproduces every test) and prints the per-test table; progress on stderr.
    Fit(fit::FitArgs),
    /// Check a fabric dataset (fabric.toml and its CSV curves): print a summary of every test
    /// and what the fit will do with it, then any warnings; exit 2 on an error.
    Check(fabric::CheckArgs),
    /// Write a synthetic dataset from a material through the virtual lab: tensile strips at
    /// 90, 0, 45, 22.5 and 67.5 degrees, and the warp and weft cantilevers at 41.5 degrees.
    Synth(synth::SynthArgs),
}

/// "A,B" (across, along) or "A" (both) → a strip cage grading, each in [0, 1).
pub(crate) fn parse_grading(s: &str) -> Result<kshell::mesh::Grading, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let num = |t: &str| {
        t.parse::<f64>()
            .map_err(|_| format!("a grading looks like 0.8,0.8 (across, along), got '{s}'"))
    };
    let g = match parts.as_slice() {
        [a] => kshell::mesh::Grading {
            across: num(a)?,
            along: num(a)?,
        },
        [a, b] => kshell::mesh::Grading {
            across: num(a)?,
            along: num(b)?,
        },
        _ => {
            return Err(format!(
                "a grading looks like 0.8,0.8 (across, along), got '{s}'"
            ))
        }
    };
    if g.is_valid() {
        Ok(g)
    } else {
        Err(format!("grading strengths must be in [0, 1), got '{s}'"))
    }
}

/// "NXxNY" → (NX, NY), both at least 1.
fn parse_mesh(s: &str) -> Result<(usize, usize), String> {
    match kshell::converge::parse_ladder(s)?.as_slice() {
        [one] => Ok(*one),
        _ => Err(format!("a mesh looks like 8x12, got '{s}'")),
    }
}

/// Runs one command; `Ok(false)` when it ran but failed its check (exit code 3).
fn run(command: Command, force: bool) -> Result<bool, String> {
    match command {
        Command::Mesh(a) => cmd_mesh(
            &a.file,
            a.limit.as_deref(),
            a.boundary,
            a.subdivide,
            a.write.as_deref(),
            force,
        )
        .map(|()| true),
        Command::Tensile(a) => cmd_tensile(
            &a.material,
            a.angle,
            a.width,
            a.length,
            a.to,
            a.steps,
            &a.solve,
        )
        .map(|()| true),
        Command::Bend(a) => {
            cmd_bend(&a.material, a.angle, a.overhang, a.width, &a.solve).map(|()| true)
        }
        Command::Converge { scene } => cmd_converge(scene, force).map(|()| true),
        Command::Scene { scene } => sheets::cmd_scene(scene, force).map(|()| true),
        Command::Export(a) => {
            export::cmd_export(&a.material, a.format, &a.out, a.max_strain, force).map(|()| true)
        }
        Command::Render(a) => {
            render::cmd_render(&a.files, &a.out, a.columns, &a.image, force).map(|()| true)
        }
        Command::Recommend { args } => recommend::cmd_recommend(&args),
        Command::Demo => cmd_demo().map(|()| true),
        Command::Check(args) => cmd_check(&args).map(|()| true),
        Command::Batch(args) => batch::cmd_batch(&args),
        Command::Fit(args) => fit::run(&args, force),
        Command::Synth(args) => synth::run(&args, force).map(|()| true),
    }
}

/// What clap refused, as ks-fit says it: one line `ks-fit: error: …` (clap's message, its
/// lines joined), then clap's tips and usage, each on a line of its own; exit code 2. Help and
/// version print as clap prints them, with exit code 0.
fn clap_refusal(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    match e.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => e.exit(),
        ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            eprintln!("ks-fit: error: a command is missing; its help follows");
            eprint!("{}", e.render());
            return ExitCode::from(2);
        }
        _ => {}
    }
    let text = e.render().to_string();
    let mut lines = text.lines().map(str::trim);
    let mut message: Vec<&str> = Vec::new();
    for l in lines.by_ref() {
        if l.is_empty() {
            break;
        }
        message.push(l.strip_prefix("error:").map_or(l, str::trim_start));
    }
    eprintln!("ks-fit: error: {}", message.join(" "));
    for l in lines.filter(|l| !l.is_empty()) {
        eprintln!("ks-fit: {l}");
    }
    ExitCode::from(2)
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return clap_refusal(e),
    };
    if cli.max_faces == 0 {
        eprintln!(
            "ks-fit: error: --max-faces must be at least 1 (a mesh has one face or more), got 0"
        );
        return ExitCode::from(2);
    }
    kshell::solve::deterministic_factorizations();
    kshell::limits::set_max_faces(cli.max_faces);
    let draws = matches!(
        cli.command,
        Command::Render { .. } | Command::Scene { .. } | Command::Fit(_)
    );
    if draws {
        render::quiet_driver_warnings();
    }
    let result = run(cli.command, cli.force);
    if draws {
        render::cleanup_driver_folder();
    }
    match result {
        Ok(true) => ExitCode::SUCCESS,
        // the fit ran but missed --max-error on a fitted test (the verdict line says which)
        Ok(false) => ExitCode::from(3),
        Err(msg) => {
            eprintln!("ks-fit: error: {msg}");
            ExitCode::from(2)
        }
    }
}
