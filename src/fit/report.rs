//! What `ks-fit fit` hands back: the fitted material file with its `[fit]` table (meshes,
//! time, evaluations and one `[[fit.test]]` per test, in the terms of the paper's Tables 3–5),
//! the same table as text, and per-test CSV and SVG plots in the style of the paper's Figure 2
//! (measured dashed, fitted solid; full range and small-strain close-up).

use super::{FitResult, TestOutcome};
use crate::io::num;
use crate::material::material_toml;
use std::fmt::Write;

/// A TOML basic string ([`crate::io::toml_string`]; `{:?}` would make a fit file with a
/// combining mark in a note or a file name unreadable).
fn toml_str(s: &str) -> String {
    crate::io::toml_string(s)
}

/// A TOML key: bare where it may be (letters, digits, `_`, `-`), quoted otherwise (an
/// off-axis row's `22.5` would otherwise open a nested table).
fn toml_key(k: &str) -> String {
    let bare = !k.is_empty()
        && k.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if bare {
        k.to_string()
    } else {
        toml_str(k)
    }
}

/// The material file followed by the `[fit]` table; loadable by every command that reads
/// materials (the loader reads past `[fit]`).
pub fn fit_toml(r: &FitResult, source: &str) -> String {
    let mut s = format!("# fitted by ks-fit fit from {source}\n");
    s += &material_toml(&r.material);
    let _ = writeln!(s, "\n[fit]");
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
    let notes: Vec<String> = r.notes.iter().map(|n| toml_str(n)).collect();
    let _ = writeln!(s, "notes = [{}]", notes.join(", "));
    let ident: Vec<String> = r.identifiability.iter().map(|n| toml_str(n)).collect();
    let _ = writeln!(s, "identifiability = [{}]", ident.join(", "));
    let log: Vec<String> = r.degree_log.iter().map(|n| toml_str(n)).collect();
    let _ = writeln!(s, "degree_choice = [{}]", log.join(", "));
    let verdict = super::verdict::verdict(r, r.max_error);
    let _ = writeln!(s, "max_error = {}", r.max_error);
    let _ = writeln!(s, "passed = {}", verdict.passed());
    let _ = writeln!(s, "verdict = {}", toml_str(&verdict.line));
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
    let judged = super::verdict::judge(r, r.max_error);
    for (t, judgement) in r.tests.iter().zip(&judged) {
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
            let _ = writeln!(s, "avg_rel_error = {e:.6}");
        }
        let excluded = t.points.iter().filter(|p| !p.2.is_finite()).count();
        if excluded > 0 {
            // points whose model equilibrium is a saddle: left out of the errors
            let _ = writeln!(s, "excluded_points = {excluded}");
        }
        if let Some(e) = t.avg_rel_error_aligned {
            let _ = writeln!(s, "avg_rel_error_aligned = {e:.6}");
        }
        if let Some(k) = t.repeat_scale {
            let _ = writeln!(s, "repeat_scale = {k:.6}");
        }
        if let Some(e) = t.avg_rel_error_scaled {
            let _ = writeln!(s, "avg_rel_error_scaled = {e:.6}");
        }
        if let Some(toe) = t.toe {
            let _ = writeln!(s, "toe_mm = {:.4}", toe * 1e3);
        }
        if let Some((nx, ny)) = t.mesh {
            let _ = writeln!(s, "mesh = \"{nx}x{ny}\"");
        }
        if let Some(m) = t.mesh_error_est {
            let _ = writeln!(s, "mesh_error_est = {m:.6}");
        }
        if !t.points.is_empty() {
            let _ = writeln!(s, "points = {}", t.points.len());
        }
        if let Some(a) = t.drape_angle_deg {
            let _ = writeln!(s, "drape_angle_deg = {a:.4}");
        }
        if let Some(a) = t.target_drape_deg {
            let _ = writeln!(s, "target_drape_angle_deg = {a:.4}");
        }
        if let Some(m) = t.misalign_deg {
            let _ = writeln!(s, "misalign_deg = {m:.3}");
        }
        let _ = writeln!(s, "used_in_fit = {}", t.used_in_fit);
        if let Some(e) = judgement.error {
            let _ = writeln!(s, "judged_error = {e:.6}");
        }
        let _ = writeln!(s, "verdict = {}", toml_str(judgement.mark));
    }
    s
}

/// The per-test table printed at the end of a fit.
pub fn table(r: &FitResult) -> String {
    let mut s = format!(
        "{:<11} {:>7} {:<16} {:>14} {:>7} {:>13} {:>16} {:>13} {:>13} {:>8} {:>8} {:>9} {:>6} {:>7}\n",
        "kind",
        "angle",
        "curve",
        "avg_rel_error",
        "scale",
        "scaled_error",
        "drape_angle_deg",
        "misalign_deg",
        "aligned_error",
        "toe_mm",
        "mesh",
        "mesh_err",
        "fitted",
        "verdict"
    );
    let judged = super::verdict::judge(r, r.max_error);
    for (t, judgement) in r.tests.iter().zip(&judged) {
        let opt = |v: Option<f64>, f: &dyn Fn(f64) -> String| v.map(f).unwrap_or("-".into());
        let _ = writeln!(
            s,
            "{:<11} {:>7.1} {:<16} {:>14} {:>7} {:>13} {:>16} {:>13} {:>13} {:>8} {:>8} {:>9} {:>6} {:>7}",
            t.kind,
            t.angle_deg,
            t.curve.as_deref().unwrap_or("-"),
            opt(t.avg_rel_error, &|e| format!("{:.2} %", 100.0 * e)),
            opt(t.repeat_scale, &|k| format!("{k:.3}")),
            opt(t.avg_rel_error_scaled, &|e| format!("{:.2} %", 100.0 * e)),
            match (t.drape_angle_deg, t.target_drape_deg) {
                (Some(a), Some(g)) => format!("{a:.2} ({g:.1})"),
                _ => "-".into(),
            },
            opt(t.misalign_deg, &|m| format!("{m:+.2}")),
            opt(t.avg_rel_error_aligned, &|e| format!("{:.2} %", 100.0 * e)),
            opt(t.toe, &|m| format!("{:.3}", m * 1e3)),
            t.mesh.map_or("-".into(), |(a, b)| format!("{a}x{b}")),
            opt(t.mesh_error_est, &|e| format!("{:.2} %", 100.0 * e)),
            if t.used_in_fit { "yes" } else { "no" },
            judgement.mark,
        );
    }
    let _ = writeln!(s, "{}", super::verdict::verdict(r, r.max_error).line);
    s
}

/// File-name stem of a test's report files.
fn stem(t: &TestOutcome, i: usize) -> String {
    let base = t
        .curve
        .as_deref()
        .and_then(|c| std::path::Path::new(c).file_stem())
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| format!("test{i}"));
    format!("{}-{base}", t.kind)
}

/// CSV of measured against fitted force (`elongation_mm,measured_n,fitted_n,rel_error`).
pub fn curve_csv(t: &TestOutcome) -> String {
    let mut s = String::from("elongation_mm,measured_n,fitted_n,rel_error\n");
    for &(e, m, f) in &t.points {
        if !f.is_finite() {
            // excluded (a saddle): no model force
            let _ = writeln!(s, "{},{},,", num(e * 1e3), num(m));
            continue;
        }
        let _ = writeln!(
            s,
            "{},{},{},{}",
            num(e * 1e3),
            num(m),
            num(f),
            num((f - m) / m)
        );
    }
    s
}

/// A tick label: at most four significant digits, no float noise (not `9.99999e-5`).
fn tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let digits = (3 - v.abs().log10().floor() as i32).clamp(0, 9) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// SVG: measured (dashed) and fitted (solid) force against elongation, the full range on the
/// left and the first quarter of the elongation on the right.
pub fn curve_svg(t: &TestOutcome, title: &str) -> Result<String, String> {
    use plotters::prelude::*;
    if t.points.len() < 2 {
        return Err("a curve needs two points to plot".into());
    }
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (960, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let root = root
            .titled(title, ("sans-serif", 18))
            .map_err(|e| e.to_string())?;
        let (left, right) = root.split_horizontally(480);
        let emax = t.points.iter().map(|p| p.0 * 1e3).fold(0.0, f64::max);
        for (area, xmax) in [(&left, emax), (&right, 0.25 * emax)] {
            let inside: Vec<&(f64, f64, f64)> = t
                .points
                .iter()
                .filter(|p| p.0 * 1e3 <= xmax * 1.0001)
                .collect();
            let fmax = inside
                .iter()
                .map(|p| p.1.max(p.2))
                .fold(0.0, f64::max)
                .max(1e-12);
            let mut chart = ChartBuilder::on(area)
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(60)
                .build_cartesian_2d(0.0..xmax, 0.0..1.05 * fmax)
                .map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .x_desc("elongation (mm)")
                .y_desc("force (N)")
                .x_label_formatter(&|v| tick(*v))
                .y_label_formatter(&|v| tick(*v))
                .draw()
                .map_err(|e| e.to_string())?;
            let measured: Vec<(f64, f64)> = inside.iter().map(|p| (p.0 * 1e3, p.1)).collect();
            let fitted: Vec<(f64, f64)> = inside.iter().map(|p| (p.0 * 1e3, p.2)).collect();
            chart
                .draw_series(DashedLineSeries::new(
                    measured.clone(),
                    6,
                    4,
                    ShapeStyle::from(&BLACK).stroke_width(2),
                ))
                .map_err(|e| e.to_string())?
                .label("measured")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
            chart
                .draw_series(LineSeries::new(
                    fitted,
                    ShapeStyle::from(&BLUE).stroke_width(2),
                ))
                .map_err(|e| e.to_string())?
                .label("fitted")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .border_style(BLACK)
                .background_style(WHITE)
                .draw()
                .map_err(|e| e.to_string())?;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(buf)
}

/// Force at elongation `x` on a measured curve, linear between its points (`None` outside).
fn measured_at(points: &[(f64, f64, f64)], x: f64) -> Option<f64> {
    let i = points.partition_point(|p| p.0 < x);
    if i == 0 {
        return (points.first()?.0 == x).then(|| points[0].1);
    }
    let (a, b) = (points[i - 1], *points.get(i)?);
    Some(a.1 + (b.1 - a.1) * (x - a.0) / (b.0 - a.0))
}

/// SVG of every repeat at one angle: the repeats' scatter band (grey, between the smallest and
/// largest measured force where every repeat has data), each repeat measured (dashed) and the
/// fit (solid, one line per strip geometry).
pub fn angle_svg(tests: &[&TestOutcome], title: &str) -> Result<String, String> {
    use plotters::prelude::*;
    let emax = tests
        .iter()
        .flat_map(|t| t.points.iter().map(|p| p.0 * 1e3))
        .fold(0.0, f64::max);
    let fmax = tests
        .iter()
        .flat_map(|t| t.points.iter().map(|p| p.1.max(p.2)))
        .fold(0.0, f64::max)
        .max(1e-12);
    if emax <= 0.0 {
        return Err("nothing to plot".into());
    }
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (640, 440)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..emax, 0.0..1.05 * fmax)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("elongation (mm)")
            .y_desc("force (N)")
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .draw()
            .map_err(|e| e.to_string())?;
        if tests.len() > 1 {
            let n = 100;
            let (mut lo, mut hi) = (Vec::new(), Vec::new());
            for k in 0..=n {
                let x = emax * 1e-3 * k as f64 / n as f64;
                let at: Option<Vec<f64>> =
                    tests.iter().map(|t| measured_at(&t.points, x)).collect();
                if let Some(v) = at {
                    let (a, b) = v
                        .iter()
                        .fold((f64::MAX, f64::MIN), |m, &f| (m.0.min(f), m.1.max(f)));
                    lo.push((x * 1e3, a));
                    hi.push((x * 1e3, b));
                }
            }
            hi.reverse();
            lo.extend(hi);
            if lo.len() > 2 {
                chart
                    .draw_series(std::iter::once(Polygon::new(
                        lo,
                        RGBColor(210, 210, 210).filled(),
                    )))
                    .map_err(|e| e.to_string())?
                    .label("repeat scatter")
                    .legend(|(x, y)| {
                        Rectangle::new(
                            [(x, y - 4), (x + 20, y + 4)],
                            RGBColor(210, 210, 210).filled(),
                        )
                    });
            }
        }
        for (i, t) in tests.iter().enumerate() {
            let colour = Palette99::pick(i).to_rgba();
            let measured: Vec<(f64, f64)> = t.points.iter().map(|p| (p.0 * 1e3, p.1)).collect();
            let name = t.curve.clone().unwrap_or_default();
            chart
                .draw_series(DashedLineSeries::new(
                    measured,
                    5,
                    4,
                    colour.stroke_width(2),
                ))
                .map_err(|e| e.to_string())?
                .label(format!("{name} measured"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
            let fitted: Vec<(f64, f64)> = t
                .points
                .iter()
                .filter(|p| p.2.is_finite())
                .map(|p| (p.0 * 1e3, p.2))
                .collect();
            chart
                .draw_series(LineSeries::new(fitted, BLACK.stroke_width(1)))
                .map_err(|e| e.to_string())?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .border_style(BLACK)
            .background_style(WHITE)
            .draw()
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(buf)
}

/// The cut angles that have measured curves, ascending.
pub(super) fn curve_angles(r: &FitResult) -> Vec<f64> {
    let mut angles: Vec<f64> = r
        .tests
        .iter()
        .filter(|t| !t.points.is_empty())
        .map(|t| t.angle_deg)
        .collect();
    angles.sort_by(f64::total_cmp);
    angles.dedup();
    angles
}

/// The tests with measured curves at cut angle `a`.
pub(super) fn curves_at(r: &FitResult, a: f64) -> Vec<&TestOutcome> {
    r.tests
        .iter()
        .filter(|t| t.angle_deg == a && !t.points.is_empty())
        .collect()
}

/// Writes `DIR/<kind>-<curve>.csv` and `.svg` for every tensile and validation test, and
/// `DIR/summary.txt` with the table. Returns the files written.
pub fn write_report(r: &FitResult, dir: &std::path::Path) -> std::io::Result<Vec<String>> {
    std::fs::create_dir_all(dir)?;
    let mut written = Vec::new();
    for (i, t) in r.tests.iter().enumerate() {
        if t.points.is_empty() {
            continue;
        }
        let stem = stem(t, i);
        let csv = dir.join(format!("{stem}.csv"));
        crate::io::write_atomic(&csv, curve_csv(t))?;
        written.push(csv.display().to_string());
        let title = format!(
            "{} {}°: mean |relative error| {:.2} %",
            t.kind,
            t.angle_deg,
            100.0 * t.avg_rel_error.unwrap_or(f64::NAN)
        );
        if let Ok(svg) = curve_svg(t, &title) {
            let path = dir.join(format!("{stem}.svg"));
            crate::io::write_atomic(&path, svg)?;
            written.push(path.display().to_string());
        }
    }
    // one plot per angle with every repeat and their scatter band
    for a in curve_angles(r) {
        let at = curves_at(r, a);
        let title = format!("{a}°: {} repeat(s), fit solid", at.len());
        if let Ok(svg) = angle_svg(&at, &title) {
            let path = dir.join(format!("angle-{a}.svg"));
            crate::io::write_atomic(&path, svg)?;
            written.push(path.display().to_string());
        }
    }
    let summary = dir.join("summary.txt");
    crate::io::write_atomic(&summary, table(r))?;
    written.push(summary.display().to_string());
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::{tick, toml_str};

    /// Notes and file names with combining marks, quotes, backslashes and control characters
    /// read back as written.
    #[test]
    fn strings_are_toml_whatever_they_hold() {
        for text in [
            "ln(F\u{302}/F)",
            "tisse\u{301}.csv",
            "a \"b\" \\ c\td\n",
            "τ·ν₁₂",
        ] {
            let doc: toml::Table = format!("k = {}", toml_str(text)).parse().unwrap();
            assert_eq!(doc["k"].as_str(), Some(text));
        }
    }

    #[test]
    fn tick_labels_have_no_float_noise() {
        assert_eq!(tick(9.999_999_999_999_999e-5), "0.0001");
        assert_eq!(tick(0.30000000000000004), "0.3");
        assert_eq!(tick(12.5), "12.5");
        assert_eq!(tick(1500.0), "1500");
        assert_eq!(tick(0.0), "0");
    }
}
