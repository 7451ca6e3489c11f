//! `ks-fit synth`: a synthetic dataset from a material through the virtual lab, on the shell
//! or a triangle model.

use crate::flags::{grading_help, model_help, yarn_rule_help, Model};
use crate::guard::{Guard, Marker};
use crate::{parse_grading, parse_mesh};
use kshell::material::load_material;
use kshell::synth::SynthOptions;
use std::path::{Path, PathBuf};

/// The marker of a synth `--out`: a folder holding a dataset's fabric.toml is never written
/// over without `--force`, whoever wrote the file (the guard refuses it on the name alone).
const DATASET: Marker = Marker {
    file: "fabric.toml",
    ours: |_| true,
};

/// The flags of `ks-fit synth`.
#[derive(clap::Args)]
pub struct SynthArgs {
    /// Material file (TOML).
    #[arg(long)]
    material: PathBuf,
    /// Output folder (fabric.toml and the curves).
    #[arg(long)]
    out: PathBuf,
    /// Largest engineering strain of the tensile curves.
    #[arg(long, allow_negative_numbers = true, default_value_t = SynthOptions::default().max_strain)]
    max_strain: f64,
    /// Points per tensile curve.
    #[arg(long, default_value_t = SynthOptions::default().points)]
    points: usize,
    /// Curves per tensile angle.
    #[arg(long, default_value_t = SynthOptions::default().repeats)]
    repeats: usize,
    /// Relative force noise: each repeat scaled by 1 + REL·z, each point by 1 + REL/10·z.
    #[arg(long, allow_negative_numbers = true, default_value_t = SynthOptions::default().noise)]
    noise: f64,
    /// Standard deviation of each repeat's cut angle, degrees.
    #[arg(long, allow_negative_numbers = true, default_value_t = SynthOptions::default().misalign_deg)]
    misalign: f64,
    /// Seed of the noise.
    #[arg(long, default_value_t = SynthOptions::default().seed)]
    seed: u64,
    /// Tensile angles beyond the five always written (90, 0, 45, 22.5, 67.5), degrees from
    /// the weft, comma-separated (e.g. 15,30,60,75 for the 15° steps of an off-axis study);
    /// written as a<angle>-<repeat>.csv and fitted by default.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    angles: Vec<f64>,
    /// Tensile strip mesh, faces across × along.
    #[arg(long, value_parser = parse_mesh, default_value = "16x24")]
    mesh: (usize, usize),
    #[arg(long, value_parser = parse_grading, default_value_t = SynthOptions::default().grading,
        help = grading_help(""))]
    grading: kshell::mesh::Grading,
    #[arg(long, default_value = SynthOptions::default().yarn_rule.name(),
        help = yarn_rule_help("; the strips only: the cantilevers always use the full rule"))]
    yarn_rule: kshell::assembly::YarnRule,
    #[arg(long, default_value = crate::flags::DEFAULT_MODEL,
        help = model_help(" that the virtual lab runs, from the file's [model] table or converted from its shell law: data another discretisation made, to fit with any model; triangle strips use --mesh and no grading"))]
    model: String,
}

/// The model `synth --model` runs, read from the material file.
fn lab_model(material: &Path, model: &str) -> Result<kshell::synth::LabModel, String> {
    use kshell::synth::LabModel;
    use kshell::tri::file::{load_tri, TriSource};
    let kind = match Model::parse(model)? {
        Model::Kl => {
            let shell = load_material(material).map_err(|e| e.to_string())?;
            return Ok(LabModel::Shell(shell));
        }
        Model::Tri(kind) => kind,
    };
    let source = load_tri(material, kind).map_err(|e| e.to_string())?;
    let (name, thickness) = match &source {
        TriSource::Shell(m) => (m.name.clone(), m.thickness),
        TriSource::Table(_) => {
            // a [model] table has no thickness; the dataset records the file's thickness_mm
            let text = std::fs::read_to_string(material)
                .map_err(|e| format!("{}: {e}", material.display()))?;
            let doc: toml::Table = text
                .parse()
                .map_err(|e| format!("{}: {e}", material.display()))?;
            let number = |k: &str| {
                doc.get(k)
                    .and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)))
            };
            let thickness = number("thickness_mm").filter(|t| t.is_finite() && *t > 0.0).ok_or_else(|| {
                format!(
                    "{}: synth --model {model} needs thickness_mm (a positive number) beside the [model] table: the dataset records the fabric's thickness",
                    material.display()
                )
            })?;
            let name = doc
                .get("name")
                .and_then(|v| v.as_str())
                .unwrap_or(model)
                .to_string();
            (name, thickness * 1e-3)
        }
    };
    Ok(LabModel::Tri {
        kind,
        source,
        name,
        thickness,
    })
}

/// Runs `ks-fit synth`.
pub fn run(a: &SynthArgs, force: bool) -> Result<(), String> {
    let opts = SynthOptions {
        max_strain: a.max_strain,
        points: a.points,
        repeats: a.repeats,
        noise: a.noise,
        misalign_deg: a.misalign,
        seed: a.seed,
        mesh: a.mesh,
        grading: a.grading,
        yarn_rule: a.yarn_rule,
        extra_angles: a.angles.clone(),
    };
    cmd_synth(&a.material, &a.out, &a.model, &opts, force)
}

fn cmd_synth(
    material: &Path,
    out: &Path,
    model: &str,
    opts: &SynthOptions,
    force: bool,
) -> Result<(), String> {
    if model != crate::flags::DEFAULT_MODEL
        && (opts.grading.across != 0.0 || opts.grading.along != 0.0)
    {
        return Err(format!(
            "--grading applies to the kl model's strip cage, not to --model {model}"
        ));
    }
    if model != crate::flags::DEFAULT_MODEL && opts.yarn_rule != kshell::assembly::YarnRule::Auto {
        return Err(format!(
            "--yarn-rule applies to the kl model's limit surface, not to --model {model}"
        ));
    }
    let lab = lab_model(material, model)?;
    let mut guard = Guard::new(force);
    guard.input(material);
    guard.folder("--out", out, &DATASET)?;
    let mut progress = |line: &str| eprintln!("ks-fit: synth: {line}");
    let data =
        kshell::synth::synthesize_with(&lab, opts, &mut progress).map_err(|e| e.to_string())?;
    let comment = format!(
        "SYNTHETIC dataset written by ks-fit synth from the material {} (model {})\n\
         options: --max-strain {} --points {} --repeats {} --noise {} --misalign {} --seed {} --mesh {}x{} --grading {},{} --yarn-rule {}{}\n\
         tensile strips 50 x 75 mm; cantilevers 25 mm wide at the overhang giving 41.5 degrees{}",
        material.display(),
        lab.model_name(),
        opts.max_strain,
        opts.points,
        opts.repeats,
        opts.noise,
        opts.misalign_deg,
        opts.seed,
        opts.mesh.0,
        opts.mesh.1,
        opts.grading.across,
        opts.grading.along,
        opts.yarn_rule.name(),
        if opts.extra_angles.is_empty() {
            String::new()
        } else {
            let a: Vec<String> = opts.extra_angles.iter().map(|a| a.to_string()).collect();
            format!(" --angles {}", a.join(","))
        },
        data.notes
            .iter()
            .map(|n| format!("\n{n}"))
            .collect::<String>()
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

#[cfg(test)]
mod tests {
    use clap::Parser;

    /// `ks-fit synth` without options runs the library's default settings.
    #[test]
    fn the_flags_default_to_the_librarys_options() {
        let cli = crate::Cli::try_parse_from(["ks-fit", "synth", "--material", "m", "--out", "o"]);
        let Ok(crate::Cli {
            command: crate::Command::Synth(a),
            ..
        }) = cli
        else {
            panic!("`ks-fit synth` does not parse");
        };
        let defaults = kshell::synth::SynthOptions::default();
        assert_eq!(
            (
                a.max_strain,
                a.points,
                a.repeats,
                a.noise,
                a.misalign,
                a.seed
            ),
            (
                defaults.max_strain,
                defaults.points,
                defaults.repeats,
                defaults.noise,
                defaults.misalign_deg,
                defaults.seed
            )
        );
        assert_eq!(
            (a.mesh, a.grading, a.yarn_rule),
            (defaults.mesh, defaults.grading, defaults.yarn_rule)
        );
    }
}
