//! Trust-region Newton on the factorised Hessian, in Levenberg–Marquardt form (Nocedal & Wright,
//! *Numerical Optimization*, 2nd ed., §4.1–4.3; Moré 1978 for the diagonal scaling).
//!
//! Each step solves (K + λD) d = −g, D the largest |diag K| seen so far (Moré's scaling: the
//! shift means the same thing for bending and membrane DOFs, whose stiffnesses are decades
//! apart). The shift λ plays the trust radius backwards: the model m(d) = g·d + ½ dᵀK d predicts
//! the energy drop, and the ratio ρ of actual to predicted drop sets the next λ (÷ 4 when
//! ρ > 3/4, × 4 when ρ < 1/4; the step is taken when ρ > 1e-4). No line search: a rejected step
//! costs one factorisation and one energy evaluation, no assembly. With λ = 0 the step is
//! Newton's, so convergence near the solution is quadratic. The backward-Euler solver stays as
//! the last resort the paper asks for: after [`MAX_REJECTIONS`] rejections in a row, or when no
//! shift makes the system positive definite, [`super::line_search`]'s solver (with its
//! fallback) takes over from the current state.

use super::measure::{linearize, Balance};
use super::perturb::perturb;
use super::{
    norm, refine, FreeSystem, Linearization, NewtonOptions, SolveError, SolveReport, Strategy,
    STALL_RTOL, STEP_FORCING,
};
use crate::model::{BlockMatrix, ClothModel};
use crate::Vec3;
use faer::prelude::Solve;
use faer::MatMut;
use std::time::Instant;

/// Shift at which a trust region starts once one is needed (a thousandth of the diagonal).
const LAMBDA_START: f64 = 1e-3;

/// Shifts below this are dropped to 0 (Newton's step).
const LAMBDA_DROP: f64 = 1e-9;

/// Rejected steps in a row before the line-search solver takes over.
pub const MAX_REJECTIONS: usize = 30;

/// What one trial step gave.
enum Trial {
    Taken,
    Rejected,
}

/// The trust-region solve (see the module docs); same contract as
/// [`super::newton_linearized`].
pub(super) fn trust_region(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    opts: &NewtonOptions,
) -> Result<(SolveReport, Option<Linearization>), SolveError> {
    let t0 = Instant::now();
    let nf = system.num_free;
    let mut grad = vec![[0.0; 3]; model.num_nodes()];
    let mut hess = BlockMatrix::zeros(model.pattern().clone());
    let mut values = Vec::new();
    let mut report = SolveReport {
        precision: opts.precision,
        ..SolveReport::default()
    };
    let external = model.external_load();
    let external_scale = norm(&external.concat());
    let (mut trial, mut gf) = (x.to_vec(), vec![0.0; nf]);
    let (mut scaling, mut lambda) = (vec![0.0; nf], 0.0f64);
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mass = system.free_mass(&model.lumped_mass());
    let (mut at_floor, mut last_residual) = (false, f64::INFINITY);
    system.apply_constraints(x);
    for it in 0..=opts.max_iterations {
        let (energy, balance) = linearize(
            model,
            system,
            x,
            it,
            (&mut grad, &mut hess, &mut values, &mut gf),
            (&external, external_scale),
            &mut report,
        )?;
        let Balance {
            gnorm,
            scale,
            floor,
        } = balance;
        // as in Newton: a step that does not halve a residual under STALL_RTOL is at the floor
        let stalled = gnorm <= STALL_RTOL * scale && (at_floor || gnorm >= 0.5 * last_residual);
        last_residual = gnorm;
        if gnorm <= opts.rtol * scale || gnorm <= floor || gnorm == 0.0 || stalled {
            report.precision_limited = gnorm > opts.rtol * scale;
            let llt = system.try_factor(&values)?;
            if llt.is_none() && opts.fallback && report.saddle_escapes < 5 {
                // a saddle: nudge it off; the shifted steps then follow the negative curvature
                report.saddle_escapes += 1;
                perturb(system, x, &mut seed);
                lambda = lambda.max(LAMBDA_START);
                (at_floor, last_residual) = (false, f64::INFINITY);
                continue;
            }
            report.stable = llt.is_some();
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
        metric(system, &values, &mass, &mut scaling);
        let taken = step(
            model,
            system,
            (x, &mut trial),
            (&values, &gf, &scaling),
            energy,
            &mut lambda,
            opts,
            (&mut report, &mut seed),
        )?;
        if !taken {
            if gnorm <= STALL_RTOL * scale {
                at_floor = true;
                continue;
            }
            return hand_over(model, system, x, opts, report, t0);
        }
    }
    Err(SolveError::NotConverged {
        iterations: opts.max_iterations,
        residual: report.residual,
        factorizations: report.factorizations,
    })
}

/// Trial steps from `x` until one is taken (true), the shift cannot make the system positive
/// definite, or [`MAX_REJECTIONS`] are rejected (false); rejections count as backtracks.
#[allow(clippy::too_many_arguments)]
fn step(
    model: &dyn ClothModel,
    system: &FreeSystem,
    (x, trial): (&mut [Vec3], &mut [Vec3]),
    (values, gf, scaling): (&[f64], &[f64], &[f64]),
    energy: f64,
    lambda: &mut f64,
    opts: &NewtonOptions,
    (report, seed): (&mut SolveReport, &mut u64),
) -> Result<bool, SolveError> {
    for _ in 0..MAX_REJECTIONS {
        match try_step(
            model,
            system,
            x,
            trial,
            (values, gf, scaling),
            energy,
            lambda,
            opts,
            report,
            seed,
        )? {
            Some(Trial::Taken) => return Ok(true),
            Some(Trial::Rejected) => report.backtracks += 1,
            None => break,
        }
    }
    Ok(false)
}

/// One trial step with the current shift; updates λ from the ratio ρ. `None`: no shift up to
/// 1e12 · D makes K + λD positive definite.
#[allow(clippy::too_many_arguments)]
fn try_step(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    trial: &mut [Vec3],
    (values, gf, scaling): (&[f64], &[f64], &[f64]),
    energy: f64,
    lambda: &mut f64,
    opts: &NewtonOptions,
    report: &mut SolveReport,
    seed: &mut u64,
) -> Result<Option<Trial>, SolveError> {
    let nf = system.num_free;
    let tf = Instant::now();
    let mut shifted = values.to_vec();
    let mut indefinite = false;
    let llt = loop {
        shifted.copy_from_slice(values);
        for (&k, &s) in system.diag.iter().zip(scaling) {
            shifted[k] += *lambda * s;
        }
        report.factorizations += 1;
        if let Some(llt) = system.try_factor(&shifted)? {
            break llt;
        }
        indefinite = true;
        *lambda = grow(*lambda);
        if *lambda > 1e12 {
            return Ok(None);
        }
    };
    // the shift hid negative curvature: go down it first (the trust region's hard case)
    if indefinite {
        let dir = super::curvature::direction(system, &llt, &shifted, *lambda, scaling, seed);
        if let Some((v, c)) = dir {
            if super::curvature::search(model, system, x, trial, (&v, c), gf, energy, report) {
                report.curvature_steps += 1;
                return Ok(Some(Trial::Taken));
            }
        }
    }
    let mut d: Vec<f64> = gf.iter().map(|g| -g).collect();
    let rhs = d.clone();
    llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut d, nf, 1));
    if opts.refine_steps > 0 {
        let rep = refine::refine_to(
            &system.sym_lower(&shifted),
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
    // (K + λD) d = −g gives dᵀK d = −g·d − λ dᵀD d, so the model's drop is
    // −(g·d + ½ dᵀK d) = −½ g·d + ½ λ dᵀD d, with no product by K
    let gd: f64 = gf.iter().zip(&d).map(|(g, d)| g * d).sum();
    let ddd: f64 = d.iter().zip(scaling).map(|(d, s)| d * d * s).sum();
    let predicted = -0.5 * gd + 0.5 * *lambda * ddd;
    trial.copy_from_slice(x);
    system.step(trial, &d, 1.0);
    let actual = match model.energy(trial) {
        Ok(e) if e.is_finite() => energy - e,
        _ => f64::NEG_INFINITY,
    };
    let rho = if predicted > 0.0 {
        actual / predicted
    } else {
        f64::NEG_INFINITY
    };
    // a change below round-off of the energy is no evidence either way: take it
    let round_off = actual.abs() <= 1e-14 * energy.abs().max(f64::MIN_POSITIVE);
    if rho > 0.75 || round_off {
        *lambda = if *lambda * 0.25 < LAMBDA_DROP {
            0.0
        } else {
            *lambda * 0.25
        };
    } else if rho < 0.25 {
        *lambda = grow(*lambda);
    }
    if rho > 1e-4 || round_off {
        x.copy_from_slice(trial);
        return Ok(Some(Trial::Taken));
    }
    Ok(Some(Trial::Rejected))
}

/// The trust region's metric D: the lumped mass, scaled so that its mean is K's mean diagonal
/// (so λ = 1 doubles the diagonal on average); K's mean diagonal alone where there is no mass.
fn metric(system: &FreeSystem, values: &[f64], mass: &[f64], out: &mut [f64]) {
    let n = out.len().max(1) as f64;
    let mean = system.diag.iter().map(|&k| values[k].abs()).sum::<f64>() / n;
    let mean_mass = mass.iter().sum::<f64>() / n;
    for (o, m) in out.iter_mut().zip(mass) {
        *o = if mean_mass > 0.0 {
            m / mean_mass * mean
        } else {
            mean
        }
        .max(f64::MIN_POSITIVE);
    }
}

/// The shift after a poor step: × 4, or [`LAMBDA_START`] from Newton's 0.
fn grow(lambda: f64) -> f64 {
    if lambda == 0.0 {
        LAMBDA_START
    } else {
        4.0 * lambda
    }
}

/// The trust region gave up: the line-search solver with the backward-Euler fallback goes on
/// from `x`, and the two reports are summed.
fn hand_over(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    opts: &NewtonOptions,
    before: SolveReport,
    t0: Instant,
) -> Result<(SolveReport, Option<Linearization>), SolveError> {
    if !opts.fallback {
        return Err(SolveError::Stalled {
            residual: before.residual,
        });
    }
    let rest = NewtonOptions {
        strategy: Strategy::Ramp,
        max_iterations: opts.max_iterations.saturating_sub(before.iterations),
        ..*opts
    };
    let (mut report, lin) = super::line_search::line_search(model, system, x, &rest)?;
    report.iterations += before.iterations;
    report.factorizations += before.factorizations;
    report.refinement_steps += before.refinement_steps;
    report.backtracks += before.backtracks;
    report.trust_region_gave_up = true;
    report.saddle_escapes += before.saddle_escapes;
    report.assembly_seconds += before.assembly_seconds;
    report.factor_seconds += before.factor_seconds;
    report.seconds = t0.elapsed().as_secs_f64();
    Ok((report, lin))
}
