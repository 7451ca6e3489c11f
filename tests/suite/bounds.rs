//! Sizes are bounded and refusals are tidy: long curves thinned (and huge ones refused), laws
//! of many terms, datasets of many tests and manifests of many rows refused at their line,
//! clap's own errors as one `ks-fit: error:` line, numbers echoed and shown compactly. Each
//! bound is tested just over its limit (the limits are the library's constants).

use crate::common::{folder, ks_fit, s};
use kshell::limits::{
    MAX_BATCH_ROWS, MAX_CURVE_POINTS, MAX_CURVE_ROWS, MAX_DATASET_TESTS, MAX_LAW_TERMS,
};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const MATERIAL: &str = "examples/materials/cotton.toml";

/// Exit code 2 and a first line `ks-fit: error: …` containing `want`; the whole stderr.
fn refused(args: &[&str], want: &str) -> String {
    let (rc, out, err) = ks_fit(args);
    assert_eq!(rc, 2, "{args:?}: expected exit 2, got {rc}\n{out}{err}");
    let first = err.lines().next().unwrap_or_default();
    assert!(first.starts_with("ks-fit: error:"), "{args:?}:\n{err}");
    assert!(first.contains(want), "{args:?}: missing {want:?} in\n{err}");
    err
}

/// A dataset in a fresh folder: `fabric.toml` from `toml`, and `c.csv` from `csv`.
#[track_caller]
fn dataset(tag: &str, toml: &str, csv: &str) -> PathBuf {
    let dir = folder(tag);
    std::fs::write(dir.join("c.csv"), csv).unwrap();
    std::fs::write(dir.join("fabric.toml"), toml).unwrap();
    dir.join("fabric.toml")
}

const HEAD: &str = "name = \"bounds\"\nthickness_mm = 0.18\n";
const TENSILE: &str =
    "[[tensile]]\nangle_deg = 90\nwidth_mm = 50\ngauge_length_mm = 75\ncurve = \"c.csv\"\n";

/// A short warp curve.
fn short_curve() -> String {
    let mut c = String::from("elongation_mm,force_n\n");
    for i in 1..=20 {
        let e = 0.3 * i as f64;
        let _ = writeln!(c, "{e},{}", 40.0 * e + 2.0 * e * e * e);
    }
    c
}

/// Piecewise-linear interpolation of (`x`, `y`) at `at` (within the range).
fn interpolate(x: &[f64], y: &[f64], at: f64) -> f64 {
    let k = x.partition_point(|&v| v < at).clamp(1, x.len() - 1);
    let t = (at - x[k - 1]) / (x[k] - x[k - 1]);
    y[k - 1] + t * (y[k] - y[k - 1])
}

#[test]
fn a_long_curve_is_thinned_within_a_thousandth_of_its_force_range() {
    // a smooth rise with a ripple of ±0.5 N, one point over the limit
    let n = MAX_CURVE_POINTS + 1;
    let points: Vec<(f64, f64)> = (1..=n)
        .map(|i| {
            let e = 6.0 * i as f64 / n as f64;
            (e, 40.0 * e + 2.0 * e * e * e + 0.5 * (9.0 * e).sin())
        })
        .collect();
    let mut csv = String::from("elongation_mm,force_n\n");
    for (e, f) in &points {
        let _ = writeln!(csv, "{e},{f}");
    }
    let toml = dataset("thin", &format!("{HEAD}{TENSILE}"), &csv);
    let (rc, out, err) = ks_fit(&["check", s(&toml)]);
    assert_eq!(rc, 0, "{out}{err}");
    let warning = out
        .lines()
        .find(|l| l.contains("thinned"))
        .unwrap_or_else(|| panic!("no thinning warning:\n{out}"));
    assert!(
        warning.contains("fabric.toml:7: warning:") && warning.contains(&format!("{n} points")),
        "{warning}"
    );
    let (data, _) = kshell::dataset::load_dataset(&toml).unwrap();
    let t = &data.tensile[0];
    assert!(
        t.elongation.len() < MAX_CURVE_POINTS,
        "{}",
        t.elongation.len()
    );
    assert!(warning.contains(&format!("thinned to the {} points", t.elongation.len())));
    let (lo, hi) = points.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
        (lo.min(p.1), hi.max(p.1))
    });
    let worst = points
        .iter()
        .map(|&(e, f)| (interpolate(&t.elongation, &t.force, e * 1e-3) - f).abs())
        .fold(0.0, f64::max);
    let tol = kshell::dataset::THINNING_TOLERANCE * (hi - lo);
    assert!(worst <= tol * (1.0 + 1e-9), "{worst} N above {tol} N");
    assert_eq!(t.elongation.last(), Some(&(points[n - 1].0 * 1e-3)));
}

#[test]
fn a_curve_over_the_hard_bound_is_refused_at_its_line() {
    let mut csv = String::with_capacity(16 * MAX_CURVE_ROWS);
    csv.push_str("elongation_mm,force_n\n");
    for i in 1..=MAX_CURVE_ROWS + 1 {
        let _ = writeln!(csv, "{i},{i}");
    }
    let toml = dataset("huge", &format!("{HEAD}{TENSILE}"), &csv);
    let err = refused(
        &["check", s(&toml)],
        &format!("more than {MAX_CURVE_ROWS} points"),
    );
    assert!(
        err.contains(&format!("c.csv:{}:", MAX_CURVE_ROWS + 2)),
        "{err}"
    );
}

/// The example material with a `[warp]` law of `terms` terms, in a fresh folder.
#[track_caller]
fn material_with_terms(tag: &str, terms: usize) -> PathBuf {
    let mut text = std::fs::read_to_string(MATERIAL).unwrap();
    let mu: Vec<&str> = (0..terms)
        .map(|i| if i == 0 { "1.0" } else { "0.0" })
        .collect();
    let alpha = vec!["1.0"; terms];
    let _ = write!(
        text,
        "\n[warp]\nmu = [{}]\nalpha = [{}]\n",
        mu.join(", "),
        alpha.join(", ")
    );
    let path = folder(tag).join("m.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_law_of_too_many_terms_is_refused_at_its_line() {
    let tensile = |m: &Path| {
        [
            "tensile",
            "--material",
            s(m),
            "--angle",
            "90",
            "--width",
            "50",
            "--length",
            "75",
            "--to",
            "1",
            "--steps",
            "1",
            "--mesh",
            "2x3",
        ]
        .map(String::from)
    };
    let over = material_with_terms("terms-over", MAX_LAW_TERMS + 1);
    let args = tensile(&over);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let err = refused(
        &args,
        &format!(
            "[warp] has {} terms, more than the {MAX_LAW_TERMS}",
            MAX_LAW_TERMS + 1
        ),
    );
    let line = std::fs::read_to_string(&over)
        .unwrap()
        .lines()
        .position(|l| l.starts_with("mu = "))
        .unwrap()
        + 1;
    assert!(err.contains(&format!("m.toml:{line}:")), "{err}");
    let at = material_with_terms("terms-at", MAX_LAW_TERMS);
    let args = tensile(&at);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let (rc, _, err) = ks_fit(&args);
    assert_eq!(rc, 0, "{err}");
}

#[test]
fn a_dataset_of_too_many_tests_is_refused_at_the_first_beyond() {
    let many = |n: usize| format!("{HEAD}{}", TENSILE.repeat(n));
    let toml = dataset("tests-over", &many(MAX_DATASET_TESTS + 1), &short_curve());
    // HEAD is 2 lines, each table 5
    let line = 2 + 5 * MAX_DATASET_TESTS + 1;
    let err = refused(
        &["check", s(&toml)],
        &format!("{} tests", MAX_DATASET_TESTS + 1),
    );
    assert!(err.contains(&format!("fabric.toml:{line}:")), "{err}");
    let toml = dataset("tests-at", &many(MAX_DATASET_TESTS), &short_curve());
    let (rc, out, err) = ks_fit(&["check", s(&toml)]);
    assert_eq!(rc, 0, "{err}");
    assert!(
        out.contains(&format!("tests: {MAX_DATASET_TESTS} tensile")),
        "{out}"
    );
}

#[test]
fn check_shows_lab_numbers_rounded_and_refuses_an_implausible_density() {
    let bend =
        "[[bend]]\nangle_deg = 90\nwidth_mm = 25\noverhang_mm = 52\ndrape_angle_deg = 41.5\n";
    let toml = format!(
        "name = \"bounds\"\nareal_density_g_m2 = 103.6\nthickness_mm = 0.18\n{}{bend}",
        TENSILE.replace("width_mm = 50", "width_mm = 52")
    );
    let path = dataset("shown", &toml, &short_curve());
    let (rc, out, err) = ks_fit(&["check", s(&path)]);
    assert_eq!(rc, 0, "{err}");
    assert!(!out.contains("0000000"), "conversion noise shown:\n{out}");
    let rows: Vec<&str> = out
        .lines()
        .filter(|l| l.starts_with("tensile") || l.starts_with("bend"))
        .collect();
    assert!(
        rows.len() == 2 && rows.iter().all(|r| r.contains(" 52 ")),
        "{out}"
    );
    assert!(out.contains("areal density: 103.6 g/m²") && out.contains("thickness: 0.18 mm"));
    let heavy = dataset(
        "heavy",
        &toml.replace("areal_density_g_m2 = 103.6", "areal_density_g_m2 = 1e9"),
        &short_curve(),
    );
    let err = refused(
        &["check", s(&heavy)],
        "areal_density_g_m2 must be in [1, 5000]",
    );
    assert!(
        err.contains("fabric.toml:2:") && err.contains("got 1000000000"),
        "{err}"
    );
}

#[test]
fn clap_refusals_are_one_error_line_and_help_still_prints() {
    for args in [
        &["tensile", "--bogus"][..],
        &["tensile"][..],
        &["tensile", "--material", MATERIAL, "--steps", "abc"][..],
        &["no-such-command"][..],
        &[][..],
    ] {
        let (rc, out, err) = ks_fit(args);
        assert_eq!(rc, 2, "{args:?}\n{out}{err}");
        let lines: Vec<&str> = err.lines().collect();
        assert!(lines[0].starts_with("ks-fit: error: "), "{args:?}:\n{err}");
        let errors = lines
            .iter()
            .filter(|l| l.trim_start().to_lowercase().contains("error:"))
            .count();
        assert_eq!(errors, 1, "{args:?}: more than one error line:\n{err}");
    }
    let (_, _, err) = ks_fit(&["tensile"]);
    let first = err.lines().next().unwrap();
    assert!(
        first.contains("--material") && first.contains("--steps"),
        "{err}"
    );
    assert!(
        err.contains("Usage: ks-fit tensile"),
        "the usage is gone:\n{err}"
    );
    for flag in ["--help", "--version"] {
        let (rc, out, err) = ks_fit(&[flag]);
        assert_eq!(rc, 0, "{flag}: {err}");
        assert!(
            out.starts_with("Simulation-ready") || out.starts_with("ks-fit "),
            "{out}"
        );
    }
    let (rc, out, _) = ks_fit(&["tensile", "--help"]);
    assert!(rc == 0 && out.contains("Usage: ks-fit tensile"), "{out}");
}

#[test]
fn limits_and_huge_numbers_are_echoed_as_given() {
    let err = refused(
        &[
            "--max-faces",
            "0",
            "tensile",
            "--material",
            MATERIAL,
            "--angle",
            "0",
            "--width",
            "50",
            "--length",
            "75",
            "--to",
            "1",
            "--steps",
            "1",
            "--mesh",
            "2x3",
        ],
        "--max-faces must be at least 1",
    );
    assert!(!err.contains("limit of 1"), "{err}");
    let out = folder("echo");
    let json = out.join("m.json");
    for (args, want) in [
        (
            vec![
                "export",
                "--material",
                MATERIAL,
                "--format",
                "arcsim",
                "--out",
                s(&json),
                "--max-strain",
                "1e308",
            ],
            "strain range",
        ),
        (
            vec![
                "scene",
                "corner-pull",
                "--material",
                MATERIAL,
                "--out",
                s(&out),
                "--stretch",
                "1e308",
            ],
            "--stretch",
        ),
        (
            vec![
                "scene",
                "drape",
                "--material",
                MATERIAL,
                "--out",
                s(&out),
                "--tol",
                "1e308",
            ],
            "--tol",
        ),
        (
            vec![
                "recommend",
                "--material",
                MATERIAL,
                "--scene",
                "tensile",
                "--tol",
                "1e308",
            ],
            "--tol",
        ),
    ] {
        let err = refused(&args, want);
        assert!(err.contains("1e308") && err.len() < 300, "{args:?}: {err}");
    }
}

#[test]
fn a_manifest_of_too_many_rows_is_refused_at_the_first_beyond() {
    let dir = folder("rows");
    let mut text = String::from("fabric,dataset\n");
    for i in 0..=MAX_BATCH_ROWS {
        let _ = writeln!(text, "f{i},d/fabric.toml");
    }
    let manifest = dir.join("m.csv");
    std::fs::write(&manifest, text).unwrap();
    let err = refused(
        &["batch", s(&manifest), "--out", s(&dir.join("out"))],
        &format!("more than {MAX_BATCH_ROWS} fabrics"),
    );
    assert!(
        err.contains(&format!("m.csv:{}:", MAX_BATCH_ROWS + 2)),
        "{err}"
    );
    assert!(!dir.join("out").exists(), "the batch started");
}

#[test]
fn a_batch_estimates_the_time_left_only_from_enough_fabrics() {
    let dir = folder("eta");
    let manifest = dir.join("m.csv");
    let rows: String = (0..4)
        .map(|i| format!("f{i},missing{i}/fabric.toml\n"))
        .collect();
    std::fs::write(&manifest, format!("fabric,dataset\n{rows}")).unwrap();
    let (rc, _, err) = ks_fit(&["batch", s(&manifest), "--out", s(&dir.join("out"))]);
    assert_eq!(rc, 3, "{err}");
    let done: Vec<&str> = err.lines().filter(|l| l.contains(" of 4 done")).collect();
    assert_eq!(done.len(), 4, "{err}");
    for l in &done[..2] {
        assert!(l.contains("time left not estimated until 3 fabrics"), "{l}");
    }
    assert!(
        done[2].contains(", about ") && done[2].contains(" left (1 fabric at the "),
        "{}",
        done[2]
    );
    assert!(!done[3].contains("left"), "{}", done[3]);
    let summary = std::fs::read_to_string(dir.join("out/summary.csv")).unwrap();
    assert_eq!(summary.lines().count(), 5, "{summary}");
}
