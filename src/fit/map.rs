//! The map between a stage's variables p and the law (paper §5 stages 2, 3 and 5).
//!
//! A stage fits one η and its stiffness c (a11 for warp, a22 for weft, G12 for shear). Its
//! variables are O(1): ln c (absent when c is known), μ₂…μ_d (μ₁ = 1 − Σ the others) and,
//! per term, u with β = α x̂ = B tanh(u/B), x̂ the largest tested value of η's argument, so
//! that β ≈ 1 is where η bends.
//!
//! **Bounded exponents.** A term μ(x + 1)^α contributes μ(1 + x)^(α−1) ≈ μ e^(β x/x̂) to η', so
//! |β| ≤ B = [`BETA_MAX`] = 6 caps how much one term can stiffen (or soften) across the
//! exercised range at e⁶ ≈ 400×. Fabrics need far less: the bundled materials reach β ≈ 1.6,
//! and fitted laws stay within β ≤ 3.2 wherever the term matters; what the bound excludes are
//! degenerate laws (μ = 2.5e-8 with α = 2168, β ≈ 16) that fit a knee at the last points with
//! a term worth nothing anywhere else and e⁶⁴ at twice the strain. Beyond the
//! exercised range the fitter's cut-offs carry each term on as its quadratic Taylor
//! extension, so the law there is finite and its stress linear in strain. The smooth map
//! keeps the objective differentiable and needs no active set; its slope 1 − (β/B)² is in
//! [`StageMap::chain`].
//!
//! a12 follows its rule ([`A12Rule`]) whenever a11 or a22 changes.
//!
//! **Coupling.** A shear stage with `coupling` also fits the tension–shear coupling κ₁, κ₂
//! ([`crate::material::ShearCoupling`]), two variables after η's: v with
//! κ = K tanh(v/K)/ê, ê = 2√x̂ the largest axial Green strain of the stage's strips, so that
//! |κ ê| ≤ K = [`COUPLING_SPAN`]: across the exercised range the coupling changes the shear
//! stiffness by e^K ≈ 7× at most.

use crate::material::{Eta, Orthotropic, ShearCoupling};

/// Bound B of every term's β = α x̂ (see the module doc).
pub const BETA_MAX: f64 = 6.0;

/// Bound K of the coupling's κ ê (see the module doc).
pub const COUPLING_SPAN: f64 = 2.0;

/// Share of the coupling's bound K within which a stage starts κ ê ([`StageMap::encode_start`]).
pub const UNSATURATED: f64 = 0.9;

/// The variable u of a term bending at β (β clamped just inside ±B).
pub fn beta_to_var(beta: f64) -> f64 {
    let t = (beta / BETA_MAX).clamp(-1.0 + 1e-9, 1.0 - 1e-9);
    BETA_MAX * t.atanh()
}

/// β of a term's variable u.
pub fn var_to_beta(u: f64) -> f64 {
    BETA_MAX * (u / BETA_MAX).tanh()
}

/// dβ/du.
fn dbeta(u: f64) -> f64 {
    let t = (u / BETA_MAX).tanh();
    1.0 - t * t
}

/// Which η and stiffness a stage fits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    Warp,
    Weft,
    Shear,
}

impl Direction {
    pub fn name(self) -> &'static str {
        match self {
            Self::Warp => "warp",
            Self::Weft => "weft",
            Self::Shear => "bias",
        }
    }
}

/// How a12 is set: strips alone do not determine it (see the crate's identifiability notes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum A12Rule {
    /// a12 = ½ min(a11, a22) (the paper's §3 default)
    HalfMin,
    /// a12 = ν12 a22, from a measured Poisson ratio
    Poisson(f64),
    /// a known value
    Fixed(f64),
}

impl A12Rule {
    pub fn apply(self, law: &mut Orthotropic) {
        law.a12 = match self {
            Self::HalfMin => 0.5 * law.a11.min(law.a22),
            Self::Poisson(nu) => nu * law.a22,
            Self::Fixed(v) => v,
        };
    }

    /// ∂a12/∂c of a stage's stiffness c.
    fn derivative(self, dir: Direction, law: &Orthotropic) -> f64 {
        match (self, dir) {
            (Self::HalfMin, Direction::Warp) if law.a11 <= law.a22 => 0.5,
            (Self::HalfMin, Direction::Weft) if law.a22 < law.a11 => 0.5,
            (Self::Poisson(nu), Direction::Weft) => nu,
            _ => 0.0,
        }
    }
}

/// The map between a stage's variables p and the law.
#[derive(Clone, Copy, Debug)]
pub struct StageMap {
    pub dir: Direction,
    /// x̂: the largest tested value of η's argument
    pub xhat: f64,
    /// the stiffness is known (`[known]`): p holds only η's variables
    pub c_known: bool,
    pub a12: A12Rule,
    /// a shear stage that fits the tension–shear coupling too (two variables after η's)
    pub coupling: bool,
}

impl StageMap {
    pub(super) fn offset(&self) -> usize {
        usize::from(!self.c_known)
    }

    /// The coupling's variables after η's (0 or 2).
    fn tail(&self) -> usize {
        2 * usize::from(self.coupling)
    }

    /// ê: the largest axial Green strain of the stage's strips (x̂ = (ê/2)² for the shear).
    fn ehat(&self) -> f64 {
        2.0 * self.xhat.sqrt()
    }

    /// κ of a coupling variable v.
    pub fn kappa(&self, v: f64) -> f64 {
        COUPLING_SPAN * (v / COUPLING_SPAN).tanh() / self.ehat()
    }

    /// dκ/dv.
    pub fn dkappa(&self, v: f64) -> f64 {
        let t = (v / COUPLING_SPAN).tanh();
        (1.0 - t * t) / self.ehat()
    }

    /// v of a coupling κ (κ ê clamped just inside ±K).
    fn kappa_var(&self, kappa: f64) -> f64 {
        let t = (kappa * self.ehat() / COUPLING_SPAN).clamp(-1.0 + 1e-9, 1.0 - 1e-9);
        COUPLING_SPAN * t.atanh()
    }

    pub fn eta<'a>(&self, law: &'a Orthotropic) -> &'a Eta {
        match self.dir {
            Direction::Warp => &law.warp,
            Direction::Weft => &law.weft,
            Direction::Shear => &law.shear,
        }
    }

    pub fn eta_mut<'a>(&self, law: &'a mut Orthotropic) -> &'a mut Eta {
        match self.dir {
            Direction::Warp => &mut law.warp,
            Direction::Weft => &mut law.weft,
            Direction::Shear => &mut law.shear,
        }
    }

    pub fn stiffness(&self, law: &Orthotropic) -> f64 {
        match self.dir {
            Direction::Warp => law.a11,
            Direction::Weft => law.a22,
            Direction::Shear => law.g12,
        }
    }

    /// [`StageMap::encode`] as a minimiser's start: a coupling at its bound (|κ ê| above
    /// [`UNSATURATED`] of K) is moved inside it. There tanh is flat (dκ/dv ≈ 1e-9 at the
    /// bound), so a stage started from a saturated κ could never move it back: on strips made
    /// with κ₁ = −25 at 7 angles, the 8 × 12 level drives κ₁ to the bound (−39.0, absorbing
    /// that mesh's error), where every finer level would leave it.
    pub fn encode_start(&self, law: &Orthotropic) -> Vec<f64> {
        let mut p = self.encode(law);
        if self.coupling {
            let top = COUPLING_SPAN * UNSATURATED.atanh();
            let n = p.len();
            for v in &mut p[n - 2..] {
                *v = v.clamp(-top, top);
            }
        }
        p
    }

    pub fn encode(&self, law: &Orthotropic) -> Vec<f64> {
        let eta = self.eta(law);
        let mut p = Vec::new();
        if !self.c_known {
            p.push(self.stiffness(law).ln());
        }
        p.extend(&eta.mu[1..]);
        p.extend(eta.alpha.iter().map(|a| beta_to_var(a * self.xhat)));
        if self.coupling {
            let c = law.coupling.unwrap_or(ShearCoupling {
                warp: 0.0,
                weft: 0.0,
            });
            p.extend([self.kappa_var(c.warp), self.kappa_var(c.weft)]);
        }
        p
    }

    /// dα/du of the term whose variable is `u`.
    pub fn dalpha(&self, u: f64) -> f64 {
        dbeta(u) / self.xhat
    }

    pub fn degree(&self, p: &[f64]) -> usize {
        (p.len() - self.offset() - self.tail()).div_ceil(2)
    }

    /// Index in p of the first exponent variable u (η's α come after the μ).
    pub(super) fn first_alpha(&self, p: &[f64]) -> usize {
        self.offset() + self.degree(p) - 1
    }

    /// The variables of degree d + 1 that start exactly at degree d's law `p`: a new term
    /// with μ = 0 bending at `beta` (β, clamped inside the bound).
    pub fn raise(&self, p: &[f64], beta: f64) -> Vec<f64> {
        let o = self.offset();
        let d = self.degree(p);
        let mut q = p[..o + d - 1].to_vec();
        q.push(0.0);
        q.extend(&p[o + d - 1..o + 2 * d - 1]);
        q.push(beta_to_var(beta));
        q.extend(&p[o + 2 * d - 1..]);
        q
    }

    pub fn decode(&self, p: &[f64], law: &mut Orthotropic) {
        let o = self.offset();
        let d = self.degree(p);
        let mus = &p[o..o + d - 1];
        let mut mu = vec![1.0 - mus.iter().sum::<f64>()];
        mu.extend(mus);
        let alpha: Vec<f64> = p[o + d - 1..o + 2 * d - 1]
            .iter()
            .map(|&u| var_to_beta(u) / self.xhat)
            .collect();
        let eta = Eta { mu, alpha };
        let c = if self.c_known {
            self.stiffness(law)
        } else {
            p[0].exp()
        };
        match self.dir {
            Direction::Warp => {
                law.a11 = c;
                law.warp = eta;
            }
            Direction::Weft => {
                law.a22 = c;
                law.weft = eta;
            }
            Direction::Shear => {
                law.g12 = c;
                law.shear = eta;
            }
        }
        if self.coupling {
            let v = &p[o + 2 * d - 1..];
            law.coupling = Some(ShearCoupling {
                warp: self.kappa(v[0]),
                weft: self.kappa(v[1]),
            });
        }
        self.a12.apply(law);
    }

    /// Index of the stage's stiffness and of its η's first parameter in the law's
    /// parameters ([`Orthotropic::names`] order).
    fn indices(&self, law: &Orthotropic) -> (usize, usize) {
        let (d1, d3) = (law.warp.degree(), law.weft.degree());
        match self.dir {
            Direction::Warp => (0, 4),
            Direction::Weft => (1, 4 + 2 * d1),
            Direction::Shear => (3, 4 + 2 * d1 + 2 * d3),
        }
    }

    /// The law parameters (then thickness) a stage's forces depend on through p.
    pub fn wanted(&self, law: &Orthotropic) -> Vec<bool> {
        let n = law.params().len();
        let mut w = vec![false; n + 1];
        let (ci, offset) = self.indices(law);
        let d = self.eta(law).degree();
        w[ci] = true;
        w[2] = true;
        w[offset..offset + 2 * d].iter_mut().for_each(|v| *v = true);
        if self.coupling {
            w[n - 2] = true;
            w[n - 1] = true;
        }
        w
    }

    /// dF/dp from dF/dk (the law's parameters in [`Orthotropic::names`] order).
    pub fn chain(&self, p: &[f64], law: &Orthotropic, dk: &[f64]) -> Vec<f64> {
        let o = self.offset();
        let d = self.degree(p);
        let (ci, offset) = self.indices(law);
        let mut out = vec![0.0; p.len()];
        if !self.c_known {
            let c = p[0].exp();
            out[0] = c * (dk[ci] + self.a12.derivative(self.dir, law) * dk[2]);
        }
        for i in 1..d {
            out[o + i - 1] = dk[offset + i] - dk[offset];
        }
        for i in 0..d {
            out[o + d - 1 + i] = dk[offset + d + i] * self.dalpha(p[o + d - 1 + i]);
        }
        if self.coupling {
            // κ₁, κ₂ are the law's last parameters
            let n = law.params().len();
            for i in 0..2 {
                let v = p[o + 2 * d - 1 + i];
                out[o + 2 * d - 1 + i] = dk[n - 2 + i] * self.dkappa(v);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Cutoffs;

    fn law() -> Orthotropic {
        Orthotropic {
            a11: 2e8,
            a22: 1e8,
            a12: 5e7,
            g12: 3e6,
            warp: Eta {
                mu: vec![0.6, 0.4],
                alpha: vec![1.0, 40.0],
            },
            weft: Eta::linear(),
            shear: Eta {
                mu: vec![0.7, 0.3],
                alpha: vec![2.0, 90.0],
            },
            cutoffs: Cutoffs::none(),
            coupling: None,
        }
    }

    #[test]
    fn encode_decode_and_raise_round_trip() {
        for c_known in [false, true] {
            for dir in [Direction::Warp, Direction::Weft, Direction::Shear] {
                let map = StageMap {
                    dir,
                    xhat: 2e-3,
                    c_known,
                    a12: A12Rule::Poisson(0.1),
                    coupling: false,
                };
                let l = law();
                let p = map.encode(&l);
                let mut back = l.clone();
                map.decode(&p, &mut back);
                assert_eq!(map.eta(&back).mu.len(), map.eta(&l).mu.len());
                assert!((map.stiffness(&back) - map.stiffness(&l)).abs() < 1e-6);
                assert!((back.a12 - 0.1 * back.a22).abs() < 1e-6);
                // the raised law is the same law: a new term with μ = 0
                let q = map.raise(&p, 7.0);
                assert_eq!(map.degree(&q), map.degree(&p) + 1);
                let mut raised = l.clone();
                map.decode(&q, &mut raised);
                let (a, b) = (map.eta(&back), map.eta(&raised));
                for x in [1e-4, 1e-3, 4e-3] {
                    let (va, vb) = (a.eval(x).unwrap()[0], b.eval(x).unwrap()[0]);
                    assert!((va - vb).abs() < 1e-12 * va.abs());
                }
            }
        }
    }

    /// The coupled shear map: κ round-trips through encode and decode, survives a raised
    /// degree, stays inside its span, and `chain` is the derivative of the decoded law.
    #[test]
    fn the_coupled_shear_map_round_trips_and_differentiates() {
        let map = StageMap {
            dir: Direction::Shear,
            xhat: 4e-4,
            c_known: false,
            a12: A12Rule::HalfMin,
            coupling: true,
        };
        let mut l = law();
        l.coupling = Some(ShearCoupling {
            warp: -12.0,
            weft: 7.5,
        });
        let p = map.encode(&l);
        assert_eq!(p.len(), 1 + 3 + 2);
        assert_eq!(map.degree(&p), 2);
        let mut back = l.clone();
        back.coupling = None;
        map.decode(&p, &mut back);
        let c = back.coupling.unwrap();
        assert!(
            (c.warp + 12.0).abs() < 1e-9 && (c.weft - 7.5).abs() < 1e-9,
            "{c:?}"
        );
        let q = map.raise(&p, 2.0);
        let mut raised = l.clone();
        map.decode(&q, &mut raised);
        assert_eq!(raised.shear.degree(), 3);
        assert!((raised.coupling.unwrap().warp + 12.0).abs() < 1e-9);
        // a start leaves κ alone inside UNSATURATED of the bound, and moves a saturated κ
        // back to where tanh has slope again (a stage could not move it otherwise)
        assert_eq!(map.encode_start(&l), p);
        let ehat = 2.0 * map.xhat.sqrt();
        let mut at_bound = l.clone();
        at_bound.coupling = Some(ShearCoupling {
            warp: -COUPLING_SPAN / ehat,
            weft: 0.5 * COUPLING_SPAN / ehat,
        });
        let saturated = map.encode(&at_bound);
        assert!(map.dkappa(saturated[4]) * ehat < 1e-6, "{saturated:?}");
        let start = map.encode_start(&at_bound);
        assert_eq!(start[..5], [&saturated[..4], &[start[4]]].concat()[..]);
        assert_eq!(start[5], saturated[5]);
        let mut moved = at_bound.clone();
        map.decode(&start, &mut moved);
        let k = moved.coupling.unwrap().warp * ehat;
        assert!((k + UNSATURATED * COUPLING_SPAN).abs() < 1e-12, "κê = {k}");
        assert!(map.dkappa(start[4]) * ehat > 0.15, "{start:?}");
        // |κ ê| ≤ K whatever the variables
        for v in [-1e4, -3.0, 0.0, 40.0] {
            let mut r = p.clone();
            r[4] = v;
            map.decode(&r, &mut back);
            let k = back.coupling.unwrap().warp * 2.0 * map.xhat.sqrt();
            assert!(k.abs() <= COUPLING_SPAN, "v = {v}: κê = {k}");
        }
        // chain: F(k) = Σ wᵢ kᵢ over the law's parameters, against central differences in p
        // (a12 follows a11 and a22 by its rule, so F sees it too)
        let nk = l.params().len();
        // (weights over each parameter's size, so that F is O(1) and differences keep digits)
        let k0 = l.params();
        let w: Vec<f64> = (0..nk)
            .map(|i| (1.0 + 0.37 * i as f64) / k0[i].abs().max(1.0))
            .collect();
        let f = |q: &[f64]| {
            let mut m = l.clone();
            map.decode(q, &mut m);
            m.params().iter().zip(&w).map(|(a, b)| a * b).sum::<f64>()
        };
        let dp = map.chain(&p, &l, &w);
        for k in 0..p.len() {
            let h = 1e-6 * p[k].abs().max(1.0);
            let (mut qp, mut qm) = (p.clone(), p.clone());
            qp[k] += h;
            qm[k] -= h;
            let fd = (f(&qp) - f(&qm)) / (2.0 * h);
            assert!(
                (fd - dp[k]).abs() <= 1e-6 * dp[k].abs().max(1.0),
                "variable {k}: {fd} vs {}",
                dp[k]
            );
        }
        // the coupling's parameters are among those the stage wants
        let want = map.wanted(&l);
        assert_eq!(want.len(), nk + 1);
        assert!(want[nk - 2] && want[nk - 1]);
    }

    #[test]
    fn exponents_stay_bounded_and_their_slope_is_exact() {
        let map = StageMap {
            dir: Direction::Warp,
            xhat: 4e-3,
            c_known: false,
            a12: A12Rule::HalfMin,
            coupling: false,
        };
        let mut l = law();
        // any variables decode to |α x̂| ≤ B, however far the optimiser wanders
        for u in [-1e3, -20.0, -1.0, 0.0, 3.0, 50.0, 1e6] {
            map.decode(&[18.0, 0.4, 0.5, u], &mut l);
            let beta = l.warp.alpha[1] * map.xhat;
            assert!(beta.abs() <= BETA_MAX, "u = {u}: β = {beta}");
        }
        // inside the bound the map is one-to-one
        for beta in [-5.0, -0.3, 0.0, 1.6, 5.9] {
            assert!((var_to_beta(beta_to_var(beta)) - beta).abs() < 1e-12);
        }
        // dα/du against a central difference
        for u in [-7.0, -0.5, 0.0, 2.0, 9.0] {
            let h = 1e-5;
            let fd = (var_to_beta(u + h) - var_to_beta(u - h)) / (2.0 * h) / map.xhat;
            let exact = map.dalpha(u);
            assert!(
                (fd - exact).abs() < 1e-7 * exact.abs(),
                "u = {u}: {fd} vs {exact}"
            );
        }
    }
}
