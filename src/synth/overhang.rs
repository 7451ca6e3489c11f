//! The cantilevers' overhang search of [`super::synthesize`]: the overhang whose drape angle is
//! 41.5°, on the mesh `ks-fit bend` would choose (see the module doc of `synth`).

use super::*;
use crate::converge::ErrorMeasure;

/// The overhang (m) whose drape angle is 41.5° for a cantilever cut at `angle`: searched on
/// ladder level 0, the angle there checked on levels 1 and 2, and searched again on the
/// coarsest level whose estimated angle error is below [`BEND_TOL_DEG`] (the finest where
/// none is, or where the ladder does not converge monotonically).
pub(super) fn find_overhang(
    lab: &LabModel,
    angle: f64,
    test: &str,
    solves: &std::cell::Cell<usize>,
) -> Result<FoundOverhang, SynthError> {
    let target = DEFAULT_DRAPE_ANGLE_DEG;
    let weight = lab.areal_density() * crate::assembly::STANDARD_GRAVITY;
    let rigidity = lab.rigidity_guess(angle);
    let c = (rigidity / weight).cbrt();
    let mut guess = 2.0 * c;
    if !(guess.is_finite() && guess > 0.0) {
        return Err(SynthError::Bracket(format!(
            "{test}: no bending length from a rigidity of {rigidity} N·m and {} kg/m²",
            lab.areal_density()
        )));
    }
    // the mesh follows the overhang as `CantileverBend::new` chooses it; it is held during a
    // search (the angle is then smooth in the overhang) and the search repeated if the found
    // overhang asks for another mesh
    let mut found = None;
    for _ in 0..4 {
        let mesh = bend_mesh(guess, angle, 0);
        let f = search(lab, angle, mesh, guess, target, test, solves)?;
        found = Some((f, mesh));
        if bend_mesh(f.0, angle, 0) == mesh {
            break;
        }
        guess = f.0;
    }
    let ((overhang, angle0), mesh0) =
        found.ok_or_else(|| SynthError::Bracket(format!("{test}: no overhang found")))?;
    let mut ladder = vec![(mesh0, angle0)];
    for k in 1..BEND_LEVELS {
        let mesh = (mesh0.0 << k, mesh0.1 << k);
        solves.set(solves.get() + 1);
        let (a, _) = lab
            .cantilever((BEND_WIDTH, overhang, angle), mesh)
            .map_err(|source| SynthError::Scene {
                test: format!(
                    "{test} at overhang {:.4} mm on {}x{}",
                    overhang * 1e3,
                    mesh.0,
                    mesh.1
                ),
                source,
            })?;
        ladder.push((mesh, a));
    }
    let levels = ladder
        .iter()
        .map(|&(mesh, qoi)| crate::converge::Level::solved(mesh, 0, 0.0, qoi))
        .collect();
    let chosen =
        crate::converge::analyse_monotone(levels).choose(BEND_TOL_DEG, ErrorMeasure::Absolute);
    let k = chosen.index(ladder.len());
    let (mesh, angle_deg, overhang) = if k == 0 {
        (mesh0, angle0, overhang)
    } else {
        let mesh = ladder[k].0;
        let (l, a) = search(lab, angle, mesh, overhang, target, test, solves)?;
        (mesh, a, l)
    };
    Ok(FoundOverhang {
        overhang,
        angle_deg,
        mesh,
        error_deg: chosen.error(),
        ladder,
    })
}

/// Secant steps in ln(overhang) on a fixed mesh from `guess`, kept inside the bracket once
/// there is one (bisection when a step leaves it).
fn search(
    lab: &LabModel,
    angle: f64,
    mesh: (usize, usize),
    guess: f64,
    target: f64,
    test: &str,
    solves: &std::cell::Cell<usize>,
) -> Result<(f64, f64), SynthError> {
    let f = |ln_l: f64| -> Result<f64, SynthError> {
        solves.set(solves.get() + 1);
        let l = ln_l.exp();
        let (drape, stable) = lab
            .cantilever((BEND_WIDTH, l, angle), mesh)
            .map_err(|source| SynthError::Scene {
                test: format!("{test} at overhang {:.4} mm", l * 1e3),
                source,
            })?;
        if !stable {
            return Err(SynthError::Unstable {
                test: test.to_string(),
                what: format!("the cantilever at overhang {:.4} mm", l * 1e3),
            });
        }
        Ok(drape - target)
    };
    // the drape angle grows with the overhang, about 60° per unit of ln(overhang) near 41.5°
    let (mut x0, mut f0) = (guess.ln(), f(guess.ln())?);
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    let bracket = |x: f64, fx: f64, lo: &mut f64, hi: &mut f64| {
        if fx < 0.0 {
            *lo = lo.max(x);
        } else {
            *hi = hi.min(x);
        }
    };
    bracket(x0, f0, &mut lo, &mut hi);
    if f0.abs() <= ANGLE_TOL {
        return Ok((guess, f0 + target));
    }
    let mut x1 = x0 - (f0 / 60.0).clamp(-0.7, 0.7);
    let mut f1 = f(x1)?;
    bracket(x1, f1, &mut lo, &mut hi);
    for _ in 0..60 {
        if f1.abs() <= ANGLE_TOL {
            return Ok((x1.exp(), f1 + target));
        }
        let mut x2 = if f1 != f0 {
            x1 - f1 * (x1 - x0) / (f1 - f0)
        } else {
            f64::NAN
        };
        // without a bracket, go at most a factor 2 at a time; with one, stay inside it
        if !x2.is_finite() || (x2 - x1).abs() > 0.7 {
            x2 = x1 - 0.7 * f1.signum();
        }
        if lo.is_finite() && hi.is_finite() && !(x2 > lo && x2 < hi) {
            x2 = 0.5 * (lo + hi);
        }
        if lo.is_finite() && hi.is_finite() && hi - lo < 1e-12 {
            return Ok((x1.exp(), f1 + target));
        }
        (x0, f0) = (x1, f1);
        x1 = x2;
        f1 = f(x1)?;
        bracket(x1, f1, &mut lo, &mut hi);
    }
    Err(SynthError::Bracket(format!(
        "{test}: no overhang found whose drape angle is {target}° within {ANGLE_TOL}° (last {:.2} mm: {:.4}°)",
        x1.exp() * 1e3,
        f1 + target
    )))
}
