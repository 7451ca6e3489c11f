//! One self-contained HTML page per fit (`ks-fit fit --report DIR` writes `DIR/index.html`): the
//! verdict, the fitted material with its standard errors and what the data leave undetermined,
//! every test's error, the measured curves and repeats against the fit (inline SVG, the plots of
//! [`super::report`]), the degree progression, the mesh ladder and its error estimates, the
//! timings, and optional pictures (inline PNG, e.g. the scenes on the fitted material).
//!
//! The page is polyglot markup (well-formed XML as well as HTML5) and references nothing
//! outside itself: no scripts, no style sheets, no fonts, no images by address.

use super::report::{angle_svg, angle_title, curve_angles, curves_at, table};
use super::FitResult;
use crate::material::material_toml;
use std::fmt::Write;

/// A picture for the page: a title, a caption and PNG bytes.
#[derive(Clone, Debug)]
pub struct Figure {
    pub title: String,
    pub caption: String,
    pub png: Vec<u8>,
}

/// Escapes text for element content and attribute values.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

/// Standard base64 (RFC 4648 §4) with padding.
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut o = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                o.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                o.push('=');
            }
        }
    }
    o
}

/// The page's style. The page fits a 1280-pixel window: the body is at most 1200 pixels wide,
/// headers wrap, and the error table (sixteen columns) is set smaller.
const STYLE: &str = "body{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}\
table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right;white-space:nowrap}\
th{background:#f3f3f3;white-space:normal;vertical-align:bottom}table.errors{font-size:0.85em}table.errors td,table.errors th{padding:2px 4px}\
td.l,th.l{text-align:left}.pass{color:#176b1e}.fail{color:#b00020}\
pre{background:#f7f7f7;padding:0.6em;overflow-x:auto}figure{display:inline-block;margin:0.5em}\
figure img{max-width:100%}.und{color:#777}";

fn pct(v: Option<f64>) -> String {
    v.map_or("-".into(), |e| format!("{:.2} %", 100.0 * e))
}

/// Strips what precedes the `<svg` element (an XML declaration) from a plot.
fn inline_svg(svg: &str) -> &str {
    svg.find("<svg").map_or(svg, |i| &svg[i..])
}

/// The page. `source` names the dataset; `figures` are appended in their own section.
pub fn fit_html(r: &FitResult, source: &str, figures: &[Figure]) -> String {
    let verdict = super::verdict::verdict(r, r.max_error);
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html xmlns=\"http://www.w3.org/1999/xhtml\" lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n<title>ks-fit: {}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n",
        escape(source)
    );
    let _ = writeln!(h, "<h1>Fit of {}</h1>", escape(source));
    let class = if verdict.passed() { "pass" } else { "fail" };
    let _ = writeln!(
        h,
        "<p class=\"{class}\"><b>{}</b></p>",
        escape(&verdict.line)
    );
    let _ = writeln!(
        h,
        "<p>Method {}, meshes {}, {:.1} s, {} model evaluations, {} Newton iterations.</p>",
        escape(&r.method),
        r.meshes
            .iter()
            .map(|m| format!("{}x{}", m.0, m.1))
            .collect::<Vec<_>>()
            .join(" → "),
        r.stats.seconds,
        r.stats.evaluations,
        r.stats.newton_iterations
    );
    material_section(&mut h, r);
    tests_section(&mut h, r);
    curves_section(&mut h, r);
    ladder_section(&mut h, r);
    list(&mut h, "Degree choice", &r.degree_log);
    list(&mut h, "What the data determine", &r.identifiability);
    list(&mut h, "Notes", &r.notes);
    timing_section(&mut h, r);
    if !figures.is_empty() {
        let _ = writeln!(h, "<h2>Scenes on the fitted material</h2>");
        for f in figures {
            let _ = writeln!(
                h,
                "<figure><img alt=\"{}\" src=\"data:image/png;base64,{}\"/><figcaption><b>{}</b>: {}</figcaption></figure>",
                escape(&f.title),
                base64(&f.png),
                escape(&f.title),
                escape(&f.caption)
            );
        }
    }
    let _ = writeln!(
        h,
        "<h2>Material file</h2>\n<pre>{}</pre>",
        escape(&material_toml(&r.material))
    );
    let _ = writeln!(
        h,
        "<h2>Summary table</h2>\n<pre>{}</pre>",
        escape(&table(r))
    );
    h.push_str("</body>\n</html>\n");
    h
}

fn list(h: &mut String, title: &str, items: &[String]) {
    if items.is_empty() {
        return;
    }
    let _ = writeln!(h, "<h2>{}</h2>\n<ul>", escape(title));
    for i in items {
        let _ = writeln!(h, "<li>{}</li>", escape(i));
    }
    h.push_str("</ul>\n");
}

fn material_section(h: &mut String, r: &FitResult) {
    let _ = writeln!(h, "<h2>Fitted parameters</h2>");
    if r.uncertainty.is_empty() {
        let _ = writeln!(h, "<p>No standard errors were estimated for this fit.</p>");
        return;
    }
    h.push_str("<table><tr><th class=\"l\">parameter</th><th>value</th><th>standard error</th><th>relative</th><th class=\"l\">basis</th><th class=\"l\">determined by the data</th></tr>\n");
    for e in &r.uncertainty {
        let (se, rel) = match e.std_error {
            Some(s) => (
                format!("{s:.3e}"),
                if e.value != 0.0 {
                    format!("{:.1} %", 100.0 * s / e.value.abs())
                } else {
                    "-".into()
                },
            ),
            None => ("-".into(), "-".into()),
        };
        let row_class = if e.determined { "" } else { " class=\"und\"" };
        let _ = writeln!(
            h,
            "<tr{row_class}><td class=\"l\">{}</td><td>{:.5e}</td><td>{se}</td><td>{rel}</td><td class=\"l\">{}</td><td class=\"l\">{}</td></tr>",
            escape(&e.name),
            e.value,
            escape(e.basis),
            if e.determined { "yes" } else { "no: a value chosen, not measured" }
        );
    }
    h.push_str("</table>\n");
}

fn tests_section(h: &mut String, r: &FitResult) {
    let judged = super::verdict::judge(r, r.max_error);
    let _ = writeln!(
        h,
        "<h2>Errors per test</h2>\n<p><b>error</b>: the raw mean |relative error| of each curve at its nominal angle (a repeat's force scale included); <b>judged error</b>, beside the verdict: the error judged against --max-error {} % (repeats fitted together: the larger of the scaled error and the fit's distance outside the repeats' scatter band; a bend: its drape angle's); the diagnostics between them.</p>",
        100.0 * r.max_error
    );
    h.push_str("<table class=\"errors\"><tr><th class=\"l\">kind</th><th>angle</th><th class=\"l\">curve</th><th>repeat</th><th>error</th><th>scale</th><th>scaled error</th><th>drape angle (target)</th><th>misalign</th><th>aligned error</th><th>toe (mm)</th><th>mesh</th><th>mesh error</th><th>fitted</th><th>judged error</th><th>verdict</th></tr>\n");
    for (t, j) in r.tests.iter().zip(&judged) {
        let class = match j.mark {
            "OVER" => " class=\"fail\"",
            "high" => " class=\"fail\"",
            _ => "",
        };
        let _ = writeln!(
            h,
            "<tr><td class=\"l\">{}</td><td>{}</td><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td{class}>{}</td></tr>",
            t.kind,
            t.angle_deg,
            escape(t.curve.as_deref().unwrap_or("-")),
            t.repeat.map_or("-".into(), |k| k.to_string()),
            pct(t.avg_rel_error),
            t.repeat_scale.map_or("-".into(), |k| format!("{k:.3}")),
            pct(t.avg_rel_error_scaled),
            match (t.drape_angle_deg, t.target_drape_deg) {
                (Some(a), Some(g)) => format!("{a:.2}° ({g:.1}°)"),
                _ => "-".into(),
            },
            t.misalign_deg.map_or("-".into(), |m| format!("{m:+.2}°")),
            pct(t.avg_rel_error_aligned),
            t.toe.map_or("-".into(), |m| format!("{:.3}", m * 1e3)),
            t.mesh.map_or("-".into(), |(a, b)| format!("{a}x{b}")),
            pct(t.mesh_error_est),
            if t.used_in_fit { "yes" } else { "validation" },
            pct(j.error),
            j.mark
        );
    }
    h.push_str("</table>\n");
}

fn curves_section(h: &mut String, r: &FitResult) {
    let angles = curve_angles(r);
    if angles.is_empty() {
        return;
    }
    let _ = writeln!(
        h,
        "<h2>Measured curves and the fit</h2>\n<p>Every repeat measured (dashed) against the fitted model at its points (solid, in the repeat's colour), one plot per cut angle; each title gives the worst verdict at its angle and the largest judged error.</p>"
    );
    let judged = super::verdict::judge(r, r.max_error);
    for a in angles {
        let at = curves_at(r, a);
        let title = angle_title(r, &judged, a);
        match angle_svg(&at, &title) {
            Ok(svg) => {
                let _ = writeln!(h, "<figure>{}</figure>", inline_svg(&svg));
            }
            Err(e) => {
                let _ = writeln!(h, "<p>{}: no plot ({})</p>", escape(&title), escape(&e));
            }
        }
    }
}

fn ladder_section(h: &mut String, r: &FitResult) {
    let _ = writeln!(h, "<h2>Meshes and their error</h2>");
    let _ = writeln!(
        h,
        "<p>Mesh ladder of the 50 × 75 mm strip: {}.</p>",
        r.meshes
            .iter()
            .map(|m| format!("{}x{}", m.0, m.1))
            .collect::<Vec<_>>()
            .join(" → ")
    );
    match &r.mesh_check {
        None => {
            let _ = writeln!(h, "<p>No mesh check was run (--mesh-check off).</p>");
        }
        Some(m) => {
            let _ = writeln!(
                h,
                "<p>Refining {}x{} once more (solved on {}x{}) would change the determined parameters by up to <b>{:.2} %</b> ({}) and the curves by up to {:.2} %.</p>",
                m.mesh.0,
                m.mesh.1,
                m.solved_on.0,
                m.solved_on.1,
                100.0 * m.change,
                escape(&m.parameter),
                100.0 * m.curve_change
            );
            h.push_str("<table><tr><th class=\"l\">quantity</th><th>relative change</th></tr>\n");
            for (name, c) in &m.changes {
                let _ = writeln!(
                    h,
                    "<tr><td class=\"l\">{}</td><td>{:.3} %</td></tr>",
                    escape(name),
                    100.0 * c
                );
            }
            h.push_str("</table>\n");
        }
    }
}

fn timing_section(h: &mut String, r: &FitResult) {
    let _ = writeln!(
        h,
        "<h2>Time</h2>\n<p>{:.1} s in all; {} shell evaluations, {} homogeneous-strip evaluations, {} unstable solves left out.</p>",
        r.stats.seconds, r.stats.evaluations, r.stats.bootstrap_evaluations, r.stats.unstable_solves
    );
    h.push_str(
        "<table><tr><th class=\"l\">stage</th><th>seconds</th><th>Newton iterations</th></tr>\n",
    );
    for (stage, t) in &r.stats.stage_seconds {
        let its = r
            .stats
            .stage_iterations
            .iter()
            .find(|e| &e.0 == stage)
            .map_or(String::new(), |e| e.1.to_string());
        let _ = writeln!(
            h,
            "<tr><td class=\"l\">{}</td><td>{t:.2}</td><td>{its}</td></tr>",
            escape(stage)
        );
    }
    h.push_str("</table>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc_4648_test_vectors() {
        // RFC 4648 §10
        for (i, o) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(i.as_bytes()), o);
        }
    }

    /// A fit with no tests and one figure: the figure is inline as a data URL, text is escaped,
    /// and the page holds nothing that loads from elsewhere.
    #[test]
    fn figures_are_inline_and_text_is_escaped() {
        let material = crate::material::file::parse_material(
            include_str!("../../examples/materials/cotton.toml"),
            "cotton.toml",
        )
        .unwrap();
        let r = FitResult {
            material,
            method: "hybrid".into(),
            meshes: vec![(8, 12)],
            stats: Default::default(),
            degree_log: vec!["warp: degree 1 <kept>".into()],
            notes: Vec::new(),
            identifiability: Vec::new(),
            a12_dependence: [None; 3],
            uncertainty: Vec::new(),
            tests: Vec::new(),
            max_error: 0.1,
            mesh_check: None,
            shapes_fitted: false,
            yarn_rule: crate::assembly::YarnRule::Full,
            shear_coupling: crate::fit::coupling::CouplingOutcome::Off,
            objective: crate::fit::Misfit::Relative,
            joint: false,
            test_meshes: crate::fit::TestMeshes::Own,
        };
        let png = vec![0x89, b'P', b'N', b'G', 1, 2, 3];
        let fig = Figure {
            title: "drape".into(),
            caption: "a & b".into(),
            png: png.clone(),
        };
        let page = fit_html(&r, "data/fabric.toml", &[fig]);
        assert!(page.contains(&format!("src=\"data:image/png;base64,{}\"", base64(&png))));
        assert!(page.contains("warp: degree 1 &lt;kept&gt;"));
        assert!(page.contains("a &amp; b"));
        assert!(page.contains("--max-error 10 %"));
        assert!(!page.contains("<script") && !page.contains("<link"));
        // the only addresses are XML namespace names, which nothing loads
        assert_eq!(
            page.matches("http").count(),
            page.matches("xmlns=\"http").count()
        );
    }

    #[test]
    fn escaping_covers_markup_characters() {
        assert_eq!(
            escape("a<b & \"c\" 'd'>"),
            "a&lt;b &amp; &quot;c&quot; &#39;d&#39;&gt;"
        );
    }
}
