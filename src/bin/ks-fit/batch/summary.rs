//! What a batch knows of each fabric: its `status.toml` (written with the fabric's outputs,
//! read back on a rerun and by `--collect`), and the summary table built from all of them,
//! `summary.csv` and `index.html`, one row per fabric in manifest order.

use super::manifest::Row;
use std::path::Path;

/// The outcome of one fabric, as its `status.toml` records it.
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
pub struct Status {
    /// `done` (the fit ran; `passed` says whether every fitted test met --max-error) or
    /// `failed` (no material: `error` says why)
    pub status: String,
    #[serde(default)]
    pub passed: bool,
    /// [`super::manifest::inputs_hash`] of the inputs it was made from
    pub hash: String,
    pub exit_code: Option<i32>,
    pub seconds: f64,
    #[serde(default)]
    pub error: String,
    /// lines of its log that are warnings
    #[serde(default)]
    pub warnings: usize,
    #[serde(default)]
    pub first_warning: String,
}

impl Status {
    pub fn is_done(&self) -> bool {
        self.status == "done"
    }

    pub fn to_toml(&self, row: &Row) -> String {
        format!(
            "# written by ks-fit batch\nfabric = {:?}\ndataset = {:?}\nstatus = {:?}\npassed = {}\nhash = {:?}\nexit_code = {}\nseconds = {:.3}\nerror = {:?}\nwarnings = {}\nfirst_warning = {:?}\n",
            row.fabric,
            row.dataset.display().to_string(),
            self.status,
            self.passed,
            self.hash,
            self.exit_code.unwrap_or(-1),
            self.seconds,
            self.error,
            self.warnings,
            self.first_warning
        )
    }
}

/// The status recorded in `dir` (`None` when there is none or it cannot be read: the fabric
/// is then run again).
pub fn read_status(dir: &Path) -> Option<Status> {
    let text = std::fs::read_to_string(dir.join("status.toml")).ok()?;
    toml::from_str(&text).ok()
}

/// Figures of a fitted material's `[fit]` table for the summary (empty where absent).
#[derive(Clone, Debug, Default, PartialEq)]
struct FitFigures {
    wall_seconds: String,
    evaluations: String,
    newton_iterations: String,
    /// largest mean |relative error| of a fitted curve, percent (raw: repeats' scale scatter
    /// included; the verdict judges repeats by their shape, see `kshell::fit::verdict`)
    worst_error_pct: String,
    /// the fit's verdict line
    verdict: String,
    /// largest `shape_error` of a captured shape, fitted or predicted, percent
    worst_shape_error_pct: String,
}

fn fit_figures(material: &Path) -> FitFigures {
    let Ok(text) = std::fs::read_to_string(material) else {
        return FitFigures::default();
    };
    let Ok(doc) = text.parse::<toml::Table>() else {
        return FitFigures::default();
    };
    let Some(fit) = doc.get("fit").and_then(|f| f.as_table()) else {
        return FitFigures::default();
    };
    let num = |k: &str| {
        fit.get(k)
            .map(|v| match v {
                toml::Value::Float(x) => format!("{x}"),
                toml::Value::Integer(i) => format!("{i}"),
                other => other.to_string(),
            })
            .unwrap_or_default()
    };
    // the largest `key` of the [[fit.test]] entries that `keep` keeps
    let largest = |keep: &dyn Fn(&toml::Table) -> bool, key: &str| {
        fit.get("test")
            .and_then(|t| t.as_array())
            .into_iter()
            .flatten()
            .filter_map(|t| t.as_table())
            .filter(|t| keep(t))
            .filter_map(|t| t.get(key).and_then(|e| e.as_float()))
            .fold(None, |m: Option<f64>, e| Some(m.map_or(e, |m| m.max(e))))
    };
    let worst = largest(
        &|t| {
            t.get("used_in_fit")
                .and_then(|u| u.as_bool())
                .unwrap_or(true)
        },
        "avg_rel_error",
    );
    let worst_shape = largest(
        &|t| t.get("kind").and_then(|k| k.as_str()) == Some("shape"),
        "shape_error",
    );
    // a triangle model's fit names them `seconds` and `evaluations`
    let either = |a: &str, b: &str| {
        let v = num(a);
        if v.is_empty() {
            num(b)
        } else {
            v
        }
    };
    FitFigures {
        wall_seconds: either("wall_seconds", "seconds"),
        evaluations: either("objective_evaluations", "evaluations"),
        newton_iterations: num("newton_iterations"),
        worst_error_pct: worst
            .map(|e| format!("{:.2}", 100.0 * e))
            .unwrap_or_default(),
        verdict: fit
            .get("verdict")
            .and_then(|v| v.as_str())
            .unwrap_or_default()
            .to_string(),
        worst_shape_error_pct: worst_shape
            .map(|e| format!("{:.2}", 100.0 * e))
            .unwrap_or_default(),
    }
}

/// The header of `summary.csv`.
pub const SUMMARY_HEADER: &str = "fabric,status,passed,seconds,wall_seconds,objective_evaluations,newton_iterations,worst_curve_error_pct,verdict,warnings,material,report,log,error,worst_shape_error_pct";

/// One summary row per fabric: (row, its status if it has one).
pub struct Entry<'a> {
    pub row: &'a Row,
    pub status: Option<Status>,
    /// true while its fit runs
    pub running: bool,
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The cells of one entry, in [`SUMMARY_HEADER`] order (paths relative to the batch folder).
fn cells(out: &Path, e: &Entry) -> Vec<String> {
    let f = &e.row.fabric;
    let state = match (&e.status, e.running) {
        (_, true) => "running".to_string(),
        (Some(s), _) => s.status.clone(),
        (None, _) => "pending".to_string(),
    };
    let Some(s) = e.status.as_ref().filter(|_| !e.running) else {
        let mut v = vec![f.clone(), state];
        v.resize(15, String::new());
        return v;
    };
    let material = format!("{f}/material.toml");
    let mut figures = fit_figures(&out.join(&material));
    if figures.verdict.is_empty() {
        // no verdict in the file (a triangle model's fit): its FIT FAILED line, if any
        let log = std::fs::read_to_string(out.join(f).join("log.txt")).unwrap_or_default();
        if let Some(l) = log.lines().rev().find(|l| l.starts_with("FIT FAILED")) {
            figures.verdict = l.to_string();
        }
    }
    let report = format!("{f}/report/index.html");
    let log = format!("{f}/log.txt");
    let has = |p: &str| out.join(p).is_file();
    vec![
        f.clone(),
        state,
        if s.is_done() {
            s.passed.to_string()
        } else {
            String::new()
        },
        format!("{:.1}", s.seconds),
        figures.wall_seconds,
        figures.evaluations,
        figures.newton_iterations,
        figures.worst_error_pct,
        figures.verdict,
        s.warnings.to_string(),
        if has(&material) {
            material
        } else {
            String::new()
        },
        if has(&report) { report } else { String::new() },
        if has(&log) { log } else { String::new() },
        s.error.clone(),
        figures.worst_shape_error_pct,
    ]
}

/// `summary.csv`.
pub fn summary_csv(out: &Path, entries: &[Entry]) -> String {
    let mut s = format!("{SUMMARY_HEADER}\n");
    for e in entries {
        let row: Vec<String> = cells(out, e).iter().map(|c| csv_field(c)).collect();
        s.push_str(&row.join(","));
        s.push('\n');
    }
    s
}

/// `index.html`: the same table, with links to each fabric's report, material and log.
pub fn summary_html(out: &Path, entries: &[Entry], title: &str) -> String {
    use kshell::fit::html::escape;
    let (done, failed) = (
        entries
            .iter()
            .filter(|e| e.status.as_ref().is_some_and(|s| s.is_done()) && !e.running)
            .count(),
        entries
            .iter()
            .filter(|e| e.status.as_ref().is_some_and(|s| !s.is_done()) && !e.running)
            .count(),
    );
    let mut h = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"/><title>{t}</title>\n<style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:collapse}}td,th{{border:1px solid #bbb;padding:4px 8px;text-align:left}}.failed{{background:#fdd}}.false{{background:#ffe8c0}}</style></head>\n<body><h1>{t}</h1>\n<p>{n} fabrics: {done} fitted, {failed} failed, {rest} to go. Written by ks-fit batch; summary.csv holds the same table.</p>\n<table>\n<tr><th>fabric</th><th>status</th><th>passed</th><th>seconds</th><th>evaluations</th><th>Newton iterations</th><th>worst curve error (%)</th><th>worst shape error (%)</th><th>verdict</th><th>warnings</th><th>outputs</th><th>error</th></tr>\n",
        t = escape(title),
        n = entries.len(),
        rest = entries.len() - done - failed,
    );
    for e in entries {
        let c = cells(out, e);
        let link = |path: &str, text: &str| {
            if path.is_empty() {
                String::new()
            } else {
                format!("<a href=\"{}\">{text}</a> ", escape(path))
            }
        };
        let class = match (c[1].as_str(), c[2].as_str()) {
            ("failed", _) => " class=\"failed\"",
            (_, "false") => " class=\"false\"",
            _ => "",
        };
        let _ = std::fmt::Write::write_fmt(
            &mut h,
            format_args!(
                "<tr{class}><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}{}{}</td><td>{}</td></tr>\n",
                escape(&c[0]),
                escape(&c[1]),
                escape(&c[2]),
                escape(&c[3]),
                escape(&c[5]),
                escape(&c[6]),
                escape(&c[7]),
                escape(&c[14]),
                escape(&c[8]),
                escape(&c[9]),
                link(&c[11], "report"),
                link(&c[10], "material"),
                link(&c[12], "log"),
                escape(&c[13]),
            ),
        );
    }
    h.push_str("</table></body></html>\n");
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statuses_round_trip_and_fields_are_quoted() {
        let row = Row {
            line: 2,
            fabric: "a".into(),
            dataset: "x/fabric.toml".into(),
            given: "fabric.toml".into(),
            folder: "x".into(),
            options: vec![],
        };
        let s = Status {
            status: "failed".into(),
            passed: false,
            hash: "0123456789abcdef".into(),
            exit_code: Some(2),
            seconds: 1.5,
            error: "x/fabric.toml:3: bad \"value\", here".into(),
            warnings: 1,
            first_warning: "ks-fit: warning: toe".into(),
        };
        let back: Status = toml::from_str(&s.to_toml(&row)).unwrap();
        assert_eq!(back, s);
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
        let entries = [Entry {
            row: &row,
            status: Some(s),
            running: false,
        }];
        let csv = summary_csv(Path::new("/nonexistent"), &entries);
        let mut reader = csv::Reader::from_reader(csv.as_bytes());
        let rec = reader.records().next().unwrap().unwrap();
        assert_eq!(rec.len(), SUMMARY_HEADER.split(',').count());
        assert_eq!(&rec[1], "failed");
        assert_eq!(&rec[13], "x/fabric.toml:3: bad \"value\", here");
        let html = summary_html(Path::new("/nonexistent"), &entries, "t <1>");
        assert!(html.contains("t &lt;1&gt;") && html.contains("class=\"failed\""));
    }

    #[test]
    fn the_worst_curve_counts_fitted_curves_and_the_worst_shape_every_shape() {
        let dir = std::env::temp_dir().join(format!("kshell-summary-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let material = dir.join("material.toml");
        let text = "[fit]\nseconds = 2.0\n\n[[fit.test]]\nkind = \"tensile\"\navg_rel_error = 0.02\n\n[[fit.test]]\nkind = \"validation\"\navg_rel_error = 0.3\nused_in_fit = false\n\n[[fit.test]]\nkind = \"shape\"\nshape_error = 0.125\nfitted = false\n\n[[fit.test]]\nkind = \"shape\"\nshape_error = 0.05\nfitted = true\n";
        std::fs::write(&material, text).unwrap();
        let f = fit_figures(&material);
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(f.worst_error_pct, "2.00");
        assert_eq!(f.worst_shape_error_pct, "12.50");
        assert_eq!(f.wall_seconds, "2");
    }
}
