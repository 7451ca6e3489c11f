//! Speed against accuracy across cloth models: the example cotton as the shell (`kl`) and as
//! each triangle model converted from its zero-strain moduli, on three meshes each, for a warp
//! and a bias strip (50 × 75 mm pulled 1.5 mm), the warp cantilever (25 × 47.7 mm), the
//! picture frame, the corner pull and the drape (its mean drop). The reference is the shell's
//! Richardson extrapolation over its three meshes (the drape's: the shell on 48 × 48, see
//! [`LabTest::Drape`]). Writes `paper_repro/models/results.md` and one SVG per test (time
//! against error, log–log).
//!
//! `cargo run --release --example model_chart` (about ten minutes on two cores, six of them
//! the drape).
//!
//! With `-- --fits FILE...` (materials written by `ks-fit fit --model`, one per triangle model)
//! the triangle models run with those fitted parameters instead, into
//! `paper_repro/models/fitted/`: what a user gets who fits each model to the same lab data
//! (`paper_repro/models/fitted/run.sh` makes the data, the fits and the chart).

use kshell::material::load_material;
use kshell::recommend::{compare, LabTest, Run};
use kshell::tri::file::{model_only, parse_tri, TriSource};
use kshell::tri::TriMaterial;
use std::fmt::Write;

const COLOURS: [(&str, &str); 5] = [
    ("kl", "#000000"),
    ("springs", "#d62728"),
    ("soft-constraints", "#1f77b4"),
    ("stvk-ds", "#2ca02c"),
    ("xpbd", "#9467bd"),
];

fn svg(title: &str, points: &[Run], reference: f64) -> String {
    let (w, h, pad) = (640.0, 420.0, 60.0);
    let xs: Vec<f64> = points.iter().map(|p| p.seconds.max(1e-5).log10()).collect();
    let ys: Vec<f64> = points
        .iter()
        .map(|p| {
            ((p.value - reference).abs() / reference.abs())
                .max(1e-6)
                .log10()
        })
        .collect();
    let (x0, x1) = (
        xs.iter().cloned().fold(f64::INFINITY, f64::min).floor(),
        xs.iter().cloned().fold(f64::NEG_INFINITY, f64::max).ceil(),
    );
    let (y0, y1) = (
        ys.iter().cloned().fold(f64::INFINITY, f64::min).floor(),
        ys.iter().cloned().fold(f64::NEG_INFINITY, f64::max).ceil(),
    );
    let px = |x: f64| pad + (x - x0) / (x1 - x0).max(1e-9) * (w - 2.0 * pad);
    let py = |y: f64| h - pad - (y - y0) / (y1 - y0).max(1e-9) * (h - 2.0 * pad);
    let mut s = format!("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{}\" y=\"20\" text-anchor=\"middle\">{title}</text>\n", w / 2.0);
    let _ = writeln!(
        s,
        "<line x1=\"{pad}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\"/>",
        h - pad,
        w - pad,
        h - pad
    );
    let _ = writeln!(
        s,
        "<line x1=\"{pad}\" y1=\"{pad}\" x2=\"{pad}\" y2=\"{}\" stroke=\"black\"/>",
        h - pad
    );
    for k in x0 as i32..=x1 as i32 {
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\">1e{k} s</text>",
            px(k as f64),
            h - pad + 16.0
        );
    }
    for k in y0 as i32..=y1 as i32 {
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">1e{k}</text>",
            pad - 4.0,
            py(k as f64) + 4.0
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">wall time (median of 3)</text>",
        w / 2.0,
        h - 12.0
    );
    let _ = writeln!(s, "<text x=\"14\" y=\"{}\" transform=\"rotate(-90 14 {})\" text-anchor=\"middle\">relative error against the converged shell</text>", h / 2.0, h / 2.0);
    for (i, (model, colour)) in COLOURS.iter().enumerate() {
        let pts: Vec<String> = points
            .iter()
            .zip(xs.iter().zip(&ys))
            .filter(|(p, _)| p.model == *model)
            .map(|(_, (x, y))| format!("{:.1},{:.1}", px(*x), py(*y)))
            .collect();
        if pts.is_empty() {
            continue;
        }
        let _ = writeln!(
            s,
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{colour}\"/>",
            pts.join(" ")
        );
        for p in &pts {
            let (cx, cy) = p.split_once(',').unwrap();
            let _ = writeln!(
                s,
                "<circle cx=\"{cx}\" cy=\"{cy}\" r=\"3\" fill=\"{colour}\"/>"
            );
        }
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" fill=\"{colour}\">{model}</text>",
            w - pad - 110.0,
            pad + 14.0 * i as f64
        );
    }
    s.push_str("</svg>\n");
    s
}

/// The fitted triangle materials named after `--fits`.
fn fitted_materials() -> Vec<(String, TriMaterial)> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(i) = args.iter().position(|a| a == "--fits") else {
        return Vec::new();
    };
    args[i + 1..]
        .iter()
        .map(|f| {
            let text = std::fs::read_to_string(f).unwrap_or_else(|e| panic!("{f}: {e}"));
            let kind = model_only(&text).unwrap_or_else(|| {
                panic!("{f}: no [model] table (the output of ks-fit fit --model)")
            });
            let kind = kind.parse().unwrap_or_else(|e: String| panic!("{f}: {e}"));
            match parse_tri(&text, f, kind).unwrap_or_else(|e| panic!("{e}")) {
                TriSource::Table(t) => (f.clone(), t),
                TriSource::Shell(_) => unreachable!("model_only said it has a [model] table"),
            }
        })
        .collect()
}

fn main() {
    let m = load_material(std::path::Path::new("examples/materials/cotton.toml"))
        .expect("example material");
    let fits = fitted_materials();
    let fitted: Vec<TriMaterial> = fits.iter().map(|(_, t)| t.clone()).collect();
    let dir = if fits.is_empty() {
        std::path::PathBuf::from("paper_repro/models")
    } else {
        std::path::PathBuf::from("paper_repro/models/fitted")
    };
    let dir = dir.as_path();
    std::fs::create_dir_all(dir).expect("output folder");
    let mut md = String::from("# Speed against accuracy across cloth models\n\nWritten by `cargo run --release --example model_chart` (2 cores; times are medians of three runs for the strips and the cantilever, one run for the scenes).\n");
    if fits.is_empty() {
        md.push_str("The example cotton (linear: a₁₁ 2e8, a₂₂ 1.2e8, G₁₂ 4e6 Pa, τ 0.18 mm) as the shell and as each\ntriangle model converted from its zero-strain moduli (`TriMaterial::equivalent`), NOT fitted:\nthe errors are discretisation plus what each model's form cannot represent of the shell.\n");
    } else {
        md.push_str("The example cotton (linear: a₁₁ 2e8, a₂₂ 1.2e8, G₁₂ 4e6 Pa, τ 0.18 mm) as the shell, and each\ntriangle model FITTED by `ks-fit fit --model` to the shell's synthetic lab data (`run.sh`):\nthe errors are discretisation, the fit's own error and what each model's form cannot\nrepresent of the shell. Fitted materials:\n\n");
        for (f, t) in &fits {
            let _ = writeln!(md, "- `{f}` ({})", t.kind.name());
        }
        md.push('\n');
    }
    md.push_str("Reference: the shell's Richardson extrapolation over its three meshes, except where a\ntest's section says otherwise (the drape: the shell on 48 × 48).\n");
    let strip = |angle_deg| LabTest::Tensile {
        angle_deg,
        width: 0.05,
        length: 0.075,
        elongation: 1.5e-3,
    };
    let cases = [
        (
            "tensile_90",
            "warp strip 50 × 75 mm, force at 1.5 mm (N)",
            strip(90.0),
        ),
        (
            "tensile_45",
            "bias strip 50 × 75 mm, force at 1.5 mm (N)",
            strip(45.0),
        ),
        (
            "bend_90",
            "warp cantilever 25 × 47.7 mm, drape angle (°)",
            LabTest::Bend {
                angle_deg: 90.0,
                width: 0.025,
                overhang: 0.0477,
            },
        ),
        (
            "frame_20",
            "picture frame, 10 cm square sheared 20°, shear force (N); one run per point",
            LabTest::Frame {
                shear_deg: 20.0,
                side: 0.1,
            },
        ),
        (
            "corner_pull_10",
            "corner pull, 10 cm square stretched 10 % along a diagonal, force (N); one run per point",
            LabTest::Corner {
                stretch: 0.1,
                side: 0.1,
            },
        ),
        (
            "drape",
            "drape, 1 m square from two corners 60 cm apart, mean drop (mm); one run per point",
            LabTest::Drape {
                side: 1.0,
                span: 0.6,
            },
        ),
    ];
    for (file, title, test) in cases {
        // the scenes take seconds to minutes a run: one run each
        let repeats = match test {
            LabTest::Frame { .. } | LabTest::Corner { .. } | LabTest::Drape { .. } => 1,
            _ => 3,
        };
        let c = compare(&m, &fitted, test, repeats, &mut |line| {
            eprintln!("model_chart: {file}: {line}")
        });
        let (r, points) = (c.reference, &c.runs);
        let _ = writeln!(
            md,
            "\n## {title}\n\nreference {r:.6} ({}); chart `{file}.svg`\n",
            c.reference_from
        );
        let _ = writeln!(md, "| model | parameters | mesh | value | relative error | seconds |\n|---|---|---|---|---|---|");
        for p in points {
            let _ = writeln!(
                md,
                "| {} | {} | {}x{} | {:.6} | {:.2e} | {:.4} |",
                p.model,
                p.params,
                p.mesh.0,
                p.mesh.1,
                p.value,
                (p.value - r).abs() / r.abs(),
                p.seconds
            );
        }
        for f in &c.failures {
            let _ = writeln!(md, "\nnot run or failed: {f}");
        }
        std::fs::write(dir.join(format!("{file}.svg")), svg(title, points, r))
            .expect("write the chart");
    }
    // a hand-written reading after the tables is kept
    let path = dir.join("results.md");
    if let Ok(old) = std::fs::read_to_string(&path) {
        if let Some(i) = old.find("\n## Reading") {
            md.push_str(&old[i..]);
        }
    }
    std::fs::write(&path, md).expect("write the table");
    println!("wrote {}/results.md and six charts", dir.display());
}
