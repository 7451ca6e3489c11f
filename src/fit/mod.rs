//! Fitting a fabric's test data (Clyde et al. 2017 §5): the staged protocol, its parameter
//! maps and the multiresolution ladder.
//!
//! Objective (paper Eq. 3): the sum of squared relative errors of the tensile forces and the
//! drape angles. Each stage fits a few parameters with the others held:
//! 1. warp (90°): a11 and η₁; 2. weft (0°): a22 and η₃; 3. the Ẽ11, Ẽ22 cut-offs at 95 % of
//!    the largest tested strain; 4. bias (45°): G12 and η₄; 5. the Ẽ12 cut-off likewise;
//! 6. thickness from the bend tests, with a_ij and G12 scaled by τ⁰/τ so that the membrane
//!    stiffnesses a·τ, and so the tensile fits, are kept.
//!
//! Stage variables are scaled to be O(1): ln c for the stiffness c, the μ₂…μ_d of η (μ₁ = 1 −
//! Σ the others), and β = α x̂ with x̂ the largest tested value of η's argument (Ẽ² at the
//! largest strain), so that β ≈ 1 is where η bends. a12 follows ½ min(a11, a22) (paper §3).
//!
//! Initial guesses and the polynomial degrees come from the homogeneous-strain strip
//! ([`bootstrap`]): each degree is fitted there from several starts (cheap), the lowest degree
//! that fits is kept, and the shell model then refines that fit with BFGS (or Gauss–Newton) on
//! each mesh of the ladder, each level started from the last. Forces and angles are
//! differentiated exactly through the equilibrium ([`crate::scene::StripRig`],
//! [`crate::scene::BendRig`]).

pub mod bootstrap;
pub mod optim;
pub mod report;

use crate::dataset::{BendTest, FabricDataset, TensileTest};
use crate::material::{Cutoffs, Eta, FabricMaterial, Orthotropic};
use crate::scene::{BendRig, CantileverBend, SceneError, StripRig, TensileStrip};
use bootstrap::homogeneous_curve;
use nalgebra::DMatrix;
use optim::{minimize, Evaluation, Method, OptimOptions};
use std::time::Instant;

/// The fit could not be done.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error("{0}")]
    Data(String),
    #[error("{stage}: {source}")]
    Scene { stage: String, source: SceneError },
}

/// Settings of `ks-fit fit`.
#[derive(Clone, Debug)]
pub struct FitOptions {
    /// Highest degree of each η tried.
    pub max_degree: usize,
    /// Use exactly this degree for every η (no automatic choice), for comparisons.
    pub fixed_degree: Option<usize>,
    /// Meshes of a 50 × 75 mm strip, coarse to fine; other strips keep the element size.
    pub ladder: Vec<(usize, usize)>,
    pub method: Method,
    /// Skip a finer level when it changes (measured, for the second level) or would change
    /// (estimated at order 1.5 from the last change, for later levels) the fitted forces by
    /// less than this, mean relative. Default 1 %: below the repeat-to-repeat scatter of
    /// real tests and the paper's fit errors (Table 3: 1–5 %).
    pub skip_tol: f64,
    /// A degree is raised only if that lowers the mean relative error by at least this factor.
    pub degree_gain: f64,
    /// Mean relative error below which a degree fits (no higher degree is tried).
    pub degree_good: f64,
    /// Most points per curve used by the fit (evenly spread along the elongation) on the
    /// finer levels, and on the first level.
    pub max_points: usize,
    pub coarse_points: usize,
    /// A stage stops once its rms relative error is below this, or when an iteration lowers
    /// the objective by less than `rel_decrease`.
    pub fit_tol: f64,
    pub rel_decrease: f64,
    pub max_iterations: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            max_degree: 3,
            fixed_degree: None,
            ladder: vec![(8, 12), (16, 24), (32, 48)],
            method: Method::Bfgs,
            skip_tol: 1e-2,
            degree_gain: 0.7,
            degree_good: 2e-3,
            max_points: 10,
            coarse_points: 8,
            fit_tol: 1e-3,
            rel_decrease: 1e-2,
            max_iterations: 25,
        }
    }
}

/// One test's outcome.
#[derive(Clone, Debug)]
pub struct TestOutcome {
    /// "tensile", "bend" or "validation"
    pub kind: &'static str,
    pub angle_deg: f64,
    /// the CSV file (tensile and validation)
    pub curve: Option<String>,
    /// mean |relative error| over the curve (paper Table 3 / 5)
    pub avg_rel_error: Option<f64>,
    /// fitted drape angle (paper Table 4)
    pub drape_angle_deg: Option<f64>,
    pub target_drape_deg: Option<f64>,
    /// solved alignment error of a validation run (paper Table 5)
    pub misalign_deg: Option<f64>,
    /// (elongation m, measured N, fitted N)
    pub points: Vec<(f64, f64, f64)>,
    pub used_in_fit: bool,
}

/// Where the time went.
#[derive(Clone, Debug, Default)]
pub struct FitStats {
    pub seconds: f64,
    /// shell-model evaluations (every run of a strip or cantilever)
    pub evaluations: usize,
    /// homogeneous-strip evaluations of the bootstrap (each a few microseconds)
    pub bootstrap_evaluations: usize,
    pub newton_iterations: usize,
    /// (stage, seconds)
    pub stage_seconds: Vec<(String, f64)>,
}

#[derive(Clone, Debug)]
pub struct FitResult {
    pub material: FabricMaterial,
    /// the minimiser's name
    pub method: String,
    pub meshes: Vec<(usize, usize)>,
    pub stats: FitStats,
    /// degree choice, one line per direction and degree tried
    pub degree_log: Vec<String>,
    /// what was not fitted and why, choices made
    pub notes: Vec<String>,
    pub tests: Vec<TestOutcome>,
}

/// Smallest and largest membrane strain (Ẽ11, Ẽ22, Ẽ12) a test exercised.
type StrainRange = ([f64; 3], [f64; 3]);

/// Which η and stiffness a stage fits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    Warp,
    Weft,
    Shear,
}

impl Direction {
    fn name(self) -> &'static str {
        match self {
            Self::Warp => "warp",
            Self::Weft => "weft",
            Self::Shear => "bias",
        }
    }
    fn angle(self) -> f64 {
        match self {
            Self::Warp => 90.0,
            Self::Weft => 0.0,
            Self::Shear => 45.0,
        }
    }
}

/// The map between a stage's variables p and the law.
#[derive(Clone, Copy, Debug)]
struct StageMap {
    dir: Direction,
    /// x̂: the largest tested value of η's argument
    xhat: f64,
}

impl StageMap {
    fn eta<'a>(&self, law: &'a Orthotropic) -> &'a Eta {
        match self.dir {
            Direction::Warp => &law.warp,
            Direction::Weft => &law.weft,
            Direction::Shear => &law.shear,
        }
    }

    fn encode(&self, law: &Orthotropic) -> Vec<f64> {
        let c = match self.dir {
            Direction::Warp => law.a11,
            Direction::Weft => law.a22,
            Direction::Shear => law.g12,
        };
        let eta = self.eta(law);
        let mut p = vec![c.ln()];
        p.extend(&eta.mu[1..]);
        p.extend(eta.alpha.iter().map(|a| a * self.xhat));
        p
    }

    fn degree(p: &[f64]) -> usize {
        (p.len()) / 2
    }

    fn decode(&self, p: &[f64], law: &mut Orthotropic) {
        let d = Self::degree(p);
        let c = p[0].exp();
        let mut mu = vec![1.0 - p[1..d].iter().sum::<f64>()];
        mu.extend(&p[1..d]);
        let alpha: Vec<f64> = p[d..2 * d].iter().map(|b| b / self.xhat).collect();
        let eta = Eta { mu, alpha };
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
        law.a12 = 0.5 * law.a11.min(law.a22);
    }

    /// The law parameters (then thickness) a stage's forces depend on through p.
    fn wanted(&self, law: &Orthotropic) -> Vec<bool> {
        let (d1, d3, d4) = (law.warp.degree(), law.weft.degree(), law.shear.degree());
        let mut w = vec![false; 4 + 2 * (d1 + d3 + d4) + 1];
        let (ci, offset, d) = match self.dir {
            Direction::Warp => (0, 4, d1),
            Direction::Weft => (1, 4 + 2 * d1, d3),
            Direction::Shear => (3, 4 + 2 * d1 + 2 * d3, d4),
        };
        w[ci] = true;
        w[2] = true;
        w[offset..offset + 2 * d].iter_mut().for_each(|v| *v = true);
        w
    }

    /// dF/dp from dF/dk (the law's parameters in [`Orthotropic::names`] order).
    fn chain(&self, p: &[f64], law: &Orthotropic, dk: &[f64]) -> Vec<f64> {
        let d = Self::degree(p);
        let c = p[0].exp();
        let (ci, offset) = {
            let (d1, d3) = (law.warp.degree(), law.weft.degree());
            match self.dir {
                Direction::Warp => (0, 4),
                Direction::Weft => (1, 4 + 2 * d1),
                Direction::Shear => (3, 4 + 2 * d1 + 2 * d3),
            }
        };
        let mut out = vec![0.0; 2 * d];
        out[0] = c * dk[ci];
        // a12 = ½ min(a11, a22)
        let owns_min = match self.dir {
            Direction::Warp => law.a11 <= law.a22,
            Direction::Weft => law.a22 < law.a11,
            Direction::Shear => false,
        };
        if owns_min {
            out[0] += 0.5 * c * dk[2];
        }
        for i in 1..d {
            out[i] = dk[offset + i] - dk[offset];
        }
        for i in 0..d {
            out[d + i] = dk[offset + d + i] / self.xhat;
        }
        out
    }
}

/// Relative residual at which the fit's equilibrium solves stop.
const FIT_RTOL: f64 = 1e-8;

/// Green strain along the axis at an elongation.
fn green(dl: f64, length: f64) -> f64 {
    let l = 1.0 + dl / length;
    0.5 * (l * l - 1.0)
}

/// A curve thinned to at most `n` points evenly spread along the elongation (last kept);
/// points with forces under 1e-3 of the largest are left out (relative errors blow up there).
fn fit_points(t: &TensileTest, n: usize) -> Vec<(f64, f64)> {
    let fmax = t.force.iter().cloned().fold(0.0, f64::max);
    let pts: Vec<(f64, f64)> = t
        .elongation
        .iter()
        .zip(&t.force)
        .filter(|(_, &f)| f > 1e-3 * fmax)
        .map(|(&e, &f)| (e, f))
        .collect();
    if pts.len() <= n {
        return pts;
    }
    let emax = pts.last().map_or(0.0, |p| p.0);
    let mut out: Vec<(f64, f64)> = Vec::new();
    for k in 1..=n {
        let target = emax * k as f64 / n as f64;
        let best = pts
            .iter()
            .min_by(|a, b| (a.0 - target).abs().total_cmp(&(b.0 - target).abs()))
            .copied();
        if let Some(p) = best {
            if out.last().is_none_or(|q| q.0 < p.0) {
                out.push(p);
            }
        }
    }
    out
}

fn max_force(t: &TensileTest) -> f64 {
    t.force.iter().cloned().fold(f64::MIN, f64::max)
}

/// Residuals and Jacobian rows of a curve: r = (F̂ − F)/F.
fn curve_residuals(
    measured: &[(f64, f64)],
    fitted: &[f64],
    dfitted: Option<&[Vec<f64>]>,
    out_r: &mut Vec<f64>,
    out_j: &mut Vec<Vec<f64>>,
) {
    for (i, &(_, f)) in measured.iter().enumerate() {
        out_r.push((fitted[i] - f) / f);
        if let Some(d) = dfitted {
            out_j.push(d[i].iter().map(|v| v / f).collect());
        }
    }
}

fn to_evaluation(r: Vec<f64>, j: Vec<Vec<f64>>, n: usize, jac: bool) -> Evaluation {
    let jacobian = jac.then(|| {
        let mut m = DMatrix::zeros(r.len(), n);
        for (i, row) in j.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                m[(i, c)] = *v;
            }
        }
        m
    });
    Evaluation {
        residuals: r,
        jacobian,
    }
}

fn mean_abs(r: &[f64]) -> f64 {
    r.iter().map(|v| v.abs()).sum::<f64>() / r.len().max(1) as f64
}

/// The fitter's working state.
struct Fitter<'a> {
    data: &'a FabricDataset,
    opts: &'a FitOptions,
    progress: &'a mut dyn FnMut(&str),
    start: Instant,
    stats: FitStats,
    law: Orthotropic,
    thickness: f64,
    degree_log: Vec<String>,
    notes: Vec<String>,
    /// drape angles of the bend tests at the last thickness stage's result
    bend_angles: Vec<f64>,
    /// strips already set up, warm
    rigs: std::collections::HashMap<RigKey, StripRig>,
    /// forces already predicted, by strip and parameter bits
    predictions: std::collections::HashMap<(RigKey, Vec<u64>), Vec<f64>>,
}

/// Newton iterations a trial point's cold solve may take after its warm start failed (cold
/// solves of the bundled fabrics take 3–10 iterations, 20–60 where the strip wrinkles; trial
/// points far from the fit took up to 500 and still failed).
const TRIAL_RETRY_ITERATIONS: usize = 100;

/// Strips cut within this many degrees of each other share warm starts.
const NEAR_ANGLE_DEG: f64 = 1.5;

/// ([width, gauge length, angle] bits, mesh level, elongation bits) of a cached strip.
type RigKey = ([u64; 3], (usize, usize), Vec<u64>);

impl Fitter<'_> {
    fn say(&mut self, msg: &str) {
        let t = self.start.elapsed().as_secs_f64();
        (self.progress)(&format!("[{t:7.1} s] {msg}"));
    }

    fn material(&self) -> FabricMaterial {
        FabricMaterial {
            name: self.data.name.clone(),
            areal_density: self.data.areal_density.unwrap_or(0.1),
            thickness: self.thickness,
            law: self.law.clone(),
        }
    }

    fn time_stage(&mut self, stage: &str, t: Instant) {
        let s = t.elapsed().as_secs_f64();
        if let Some(e) = self.stats.stage_seconds.iter_mut().find(|e| e.0 == stage) {
            e.1 += s;
        } else {
            self.stats.stage_seconds.push((stage.to_string(), s));
        }
    }

    /// Bootstrap fit of one direction at one degree from a start p, with the homogeneous
    /// strip; returns (p, mean relative error).
    fn bootstrap_fit(
        &mut self,
        map: StageMap,
        test: &TensileTest,
        points: &[(f64, f64)],
        p0: Vec<f64>,
    ) -> Option<(Vec<f64>, f64)> {
        let elong: Vec<f64> = points.iter().map(|p| p.0).collect();
        let mut p = p0;
        let base = self.law.clone();
        let tau = self.thickness;
        let opts = OptimOptions {
            method: Method::GaussNewton,
            max_iterations: 100,
            rel_decrease: 1e-10,
            gtol: 0.0,
            target: 0.0,
            max_step: 2.0,
        };
        let problem = |q: &[f64], jac: bool| -> Result<Evaluation, ()> {
            let mut law = base.clone();
            map.decode(q, &mut law);
            let curve = homogeneous_curve(
                &law,
                map.dir.angle(),
                test.width,
                test.gauge_length,
                tau,
                &elong,
                jac,
            )
            .map_err(|_| ())?;
            let fitted: Vec<f64> = curve.iter().map(|c| c.force).collect();
            let d: Vec<Vec<f64>> = curve
                .iter()
                .map(|c| map.chain(q, &law, &c.dforce))
                .collect();
            let (mut r, mut j) = (Vec::new(), Vec::new());
            curve_residuals(points, &fitted, jac.then_some(&d[..]), &mut r, &mut j);
            Ok(to_evaluation(r, j, q.len(), jac))
        };
        let rep = minimize(&mut p, &opts, problem).ok()?;
        self.stats.bootstrap_evaluations += rep.evaluations;
        let mut law = base;
        map.decode(&p, &mut law);
        let curve = homogeneous_curve(
            &law,
            map.dir.angle(),
            test.width,
            test.gauge_length,
            tau,
            &elong,
            false,
        )
        .ok()?;
        let r: Vec<f64> = points
            .iter()
            .zip(&curve)
            .map(|(m, c)| (c.force - m.1) / m.1)
            .collect();
        let err = mean_abs(&r);
        err.is_finite().then_some((p, err))
    }

    /// Degree choice and initial guess of one direction from the homogeneous strip.
    /// Returns the chosen degree's variables, and every degree's fit (index d − 1) tried.
    fn bootstrap(
        &mut self,
        map: StageMap,
        test: &TensileTest,
        points: &[(f64, f64)],
    ) -> (Vec<f64>, Vec<Vec<f64>>) {
        let (dl, f) = *points.last().expect("a curve with points");
        let lambda = 1.0 + dl / test.gauge_length;
        let e = green(dl, test.gauge_length);
        // secant stiffness of the whole curve as the start of degree 1
        let secant = f / (test.width * self.thickness * lambda * e);
        let c0 = match map.dir {
            Direction::Shear => 0.25 * secant,
            _ => secant,
        };
        let mut best: Option<(Vec<f64>, f64)> = None;
        for beta in [1e-3, 1.0, 5.0] {
            let p = vec![c0.ln(), beta];
            if let Some(r) = self.bootstrap_fit(map, test, points, p) {
                if best.as_ref().is_none_or(|b| r.1 < b.1) {
                    best = Some(r);
                }
            }
        }
        let Some(mut chosen) = best else {
            return (StageMap::encode(&map, &self.law), Vec::new());
        };
        let mut all = vec![chosen.0.clone()];
        let line = format!(
            "{}: degree 1, mean relative error {:.3} % (homogeneous strip)",
            map.dir.name(),
            100.0 * chosen.1
        );
        self.say(&line);
        self.degree_log.push(line);
        let fixed = self.opts.fixed_degree;
        for degree in 2..=fixed.unwrap_or(self.opts.max_degree) {
            if fixed.is_none() && chosen.1 <= self.opts.degree_good {
                let line = format!(
                    "{}: degree {} kept: error below {:.2} %",
                    map.dir.name(),
                    degree - 1,
                    100.0 * self.opts.degree_good
                );
                self.degree_log.push(line);
                break;
            }
            let prev = &chosen.0;
            let d = degree - 1;
            let mut best: Option<(Vec<f64>, f64)> = None;
            for mu_new in [0.3, -0.3, 0.7] {
                for beta_new in [0.5, 3.0, 15.0, 60.0] {
                    let mut p = vec![prev[0]];
                    p.extend(&prev[1..d]);
                    p.push(mu_new);
                    p.extend(&prev[d..2 * d]);
                    p.push(beta_new);
                    if let Some(r) = self.bootstrap_fit(map, test, points, p) {
                        if best.as_ref().is_none_or(|b| r.1 < b.1) {
                            best = Some(r);
                        }
                    }
                }
            }
            let Some(candidate) = best else { break };
            let line = format!(
                "{}: degree {degree}, mean relative error {:.3} % (homogeneous strip)",
                map.dir.name(),
                100.0 * candidate.1
            );
            self.say(&line);
            self.degree_log.push(line);
            all.push(candidate.0.clone());
            if fixed.is_some() || candidate.1 <= self.opts.degree_gain * chosen.1 {
                chosen = candidate;
            } else {
                let line = format!(
                    "{}: degree {d} kept: degree {degree} lowers the error by less than {:.0} %",
                    map.dir.name(),
                    100.0 * (1.0 - self.opts.degree_gain)
                );
                self.degree_log.push(line);
                break;
            }
        }
        (chosen.0, all)
    }
}

/// A strip mesh at a ladder level: the level's 50 × 75 mm mesh scaled to the strip.
fn strip_mesh(level: (usize, usize), width: f64, length: f64) -> (usize, usize) {
    let h = 0.05 / level.0 as f64;
    (
        ((width / h).round() as usize).max(2),
        ((length / h).round() as usize).max(2),
    )
}

/// A cantilever mesh at a ladder level (4 × (overhang / 6.25 mm) at 8 × 12, doubled per level).
fn bend_mesh(level: (usize, usize), bend: &BendTest) -> (usize, usize) {
    let f = level.0 as f64 / 8.0;
    let nx = ((4.0 * f).round() as usize).max(2);
    let ny = ((bend.overhang / (bend.width / 4.0) * f).round() as usize).max(4);
    (nx, ny)
}

impl Fitter<'_> {
    /// The rig of a test at an angle, mesh level and set of elongations: taken from the cache
    /// (warm, with its last equilibria) or set up; hand it back with [`Fitter::keep_rig`].
    fn strip_rig(
        &mut self,
        test: &TensileTest,
        angle: f64,
        level: (usize, usize),
        elong: &[f64],
    ) -> Result<(RigKey, StripRig), FitError> {
        // repeats share a strip when their geometry and elongations agree
        let key = (
            [
                test.width.to_bits(),
                test.gauge_length.to_bits(),
                angle.to_bits(),
            ],
            level,
            elong.iter().map(|e| e.to_bits()).collect::<Vec<u64>>(),
        );
        if let Some(rig) = self.rigs.remove(&key) {
            return Ok((key, rig));
        }
        let mut rig = self.new_rig(test, angle, level, elong)?;
        // a strip cut at a nearby angle (the validation Δθ grid) starts from the nearest such
        // strip's equilibria rather than from rest
        let nearest = self
            .rigs
            .iter()
            .filter(|(k, _)| k.0[..2] == key.0[..2] && k.1 == key.1 && k.2 == key.2)
            .map(|(k, r)| ((f64::from_bits(k.0[2]) - angle).abs(), r))
            .filter(|(d, _)| *d <= NEAR_ANGLE_DEG)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, other)) = nearest {
            rig.warm_from(other);
        }
        Ok((key, rig))
    }

    fn keep_rig(&mut self, key: RigKey, mut rig: StripRig) {
        rig.set_wanted(None);
        self.rigs.insert(key, rig);
    }

    fn new_rig(
        &self,
        test: &TensileTest,
        angle: f64,
        level: (usize, usize),
        elong: &[f64],
    ) -> Result<StripRig, FitError> {
        let mut strip = TensileStrip::new(test.width, test.gauge_length, angle);
        strip.mesh = strip_mesh(level, test.width, test.gauge_length);
        // thin off-axis strips wrinkle: allow the backward-Euler fallback time to settle them
        strip.solver.max_iterations = 500;
        // forces to 1e-8 are far inside any fit's reach; 1e-10 made Newton crawl at round-off
        strip.solver.rtol = FIT_RTOL;
        strip
            .rig(&self.material(), elong)
            .map_err(|source| FitError::Scene {
                stage: format!("setting up the {angle}° strip"),
                source,
            })
    }

    /// Runs a rig with the current material (forces, and ∂F/∂k when asked).
    fn run_strip(
        &mut self,
        rig: &mut StripRig,
        law: &Orthotropic,
        sens: bool,
    ) -> Result<(Vec<f64>, Vec<Vec<f64>>), SceneError> {
        rig.set_material(law, self.thickness)?;
        let pts = rig.run(sens)?;
        self.stats.evaluations += 1;
        self.stats.newton_iterations += pts.iter().map(|p| p.report.iterations).sum::<usize>();
        Ok((
            pts.iter().map(|p| p.force).collect(),
            pts.into_iter().map(|p| p.dforce).collect(),
        ))
    }

    /// One tensile stage on the shell model at one mesh level.
    fn shell_stage(
        &mut self,
        map: StageMap,
        test: &TensileTest,
        points: &[(f64, f64)],
        level: (usize, usize),
        strain_range: bool,
    ) -> Result<(f64, Option<StrainRange>), FitError> {
        let t0 = Instant::now();
        let elong: Vec<f64> = points.iter().map(|p| p.0).collect();
        let (key, mut rig) = self.strip_rig(test, map.dir.angle(), level, &elong)?;
        rig.set_wanted(Some(map.wanted(&self.law)));
        let mut p = map.encode(&self.law);
        let base = self.law.clone();
        // finer levels start from the last level's fit and only polish it
        let (max_iterations, rel_decrease) = if level == self.opts.ladder[0] {
            (self.opts.max_iterations, self.opts.rel_decrease)
        } else {
            (
                self.opts.max_iterations.min(5),
                self.opts.rel_decrease.max(0.05),
            )
        };
        let opts = OptimOptions {
            method: self.opts.method,
            max_iterations,
            rel_decrease,
            gtol: 1e-12,
            target: points.len() as f64 * self.opts.fit_tol.powi(2),
            max_step: 0.5,
        };
        let mut evals = 0;
        let mut newton = 0;
        let tau = self.thickness;
        let mut problem = |q: &[f64], jac: bool| -> Result<Evaluation, SceneError> {
            let mut law = base.clone();
            map.decode(q, &mut law);
            rig.set_material(&law, tau)?;
            // the stage's first evaluation must succeed; later ones are trials
            rig.retry_iterations = (evals > 0).then_some(TRIAL_RETRY_ITERATIONS);
            let pts = rig.run(jac);
            rig.retry_iterations = None;
            let pts = pts?;
            evals += 1;
            newton += pts.iter().map(|p| p.report.iterations).sum::<usize>();
            let fitted: Vec<f64> = pts.iter().map(|p| p.force).collect();
            let d: Vec<Vec<f64>> = pts.iter().map(|p| map.chain(q, &law, &p.dforce)).collect();
            let (mut r, mut j) = (Vec::new(), Vec::new());
            curve_residuals(points, &fitted, jac.then_some(&d[..]), &mut r, &mut j);
            Ok(to_evaluation(r, j, q.len(), jac))
        };
        let fail = |source| FitError::Scene {
            stage: format!("{} stage on {}×{}", map.dir.name(), level.0, level.1),
            source,
        };
        if level == self.opts.ladder[0] {
            // the homogeneous strip misjudges clamped strips' stiffness (most at 45°, where the
            // jaws stop the strip from shearing freely): first fit the stiffness c alone
            let rest = p[1..].to_vec();
            let mut scale = vec![p[0]];
            let one = OptimOptions {
                method: Method::GaussNewton,
                max_iterations: 10,
                rel_decrease: 1e-2,
                ..opts
            };
            minimize(&mut scale, &one, |q: &[f64], jac: bool| {
                let mut full = vec![q[0]];
                full.extend(&rest);
                let e = problem(&full, jac)?;
                Ok(Evaluation {
                    residuals: e.residuals,
                    jacobian: e.jacobian.map(|j| j.columns(0, 1).into_owned()),
                })
            })
            .map_err(fail)?;
            p[0] = scale[0];
        }
        let rep = minimize(&mut p, &opts, problem).map_err(fail)?;
        self.stats.evaluations += evals;
        self.stats.newton_iterations += newton;
        map.decode(&p, &mut self.law);
        let newton = newton;
        let err = (rep.objective / points.len() as f64).sqrt();
        let msg = format!(
            "{} stage, degree {}, mesh {}×{}: rms relative error {:.3} % after {} iterations, {} evaluations, {} Newton iterations ({})",
            map.dir.name(),
            StageMap::degree(&p),
            level.0,
            level.1,
            100.0 * err,
            rep.iterations,
            rep.evaluations,
            newton,
            rep.stop
        );
        self.say(&msg);
        let range = if strain_range {
            // the strains the test exercised, at the fitted parameters
            let law = self.law.clone();
            self.run_strip(&mut rig, &law, false)
                .map_err(|source| FitError::Scene {
                    stage: format!("{} strip at the fit", map.dir.name()),
                    source,
                })?;
            rig.strain_range()
        } else {
            None
        };
        self.keep_rig(key, rig);
        self.time_stage(map.dir.name(), t0);
        Ok((err, range))
    }

    /// Degree choice on the shell model: each candidate (degree d at index d − 1, from the
    /// homogeneous bootstrap) refined on the shell; a degree is kept unless the next lowers
    /// the rms error by the degree gain.
    #[allow(clippy::type_complexity)]
    fn shell_degree_ladder(
        &mut self,
        map: StageMap,
        test: &TensileTest,
        points: &[(f64, f64)],
        level: (usize, usize),
        candidates: &[Vec<f64>],
    ) -> Result<(f64, Option<StrainRange>), FitError> {
        let base = self.law.clone();
        let mut best: Option<(f64, Orthotropic, Option<StrainRange>)> = None;
        for (i, cand) in candidates.iter().enumerate() {
            let degree = i + 1;
            self.law = base.clone();
            match &best {
                // degree d + 1 starts from the shell's degree-d fit plus a small new term
                // (μ = 0.1) bending where the homogeneous fit put its last term
                Some((_, law, _)) if degree > 1 => {
                    let prev = map.encode(law);
                    let d = degree - 1;
                    let mut p = vec![prev[0]];
                    p.extend(&prev[1..d]);
                    p.push(0.1);
                    p.extend(&prev[d..2 * d]);
                    p.push(cand[2 * degree - 1]);
                    self.law = law.clone();
                    map.decode(&p, &mut self.law);
                }
                _ => map.decode(cand, &mut self.law),
            }
            let (err, range) = match self.shell_stage(map, test, points, level, true) {
                Ok(r) => r,
                Err(e) if best.is_some() => {
                    // this degree's start is not solvable (a law that softens to instability
                    // inside the tested strains): keep the last degree
                    let line = format!(
                        "{}: degree {degree} failed on the shell ({e}); degree {} kept",
                        map.dir.name(),
                        degree - 1
                    );
                    self.say(&line);
                    self.degree_log.push(line);
                    break;
                }
                Err(e) => return Err(e),
            };
            let line = format!(
                "{}: degree {degree}, rms relative error {:.3} % (shell, {}×{})",
                map.dir.name(),
                100.0 * err,
                level.0,
                level.1
            );
            self.degree_log.push(line);
            let better = match &best {
                None => true,
                Some(_) if self.opts.fixed_degree.is_some() => true,
                Some(b) => err <= self.opts.degree_gain * b.0,
            };
            if better {
                best = Some((err, self.law.clone(), range));
            } else {
                let line = format!(
                    "{}: degree {} kept: degree {degree} lowers the error by less than {:.0} %",
                    map.dir.name(),
                    degree - 1,
                    100.0 * (1.0 - self.opts.degree_gain)
                );
                self.say(&line);
                self.degree_log.push(line);
                break;
            }
            if self.opts.fixed_degree.is_none() && err <= self.opts.degree_good {
                let line = format!(
                    "{}: degree {degree} kept: error below {:.2} %",
                    map.dir.name(),
                    100.0 * self.opts.degree_good
                );
                self.degree_log.push(line);
                break;
            }
        }
        let (err, law, range) = best.expect("one candidate at least");
        self.law = law;
        Ok((err, range))
    }

    /// Thickness from the bend tests, a_ij and G12 scaled by τ⁰/τ.
    fn thickness_stage(
        &mut self,
        bends: &[BendTest],
        level: (usize, usize),
    ) -> Result<(), FitError> {
        let t0 = Instant::now();
        let mut rigs = Vec::new();
        for b in bends {
            let mut bend = CantileverBend::new(b.width, b.overhang, b.angle_deg);
            bend.mesh = bend_mesh(level, b);
            bend.solver.rtol = FIT_RTOL;
            let rig = BendRig::new(&bend, &self.material()).map_err(|source| FitError::Scene {
                stage: format!("setting up the {}° cantilever", b.angle_deg),
                source,
            })?;
            rigs.push(rig);
        }
        let (law0, tau0) = (self.law.clone(), self.thickness);
        let scaled = |q: &[f64]| {
            let tau = tau0 * q[0].exp();
            let s = tau0 / tau;
            let mut law = law0.clone();
            law.a11 *= s;
            law.a22 *= s;
            law.a12 *= s;
            law.g12 *= s;
            (law, tau)
        };
        let mut p = vec![0.0];
        // as for the tensile stages, finer levels only polish the last level's thickness
        let (max_iterations, rel_decrease) = if level == self.opts.ladder[0] {
            (self.opts.max_iterations, self.opts.rel_decrease)
        } else {
            (
                self.opts.max_iterations.min(5),
                self.opts.rel_decrease.max(0.05),
            )
        };
        let opts = OptimOptions {
            method: self.opts.method,
            max_iterations,
            rel_decrease,
            gtol: 1e-14,
            target: bends.len() as f64 * self.opts.fit_tol.powi(2),
            max_step: 0.5,
        };
        let mut evals = 0;
        let mut newton = 0;
        let problem = |q: &[f64], jac: bool| -> Result<Evaluation, SceneError> {
            let (law, tau) = scaled(q);
            let (mut r, mut j) = (Vec::new(), Vec::new());
            for (rig, b) in rigs.iter_mut().zip(bends) {
                rig.set_material(&law, tau)?;
                let pt = rig.run(jac)?;
                evals += 1;
                newton += pt.report.iterations;
                r.push((pt.drape_angle_deg - b.drape_angle_deg) / b.drape_angle_deg);
                if jac {
                    // d/d ln τ = τ ∂/∂τ − Σ a ∂/∂a over a11, a22, a12, g12
                    let d = &pt.dangle;
                    let dtau = tau * d[d.len() - 1]
                        - law.a11 * d[0]
                        - law.a22 * d[1]
                        - law.a12 * d[2]
                        - law.g12 * d[3];
                    j.push(vec![dtau / b.drape_angle_deg]);
                }
            }
            Ok(to_evaluation(r, j, 1, jac))
        };
        let rep = minimize(&mut p, &opts, problem).map_err(|source| FitError::Scene {
            stage: format!("thickness stage on {}×{}", level.0, level.1),
            source,
        })?;
        self.stats.evaluations += evals;
        self.stats.newton_iterations += newton;
        let (law, tau) = scaled(&p);
        // the drape angles at the accepted thickness (warm: a Newton step or two)
        self.bend_angles.clear();
        for rig in &mut rigs {
            rig.set_material(&law, tau)
                .and_then(|_| rig.run(false))
                .map(|pt| self.bend_angles.push(pt.drape_angle_deg))
                .map_err(|source| FitError::Scene {
                    stage: "drape angles at the fitted thickness".into(),
                    source,
                })?;
            self.stats.evaluations += 1;
        }
        self.law = law;
        self.thickness = tau;
        let msg = format!(
            "thickness stage, mesh {}×{}: τ = {:.4} mm, rms relative angle error {:.3} % ({} evaluations, {})",
            level.0,
            level.1,
            tau * 1e3,
            100.0 * (rep.objective / bends.len() as f64).sqrt(),
            rep.evaluations,
            rep.stop
        );
        self.say(&msg);
        self.time_stage("thickness", t0);
        Ok(())
    }

    /// Predicted forces of a test at an angle on a mesh level (no sensitivities).
    fn predict(
        &mut self,
        test: &TensileTest,
        angle: f64,
        points: &[(f64, f64)],
        level: (usize, usize),
    ) -> Result<Vec<f64>, FitError> {
        let elong: Vec<f64> = points.iter().map(|p| p.0).collect();
        let (key, mut rig) = self.strip_rig(test, angle, level, &elong)?;
        let law = self.law.clone();
        // the same strip with the same material was run already (another repeat, or the same
        // trial angle of another validation run)
        let mut params = law.params();
        params.push(self.thickness);
        let memo_key = (
            key.clone(),
            params.iter().map(|v| v.to_bits()).collect::<Vec<u64>>(),
        );
        if let Some(f) = self.predictions.get(&memo_key) {
            let f = f.clone();
            self.keep_rig(key, rig);
            return Ok(f);
        }
        let out = self
            .run_strip(&mut rig, &law, false)
            .map(|r| r.0)
            .map_err(|source| FitError::Scene {
                stage: format!("predicting the {angle}° strip"),
                source,
            });
        self.keep_rig(key, rig);
        if let Ok(f) = &out {
            self.predictions.insert(memo_key, f.clone());
        }
        out
    }

    /// The alignment error Δθ ∈ [−5°, 5°] that best explains a validation run: the mean
    /// squared relative error on a 1° grid (the predictions are shared by every repeat with
    /// the same elongations), refined by the parabola through the best grid point and its
    /// neighbours.
    fn misalignment(
        &mut self,
        test: &TensileTest,
        points: &[(f64, f64)],
        level: (usize, usize),
    ) -> f64 {
        let grid: Vec<f64> = (-5..=5).map(f64::from).collect();
        let costs: Vec<f64> = grid
            .iter()
            .map(
                |&d| match self.predict(test, test.angle_deg + d, points, level) {
                    Ok(f) => points
                        .iter()
                        .zip(&f)
                        .map(|(m, p)| ((p - m.1) / m.1).powi(2))
                        .sum(),
                    Err(_) => f64::INFINITY,
                },
            )
            .collect();
        let k = (0..grid.len())
            .min_by(|&i, &j| costs[i].total_cmp(&costs[j]))
            .unwrap_or(grid.len() / 2);
        if k == 0 || k + 1 == grid.len() {
            return grid[k];
        }
        let (l, c, r) = (costs[k - 1], costs[k], costs[k + 1]);
        let curvature = l - 2.0 * c + r;
        if !(curvature > 0.0 && curvature.is_finite()) {
            return grid[k];
        }
        grid[k] - (0.5 * (r - l) / curvature).clamp(-1.0, 1.0)
    }
}

/// Fits a dataset; progress lines go to `progress`.
pub fn fit(
    data: &FabricDataset,
    opts: &FitOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<FitResult, FitError> {
    if opts.ladder.is_empty() {
        return Err(FitError::Data("the mesh ladder is empty".into()));
    }
    if opts.max_degree == 0 {
        return Err(FitError::Data("--max-degree must be at least 1".into()));
    }
    let start = Instant::now();
    let mut notes = Vec::new();
    // repeats: warp and weft fit the repeat with the largest forces, bias the median one
    let pick = |angle: f64, median: bool| -> Option<TensileTest> {
        let mut runs: Vec<&TensileTest> = data.tests_at(angle);
        runs.sort_by(|a, b| max_force(a).total_cmp(&max_force(b)));
        let i = if median {
            runs.len() / 2
        } else {
            runs.len().checked_sub(1)?
        };
        runs.get(i).map(|t| (*t).clone())
    };
    let warp = pick(90.0, false);
    let weft = pick(0.0, false);
    let bias = pick(45.0, true);
    for (name, t, angle, rule) in [
        ("warp", &warp, 90.0, "the largest forces"),
        ("weft", &weft, 0.0, "the largest forces"),
        ("bias", &bias, 45.0, "the median largest force"),
    ] {
        let n = data.tests_at(angle).len();
        if let Some(t) = t {
            if n > 1 {
                notes.push(format!(
                    "{name}: fitted repeat {} of {n} ({rule})",
                    t.curve.display()
                ));
            }
        }
    }
    if warp.is_none() && weft.is_none() {
        return Err(FitError::Data(
            "no warp (90°) or weft (0°) tensile test: nothing to fit the stiffness to".into(),
        ));
    }
    if data.bend.is_empty() {
        notes.push(format!(
            "thickness not fitted (no bend tests): kept at the measured {:.3} mm",
            data.thickness * 1e3
        ));
    } else if data.areal_density.is_none() {
        return Err(FitError::Data(
            "bend tests need the areal density (areal_density_g_m2)".into(),
        ));
    }
    let mut f = Fitter {
        data,
        opts,
        progress,
        start,
        stats: FitStats::default(),
        law: Orthotropic {
            a11: 1.0e8,
            a22: 1.0e8,
            a12: 0.5e8,
            g12: 2.0e6,
            warp: Eta::linear(),
            weft: Eta::linear(),
            shear: Eta::linear(),
            cutoffs: Cutoffs::none(),
        },
        thickness: data.thickness,
        degree_log: Vec::new(),
        notes,
        bend_angles: Vec::new(),
        rigs: Default::default(),
        predictions: Default::default(),
    };
    let pts = |t: &Option<TensileTest>| t.as_ref().map(|t| fit_points(t, opts.max_points));
    let (wp, fp, bp) = (pts(&warp), pts(&weft), pts(&bias));
    let xhat = |t: &Option<TensileTest>, p: &Option<Vec<(f64, f64)>>, shear: bool| -> f64 {
        match (t, p) {
            (Some(t), Some(p)) if !p.is_empty() => {
                let e = green(p[p.len() - 1].0, t.gauge_length);
                if shear {
                    0.25 * e * e
                } else {
                    e * e
                }
            }
            _ => 1e-2,
        }
    };
    let maps = [
        StageMap {
            dir: Direction::Warp,
            xhat: xhat(&warp, &wp, false),
        },
        StageMap {
            dir: Direction::Weft,
            xhat: xhat(&weft, &fp, false),
        },
        StageMap {
            dir: Direction::Shear,
            xhat: xhat(&bias, &bp, true),
        },
    ];
    // 1. bootstrap: degrees and initial guesses from the homogeneous strip
    let t0 = Instant::now();
    let mut bias_candidates: Vec<Vec<f64>> = Vec::new();
    f.say("bootstrap on the homogeneous-strain strip");
    for (k, (t, p)) in [(&warp, &wp), (&weft, &fp)].into_iter().enumerate() {
        if let (Some(t), Some(p)) = (t, p) {
            let (q, _) = f.bootstrap(maps[k], t, p);
            let mut law = f.law.clone();
            maps[k].decode(&q, &mut law);
            f.law = law;
        }
    }
    match (&warp, &weft) {
        (None, Some(_)) => {
            f.law.a11 = f.law.a22;
            f.law.warp = f.law.weft.clone();
            f.notes
                .push("warp not fitted (no 90° test): taken equal to the weft".into());
        }
        (Some(_), None) => {
            f.law.a22 = f.law.a11;
            f.law.weft = f.law.warp.clone();
            f.notes
                .push("weft not fitted (no 0° test): taken equal to the warp".into());
        }
        _ => {}
    }
    f.law.a12 = 0.5 * f.law.a11.min(f.law.a22);
    if let (Some(t), Some(p)) = (&bias, &bp) {
        let (q, all) = f.bootstrap(maps[2], t, p);
        let mut law = f.law.clone();
        maps[2].decode(&q, &mut law);
        f.law = law;
        bias_candidates = all;
    } else {
        f.law.g12 = 0.02 * f.law.a11.min(f.law.a22);
        f.notes.push(format!(
            "shear not fitted (no 45° test): linear, G12 = 2 % of min(a11, a22) = {:.4e} Pa",
            f.law.g12
        ));
    }
    f.time_stage("bootstrap", t0);
    // 4. the shell model, coarse to fine
    let mut meshes = Vec::new();
    let mut previous: Option<Vec<f64>> = None;
    let mut last_change: Option<f64> = None;
    for (li, &level) in opts.ladder.iter().enumerate() {
        // 6. is this level worth it? the last level's parameters on this mesh: if the forces
        // barely move, the discretisation error is below the fit's reach
        if let (Some(change), true) = (last_change, li >= 2) {
            // the change this level would bring, from the last measured one at order 1.5
            // (the slowest order measured on strips: the 45° strip's clamped corners)
            let estimate = change / 2f64.powf(1.5);
            if estimate < opts.skip_tol {
                let from = meshes.last().copied().unwrap_or(level);
                let note = format!(
                    "meshes from {}×{} on skipped: estimated to change the {}×{} fit's forces by {:.2} % (the last level changed them by {:.2} %; below {:.2} %)",
                    level.0,
                    level.1,
                    from.0,
                    from.1,
                    100.0 * estimate,
                    100.0 * change,
                    100.0 * opts.skip_tol
                );
                f.say(&note);
                f.notes.push(note);
                break;
            }
        }
        if let Some(prev) = &previous {
            let mut now = Vec::new();
            for t in [&warp, &weft, &bias].into_iter().flatten() {
                now.extend(f.predict(t, t.angle_deg, &fit_points(t, opts.max_points), level)?);
            }
            let change = prev
                .iter()
                .zip(&now)
                .map(|(a, b)| ((b - a) / b).abs())
                .sum::<f64>()
                / now.len().max(1) as f64;
            let from = meshes.last().copied().unwrap_or(level);
            let msg = format!(
                "the {}×{} fit's forces change by {:.3} % (mean) on {}×{}",
                from.0,
                from.1,
                100.0 * change,
                level.0,
                level.1
            );
            f.say(&msg);
            last_change = Some(change);
            if change < opts.skip_tol {
                let note = format!(
                    "meshes from {}×{} on skipped: they change the {}×{} fit's forces by only {:.3} % (below {:.2} %)",
                    level.0,
                    level.1,
                    from.0,
                    from.1,
                    100.0 * change,
                    100.0 * opts.skip_tol
                );
                f.say(&note);
                f.notes.push(note);
                break;
            }
        }
        meshes.push(level);
        let n = if li == 0 {
            opts.coarse_points
        } else {
            opts.max_points
        };
        for (k, t) in [&warp, &weft, &bias].into_iter().enumerate() {
            let Some(t) = t else { continue };
            let p = &fit_points(t, n);
            let (_, range) = if k == 2 && li == 0 && bias_candidates.len() > 1 {
                // the homogeneous strip models a clamped bias strip poorly: choose the shear
                // degree on the shell model itself
                f.shell_degree_ladder(maps[2], t, p, level, &bias_candidates)?
            } else {
                f.shell_stage(maps[k], t, p, level, li == 0)?
            };
            // 3 and 5. cut-offs at 95 % of the largest strain the test exercised (over the
            // strip's Gauss points at the largest elongation), set once on the first mesh
            if let Some((lo, hi)) = range {
                let law = &mut f.law;
                let msg = match k {
                    0 => {
                        law.cutoffs.e11 = (0.0, 0.95 * hi[0]);
                        format!("cut-off Ẽ11 ≤ {:.4}", law.cutoffs.e11.1)
                    }
                    1 => {
                        law.cutoffs.e22 = (0.0, 0.95 * hi[1]);
                        format!("cut-off Ẽ22 ≤ {:.4}", law.cutoffs.e22.1)
                    }
                    _ => {
                        let e12 = 0.95 * hi[2].abs().max(lo[2].abs());
                        law.cutoffs.e12 = (-e12, e12);
                        format!("cut-off |Ẽ12| ≤ {e12:.4}")
                    }
                };
                f.say(&msg);
            }
        }
        if !data.bend.is_empty() {
            f.thickness_stage(&data.bend, level)?;
        }
        // this level's forces at its own fit, on the points the next level fits
        if li + 1 < opts.ladder.len() {
            let mut now = Vec::new();
            for t in [&warp, &weft, &bias].into_iter().flatten() {
                now.extend(f.predict(t, t.angle_deg, &fit_points(t, opts.max_points), level)?);
            }
            previous = Some(now);
        }
    }
    let last = *meshes.last().expect("one level at least");
    // 7. the report: every test at the final level
    let t0 = Instant::now();
    let mut tests = Vec::new();
    for t in &data.tensile {
        let angle = t.angle_deg;
        let fitted_angle = [0.0f64, 45.0, 90.0]
            .iter()
            .any(|a| (a - angle).abs() < 1e-9);
        let p = fit_points(t, opts.max_points);
        let used = [&warp, &weft, &bias]
            .iter()
            .any(|w| w.as_ref().is_some_and(|w| w.curve == t.curve));
        let (misalign, angle_used) = if fitted_angle {
            (None, angle)
        } else {
            let d = f.misalignment(t, &p, opts.ladder[0]);
            (Some(d), angle + d)
        };
        let pred = f.predict(t, angle_used, &p, last)?;
        let r: Vec<f64> = p.iter().zip(&pred).map(|(m, q)| (q - m.1) / m.1).collect();
        tests.push(TestOutcome {
            kind: if fitted_angle {
                "tensile"
            } else {
                "validation"
            },
            angle_deg: angle,
            curve: Some(t.curve.display().to_string()),
            avg_rel_error: Some(mean_abs(&r)),
            drape_angle_deg: None,
            target_drape_deg: None,
            misalign_deg: misalign,
            points: p.iter().zip(&pred).map(|(m, q)| (m.0, m.1, *q)).collect(),
            used_in_fit: used,
        });
    }
    for (b, &angle) in data.bend.iter().zip(&f.bend_angles) {
        tests.push(TestOutcome {
            kind: "bend",
            angle_deg: b.angle_deg,
            curve: None,
            avg_rel_error: None,
            drape_angle_deg: Some(angle),
            target_drape_deg: Some(b.drape_angle_deg),
            misalign_deg: None,
            points: Vec::new(),
            used_in_fit: true,
        });
    }
    f.time_stage("report", t0);
    f.stats.seconds = f.start.elapsed().as_secs_f64();
    let material = f.material();
    Ok(FitResult {
        material,
        method: format!("{:?}", opts.method).to_lowercase(),
        meshes,
        stats: f.stats,
        degree_log: f.degree_log,
        notes: f.notes,
        tests,
    })
}
