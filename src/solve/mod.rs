//! Quasistatic equilibrium: Newton's method on the total energy over the free DOFs (Clyde et al.
//! 2017 §6).
//!
//! Clamped control points are Dirichlet values eliminated from the system; the reaction on them
//! is their entry of the energy gradient. Each Newton step solves H d = −g with faer's sparse
//! Cholesky, whose symbolic factorisation is computed once per constraint set
//! ([`FreeSystem`]) and reused for every numeric refactorisation. A non-positive pivot is met by
//! adding a growing multiple of the mean diagonal (a Levenberg shift) until the factorisation
//! succeeds; every solve's residual is checked. A backtracking line search on the energy keeps
//! each step a descent step, and halves steps that leave the law's domain.
//!
//! Converged means ‖g_free‖₂ ≤ `rtol` · (‖internal force over all DOFs‖₂ + ‖gravity load‖₂):
//! the out-of-balance force is a tiny fraction of the forces flowing through the structure; or
//! ‖g_free‖₂ ≤ 2 ε ‖diag K‖₂ ‖x‖∞, the round-off floor of the force evaluation (positions are
//! known to ε‖x‖∞; thin shells, whose stiffness spans ten decades, reach this floor first and
//! the report says so).

mod certificate;
mod chord;
mod continuation;
mod curvature;
pub mod dump;
mod fallback;
mod line_search;
mod linearization;
mod measure;
mod newton;
mod perturb;
pub mod refine;
mod system;
pub mod trust;

pub use continuation::{continuation, ContinuationReport};
pub use linearization::Linearization;
pub use newton::{is_stable, newton, newton_linearized, relative_residual};
pub use refine::Precision;
pub use system::{FreeSystem, Slave};

/// Relative residual below which a Newton iteration that no longer converges counts as having
/// reached the round-off floor (see [`newton`]).
pub(crate) const STALL_RTOL: f64 = 1e-6;

/// Linear residual of a Newton step, relative to its right-hand side, below which the step is
/// not refined (see [`refine::refine_to`]): from a relative residual r the step then leaves at
/// most 1e-8 r beside the O(r²) of the nonlinearity, under any `rtol` in use (1e-8 to 1e-10).
pub(crate) const STEP_FORCING: f64 = 1e-8;

/// The linear algebra could not be set up or failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SolveError {
    #[error("sparse factorisation set-up failed: {0}")]
    Setup(String),
    #[error("the material law is undefined at the starting configuration ({0})")]
    StartOutOfDomain(String),
    #[error(
        "Newton did not converge in {iterations} iterations (relative residual {residual:.3e})"
    )]
    NotConverged {
        iterations: usize,
        residual: f64,
        /// factorisations the attempt made (failed ones included), for counts of all the work
        factorizations: usize,
    },
    #[error("the line search found no decrease of the energy (relative residual {residual:.3e})")]
    Stalled { residual: f64 },
    #[error("linear solve failed: {0}")]
    Linear(String),
    #[error("the Hessian is not positive definite (plain Newton has no fallback; relative residual {residual:.3e})")]
    Indefinite { residual: f64 },
}

/// Newton settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonOptions {
    pub max_iterations: usize,
    /// Relative residual target (see the module docs).
    pub rtol: f64,
    /// Take backward-Euler steps when Newton cannot (indefinite Hessian, ascent direction,
    /// stagnation). Without it those cases are failures: that is plain Newton.
    pub fallback: bool,
    /// Arithmetic of the iterative-refinement residual.
    pub precision: Precision,
    /// Most refinement corrections per linear solve (0: none).
    pub refine_steps: usize,
    /// How a load is brought on ([`continuation`]) and how the first steps are accepted.
    pub strategy: Strategy,
    /// The first this-many Newton iterations take the full step wherever the energy is
    /// defined, even uphill (non-monotone: the energy line search would cut the first
    /// membrane-stretching step of a heavy cantilever to nothing); 0: always line-searched.
    pub full_steps: usize,
    /// A Newton step from a relative residual under √rtol is taken whole and checked by a
    /// gradient assembly, without a further Hessian assembly and factorisation where it lands
    /// within `rtol` (the tangent of the preceding point is kept as the linearisation). The
    /// line-search strategies only; the trust region assembles at its last point as at any other.
    pub polish: bool,
    /// Relative residual under which a polished Newton step may be finished by chord steps on
    /// its own factorisation (see `chord::polish`); the linearisation handed back is then the
    /// tangent where the chord began, marked [`Linearization::stale`]. Under √rtol it changes
    /// nothing.
    pub chord_from: f64,
}

/// The default [`NewtonOptions::chord_from`].
pub const CHORD_FROM: f64 = 5e-2;

/// How [`continuation`] brings on a load, and how each solve is globalised.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Strategy {
    /// Load steps from 1/8, doubled after easy solves, halved after failed ones; each solve
    /// Newton with an energy line search and the backward-Euler fallback.
    Ramp,
    /// First the whole load at once by full-step Newton (at most [`FULL_STEP_ITERATIONS`]
    /// iterations, kept only if it converges to a stable equilibrium), then the ramp from the
    /// start if it did not, each load step's first `continuation::RAMP_FULL_STEPS` Newton steps
    /// taken whole. The default: of ten cantilevers of the example material (20–400 mm, 0° and
    /// 45°) it solves nine and the ramp seven; on those seven it takes 952 Newton iterations
    /// where the ramp takes 1666 (heavy D1388 cantilever at 4×16: 15 against 108), drape angles
    /// equal to 1e-9.
    #[default]
    FullStep,
    /// Trust-region Newton on the factorised Hessian ([`trust`]) for every solve; the whole
    /// load first, then the ramp if that fails.
    TrustRegion,
    /// Load continuation whose step is set by the secant predictor's error: after each solve the
    /// step is scaled by √(tol / e), e the corrector's move relative to the last increment
    /// (the predictor's error is second order in the step), within ½–2×.
    Adaptive,
}

impl Strategy {
    /// Every strategy with its command-line name.
    pub const ALL: [(&'static str, Strategy); 4] = [
        ("ramp", Strategy::Ramp),
        ("full-step", Strategy::FullStep),
        ("trust-region", Strategy::TrustRegion),
        ("adaptive", Strategy::Adaptive),
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, s)| *s == self)
            .map_or("?", |(n, _)| n)
    }
}

impl std::str::FromStr for Strategy {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .iter()
            .find(|(n, _)| *n == s)
            .map(|(_, st)| *st)
            .ok_or_else(|| {
                format!(
                    "unknown strategy '{s}' (expected ramp, full-step, trust-region or adaptive)"
                )
            })
    }
}

/// Iteration budget of the full-step attempt (plain full-step Newton brings the heavy
/// ASTM D1388 cantilever from flat in 15).
pub const FULL_STEP_ITERATIONS: usize = 25;

impl Default for NewtonOptions {
    fn default() -> Self {
        Self {
            max_iterations: 60,
            rtol: 1e-10,
            fallback: true,
            precision: Precision::DoubleDouble,
            refine_steps: 4,
            strategy: Strategy::FullStep,
            full_steps: 0,
            polish: true,
            chord_from: CHORD_FROM,
        }
    }
}

impl NewtonOptions {
    /// Newton with a line search and nothing else (loads ramped).
    pub fn plain() -> Self {
        Self {
            fallback: false,
            refine_steps: 0,
            strategy: Strategy::Ramp,
            polish: false,
            ..Self::default()
        }
    }
}

/// Why backward Euler is used.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FallbackCounts {
    /// The Cholesky factorisation met a non-positive pivot (the Hessian is not positive definite).
    pub indefinite: usize,
    /// The Newton step is not a descent direction, or the line search finds no decrease.
    pub ascent: usize,
    /// Three consecutive Newton steps lowered the energy by ≤ 0.1 % in all without the residual
    /// falling tenfold.
    pub stagnation: usize,
    /// The line search cut a Newton step below 1/8 (our addition to the paper's triggers).
    pub short_step: usize,
}

/// What a solve did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolveReport {
    /// Newton and backward-Euler iterations.
    pub iterations: usize,
    pub energy: f64,
    /// ‖g_free‖ / force scale at the end.
    pub residual: f64,
    /// ‖g_free‖ / force scale at the start (`None` until the first assembly).
    pub initial_residual: Option<f64>,
    pub factorizations: usize,
    /// Backward-Euler steps taken, and why the solver turned to them.
    pub backward_euler_steps: usize,
    pub fallbacks: FallbackCounts,
    /// Refinement corrections applied over all linear solves, and the precision used.
    pub refinement_steps: usize,
    pub precision: Precision,
    /// Steps along a direction of negative curvature (see `curvature`), taken where Newton's
    /// factorisation failed.
    pub curvature_steps: usize,
    /// Steps on the convexified Hessian (`Want::ProjectedHessian`), taken after a
    /// negative-curvature step where Newton's factorisation fails again (see `newton`).
    pub convexified_steps: usize,
    /// Line-search step halvings in total (trust region: rejected steps).
    pub backtracks: usize,
    /// [`Strategy::TrustRegion`] only: the trust region gave up and the line-search solver
    /// with the backward-Euler fallback finished the solve.
    pub trust_region_gave_up: bool,
    pub assembly_seconds: f64,
    pub factor_seconds: f64,
    pub seconds: f64,
    /// Converged at the round-off floor of the force evaluation rather than by `rtol`.
    pub precision_limited: bool,
    /// The Hessian is positive definite at the solution (a stable equilibrium).
    pub stable: bool,
    /// Times an unstable equilibrium (a saddle) was perturbed and the solve continued.
    pub saddle_escapes: usize,
    /// The last Newton step is taken on the preceding point's factorisation and checked by a
    /// gradient assembly (see [`NewtonOptions::polish`]): the linearisation is that point's.
    pub polished: bool,
    /// Such last steps that missed `rtol` (each one gradient assembly spent; the solve went on).
    pub polish_misses: usize,
    /// Chord steps after polished Newton steps (each one gradient assembly and one
    /// back-substitution on the step's own factorisation; not counted as iterations).
    pub chord_steps: usize,
}

pub(crate) fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Makes every sparse factorisation sequential (faer's own parallelism off), so that a result
/// does not depend on the number of threads: faer's supernodal Cholesky splits its dense
/// updates by the rayon pool's size, and on the 32 × 48 strips a fit refines to, one thread and
/// two give fitted parameters differing in the 13th digit (`ks-fit batch --jobs 2` runs each
/// fit on one thread). The fit's independent solves run side by side instead, and on 2 cores
/// `Par::rayon(2)` is slower than sequential factorisation anyway (on an n = 30k shell-like
/// system). `ks-fit` calls this first; a library user who wants the same should too.
pub fn deterministic_factorizations() {
    faer::set_global_parallelism(faer::Par::Seq);
}
