//! A zoo fabric's dataset: its curves measured (law fabrics, in the virtual lab) or evaluated
//! (analytic fabrics), resampled to the lab's points, with the lab's artefacts.

use super::curves::pchip;
use super::{Export, Protocol, Source, ZooFabric, G};
use crate::assembly::YarnRule;
use crate::dataset::{
    dataset_toml, BendTest, FabricDataset, Known, TensileTest, DEFAULT_DRAPE_ANGLE_DEG,
};
use crate::material::{material_toml, FabricMaterial};
use crate::scene::STRIP_GRADING;
use crate::synth::{LabModel, Rng, SynthError};
use crate::tri::file::TriSource;
use crate::tri::TriKind;
use std::path::{Path, PathBuf};

/// A built dataset: the dataset (curve paths relative to its folder), each curve file's text,
/// the truth's material file for law fabrics, and the mesh each angle's strips were solved on.
#[derive(Clone, Debug)]
pub struct ZooDataset {
    pub data: FabricDataset,
    pub curves: Vec<(PathBuf, String)>,
    pub truth: Option<String>,
    pub lab_meshes: Vec<LabMesh>,
}

/// The mesh the virtual lab kept for one angle's strips of a law fabric measured by the shell,
/// with the Richardson estimate of its end force's relative error (`None`: the ladder did not
/// converge monotonically, so there is no estimate).
#[derive(Clone, Debug, PartialEq)]
pub struct LabMesh {
    pub angle: f64,
    pub mesh: (usize, usize),
    pub error: Option<f64>,
}

impl LabMesh {
    /// Whether the estimate meets [`STRIP_TOL`]: the curve is the converged model's.
    pub fn converged(&self) -> bool {
        self.error.is_some_and(|e| e < STRIP_TOL)
    }
}

/// Relative error of a strip's end force that the virtual lab accepts: well below the 3 % of
/// Clyde et al.'s Table 3 that fits are judged by, so that the data are the law's, not a mesh's.
pub const STRIP_TOL: f64 = 0.002;

/// The lab's mesh ladder: faces across a strip, each level twice the last (along, as many as
/// keep the faces square, at least as many as across). The last level costs about 20 s a
/// curve on two cores.
const STRIP_LADDER: [usize; 4] = [12, 24, 48, 96];

impl ZooDataset {
    /// Writes the dataset into `folder` (created if missing): `fabric.toml` with `comment` on
    /// top, its curve files, and `truth.toml` for a law fabric.
    pub fn write(&self, folder: &Path, comment: &str) -> std::io::Result<()> {
        std::fs::create_dir_all(folder)?;
        for (name, text) in &self.curves {
            std::fs::write(folder.join(name), text)?;
        }
        if let Some(truth) = &self.truth {
            std::fs::write(folder.join("truth.toml"), truth)?;
        }
        if !self.lab_meshes.is_empty() {
            std::fs::write(folder.join("lab.csv"), lab_csv(&self.lab_meshes))?;
        }
        std::fs::write(
            folder.join("fabric.toml"),
            dataset_toml(&self.data, comment),
        )
    }
}

/// Points the virtual lab solves a law fabric's curve at; the lab's record is interpolated
/// between them ([`pchip`]).
const SOLVED_POINTS: usize = 12;

/// Faces across a strip measured by a triangle model (converted from the law at that cell
/// size, so not refined); along it, as many as keep the faces square.
const STRIP_FACES_ACROSS: usize = 12;

/// Cantilever width, m (ASTM D1388: 25 mm).
const BEND_WIDTH: f64 = 0.025;

/// The dataset of `fabric`; `progress` gets a line per curve.
pub fn build(fabric: &ZooFabric, progress: &mut dyn FnMut(&str)) -> Result<ZooDataset, SynthError> {
    let p = &fabric.protocol;
    let mut rng = Rng(fabric
        .name
        .bytes()
        .fold(17u64, |h, b| h.wrapping_mul(31).wrapping_add(b as u64)));
    let (mut tensile, mut curves, mut lab_meshes) = (Vec::new(), Vec::new(), Vec::new());
    let named = |stem: &str, e: SynthError| match e {
        SynthError::Scene { source, .. } => SynthError::Scene {
            test: format!("{}: tensile {stem}", fabric.name),
            source,
        },
        other => other,
    };
    for &angle in &p.angles {
        let mesh = match (&fabric.source, fabric.lab) {
            (Source::Law(m), None) => {
                let (kept, exact) =
                    strip_mesh(m, p, angle).map_err(|e| named(&format!("a{angle}"), e))?;
                progress(&format!(
                    "{}: a{angle} on {}x{} (estimated end-force error {})",
                    fabric.name,
                    kept.mesh.0,
                    kept.mesh.1,
                    kept.error
                        .map_or("unknown".to_string(), |e| format!("{:.3} %", 100.0 * e))
                ));
                let mesh = kept.mesh;
                lab_meshes.push(kept);
                Some((mesh, exact))
            }
            _ => None,
        };
        for r in 1..=p.repeats {
            let stem = format!("a{angle}-{r}");
            let cut = angle + p.misalign_deg * rng.normal();
            let lab = match &mesh {
                // the ladder's own curve where the strip is cut at the nominal angle
                Some((_, exact)) if cut == angle => Ok(exact.clone()),
                _ => lab_curve(fabric, cut, mesh.as_ref().map(|m| m.0)),
            };
            let lab = lab.map_err(|e| named(&stem, e))?;
            let (test, text) = record(p, angle, &stem, &lab, &mut rng);
            progress(&format!("{}: {stem} ({} points)", fabric.name, p.points));
            tensile.push(test);
            curves.push((PathBuf::from(format!("{stem}.csv")), text));
        }
    }
    let bend = if p.bends { bends(fabric)? } else { Vec::new() };
    let (areal_density, thickness) = match &fabric.source {
        Source::Law(m) => (m.areal_density, m.thickness),
        Source::Analytic {
            areal_density,
            thickness,
            ..
        } => (*areal_density, *thickness),
    };
    let mut known = Known::default();
    if let (true, Source::Law(m)) = (p.bias_only, &fabric.source) {
        known.a11 = Some(m.law.a11);
        known.a22 = Some(m.law.a22);
        known.thickness = Some(m.thickness);
    }
    // the truth of a fabric a triangle model measured is the model's, not the shell's
    let truth = match (&fabric.source, fabric.lab) {
        (Source::Law(m), None) => Some(material_toml(m)),
        _ => None,
    };
    let data = FabricDataset {
        name: fabric.name.clone(),
        path: PathBuf::from("fabric.toml"),
        areal_density: Some(areal_density),
        thickness,
        tensile,
        bend,
        shapes: Vec::new(),
        known,
        notes: Vec::new(),
    };
    Ok(ZooDataset {
        data,
        curves,
        truth,
        lab_meshes,
    })
}

/// `lab.csv`: each angle's mesh and estimated error.
fn lab_csv(meshes: &[LabMesh]) -> String {
    let mut text = String::from("angle_deg,mesh,estimated_error\n");
    for m in meshes {
        let error = m.error.map_or("none".to_string(), |e| format!("{e:.3e}"));
        text += &format!("{},{}x{},{error}\n", m.angle, m.mesh.0, m.mesh.1);
    }
    text
}

/// The mesh a law fabric's strips at `angle` are solved on: the coarsest of [`STRIP_LADDER`]
/// whose Richardson estimate of the end force's error meets [`STRIP_TOL`] (the limit only from
/// a monotone ladder), else the finest; with the strip's exact curve on it.
fn strip_mesh(
    m: &FabricMaterial,
    p: &Protocol,
    angle: f64,
) -> Result<(LabMesh, Vec<(f64, f64)>), SynthError> {
    use crate::converge::{analyse_monotone, Chosen, ErrorMeasure, Level};
    let (width, gauge) = p.strip;
    let shell = LabModel::Shell(m.clone());
    let mut levels = Vec::new();
    let mut curves = Vec::new();
    for &across in &STRIP_LADDER {
        let mesh = (across, strip_along(across, width, gauge));
        let t0 = std::time::Instant::now();
        let curve = match law_curve(&shell, p, angle, mesh) {
            Ok(c) => c,
            // a finer level that does not solve leaves the coarser ones' choice
            Err(_) if !levels.is_empty() => break,
            Err(e) => return Err(e),
        };
        let end = curve.last().map_or(0.0, |c| c.1);
        levels.push(Level::solved(mesh, 0, t0.elapsed().as_secs_f64(), end));
        curves.push(curve);
        let met = levels.len() >= 3
            && matches!(
                analyse_monotone(levels.clone()).choose(STRIP_TOL, ErrorMeasure::Relative),
                Chosen::Met { .. }
            );
        if met {
            break;
        }
    }
    let chosen = analyse_monotone(levels.clone()).choose(STRIP_TOL, ErrorMeasure::Relative);
    let index = chosen.index(levels.len());
    let kept = LabMesh {
        angle,
        mesh: levels[index].mesh,
        error: chosen.error(),
    };
    Ok((kept, curves.swap_remove(index)))
}

/// Faces along a strip `across` faces wide: square faces, at least as many as across.
fn strip_along(across: usize, width: f64, gauge: f64) -> usize {
    ((across as f64 * gauge / width).round() as usize).max(across)
}

/// The exact curve of a law fabric's strip cut at `cut` degrees, measured by `model` on
/// `mesh` at [`SOLVED_POINTS`] elongations: (elongation m, force N) from zero.
fn law_curve(
    model: &LabModel,
    p: &Protocol,
    cut: f64,
    mesh: (usize, usize),
) -> Result<Vec<(f64, f64)>, SynthError> {
    let (width, gauge) = p.strip;
    let elongations = lab_elongations(p);
    let strip = model.strip(
        (width, gauge, cut),
        mesh,
        (STRIP_GRADING, YarnRule::Auto),
        &elongations,
    );
    let forces = strip.map_err(|source| SynthError::Scene {
        test: String::new(),
        source,
    })?;
    let mut curve = vec![(0.0, 0.0)];
    curve.extend(elongations.into_iter().zip(forces.iter().map(|f| f.0)));
    Ok(curve)
}

/// The [`SOLVED_POINTS`] elongations (m) the lab solves a curve at, up to the protocol's
/// largest strain.
fn lab_elongations(p: &Protocol) -> Vec<f64> {
    let top = p.max_strain * p.strip.1;
    let n = SOLVED_POINTS.min(p.points.max(2));
    (1..=n).map(|i| top * i as f64 / n as f64).collect()
}

/// The exact curve of one strip cut at `cut` degrees at [`SOLVED_POINTS`] elongations:
/// (elongation m, force N) from zero to the protocol's largest strain; a law fabric measured by
/// the shell on `mesh` (its angle's [`strip_mesh`]).
fn lab_curve(
    fabric: &ZooFabric,
    cut: f64,
    mesh: Option<(usize, usize)>,
) -> Result<Vec<(f64, f64)>, SynthError> {
    let p = &fabric.protocol;
    let (width, gauge) = p.strip;
    let top = p.max_strain * gauge;
    let curve = match (&fabric.source, mesh) {
        (Source::Law(m), Some(mesh)) => law_curve(&LabModel::Shell(m.clone()), p, cut, mesh)?,
        (Source::Law(m), None) => {
            let mesh = (
                STRIP_FACES_ACROSS,
                strip_along(STRIP_FACES_ACROSS, width, gauge),
            );
            law_curve(&lab_model(m, fabric.lab), p, cut, mesh)?
        }
        (
            Source::Analytic {
                warp, weft, bias, ..
            },
            _,
        ) => {
            // the nearest of warp (90°), bias (45°) and weft (0°)
            let family = match cut {
                a if a >= 67.5 => warp,
                a if a <= 22.5 => weft,
                _ => bias,
            };
            let points = lab_elongations(p)
                .into_iter()
                .map(|e| (e, family.force(width, e / gauge)));
            std::iter::once((0.0, 0.0)).chain(points).collect()
        }
    };
    carries_force(curve, cut, top)
}

/// `curve`, unless it carries no force (nothing to write).
fn carries_force(
    curve: Vec<(f64, f64)>,
    cut: f64,
    top: f64,
) -> Result<Vec<(f64, f64)>, SynthError> {
    if !curve.iter().any(|&(_, f)| f > 0.0) {
        return Err(SynthError::Options(format!(
            "the strip cut at {cut:.2}° carries no force up to {:.3} mm: no curve to write",
            top * 1e3
        )));
    }
    Ok(curve)
}

/// The lab's record of one strip from its exact curve: `points` points over the machine's
/// travel, slack or preload, noise, and the export's units. Returns the test and the CSV text.
fn record(
    p: &Protocol,
    angle: f64,
    stem: &str,
    exact: &[(f64, f64)],
    rng: &mut Rng,
) -> (TensileTest, String) {
    let (xs, ys): (Vec<f64>, Vec<f64>) = exact.iter().copied().unzip();
    let top = xs[xs.len() - 1];
    let fmax = ys.iter().fold(0.0f64, |a, &b| a.max(b));
    let scale = (1.0 + p.scale_noise * rng.normal()).max(0.5);
    let travel = top + p.slack - p.preload;
    let mut elongation = Vec::with_capacity(p.points);
    let mut force = Vec::with_capacity(p.points);
    for i in 1..=p.points {
        let e = travel * i as f64 / p.points as f64;
        let strain_e = e - p.slack + p.preload;
        let f = if strain_e <= 0.0 {
            // slack: the load cell's noise around zero
            0.002 * fmax * rng.normal()
        } else {
            pchip(&xs, &ys, strain_e) * scale * (1.0 + p.point_noise * rng.normal())
        };
        elongation.push(e);
        force.push(f.max(-0.005 * fmax));
    }
    let (header, divisor, force_scale) = match p.export {
        Export::Newtons => ("elongation_mm,force_n", 1.0, 1.0),
        Export::KiloNewtonsHeader => ("Extension (mm),Load (kN)", 1e3, 1.0),
        Export::KiloNewtonsScaled => ("elongation_mm,force_n", 1e3, 1e3),
    };
    let mut text = format!("{header}\n");
    for (e, f) in elongation.iter().zip(&force) {
        text += &format!("{:.6},{:.6e}\n", e * 1e3, f / divisor);
    }
    let mut test = TensileTest::new(
        angle,
        p.strip.0,
        p.strip.1,
        PathBuf::from(format!("{stem}.csv")),
        elongation,
        force,
    );
    test.force_scale = force_scale;
    (test, text)
}

/// The virtual lab's model of a law fabric: the shell, or the triangle model `tri` converted
/// from it.
fn lab_model(m: &FabricMaterial, tri: Option<TriKind>) -> LabModel {
    match tri {
        None => LabModel::Shell(m.clone()),
        Some(kind) => LabModel::Tri {
            kind,
            source: TriSource::Shell(m.clone()),
            name: m.name.clone(),
            thickness: m.thickness,
        },
    }
}

/// Warp and weft cantilevers at 41.5°: the virtual lab's overhang for law fabrics, twice
/// ASTM D1388's bending length c = (G / (ρ g))^⅓ for analytic ones.
fn bends(fabric: &ZooFabric) -> Result<Vec<BendTest>, SynthError> {
    let mut out = Vec::new();
    for (k, angle) in [90.0, 0.0].into_iter().enumerate() {
        let overhang = match &fabric.source {
            Source::Law(m) => {
                let solves = std::cell::Cell::new(0);
                let lab = lab_model(m, fabric.lab);
                let test = format!("{}: cantilever {angle}°", m.name);
                crate::synth::overhang::find_overhang(&lab, angle, &test, &solves)?.overhang
            }
            Source::Analytic {
                areal_density,
                bending,
                ..
            } => {
                let g = if k == 0 { bending.0 } else { bending.1 };
                2.0 * (g / (areal_density * G)).cbrt()
            }
        };
        out.push(BendTest {
            angle_deg: angle,
            width: BEND_WIDTH,
            overhang,
            drape_angle_deg: DEFAULT_DRAPE_ANGLE_DEG,
        });
    }
    Ok(out)
}
