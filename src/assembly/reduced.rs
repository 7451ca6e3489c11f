//! Selective reduced integration of the yarn terms: a membrane that does not lock when the
//! yarns are nearly inextensible and lie across the cage.
//!
//! A bias strip of stiff yarns (a₁₁ = a₂₂ ≫ G₁₂) deforms by shearing the yarn net at constant
//! yarn length. On a cage along the strip's axes the yarns run at 45° to the faces, and 4 × 4
//! Gauss points per face impose Ẽ₁₁ ≈ Ẽ₂₂ ≈ 0 at 32 points against about two in-plane degrees
//! of freedom per face: the membrane locks, and the force falls 2–6× with every refinement
//! (`paper_repro/convergence/stiff_bias`). 2 × 2 points lock as badly.
//!
//! [`YarnRule::Centre`] splits the separable law ψ = ψ_y(Ẽ₁₁, Ẽ₂₂) + ψ_s(Ẽ₁₂)
//! ([`crate::material::Law::yarn_response`]) and integrates the membrane yarn part τ ψ_y(Ẽ_m)
//! at one point per face, the face centre, weighted by the face's rest area; the shear term
//! and all bending stay on the full rule. Per Gauss point the section is the whole one minus
//! τ ψ_y(Ẽ_m), so the paper's section keeps its yarn bending (∫ψ_y(Ẽ_m + ξẼ_b) − τ ψ_y(Ẽ_m))
//! and bending of its own keeps exactly its rigidities. A homogeneous strain gives the same
//! energy under either rule (the weights of both sum to the face area). What is lost is only
//! the yarn part's variation across a face, which is what locks; the modes it frees are held
//! by the shear term and the bending (the stiffness matrix stays definite at rest).
//!
//! Held by the shear alone, those modes turn the tangent indefinite under load: a 67.5° strip
//! at a yarn-to-shear ratio of 1000 on 64 × 96 takes 15–25 Newton iterations per step with
//! indefinite backward-Euler steps, then stalls for minutes in the third (the full rule: 10).
//! So a fraction β = min(1, [`HOURGLASS_RATIO`]/ratio) of the yarn part stays on the Gauss
//! points (the centres carry 1 − β): the freed modes see a yarn stiffness of 20 shears, as
//! the full rule would at a ratio of 20, where it does not lock. With it that strip takes
//! 10–13 iterations per step. β is fixed when the rule is set, by the law at that moment or
//! by a ratio the caller pins ([`ShellModel::set_yarn_rule_at`]), so each model's energy stays
//! one function of the positions and the parameters (and the sensitivities exact). A fit pins
//! the ratio at the start of each ladder level, so that one level's strips, and the checks
//! and reports on it, share one discretisation: with β from each rig's own law, a 30° strip
//! on 4 × 6 set up at a ratio of 50 and one set up at 150 differed by 12 % in force at the
//! same law.

use super::{Accumulator, FaceScratch, ModelError, ShellModel, Want};
use crate::material::OutOfDomain;
use crate::shell::{kinematic_vector, RestPoint};
use crate::subdiv::{LimitBasis, StencilTable};
use crate::Vec3;

/// How the yarn (warp, weft, a₁₂) terms of the membrane are integrated over a face.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum YarnRule {
    /// [`YarnRule::Centre`] when the law's yarns are more than [`CENTRE_FROM_RATIO`] times
    /// stiffer than its shear, else [`YarnRule::Full`] (which the centre rule is below it).
    #[default]
    Auto,
    /// The full Gauss rule, like every other term (the paper's discretisation).
    Full,
    /// One point per face, the centre, weighted by the face's rest area.
    Centre,
}

/// The yarn-to-shear stiffness ratio max(a₁₁, a₂₂)/G₁₂ above which [`YarnRule::Auto`] puts
/// the yarn terms on the face centres: [`HOURGLASS_RATIO`], below which the centre rule keeps
/// the whole yarn part on the Gauss points (β = 1) and is the full rule. On a 50 × 75 mm strip
/// at 45° pulled 5 %, graded cages (`paper_repro/convergence/stiff_bias/yarn_rules.md`), the
/// force's estimated error on 16 × 24 / 64 × 96: at a ratio of 50 the full rule 1.0 % /
/// 0.086 %, the centre rule 0.54 % / 0.033 %; at 200 the full rule 3.6 % / 0.27 % against
/// 1.1 % / 0.071 %; at 1000 12 % / 0.98 % against 2.4 % / 1.0 % (neither extrapolation settles
/// there); 30°, 45° and 60° strips of the coupled materials of
/// `paper_repro/off_axis/yarn_rules.md` on 32 × 48: at a ratio of 30 the centre rule
/// 0.21–0.25 % against 0.28–0.37 %, at 100 0.01–0.10 % against 0.03–0.52 %. At 0° and 90° the
/// full rule is the more accurate (1e-5 against 9e-5 on 16 × 24), but a fit's error is its
/// off-axis strips'. (From 20 the noise-free cotton of `paper_repro/mesh_independence` is on
/// the centre rule, where on 8 × 12 the raised degree's mapped start leads into a degenerate
/// basin, although the law that made the data scores a lower shape error there on the centre
/// rule than on the full one, 0.39 % against 0.65 %; the raise's second start,
/// `fit::degrees`, finds it.)
pub const CENTRE_FROM_RATIO: f64 = HOURGLASS_RATIO;

impl YarnRule {
    /// `Auto` decided for a law of yarn-to-shear ratio `ratio` (`None`: unknown, full rule).
    pub fn resolve(self, ratio: Option<f64>) -> YarnRule {
        match self {
            YarnRule::Auto => match ratio {
                Some(r) if r > CENTRE_FROM_RATIO => YarnRule::Centre,
                _ => YarnRule::Full,
            },
            rule => rule,
        }
    }

    /// The rule a bending-dominated scene (cantilever, drape) takes: `Auto` means the full
    /// rule there. Locking is a membrane-shear effect of tension tests; in a bend the yarn
    /// strains are small, and one point per face leaves hourglass modes held only by the
    /// (soft) shear term and β; without β the Newton solve of a 4 × 32 cantilever at a ratio
    /// of 300 stalls (a relative residual of 1.0 in the first load step,
    /// `tests/cantilever.rs`).
    pub fn for_bending(self) -> YarnRule {
        match self {
            YarnRule::Auto => YarnRule::Full,
            rule => rule,
        }
    }

    /// The rule a tensile strip cut at `angle_deg` from the weft takes: `Auto` means the full
    /// rule where the yarns run along the cage (0° and 90°, nothing to lock; the full rule's
    /// error there is the smaller, 1e-5 against 9e-5 on 16 × 24, and the centre rule's
    /// 90° force at a ratio of 50 does not converge monotonically from 8 × 12 to 32 × 48, by
    /// 1e-4 of itself), and is decided by the ratio elsewhere.
    pub fn for_strip(self, angle_deg: f64) -> YarnRule {
        let aligned = (angle_deg / 90.0 - (angle_deg / 90.0).round()).abs() < 1e-9;
        match self {
            YarnRule::Auto if aligned => YarnRule::Full,
            rule => rule,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            YarnRule::Auto => "auto",
            YarnRule::Full => "full",
            YarnRule::Centre => "centre",
        }
    }
}

impl std::str::FromStr for YarnRule {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(YarnRule::Auto),
            "full" => Ok(YarnRule::Full),
            "centre" | "center" => Ok(YarnRule::Centre),
            _ => Err(format!("a yarn rule is auto, full or centre, got '{s}'")),
        }
    }
}

/// A face centre's stencil (indices, weights), kinematic vector and rest frame.
pub(super) type CentreKinematics<'a> =
    (&'a [u32], &'a [[f64; 6]], crate::shell::YVec, &'a RestPoint);

/// Which part of the section a point carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Part {
    /// The whole section.
    Whole,
    /// The whole section less τ ψ_y(Ẽ_m) (a full-rule point under [`YarnRule::Centre`]).
    LessYarn,
    /// τ ψ_y(Ẽ_m) alone (a face centre).
    Yarn,
}

/// The face centres of [`YarnRule::Centre`].
pub(super) struct Centres {
    /// One limit stencil per face, at (½, ½).
    pub stencils: StencilTable,
    /// Rest frames at the centres, d_area the face's rest area.
    pub rest: Vec<RestPoint>,
    /// Position of every stencil entry in its face's node list.
    pub local_index: Vec<u16>,
    /// The fraction 1 − β of the yarn part moved to the centres; β stays on the Gauss points
    /// ([`HOURGLASS_RATIO`]).
    pub moved: f64,
}

/// The yarn stiffness left on the Gauss points under [`YarnRule::Centre`], as a multiple of
/// G₁₂: β = min(1, this / ratio) of the yarn part. It holds the modes that one point per face
/// cannot see at a stiffness of that many shears, which locks no more than the full rule does
/// at that ratio.
pub const HOURGLASS_RATIO: f64 = 20.0;

impl ShellModel {
    /// Chooses how the yarn terms are integrated (see the module doc); `Auto` and the centre
    /// rule's β are decided by the current law.
    pub fn set_yarn_rule(&mut self, rule: YarnRule) -> Result<(), ModelError> {
        self.set_yarn_rule_at(rule, None)
    }

    /// [`ShellModel::set_yarn_rule`] with `Auto` and β decided by the yarn-to-shear ratio
    /// `ratio` instead (`None`: the current law's), so that models built for different laws
    /// can share one discretisation.
    pub fn set_yarn_rule_at(
        &mut self,
        rule: YarnRule,
        ratio: Option<f64>,
    ) -> Result<(), ModelError> {
        let ratio = ratio.or_else(|| self.law.yarn_shear_ratio());
        let rule = rule.resolve(ratio);
        let beta = match ratio {
            Some(r) if r > HOURGLASS_RATIO => HOURGLASS_RATIO / r,
            _ => 1.0,
        };
        let same = match &self.centres {
            Some(c) => rule == YarnRule::Centre && c.moved == 1.0 - beta,
            None => rule == YarnRule::Full,
        };
        if same {
            return Ok(());
        }
        self.centres = match rule {
            YarnRule::Centre => Some(self.build_centres(beta)?),
            _ => None,
        };
        Ok(())
    }

    /// The rule in force (`Full` or `Centre`).
    pub fn yarn_rule(&self) -> YarnRule {
        if self.centres.is_some() {
            YarnRule::Centre
        } else {
            YarnRule::Full
        }
    }

    fn build_centres(&self, beta: f64) -> Result<Centres, ModelError> {
        let one = LimitBasis::from_surface(self.basis.surface(), 1)
            .map_err(|e| ModelError::Centre(e.to_string()))?;
        let npf = self.basis.points_per_face;
        let x = &self.basis.control_points;
        let mut rest = Vec::with_capacity(one.num_faces);
        let mut local_index = vec![0u16; one.stencils.indices.len()];
        for face in 0..one.num_faces {
            let area: f64 = self.rest[face * npf..(face + 1) * npf]
                .iter()
                .map(|r| r.d_area)
                .sum();
            let p = one.limit_stencil(face).apply(x);
            let mut r =
                RestPoint::new(&p.d, 1.0, self.warp).map_err(|source| ModelError::Rest {
                    point: face * npf,
                    source,
                })?;
            r.d_area = area;
            rest.push(r);
            let nodes = &self.face_nodes[face];
            let off = one.stencils.offsets[face] as usize;
            for (k, i) in one.stencil(face).0.iter().enumerate() {
                let at = nodes.binary_search(i).map_err(|_| {
                    ModelError::Centre(format!(
                        "face {face}: the centre's stencil reaches control point {i}, \
                         outside the face's Gauss-point stencils"
                    ))
                })?;
                local_index[off + k] = at as u16;
            }
        }
        Ok(Centres {
            stencils: one.stencils,
            rest,
            local_index,
            moved: 1.0 - beta,
        })
    }

    /// Adds the yarn terms of `face`'s centre (nothing under the full rule).
    #[inline(always)]
    pub(super) fn centre_terms(
        &self,
        face: usize,
        x: &[Vec3],
        want: Want,
        acc: &mut Accumulator,
        s: &mut FaceScratch,
    ) -> Result<(), OutOfDomain> {
        let Some((idx, w, y, rest)) = self.centre_kinematics(face, x) else {
            return Ok(());
        };
        let c = self
            .centres
            .as_ref()
            .expect("centres exist when their kinematics do");
        let off = c.stencils.offsets[face] as usize;
        let local = &c.local_index[off..off + idx.len()];
        let (e, gy, hy) = self.rest_point_terms(rest, &y, want, Part::Yarn)?;
        acc.energy += e;
        self.scatter(
            idx,
            w,
            local,
            self.face_nodes[face].len(),
            &gy,
            hy,
            want,
            acc,
            s,
        );
        Ok(())
    }

    /// The centre's kinematic vector and rest frame of `face`, when the yarns are on centres.
    pub(super) fn centre_kinematics(
        &self,
        face: usize,
        x: &[Vec3],
    ) -> Option<CentreKinematics<'_>> {
        let c = self.centres.as_ref()?;
        let (idx, w) = c.stencils.row(face);
        let mut d = [[0.0; 3]; 6];
        for (&i, wi) in idx.iter().zip(w) {
            for k in 1..6 {
                for e in 0..3 {
                    d[k][e] += wi[k] * x[i as usize][e];
                }
            }
        }
        Some((idx, w, kinematic_vector(&d), &c.rest[face]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Cutoffs, Eta, Orthotropic};
    use crate::mesh::graded_grid;
    use crate::subdiv::BasisOptions;
    use std::sync::Arc;

    fn law() -> Orthotropic {
        Orthotropic {
            a11: 1.0e9,
            a22: 6.0e8,
            a12: 2.0e7,
            g12: 1.0e5,
            warp: Eta {
                mu: vec![0.6, 0.4],
                alpha: vec![1.0, 8.0],
            },
            weft: Eta::linear(),
            shear: Eta {
                mu: vec![1.5, -0.5],
                alpha: vec![2.0, -2.0],
            },
            cutoffs: Cutoffs::none(),
            coupling: None,
        }
    }

    fn model(rule: YarnRule) -> ShellModel {
        let mesh = graded_grid(0.05, 0.075, 4, 6, crate::mesh::Grading::UNIFORM);
        let basis = LimitBasis::new(&mesh, BasisOptions::default()).unwrap();
        let warp = crate::material::warp_direction(45.0);
        let mut m = ShellModel::new(basis, warp, Arc::new(law()), 3e-4, 0.1).unwrap();
        m.set_yarn_rule(rule).unwrap();
        m
    }

    /// A homogeneous in-plane strain costs the same under either rule (the centre weights sum
    /// to each face's area), while a strain that varies across the faces does not.
    #[test]
    fn both_rules_agree_on_homogeneous_strains_only() {
        let (full, centre) = (model(YarnRule::Full), model(YarnRule::Centre));
        assert_eq!(centre.yarn_rule(), YarnRule::Centre);
        let x0 = &full.basis.control_points;
        let affine: Vec<Vec3> = x0
            .iter()
            .map(|p| [1.03 * p[0] + 0.02 * p[1], 0.99 * p[1] - 0.01 * p[0], p[2]])
            .collect();
        let (a, b) = (
            full.energy(&affine).unwrap(),
            centre.energy(&affine).unwrap(),
        );
        assert!(a > 0.0 && (a - b).abs() <= 1e-12 * a, "{a} {b}");
        let bent: Vec<Vec3> = x0
            .iter()
            .map(|p| [p[0] * (1.0 + 0.5 * p[1]), p[1], p[2]])
            .collect();
        let (a, b) = (full.energy(&bent).unwrap(), centre.energy(&bent).unwrap());
        assert!((a - b).abs() > 1e-6 * a, "{a} {b}");
    }

    /// The centre rule leaves the stiffness at rest definite once rigid motions are held
    /// (three corners' positions): no zero-energy mode appears.
    #[test]
    fn the_centre_rule_has_no_zero_energy_mode() {
        let m = model(YarnRule::Centre);
        let x = m.basis.control_points.clone();
        let mut h = super::super::BlockMatrix::zeros(m.pattern.clone());
        let mut g = vec![[0.0; 3]; m.num_nodes()];
        m.assemble(&x, Want::Hessian, Some(&mut g), Some(&mut h))
            .unwrap();
        let n = 3 * m.num_nodes();
        let mut dense = nalgebra::DMatrix::<f64>::zeros(n, n);
        for i in 0..m.num_nodes() {
            let mut e = vec![[0.0; 3]; m.num_nodes()];
            for c in 0..3 {
                e[i][c] = 1.0;
                let mut col = vec![[0.0; 3]; m.num_nodes()];
                h.mul(&e, &mut col);
                for (j, v) in col.iter().enumerate() {
                    for d in 0..3 {
                        dense[(3 * j + d, 3 * i + c)] = v[d];
                    }
                }
                e[i][c] = 0.0;
            }
        }
        // hold rigid motions: three nodes fully (more than enough), the rest free
        let last = m.num_nodes() - 1;
        let held: Vec<usize> = [0, 1, last]
            .iter()
            .flat_map(|&i| 3 * i..3 * i + 3)
            .collect();
        let free: Vec<usize> = (0..n).filter(|k| !held.contains(k)).collect();
        let k = dense.select_rows(&free).select_columns(&free);
        let eig = nalgebra::SymmetricEigen::new(k).eigenvalues;
        let (lo, hi) = eig
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(lo > 1e-14 * hi, "smallest eigenvalue {lo:e} of {hi:e}");
    }

    /// β = min(1, HOURGLASS_RATIO/ratio) of the yarn part stays on the Gauss points: with the
    /// yarns only 10 times the shear, β = 1 and the centre rule is the full rule to round-off,
    /// for any deformation; at the test law's ratio of 1e4 it is not.
    #[test]
    fn the_yarns_stay_on_the_gauss_points_in_proportion_beta() {
        let bent = |m: &ShellModel| -> Vec<Vec3> {
            m.basis
                .control_points
                .iter()
                .map(|p| [p[0] * (1.0 + 0.5 * p[1]), p[1], 0.3 * p[0] * p[1]])
                .collect()
        };
        let mut soft = law();
        soft.a11 = 1.0e6;
        soft.a22 = 6.0e5;
        soft.a12 = 1.0e5;
        let soft_model = |rule| {
            let mut m = model(YarnRule::Full);
            m.law = Arc::new(soft.clone());
            m.set_yarn_rule(rule).unwrap();
            m
        };
        let (full, centre) = (soft_model(YarnRule::Full), soft_model(YarnRule::Centre));
        assert_eq!(centre.yarn_rule(), YarnRule::Centre);
        let x = bent(&full);
        let (a, b) = (full.energy(&x).unwrap(), centre.energy(&x).unwrap());
        assert!((a - b).abs() <= 1e-12 * a, "{a} {b}");
        let (full, centre) = (model(YarnRule::Full), model(YarnRule::Centre));
        let x = bent(&full);
        let (a, b) = (full.energy(&x).unwrap(), centre.energy(&x).unwrap());
        assert!((a - b).abs() > 1e-6 * a, "{a} {b}");
    }
}
