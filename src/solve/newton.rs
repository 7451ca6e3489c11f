//! Newton's method with an energy line search and the backward-Euler fallback (Clyde et al.
//! 2017 §6).

use super::{
    norm, refine, FreeSystem, Linearization, NewtonOptions, SolveError, SolveReport, Strategy,
    STALL_RTOL, STEP_FORCING,
};
use crate::model::{BlockMatrix, ClothModel, Want};
use crate::Vec3;
use faer::prelude::Solve;
use faer::sparse::linalg::solvers::Llt;
use faer::MatMut;
use std::time::Instant;

/// Why the next step is a backward-Euler step.
enum Mode {
    Newton,
    BackwardEuler,
}

/// Whether `x` is a stable state of `system`: its reduced Hessian is positive definite (one
/// assembly and one Cholesky attempt; meaningful at an equilibrium).
pub fn is_stable(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &[Vec3],
) -> Result<bool, SolveError> {
    let mut x = x.to_vec();
    system.apply_constraints(&mut x);
    let mut grad = vec![[0.0; 3]; model.num_nodes()];
    let mut hess = BlockMatrix::zeros(model.pattern().clone());
    model
        .assemble(&x, Want::Hessian, Some(&mut grad), Some(&mut hess))
        .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
    let mut values = Vec::new();
    system.values(&hess, &mut values);
    Ok(system.try_factor(&values)?.is_some())
}

/// The relative residual ‖g_free‖ / force scale of `x` (constraints applied), as the solver
/// measures it at its first iteration (see the module docs of [`super`]): one gradient
/// assembly, for choosing between starts.
pub fn relative_residual(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &[Vec3],
) -> Result<f64, SolveError> {
    let mut x = x.to_vec();
    system.apply_constraints(&mut x);
    let mut grad = vec![[0.0; 3]; model.num_nodes()];
    model
        .assemble(&x, Want::Gradient, Some(&mut grad), None)
        .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
    let external = model.external_load();
    let scale = force_scale(&grad, &external, norm(&external.concat()));
    let gnorm = norm(&system.reduced(&grad));
    Ok(if scale > 0.0 { gnorm / scale } else { gnorm })
}

/// Solves for equilibrium from `x` (fixed DOFs keep their values, slaved ones follow), in place.
///
/// Each iteration assembles energy, gradient and Hessian and tests convergence. A Newton step
/// solves H d = −g (Cholesky, refined); a backward-Euler step solves (H + μM) d = −g, the
/// linearised minimiser of E(x) + μ/2 ‖x − x̂‖²_M (μ = 1/h², M the lumped mass), with μ raised
/// tenfold until the factorisation succeeds. Both are followed by a backtracking line search on
/// the energy. Backward Euler takes over when the Hessian is not positive definite, when the
/// Newton step is not a descent direction, when three Newton steps lower the energy by ≤ 0.1 %
/// without the residual falling tenfold (the paper's triggers), and when the line search cuts a
/// Newton step below 1/8. After each backward-Euler step Newton is tried again; h is adapted
/// like a trust region (μ ÷ 4 after a full step, × 4 after a cut one) and kept between uses.
///
/// With [`Strategy::TrustRegion`] the steps are trust-region steps instead (see
/// [`super::trust`]), the line search and backward Euler kept as the last resort.
pub fn newton(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    opts: &NewtonOptions,
) -> Result<SolveReport, SolveError> {
    newton_linearized(model, system, x, opts).map(|r| r.0)
}

/// [`newton`], also handing back the factorised tangent at the solution when it is positive
/// definite (the stability check factorises it anyway): sensitivities then cost no further
/// assembly or factorisation.
pub fn newton_linearized(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    opts: &NewtonOptions,
) -> Result<(SolveReport, Option<Linearization>), SolveError> {
    let result = match opts.strategy {
        Strategy::TrustRegion => super::trust::trust_region(model, system, x, opts),
        _ => line_search(model, system, x, opts),
    };
    if let Err(e) = &result {
        super::dump::on_failure(model, system, x, e);
    }
    result
}

/// Newton with the energy line search and the backward-Euler fallback (see [`newton`]).
pub(super) fn line_search(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    opts: &NewtonOptions,
) -> Result<(SolveReport, Option<Linearization>), SolveError> {
    let t0 = Instant::now();
    let nn = model.num_nodes();
    let nf = system.num_free;
    let mut grad = vec![[0.0; 3]; nn];
    let mut hess = BlockMatrix::zeros(model.pattern().clone());
    let mut values = Vec::new();
    let mut report = SolveReport {
        precision: opts.precision,
        ..SolveReport::default()
    };
    let external = model.external_load();
    let external_scale = norm(&external.concat());
    let mass = system.free_mass(&model.lumped_mass());
    let mut trial = x.to_vec();
    let mut gf = vec![0.0; nf];
    let mut d = vec![0.0; nf];
    let mut mode = Mode::Newton;
    // the convexified Hessian (allocated on first use) and its entries, and whether the last
    // fallback step was along negative curvature (the next one is then a step on the
    // convexified Hessian)
    let mut phess: Option<BlockMatrix> = None;
    let mut pvalues = Vec::new();
    let mut after_curvature = false;
    let mut mu = 0.0f64;
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut be_energy: Vec<f64> = Vec::new();
    // (energy, residual) after recent Newton steps, for the stagnation rule
    let mut history: Vec<(f64, f64)> = Vec::new();
    // a Newton step at a residual under STALL_RTOL found no use: the round-off floor
    let mut at_floor = false;
    system.apply_constraints(x);
    for it in 0..=opts.max_iterations {
        let (
            energy,
            Balance {
                gnorm,
                scale,
                floor,
            },
        ) = linearize(
            model,
            system,
            x,
            it,
            (&mut grad, &mut hess, &mut values, &mut gf),
            (&external, external_scale),
            &mut report,
        )?;
        // the floor estimate can miss: an off-axis strip at 0.03 % strain stalls at 8.6e-9
        // (its strains are differences of O(1) metrics, good to ε/strain). A Newton step that
        // does not halve a residual already under STALL_RTOL, or one the line search cannot
        // use there, means Newton is at the floor: forces good to 1e-6 are far inside any
        // measurement
        let stalled = gnorm <= STALL_RTOL * scale
            && (at_floor
                || (matches!(mode, Mode::Newton)
                    && history.last().is_some_and(|&(_, r)| gnorm >= 0.5 * r)));
        if gnorm <= opts.rtol * scale || gnorm <= floor || gnorm == 0.0 || stalled {
            report.precision_limited = gnorm > opts.rtol * scale;
            // an equilibrium whose Hessian is not positive definite is a saddle (a flat strip in
            // compression, held there by its own symmetry): nudge it off and go on
            let llt = system.try_factor(&values)?;
            let stable = llt.is_some();
            if !stable && opts.fallback && report.saddle_escapes < 5 && it < opts.max_iterations {
                report.saddle_escapes += 1;
                perturb(system, x, &mut seed);
                mode = Mode::BackwardEuler;
                history.clear();
                continue;
            }
            report.stable = stable;
            report.seconds = t0.elapsed().as_secs_f64();
            let lin = llt.map(|llt| Linearization {
                hessian: hess,
                gradient: grad,
                values,
                llt,
                stale: 0.0,
            });
            return Ok((report, lin));
        }
        if it == opts.max_iterations {
            break;
        }
        // stagnation: three Newton steps with ≤ 0.1 % energy drop and no tenfold residual drop
        // (not while full steps are taken: the energy may rise there by design)
        if let (Mode::Newton, true) = (&mode, history.len() >= 3 && it >= opts.full_steps) {
            let (e0, r0) = history[history.len() - 3];
            if e0 - energy <= 1e-3 * e0.abs() && gnorm > 0.1 * r0 && opts.fallback {
                report.fallbacks.stagnation += 1;
                mode = Mode::BackwardEuler;
                history.clear();
            }
        }
        let tf = Instant::now();
        // the factorisation is of the Hessian itself (Newton's, not shifted): a step on it may
        // be the last one (see `polish`)
        let mut own_hessian = false;
        let mut projected_step = false;
        let llt = match mode {
            Mode::Newton => match system.try_factor(&values)? {
                Some(llt) => {
                    own_hessian = true;
                    llt
                }
                None => {
                    report.factorizations += 1;
                    if !opts.fallback {
                        return Err(SolveError::Indefinite {
                            residual: report.residual,
                        });
                    }
                    report.fallbacks.indefinite += 1;
                    mode = Mode::BackwardEuler;
                    history.clear();
                    let convexified = if after_curvature && model.convexifies() {
                        let ph = phess
                            .get_or_insert_with(|| BlockMatrix::zeros(model.pattern().clone()));
                        convexified_factor(model, system, x, ph, &mut pvalues, &mut report)?
                    } else {
                        None
                    };
                    if let Some(llt) = convexified {
                        values.copy_from_slice(&pvalues);
                        projected_step = true;
                        llt
                    } else {
                        let llt = backward_euler_factor(
                            system,
                            &mut values,
                            &mass,
                            &mut mu,
                            &mut report,
                        )?;
                        if let Some(v) =
                            super::curvature::direction(system, &llt, &values, mu, &mass, &mut seed)
                        {
                            let moved = super::curvature::search(
                                model,
                                system,
                                x,
                                &mut trial,
                                (&v.0, v.1),
                                &gf,
                                energy,
                                &mut report,
                            );
                            if moved {
                                after_curvature = true;
                                report.factorizations += 1;
                                report.curvature_steps += 1;
                                mode = Mode::Newton;
                                continue;
                            }
                        }
                        llt
                    }
                }
            },
            Mode::BackwardEuler => {
                backward_euler_factor(system, &mut values, &mass, &mut mu, &mut report)?
            }
        };
        report.factorizations += 1;
        for (di, gi) in d.iter_mut().zip(&gf) {
            *di = -gi;
        }
        let rhs = d.clone();
        llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut d, nf, 1));
        if opts.refine_steps > 0 {
            let rep = refine::refine_to(
                &system.sym_lower(&values),
                &rhs,
                &mut d,
                opts.precision,
                opts.refine_steps,
                STEP_FORCING * norm(&rhs),
                |r| llt.solve_in_place(MatMut::from_column_major_slice_mut(r, nf, 1)),
            );
            report.refinement_steps += rep.steps;
        }
        report.factor_seconds += tf.elapsed().as_secs_f64();
        // chords from beyond √rtol only where Newton is converging: the solve's first step (a
        // warm start or a predictor), or after a step that cut the residual tenfold; a state
        // crawling through a wrinkle pattern would spend gradient assemblies on chords that
        // miss at every step (chords everywhere make the ratio-2e4 fit about 30 % slower)
        let converging = it == 0 || history.last().is_some_and(|&(_, r)| gnorm <= 0.1 * r);
        let reach = if converging {
            super::chord::polish_from(opts)
        } else {
            opts.rtol.sqrt()
        };
        if own_hessian && opts.polish && gnorm <= reach * scale {
            match super::chord::polish(
                model,
                system,
                (x, energy, gnorm, scale),
                &d,
                &llt,
                opts,
                (&external, external_scale),
                &values,
            ) {
                super::chord::Polish::Converged(done) => {
                    report.iterations = it + 1;
                    report.polished = true;
                    report.chord_steps += done.chord_steps;
                    report.energy = done.energy;
                    report.residual = done.residual;
                    report.precision_limited = done.at_floor;
                    report.stable = true;
                    report.seconds = t0.elapsed().as_secs_f64();
                    return Ok((
                        report,
                        Some(Linearization {
                            hessian: hess,
                            gradient: done.gradient,
                            values,
                            llt,
                            stale: if scale > 0.0 { gnorm / scale } else { 0.0 },
                        }),
                    ));
                }
                super::chord::Polish::Moved {
                    energy,
                    chord_steps,
                } => {
                    // the steps did not reach rtol but went down in energy and residual, or
                    // reached it where the tangent is not certified: they stand as this
                    // iteration's step, and the next linearises there
                    report.polish_misses += 1;
                    report.chord_steps += chord_steps;
                    history.push((energy, gnorm));
                    be_energy.clear();
                    continue;
                }
                super::chord::Polish::Missed { chord_steps } => {
                    report.polish_misses += 1;
                    report.chord_steps += chord_steps;
                }
            }
        }
        let slope: f64 = d.iter().zip(&gf).map(|(a, b)| a * b).sum();
        let descent = slope < 0.0;
        // backtracking (Armijo) line search on the energy
        let mut accepted = None;
        let mut alpha = 1.0;
        if descent && it < opts.full_steps && matches!(mode, Mode::Newton) {
            trial.copy_from_slice(x);
            system.step(&mut trial, &d, 1.0);
            accepted = model.energy(&trial).ok().filter(|e| e.is_finite());
        }
        if descent && accepted.is_none() {
            for _ in 0..40 {
                trial.copy_from_slice(x);
                system.step(&mut trial, &d, alpha);
                if let Ok(e) = model.energy(&trial) {
                    // accept a decrease, or a change below round-off of the energy
                    if e <= energy + 1e-4 * alpha * slope
                        || (e - energy).abs() <= 1e-14 * energy.abs().max(f64::MIN_POSITIVE)
                    {
                        accepted = Some(e);
                        break;
                    }
                }
                alpha *= 0.5;
                report.backtracks += 1;
            }
        }
        match (accepted, &mode) {
            (Some(e), Mode::Newton) => {
                x.copy_from_slice(&trial);
                history.push((e, gnorm));
                be_energy.clear();
                // a Newton step the line search had to cut below 1/8 is not trusted: the
                // quadratic model is poor here (large rotations of a thin shell, say)
                if alpha < 0.125 && report.residual <= STALL_RTOL {
                    at_floor = true;
                } else if alpha < 0.125 && opts.fallback {
                    report.fallbacks.short_step += 1;
                    mode = Mode::BackwardEuler;
                    history.clear();
                }
            }
            (Some(e), Mode::BackwardEuler) => {
                x.copy_from_slice(&trial);
                after_curvature = false;
                if projected_step {
                    report.convexified_steps += 1;
                } else {
                    report.backward_euler_steps += 1;
                }
                // creeping towards a saddle: the Hessian stays indefinite (we are in backward
                // Euler because Newton's factorisation failed) while the energy no longer
                // moves; the symmetric state will not leave by itself, so nudge it
                be_energy.push(e);
                let n = be_energy.len();
                if n >= 8
                    && (be_energy[n - 8] - e).abs() <= 1e-7 * e.abs()
                    && report.saddle_escapes < 5
                {
                    report.saddle_escapes += 1;
                    perturb(system, x, &mut seed);
                    be_energy.clear();
                }
                // trust-region-like control of the step size h = 1/√μ: longer after a full
                // step, shorter after a cut one; then try Newton again (if the Hessian is still
                // indefinite the next factorisation sends us straight back, with this μ)
                if alpha == 1.0 {
                    mu *= 0.25;
                } else {
                    mu *= 4.0;
                }
                mode = Mode::Newton;
            }
            (None, Mode::Newton) if report.residual <= STALL_RTOL => at_floor = true,
            (None, Mode::Newton) => {
                if !opts.fallback {
                    return Err(SolveError::Stalled {
                        residual: report.residual,
                    });
                }
                report.fallbacks.ascent += 1;
                mode = Mode::BackwardEuler;
                history.clear();
            }
            (None, Mode::BackwardEuler) => {
                // a stiffer regularisation gives a shorter, safer step
                mu = if mu > 0.0 { 10.0 * mu } else { 1.0 };
            }
        }
    }
    Err(SolveError::NotConverged {
        iterations: opts.max_iterations,
        residual: report.residual,
        factorizations: report.factorizations,
    })
}

/// The diagonal of the bounding box of `x`.
pub(super) fn size(x: &[Vec3]) -> f64 {
    let (lo, hi) = x
        .iter()
        .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
            (
                std::array::from_fn(|c| lo[c].min(p[c])),
                std::array::from_fn(|c| hi[c].max(p[c])),
            )
        });
    (0..3).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt()
}

/// A pseudo-random number in [−1, 1) (xorshift; deterministic from `seed`).
pub(super) fn uniform(seed: &mut u64) -> f64 {
    *seed ^= *seed << 13;
    *seed ^= *seed >> 7;
    *seed ^= *seed << 17;
    ((*seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0
}

/// Moves every free DOF by a pseudo-random amount of 1e-6 of the body's size (deterministic).
pub(super) fn perturb(system: &FreeSystem, x: &mut [Vec3], seed: &mut u64) {
    let size = size(x);
    let d: Vec<f64> = (0..system.num_free)
        .map(|_| uniform(seed) * 1e-6 * size)
        .collect();
    system.step(x, &d, 1.0);
}

/// Assembles and factorises the convexified Hessian at `x` ([`Want::ProjectedHessian`]: each
/// Gauss point's section tangent projected onto its positive semidefinite part, compression
/// dropped from the stress term, the moments' term left out) into `values`; `None` where it is
/// singular (its factorisation counted).
///
/// Used for the fallback step that follows a negative-curvature step: the curvature step
/// leaves the saddle, and a step on this tangent, which keeps every stiffness that is positive,
/// then moves the whole state down at once, where backward Euler (H + μM) damps every soft mode
/// alike. Alone, without the curvature steps, it cannot leave a symmetric saddle (its gradient
/// has no component along the buckling mode) and stalls there.
fn convexified_factor(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &[Vec3],
    hess: &mut BlockMatrix,
    values: &mut Vec<f64>,
    report: &mut SolveReport,
) -> Result<Option<Llt<usize, f64>>, SolveError> {
    let ta = Instant::now();
    model
        .assemble(x, Want::ProjectedHessian, None, Some(hess))
        .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
    report.assembly_seconds += ta.elapsed().as_secs_f64();
    system.values(hess, values);
    let llt = system.try_factor(values)?;
    if llt.is_none() {
        report.factorizations += 1;
    }
    Ok(llt)
}

/// Factorises H + μM, raising μ tenfold until the factorisation succeeds. `values` comes back
/// holding H + μM.
fn backward_euler_factor(
    system: &FreeSystem,
    values: &mut [f64],
    mass: &[f64],
    mu: &mut f64,
    report: &mut SolveReport,
) -> Result<Llt<usize, f64>, SolveError> {
    let mean_diag =
        system.diag.iter().map(|&k| values[k].abs()).sum::<f64>() / system.diag.len().max(1) as f64;
    let mean_mass = mass.iter().sum::<f64>() / mass.len().max(1) as f64;
    if !mu.is_finite() || *mu <= 0.0 {
        // start where the mass term is a thousandth of the stiffness
        *mu = 1e-3 * mean_diag / mean_mass.max(f64::MIN_POSITIVE);
    }
    let mut applied = 0.0;
    for _ in 0..40 {
        for (&k, &m) in system.diag.iter().zip(mass) {
            values[k] += (*mu - applied) * m;
        }
        applied = *mu;
        if let Some(llt) = system.try_factor(values)? {
            return Ok(llt);
        }
        report.factorizations += 1;
        *mu *= 10.0;
    }
    Err(SolveError::Linear(
        "no backward-Euler step size makes the system positive definite".into(),
    ))
}

/// One assembly at `x` (energy, gradient, Hessian; K's entries into `values`), measured by
/// [`balance`]; records the energy, the relative residual, the iteration and the assembly time
/// in `report`.
pub(super) fn linearize(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &[Vec3],
    it: usize,
    (grad, hess, values, gf): (&mut [Vec3], &mut BlockMatrix, &mut Vec<f64>, &mut [f64]),
    (external, external_scale): (&[Vec3], f64),
    report: &mut SolveReport,
) -> Result<(f64, Balance), SolveError> {
    let ta = Instant::now();
    let energy = model
        .assemble(x, Want::Hessian, Some(grad), Some(hess))
        .map_err(|e| SolveError::StartOutOfDomain(e.to_string()))?;
    report.assembly_seconds += ta.elapsed().as_secs_f64();
    report.energy = energy;
    system.values(hess, values);
    let b = balance(system, x, grad, external, external_scale, values, gf);
    report.residual = if b.scale > 0.0 {
        b.gnorm / b.scale
    } else {
        b.gnorm
    };
    // forces that overflow compare equal to an infinite round-off floor: never a solution
    if !b.gnorm.is_finite() {
        return Err(if it == 0 {
            SolveError::StartOutOfDomain("its forces are not finite".into())
        } else {
            SolveError::NotConverged {
                iterations: it,
                residual: report.residual,
                factorizations: report.factorizations,
            }
        });
    }
    report.iterations = it;
    if it == 0 && report.initial_residual.is_none() {
        report.initial_residual = Some(report.residual);
    }
    Ok((energy, b))
}

/// The out-of-balance force and what it is measured against.
pub(super) struct Balance {
    /// ‖g_free‖₂.
    pub gnorm: f64,
    /// ‖internal force over all DOFs‖₂ + ‖external load‖₂.
    pub scale: f64,
    /// The round-off floor of the force evaluation.
    pub floor: f64,
}

/// What a residual is measured against: ‖internal force over all DOFs (gradient plus the
/// external load)‖₂ + ‖external load‖₂ (`external_scale`).
fn force_scale(grad: &[Vec3], external: &[Vec3], external_scale: f64) -> f64 {
    let mut internal = 0.0;
    for (g, f) in grad.iter().zip(external) {
        for c in 0..3 {
            internal += (g[c] + f[c]).powi(2);
        }
    }
    internal.sqrt() + external_scale
}

/// Reduces `grad` into `gf` and measures it (see the module docs); `values` holds K's entries.
pub(super) fn balance(
    system: &FreeSystem,
    x: &[Vec3],
    grad: &[Vec3],
    external: &[Vec3],
    external_scale: f64,
    values: &[f64],
    gf: &mut [f64],
) -> Balance {
    system.reduce(grad, gf);
    // the round-off floor of the force evaluation: positions are known to ε‖x‖∞, so forces
    // to about ε‖diag K‖‖x‖∞ (residuals stall at 0.15–0.3 of this)
    let diag_norm = system
        .diag
        .iter()
        .map(|&k| values[k] * values[k])
        .sum::<f64>()
        .sqrt();
    let xmax = x.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    Balance {
        gnorm: norm(gf),
        scale: force_scale(grad, external, external_scale),
        floor: 2.0 * f64::EPSILON * diag_norm * xmax,
    }
}
