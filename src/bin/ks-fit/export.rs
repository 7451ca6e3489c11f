//! `ks-fit export`: a material in another simulator's format (ARCSim's JSON, Wang et al. 2011),
//! read back after writing to report how closely it reproduces the law.

use crate::guard::Guard;
use kshell::material::arcsim::{export, stress_deviation, ArcsimMaterial};
use kshell::material::load_material;
use std::path::Path;
use std::path::PathBuf;

/// The flags of `ks-fit export`.
#[derive(clap::Args)]
pub struct ExportArgs {
    /// Material file (TOML).
    #[arg(long)]
    pub material: PathBuf,
    /// Output format: arcsim.
    #[arg(long)]
    pub format: Format,
    /// Output file.
    #[arg(long)]
    pub out: PathBuf,
    /// Engineering strain up to which the format's stiffness ramps are fitted to the law
    /// (the range the material was measured over; at most 1/6, where ARCSim's ramp ends).
    #[arg(long, default_value_t = 0.08)]
    pub max_strain: f64,
}

/// Formats `ks-fit export` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// ARCSim's material JSON (density, stretching and bending tables).
    Arcsim,
}

pub fn cmd_export(
    material: &Path,
    format: Format,
    out: &Path,
    max_strain: f64,
    force: bool,
) -> Result<(), String> {
    let m = load_material(material).map_err(|e| e.to_string())?;
    let mut guard = Guard::new(force);
    guard.input(material);
    guard.file("--out", out)?;
    match format {
        Format::Arcsim => {
            let (a, warnings) = export(&m, max_strain).map_err(|e| format!("export: {e}"))?;
            for w in &warnings {
                eprintln!("ks-fit: warning: {w}");
            }
            let comment = format!(
                "ARCSim material written by ks-fit export from {} ({})\nwarp on u, weft on v; stretching N/m, bending N*m, density kg/m^2; rows fitted up to {} % strain",
                material.display(),
                m.name,
                100.0 * max_strain
            );
            let text = a.json(&comment);
            // what a reader gets back is what was meant
            let back = ArcsimMaterial::parse(&text).map_err(|e| format!("internal: {e}"))?;
            let dev =
                stress_deviation(&m, &back, max_strain).map_err(|e| format!("export: {e}"))?;
            kshell::io::write_atomic(out, &text)
                .map_err(|e| format!("writing {}: {e}", out.display()))?;
            eprintln!(
                "ks-fit: export: wrote {}; ARCSim's stress on uniaxial stretches up to {:.1} % at 0-90 degrees is within {:.2} % of the law's (exact at small strain)",
                out.display(),
                100.0 * max_strain,
                100.0 * dev
            );
        }
    }
    Ok(())
}
