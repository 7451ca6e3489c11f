//! End-to-end tests of the fabric dataset through `ks-fit check` and `ks-fit synth`: a good
//! dataset is summarised, broken ones exit with code 2 naming the file and line, and a
//! synthetic dataset checks, rises, and reproduces its drape angles.

use crate::common::ks_fit;
use std::path::{Path, PathBuf};

/// A fresh folder for one test.
fn folder(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("kshell-dataset-cli-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const TOML: &str = "name = \"poplin\"
areal_density_g_m2 = 103.6
thickness_mm = 0.18

[[tensile]]
angle_deg = 90
width_mm = 50
gauge_length_mm = 75
curve = \"warp-1.csv\"

[[tensile]]
angle_deg = 22.5
width_mm = 50
gauge_length_mm = 75
curve = \"a22.5-1.csv\"

[[bend]]
angle_deg = 90
width_mm = 25
overhang_mm = 61.0
drape_angle_deg = 41.5
";

const CSV: &str = "elongation_mm,force_n\n0.75,20.5\n1.5,41.0\n3.0,80.0\n";

/// Writes the dataset (`toml`, and `csv` as both curves) and returns its fabric.toml.
fn dataset(tag: &str, toml: &str, csv: &str) -> PathBuf {
    let dir = folder(tag);
    std::fs::write(dir.join("fabric.toml"), toml).unwrap();
    std::fs::write(dir.join("warp-1.csv"), csv).unwrap();
    std::fs::write(dir.join("a22.5-1.csv"), CSV).unwrap();
    dir.join("fabric.toml")
}

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn check_summarises_a_good_dataset() {
    let toml = dataset("good", TOML, CSV);
    let (rc, out, err) = ks_fit(&["check", path_str(&toml)]);
    assert_eq!(rc, 0, "{out}{err}");
    for want in [
        "name: poplin",
        "areal density: 103.6 g/m²",
        "thickness: 0.18 mm",
        "tests: 2 tensile, 1 bend",
        "fitted (warp-1.csv)",
        "fitted (a22.5-1.csv)",
        "info: tensile 22.5° (a22.5-1.csv) is not at 0, 45 or 90°: fitted by default",
        "fitted (drape 41.5°)",
        "valid",
    ] {
        assert!(out.contains(want), "missing {want:?} in\n{out}");
    }
    let row = out.lines().find(|l| l.contains("warp-1.csv")).unwrap();
    let cols: Vec<&str> = row.split_whitespace().collect();
    assert_eq!(
        cols[..7],
        ["tensile", "90", "50", "75", "3", "3.0000", "80.0000"]
    );
    // warnings are listed, and the dataset stays valid
    let toml = dataset("warn", TOML, "elongation_mm,force_n\n1.5,0.04\n3,0.08\n");
    let (rc, out, _) = ks_fit(&["check", path_str(&toml)]);
    assert_eq!(rc, 0);
    assert!(
        out.contains("warp-1.csv:3: warning: the largest force is 0.08 N"),
        "{out}"
    );
    assert!(out.contains("valid (1 warning)"), "{out}");
}

#[test]
fn check_errors_name_file_and_line_with_exit_code_2() {
    let cases = [
        (
            TOML.replace("thickness_mm = 0.18", "thickness_mm = 0.18 0.2"),
            CSV.to_string(),
            "fabric.toml:3: ",
        ),
        (
            format!("{TOML}colour = \"blue\"\n"),
            CSV.to_string(),
            "fabric.toml:22: unknown field `colour`",
        ),
        (
            TOML.replace("areal_density_g_m2 = 103.6\n", ""),
            CSV.to_string(),
            "fabric.toml:16: bend test 1: a bend test needs areal_density_g_m2",
        ),
        (
            TOML.replace("curve = \"warp-1.csv\"", "curve = \"missing.csv\""),
            CSV.to_string(),
            "fabric.toml:9: tensile test 1: cannot read curve file",
        ),
        (
            TOML.replace("angle_deg = 22.5", "angle_deg = 200"),
            CSV.to_string(),
            "fabric.toml:12: tensile test 2: angle_deg must be in [0, 180)",
        ),
        (
            TOML.to_string(),
            "elongation_mm,force_n\n1,2\n0.5,3\n".into(),
            "warp-1.csv:3: column 1 (elongation_mm) = 0.5 is below the previous row's 1",
        ),
        (
            TOML.to_string(),
            "elong;force\n1;2\n".into(),
            "warp-1.csv:1: the header must be",
        ),
        (
            TOML.to_string(),
            "elongation_mm,force_n\n1,2\n2,abc\n".into(),
            "warp-1.csv:3: column 2 (force_n): `abc` is not a number",
        ),
    ];
    for (i, (toml, csv, want)) in cases.iter().enumerate() {
        let path = dataset(&format!("bad{i}"), toml, csv);
        let (rc, out, err) = ks_fit(&["check", path_str(&path)]);
        assert_eq!(rc, 2, "{want}: {out}{err}");
        assert!(out.is_empty(), "{out}");
        let line = err.trim_end();
        assert!(line.starts_with("ks-fit: error: "), "{err}");
        assert!(!line.contains('\n'), "{err}");
        let dir = path.parent().unwrap().display().to_string();
        assert!(line.contains(&dir), "{err} should name the file in {dir}");
        assert!(line.contains(want), "{err} should contain {want:?}");
    }
    let (rc, _, err) = ks_fit(&["check", "no/such/fabric.toml"]);
    assert_eq!(rc, 2);
    assert!(
        err.contains("no/such/fabric.toml: cannot read file"),
        "{err}"
    );
}

#[test]
fn synth_round_trip_checks_rises_and_reproduces_the_drape_angle() {
    let dir = folder("synth");
    let out_dir = dir.join("cotton");
    let (rc, out, err) = ks_fit(&[
        "synth",
        "--material",
        "examples/materials/cotton.toml",
        "--out",
        path_str(&out_dir),
        "--points",
        "3",
        "--mesh",
        "4x6",
    ]);
    assert_eq!(rc, 0, "{out}{err}");
    assert!(err.contains("cantilever warp (90°)"), "{err}");
    let toml = out_dir.join("fabric.toml");
    let text = std::fs::read_to_string(&toml).unwrap();
    assert!(text.starts_with("# SYNTHETIC dataset"), "{text}");
    assert!(text.contains("examples/materials/cotton.toml"), "{text}");
    let (rc, out, err) = ks_fit(&["check", path_str(&toml)]);
    assert_eq!(rc, 0, "{out}{err}");
    assert!(out.contains("tests: 5 tensile, 2 bend"), "{out}");
    assert!(!out.contains("warning"), "{out}");

    let (data, warnings) = kshell::dataset::load_dataset(&toml).unwrap();
    assert!(warnings.is_empty());
    let warp = data.tests_at(90.0);
    assert_eq!(warp.len(), 1);
    assert_eq!(warp[0].curve, PathBuf::from("warp-1.csv"));
    assert_eq!(warp[0].elongation.len(), 3);
    assert!((warp[0].elongation[2] - 0.0075).abs() < 1e-15);
    assert!(warp[0].force[0] > 0.0);
    assert!(
        warp[0].force.windows(2).all(|w| w[1] > w[0]),
        "{:?}",
        warp[0].force
    );
    for stem in ["weft-1.csv", "bias-1.csv", "a22.5-1.csv", "a67.5-1.csv"] {
        assert!(out_dir.join(stem).exists(), "{stem}");
    }
    assert_eq!(data.bend.len(), 2);
    // the file's notes name each cantilever's mesh (warp, then weft, as the tests)
    let meshes: Vec<&str> = text
        .lines()
        .filter_map(|l| l.split("overhang found on ").nth(1))
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(meshes.len(), 2, "{text}");
    for (b, mesh) in data.bend.iter().zip(meshes) {
        let overhang = format!("{:?}", b.overhang * 1e3);
        let angle = format!("{}", b.angle_deg);
        let drape = |extra: &[&str]| -> (f64, String) {
            let mut args = vec![
                "bend",
                "--material",
                "examples/materials/cotton.toml",
                "--angle",
                &angle,
                "--overhang",
                &overhang,
            ];
            args.extend_from_slice(extra);
            let (rc, out, err) = ks_fit(&args);
            assert_eq!(rc, 0, "{err}");
            let a = out.lines().nth(1).unwrap().split(',').nth(1).unwrap();
            (a.parse().unwrap(), err)
        };
        // the mesh named reproduces the target angle (the search's tolerance is 1e-4°)
        let (on_mesh, _) = drape(&["--mesh", mesh]);
        assert!(
            (on_mesh - 41.5).abs() < 1e-3,
            "{angle}°: {overhang} mm gives {on_mesh}° on {mesh}"
        );
        // and the data carry no visible mesh error: `bend`'s own automatic mesh at 0.005°
        // agrees within synth's 0.01° plus that
        let (converged, err) = drape(&["--tol", "0.005"]);
        assert!(
            (converged - 41.5).abs() < kshell::synth::BEND_TOL_DEG + 0.005,
            "{angle}°: {overhang} mm drapes {converged}° on a converged mesh ({err})"
        );
    }

    // bad options are one-line errors with exit code 2
    for (flag, value, want) in [
        ("--points", "0", "points must be at least 1"),
        ("--max-strain", "1.5", "max strain must be in (0, 1]"),
        ("--noise", "-0.1", "noise must be"),
    ] {
        let (rc, _, err) = ks_fit(&[
            "synth",
            "--material",
            "examples/materials/cotton.toml",
            "--out",
            path_str(&dir.join("never")),
            flag,
            value,
        ]);
        assert_eq!(rc, 2, "{flag} {value}: {err}");
        assert!(
            err.starts_with("ks-fit: error: ") && err.contains(want),
            "{err}"
        );
    }
    assert!(!dir.join("never").exists());
}
