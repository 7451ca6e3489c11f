//! Where the fit's solves and polishes stop, and which strips share warm starts: the
//! tolerances the stages, rigs and checks share.

/// Relative residual at which the fit's equilibrium solves stop.
pub(super) const FIT_RTOL: f64 = 1e-8;

/// Newton iterations a trial point's cold solve may take after its warm start fails (cold
/// solves of the bundled fabrics take 3–10 iterations, 20–60 where the strip wrinkles; trial
/// points far from the fit can take 500 and still fail).
pub(super) const TRIAL_RETRY_ITERATIONS: usize = 100;

/// A finer level's polish stops, without trying it, when its next step would move every
/// variable by less than this: 0.1 % of a stiffness (its variable is ln c), a thousandth of a
/// term's share μ or of its bend β, a tenth of the mesh check's 1 % criterion. Such a step's
/// line search is all cost where a strip wrinkles: on the bundled cotton with
/// `--test-meshes strict`, the refit after its 67.5° strip is refined to 32 × 48 proposes a
/// step of 6e-4 in ln G12, whose first two trials fail on that strip (a stored wrinkle
/// pattern turns saddle under that change), and the step's line search would take the refit
/// from 20 s to about 50 s; no fitted value of the ten bundled fits (`own` and `strict`)
/// moves by more than 7.7e-4 for it (`paper_repro/fit_speed/strict.md`). It is not free
/// everywhere: on `paper_repro/mesh_independence`'s noise-free cotton it stops the 16 × 24
/// polish a step earlier, and the refit on the strips' own meshes then takes another path
/// (12 evaluations against 9; 146 against 116 s, G12 −0.45 against −0.42 % of the true value).
pub(super) const POLISH_XTOL: f64 = 1e-3;

/// Strips cut within this many degrees of each other share warm starts.
pub(super) const NEAR_ANGLE_DEG: f64 = 1.5;

/// Largest relative error of the interpolated model curve against solves between its nodes
/// before the interpolation check warns (0.1 %, a third of the mesh check's curve rule).
pub(super) const INTERPOLATION_TOL: f64 = 1e-3;
