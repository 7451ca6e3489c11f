//! What `ks-fit fit` hands back: the fitted material file with its `[fit]` table (meshes,
//! time, evaluations and one `[[fit.test]]` per test, in the terms of the paper's Tables 3–5),
//! the same table as text, and per-test CSV and SVG plots in the style of the paper's Figure 2
//! (measured dashed, fitted solid; full range and small-strain close-up).

mod fit_file;

use super::verdict::{judge, Judgement};
use super::{FitResult, TestOutcome};
use crate::io::num;
pub use fit_file::fit_toml;
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

/// What the table's two error columns mean, printed under it: the raw error that the paper's
/// tables report and the error the verdict reads.
pub const ERROR_KEY: &str = "errors: avg_rel_error is the raw mean |relative error| at the nominal angle (a repeat's force scale included); judged_error is what the verdict reads (repeats fitted together: the larger of scaled_error and the fit's distance outside their scatter band; a bend: |drape angle - target| / target)";

/// The table's columns through `verdict`, which every report's `summary.txt` starts with (the
/// `judged_error` column follows them).
fn table_columns() -> String {
    format!(
        "{:<11} {:>7} {:<16} {:>14} {:>7} {:>13} {:>16} {:>13} {:>13} {:>8} {:>8} {:>9} {:>6} {:>7}",
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
    )
}

/// Whether `text` (a `summary.txt`) is one that [`write_report`] wrote: its first line is the
/// table's header (its columns through `verdict`). A folder holding a `summary.txt` that is not one is no earlier report.
pub fn is_report_summary(text: &str) -> bool {
    text.lines()
        .next()
        .is_some_and(|l| l.starts_with(&table_columns()))
}

/// The per-test table printed at the end of a fit: one row per test, its `verdict` mark and,
/// beside it, the `judged_error` that decides the mark; then [`ERROR_KEY`] and the verdict.
pub fn table(r: &FitResult) -> String {
    let mut s = format!("{} {:>12}\n", table_columns(), "judged_error");
    let judged = judge(r, r.max_error);
    for (t, judgement) in r.tests.iter().zip(&judged) {
        let opt = |v: Option<f64>, f: &dyn Fn(f64) -> String| v.map(f).unwrap_or("-".into());
        let _ = writeln!(
            s,
            "{:<11} {:>7.1} {:<16} {:>14} {:>7} {:>13} {:>16} {:>13} {:>13} {:>8} {:>8} {:>9} {:>6} {:>7} {:>12}",
            t.kind,
            t.angle_deg,
            t.curve.as_deref().unwrap_or("-"),
            pct(t.avg_rel_error),
            opt(t.repeat_scale, &|k| format!("{k:.3}")),
            pct(t.avg_rel_error_scaled),
            match (t.drape_angle_deg, t.target_drape_deg) {
                (Some(a), Some(g)) => format!("{a:.2} ({g:.1})"),
                _ => "-".into(),
            },
            opt(t.misalign_deg, &|m| format!("{m:+.2}")),
            pct(t.avg_rel_error_aligned),
            opt(t.toe, &|m| format!("{:.3}", m * 1e3)),
            t.mesh.map_or("-".into(), |(a, b)| format!("{a}x{b}")),
            pct(t.mesh_error_est),
            if t.used_in_fit { "yes" } else { "no" },
            judgement.mark,
            pct(judgement.error),
        );
    }
    if !r.tests.is_empty() {
        let _ = writeln!(s, "{ERROR_KEY}");
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
                .legend(|(x, y)| {
                    // two dashes: the swatch of a dashed line
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (8, 0)], BLACK)
                        + PathElement::new(vec![(12, 0), (20, 0)], BLACK)
                });
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
/// fit at its points (solid, in the repeat's colour); the legend names every line.
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
                .legend(move |(x, y)| {
                    // two dashes: the swatch of a dashed line
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (8, 0)], colour)
                        + PathElement::new(vec![(12, 0), (20, 0)], colour)
                });
            let fitted: Vec<(f64, f64)> = t
                .points
                .iter()
                .filter(|p| p.2.is_finite())
                .map(|p| (p.0 * 1e3, p.2))
                .collect();
            chart
                .draw_series(LineSeries::new(fitted, colour.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(format!("{name} fitted"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
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

/// A percentage with two decimals, `-` where there is none.
fn pct(v: Option<f64>) -> String {
    v.map_or("-".into(), |e| format!("{:.2} %", 100.0 * e))
}

/// The title of one curve's plot: the test, its raw error, the error the verdict reads and
/// the verdict's mark.
pub(super) fn curve_title(t: &TestOutcome, j: &Judgement) -> String {
    format!(
        "{} {}°: raw error {}, judged {}, verdict {}",
        t.kind,
        t.angle_deg,
        pct(t.avg_rel_error),
        pct(j.error),
        j.mark
    )
}

/// How bad a verdict mark is, for the worst of several: `OVER`, then `high`, `ok`, `T3`, `-`.
fn mark_rank(mark: &str) -> u8 {
    match mark {
        "OVER" => 4,
        "high" => 3,
        "ok" => 2,
        "T3" => 1,
        _ => 0,
    }
}

/// The title of the plot of every repeat at cut angle `a`: how many, fitted or validation,
/// and the worst verdict mark among them with the largest judged error (`judged` in the order
/// of `r.tests`).
pub(super) fn angle_title(r: &FitResult, judged: &[Judgement], a: f64) -> String {
    let at: Vec<(&TestOutcome, &Judgement)> = r
        .tests
        .iter()
        .zip(judged)
        .filter(|(t, _)| t.angle_deg == a && !t.points.is_empty())
        .collect();
    let fitted = at.iter().any(|(t, _)| t.used_in_fit);
    let mark = at
        .iter()
        .map(|(_, j)| j.mark)
        .max_by_key(|m| mark_rank(m))
        .unwrap_or("-");
    let worst = at
        .iter()
        .filter_map(|(_, j)| j.error)
        .fold(None, |m: Option<f64>, e| {
            // a NaN error (a failed solve) is the worst, never skipped by `max`
            Some(m.map_or(e, |m| {
                if m.is_nan() || e.is_nan() {
                    f64::NAN
                } else {
                    m.max(e)
                }
            }))
        });
    format!(
        "{a}°: {} {}; verdict {mark} (judged error ≤ {})",
        at.len(),
        if fitted {
            "fitted repeat(s)"
        } else {
            "validation run(s)"
        },
        pct(worst)
    )
}

/// Writes `DIR/<kind>-<curve>.csv` and `.svg` for every tensile and validation test, and
/// `DIR/summary.txt` with the table. Returns the files written.
pub fn write_report(r: &FitResult, dir: &std::path::Path) -> std::io::Result<Vec<String>> {
    std::fs::create_dir_all(dir)?;
    let mut written = Vec::new();
    let judged = judge(r, r.max_error);
    for (i, t) in r.tests.iter().enumerate() {
        if t.points.is_empty() {
            continue;
        }
        let stem = stem(t, i);
        let csv = dir.join(format!("{stem}.csv"));
        crate::io::write_atomic(&csv, curve_csv(t))?;
        written.push(csv.display().to_string());
        let title = curve_title(t, &judged[i]);
        if let Ok(svg) = curve_svg(t, &title) {
            let path = dir.join(format!("{stem}.svg"));
            crate::io::write_atomic(&path, svg)?;
            written.push(path.display().to_string());
        }
    }
    // one plot per angle with every repeat and their scatter band
    for a in curve_angles(r) {
        let at = curves_at(r, a);
        let title = angle_title(r, &judged, a);
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
