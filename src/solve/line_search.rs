//! Newton's method with an energy line search and the backward-Euler fallback (Clyde et al.
//! 2017 §6): the iteration behind [`super::newton`] under every strategy but the trust region,
//! and the trust region's last resort.

use super::chord::{self, Polish, Polished};
use super::fallback::{backward_euler_factor, convexified_factor};
use super::measure::{linearize, Balance};
use super::perturb::perturb;
use super::{
    norm, refine, FreeSystem, Linearization, NewtonOptions, SolveError, SolveReport, STALL_RTOL,
    STEP_FORCING,
};
use crate::model::{BlockMatrix, ClothModel};
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

/// Newton with the energy line search and the backward-Euler fallback (see [`super::newton`]).
pub(super) fn line_search(
    model: &dyn ClothModel,
    system: &FreeSystem,
    x: &mut [Vec3],
    opts: &NewtonOptions,
) -> Result<(SolveReport, Option<Linearization>), SolveError> {
    let mut s = Solver::new(model, system, x, opts);
    system.apply_constraints(x);
    for it in 0..=opts.max_iterations {
        let (energy, balance) = linearize(
            model,
            system,
            x,
            it,
            (&mut s.grad, &mut s.hess, &mut s.values, &mut s.gf),
            (&s.external, s.external_scale),
            &mut s.report,
        )?;
        let Balance {
            gnorm,
            scale,
            floor,
        } = balance;
        if s.converged(gnorm, scale, floor) {
            s.report.precision_limited = gnorm > opts.rtol * scale;
            // an equilibrium whose Hessian is not positive definite is a saddle (a flat strip in
            // compression, held there by its own symmetry): nudge it off and go on
            let llt = system.try_factor(&s.values)?;
            if llt.is_none()
                && opts.fallback
                && s.report.saddle_escapes < 5
                && it < opts.max_iterations
            {
                s.escape_saddle(x);
                continue;
            }
            return Ok(s.finish(llt));
        }
        if it == opts.max_iterations {
            break;
        }
        s.check_stagnation(energy, gnorm, it);
        let tf = Instant::now();
        let Some(step) = s.factor(x, energy)? else {
            continue;
        };
        s.report.factorizations += 1;
        s.solve_direction(&step.llt);
        s.report.factor_seconds += tf.elapsed().as_secs_f64();
        let reach = s.polish_reach(it, gnorm);
        if step.own_hessian && opts.polish && gnorm <= reach * scale {
            match s.polish(x, (energy, gnorm, scale), &step.llt) {
                Polish::Converged(done) => {
                    return Ok(s.finish_polished(it, done, step.llt, gnorm, scale));
                }
                Polish::Moved {
                    energy,
                    chord_steps,
                } => {
                    s.polish_moved(energy, chord_steps, gnorm);
                    continue;
                }
                Polish::Missed { chord_steps } => s.polish_missed(chord_steps),
            }
        }
        let (accepted, alpha) = s.search(x, energy, it);
        s.take(x, (accepted, alpha), gnorm, step.projected_step)?;
    }
    Err(SolveError::NotConverged {
        iterations: opts.max_iterations,
        residual: s.report.residual,
        factorizations: s.report.factorizations,
    })
}

/// A factorisation to step on.
struct Factored {
    llt: Llt<usize, f64>,
    /// The factorisation is of the Hessian itself (Newton's, not shifted): a step on it may be
    /// the last one (see [`chord::polish`]).
    own_hessian: bool,
    /// The factorisation is of the convexified Hessian.
    projected_step: bool,
}

/// What the line-search iteration carries from one iteration to the next.
struct Solver<'a> {
    model: &'a dyn ClothModel,
    system: &'a FreeSystem,
    opts: &'a NewtonOptions,
    t0: Instant,
    grad: Vec<Vec3>,
    hess: BlockMatrix,
    /// K's entries (or those of the shifted or convexified system stepped on)
    values: Vec<f64>,
    report: SolveReport,
    external: Vec<Vec3>,
    external_scale: f64,
    /// the lumped mass of the free DOFs, the metric of backward Euler
    mass: Vec<f64>,
    trial: Vec<Vec3>,
    /// the reduced gradient
    gf: Vec<f64>,
    /// the step
    d: Vec<f64>,
    mode: Mode,
    /// the convexified Hessian (allocated on first use) and its entries
    phess: Option<BlockMatrix>,
    pvalues: Vec<f64>,
    /// whether the last fallback step was along negative curvature (the next one is then a
    /// step on the convexified Hessian)
    after_curvature: bool,
    /// the backward-Euler weight μ = 1/h², kept between uses
    mu: f64,
    seed: u64,
    /// energies after recent backward-Euler steps, for the saddle creep rule
    be_energy: Vec<f64>,
    /// (energy, residual) after recent Newton steps, for the stagnation rule
    history: Vec<(f64, f64)>,
    /// a Newton step at a residual under STALL_RTOL found no use: the round-off floor
    at_floor: bool,
}

impl<'a> Solver<'a> {
    fn new(
        model: &'a dyn ClothModel,
        system: &'a FreeSystem,
        x: &[Vec3],
        opts: &'a NewtonOptions,
    ) -> Self {
        let t0 = Instant::now();
        let nn = model.num_nodes();
        let nf = system.num_free;
        let grad = vec![[0.0; 3]; nn];
        let hess = BlockMatrix::zeros(model.pattern().clone());
        let report = SolveReport {
            precision: opts.precision,
            ..SolveReport::default()
        };
        let external = model.external_load();
        let external_scale = norm(&external.concat());
        let mass = system.free_mass(&model.lumped_mass());
        Solver {
            model,
            system,
            opts,
            t0,
            grad,
            hess,
            values: Vec::new(),
            report,
            external,
            external_scale,
            mass,
            trial: x.to_vec(),
            gf: vec![0.0; nf],
            d: vec![0.0; nf],
            mode: Mode::Newton,
            phess: None,
            pvalues: Vec::new(),
            after_curvature: false,
            mu: 0.0,
            seed: 0x9e37_79b9_7f4a_7c15u64,
            be_energy: Vec::new(),
            history: Vec::new(),
            at_floor: false,
        }
    }

    /// Whether the residual `gnorm` ends the solve: under `rtol` of `scale`, under the round-off
    /// floor, or stalled there.
    fn converged(&self, gnorm: f64, scale: f64, floor: f64) -> bool {
        // the floor estimate can miss: an off-axis strip at 0.03 % strain stalls at 8.6e-9
        // (its strains are differences of O(1) metrics, good to ε/strain). A Newton step that
        // does not halve a residual already under STALL_RTOL, or one the line search cannot
        // use there, means Newton is at the floor: forces good to 1e-6 are far inside any
        // measurement
        let stalled = gnorm <= STALL_RTOL * scale
            && (self.at_floor
                || (matches!(self.mode, Mode::Newton)
                    && self.history.last().is_some_and(|&(_, r)| gnorm >= 0.5 * r)));
        gnorm <= self.opts.rtol * scale || gnorm <= floor || gnorm == 0.0 || stalled
    }

    /// Nudges `x` off a saddle and goes on in backward Euler.
    fn escape_saddle(&mut self, x: &mut [Vec3]) {
        self.report.saddle_escapes += 1;
        perturb(self.system, x, &mut self.seed);
        self.mode = Mode::BackwardEuler;
        self.history.clear();
    }

    /// The report and linearisation of an equilibrium, `llt` the factorised Hessian there
    /// (`None` where it is not positive definite).
    fn finish(mut self, llt: Option<Llt<usize, f64>>) -> (SolveReport, Option<Linearization>) {
        let stable = llt.is_some();
        self.report.stable = stable;
        self.report.seconds = self.t0.elapsed().as_secs_f64();
        let lin = llt.map(|llt| Linearization {
            hessian: self.hess,
            gradient: self.grad,
            values: self.values,
            llt,
            stale: 0.0,
        });
        (self.report, lin)
    }

    /// Stagnation: three Newton steps with ≤ 0.1 % energy drop and no tenfold residual drop
    /// send the iteration to backward Euler (not while full steps are taken: the energy may
    /// rise there by design).
    fn check_stagnation(&mut self, energy: f64, gnorm: f64, it: usize) {
        let many = self.history.len() >= 3 && it >= self.opts.full_steps;
        if let (Mode::Newton, true) = (&self.mode, many) {
            let (e0, r0) = self.history[self.history.len() - 3];
            if e0 - energy <= 1e-3 * e0.abs() && gnorm > 0.1 * r0 && self.opts.fallback {
                self.report.fallbacks.stagnation += 1;
                self.mode = Mode::BackwardEuler;
                self.history.clear();
            }
        }
    }

    /// The factorisation this iteration steps on; `None` where a negative-curvature step has
    /// already moved `x` (the iteration then goes on from there).
    fn factor(&mut self, x: &mut [Vec3], energy: f64) -> Result<Option<Factored>, SolveError> {
        let llt = match self.mode {
            Mode::Newton => match self.system.try_factor(&self.values)? {
                Some(llt) => {
                    return Ok(Some(Factored {
                        llt,
                        own_hessian: true,
                        projected_step: false,
                    }))
                }
                None => return self.indefinite(x, energy),
            },
            Mode::BackwardEuler => backward_euler_factor(
                self.system,
                &mut self.values,
                &self.mass,
                &mut self.mu,
                &mut self.report,
            )?,
        };
        Ok(Some(Factored {
            llt,
            own_hessian: false,
            projected_step: false,
        }))
    }

    /// Newton's factorisation failed: the fallback's factorisation (the convexified Hessian
    /// after a negative-curvature step, else H + μM), or a negative-curvature step (`None`).
    fn indefinite(&mut self, x: &mut [Vec3], energy: f64) -> Result<Option<Factored>, SolveError> {
        self.report.factorizations += 1;
        if !self.opts.fallback {
            return Err(SolveError::Indefinite {
                residual: self.report.residual,
            });
        }
        self.report.fallbacks.indefinite += 1;
        self.mode = Mode::BackwardEuler;
        self.history.clear();
        let model = self.model;
        let convexified = if self.after_curvature && model.convexifies() {
            let ph = self
                .phess
                .get_or_insert_with(|| BlockMatrix::zeros(model.pattern().clone()));
            convexified_factor(
                model,
                self.system,
                x,
                ph,
                &mut self.pvalues,
                &mut self.report,
            )?
        } else {
            None
        };
        if let Some(llt) = convexified {
            self.values.copy_from_slice(&self.pvalues);
            return Ok(Some(Factored {
                llt,
                own_hessian: false,
                projected_step: true,
            }));
        }
        let llt = backward_euler_factor(
            self.system,
            &mut self.values,
            &self.mass,
            &mut self.mu,
            &mut self.report,
        )?;
        if self.curvature_step(x, &llt, energy) {
            return Ok(None);
        }
        Ok(Some(Factored {
            llt,
            own_hessian: false,
            projected_step: false,
        }))
    }

    /// A step along a direction of negative curvature of H, found on the factorised H + μM;
    /// whether it moved `x`.
    fn curvature_step(&mut self, x: &mut [Vec3], llt: &Llt<usize, f64>, energy: f64) -> bool {
        if let Some(v) = super::curvature::direction(
            self.system,
            llt,
            &self.values,
            self.mu,
            &self.mass,
            &mut self.seed,
        ) {
            let moved = super::curvature::search(
                self.model,
                self.system,
                x,
                &mut self.trial,
                (&v.0, v.1),
                &self.gf,
                energy,
                &mut self.report,
            );
            if moved {
                self.after_curvature = true;
                self.report.factorizations += 1;
                self.report.curvature_steps += 1;
                self.mode = Mode::Newton;
                return true;
            }
        }
        false
    }

    /// Solves the factorised system for the step d = −K⁻¹g, refined.
    fn solve_direction(&mut self, llt: &Llt<usize, f64>) {
        let nf = self.system.num_free;
        for (di, gi) in self.d.iter_mut().zip(&self.gf) {
            *di = -gi;
        }
        let rhs = self.d.clone();
        llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut self.d, nf, 1));
        if self.opts.refine_steps > 0 {
            let rep = refine::refine_to(
                &self.system.sym_lower(&self.values),
                &rhs,
                &mut self.d,
                self.opts.precision,
                self.opts.refine_steps,
                STEP_FORCING * norm(&rhs),
                |r| llt.solve_in_place(MatMut::from_column_major_slice_mut(r, nf, 1)),
            );
            self.report.refinement_steps += rep.steps;
        }
    }

    /// The relative residual under which a step on the Hessian itself is polished.
    fn polish_reach(&self, it: usize, gnorm: f64) -> f64 {
        // chords from beyond √rtol only where Newton is converging: the solve's first step (a
        // warm start or a predictor), or after a step that cut the residual tenfold; a state
        // crawling through a wrinkle pattern would spend gradient assemblies on chords that
        // miss at every step (chords everywhere make the ratio-2e4 fit about 30 % slower)
        let converging = it == 0 || self.history.last().is_some_and(|&(_, r)| gnorm <= 0.1 * r);
        if converging {
            chord::polish_from(self.opts)
        } else {
            self.opts.rtol.sqrt()
        }
    }

    /// The step polished on its own factorisation (see [`chord::polish`]).
    fn polish(
        &self,
        x: &mut [Vec3],
        (energy, gnorm, scale): (f64, f64, f64),
        llt: &Llt<usize, f64>,
    ) -> Polish {
        chord::polish(
            self.model,
            self.system,
            (x, energy, gnorm, scale),
            &self.d,
            llt,
            self.opts,
            (&self.external, self.external_scale),
            &self.values,
        )
    }

    /// A polish whose steps did not reach rtol but went down in energy and residual, or reached
    /// it where the tangent is not certified: they stand as this iteration's step (ending at
    /// `energy`), and the next linearises there.
    fn polish_moved(&mut self, energy: f64, chord_steps: usize, gnorm: f64) {
        self.report.polish_misses += 1;
        self.report.chord_steps += chord_steps;
        self.history.push((energy, gnorm));
        self.be_energy.clear();
    }

    /// A polish that left `x` where it is.
    fn polish_missed(&mut self, chord_steps: usize) {
        self.report.polish_misses += 1;
        self.report.chord_steps += chord_steps;
    }

    /// The report and linearisation of an equilibrium reached by a polished step: the tangent
    /// is the one the step is computed on, stale by the relative residual there.
    fn finish_polished(
        mut self,
        it: usize,
        done: Polished,
        llt: Llt<usize, f64>,
        gnorm: f64,
        scale: f64,
    ) -> (SolveReport, Option<Linearization>) {
        let report = &mut self.report;
        report.iterations = it + 1;
        report.polished = true;
        report.chord_steps += done.chord_steps;
        report.energy = done.energy;
        report.residual = done.residual;
        report.precision_limited = done.at_floor;
        report.stable = true;
        report.seconds = self.t0.elapsed().as_secs_f64();
        (
            self.report,
            Some(Linearization {
                hessian: self.hess,
                gradient: done.gradient,
                values: self.values,
                llt,
                stale: if scale > 0.0 { gnorm / scale } else { 0.0 },
            }),
        )
    }

    /// Backtracking (Armijo) line search on the energy along the step from `x`: the energy
    /// accepted (`None` where the step is not a descent direction or no length is accepted)
    /// and the step length.
    fn search(&mut self, x: &[Vec3], energy: f64, it: usize) -> (Option<f64>, f64) {
        let slope: f64 = self.d.iter().zip(&self.gf).map(|(a, b)| a * b).sum();
        let descent = slope < 0.0;
        let mut accepted = None;
        let mut alpha = 1.0;
        if descent && it < self.opts.full_steps && matches!(self.mode, Mode::Newton) {
            self.trial.copy_from_slice(x);
            self.system.step(&mut self.trial, &self.d, 1.0);
            accepted = self
                .model
                .energy(&self.trial)
                .ok()
                .filter(|e| e.is_finite());
        }
        if descent && accepted.is_none() {
            for _ in 0..40 {
                self.trial.copy_from_slice(x);
                self.system.step(&mut self.trial, &self.d, alpha);
                if let Ok(e) = self.model.energy(&self.trial) {
                    // accept a decrease, or a change below round-off of the energy
                    if e <= energy + 1e-4 * alpha * slope
                        || (e - energy).abs() <= 1e-14 * energy.abs().max(f64::MIN_POSITIVE)
                    {
                        accepted = Some(e);
                        break;
                    }
                }
                alpha *= 0.5;
                self.report.backtracks += 1;
            }
        }
        (accepted, alpha)
    }

    /// Takes the line search's step (energy `accepted` at length `alpha`) or reacts to its
    /// failure, and chooses the next iteration's mode.
    fn take(
        &mut self,
        x: &mut [Vec3],
        (accepted, alpha): (Option<f64>, f64),
        gnorm: f64,
        projected_step: bool,
    ) -> Result<(), SolveError> {
        match (accepted, &self.mode) {
            (Some(e), Mode::Newton) => self.newton_step(x, e, alpha, gnorm),
            (Some(e), Mode::BackwardEuler) => self.backward_euler_step(x, e, alpha, projected_step),
            (None, Mode::Newton) if self.report.residual <= STALL_RTOL => self.at_floor = true,
            (None, Mode::Newton) => {
                if !self.opts.fallback {
                    return Err(SolveError::Stalled {
                        residual: self.report.residual,
                    });
                }
                self.report.fallbacks.ascent += 1;
                self.mode = Mode::BackwardEuler;
                self.history.clear();
            }
            (None, Mode::BackwardEuler) => {
                // a stiffer regularisation gives a shorter, safer step
                self.mu = if self.mu > 0.0 { 10.0 * self.mu } else { 1.0 };
            }
        }
        Ok(())
    }

    /// Moves `x` to the accepted Newton step (energy `e`, length `alpha`).
    fn newton_step(&mut self, x: &mut [Vec3], e: f64, alpha: f64, gnorm: f64) {
        x.copy_from_slice(&self.trial);
        self.history.push((e, gnorm));
        self.be_energy.clear();
        // a Newton step the line search had to cut below 1/8 is not trusted: the quadratic
        // model is poor here (large rotations of a thin shell, say)
        if alpha < 0.125 && self.report.residual <= STALL_RTOL {
            self.at_floor = true;
        } else if alpha < 0.125 && self.opts.fallback {
            self.report.fallbacks.short_step += 1;
            self.mode = Mode::BackwardEuler;
            self.history.clear();
        }
    }

    /// Moves `x` to the accepted backward-Euler step (energy `e`, length `alpha`), adapts μ and
    /// goes back to Newton.
    fn backward_euler_step(&mut self, x: &mut [Vec3], e: f64, alpha: f64, projected_step: bool) {
        x.copy_from_slice(&self.trial);
        self.after_curvature = false;
        if projected_step {
            self.report.convexified_steps += 1;
        } else {
            self.report.backward_euler_steps += 1;
        }
        // creeping towards a saddle: the Hessian stays indefinite (we are in backward Euler
        // because Newton's factorisation failed) while the energy no longer moves; the
        // symmetric state will not leave by itself, so nudge it
        self.be_energy.push(e);
        let n = self.be_energy.len();
        if n >= 8
            && (self.be_energy[n - 8] - e).abs() <= 1e-7 * e.abs()
            && self.report.saddle_escapes < 5
        {
            self.report.saddle_escapes += 1;
            perturb(self.system, x, &mut self.seed);
            self.be_energy.clear();
        }
        // trust-region-like control of the step size h = 1/√μ: longer after a full step,
        // shorter after a cut one; then try Newton again (if the Hessian is still indefinite
        // the next factorisation sends us straight back, with this μ)
        if alpha == 1.0 {
            self.mu *= 0.25;
        } else {
            self.mu *= 4.0;
        }
        self.mode = Mode::Newton;
    }
}
