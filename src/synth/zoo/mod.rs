//! The fabric zoo: plausible woven fabrics drawn at random, and datasets drawn the way labs
//! make them, to test the fitter on data it was not developed on.
//!
//! Every fabric is drawn from its own random stream (the zoo's seed and its index), so the
//! first N fabrics of a zoo do not depend on how many are drawn. Even indices are **law**
//! fabrics: a material of the paper's law ([`draw_material`]) whose curves and bends the
//! virtual lab measures ([`build`]), so the fit can be checked against the truth; one in four
//! of them is measured by a triangle model of the same material instead of the shell (data
//! another discretisation made: its own mesh, energy, bending and Poisson behaviour). Odd indices
//! are **analytic** fabrics: curves of families a lab sees that the law did not make
//! ([`curves::Family`]) and cantilever overhangs from ASTM D1388's bending length, so the fit
//! shows what it does with a model that does not match. The ranges are written beside each
//! draw and in `paper_repro/zoo/README.md`, with their sources.

mod build;
pub mod curves;

pub use build::{build, LabMesh, ZooDataset, STRIP_TOL};

use super::Rng;
use crate::material::{BendingRigidity, Eta, FabricMaterial, Orthotropic, OrthotropicStvk};
use crate::tri::TriKind;
use curves::Family;

/// How a curve's forces are written.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Export {
    /// `elongation_mm,force_n`
    Newtons,
    /// a machine's header with units, forces in kN
    KiloNewtonsHeader,
    /// forces in kN under a header without units, with `force_scale = 1000` in the dataset
    KiloNewtonsScaled,
}

/// How the lab tested one fabric.
#[derive(Clone, Debug, PartialEq)]
pub struct Protocol {
    /// tensile angles, degrees from the weft
    pub angles: Vec<f64>,
    pub repeats: usize,
    /// points per curve as written
    pub points: usize,
    /// largest engineering strain
    pub max_strain: f64,
    /// strip width and gauge length, m
    pub strip: (f64, f64),
    /// relative standard deviation of each repeat's force scale
    pub scale_noise: f64,
    /// relative standard deviation of each point's force
    pub point_noise: f64,
    /// standard deviation of each repeat's cut angle, degrees
    pub misalign_deg: f64,
    /// slack before the strip carries load, m (0: none)
    pub slack: f64,
    /// elongation already applied when the record starts (a preload), m (0: none)
    pub preload: f64,
    pub export: Export,
    /// warp and weft cantilevers
    pub bends: bool,
    /// only a bias-extension sample, with the yarn stiffnesses given in `[known]`
    pub bias_only: bool,
}

impl Protocol {
    /// The same tests without the lab's artefacts: no noise, scatter, misalignment, slack or
    /// preload, forces in newtons (the truth-recovery study).
    pub fn clean(&self) -> Protocol {
        Protocol {
            scale_noise: 0.0,
            point_noise: 0.0,
            misalign_deg: 0.0,
            slack: 0.0,
            preload: 0.0,
            export: Export::Newtons,
            repeats: 1,
            ..self.clone()
        }
    }
}

/// What made a fabric's curves.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// the paper's law, measured by the virtual lab
    Law(FabricMaterial),
    /// analytic curves: one family per tensile angle, rigidities (N·m) for the bends
    Analytic {
        warp: Family,
        weft: Family,
        bias: Family,
        areal_density: f64,
        thickness: f64,
        bending: (f64, f64),
    },
}

/// One fabric of the zoo.
#[derive(Clone, Debug, PartialEq)]
pub struct ZooFabric {
    pub name: String,
    pub source: Source,
    pub protocol: Protocol,
    /// the triangle model that measures a law fabric (`None`: the shell)
    pub lab: Option<TriKind>,
}

/// Extra tensile angles a lab may add to warp, weft and bias, degrees from the weft.
const EXTRA_ANGLES: [f64; 6] = [15.0, 22.5, 30.0, 60.0, 67.5, 75.0];

/// Least shear stiffness per width G12·τ, N/m: a 50 mm bias strip at 10 % strain then carries
/// about 0.2 N (the softest shear the fitter is asked to take: yarn-to-shear ratios of 1e4 on
/// soft yarns carry 0.45 N there).
const MIN_SHEAR: f64 = 10.0;

/// Tension per width at which a strip breaks, N/m: apparel wovens 5–20 kN/m, technical
/// fabrics to 40 kN/m; the lab pulls no further than the stronger yarn's tension (of its own
/// law, stiffening included) reaches it.
const BREAK_TENSION: (f64, f64) = (5e3, 4e4);

/// Standard gravity, m/s² (the bending length's weight).
const G: f64 = 9.806_65;

impl Rng {
    /// Uniform in [lo, hi).
    fn between(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (1.0 - self.uniform())
    }

    /// Log-uniform in [lo, hi).
    fn log_between(&mut self, lo: f64, hi: f64) -> f64 {
        self.between(lo.ln(), hi.ln()).exp()
    }

    /// True with probability `p`.
    fn chance(&mut self, p: f64) -> bool {
        self.uniform() <= p
    }

    /// An integer in lo..=hi.
    fn int(&mut self, lo: usize, hi: usize) -> usize {
        lo + ((self.uniform() * (hi - lo + 1) as f64).ceil() as usize).clamp(1, hi - lo + 1) - 1
    }
}

/// The zoo's fabric number `index` for `seed`.
pub fn draw(seed: u64, index: usize) -> ZooFabric {
    let mut rng = Rng(seed ^ (index as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    for _ in 0..4 {
        rng.next_u64();
    }
    let law = index % 2 == 0;
    let source = if law {
        Source::Law(draw_material(&mut rng, &format!("zoo-{index:04}")))
    } else {
        draw_analytic(&mut rng)
    };
    let protocol = draw_protocol(&mut rng, law, &|e| yarn_tension(&source, e));
    let lab = (law && index % 8 == 6).then(|| TriKind::ALL[rng.int(0, 3)].1);
    let kind = match (law, lab) {
        (true, None) => "law",
        (true, Some(k)) => k.name(),
        (false, _) => "analytic",
    };
    ZooFabric {
        name: format!("z{index:04}-{kind}"),
        source,
        protocol,
        lab,
    }
}

/// Tension per width (N/m) of the stronger yarn at engineering strain `e` along it: the law's
/// first Piola stress (1 + e)·S(Ẽ) at Ẽ = e + e²/2 alone, times the thickness (a bound on what
/// the strip carries: its other strains stay near zero), or the analytic family's own.
fn yarn_tension(source: &Source, e: f64) -> f64 {
    match source {
        Source::Law(m) => {
            let g = e + 0.5 * e * e;
            let along = |k: usize| {
                let mut strain = nalgebra::Vector3::zeros();
                strain[k] = g;
                crate::material::Law::response(&m.law, &strain)
                    .map_or(f64::INFINITY, |r| r.stress[k])
            };
            (1.0 + e) * along(0).max(along(1)) * m.thickness
        }
        Source::Analytic { warp, weft, .. } => warp.force(1.0, e).max(weft.force(1.0, e)),
    }
}

/// The largest strain in (0, `cap`] at which `tension` stays within `limit` (bisection; the
/// tension rises with the strain).
fn strain_at_tension(tension: &dyn Fn(f64) -> f64, limit: f64, cap: f64) -> f64 {
    if tension(cap) <= limit {
        return cap;
    }
    let (mut lo, mut hi) = (0.0, cap);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if tension(mid) <= limit {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Membrane stiffnesses per width (N/m) of the stronger yarn, the weaker yarn and the shear.
fn draw_stiffnesses(rng: &mut Rng) -> (f64, f64, f64) {
    // E1·τ: 2e3 N/m (soft apparel wovens, a tenth of the bundled cotton's 3.6e4) to 2e6 N/m
    // (a 300 g/m² E-glass weave: 150 g/m² of fibre a direction / 2540 kg/m³ × 72 GPa is
    // 4e6 N/m straight, about half of it through the crimp)
    let e1 = rng.log_between(2e3, 2e6);
    // warp/weft ratio 0.2–5
    let e2 = e1 / rng.log_between(0.2, 5.0);
    // yarn-to-shear ratio 10–1e5, with G12·τ at least [`MIN_SHEAR`]
    let top = e1.max(e2);
    let g = top / rng.log_between(10.0, (top / MIN_SHEAR).clamp(10.0, 1e5));
    (e1, e2, g)
}

/// A material of the paper's law (Clyde et al. 2017, Eq. 2) with its own bending.
fn draw_material(rng: &mut Rng, name: &str) -> FabricMaterial {
    let (e1, e2, g) = draw_stiffnesses(rng);
    // thickness 0.08–1.3 mm (silk charmeuse 0.18 mm to wool coating 1.28 mm in Clyde et al.
    // 2017, Table 2, and thinner)
    let tau = rng.log_between(0.08e-3, 1.3e-3);
    let (a11, a22) = (e1 / tau, e2 / tau);
    // a12 from a slightly negative to a strong Poisson coupling, |a12| < √(a11 a22)
    let a12 = rng.between(-0.1, 0.5) * (a11 * a22).sqrt();
    let mut law: Orthotropic = OrthotropicStvk {
        a11,
        a22,
        a12,
        g12: g / tau,
    }
    .into();
    law.warp = draw_eta(rng, 300.0);
    law.weft = draw_eta(rng, 300.0);
    law.shear = draw_eta(rng, 100.0);
    rising_cutoffs(&mut law);
    let areal_density = draw_density(rng);
    let (warp, weft) = draw_rigidities(rng, areal_density);
    let bending = BendingRigidity::following(warp, weft, &law).ok();
    FabricMaterial {
        name: name.to_string(),
        areal_density,
        thickness: tau,
        law,
        bending,
    }
}

/// Cut-offs at 95 % of the Green strain where a direction's stress stops rising (a softening
/// term can make it stop below 1), past which the law goes on along its tangent: what the
/// material file asks of such a law, so that the truth's file loads and is the lab's law.
fn rising_cutoffs(law: &mut Orthotropic) {
    for (eta, cut) in [
        (&law.warp, &mut law.cutoffs.e11),
        (&law.weft, &mut law.cutoffs.e22),
        (&law.shear, &mut law.cutoffs.e12),
    ] {
        if let Some(peak) = eta.stress_peak(1.0) {
            let to = 0.95 * peak;
            *cut = (cut.0.max(-to), cut.1.min(to));
        }
    }
}

/// Areal density, kg/m²: 50–700 g/m², chiffon to heavy canvas (Clyde et al. 2017's five span
/// 83–481 g/m²).
fn draw_density(rng: &mut Rng) -> f64 {
    rng.log_between(0.05, 0.7)
}

/// Warp and weft flexural rigidities (N·m) from ASTM D1388 bending lengths c of 1.2–6 cm
/// (G = ρ g c³; silk to canvas: the bundled fabrics span 2.5–4.5 cm), the weft's within a
/// factor 1.4 of the warp's length.
fn draw_rigidities(rng: &mut Rng, areal_density: f64) -> (f64, f64) {
    let c = rng.between(0.012, 0.06);
    let c2 = c * rng.log_between(1.0 / 1.4, 1.4);
    let w = areal_density * G;
    (w * c.powi(3), w * c2.powi(3))
}

/// An η of degree 1–4 (Clyde et al. 2017, Eq. 2): weights summing to one, the first term
/// linear, each further term stiffening (α up to `max_alpha`) or, one time in four, softening
/// (α from −30 to −2).
fn draw_eta(rng: &mut Rng, max_alpha: f64) -> Eta {
    let degree = rng.int(1, 4);
    let raw: Vec<f64> = (0..degree).map(|_| rng.between(0.2, 1.0)).collect();
    let total: f64 = raw.iter().sum();
    let mu: Vec<f64> = raw.iter().map(|m| m / total).collect();
    let mut alpha = vec![1.0];
    for _ in 1..degree {
        alpha.push(if rng.chance(0.25) {
            rng.between(-30.0, -2.0)
        } else {
            rng.log_between(2.0, max_alpha)
        });
    }
    Eta { mu, alpha }
}

/// An analytic fabric: each direction's curve from a family drawn at the law fabrics'
/// stiffnesses.
fn draw_analytic(rng: &mut Rng) -> Source {
    let (e1, e2, g) = draw_stiffnesses(rng);
    // a bias strip is about 4 G τ stiff for soft shear, capped by the yarns
    let bias = (4.0 * g).min(0.5 * e1.min(e2));
    let areal_density = draw_density(rng);
    let thickness = rng.log_between(0.08e-3, 1.3e-3);
    let bending = draw_rigidities(rng, areal_density);
    Source::Analytic {
        warp: Family::draw(rng, e1),
        weft: Family::draw(rng, e2),
        bias: Family::draw(rng, bias),
        areal_density,
        thickness,
        bending,
    }
}

/// How a lab tests: 3–9 angles, 1–5 repeats with scatter, noise, misalignment, slack or
/// preload, kN exports, narrow and wide strips, 5–2,000 points, with and without bends; one
/// law fabric in ten is a bias-extension sample alone with known yarns.
fn draw_protocol(rng: &mut Rng, law: bool, tension: &dyn Fn(f64) -> f64) -> Protocol {
    let bias_only = law && rng.chance(0.1);
    let mut angles = vec![90.0, 0.0, 45.0];
    let extra = rng.int(0, EXTRA_ANGLES.len());
    let mut pool = EXTRA_ANGLES.to_vec();
    for _ in 0..extra {
        let k = rng.int(0, pool.len() - 1);
        angles.push(pool.swap_remove(k));
    }
    if bias_only {
        angles = vec![45.0];
    }
    // ASTM D5035 strips are 25 or 50 mm wide, 75 mm gauge; wider grabs and longer gauges occur;
    // a bias-extension sample is three times as long as wide
    let strip = if bias_only {
        (0.05, 0.15)
    } else {
        let widths = [0.025, 0.05, 0.05, 0.1];
        (
            widths[rng.int(0, 3)],
            [0.075, 0.075, 0.1, 0.15][rng.int(0, 3)],
        )
    };
    let slack = if rng.chance(0.4) {
        rng.between(0.2e-3, 2e-3)
    } else {
        0.0
    };
    let preload = if slack == 0.0 && rng.chance(0.2) {
        rng.between(0.05e-3, 0.3e-3)
    } else {
        0.0
    };
    let export = match rng.int(0, 9) {
        0 => Export::KiloNewtonsHeader,
        1 => Export::KiloNewtonsScaled,
        _ => Export::Newtons,
    };
    Protocol {
        angles,
        repeats: rng.int(1, 5),
        points: rng.log_between(5.0, 2000.0).round() as usize,
        max_strain: {
            let cap = rng.between(0.04, 0.15);
            let limit = rng.between(BREAK_TENSION.0, BREAK_TENSION.1);
            strain_at_tension(tension, limit, cap).max(0.01)
        },
        strip,
        scale_noise: if rng.chance(0.3) {
            0.0
        } else {
            rng.between(0.0, 0.05)
        },
        point_noise: if rng.chance(0.3) {
            0.0
        } else {
            rng.between(0.0, 0.01)
        },
        misalign_deg: if rng.chance(0.5) {
            0.0
        } else {
            rng.between(0.0, 2.0)
        },
        slack,
        preload,
        export,
        bends: !bias_only && rng.chance(0.7),
        bias_only,
    }
}

#[cfg(test)]
mod tests;
