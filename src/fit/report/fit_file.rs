//! The fit file: the material file followed by the `[fit]` table and its subtables (the
//! uncertainty, the mesh check, the stages' times and iterations, one `[[fit.test]]` per test).

use super::{toml_key, toml_str};
use crate::fit::verdict::Judgement;
use crate::fit::{FitResult, TestOutcome};
use crate::io::toml_float;
use crate::material::material_toml;
use std::fmt::Write;

/// The material file followed by the `[fit]` table; loadable by every command that reads
/// materials (the loader reads past `[fit]`).
pub fn fit_toml(r: &FitResult, source: &str) -> String {
    let mut s = format!("# fitted by ks-fit fit from {source}\n");
    s += &material_toml(&r.material);
    let _ = writeln!(s, "\n[fit]");
    fit_settings(&mut s, r, source);
    coupling_errors(&mut s, r);
    degrees_and_mesh_change(&mut s, r);
    notes_and_verdict(&mut s, r);
    uncertainty_table(&mut s, r);
    mesh_check_table(&mut s, r);
    stage_tables(&mut s, r);
    let judged = crate::fit::verdict::judge(r, r.max_error);
    for (t, judgement) in r.tests.iter().zip(&judged) {
        test_table(&mut s, t, judgement);
    }
    s
}

/// The `[fit]` keys that say how the fit ran: dataset, meshes, method, work, and the choices
/// its options made.
fn fit_settings(s: &mut String, r: &FitResult, source: &str) {
    let _ = writeln!(s, "dataset = {}", toml_str(source));
    let meshes: Vec<String> = r
        .meshes
        .iter()
        .map(|m| toml_str(&format!("{}x{}", m.0, m.1)))
        .collect();
    let _ = writeln!(s, "meshes = [{}]", meshes.join(", "));
    let _ = writeln!(s, "method = {}", toml_str(&r.method));
    let _ = writeln!(s, "wall_seconds = {:.3}", r.stats.seconds);
    let _ = writeln!(s, "objective_evaluations = {}", r.stats.evaluations);
    let _ = writeln!(s, "newton_iterations = {}", r.stats.newton_iterations);
    let _ = writeln!(
        s,
        "equilibria_solved = {}    # strip nodes and cantilevers solved, every run (Newton iterations per equilibrium: newton_iterations / equilibria_solved)",
        r.stats.equilibria
    );
    let _ = writeln!(
        s,
        "yarn_rule = {}    # how the strips integrated the yarn terms (--yarn-rule; auto as decided)",
        toml_str(r.yarn_rule.name())
    );
    let _ = writeln!(
        s,
        "shear_coupling = {}    # the tension–shear coupling (--shear-coupling): off, not tried, not kept or kept",
        toml_str(r.shear_coupling.name())
    );
    let _ = writeln!(
        s,
        "objective = {}    # the misfit each point added squared (--objective; auto as decided): relative (F̂ − F)/F or log ln(F̂/F)",
        toml_str(r.objective.name())
    );
    let _ = writeln!(
        s,
        "joint = {}    # the warp and weft stages refitted over the off-axis strips too (--joint; auto as decided)",
        r.joint
    );
    let _ = writeln!(
        s,
        "test_meshes = {}    # each test's mesh (--test-meshes): own, strict (a curve the mesh check moves by 0.3 % refines its strip too) or ladder",
        toml_str(r.test_meshes.name())
    );
}

/// The shear stage's errors without and with the tension–shear coupling, when the fit tries it.
fn coupling_errors(s: &mut String, r: &FitResult) {
    if let crate::fit::coupling::CouplingOutcome::Kept { without, with }
    | crate::fit::coupling::CouplingOutcome::Rejected { without, with, .. } = &r.shear_coupling
    {
        // -1: the coupled stage failed
        let v = |x: f64| if x.is_finite() { x } else { -1.0 };
        let _ = writeln!(
            s,
            "shear_coupling_errors = {{ shape_without = {:.6}, shape_with = {:.6}, rms_without = {:.6}, rms_with = {:.6} }}    # the shear stage's on the first mesh, without and with it",
            v(without.shape),
            v(with.shape),
            v(without.rms),
            v(with.rms)
        );
    }
}

/// The law's degrees and the mesh check's summary keys.
fn degrees_and_mesh_change(s: &mut String, r: &FitResult) {
    let _ = writeln!(
        s,
        "degrees = {{ warp = {}, weft = {}, shear = {} }}",
        r.material.law.warp.degree(),
        r.material.law.weft.degree(),
        r.material.law.shear.degree()
    );
    if let Some(m) = &r.mesh_check {
        let _ = writeln!(
            s,
            "mesh_change = {:.6}    # largest relative change of a determined parameter if the last mesh were refined once more (first-order refit on {}x{})",
            m.change, m.mesh.0, m.mesh.1
        );
        let _ = writeln!(s, "mesh_change_parameter = {}", toml_str(&m.parameter));
        let _ = writeln!(s, "mesh_change_curves = {:.6}", m.curve_change);
        let _ = writeln!(
            s,
            "mesh_check_mesh = {}",
            toml_str(&format!("{}x{}", m.mesh.0, m.mesh.1))
        );
        let _ = writeln!(
            s,
            "mesh_check_solved_on = {}",
            toml_str(&format!("{}x{}", m.solved_on.0, m.solved_on.1))
        );
        if let Some(a) = m.angle_change_deg {
            let _ = writeln!(s, "mesh_change_drape_deg = {a:.4}");
        }
    }
}

/// The notes, the identifiability and degree logs, and the verdict.
fn notes_and_verdict(s: &mut String, r: &FitResult) {
    let notes: Vec<String> = r.notes.iter().map(|n| toml_str(n)).collect();
    let _ = writeln!(s, "notes = [{}]", notes.join(", "));
    let ident: Vec<String> = r.identifiability.iter().map(|n| toml_str(n)).collect();
    let _ = writeln!(s, "identifiability = [{}]", ident.join(", "));
    for (name, d) in ["warp", "weft", "off_axis"].iter().zip(r.a12_dependence) {
        if let Some(d) = d {
            let _ = writeln!(
                s,
                "a12_dependence_{name} = {d:.6}    # relative change of these strips' smallest-elongation force with a12 = 0 at the same E1, E2 and off-axis compliance"
            );
        }
    }
    let log: Vec<String> = r.degree_log.iter().map(|n| toml_str(n)).collect();
    let _ = writeln!(s, "degree_choice = [{}]", log.join(", "));
    let verdict = crate::fit::verdict::verdict(r, r.max_error);
    let _ = writeln!(s, "max_error = {}", r.max_error);
    let _ = writeln!(s, "passed = {}", verdict.passed());
    let _ = writeln!(s, "verdict = {}", toml_str(&verdict.line));
}

/// `[fit.uncertainty]`: each parameter's standard error, where the fit estimates any.
fn uncertainty_table(s: &mut String, r: &FitResult) {
    if !r.uncertainty.is_empty() {
        let _ = writeln!(
            s,
            "\n[fit.uncertainty]    # standard errors at the optimum; basis: curves (spread across curves and repeats), points (independent point errors: a lower bound), none (not estimable), assumed"
        );
        for e in &r.uncertainty {
            let se = e
                .std_error
                .map(|v| format!(", std_error = {v:.4e}"))
                .unwrap_or_default();
            let _ = writeln!(
                s,
                "{} = {{ value = {:?}{se}, basis = {}, determined = {} }}",
                toml_key(&e.name),
                e.value,
                toml_str(e.basis),
                e.determined
            );
        }
    }
}

/// `[fit.mesh_check]`: each determined quantity's change, where the fit checks the mesh.
fn mesh_check_table(s: &mut String, r: &FitResult) {
    if let Some(m) = &r.mesh_check {
        let _ = writeln!(
            s,
            "\n[fit.mesh_check]    # relative change of each determined quantity if the last mesh were refined to {}x{} (first-order refit)",
            m.mesh.0, m.mesh.1
        );
        for (name, c) in &m.changes {
            let _ = writeln!(s, "{} = {c:.6}", toml_key(name));
        }
    }
}

/// `[fit.stage_seconds]` and `[fit.stage_iterations]`.
fn stage_tables(s: &mut String, r: &FitResult) {
    let _ = writeln!(s, "\n[fit.stage_seconds]");
    for (stage, t) in &r.stats.stage_seconds {
        let _ = writeln!(s, "{} = {t:.3}", toml_str(stage));
    }
    let _ = writeln!(
        s,
        "\n[fit.stage_iterations]    # Newton iterations per stage"
    );
    for (stage, n) in &r.stats.stage_iterations {
        let _ = writeln!(s, "{} = {n}", toml_str(stage));
    }
}

/// One `[[fit.test]]`: what the test is, its errors and its judgement.
fn test_table(s: &mut String, t: &TestOutcome, judgement: &Judgement) {
    let _ = writeln!(s, "\n[[fit.test]]");
    let _ = writeln!(s, "kind = {}", toml_str(t.kind));
    let _ = writeln!(s, "angle_deg = {:?}", t.angle_deg);
    if let Some(c) = &t.curve {
        let _ = writeln!(s, "curve = {}", toml_str(c));
    }
    if let Some(k) = t.repeat {
        let _ = writeln!(s, "repeat = {k}");
    }
    if let Some(e) = t.avg_rel_error {
        let _ = writeln!(s, "avg_rel_error = {}", toml_float(e, 6));
    }
    let excluded = t.points.iter().filter(|p| !p.2.is_finite()).count();
    if excluded > 0 {
        // points whose model equilibrium is a saddle: left out of the errors
        let _ = writeln!(s, "excluded_points = {excluded}");
    }
    if let Some(e) = t.avg_rel_error_aligned {
        let _ = writeln!(s, "avg_rel_error_aligned = {}", toml_float(e, 6));
    }
    if let Some(k) = t.repeat_scale {
        let _ = writeln!(s, "repeat_scale = {}", toml_float(k, 6));
    }
    if let Some(e) = t.avg_rel_error_scaled {
        let _ = writeln!(s, "avg_rel_error_scaled = {}", toml_float(e, 6));
    }
    if let Some(toe) = t.toe {
        let _ = writeln!(s, "toe_mm = {}", toml_float(toe * 1e3, 4));
    }
    if let Some((nx, ny)) = t.mesh {
        let _ = writeln!(s, "mesh = \"{nx}x{ny}\"");
    }
    if let Some(m) = t.mesh_error_est {
        let _ = writeln!(s, "mesh_error_est = {}", toml_float(m, 6));
    }
    if !t.points.is_empty() {
        let _ = writeln!(s, "points = {}", t.points.len());
    }
    if let Some(a) = t.drape_angle_deg {
        let _ = writeln!(s, "drape_angle_deg = {}", toml_float(a, 4));
    }
    if let Some(a) = t.target_drape_deg {
        let _ = writeln!(s, "target_drape_angle_deg = {}", toml_float(a, 4));
    }
    if let Some(m) = t.misalign_deg {
        let _ = writeln!(s, "misalign_deg = {}", toml_float(m, 3));
    }
    let _ = writeln!(s, "used_in_fit = {}", t.used_in_fit);
    if let Some(e) = judgement.error {
        let _ = writeln!(s, "judged_error = {}", toml_float(e, 6));
    }
    let _ = writeln!(s, "verdict = {}", toml_str(judgement.mark));
}
