//! Speed against accuracy across cloth models (the user's request, which none of the three
//! papers answers): one lab test run by the shell and by each triangle model on a ladder of
//! meshes, each run's wall time (median of several) and its error against the converged shell
//! (Richardson extrapolation over the shell's ladder), and the cheapest run whose error meets a
//! tolerance. Used by `ks-fit recommend` and `examples/model_chart.rs`.

use crate::converge::{analyse, Level};
use crate::material::FabricMaterial;
use crate::scene::{CantileverBend, CornerPull, Drape, PictureFrame, TensileStrip};
use crate::scene::{TriCantilever, TriTensile};
use crate::solve::NewtonOptions;
use crate::tri::file::SPRING_CURVATURE;
use crate::tri::{TriKind, TriMaterial};
use std::time::Instant;

/// Faces (across, along) of one mesh.
pub type Mesh = (usize, usize);

/// The test whose quantity is compared.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LabTest {
    /// A strip's force (N) at `elongation`; lengths in m, angle from the weft in degrees.
    Tensile {
        angle_deg: f64,
        width: f64,
        length: f64,
        elongation: f64,
    },
    /// A D1388 cantilever's drape angle (degrees).
    Bend {
        angle_deg: f64,
        width: f64,
        overhang: f64,
    },
    /// The picture frame's shear force (N) at `shear_deg` on a square of `side` m
    /// ([`PictureFrame`], free to wrinkle, 8 steps).
    Frame { shear_deg: f64, side: f64 },
    /// The corner pull's force (N) at `stretch` (a fraction of the diagonal) on a square of
    /// `side` m ([`CornerPull`], 8 steps).
    Corner { stretch: f64, side: f64 },
    /// The drape's mean drop (mm): how far the centre of mass of a square of `side` m, hung
    /// from two corners brought `span` m apart, hangs below them ([`Drape`], 8 steps; see
    /// [`crate::scene::DrapeShape::mean_drop`]). The drape folds differently on different
    /// meshes and models (several stable equilibria), so its fold depth has no converged
    /// value; the mean drop, its potential energy per unit weight, is the measure its branches
    /// share.
    Drape { side: f64, span: f64 },
}

/// Iterations allowed per solve of a showcase scene (as `ks-fit scene`): wrinkling sheets
/// spend long stretches in backward-Euler relaxation.
const SCENE_ITERATIONS: usize = 500;

fn scene_solver() -> NewtonOptions {
    NewtonOptions {
        max_iterations: SCENE_ITERATIONS,
        ..NewtonOptions::default()
    }
}

/// One run of one model on one mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// `kl` or a triangle model's name.
    pub model: &'static str,
    /// "fitted", "converted" or "shell".
    pub params: &'static str,
    pub mesh: (usize, usize),
    /// Median wall time, s.
    pub seconds: f64,
    pub value: f64,
    /// |value − reference| / |reference|.
    pub error: f64,
}

/// Every run and the reference they are measured against.
#[derive(Clone, Debug)]
pub struct Comparison {
    pub test: LabTest,
    pub reference: f64,
    /// How the reference was found.
    pub reference_from: String,
    pub runs: Vec<Run>,
    /// Runs that failed, one line each.
    pub failures: Vec<String>,
}

impl Comparison {
    /// The cheapest run whose error is at most `tol`.
    pub fn cheapest_within(&self, tol: f64) -> Option<&Run> {
        self.runs
            .iter()
            .filter(|r| r.error <= tol)
            .min_by(|a, b| a.seconds.total_cmp(&b.seconds))
    }
}

/// Median time of `repeats` runs of `f` and its value (None when a run fails).
fn timed(repeats: usize, mut f: impl FnMut() -> Result<f64, String>) -> Result<(f64, f64), String> {
    let mut times = Vec::new();
    let mut value = 0.0;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        value = f()?;
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    Ok((times[times.len() / 2], value))
}

impl LabTest {
    /// The mesh ladder every model runs: three meshes, each twice as fine.
    pub fn meshes(&self) -> Vec<(usize, usize)> {
        let base = match *self {
            LabTest::Tensile { .. } => (8, 12),
            LabTest::Bend {
                width,
                overhang,
                angle_deg,
            } => CantileverBend::new(width, overhang, angle_deg).mesh,
            LabTest::Frame { .. } => (8, 8),
            // the clips (a tenth of the side) on cage lines
            LabTest::Corner { .. } => (10, 10),
            LabTest::Drape { .. } => (8, 8),
        };
        (0..3).map(|k| (base.0 << k, base.1 << k)).collect()
    }

    /// The shell's ladder: [`LabTest::meshes`], and for the drape one more, 48², whose value
    /// is the reference (a 1 m sheet of the example cotton locks into an arch on 8² and 16²
    /// and forms the cowl of Clyde et al.'s Figure 1 from 32²; 32² and 48² fold differently
    /// and agree in the mean drop to 0.04 %; a 48² triangle model costs minutes).
    pub fn shell_meshes(&self) -> Vec<(usize, usize)> {
        let mut m = self.meshes();
        if matches!(self, LabTest::Drape { .. }) {
            m.push((48, 48));
        }
        m
    }

    fn run_shell(&self, m: &FabricMaterial, mesh: (usize, usize)) -> Result<f64, String> {
        match *self {
            LabTest::Tensile {
                angle_deg,
                width,
                length,
                elongation,
            } => {
                let mut s = TensileStrip::new(width, length, angle_deg);
                s.mesh = mesh;
                let p = s.run(m, &[elongation]).map_err(|e| e.to_string())?;
                Ok(p[0].force)
            }
            LabTest::Bend {
                angle_deg,
                width,
                overhang,
            } => {
                let mut b = CantileverBend::new(width, overhang, angle_deg);
                b.mesh = mesh;
                Ok(b.run(m).map_err(|e| e.to_string())?.drape_angle_deg)
            }
            LabTest::Frame { .. } => {
                let (p, _) = self.frame(mesh).run(m).map_err(|e| e.to_string())?;
                Ok(p.last().map_or(f64::NAN, |p| p.shear_force))
            }
            LabTest::Corner { .. } => {
                let (p, _) = self.corner(mesh).run(m).map_err(|e| e.to_string())?;
                Ok(p.last().map_or(f64::NAN, |p| p.force))
            }
            LabTest::Drape { .. } => {
                let (s, _) = self.drape(mesh).run(m).map_err(|e| e.to_string())?;
                Ok(s.mean_drop * 1e3)
            }
        }
    }

    fn drape(&self, mesh: (usize, usize)) -> Drape {
        let LabTest::Drape { side, span } = *self else {
            unreachable!("a drape")
        };
        Drape {
            side,
            span,
            mesh: mesh.0,
            solver: scene_solver(),
            ..Drape::new()
        }
    }

    fn frame(&self, mesh: (usize, usize)) -> PictureFrame {
        let LabTest::Frame { shear_deg, side } = *self else {
            unreachable!("a frame test")
        };
        PictureFrame {
            mesh: mesh.0,
            solver: scene_solver(),
            ..PictureFrame::new(side, shear_deg)
        }
    }

    fn corner(&self, mesh: (usize, usize)) -> CornerPull {
        let LabTest::Corner { stretch, side } = *self else {
            unreachable!("a corner-pull test")
        };
        CornerPull {
            mesh: mesh.0,
            solver: scene_solver(),
            ..CornerPull::new(side, stretch)
        }
    }

    fn run_tri(&self, t: &TriMaterial, mesh: (usize, usize)) -> Result<f64, String> {
        match *self {
            LabTest::Tensile {
                angle_deg,
                width,
                length,
                elongation,
            } => {
                let mut s = TriTensile::new(width, length, angle_deg);
                s.mesh = mesh;
                let p = s.run(t, &[elongation]).map_err(|e| e.to_string())?;
                Ok(p[0].force)
            }
            LabTest::Bend {
                angle_deg,
                width,
                overhang,
            } => {
                let mut c = TriCantilever::new(width, overhang, angle_deg);
                c.mesh = mesh;
                Ok(c.run(t).map_err(|e| e.to_string())?.drape_angle_deg)
            }
            LabTest::Frame { .. } => {
                let (p, _) = self.frame(mesh).run_tri(t).map_err(|e| e.to_string())?;
                Ok(p.last().map_or(f64::NAN, |p| p.shear_force))
            }
            LabTest::Corner { .. } => {
                let (p, _) = self.corner(mesh).run_tri(t).map_err(|e| e.to_string())?;
                Ok(p.last().map_or(f64::NAN, |p| p.force))
            }
            LabTest::Drape { .. } => {
                let (s, _) = self.drape(mesh).run_tri(t).map_err(|e| e.to_string())?;
                Ok(s.mean_drop * 1e3)
            }
        }
    }

    /// The size across that the faces across divide (a triangle model's cell size).
    fn width(&self) -> f64 {
        match *self {
            LabTest::Tensile { width, .. } | LabTest::Bend { width, .. } => width,
            LabTest::Frame { side, .. }
            | LabTest::Corner { side, .. }
            | LabTest::Drape { side, .. } => side,
        }
    }
}

/// Runs `test` with the shell material `shell` and with every triangle model (its `fitted`
/// parameters where given, else converted), each on the test's three meshes (the shell also on
/// [`LabTest::shell_meshes`]), `repeats` times.
pub fn compare(
    shell: &FabricMaterial,
    fitted: &[TriMaterial],
    test: LabTest,
    repeats: usize,
    progress: &mut dyn FnMut(&str),
) -> Comparison {
    let ladders = (test.shell_meshes(), test.meshes());
    compare_on(
        shell,
        fitted,
        test,
        (&ladders.0, &ladders.1),
        repeats,
        progress,
    )
}

/// [`compare`] on given ladders (coarse to fine): the shell's, whose levels make the reference
/// (each twice as fine as the last for Richardson's extrapolation, except for the drape), and
/// the triangle models'.
pub fn compare_on(
    shell: &FabricMaterial,
    fitted: &[TriMaterial],
    test: LabTest,
    (shell_meshes, meshes): (&[Mesh], &[Mesh]),
    repeats: usize,
    progress: &mut dyn FnMut(&str),
) -> Comparison {
    let mut raw: Vec<Run> = Vec::new();
    let mut failures = Vec::new();
    for &mesh in shell_meshes {
        match timed(repeats, || test.run_shell(shell, mesh)) {
            Ok((seconds, value)) => raw.push(Run {
                model: "kl",
                params: "shell",
                mesh,
                seconds,
                value,
                error: f64::NAN,
            }),
            Err(e) => failures.push(format!("kl on {}x{}: {e}", mesh.0, mesh.1)),
        }
        progress(&format!("kl on {}x{}", mesh.0, mesh.1));
    }
    for (name, kind) in TriKind::ALL {
        let given = fitted.iter().find(|t| t.kind == kind);
        for &mesh in meshes {
            let params = match given {
                Some(t) => Ok((t.clone(), "fitted")),
                None => TriMaterial::equivalent(
                    kind,
                    shell,
                    test.width() / mesh.0 as f64,
                    SPRING_CURVATURE,
                )
                .map(|t| (t, "converted")),
            };
            let r = params.and_then(|(t, how)| {
                timed(repeats, || test.run_tri(&t, mesh)).map(|(s, v)| (s, v, how))
            });
            match r {
                Ok((seconds, value, params)) => raw.push(Run {
                    model: name,
                    params,
                    mesh,
                    seconds,
                    value,
                    error: f64::NAN,
                }),
                Err(e) => failures.push(format!("{name} on {}x{}: {e}", mesh.0, mesh.1)),
            }
            progress(&format!("{name} on {}x{}", mesh.0, mesh.1));
        }
    }
    let shell_levels: Vec<Level> = raw
        .iter()
        .filter(|r| r.model == "kl")
        .map(|r| Level::solved(r.mesh, 0, r.seconds, r.value))
        .collect();
    let (reference, reference_from) = reference(test, shell_levels);
    let runs = raw
        .into_iter()
        .map(|r| Run {
            error: (r.value - reference).abs() / reference.abs(),
            ..r
        })
        .collect();
    Comparison {
        test,
        reference,
        reference_from,
        runs,
        failures,
    }
}

/// The reference value of the shell's `levels` (coarse to fine) and how it was found:
/// Richardson's extrapolation where the ladder converges monotonically, else the finest level
/// (with how far the next coarser level lies). The drape's levels fold differently and are not
/// each twice as fine: its reference is always the finest.
fn reference(test: LabTest, levels: Vec<Level>) -> (f64, String) {
    let n = levels.len();
    let finest = levels.last().map(|l| (l.qoi, l.mesh));
    let before = levels
        .len()
        .checked_sub(2)
        .map(|i| (levels[i].qoi, levels[i].mesh));
    let spread = |v: f64| match before {
        Some((q, m)) => format!(
            "; {}x{} within {:.3} % of it",
            m.0,
            m.1,
            100.0 * ((q - v) / v).abs()
        ),
        None => String::new(),
    };
    let drape = matches!(test, LabTest::Drape { .. });
    let extrapolated = if drape {
        None
    } else {
        analyse(levels).extrapolated
    };
    match (extrapolated, finest) {
        (Some(v), _) => (
            v,
            format!(
                "the shell's Richardson extrapolation over its {}three meshes",
                if n > 3 { "finest " } else { "" }
            ),
        ),
        (None, Some((v, m))) if drape => (
            v,
            format!(
                "the shell on {}x{} (the meshes fold differently, so no extrapolation{})",
                m.0,
                m.1,
                spread(v)
            ),
        ),
        (None, Some((v, m))) => (
            v,
            format!(
                "the shell on {}x{} ({}: no extrapolation{})",
                m.0,
                m.1,
                if n < 3 {
                    "fewer than three meshes"
                } else {
                    "its ladder does not converge monotonically"
                },
                spread(v)
            ),
        ),
        (None, None) => (f64::NAN, "none: the shell failed".to_string()),
    }
}
