//! The automatic mesh of the lab commands (`bend` and `tensile` without `--mesh`): a short
//! ladder of meshes, each twice as fine as the last, each one's error estimated by Richardson
//! extrapolation (`kshell::converge`), and the coarsest within `--tol` kept. The choice and
//! the values it was made from are said on stderr; where no mesh passes, or the values do not
//! converge monotonically, the finest is kept with a WARNING.

use crate::lab_args::{check_strip_size, describe, SceneArgs, BEND_TOL_DEG, TENSILE_TOL};
use kshell::converge::{Chosen, ErrorMeasure};
use kshell::material::FabricMaterial;
use kshell::scene::{TensilePoint, TensileStrip, STRIP_GRADING};
use std::time::Instant;

/// Most meshes of the strip ladder (4, 8, 16, 32, 64 faces across for a 50 × 75 mm strip).
pub const TENSILE_LEVELS: usize = 5;
/// The strip ladder stops short of a mesh of more faces than this.
pub const TENSILE_MAX_FACES: usize = 20_000;

/// `--tol` for `bend`: a positive number of degrees.
fn bend_tol(args: &SceneArgs) -> Result<f64, String> {
    let tol = args.tol.unwrap_or(BEND_TOL_DEG);
    if tol.is_finite() && tol > 0.0 {
        Ok(tol)
    } else {
        Err(format!(
            "--tol must be a positive number of degrees, got {}",
            kshell::io::num(tol)
        ))
    }
}

/// `--tol` for `tensile`: a relative error in (0, 1).
pub fn tensile_tol(args: &SceneArgs) -> Result<f64, String> {
    let tol = args.tol.unwrap_or(TENSILE_TOL);
    if tol.is_finite() && tol > 0.0 && tol < 1.0 {
        Ok(tol)
    } else {
        Err(format!(
            "--tol must be a relative force error in (0, 1) (0.003 is 0.3 %), got {}",
            kshell::io::num(tol)
        ))
    }
}

/// The cantilever on three meshes (the default, then twice and four times as fine each way),
/// keeping the coarsest whose Richardson estimate of the drape-angle error is below `--tol`
/// degrees (the finest, with a warning, where none is or there is no estimate).
pub fn auto_bend(
    base: (usize, usize),
    args: &SceneArgs,
    run: impl Fn((usize, usize)) -> Result<kshell::scene::BendResult, String>,
) -> Result<kshell::scene::BendResult, String> {
    let tol = bend_tol(args)?;
    let (nx, ny) = base;
    let mut runs = Vec::new();
    for k in 0..3 {
        let mesh = (nx << k, ny << k);
        kshell::limits::check_mesh(&format!("mesh {}x{}", mesh.0, mesh.1), mesh.0, mesh.1)?;
        let t0 = Instant::now();
        let r = run(mesh)?;
        if args.verbose {
            eprintln!(
                "ks-fit: bend: {}x{}: {:.6}° ({:.2} s)",
                mesh.0,
                mesh.1,
                r.drape_angle_deg,
                t0.elapsed().as_secs_f64()
            );
        }
        runs.push((mesh, r, t0.elapsed().as_secs_f64()));
    }
    let levels = runs
        .iter()
        .map(|(mesh, r, secs)| kshell::converge::Level::solved(*mesh, 0, *secs, r.drape_angle_deg))
        .collect();
    let chosen = kshell::converge::analyse(levels).choose(tol, ErrorMeasure::Absolute);
    let i = chosen.index(runs.len());
    let (mesh, _, _) = runs[i];
    let said = match chosen {
        Chosen::Met { error: e, .. } => format!("estimated error {e:.3}° < --tol {tol}°"),
        Chosen::NotMet { error: e } => format!(
            "WARNING: no mesh meets --tol {}°; the finest, estimated error {e:.3}°",
            tol
        ),
        Chosen::NoEstimate => {
            "WARNING: the three angles do not converge monotonically, no error estimate; the finest"
                .into()
        }
    };
    let all: Vec<String> = runs
        .iter()
        .map(|(m, r, _)| format!("{}x{} {:.4}°", m.0, m.1, r.drape_angle_deg))
        .collect();
    eprintln!(
        "ks-fit: bend: mesh {}x{} chosen from {} ({said})",
        mesh.0,
        mesh.1,
        all.join(", ")
    );
    Ok(runs.swap_remove(i).1)
}

/// The first mesh of the strip ladder: 4 faces across the shorter side; square faces up to a
/// side ratio of 4, then faces up to 4 times longer than wide along a slender strip (whose
/// middle is strained uniformly; the grading crowds the cage at the jaws): 4 × 6 for 50 × 75
/// mm, 4 × 67 for 3 × 200 mm.
pub fn tensile_base(width: f64, length: f64) -> (usize, usize) {
    let count = |long: f64, short: f64| {
        let aspect = (long / short / 4.0).clamp(1.0, 4.0);
        ((4.0 * long / (short * aspect)).round() as usize).max(1)
    };
    if length >= width {
        (4, count(length, width))
    } else {
        (count(width, length), 4)
    }
}

/// The shell strip's curve on the automatic mesh: [`auto_ladder`] on graded cages
/// ([`STRIP_GRADING`] unless `--grading` says otherwise).
pub fn auto_tensile(
    strip: &TensileStrip,
    material: &FabricMaterial,
    elongations: &[f64],
    args: &SceneArgs,
) -> Result<Vec<TensilePoint>, String> {
    let mut strip = strip.clone();
    strip.grading = args.grading.unwrap_or(STRIP_GRADING);
    let g = strip.grading;
    let label = format!("grading {},{}", g.across, g.along);
    let size = (strip.width, strip.length);
    auto_ladder(size, &label, elongations.len(), args, |mesh| {
        let mut s = strip.clone();
        s.mesh = mesh;
        s.run(material, elongations).map_err(|e| e.to_string())
    })
}

/// A strip's curve (`run` on a mesh) on a growing ladder of meshes from [`tensile_base`],
/// each twice as fine as the last, stopping as soon as one mesh's estimated relative force
/// error ([`kshell::converge::curve_errors`]) is below `--tol`, after [`TENSILE_LEVELS`]
/// meshes, or short of one of over [`TENSILE_MAX_FACES`] faces; the choice is said on stderr
/// (`label` names the cages). Returns the chosen mesh's points.
pub fn auto_ladder(
    (width, length): (f64, f64),
    label: &str,
    steps: usize,
    args: &SceneArgs,
    run: impl Fn((usize, usize)) -> Result<Vec<TensilePoint>, String>,
) -> Result<Vec<TensilePoint>, String> {
    let tol = tensile_tol(args)?;
    let (nx, ny) = tensile_base(width, length);
    let mut runs: Vec<((usize, usize), Vec<TensilePoint>)> = Vec::new();
    let mut errors = Vec::new();
    let mut stop = None;
    for k in 0..TENSILE_LEVELS {
        let mesh = (nx << k, ny << k);
        if k >= 3 && mesh.0.saturating_mul(mesh.1) > TENSILE_MAX_FACES {
            stop = Some(format!(
                "the next mesh, {}x{}, is over {TENSILE_MAX_FACES} faces",
                mesh.0, mesh.1
            ));
            break;
        }
        check_strip_size("the automatic mesh", mesh, steps)?;
        let t0 = Instant::now();
        // a finer mesh that fails ends the ladder; the first must solve
        let points = match run(mesh) {
            Ok(p) => p,
            Err(e) if !runs.is_empty() => {
                stop = Some(format!("{}x{} failed: {e}", mesh.0, mesh.1));
                break;
            }
            Err(e) => return Err(e),
        };
        if args.verbose {
            let last = points.last().map_or(0.0, |p| p.force);
            eprintln!(
                "ks-fit: tensile: {}x{}: {last:.6} N at the last elongation ({:.2} s)",
                mesh.0,
                mesh.1,
                t0.elapsed().as_secs_f64()
            );
        }
        runs.push((mesh, points));
        let curves: Vec<Vec<f64>> = runs
            .iter()
            .map(|(_, p)| p.iter().map(|p| p.force).collect())
            .collect();
        errors = kshell::converge::curve_errors(&curves);
        if errors.iter().any(|e| e.is_some_and(|e| e < tol)) {
            break;
        }
    }
    let pick = errors.iter().position(|e| e.is_some_and(|e| e < tol));
    let i = pick.unwrap_or(runs.len() - 1);
    let pct = |e: f64| format!("{:.3} %", 100.0 * e);
    let said = match (pick, errors[i]) {
        (Some(_), Some(e)) => format!("estimated error {} < --tol {}", pct(e), pct(tol)),
        (None, Some(e)) => format!(
            "WARNING: no mesh meets --tol {}{}; the finest, estimated error {}",
            pct(tol),
            stop.map(|s| format!(" ({s})")).unwrap_or_default(),
            pct(e)
        ),
        _ => format!(
            "WARNING: the forces do not converge monotonically, no error estimate{}; the finest",
            stop.map(|s| format!(" ({s})")).unwrap_or_default()
        ),
    };
    let all: Vec<String> = runs
        .iter()
        .map(|(m, p)| {
            let f = p.last().map_or(0.0, |p| p.force);
            format!("{}x{} {f:.4}", m.0, m.1)
        })
        .collect();
    let (mesh, points) = runs.swap_remove(i);
    eprintln!(
        "ks-fit: tensile: mesh {}x{} ({label}) chosen from {} N at the last elongation ({said})",
        mesh.0,
        mesh.1,
        all.join(", ")
    );
    if args.verbose {
        for p in &points {
            eprintln!(
                "elongation {:.4} mm: {}",
                p.elongation * 1e3,
                describe(&p.report)
            );
        }
    }
    Ok(points)
}
