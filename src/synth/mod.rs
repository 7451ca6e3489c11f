//! Synthetic datasets: a material's lab tests run in the virtual lab ([`crate::scene`]), written
//! as a [`FabricDataset`] the fitter can be checked against (its answer is known).
//!
//! * Tensile strips 50 × 75 mm at 90° (warp), 0° (weft), 45° (bias), 22.5° and 67.5° (the last
//!   two are validation angles under the paper's protocol), then any `extra_angles`
//!   (`synth --angles`), `points` elongations evenly spaced from max_strain/points to
//!   max_strain times the gauge length, on the `mesh` given.
//! * Two cantilevers (90° and 0°), 25 mm wide, each at the overhang whose drape angle is 41.5°
//!   (to 1e-4°): bracketed from twice the bending length c = (D/(ρg))^⅓, D = a·τ³/12 (a11 for
//!   the warp, a22 for the weft; the material's own rigidity when it has a `[bending]` table),
//!   then refined by secant steps in ln(overhang), kept inside the bracket. The mesh is kept
//!   by the rule of `ks-fit bend`'s own ([`crate::converge::Study::choose`]): the overhang
//!   found on ladder level 0 ([`bend_mesh`]: elements of about 6.25 × 3.1 mm) is solved on two
//!   meshes twice and four times as fine, and the search repeated on the coarsest whose
//!   Richardson estimate of the angle error is below [`BEND_TOL_DEG`] (0.01°), the estimate
//!   only from a monotone ladder ([`crate::converge::analyse_monotone`]); the dataset's notes
//!   name the mesh and the estimate, and `ks-fit bend --mesh` on that mesh at the written
//!   overhang reproduces 41.5°.
//! * `repeats` curves per tensile angle. With `noise` = REL each repeat's forces are scaled by
//!   one factor 1 + REL·z (z standard normal, the factor held at ≥ 0) and each point by
//!   1 + REL/10·z; with `misalign_deg` each repeat's strip is cut at its nominal angle + DEG·z
//!   (the dataset records the nominal angle). Bends are exact. The random numbers (splitmix64
//!   and Box–Muller) depend only on `seed`; noise 0 and misalignment 0 give the exact curves.
//! * The lab runs the shell, or any triangle model ([`LabModel`], `ks-fit synth --model`), on
//!   the same strips and cantilevers: data that another discretisation made.

mod lab;
mod overhang;
pub mod zoo;

pub use lab::LabModel;

use crate::dataset::{BendTest, FabricDataset, TensileTest, DEFAULT_DRAPE_ANGLE_DEG};
use crate::material::FabricMaterial;
use crate::scene::{CantileverBend, SceneError};
use std::path::PathBuf;
use std::time::Instant;

/// Tensile angles (from the weft) and their curve-file stems, in the order written.
pub const SYNTH_TENSILE: [(f64, &str); 5] = [
    (90.0, "warp"),
    (0.0, "weft"),
    (45.0, "bias"),
    (22.5, "a22.5"),
    (67.5, "a67.5"),
];

/// Strip width and gauge length, m.
const STRIP: (f64, f64) = (0.05, 0.075);
/// Cantilever width, m.
const BEND_WIDTH: f64 = 0.025;

/// The drape-angle error (degrees) the synthetic cantilevers' mesh must meet: the overhang is
/// searched on the coarsest of [`BEND_LEVELS`] meshes ([`bend_mesh`]) whose Richardson
/// estimate of the angle error at that overhang is below it (ten times tighter than `ks-fit
/// bend`'s default, so that data carry no visible mesh error).
pub const BEND_TOL_DEG: f64 = 0.01;

/// Meshes of the cantilever ladder.
pub const BEND_LEVELS: usize = 3;

/// The cantilever mesh of ladder level `k`: [`CantileverBend::new`]'s own (elements of about
/// 6.25 mm) cut twice as fine along, then doubled each way `k` times.
pub fn bend_mesh(overhang: f64, angle: f64, k: usize) -> (usize, usize) {
    let (nx, ny) = CantileverBend::new(BEND_WIDTH, overhang, angle).mesh;
    (nx << k, (2 * ny) << k)
}

/// A synthetic cantilever's overhang and how it was found.
#[derive(Clone, Debug, PartialEq)]
pub struct FoundOverhang {
    /// m
    pub overhang: f64,
    /// its drape angle on `mesh`, degrees
    pub angle_deg: f64,
    pub mesh: (usize, usize),
    /// the Richardson estimate of that angle's mesh error, degrees (`None`: the ladder's
    /// angles do not converge monotonically)
    pub error_deg: Option<f64>,
    /// the ladder's angles at the level-0 overhang, coarse to fine
    pub ladder: Vec<((usize, usize), f64)>,
}

/// Drape-angle tolerance of the overhang search, degrees.
const ANGLE_TOL: f64 = 1e-4;

/// How to synthesise a dataset.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthOptions {
    /// Largest engineering strain of the tensile curves, in (0, 1].
    pub max_strain: f64,
    /// Points per tensile curve, ≥ 1.
    pub points: usize,
    /// Curves per tensile angle, ≥ 1.
    pub repeats: usize,
    /// Relative force noise (see the module), in [0, 1).
    pub noise: f64,
    /// Standard deviation of each repeat's cut angle, degrees, ≥ 0.
    pub misalign_deg: f64,
    pub seed: u64,
    /// Tensile strip mesh, faces across × along.
    pub mesh: (usize, usize),
    /// Its grading (uniform by default; see [`crate::scene::STRIP_GRADING`]).
    pub grading: crate::mesh::Grading,
    /// How the strips integrate the yarn terms (auto by default; the cantilevers always use
    /// the full rule).
    pub yarn_rule: crate::assembly::YarnRule,
    /// Tensile angles beyond the five of [`SYNTH_TENSILE`] (degrees from the weft, in
    /// [0, 90], none of the five), written after them as `a<angle>-<repeat>.csv`.
    pub extra_angles: Vec<f64>,
}

impl Default for SynthOptions {
    fn default() -> Self {
        Self {
            max_strain: 0.1,
            points: 20,
            repeats: 1,
            noise: 0.0,
            misalign_deg: 0.0,
            seed: 1,
            mesh: (16, 24),
            grading: crate::mesh::Grading::UNIFORM,
            yarn_rule: crate::assembly::YarnRule::Auto,
            extra_angles: Vec::new(),
        }
    }
}

/// A dataset could not be synthesised.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    #[error("{0}")]
    Options(String),
    #[error("{test}: {source}")]
    Scene { test: String, source: SceneError },
    #[error("{0}")]
    Bracket(String),
    /// A solve ended on a saddle: the dataset would record a state the fabric cannot hold.
    #[error("{test}: {what} is unstable (a saddle of the energy: the strip buckles or wrinkles there, and a small disturbance moves it to another state); no dataset is written from it")]
    Unstable { test: String, what: String },
}

/// splitmix64 with Box–Muller normals: small, deterministic, no dependency.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1].
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal (one Box–Muller draw; the second value is discarded).
    fn normal(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// Most points per curve (each one an equilibrium solve of the strip; a lab curve's shape needs
/// tens).
pub const MAX_POINTS: usize = 2_000;
/// Most repeats per angle (labs pull 3–5 strips per direction).
pub const MAX_REPEATS: usize = 20;
/// Largest standard deviation of the cut angle, degrees (a lab cuts within a few degrees).
pub const MAX_MISALIGN_DEG: f64 = 15.0;

impl SynthOptions {
    fn check(&self) -> Result<(), SynthError> {
        let bad = |m: String| Err(SynthError::Options(m));
        if !(self.max_strain.is_finite() && self.max_strain > 0.0 && self.max_strain <= 1.0) {
            return bad(format!(
                "max strain must be in (0, 1], got {:?}",
                self.max_strain
            ));
        }
        if self.points == 0 {
            return bad("points must be at least 1".into());
        }
        for (i, &a) in self.extra_angles.iter().enumerate() {
            let taken =
                SYNTH_TENSILE.iter().any(|t| t.0 == a) || self.extra_angles[..i].contains(&a);
            if !(a.is_finite() && (0.0..=90.0).contains(&a)) || taken {
                return bad(format!(
                    "each extra tensile angle must be in [0, 90] degrees and not one already written (90, 0, 45, 22.5, 67.5 or an earlier one), got {a:?}"
                ));
            }
        }
        if self.repeats == 0 {
            return bad("repeats must be at least 1".into());
        }
        if self.points > MAX_POINTS || self.repeats > MAX_REPEATS {
            return bad(format!(
                "at most {MAX_POINTS} points and {MAX_REPEATS} repeats, got {} and {}",
                self.points, self.repeats
            ));
        }
        if !(self.noise.is_finite() && (0.0..1.0).contains(&self.noise)) {
            return bad(format!(
                "noise must be a relative size in [0, 1), got {:?}",
                self.noise
            ));
        }
        if !(self.misalign_deg.is_finite() && (0.0..=MAX_MISALIGN_DEG).contains(&self.misalign_deg))
        {
            return bad(format!(
                "misalignment must be a standard deviation in [0, {MAX_MISALIGN_DEG}] degrees, got {:?}",
                self.misalign_deg
            ));
        }
        if self.mesh.0 == 0 || self.mesh.1 == 0 {
            return bad(format!(
                "the strip mesh needs at least 1 face each way, got {}x{}",
                self.mesh.0, self.mesh.1
            ));
        }
        crate::limits::check_mesh(
            &format!("the strip mesh {}x{}", self.mesh.0, self.mesh.1),
            self.mesh.0,
            self.mesh.1,
        )
        .map_err(SynthError::Options)?;
        Ok(())
    }
}

/// Runs the virtual lab on `material` as `opts` says; `progress` gets one line per test.
pub fn synthesize(
    material: &FabricMaterial,
    opts: &SynthOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<FabricDataset, SynthError> {
    synthesize_with(&LabModel::Shell(material.clone()), opts, progress)
}

/// [`synthesize`] on any model of the fabric.
pub fn synthesize_with(
    lab: &LabModel,
    opts: &SynthOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<FabricDataset, SynthError> {
    opts.check()?;
    let start = Instant::now();
    let tensile = synth_tensile(lab, opts, start, progress)?;
    let (mut bend, mut notes) = (Vec::new(), Vec::new());
    for (angle, stem) in [(90.0, "warp"), (0.0, "weft")] {
        let t0 = Instant::now();
        let test = format!("cantilever {stem} ({angle}°)");
        let solves = std::cell::Cell::new(0);
        let found = overhang::find_overhang(lab, angle, &test, &solves)?;
        let mesh = format!("{}x{}", found.mesh.0, found.mesh.1);
        let error = match found.error_deg {
            Some(e) if e < BEND_TOL_DEG => format!("estimated mesh error {e:.4}°"),
            Some(e) => format!("WARNING: estimated mesh error {e:.4}°, over {BEND_TOL_DEG}°"),
            None => "WARNING: the mesh ladder does not converge monotonically, no estimate".into(),
        };
        let ladder: Vec<String> = found
            .ladder
            .iter()
            .map(|(m, a)| format!("{}x{} {a:.4}°", m.0, m.1))
            .collect();
        notes.push(format!(
            "{test}: overhang found on {mesh}, {error} (ladder at the first overhang: {})",
            ladder.join(", ")
        ));
        progress(&format!(
            "{test}: overhang {:.4} mm for {:.5}° on {mesh}, {error} ({} solves) in {:.2} s (elapsed {:.1} s)",
            found.overhang * 1e3,
            found.angle_deg,
            solves.get(),
            t0.elapsed().as_secs_f64(),
            start.elapsed().as_secs_f64()
        ));
        bend.push(BendTest {
            angle_deg: angle,
            width: BEND_WIDTH,
            overhang: found.overhang,
            drape_angle_deg: DEFAULT_DRAPE_ANGLE_DEG,
        });
    }
    Ok(FabricDataset {
        name: format!("{}-synthetic", lab.name()),
        path: PathBuf::from("fabric.toml"),
        areal_density: Some(lab.areal_density()),
        thickness: lab.thickness(),
        tensile,
        bend,
        shapes: Vec::new(),
        known: Default::default(),
        notes,
    })
}

/// The tensile curves of [`synthesize`], in [`SYNTH_TENSILE`] order, repeats together.
fn synth_tensile(
    lab: &LabModel,
    opts: &SynthOptions,
    start: Instant,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<TensileTest>, SynthError> {
    let mut rng = Rng(opts.seed);
    let (width, gauge) = STRIP;
    let n = opts.points;
    let elongations: Vec<f64> = (1..=n)
        .map(|i| opts.max_strain * gauge * i as f64 / n as f64)
        .collect();
    let run_strip = |angle: f64, test: &str| -> Result<Vec<f64>, SynthError> {
        let curve = lab
            .strip(
                (width, gauge, angle),
                opts.mesh,
                (opts.grading, opts.yarn_rule),
                &elongations,
            )
            .map_err(|source| SynthError::Scene {
                test: test.to_string(),
                source,
            })?;
        if let Some(k) = curve.iter().position(|p| !p.1) {
            return Err(SynthError::Unstable {
                test: test.to_string(),
                what: format!(
                    "the equilibrium at elongation {:.4} mm",
                    elongations[k] * 1e3
                ),
            });
        }
        Ok(curve.iter().map(|p| p.0).collect())
    };
    let mut tensile = Vec::new();
    let extra: Vec<(f64, String)> = opts
        .extra_angles
        .iter()
        .map(|&a| (a, format!("a{a}")))
        .collect();
    let all = SYNTH_TENSILE
        .iter()
        .map(|&(a, stem)| (a, stem.to_string()))
        .chain(extra);
    for (angle, stem) in all {
        // the exact curve, shared by every repeat cut at the nominal angle
        let mut exact: Option<Vec<f64>> = None;
        for r in 1..=opts.repeats {
            let t0 = Instant::now();
            let scale_z = rng.normal();
            let angle_z = rng.normal();
            let point_z: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
            let cut = angle + opts.misalign_deg * angle_z;
            let test = format!("tensile {stem} ({angle}°) repeat {r}");
            let forces = if cut == angle {
                if exact.is_none() {
                    exact = Some(run_strip(angle, &test)?);
                }
                exact.clone().unwrap_or_default()
            } else {
                run_strip(cut, &test)?
            };
            let factor = (1.0 + opts.noise * scale_z).max(0.0);
            let force: Vec<f64> = forces
                .iter()
                .zip(&point_z)
                .map(|(f, z)| f * factor * (1.0 + 0.1 * opts.noise * z))
                .collect();
            progress(&format!(
                "{test}: cut at {cut:.4}°, force {:.3} N at {:.1} % in {:.2} s (elapsed {:.1} s)",
                force.last().copied().unwrap_or(0.0),
                100.0 * opts.max_strain,
                t0.elapsed().as_secs_f64(),
                start.elapsed().as_secs_f64()
            ));
            tensile.push(TensileTest::new(
                angle,
                width,
                gauge,
                PathBuf::from(format!("{stem}-{r}.csv")),
                elongations.clone(),
                force,
            ));
        }
    }
    Ok(tensile)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_generator_is_deterministic_and_normal() {
        let draw = |seed| {
            let mut r = Rng(seed);
            (0..20000).map(|_| r.normal()).collect::<Vec<f64>>()
        };
        let z = draw(7);
        assert_eq!(z, draw(7));
        assert_ne!(z[..10], draw(8)[..10]);
        let mean = z.iter().sum::<f64>() / z.len() as f64;
        let var = z.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / z.len() as f64;
        assert!(
            mean.abs() < 0.03 && (var - 1.0).abs() < 0.05,
            "{mean} {var}"
        );
        assert!(z.iter().all(|x| x.is_finite()));
    }

    fn cotton() -> FabricMaterial {
        crate::material::parse_material(
            include_str!("../../examples/materials/cotton.toml"),
            "cotton.toml",
        )
        .unwrap()
    }

    #[test]
    fn noise_and_misalignment_are_seeded_and_zero_means_exact() {
        let m = cotton();
        let opts = SynthOptions {
            points: 3,
            repeats: 2,
            mesh: (2, 3),
            ..SynthOptions::default()
        };
        let run = |o: &SynthOptions| {
            synth_tensile(&LabModel::Shell(m.clone()), o, Instant::now(), &mut |_| {}).unwrap()
        };
        let exact = run(&opts);
        assert_eq!(exact.len(), 10);
        let names: Vec<String> = exact
            .iter()
            .map(|t| t.curve.display().to_string())
            .collect();
        assert_eq!(
            names[..4],
            ["warp-1.csv", "warp-2.csv", "weft-1.csv", "weft-2.csv"]
        );
        assert_eq!(
            names[6..],
            ["a22.5-1.csv", "a22.5-2.csv", "a67.5-1.csv", "a67.5-2.csv"]
        );
        let mut strip = crate::scene::TensileStrip::new(0.05, 0.075, 90.0);
        strip.mesh = (2, 3);
        strip.grading = opts.grading;
        let direct: Vec<f64> = strip
            .run(&m, &[0.0025, 0.005, 0.0075])
            .unwrap()
            .iter()
            .map(|p| p.force)
            .collect();
        assert_eq!(exact[0].force, direct);
        assert_eq!(exact[1].force, direct);
        assert_eq!(exact[0].elongation, vec![0.0025, 0.005, 0.0075]);
        let noisy = SynthOptions {
            noise: 0.05,
            misalign_deg: 2.0,
            seed: 9,
            ..opts.clone()
        };
        let a = run(&noisy);
        assert_eq!(a, run(&noisy), "same seed, same data");
        assert_ne!(
            a,
            run(&SynthOptions {
                seed: 10,
                ..noisy.clone()
            })
        );
        for (t, e) in a.iter().zip(&exact) {
            assert_eq!(t.angle_deg, e.angle_deg, "the nominal angle is recorded");
            assert_ne!(t.force, e.force);
            for (f, g) in t.force.iter().zip(&e.force) {
                assert!((f / g - 1.0).abs() < 0.5, "{f} {g}");
            }
        }
        assert_ne!(a[0].force, a[1].force, "repeats differ");
    }

    #[test]
    fn options_are_checked() {
        let base = SynthOptions::default();
        for (opts, want) in [
            (
                SynthOptions {
                    points: 0,
                    ..base.clone()
                },
                "points",
            ),
            (
                SynthOptions {
                    repeats: 0,
                    ..base.clone()
                },
                "repeats",
            ),
            (
                SynthOptions {
                    max_strain: 0.0,
                    ..base.clone()
                },
                "max strain",
            ),
            (
                SynthOptions {
                    max_strain: 1.5,
                    ..base.clone()
                },
                "max strain",
            ),
            (
                SynthOptions {
                    noise: -0.1,
                    ..base.clone()
                },
                "noise",
            ),
            (
                SynthOptions {
                    noise: f64::NAN,
                    ..base.clone()
                },
                "noise",
            ),
            (
                SynthOptions {
                    misalign_deg: f64::INFINITY,
                    ..base.clone()
                },
                "misalignment",
            ),
            (
                SynthOptions {
                    mesh: (0, 4),
                    ..base.clone()
                },
                "the strip mesh",
            ),
            (
                SynthOptions {
                    extra_angles: vec![15.0, 45.0],
                    ..base.clone()
                },
                "each extra tensile angle",
            ),
            (
                SynthOptions {
                    extra_angles: vec![15.0, 95.0],
                    ..base.clone()
                },
                "each extra tensile angle",
            ),
            (
                SynthOptions {
                    extra_angles: vec![30.0, 30.0],
                    ..base.clone()
                },
                "each extra tensile angle",
            ),
        ] {
            let e = opts.check().unwrap_err().to_string();
            assert!(e.starts_with(want), "{e}");
        }
        assert!(base.check().is_ok());
    }
}
