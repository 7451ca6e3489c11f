//! The triangle models' kinds and parameters (Miguel et al. 2012 §3–4; Larionov et al. 2022
//! §3), with their zero-strain equivalents of a shell material.
//!
//! Every model has the same six components, each a [`Stiffness`] k(ε): stretch along the warp
//! and the weft and shear (N/m, membrane), and bending along the warp, the weft and the cell
//! diagonals. The membrane strains are the model's own: for `stvk-ds` and `xpbd` the Green
//! strains (E₁₁, E₂₂, 2E₁₂) of each triangle, for `soft-constraints` Baraff–Witkin's
//! (|w_u| − 1, |w_v| − 1, w_u·w_v), for `springs` the spring strains l/l₀ − 1 of the ring-1
//! grid-line and diagonal springs. Bending is the curvature θ/h of a dihedral hinge (N·m, a
//! plate rigidity; see [`super::model`]) except for `springs`, whose ring-2 springs have a
//! strain l/l₀ − 1 and a stiffness in N/m. `xpbd` is Larionov's orthotropic St. Venant–
//! Kirchhoff membrane: linear components plus the Poisson coupling C₀₁.

use super::curve::Stiffness;
use crate::material::bending::uniaxial_compliance;
use crate::material::{FabricMaterial, Law};
use nalgebra::Vector3;

/// A triangle-mesh cloth model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TriKind {
    Springs,
    SoftConstraints,
    StvkDs,
    Xpbd,
}

impl TriKind {
    pub const ALL: [(&'static str, TriKind); 4] = [
        ("springs", TriKind::Springs),
        ("soft-constraints", TriKind::SoftConstraints),
        ("stvk-ds", TriKind::StvkDs),
        ("xpbd", TriKind::Xpbd),
    ];

    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, k)| *k == self)
            .map_or("?", |(n, _)| n)
    }
}

impl std::str::FromStr for TriKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .iter()
            .find(|(n, _)| *n == s)
            .map(|(_, k)| *k)
            .ok_or_else(|| {
                format!(
                    "unknown model '{s}' (expected kl, springs, soft-constraints, stvk-ds or xpbd)"
                )
            })
    }
}

/// Component order in [`TriMaterial::curves`].
pub const COMPONENTS: [&str; 6] = [
    "stretch_warp",
    "stretch_weft",
    "shear",
    "bend_warp",
    "bend_weft",
    "bend_diag",
];

/// A triangle model's parameters, SI.
#[derive(Clone, Debug, PartialEq)]
pub struct TriMaterial {
    pub kind: TriKind,
    /// In [`COMPONENTS`] order.
    pub curves: [Stiffness; 6],
    /// Poisson coupling C₀₁ of the orthotropic StVK membrane (N/m; `xpbd` only, else 0).
    pub coupling: f64,
    /// kg/m²
    pub areal_density: f64,
}

/// Zero-strain moduli of a shell material: uniaxial membrane moduli (N/m) along the warp, the
/// weft and 45°, the law's tangent times the thickness (N/m, tensor-shear convention), and the
/// beam bending rigidities (N·m) along the warp, the weft and 45°.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZeroStrain {
    pub uniaxial: [f64; 3],
    pub tangent: nalgebra::Matrix3<f64>,
    pub bending: [f64; 3],
}

impl ZeroStrain {
    pub fn of(m: &FabricMaterial) -> Result<Self, String> {
        let c = m
            .law
            .response(&Vector3::zeros())
            .map_err(|e| e.to_string())?
            .tangent;
        let t = m.thickness;
        let at = |c: &nalgebra::Matrix3<f64>, deg: f64| {
            uniaxial_compliance(c, f64::to_radians(deg))
                .filter(|v| *v > 0.0)
                .map(|v| 1.0 / v)
                .ok_or_else(|| "the law's zero-strain tangent is singular".to_string())
        };
        let uniaxial = [at(&c, 0.0)? * t, at(&c, 90.0)? * t, at(&c, 45.0)? * t];
        let bending = match &m.bending {
            Some(b) => [b.at_angle(90.0), b.at_angle(0.0), b.at_angle(45.0)],
            None => {
                let d = c * (t * t * t / 12.0);
                [at(&d, 0.0)?, at(&d, 90.0)?, at(&d, 45.0)?]
            }
        };
        Ok(Self {
            uniaxial,
            tangent: c * t,
            bending,
        })
    }
}

impl TriMaterial {
    /// The model `kind` with the shell material's zero-strain moduli: linear components whose
    /// uniaxial warp, weft and 45° membrane moduli and warp, weft and 45° bending rigidities
    /// equal the shell's (where the model can: the springs' shear ring also stiffens the
    /// yarn directions, and their ring-2 bending has no small-curvature rigidity, so
    /// `cell` (the grid spacing, m) and `curvature` (1/m) set the curvature at which the
    /// springs' bending energy matches the plate's). A starting point for fitting, and the
    /// "same material" of the model comparisons.
    pub fn equivalent(
        kind: TriKind,
        m: &FabricMaterial,
        cell: f64,
        curvature: f64,
    ) -> Result<Self, String> {
        Ok(Self::from_zero_strain(
            kind,
            &ZeroStrain::of(m)?,
            m.areal_density,
            cell,
            curvature,
        ))
    }

    /// As [`TriMaterial::equivalent`], from the moduli themselves.
    pub fn from_zero_strain(
        kind: TriKind,
        z: &ZeroStrain,
        areal_density: f64,
        cell: f64,
        curvature: f64,
    ) -> Self {
        let [ew, ef, e45] = z.uniaxial;
        // uniaxial 45° compliance of diag(k_u, k_v, 4 k_s): ¼/k_u + ¼/k_v + ¼/k_s
        let shear_from_bias = 1.0 / (4.0 / e45 - 1.0 / ew - 1.0 / ef);
        let shear = if shear_from_bias > 0.0 && shear_from_bias.is_finite() {
            shear_from_bias
        } else {
            z.tangent[(2, 2)] / 4.0
        };
        let [bw, bf, _] = z.bending;
        // a fold across a cell diagonal bends both ways at once: its stiffness is not the
        // plate's 45° rigidity (that lets the grid fold along its diagonals; a light
        // cantilever then sags 4.3 times the beam's deflection), and the warp and weft
        // cantilevers do not determine it; the geometric mean of the two is the assumption
        let b45 = (bw * bf).sqrt();
        let k = Stiffness::constant;
        let (curves, coupling) = match kind {
            TriKind::Springs => {
                // diagonal springs k_d on square cells add k_d/4 to each yarn stiffness and
                // k_d/4 on γ = 2E₁₂; ring-2 springs: ε = −(κa)²/6 along an arc of curvature κ
                // and the ring-2 springs carry a stretch as the ring-1 ones do
                let kd = 4.0 * shear;
                let bend = |b: f64| 36.0 * b / (curvature * curvature * cell.powi(4));
                (
                    [
                        k((ew - 0.25 * kd - bend(bw)).max(0.1 * ew)),
                        k((ef - 0.25 * kd - bend(bf)).max(0.1 * ef)),
                        k(kd),
                        k(bend(bw)),
                        k(bend(bf)),
                        k(bend(b45)),
                    ],
                    0.0,
                )
            }
            TriKind::SoftConstraints | TriKind::StvkDs => {
                ([k(ew), k(ef), k(shear), k(bw), k(bf), k(b45)], 0.0)
            }
            TriKind::Xpbd => {
                let t = z.tangent;
                (
                    [
                        k(t[(0, 0)]),
                        k(t[(1, 1)]),
                        k(t[(2, 2)] / 4.0),
                        k(bw),
                        k(bf),
                        k(b45),
                    ],
                    t[(0, 1)],
                )
            }
        };
        Self {
            kind,
            curves,
            coupling,
            areal_density,
        }
    }
}
