//! `--model` on the lab commands, driven through the binary: the triangle models print the
//! shell's CSV, read and refuse material files clearly, and refuse what they cannot simulate.

use crate::common::{first_value, folder, ks_fit};

const COTTON: &str = "examples/materials/cotton.toml";

/// `ks-fit recommend --material COTTON ARGS…`: exit code, stdout, stderr.
fn recommend(args: &[&str]) -> (i32, String, String) {
    ks_fit(&[&["recommend", "--material", COTTON], args].concat())
}

/// The reference on `recommend`'s first line and the rows of its table (split at commas).
fn table(out: &str) -> (f64, Vec<Vec<&str>>) {
    let lines: Vec<&str> = out.lines().collect();
    let reference: f64 = lines[0]
        .split("reference ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(
        lines[1],
        "model,params,mesh,seconds,value,rel_error,within_tol"
    );
    let rows = lines[2..lines.len() - 1]
        .iter()
        .map(|l| l.split(',').collect())
        .collect();
    (reference, rows)
}

/// A 50 × 75 mm warp strip of stvk-ds converted from the example cotton: the aligned strip's
/// strain is uniform and the diagonal model has no Poisson coupling, so its force at
/// elongation δ is the closed form k (ε + ε²/2)(1 + ε) W with ε = δ/L and k the shell's
/// uniaxial warp modulus (a₁₁ − a₁₂²/a₂₂) τ = (2e8 − 6e7²/1.2e8) · 1.8e-4 N/m.
#[test]
fn tensile_with_a_triangle_model_prints_the_shells_csv_and_the_closed_form() {
    let (rc, out, err) = ks_fit(&[
        "tensile",
        "--material",
        COTTON,
        "--angle",
        "90",
        "--width",
        "50",
        "--length",
        "75",
        "--to",
        "1.5",
        "--steps",
        "2",
        "--model",
        "stvk-ds",
    ]);
    assert_eq!(rc, 0, "{err}");
    assert!(err.contains("converted from the shell law"), "{err}");
    // the strain is uniform: every mesh of the automatic ladder agrees, so the first is kept
    assert!(err.contains("mesh 4x6 (stvk-ds) chosen from 4x6"), "{err}");
    let rows: Vec<&str> = out.lines().collect();
    assert_eq!(rows[0], "elongation_mm,force_n");
    let k = (2e8 - 6e7 * 6e7 / 1.2e8) * 1.8e-4;
    for (row, dl) in rows[1..].iter().zip([0.75e-3, 1.5e-3]) {
        let f: f64 = row.split(',').nth(1).unwrap().parse().unwrap();
        let e: f64 = dl / 0.075;
        let exact = k * (e + 0.5 * e * e) * (1.0 + e) * 0.05;
        assert!((f - exact).abs() < 1e-9 * exact, "{f} vs {exact}");
    }
}

#[test]
fn bend_with_every_triangle_model_gives_an_angle() {
    for model in ["soft-constraints", "stvk-ds", "xpbd"] {
        let (rc, out, err) = ks_fit(&[
            "bend",
            "--material",
            COTTON,
            "--angle",
            "90",
            "--overhang",
            "47.7",
            "--mesh",
            "4x8",
            "--model",
            model,
        ]);
        assert_eq!(rc, 0, "{model}: {err}");
        let angle: f64 = first_value(&out);
        assert!(angle > 5.0 && angle < 30.0, "{model}: {out}");
    }
}

#[test]
fn what_a_model_cannot_do_is_refused_clearly() {
    let (rc, _, err) = ks_fit(&[
        "tensile",
        "--material",
        COTTON,
        "--angle",
        "45",
        "--width",
        "50",
        "--length",
        "75",
        "--to",
        "1",
        "--steps",
        "1",
        "--model",
        "springs",
    ]);
    assert_eq!(rc, 2, "{err}");
    assert!(
        err.contains("springs model needs its grid along the yarns"),
        "{err}"
    );
    for (flag, value, says) in [
        (
            "--boundary",
            "ghost",
            "--boundary and --grading apply to the kl model",
        ),
        ("--yarn-rule", "centre", "(as does --yarn-rule)"),
    ] {
        let (rc, _, err) = ks_fit(&[
            "bend",
            "--material",
            COTTON,
            "--angle",
            "90",
            "--overhang",
            "40",
            "--model",
            "xpbd",
            flag,
            value,
        ]);
        assert_eq!(rc, 2, "{err}");
        assert!(err.contains(says), "{err}");
    }
    let (rc, _, err) = ks_fit(&[
        "bend",
        "--material",
        COTTON,
        "--angle",
        "90",
        "--overhang",
        "40",
        "--model",
        "cloth",
    ]);
    assert_eq!(rc, 2, "{err}");
    assert!(err.contains("unknown model 'cloth'"), "{err}");
}

/// A file with only a `[model]` table serves its model and is pointed to `--model` by the
/// shell's commands; a table of another kind is refused naming the right flag.
#[test]
fn model_tables_are_read_and_misuse_is_explained() {
    let dir = folder("model-table");
    let path = dir.join("m.toml");
    std::fs::write(
        &path,
        "name = \"t\"\nareal_density_g_m2 = 100.0\n[model]\nkind = \"soft-constraints\"\n\
         stretch_warp_n_per_m = [30000.0]\nstretch_weft_n_per_m = [18000.0]\nshear_n_per_m = [300.0]\n\
         bend_warp_n_m = [2.0e-5]\nbend_weft_n_m = [1.0e-5]\nbend_diag_n_m = [1.4e-5]\n",
    )
    .unwrap();
    let p = path.to_str().unwrap();
    let args = |model: &'static str| {
        vec![
            "tensile",
            "--material",
            p,
            "--angle",
            "90",
            "--width",
            "50",
            "--length",
            "75",
            "--to",
            "1.5",
            "--steps",
            "1",
            "--model",
            model,
        ]
    };
    let (rc, out, err) = ks_fit(&args("soft-constraints"));
    assert_eq!(rc, 0, "{err}");
    // Baraff–Witkin strain is the stretch: F = k ε W exactly
    let f: f64 = first_value(&out);
    assert!((f - 30000.0 * 0.02 * 0.05).abs() < 1e-9, "{out}");
    let (rc, _, err) = ks_fit(&args("kl"));
    assert_eq!(rc, 2);
    assert!(
        err.contains("use it with --model soft-constraints"),
        "{err}"
    );
    let (rc, _, err) = ks_fit(&args("stvk-ds"));
    assert_eq!(rc, 2);
    assert!(err.contains("run with --model soft-constraints"), "{err}");
}

/// `synth --model`: a dataset made by a triangle model. The stvk-ds warp strip is uniform with
/// no Poisson coupling, so every point of its curve is the closed form of
/// `tensile_with_a_triangle_model_prints_the_shells_csv_and_the_closed_form`; a `[model]` table
/// needs a thickness beside it, and the shell's grading is refused.
#[test]
fn synth_with_a_triangle_model_writes_that_models_curves() {
    let dir = folder("synth-model");
    let out = dir.join("data");
    let (rc, _, err) = ks_fit(&[
        "synth",
        "--material",
        COTTON,
        "--out",
        out.to_str().unwrap(),
        "--model",
        "stvk-ds",
        "--points",
        "4",
        "--mesh",
        "4x6",
    ]);
    assert_eq!(rc, 0, "{err}");
    let toml = std::fs::read_to_string(out.join("fabric.toml")).unwrap();
    assert!(toml.contains("(model stvk-ds)"), "{toml}");
    let csv = std::fs::read_to_string(out.join("warp-1.csv")).unwrap();
    let k = (2e8 - 6e7 * 6e7 / 1.2e8) * 1.8e-4;
    let mut rows = 0;
    for row in csv.lines().skip(1) {
        let v: Vec<f64> = row.split(',').map(|x| x.parse().unwrap()).collect();
        let e = v[0] * 1e-3 / 0.075;
        let exact = k * (e + e * e / 2.0) * (1.0 + e) * 0.05;
        assert!((v[1] / exact - 1.0).abs() < 1e-6, "{row}: exact {exact}");
        rows += 1;
    }
    assert_eq!(rows, 4);
    // the dataset loads and has both bends at 41.5°
    let (data, _) = kshell::dataset::load_dataset(&out.join("fabric.toml")).unwrap();
    assert_eq!(data.bend.len(), 2);

    let table = dir.join("ds.toml");
    std::fs::write(
        &table,
        "name = \"t\"\nareal_density_g_m2 = 100.0\n[model]\nkind = \"stvk-ds\"\n\
         stretch_warp_n_per_m = [30000.0]\nstretch_weft_n_per_m = [20000.0]\n\
         shear_n_per_m = [400.0]\nbend_warp_n_m = [8e-5]\nbend_weft_n_m = [5e-5]\n\
         bend_diag_n_m = [6e-5]\n",
    )
    .unwrap();
    let args = |extra: &[&'static str]| {
        let mut a = vec![
            "synth".to_string(),
            "--material".into(),
            table.to_str().unwrap().into(),
            "--out".into(),
            dir.join("d2").to_str().unwrap().into(),
            "--model".into(),
            "stvk-ds".into(),
        ];
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    let run = |a: Vec<String>| ks_fit(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let (rc, _, err) = run(args(&[]));
    assert_eq!(rc, 2);
    assert!(err.contains("needs thickness_mm"), "{err}");
    let (rc, _, err) = run(args(&["--grading", "0.5"]));
    assert_eq!(rc, 2);
    assert!(err.contains("--grading applies to the kl model"), "{err}");
}

/// `recommend`: the table is consistent (every error is |value − reference| / reference, the
/// pick is the fastest row within --tol), a tolerance nothing meets exits 3 naming the most
/// accurate run, and a --meshes ladder Richardson's extrapolation cannot use is refused.
#[test]
fn recommend_picks_the_fastest_run_within_the_tolerance() {
    let run = |tol: &str| {
        recommend(&[
            "--scene",
            "tensile",
            "--angle",
            "90",
            "--tol",
            tol,
            "--repeats",
            "1",
        ])
    };
    let (rc, out, err) = run("0.02");
    assert_eq!(rc, 0, "{out}{err}");
    let lines: Vec<&str> = out.lines().collect();
    let (reference, rows) = table(&out);
    // the shell and all four triangle models (springs too: the strip is on the warp), 3 meshes
    assert_eq!(rows.len(), 15, "{out}");
    let mut fastest_within: Option<(f64, String)> = None;
    for r in &rows {
        let (secs, value, error): (f64, f64, f64) = (
            r[3].parse().unwrap(),
            r[4].parse().unwrap(),
            r[5].parse().unwrap(),
        );
        let exact = (value - reference).abs() / reference;
        assert!((error - exact).abs() <= 1e-3 * exact + 1e-9, "{r:?}");
        assert_eq!(r[6] == "yes", error <= 0.02, "{r:?}");
        if error <= 0.02 && fastest_within.as_ref().is_none_or(|f| secs < f.0) {
            fastest_within = Some((secs, format!("{} ({}) on {}", r[0], r[1], r[2])));
        }
    }
    let pick = fastest_within.expect("some run within 2 %").1;
    assert!(
        lines
            .last()
            .unwrap()
            .starts_with(&format!("recommended: {pick}:")),
        "{out}"
    );

    let (rc, out, _) = run("1e-9");
    assert_eq!(rc, 3, "{out}");
    assert!(out.contains("recommended: none meets --tol") && out.contains("the most accurate is"));

    // a ladder Richardson cannot use is refused before anything runs
    let (rc, _, err) = recommend(&["--scene", "tensile", "--meshes", "8x12,12x18"]);
    assert_eq!(rc, 2);
    assert!(err.contains("twice as fine"), "{err}");
}

/// `recommend --scene drape`: compared on the mean drop (the fold patterns differ between
/// meshes and models); the reference is the shell on the finest mesh of its ladder, never an
/// extrapolation, and says how far the mesh before it lies; a sheet mesh must be square.
#[test]
fn recommend_compares_the_models_on_the_drape_by_its_mean_drop() {
    let (rc, out, err) = recommend(&["--scene", "drape", "--meshes", "4x4,8x8", "--tol", "0.05"]);
    assert!(rc == 0 || rc == 3, "{out}{err}");
    let first = out.lines().next().unwrap_or_default();
    assert!(
        first.starts_with("# drape: drape's mean drop (mm)"),
        "{out}"
    );
    assert!(
        first.contains(
            "from the shell on 8x8 (the meshes fold differently, so no extrapolation; 4x4 within"
        ),
        "{out}"
    );
    let (reference, rows) = table(&out);
    // five models on two meshes, each run once (the drape's default)
    assert_eq!(rows.len(), 10, "{out}");
    for r in &rows {
        let value: f64 = r[4].parse().unwrap();
        // a 1 m sheet's centre of mass hangs about half a metre below its corners
        assert!(value > 400.0 && value < 700.0, "{r:?}");
        if r[0] == "kl" && r[2] == "8x8" {
            assert!((value - reference).abs() <= 1e-6 * reference, "{r:?}");
        }
    }
    let (rc, _, err) = recommend(&["--scene", "drape", "--meshes", "8x16"]);
    assert_eq!(rc, 2);
    assert!(err.contains("square"), "{err}");
}

/// `recommend --scene picture-frame`: every model runs the frame on the shell's three meshes;
/// the membrane models (one strain measure or another, the same zero-strain moduli) agree with
/// the converged shell within 2 % at 20° on every mesh, while the springs model, whose shear
/// is carried by diagonal springs, stiffens as its mesh is refined (Miguel et al. 2012 fit
/// their springs per mesh for this reason).
#[test]
fn recommend_compares_the_models_on_the_picture_frame() {
    let (rc, out, err) = recommend(&[
        "--scene",
        "picture-frame",
        "--shear-deg",
        "20",
        "--repeats",
        "1",
    ]);
    assert_eq!(rc, 0, "{out}{err}");
    assert!(
        out.starts_with("# picture-frame: picture frame's shear force at 20°"),
        "{out}"
    );
    let (_, rows) = table(&out);
    assert_eq!(rows.len(), 15, "{out}");
    for r in &rows {
        let error: f64 = r[5].parse().unwrap();
        match r[0] {
            "springs" => {}
            _ => assert!(error < 0.02, "{r:?}"),
        }
    }
    let springs: Vec<f64> = rows
        .iter()
        .filter(|r| r[0] == "springs")
        .map(|r| r[4].parse().unwrap())
        .collect();
    assert!(springs.windows(2).all(|w| w[1] > w[0]), "{springs:?}");
    assert!(
        out.lines().last().unwrap().starts_with("recommended: "),
        "{out}"
    );
}
