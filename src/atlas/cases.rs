//! The hard problems of the atlas, and running one with one method.

use super::{table, Method, Row};
use crate::material::{Cutoffs, Eta, FabricMaterial, Orthotropic, OrthotropicStvk};
use crate::scene::{CantileverBend, CornerPull, Drape, PictureFrame, SceneError, TensileStrip};
use crate::solve::SolveReport;
use std::time::Instant;

/// One hard problem.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Case {
    /// 45° strip of a stiffening law (degree 3), pulled to 30 % strain in three steps.
    BiasStiffening30,
    /// 90 mm cantilever of a stiff law (a11 = 1e8 Pa, τ = 0.2 mm), its whole weight brought on
    /// as the strategy chooses.
    CantileverFullGravity,
    /// The heavy ASTM D1388 cantilever (25 × 47.7349 mm, τ = 0.2 mm, a11 = a22 = 2e7 Pa,
    /// 100 g/m²: overhang twice the bending length, chord angle 41.4873°).
    HeavyD1388,
    /// τ = 0.05 mm, a11 = 1e9 Pa and a11 / G12 = 10^`exponent`, bias strip to 5 % in one step:
    /// the strip wrinkles.
    SoftShear { exponent: u8 },
    /// Warp strip of the stiffening law pushed 2 % shorter in two steps: it buckles out of
    /// its plane (the flat state is a saddle).
    Compression,
    /// Warp strip to 20 % whose strain crosses the 5 % cut-off during the solve.
    CutoffCrossing,
    /// The heavy D1388 cantilever made thin: τ = `tau_um` µm with a11 scaled by (200/τ)³ so
    /// that the bending rigidity, and so the answer (41.4873°), stay those of [`Case::HeavyD1388`]
    /// while the membrane-to-bending stiffness ratio 12 L²/τ² grows 100-fold per decade of τ
    /// (20 µm: a11 = 2e10 Pa, the order of aramid or glass yarns, about the thinnest fabric;
    /// 5 µm: 1.3e12 Pa, past any fabric). Where f64 refinement stops being enough, if anywhere.
    ThinD1388 { tau_um: u16 },
    /// The paper's drape (Figure 1) of the stiffening material: a 1 m sheet hanging from two
    /// corners brought 60 cm apart in eight steps; it buckles and folds at every step.
    Drape,
    /// The picture frame (Figure 5) sheared to 40° in eight steps: the sheet wrinkles.
    PictureFrame,
    /// The corner pull (Figure 5) to 10 % of the diagonal in eight steps: diagonal wrinkles.
    CornerPull,
    /// A bias-extension sample of nearly inextensible yarns: 150 × 450 mm at 45°, a11 = a22 =
    /// 1e10 Pa (glass or aramid weaves), G12 = 3e4 Pa, τ = 0.3 mm, pulled 20 mm in one step on
    /// graded cages. Yarns at 45° to the cage cannot shear freely: the force locks on coarse
    /// meshes (`paper_repro/convergence/stiff_bias`) and the solve is stiff (a11 / G12 ≈ 3e5).
    StiffYarnBias,
}

impl Case {
    pub fn all() -> Vec<Case> {
        vec![
            Case::BiasStiffening30,
            Case::CantileverFullGravity,
            Case::HeavyD1388,
            Case::SoftShear { exponent: 4 },
            Case::SoftShear { exponent: 5 },
            Case::SoftShear { exponent: 6 },
            Case::Compression,
            Case::CutoffCrossing,
            Case::ThinD1388 { tau_um: 20 },
            Case::ThinD1388 { tau_um: 5 },
            Case::Drape,
            Case::PictureFrame,
            Case::CornerPull,
            Case::StiffYarnBias,
        ]
    }

    /// Cases past any woven fabric (kept to show where methods fail): a strategy may fail
    /// them; the atlas test asks only the default strategy to solve them.
    pub fn beyond_fabrics(&self) -> bool {
        matches!(self, Case::ThinD1388 { tau_um } if *tau_um < 10)
    }

    pub fn name(&self) -> String {
        match self {
            Case::BiasStiffening30 => "bias strip, degree-3 stiffening law, to 30 %".into(),
            Case::CantileverFullGravity => "cantilever 90 mm, stiff law, full gravity".into(),
            Case::HeavyD1388 => "heavy D1388 cantilever (overhang 2c)".into(),
            Case::SoftShear { exponent } => {
                format!("thin (0.05 mm), a11/G12 = 1e{exponent}, bias to 5 %")
            }
            Case::Compression => "warp strip compressed 2 % (buckles)".into(),
            Case::CutoffCrossing => "warp strip crossing its 5 % cut-off, to 20 %".into(),
            Case::ThinD1388 { tau_um } => {
                format!("heavy D1388 cantilever, τ = {tau_um} µm (same rigidity)")
            }
            Case::Drape => "drape, 1 m sheet, corners to 60 cm".into(),
            Case::PictureFrame => "picture frame, 10 cm, sheared to 40°".into(),
            Case::CornerPull => "corner pull, 10 cm, to 10 %".into(),
            Case::StiffYarnBias => "bias extension, stiff yarns (1e10 Pa), 150 × 450 mm".into(),
        }
    }

    /// A short label for charts.
    pub fn label(&self) -> String {
        match self {
            Case::BiasStiffening30 => "bias 30 %".into(),
            Case::CantileverFullGravity => "cantilever".into(),
            Case::HeavyD1388 => "D1388 heavy".into(),
            Case::SoftShear { exponent } => format!("G12 1e-{exponent}"),
            Case::Compression => "compression".into(),
            Case::CutoffCrossing => "cut-off".into(),
            Case::ThinD1388 { tau_um } => format!("D1388 {tau_um} µm"),
            Case::Drape => "drape".into(),
            Case::PictureFrame => "frame".into(),
            Case::CornerPull => "corner".into(),
            Case::StiffYarnBias => "stiff yarns".into(),
        }
    }

    /// Runs this case with one method; `reduced` uses coarse meshes (for CI).
    pub fn run(&self, method: &Method, reduced: bool) -> Row {
        let t0 = Instant::now();
        let mut row = Row {
            case: *self,
            method: method.name,
            converged: false,
            residual: f64::NAN,
            iterations: 0,
            factorizations: 0,
            load_steps: 0,
            backward_euler_steps: 0,
            refinement_steps: 0,
            stable: false,
            saddle_escapes: 0,
            seconds: 0.0,
            drape_angle_deg: None,
            note: String::new(),
        };
        let mut fallbacks = Vec::new();
        let outcome = match self {
            Case::CantileverFullGravity | Case::HeavyD1388 | Case::ThinD1388 { .. } => {
                self.cantilever(method, reduced, &mut row, &mut fallbacks)
            }
            Case::Drape | Case::PictureFrame | Case::CornerPull => {
                self.sheet(method, reduced, &mut row, &mut fallbacks)
            }
            _ => self.strip(method, reduced, &mut row, &mut fallbacks),
        };
        row.seconds = t0.elapsed().as_secs_f64();
        match outcome {
            Ok(()) => {
                row.converged = true;
                row.note = table::what_happened(&row, &fallbacks);
            }
            Err(e) => row.note = table::explain(&e),
        }
        row
    }

    fn strip(
        &self,
        method: &Method,
        reduced: bool,
        row: &mut Row,
        fallbacks: &mut Vec<SolveReport>,
    ) -> Result<(), SceneError> {
        let mut size = (0.05, 0.075);
        let (material, angle, strains): (FabricMaterial, f64, Vec<f64>) = match *self {
            Case::BiasStiffening30 => (stiffening(), 45.0, vec![0.1, 0.2, 0.3]),
            Case::StiffYarnBias => {
                size = (0.15, 0.45);
                let mut m = stiffening();
                m.thickness = 3.0e-4;
                m.areal_density = 0.3;
                m.law = Orthotropic::from(OrthotropicStvk {
                    a11: 1.0e10,
                    a22: 1.0e10,
                    a12: 0.0,
                    g12: 3.0e4,
                });
                (m, 45.0, vec![0.02 / 0.45])
            }
            Case::SoftShear { exponent } => {
                let mut m = stiffening();
                m.thickness = 5.0e-5;
                m.law = Orthotropic::from(OrthotropicStvk {
                    a11: 1.0e9,
                    a22: 1.0e8,
                    a12: 1.0e7,
                    g12: 1.0e9 / 10f64.powi(exponent as i32),
                });
                (m, 45.0, vec![0.05])
            }
            Case::Compression => (stiffening(), 90.0, vec![-0.01, -0.02]),
            _ => {
                let mut m = stiffening();
                m.law.cutoffs = Cutoffs {
                    e11: (0.0, 0.05),
                    e22: (0.0, 0.05),
                    e12: (-0.05, 0.05),
                };
                (m, 90.0, vec![0.2])
            }
        };
        let mut strip = TensileStrip::new(size.0, size.1, angle);
        strip.mesh = match (self, reduced) {
            (Case::StiffYarnBias, true) => (4, 12),
            (Case::StiffYarnBias, false) => (16, 48),
            (_, true) => (4, 6),
            (_, false) => (16, 24),
        };
        if *self == Case::StiffYarnBias {
            strip.grading = crate::scene::STRIP_GRADING;
        }
        strip.solver = method.options;
        let dl: Vec<f64> = strains.iter().map(|s| s * size.1).collect();
        let curve = strip.run(&material, &dl)?;
        row.load_steps = curve.len();
        for p in curve {
            absorb(row, &p.report);
            fallbacks.push(p.report);
        }
        Ok(())
    }

    fn cantilever(
        &self,
        method: &Method,
        reduced: bool,
        row: &mut Row,
        fallbacks: &mut Vec<SolveReport>,
    ) -> Result<(), SceneError> {
        let heavy = match self {
            Case::HeavyD1388 => Some(200.0),
            Case::ThinD1388 { tau_um } => Some(f64::from(*tau_um)),
            _ => None,
        };
        let (m, mut bend) = if let Some(tau_um) = heavy {
            // the same rigidity a11 τ³/12 as at τ = 200 µm, a11 = 2e7 Pa
            let a11 = 2.0e7 * (200.0 / tau_um).powi(3);
            let m = FabricMaterial {
                name: "heavy".into(),
                areal_density: 0.1,
                thickness: tau_um * 1e-6,
                law: Orthotropic::from(OrthotropicStvk {
                    a11,
                    a22: a11,
                    a12: 0.0,
                    g12: 0.5 * a11,
                }),
                bending: None,
            };
            let mut bend = CantileverBend::new(0.025, 0.0477349, 90.0);
            bend.mesh = if reduced { (4, 8) } else { (4, 16) };
            (m, bend)
        } else {
            let mut m = stiffening();
            m.law = Orthotropic::from(OrthotropicStvk {
                a11: 1.0e8,
                a22: 6.0e7,
                a12: 0.0,
                g12: 1.5e6,
            });
            let mut bend = CantileverBend::new(0.025, 0.09, 90.0);
            bend.mesh = if reduced { (4, 12) } else { (4, 32) };
            (m, bend)
        };
        bend.solver = method.options;
        let r = bend.run(&m)?;
        absorb(row, &r.report);
        // the continuation's totals over every load step and failed attempt
        row.iterations = r.iterations;
        row.factorizations = r.factorizations;
        row.load_steps = r.load_steps;
        row.drape_angle_deg = Some(r.drape_angle_deg);
        fallbacks.push(r.report);
        Ok(())
    }
}

impl Case {
    /// The showcase scenes on the stiffening material (`reduced`: 8 × 8, 10 × 10 for the
    /// corner pull; else twice as fine).
    fn sheet(
        &self,
        method: &Method,
        reduced: bool,
        row: &mut Row,
        fallbacks: &mut Vec<SolveReport>,
    ) -> Result<(), SceneError> {
        let m = stiffening();
        let k = if reduced { 1 } else { 2 };
        let deformed = match self {
            Case::Drape => {
                let d = Drape {
                    mesh: 8 * k,
                    solver: method.options,
                    ..Drape::new()
                };
                d.run(&m)?.1
            }
            Case::PictureFrame => {
                let f = PictureFrame {
                    mesh: 8 * k,
                    solver: method.options,
                    ..PictureFrame::new(0.1, 40.0)
                };
                f.run(&m)?.1
            }
            _ => {
                let c = CornerPull {
                    mesh: 10 * k,
                    solver: method.options,
                    ..CornerPull::new(0.1, 0.1)
                };
                c.run(&m)?.1
            }
        };
        let c = &deformed.counts;
        row.iterations = c.iterations;
        row.factorizations = c.factorizations;
        row.load_steps = c.steps;
        row.backward_euler_steps = c.backward_euler_steps;
        row.saddle_escapes = c.saddle_escapes;
        row.stable = deformed.stable;
        row.residual = deformed.last.residual;
        row.refinement_steps = deformed.last.refinement_steps;
        // every kept solve's reasons for backward Euler, on the last solve's report
        fallbacks.push(SolveReport {
            fallbacks: c.fallbacks.clone(),
            curvature_steps: c.curvature_steps,
            convexified_steps: c.convexified_steps,
            ..deformed.last.clone()
        });
        Ok(())
    }
}

/// Adds one solve's counts to a row.
fn absorb(row: &mut Row, r: &SolveReport) {
    row.residual = r.residual;
    row.iterations += r.iterations;
    row.factorizations += r.factorizations;
    row.backward_euler_steps += r.backward_euler_steps;
    row.refinement_steps += r.refinement_steps;
    row.saddle_escapes += r.saddle_escapes;
    row.stable = r.stable;
}

/// The atlas's stiffening material: a degree-3 η (μ 0.6, 0.3, 0.1; α 1, 6, 14) in every
/// direction, a11 = 1e8 Pa, τ = 0.2 mm, 150 g/m².
pub fn stiffening() -> FabricMaterial {
    let stiff = Eta {
        mu: vec![0.6, 0.3, 0.1],
        alpha: vec![1.0, 6.0, 14.0],
    };
    FabricMaterial {
        name: "stiffening".into(),
        areal_density: 0.15,
        thickness: 2.0e-4,
        law: Orthotropic {
            a11: 1.0e8,
            a22: 6.0e7,
            a12: 1.0e7,
            g12: 1.5e6,
            warp: stiff.clone(),
            weft: stiff.clone(),
            shear: stiff,
            cutoffs: Cutoffs::none(),
            coupling: None,
        },
        bending: None,
    }
}
