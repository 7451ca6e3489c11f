//! The summary's account of the fits that failed their verdict: per fit, the worst judged
//! error of each test kind and angle that the verdict names, and the notes of its log that
//! say why the fit went where it did.

use std::fmt::Write as _;
use std::path::Path;

/// Phrases of the log notes that explain a failed fit: a repeat far from its fellows
/// (`verdict::outlier_repeats`), a joint sweep not kept (`joint::joint_stiffness`), tests that
/// do not solve with the fitted parameters.
const EXPLAINING: [&str; 3] = ["lies more than", "joint sweep: the", "do not solve"];

/// The worst judged error of each test kind and angle a verdict line names, in the order first
/// named: ("tensile 90°", 76.79). The shell's line lists `tensile 90° a.csv: 76.79 %` items
/// after `--max-error e %: `, split by `; `; a triangle model's, `tensile 90° a.csv (76.8 %)`
/// split by `, `.
pub fn worst_by_angle(verdict: &str) -> Vec<(String, f64)> {
    let Some((_, list)) = verdict.split_once(" %: ") else {
        return Vec::new();
    };
    let items: Vec<&str> = if list.contains("; ") {
        list.split("; ").collect()
    } else {
        list.split(", ").collect()
    };
    let mut worst: Vec<(String, f64)> = Vec::new();
    for item in items {
        let mut words = item.split_whitespace();
        let (Some(kind), Some(angle)) = (words.next(), words.next()) else {
            continue;
        };
        let number = |w: &str| w.trim_matches(|c| c == '(' || c == ')').parse::<f64>().ok();
        let Some(e) = item.split_whitespace().rev().find_map(number) else {
            continue;
        };
        let key = format!("{kind} {}", angle.trim_end_matches(':'));
        match worst.iter_mut().find(|w| w.0 == key) {
            Some(w) => w.1 = w.1.max(e),
            None => worst.push((key, e)),
        }
    }
    worst
}

/// The section: each fit with a material that failed its verdict (`rows`: fabric, model,
/// verdict line), its worst errors by angle and the explaining notes of its `log.txt` under
/// `fits_dir`.
pub fn section(fits_dir: &Path, rows: &[(String, String, String)]) -> String {
    let mut s = String::from("\n## Fits that failed their verdict\n\n");
    if rows.is_empty() {
        s += "None.\n";
        return s;
    }
    for (fabric, model, verdict) in rows {
        let worst: Vec<String> = worst_by_angle(verdict)
            .iter()
            .map(|(k, e)| format!("{k} {e:.1} %"))
            .collect();
        let _ = writeln!(
            s,
            "* {fabric} ({model}): worst judged errors {}",
            worst.join(", ")
        );
        let log =
            std::fs::read_to_string(fits_dir.join(fabric).join("log.txt")).unwrap_or_default();
        // a note repeated on every mesh with other numbers is said once, with its count
        let mut seen: Vec<(String, &str, usize)> = Vec::new();
        for line in log.lines().filter(|l| !l.starts_with("ks-fit:")) {
            let line = line.trim_start_matches("note: ");
            if !EXPLAINING.iter().any(|p| line.contains(p)) {
                continue;
            }
            let shape: String = line.chars().filter(|c| !c.is_ascii_digit()).collect();
            match seen.iter_mut().find(|n| n.0 == shape) {
                Some(n) => n.2 += 1,
                None => seen.push((shape, line, 1)),
            }
        }
        for (_, line, count) in seen {
            let times = if count > 1 {
                format!(" ({count} times, the first shown)")
            } else {
                String::new()
            };
            let _ = writeln!(s, "  * {line}{times}");
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_verdict_line_is_read_by_angle() {
        let v = "verdict: FIT FAILED: 4 fitted test(s) above --max-error 10 %: tensile 90° a90-1.csv: 76.79 %; tensile 90° a90-2.csv: 80.10 %; tensile 0° a0-1.csv: 84.82 %; bend 90°: 12.50 %";
        let w = worst_by_angle(v);
        assert_eq!(
            w,
            vec![
                ("tensile 90°".to_string(), 80.10),
                ("tensile 0°".to_string(), 84.82),
                ("bend 90°".to_string(), 12.5)
            ]
        );
        assert!(
            worst_by_angle("verdict: fit within --max-error 10 % on every fitted test").is_empty()
        );
        let tri = "FIT FAILED: fitted tests above --max-error 10.0 %: tensile 45° a45-1.csv (99.9 %), tensile 75° a75-1.csv (176.3 %), tensile 45° a45-2.csv (534579.9 %) (repeats are judged after their own force scale)";
        assert_eq!(
            worst_by_angle(tri),
            vec![
                ("tensile 45°".to_string(), 534579.9),
                ("tensile 75°".to_string(), 176.3)
            ]
        );
    }
}
