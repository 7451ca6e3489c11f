//! End-to-end tests of the `ks-fit` command line: outputs users and scripts rely on, and errors
//! that name the file and line and exit with code 2.

use crate::common::{first_value, ks_fit, TestLaw};

fn temp_file(name: &str, text: &str) -> String {
    let dir = std::env::temp_dir().join(format!("kshell-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

#[test]
fn mesh_summary_of_the_shipped_samples() {
    let (rc, out, _) = ks_fit(&["mesh", "meshes/cube.obj"]);
    assert_eq!(rc, 0);
    for line in [
        "vertices: 8",
        "faces: 6",
        "boundary edges: 0",
        "faces by kind: regular 0, boundary 0, extraordinary 6",
        "valences present: interior 3 (8); boundary none",
    ] {
        assert!(out.contains(line), "missing {line:?} in\n{out}");
    }
    let (rc, out, _) = ks_fit(&["mesh", "meshes/strip_8x12.obj"]);
    assert_eq!(rc, 0);
    assert!(
        out.contains("faces by kind: regular 60, boundary 36, extraordinary 0"),
        "{out}"
    );
    assert!(out.contains("boundary edges: 40"), "{out}");
    let (rc, out, _) = ks_fit(&["mesh", "meshes/fan4_boundary.obj"]);
    assert_eq!(rc, 0);
    assert!(out.contains("boundary 2 (6), 3 (23), 5 (1)"), "{out}");
}

#[test]
fn limit_prints_one_csv_row_with_the_documented_header() {
    let (rc, out, err) = ks_fit(&[
        "mesh",
        "meshes/strip_8x12.obj",
        "--limit",
        "9",
        "0.5",
        "0.25",
    ]);
    assert_eq!(rc, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(
        lines[0],
        "x,y,z,xu,yu,zu,xv,yv,zv,xuu,yuu,zuu,xuv,yuv,zuv,xvv,yvv,zvv"
    );
    assert_eq!(lines.len(), 2);
    let v: Vec<f64> = lines[1].split(',').map(|x| x.parse().unwrap()).collect();
    assert_eq!(v.len(), 18);
    // face 9 of the 8 × 12 strip is face (1, 1): x = (1 + u)·6.25 mm, y = (1 + v)·6.25 mm
    let expect = [
        0.009375, 0.0078125, 0.0, 0.00625, 0.0, 0.0, 0.0, 0.00625, 0.0,
    ];
    for (a, b) in v.iter().zip(expect) {
        assert!((a - b).abs() < 1e-15, "{v:?}");
    }
    assert!(v[9..].iter().all(|x| x.abs() < 1e-14));
}

#[test]
fn triangle_meshes_are_refined_once_with_a_note() {
    let (rc, out, _) = ks_fit(&["mesh", "meshes/tetra.obj"]);
    assert_eq!(rc, 0);
    assert!(out.contains("one Catmull–Clark step"), "{out}");
    assert!(out.contains("faces: 12"), "{out}");
}

#[test]
fn bad_input_is_one_line_naming_file_and_line_with_exit_code_2() {
    let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
    let cases = [
        (
            temp_file("badnum.obj", "v 0 0 0\nv 1 zero 0\n"),
            ":2: bad vertex coordinate 'zero'",
        ),
        (
            temp_file("range.obj", &format!("{quad}f 1 2 3 5\n")),
            ":5: vertex index 5 out of range",
        ),
        (
            temp_file(
                "nonmanifold.obj",
                &format!("{quad}v 0 0 1\nv 0 0 -1\nf 1 2 3 4\nf 2 1 5\nf 1 2 6\n"),
            ),
            ":9: non-manifold edge",
        ),
        (temp_file("empty.obj", ""), ": empty mesh"),
        (
            "does/not/exist.obj".to_string(),
            "does/not/exist.obj: cannot read file",
        ),
    ];
    for (path, want) in cases {
        let (rc, out, err) = ks_fit(&["mesh", &path]);
        assert_eq!(rc, 2, "{path}: {err}");
        assert!(out.is_empty());
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.contains(&path) && err.contains(want),
            "{err:?} should name {path} and say {want:?}"
        );
        assert!(!err.contains("panicked"));
    }
    for args in [
        ["mesh", "meshes/cube.obj", "--limit", "6", "0.5", "0.5"],
        ["mesh", "meshes/cube.obj", "--limit", "0", "1.5", "0.5"],
        ["mesh", "meshes/cube.obj", "--limit", "0", "nan", "0.5"],
        ["mesh", "meshes/cube.obj", "--limit", "0", "0", "0"],
        ["mesh", "meshes/cube.obj", "--limit", "x", "0", "0"],
    ] {
        let (rc, _, err) = ks_fit(&args);
        assert_eq!(rc, 2, "{args:?}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.starts_with("ks-fit: error:"), "{err}");
    }
}

#[test]
fn shipped_meshes_match_their_generators() {
    // `cargo run --example sample_meshes` writes them; this catches drift either way.
    use kshell::mesh::{read_obj, shapes};
    let cube = read_obj("meshes/cube.obj".as_ref()).unwrap();
    assert_eq!(cube.mesh, shapes::cube());
    let star = read_obj("meshes/star5.obj".as_ref()).unwrap();
    assert_eq!(star.mesh, shapes::star(5, 3));
    let l = read_obj("meshes/l_shape.obj".as_ref()).unwrap();
    assert_eq!(l.mesh, shapes::l_shape(3));
}

#[test]
fn demo_runs_and_checks_the_strip_area() {
    let (rc, out, err) = ks_fit(&["demo"]);
    assert_eq!(rc, 0, "{err}");
    assert!(out.contains("strip 50x75 mm"), "{out}");
    assert!(out.contains("relative error"), "{out}");
}

fn material_file(name: &str, extra: &str) -> String {
    temp_file(
        name,
        &(TestLaw::stvk(1e8, 6e7, 0.0, 2e6).named("t").toml() + extra),
    )
}

#[test]
fn tensile_prints_the_documented_csv() {
    let m = material_file("tensile.toml", "");
    let (rc, out, err) = ks_fit(&[
        "tensile",
        "--material",
        &m,
        "--angle",
        "90",
        "--width",
        "50",
        "--length",
        "75",
        "--to",
        "3",
        "--steps",
        "3",
        "--mesh",
        "4x6",
    ]);
    assert_eq!(rc, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], "elongation_mm,force_n");
    assert_eq!(lines.len(), 4);
    // a12 = 0, warp along the axis: F = a11 τ W λ(λ² − 1)/2
    for (i, line) in lines[1..].iter().enumerate() {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        assert!((v[0] - (i + 1) as f64).abs() < 1e-12);
        let lam = 1.0 + v[0] / 75.0;
        let exact = 1e8 * 2e-4 * 0.05 * lam * (lam * lam - 1.0) / 2.0;
        assert!((v[1] / exact - 1.0).abs() < 1e-6, "{line}");
    }
}

#[test]
fn bend_prints_one_row() {
    let m = material_file("bend.toml", "");
    let (rc, out, err) = ks_fit(&[
        "bend",
        "--material",
        &m,
        "--angle",
        "90",
        "--overhang",
        "40",
    ]);
    assert_eq!(rc, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], "overhang_mm,drape_angle_deg");
    let v: Vec<f64> = lines[1].split(',').map(|x| x.parse().unwrap()).collect();
    assert_eq!(v[0], 40.0);
    assert!(v[1] > 0.0 && v[1] < 90.0, "{out}");
    // the cantilever's default boundary treatment is the ghost clamp (README: measured)
    let (_, ghost, _) = ks_fit(&[
        "bend",
        "--material",
        &m,
        "--angle",
        "90",
        "--overhang",
        "40",
        "--boundary",
        "ghost",
    ]);
    assert_eq!(out, ghost);
}

#[test]
fn scene_commands_reject_bad_input_with_exit_code_2() {
    let good = material_file("good.toml", "");
    let unknown = material_file("unknown.toml", "colour = \"red\"\n");
    let base = [
        "--angle", "0", "--width", "50", "--length", "75", "--to", "3", "--steps", "2",
    ];
    let run = |extra: &[&str], mat: &str| {
        let mut args = vec!["tensile", "--material", mat];
        args.extend_from_slice(&base);
        args.extend_from_slice(extra);
        ks_fit(&args)
    };
    let (rc, _, err) = run(&[], &unknown);
    assert_eq!(rc, 2);
    assert!(
        err.contains("unknown.toml:8: unknown field `colour`"),
        "{err}"
    );
    let (rc, _, err) = run(&[], "no/such/material.toml");
    assert_eq!(rc, 2);
    assert!(
        err.contains("no/such/material.toml: cannot read file"),
        "{err}"
    );
    let (rc, _, err) = run(&["--mesh", "8by12"], &good);
    assert_eq!(rc, 2);
    assert!(err.contains("mesh must look like 8x12"), "{err}");
    let (rc, _, err) = run(&["--width", "-5"], &good);
    assert_eq!(rc, 2, "{err}");
    let (rc, _, err) = run(&["--steps", "0"], &good);
    assert_eq!(rc, 2, "{err}");
    assert!(!err.contains("panicked"));
    let (rc, _, err) = ks_fit(&[
        "bend",
        "--material",
        &good,
        "--angle",
        "0",
        "--overhang",
        "0",
    ]);
    assert_eq!(rc, 2);
    assert!(err.contains("--overhang must be a positive"), "{err}");
}

#[test]
fn converge_prints_a_table_and_writes_csv_and_svg() {
    let m = temp_file(
        "converge.toml",
        &TestLaw::stvk(1e8, 6e7, 3e7, 2e6).named("t").toml(),
    );
    let dir = std::env::temp_dir().join(format!("kshell-conv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (csv, svg) = (dir.join("c.csv"), dir.join("c.svg"));
    let (rc, out, err) = ks_fit(&[
        "converge",
        "tensile",
        "--material",
        &m,
        "--angle",
        "90",
        "--width",
        "50",
        "--length",
        "75",
        "--elongation",
        "3",
        "--mesh-ladder",
        "2x3,4x6,8x12",
        "--tol",
        "0.5",
        "--csv",
        csv.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(rc, 0, "{err}");
    let header = out.lines().next().unwrap();
    for col in ["mesh", "dofs", "seconds", "qoi", "est_error", "order"] {
        assert!(header.split_whitespace().any(|c| c == col), "{header}");
    }
    assert!(
        out.contains("coarsest mesh with estimated error below"),
        "{out}"
    );
    assert!(std::fs::read_to_string(&csv)
        .unwrap()
        .starts_with("mesh,nx,ny,dofs,seconds,qoi"));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    assert!(err.contains("8x12 done"), "progress on stderr: {err}");
    let (rc, _, err) = ks_fit(&[
        "converge",
        "bend",
        "--material",
        &m,
        "--angle",
        "0",
        "--overhang",
        "40",
        "--mesh-ladder",
        "4xx",
    ]);
    assert_eq!(rc, 2);
    assert!(err.contains("--mesh-ladder"), "{err}");
}

/// Tiny elongations of off-axis strips: Newton stalls at the round-off floor of the strains
/// (8.6e-9 relative here) and must say so, not fail; and a curve of 200 rows can be made.
#[test]
fn tensile_at_tiny_elongations_ends_at_the_round_off_floor() {
    // the case: the example cotton, on what was then the default mesh
    let m = "examples/materials/cotton.toml".to_string();
    let (rc, out, err) = ks_fit(&[
        "tensile",
        "--material",
        &m,
        "--angle",
        "15",
        "--width",
        "50",
        "--length",
        "75",
        "--to",
        "0.02",
        "--steps",
        "1",
        "--mesh",
        "8x12",
        "-v",
    ]);
    assert_eq!(rc, 0, "{out}{err}");
    let force: f64 = first_value(&out);
    assert!(force > 0.0, "{out}");
    let (rc, out, err) = ks_fit(&[
        "tensile",
        "--material",
        &m,
        "--angle",
        "15",
        "--width",
        "50",
        "--length",
        "75",
        "--to",
        "2",
        "--steps",
        "200",
        "--mesh",
        "4x6",
    ]);
    assert_eq!(rc, 0, "{err}");
    assert_eq!(out.lines().count(), 201);
}

/// a12 may be negative (a negative Poisson coupling): the only bound is a12² < a11·a22.
#[test]
fn negative_a12_is_a_legal_material() {
    let law = TestLaw::stvk(1e8, 6e7, -2e7, 2e6).named("t");
    let m = temp_file("negative-a12.toml", &law.toml());
    let (rc, out, err) = ks_fit(&[
        "tensile",
        "--material",
        &m,
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
        "--mesh",
        "4x6",
    ]);
    assert_eq!(rc, 0, "{out}{err}");
    // a12² = 6.4e15 > a11·a22 = 6e15
    let too_negative = TestLaw::stvk(1e8, 6e7, -8e7, 2e6).named("t");
    std::fs::write(&m, too_negative.toml()).unwrap();
    let (rc, _, err) = ks_fit(&[
        "tensile",
        "--material",
        &m,
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
        "--mesh",
        "4x6",
    ]);
    assert_eq!(rc, 2);
    assert!(err.contains("need a12² < a11·a22"), "{err}");
}

/// A large elongation step into a wrinkling bias strip: Newton from the predictor stagnated
/// (cotton at 45° on a graded 8 × 12 cage, 4 → 6 mm, relative residual stuck at 1); the step
/// is now cut into sub-steps, and the equilibrium is the one that small steps reach.
#[test]
fn a_large_step_into_a_wrinkling_strip_is_taken_in_sub_steps() {
    let material = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/paper_repro/fabrics/materials/cotton.toml"
    );
    let last_force = |steps: &str| -> f64 {
        let (rc, out, err) = ks_fit(&[
            "tensile",
            "--material",
            material,
            "--angle",
            "45",
            "--width",
            "50",
            "--length",
            "75",
            "--to",
            "6",
            "--steps",
            steps,
            "--mesh",
            "8x12",
            "--grading",
            "0.8,0.8",
        ]);
        assert_eq!(rc, 0, "{steps} steps: {err}");
        let last = out.lines().last().unwrap();
        last.split(',').nth(1).unwrap().parse().unwrap()
    };
    let (coarse, fine) = (last_force("3"), last_force("6"));
    assert!(
        (coarse / fine - 1.0).abs() < 1e-6,
        "{coarse} N against {fine} N"
    );
}
