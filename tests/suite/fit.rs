//! `ks-fit fit` end to end: a noise-free synthetic dataset from a degree-2 material is fitted
//! back (every curve within 0.5 % on average, both drape angles within 0.2° of 41.5°: the
//! issue's acceptance numbers), the output loads as a material and carries its `[fit]` table,
//! and datasets the fit cannot use are refused with exit code 2.

use crate::common::{folder, ks_fit, s, TestLaw};

/// The `[fit]` table's notes.
fn notes_of(fit: &toml::Table) -> Vec<&str> {
    fit["notes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|n| n.as_str())
        .collect()
}

/// A degree-2 material (warp and weft stiffen, shear stiffens strongly), no cut-offs.
const DEGREE2: &str = "name = \"degree-2\"
areal_density_g_m2 = 103.6
thickness_mm = 0.18
a11_pa = 2.0e8
a22_pa = 1.2e8
g12_pa = 4.0e6
[warp]
mu = [0.6, 0.4]
alpha = [1.0, 150.0]
[weft]
mu = [0.8, 0.2]
alpha = [1.0, 100.0]
[shear]
mu = [0.7, 0.3]
alpha = [1.0, 300.0]
";

/// A noise-free dataset of `DEGREE2` written by `ks-fit synth` into `dir/data` with `points`
/// per curve, on the fit's own first mesh and cage grading (so that a perfect fit exists).
fn synth_degree2(dir: &std::path::Path, points: &str) -> std::path::PathBuf {
    synth(dir, DEGREE2, points)
}

fn synth(dir: &std::path::Path, material_text: &str, points: &str) -> std::path::PathBuf {
    synth_on(dir, material_text, points, "8x12")
}

/// As [`synth`], the strips on graded `mesh` cages.
fn synth_on(
    dir: &std::path::Path,
    material_text: &str,
    points: &str,
    mesh: &str,
) -> std::path::PathBuf {
    synth_with(dir, material_text, points, mesh, &[])
}

/// [`synth_on`] with more `synth` arguments.
fn synth_with(
    dir: &std::path::Path,
    material_text: &str,
    points: &str,
    mesh: &str,
    extra: &[&str],
) -> std::path::PathBuf {
    let material = dir.join("material.toml");
    std::fs::write(&material, material_text).unwrap();
    let data = dir.join("data");
    let mut args = vec![
        "synth",
        "--material",
        s(&material),
        "--out",
        s(&data),
        "--points",
        points,
        "--mesh",
        mesh,
        "--grading",
        "0.8,0.8",
    ];
    args.extend_from_slice(extra);
    let (rc, out, err) = ks_fit(&args);
    assert_eq!(rc, 0, "{out}{err}");
    data
}

#[test]
fn noise_free_degree2_data_are_fitted_back() {
    let dir = folder("fit-degree2");
    let data = synth_degree2(&dir, "6");
    // start the thickness 25 % off: the bend tests must bring it back
    let fabric = data.join("fabric.toml");
    let text = std::fs::read_to_string(&fabric).unwrap();
    std::fs::write(
        &fabric,
        text.replace("thickness_mm = 0.18", "thickness_mm = 0.225"),
    )
    .unwrap();
    let fitted = dir.join("fitted.toml");
    let report = dir.join("report");
    let (rc, out, err) = ks_fit(&[
        "fit",
        s(&fabric),
        "-o",
        s(&fitted),
        "--report",
        s(&report),
        "--mesh-ladder",
        "8x12",
        "--max-degree",
        "2",
        "--protocol",
        "paper",
        // the material bends as the paper's model does: one thickness for both bends
        "--bending",
        "paper",
        // the data were made on this mesh, so that a perfect fit exists there: refining a
        // strip on its own would fit the data's mesh error (each_test_is_refined_… below)
        "--test-meshes",
        "ladder",
    ]);
    assert_eq!(rc, 0, "{out}{err}");
    assert!(err.contains("warp stage"), "progress on stderr: {err}");
    assert!(out.contains("avg_rel_error"), "the table: {out}");

    let m = kshell::material::load_material(&fitted).expect("the output is a material file");
    assert!(
        (m.thickness / 0.18e-3 - 1.0).abs() < 0.02,
        "thickness {}",
        m.thickness
    );
    // plausible laws (loading checked that the stress rises inside the cut-offs): exponents
    // within the bound and no negligible term over the tested range. The fitter bounds |α x̂|
    // with x̂ from the strips' largest Green strain e (synth's 10 % strain: e = 0.105): e² for
    // the yarns, (e/2)² for the shear; negligibility is judged over the range the cut-offs
    // say the strips reached, x̂ = (cut-off / 0.95)²
    {
        let law = &m.law;
        let c = law.cutoffs;
        let e = 0.105;
        for (eta, e_cut, e_fit) in [
            (&law.warp, c.e11.1, e),
            (&law.weft, c.e22.1, e),
            (&law.shear, c.e12.1, 0.5 * e),
        ] {
            for a in &eta.alpha {
                let beta = a * e_fit * e_fit;
                assert!(beta.abs() <= kshell::fit::map::BETA_MAX + 1e-9, "{eta:?}");
            }
            let xhat = (e_cut / 0.95).powi(2);
            assert!(xhat.is_finite() && xhat > 0.0, "cut-off {e_cut}");
            let small = kshell::fit::plausible::negligible_terms(eta, xhat);
            assert!(small.is_empty(), "negligible terms {small:?} in {eta:?}");
        }
    }
    let doc: toml::Table = std::fs::read_to_string(&fitted).unwrap().parse().unwrap();
    let fit = doc["fit"].as_table().expect("[fit]");
    assert_eq!(fit["meshes"].as_array().unwrap().len(), 1);
    assert!(fit["objective_evaluations"].as_integer().unwrap() > 0);
    // every Newton iteration is put down to one stage
    let per_stage: i64 = fit["stage_iterations"]
        .as_table()
        .expect("[fit.stage_iterations]")
        .values()
        .map(|v| v.as_integer().unwrap())
        .sum();
    assert_eq!(per_stage, fit["newton_iterations"].as_integer().unwrap());
    // every run solves at least one equilibrium, and every equilibrium is counted
    let equilibria = fit["equilibria_solved"].as_integer().unwrap();
    assert!(
        equilibria >= fit["objective_evaluations"].as_integer().unwrap(),
        "{equilibria} equilibria"
    );
    // what the assumed a12 does to the small-strain quantities (`fit/poisson.rs`): each
    // stage's dependence is written, and its identifiability line follows the tolerance
    let ident: Vec<&str> = fit["identifiability"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|l| l.as_str())
        .collect();
    for (key, quantity) in [
        ("a12_dependence_warp", "E1·τ"),
        ("a12_dependence_weft", "E2·τ"),
        ("a12_dependence_off_axis", "(1/G"),
    ] {
        let d = fit[key]
            .as_float()
            .unwrap_or_else(|| panic!("{key}: {fit:?}"));
        assert!((0.0..0.2).contains(&d), "{key} = {d}");
        let line = ident.iter().find(|l| l.starts_with(quantity)).unwrap();
        let tol = kshell::fit::poisson::A12_DEPENDENCE_TOL;
        assert_eq!(
            line.contains("only with the assumed a12"),
            d > tol,
            "{line}"
        );
    }
    let tests = fit["test"].as_array().expect("[[fit.test]]");
    let mut kinds = Vec::new();
    for t in tests {
        let kind = t["kind"].as_str().unwrap();
        let angle = t["angle_deg"].as_float().unwrap();
        kinds.push(kind.to_string());
        match kind {
            "tensile" => {
                let e = t["avg_rel_error"].as_float().unwrap();
                assert!(e <= 0.005, "tensile {angle}°: average relative error {e}");
            }
            "bend" => {
                let a = t["drape_angle_deg"].as_float().unwrap();
                assert!((a - 41.5).abs() <= 0.2, "bend {angle}°: {a}°");
            }
            "validation" => {
                // noise-free data cut at the nominal angle: the prediction at that angle is
                // the reported error, and the diagnostic stays inside its ±2° bound
                assert!(t["misalign_deg"].as_float().unwrap().abs() <= 2.0);
                let e = t["avg_rel_error"].as_float().unwrap();
                let aligned = t["avg_rel_error_aligned"].as_float().unwrap();
                assert!(e < 0.02, "validation {angle}°: {e}");
                assert!(aligned < 0.02, "validation {angle}°: aligned {aligned}");
            }
            other => panic!("unknown kind {other}"),
        }
    }
    for (kind, n) in [("tensile", 3), ("bend", 2), ("validation", 2)] {
        assert_eq!(kinds.iter().filter(|k| *k == kind).count(), n, "{kinds:?}");
    }
    for f in [
        "tensile-warp-1.csv",
        "tensile-warp-1.svg",
        "validation-a22.5-1.csv",
        "summary.txt",
    ] {
        assert!(report.join(f).exists(), "report file {f}");
    }
    let csv = std::fs::read_to_string(report.join("tensile-bias-1.csv")).unwrap();
    assert!(
        csv.starts_with("elongation_mm,measured_n,fitted_n,rel_error\n"),
        "{csv}"
    );
    check_report_page(&report.join("index.html"), tests.len(), 5);
    // and a browser draws it: the page at 1200 px wide, its first screen not blank
    if let Some(png) = crate::common::screenshot(
        &report.join("index.html"),
        &dir.join("page.png"),
        1200,
        1600,
    ) {
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        assert_eq!(&png[16..24], &[0, 0, 4, 176, 0, 0, 6, 64], "1200 x 1600");
        #[cfg(feature = "render")]
        {
            let decoder = png::Decoder::new(std::io::Cursor::new(&png));
            let mut reader = decoder.read_info().unwrap();
            let mut buf = vec![0; reader.output_buffer_size().unwrap()];
            let info = reader.next_frame(&mut buf).unwrap();
            let channels = info.color_type.samples();
            let inked = buf
                .chunks(channels)
                .filter(|p| p[..3].iter().any(|&c| c < 200))
                .count();
            let share = inked as f64 / (1200.0 * 1600.0);
            assert!(
                share > 0.02,
                "only {:.3} % of the page is drawn",
                100.0 * share
            );
        }
    }
}

/// The report's index.html parses (it is written as polyglot markup, so an XML parser is a
/// strict check), references nothing outside itself, has one row per test in its error table
/// and one inline plot per cut angle.
fn check_report_page(path: &std::path::Path, tests: usize, angles: usize) {
    let text = std::fs::read_to_string(path).expect("index.html");
    let opts = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    let doc = roxmltree::Document::parse_with_options(&text, opts)
        .unwrap_or_else(|e| panic!("index.html does not parse: {e}"));
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "html");
    for n in doc.descendants().filter(|n| n.is_element()) {
        let name = n.tag_name().name();
        assert!(
            !["script", "link", "iframe", "object", "embed"].contains(&name),
            "external or active content: <{name}>"
        );
        if let Some(src) = n.attribute("src") {
            assert!(
                src.starts_with("data:image/png;base64,"),
                "<{name} src={src:.40}>"
            );
        }
        if let Some(href) = n.attribute("href") {
            assert!(href.starts_with('#'), "<{name} href={href}>");
        }
    }
    let error_table = doc
        .descendants()
        .find(|n| n.has_tag_name("h2") && n.text() == Some("Errors per test"))
        .and_then(|h| h.next_siblings().find(|n| n.has_tag_name("table")))
        .expect("the error table");
    let rows = error_table
        .children()
        .filter(|n| n.has_tag_name("tr"))
        .count();
    assert_eq!(rows, tests + 1, "one row per test and a header");
    let plots = doc
        .descendants()
        .filter(|n| n.has_tag_name("figure"))
        .filter(|f| f.children().any(|c| c.tag_name().name() == "svg"))
        .count();
    assert_eq!(plots, angles, "one inline plot per cut angle");
}

/// Bending of its own: a fabric twice as stiff in
/// bending across the weft as along the warp, although its warp is the stiffer in tension
/// (ratios 0.5 and 1.7). The paper's one thickness cannot drape both cantilevers at 41.5°;
/// the default (orthotropic, both bends present) fits both and recovers the rigidities.
#[test]
fn bending_of_its_own_fits_both_drapes_where_one_thickness_cannot() {
    let dir = folder("fit-own-bending");
    let material = format!("{DEGREE2}[bending]\nwarp_n_m = 3.0e-5\nweft_n_m = 6.0e-5\n");
    let data = synth(&dir, &material, "5");
    let fabric = data.join("fabric.toml");
    let run = |mode: Option<&str>| {
        let fitted = dir.join(format!("fit-{}.toml", mode.unwrap_or("default")));
        let mut args = vec![
            "fit",
            s(&fabric),
            "-o",
            s(&fitted),
            "--mesh-ladder",
            "8x12",
            "--max-degree",
            "1",
            "--protocol",
            "paper",
            "--quiet",
            // data made on this mesh (see noise_free_degree2_data_are_fitted_back)
            "--test-meshes",
            "ladder",
        ];
        if let Some(m) = mode {
            args.extend(["--bending", m]);
        }
        let (rc, out, err) = ks_fit(&args);
        assert!(rc == 0 || rc == 3, "{out}{err}");
        let doc: toml::Table = std::fs::read_to_string(&fitted).unwrap().parse().unwrap();
        let drapes: Vec<f64> = doc["fit"]["test"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|t| t["kind"].as_str() == Some("bend"))
            .map(|t| t["drape_angle_deg"].as_float().unwrap())
            .collect();
        assert_eq!(drapes.len(), 2);
        if mode.is_none() {
            // standard errors: the yarn stiffness from its curve, the rigidities exactly
            // determined (two bends, two rigidities), the twist assumed
            let u = doc["fit"]["uncertainty"]
                .as_table()
                .expect("[fit.uncertainty]");
            assert_eq!(u["a11_pa"]["determined"].as_bool(), Some(true));
            assert!(u["a11_pa"]["std_error"].as_float().unwrap() > 0.0);
            assert_eq!(u["bending_warp_n_m"]["basis"].as_str(), Some("none"));
            assert_eq!(u["bending_twist_n_m"]["determined"].as_bool(), Some(false));
        }
        (kshell::material::load_material(&fitted).unwrap(), drapes)
    };
    let (own, drapes) = run(None);
    let b = own.bending.expect("the default writes a [bending] table");
    for (got, want, what) in [(b.warp, 3.0e-5, "warp"), (b.weft, 6.0e-5, "weft")] {
        assert!((got / want - 1.0).abs() < 0.03, "{what} rigidity {got:e}");
    }
    for a in &drapes {
        assert!((a - 41.5).abs() < 0.2, "drape {a}° ({drapes:?})");
    }
    let (paper, drapes) = run(Some("paper"));
    assert!(paper.bending.is_none());
    let worst = drapes.iter().map(|a| (a - 41.5).abs()).fold(0.0, f64::max);
    assert!(worst > 3.0, "one thickness drapes both at {drapes:?}");
}

#[test]
fn datasets_without_warp_or_weft_are_refused() {
    let dir = folder("fit-bias-only");
    std::fs::write(
        dir.join("fabric.toml"),
        "name = \"x\"\nthickness_mm = 0.2\n[[tensile]]\nangle_deg = 45\nwidth_mm = 50\n\
         gauge_length_mm = 75\ncurve = \"bias.csv\"\n",
    )
    .unwrap();
    std::fs::write(dir.join("bias.csv"), "elongation_mm,force_n\n1,2\n2,5\n").unwrap();
    let (rc, out, err) = ks_fit(&[
        "fit",
        s(&dir.join("fabric.toml")),
        "-o",
        s(&dir.join("o.toml")),
    ]);
    assert_eq!(rc, 2, "{out}{err}");
    assert!(
        err.contains(
            "no fitted warp (90°) or weft (0°) tensile test and no [known] a11_pa or a22_pa"
        ),
        "{err}"
    );
    let (rc, _, err) = ks_fit(&["fit", s(&dir.join("missing.toml"))]);
    assert_eq!(rc, 2);
    assert!(err.contains("missing.toml"), "{err}");
}

/// Strips and bends of a stage are solved concurrently; the result must not depend on how many
/// threads there are: the fitted material, every error and every count, bit for bit.
#[test]
fn the_fit_is_the_same_on_one_thread_and_on_several() {
    let dir = folder("fit-threads");
    let data = synth_degree2(&dir, "5");
    let run = |threads: &str| {
        let fitted = dir.join(format!("fit-{threads}.toml"));
        let (rc, out, err) = crate::common::ks_fit_env(
            &[
                "fit",
                s(&data.join("fabric.toml")),
                "-o",
                s(&fitted),
                "--mesh-ladder",
                "8x12",
                "--max-degree",
                "1",
                "--protocol",
                "paper",
                "--quiet",
            ],
            &[("RAYON_NUM_THREADS", threads)],
        );
        assert_eq!(rc, 0, "{out}{err}");
        // everything but the clock
        std::fs::read_to_string(&fitted)
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with("wall_seconds") && !l.starts_with('"'))
            .collect::<Vec<_>>()
            .join("\n")
    };
    let (one, several) = (run("1"), run("3"));
    assert!(one.contains("a11_pa") && one.contains("[[fit.test]]"));
    assert_eq!(one, several);
}

/// The mesh check: fitted on 4 × 6, the check's
/// first-order refit on 8 × 12 (`--mesh-check fine`) must predict what refitting on 8 × 12
/// actually gives, and the default check (solved on the coarser mesh, carried to the finer one
/// at order 1.5) must agree with the measured one. Measured when written: G12 +28.6 %
/// predicted against +28.7 % refitted, a11 −0.38 against −0.39 %, a22 −0.10 against −0.20 %,
/// thickness +0.63 against +0.64 % (uniform cages; the numbers on the default graded cages
/// are in the README).
#[test]
fn the_mesh_check_predicts_the_refit_on_the_finer_mesh() {
    let dir = folder("fit-mesh-check");
    let data = synth_degree2(&dir, "6");
    let fabric = data.join("fabric.toml");
    let fit = |ladder: &str, out: &str, check: &str| -> toml::Table {
        let fitted = dir.join(out);
        let mut args = vec![
            "fit",
            s(&fabric),
            "-o",
            s(&fitted),
            "--mesh-ladder",
            ladder,
            "--degree",
            "1",
            "--protocol",
            "paper",
            "--bending",
            "paper",
            // uniform cages: the slow convergence this check was built to catch
            "--grading",
            "0",
            // every strip on the ladder's level: the check of one level against the next
            "--test-meshes",
            "ladder",
        ];
        args.extend(["--mesh-check", check]);
        let (rc, out, err) = ks_fit(&args);
        assert!(rc == 0 || rc == 3, "{out}{err}");
        std::fs::read_to_string(&fitted).unwrap().parse().unwrap()
    };
    let coarse = fit("4x6", "coarse.toml", "fine");
    let fine = fit("8x12", "fine.toml", "fine");
    let estimated = fit("8x12", "estimated.toml", "coarse");
    let off = fit("4x6", "off.toml", "off");
    assert!(off["fit"].as_table().unwrap().get("mesh_change").is_none());
    let f = coarse["fit"].as_table().unwrap();
    assert_eq!(f["mesh_check_mesh"].as_str(), Some("8x12"));
    assert_eq!(f["mesh_check_solved_on"].as_str(), Some("8x12"));
    let predicted = f["mesh_check"].as_table().expect("[fit.mesh_check]");
    let value = |t: &toml::Table, k: &str| t[k].as_float().unwrap();
    // the default check on 8 × 12 solves on 4 × 6 and speaks of 16 × 24, as the measured one
    let (e, m) = (
        estimated["fit"].as_table().unwrap(),
        fine["fit"].as_table().unwrap(),
    );
    assert_eq!(e["mesh_check_solved_on"].as_str(), Some("4x6"));
    assert_eq!(e["mesh_check_mesh"].as_str(), Some("16x24"));
    let (eg, mg) = (
        value(e["mesh_check"].as_table().unwrap(), "g12_pa"),
        value(m["mesh_check"].as_table().unwrap(), "g12_pa"),
    );
    // the estimate assumes the slowest order measured on uniform strips (1.2, the 45° strip's
    // clamped corners), so it must not fall short of the measured change; the strips here
    // converge at 1.3–1.9, for which it is at most 2^(1.9−1.2) = 1.6 times the change
    assert!(
        mg > 0.01 && eg >= 0.9 * mg && eg <= 2.0 * mg,
        "G12 change estimated {eg:+.4}, measured {mg:+.4}"
    );
    let mut largest: f64 = 0.0;
    for key in ["a11_pa", "a22_pa", "g12_pa", "thickness_mm"] {
        let actual = value(&fine, key) / value(&coarse, key) - 1.0;
        let p = value(predicted, key);
        largest = largest.max(p.abs());
        assert!(
            (p - actual).abs() <= 0.1 * actual.abs() + 2e-3,
            "{key}: predicted {p:+.4}, refitted {actual:+.4}"
        );
    }
    // the 45° strip is far from converged on 4 × 6: the check says so
    let change = value(f, "mesh_change");
    assert!(change >= largest - 1e-12 && change > 0.1, "{change}");
    let notes = notes_of(f);
    assert!(
        notes
            .iter()
            .any(|n| n.starts_with("warning: mesh check") && n.contains("not mesh-independent")),
        "{notes:?}"
    );
}

/// The ladder: the next level is solved at the last
/// fit first; it is skipped, with every later one, when refitting on it would change no
/// determined parameter by 1 % and no curve by 0.3 %, and that measured check is the one the
/// fit reports. Where it is needed, a stage the refinement left unchanged is not refitted.
#[test]
fn the_ladder_refines_only_what_the_refit_check_says_changes() {
    let dir = folder("fit-ladder");
    let data = synth_degree2(&dir, "5");
    // warp and weft strips alone: uniaxial strips converge fast, 4 × 6 already suffices
    let yarns = data.join("yarns.toml");
    let text = std::fs::read_to_string(data.join("fabric.toml")).unwrap();
    let keep: Vec<&str> = text
        .split("\n[[")
        .filter(|b| {
            let off_axis = ["= 45", "= 22.5", "= 67.5"].iter().any(|a| b.contains(a));
            let dropped = b.starts_with("bend") || (b.starts_with("tensile") && off_axis);
            !dropped
        })
        .collect();
    std::fs::write(&yarns, keep.join("\n[[")).unwrap();
    let fit = |fabric: &std::path::Path, ladder: &str, out: &str| {
        let fitted = dir.join(out);
        let (rc, o, err) = ks_fit(&[
            "fit",
            s(fabric),
            "-o",
            s(&fitted),
            "--mesh-ladder",
            ladder,
            "--degree",
            "1",
            "--protocol",
            "paper",
            "--bending",
            "paper",
            // the ladder alone: no strip refined on its own afterwards
            "--test-meshes",
            "ladder",
        ]);
        assert!(rc == 0 || rc == 3, "{o}{err}");
        let doc: toml::Table = std::fs::read_to_string(&fitted).unwrap().parse().unwrap();
        (doc["fit"].as_table().unwrap().clone(), err)
    };
    let (f, err) = fit(&yarns, "4x6,8x12,16x24", "yarns.toml");
    let meshes: Vec<&str> = f["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|v| v.as_str())
        .collect();
    assert_eq!(meshes, ["4x6"], "{err}");
    assert!(
        err.contains("meshes from 8×12 on skipped: refitting"),
        "{err}"
    );
    // the reported check is the ladder's measured one, on 8 × 12
    assert_eq!(f["mesh_check_solved_on"].as_str(), Some("8x12"));
    assert_eq!(f["mesh_check_mesh"].as_str(), Some("8x12"));
    assert!(f["mesh_change"].as_float().unwrap() < 0.01);
    // with the bias strip the shear needs 16 × 24 (its G12 moves by 4 %); the yarns' stages
    // are not refitted there (they move by under 0.02 %; from 4 × 6 they still moved 0.2 %)
    let (f, err) = fit(&data.join("fabric.toml"), "8x12,16x24", "all.toml");
    assert_eq!(f["meshes"].as_array().unwrap().len(), 2, "{err}");
    assert!(err.contains("warp stage not refitted on 16×24"), "{err}");
    assert!(err.contains("weft stage not refitted on 16×24"), "{err}");
    assert!(
        err.contains("bias stage (45°, 1 curves), degree 1, mesh 16×24"),
        "{err}"
    );
}

/// Each test's mesh is its own, on data the fit did not make from a material it does not
/// start near: stiff
/// yarns over a soft shear (a11/G12 = 1000, 10 and 50 times the fit's start), the dataset's
/// measured thickness twice the true one, noise-free strips made on graded 32 × 48 cages, fitted
/// from a 4 × 6 ladder, all on the full yarn rule (the paper's integration, which locks here;
/// the default `auto` rule would put these yarns on the face centres). On the ladder's mesh
/// alone the locked 45° strip drives G12 to about 1 % of the truth (measured: 9.2e3 Pa); with
/// each strip refined until its estimate meets its tolerance or its budget (the 45° strip to
/// 32 × 48, where its estimate, 2.5 %, is still warned about), a11·τ, a22·τ, G12 and the
/// thickness come back within 1 % (measured: 0.2 %).
#[test]
fn each_test_is_refined_on_its_own_mesh_until_its_error_estimate_passes() {
    let dir = folder("fit-own-meshes");
    let truth = TestLaw::stvk(1.0e9, 3.0e8, 1.5e8, 1.0e6)
        .named("stiff-yarns")
        .density(0.25)
        .thickness(3.0e-4)
        .toml();
    let data = synth_with(&dir, &truth, "5", "32x48", &["--yarn-rule", "full"]);
    let fabric = data.join("fabric.toml");
    let text = std::fs::read_to_string(&fabric).unwrap();
    assert!(text.contains("thickness_mm = 0.3\n"), "{text}");
    std::fs::write(
        &fabric,
        text.replace("thickness_mm = 0.3\n", "thickness_mm = 0.6\n"),
    )
    .unwrap();
    let fit_with = |meshes: &str, nodes: &str| {
        let fitted = dir.join(format!("{meshes}-{nodes}.toml"));
        let (rc, out, err) = ks_fit(&[
            "fit",
            s(&fabric),
            "-o",
            s(&fitted),
            "--mesh-ladder",
            "4x6",
            "--degree",
            "1",
            "--protocol",
            "paper",
            "--bending",
            "paper",
            "--max-misalign",
            "0",
            "--test-meshes",
            meshes,
            "--yarn-rule",
            "full",
            "--nodes",
            nodes,
        ]);
        assert!(rc == 0 || rc == 3, "{out}{err}");
        let doc: toml::Table = std::fs::read_to_string(&fitted).unwrap().parse().unwrap();
        (doc, out)
    };
    // five points a curve: with 12 nodes every strip is solved at its points
    let fit = |meshes: &str| fit_with(meshes, "12");
    let value = |t: &toml::Table, k: &str| t[k].as_float().unwrap();
    let (ladder, _) = fit("ladder");
    let g12 = value(&ladder, "g12_pa") / 1.0e6 - 1.0;
    assert!(
        g12 < -0.5,
        "on 4 × 6 alone G12 is {:+.2} % off",
        100.0 * g12
    );
    let (own, out) = fit("own");
    assert!(
        out.contains("some tests refined on meshes of their own"),
        "{out}"
    );
    let tau = value(&own, "thickness_mm") / 0.3;
    for (name, rel) in [
        ("g12_pa", value(&own, "g12_pa") / 1.0e6),
        ("a11·τ", value(&own, "a11_pa") / 1.0e9 * tau),
        ("a22·τ", value(&own, "a22_pa") / 3.0e8 * tau),
        ("thickness", tau),
    ] {
        assert!(
            (rel - 1.0).abs() < 0.01,
            "{name}: {:+.3} %",
            100.0 * (rel - 1.0)
        );
    }
    // every fitted strip meets its tolerance on its own mesh, which [[fit.test]] names, or is
    // warned about by name
    let f = own["fit"].as_table().unwrap();
    assert_eq!(f["yarn_rule"].as_str(), Some("full"), "{f:?}");
    let notes = notes_of(f);
    assert!(
        notes.iter().any(|n| n.contains("nothing interpolated")),
        "{notes:?}"
    );
    for t in f["test"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_table().unwrap())
    {
        if t["kind"].as_str() != Some("tensile") {
            continue;
        }
        let (err, est) = (value(t, "avg_rel_error"), value(t, "mesh_error_est"));
        let curve = t["curve"].as_str().unwrap();
        let warned = notes
            .iter()
            .any(|n| n.starts_with("warning:") && n.contains(curve) && n.contains("mesh error"));
        assert!(est <= (err / 3.0).max(3e-3) || warned, "{t:?}");
        if t["angle_deg"].as_float() == Some(45.0) {
            assert_eq!(t["mesh"].as_str(), Some("32x48"), "{t:?}");
        }
    }
    // with fewer nodes than points the curves are interpolated, and the interpolation check
    // solves between the nodes on the mesh the nodes were solved on (it compared the refined
    // 45° strip with the ladder's 4 × 6 one, and reported their difference, tens of per cent
    // here, as interpolation error)
    let (four, _) = fit_with("own", "4");
    let interp: f64 = four["fit"]["notes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|n| n.as_str())
        .find_map(|n| n.split("largest interpolation error ").nth(1))
        .and_then(|r| r.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no interpolation note: {:?}", four["fit"]["notes"]));
    assert!(interp < 1.0, "interpolation error {interp} %");
}

/// `--degree 2` gives every η degree 2, the shear included. The shear's raise used to be
/// given up where its space-mapped start found no better law, which on the bundled cotton's
/// noisy repeats left a degree-1 shear under `--degree 2` (`[fit] degrees` said so; measured
/// before the fix with this very command).
#[test]
fn a_fixed_degree_is_fitted_whatever_its_start_finds() {
    let dir = folder("fixed_degree");
    let fitted = dir.join("fitted.toml");
    let (rc, out, err) = ks_fit(&[
        "fit",
        "paper_repro/fabrics/cotton/fabric.toml",
        "-o",
        s(&fitted),
        "--degree",
        "2",
        "--mesh-ladder",
        "8x12",
        "--test-meshes",
        "ladder",
    ]);
    assert!(rc == 0 || rc == 3, "{out}{err}");
    let doc: toml::Table = std::fs::read_to_string(&fitted).unwrap().parse().unwrap();
    let degrees = doc["fit"]["degrees"].as_table().unwrap();
    assert_eq!(degrees["shear"].as_integer(), Some(2), "{degrees:?}\n{err}");
    let law: toml::Table = doc["shear"].as_table().unwrap().clone();
    assert_eq!(law["mu"].as_array().unwrap().len(), 2, "{law:?}");
}

/// The default per-test meshes (`--test-meshes strict`) refine the strip of a fitted curve
/// that the mesh check moves by 0.3 % or more, and the check then passes. On the bundled denim
/// `own` leaves its 67.5° and 45° curves moving by 0.40 % and warns (measured,
/// `paper_repro/fit_speed/strict.md`); strict refines both strips to 32 × 48 and the curves
/// move by 0.19 %.
#[test]
fn default_test_meshes_refine_the_strips_whose_curves_the_mesh_check_moves() {
    let dir = folder("fit-strict-meshes");
    let fitted = dir.join("denim-strict.toml");
    let fabric = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/paper_repro/fabrics/denim/fabric.toml"
    );
    let (rc, out, err) = ks_fit(&["fit", fabric, "-o", s(&fitted)]);
    assert!(rc == 0 || rc == 3, "{out}{err}");
    let doc: toml::Table = std::fs::read_to_string(&fitted).unwrap().parse().unwrap();
    let f = doc["fit"].as_table().unwrap();
    assert_eq!(f["test_meshes"].as_str(), Some("strict"), "{f:?}");
    let notes = notes_of(f);
    assert!(
        notes
            .iter()
            .any(|n| n.contains("the mesh check moves its curve")),
        "{notes:?}"
    );
    let curves = f["mesh_change_curves"].as_float().unwrap();
    assert!(curves < 3e-3, "curves move by {:.3} %", 100.0 * curves);
    assert!(
        !notes.iter().any(|n| n.starts_with("warning: mesh check")),
        "{notes:?}"
    );
}
