//! Tests of the dataset reader and writer.

use super::*;

const TOML: &str = "name = \"poplin\"\nareal_density_g_m2 = 103.6\nthickness_mm = 0.18\n\n[[tensile]]\nangle_deg = 90\nwidth_mm = 50\ngauge_length_mm = 75\ncurve = \"warp-1.csv\"\n\n[[bend]]\nangle_deg = 90\nwidth_mm = 25\noverhang_mm = 61.0\ndrape_angle_deg = 41.5\n";
const CSV: &str = "elongation_mm,force_n\n0.75,20.5\n1.5,41.0\n3.0,80.0\n";

/// A fresh folder holding `fabric.toml` = `toml` and `warp-1.csv` = `csv`.
fn folder(tag: &str, toml: &str, csv: Option<&str>) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("kshell-dataset-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("fabric.toml"), toml).unwrap();
    if let Some(c) = csv {
        std::fs::write(dir.join("warp-1.csv"), c).unwrap();
    }
    dir
}

fn load(
    tag: &str,
    toml: &str,
    csv: Option<&str>,
) -> Result<(FabricDataset, Vec<DatasetWarning>), DatasetError> {
    load_dataset(&folder(tag, toml, csv).join("fabric.toml"))
}

#[test]
fn reads_a_good_dataset_in_si_units() {
    let (d, w) = load("good", TOML, Some(CSV)).unwrap();
    assert!(w.is_empty(), "{w:?}");
    assert_eq!(d.name, "poplin");
    assert!((d.areal_density.unwrap() - 0.1036).abs() < 1e-15);
    assert!((d.thickness - 1.8e-4).abs() < 1e-18);
    let t = &d.tensile[0];
    assert_eq!((t.angle_deg, t.width, t.gauge_length), (90.0, 0.05, 0.075));
    assert_eq!(t.curve, PathBuf::from("warp-1.csv"));
    assert_eq!(t.elongation, vec![0.75e-3, 1.5e-3, 3.0e-3]);
    assert_eq!(t.force, vec![20.5, 41.0, 80.0]);
    assert!(t.is_fitted());
    assert_eq!(d.bend[0].drape_angle_deg, 41.5);
    assert!((d.bend[0].overhang - 0.061).abs() < 1e-15);
    assert_eq!(d.tests_at(90.0).len(), 1);
    assert!(d.tests_at(0.0).is_empty());
}

#[test]
fn partial_datasets_and_tolerant_csv_are_legal() {
    // no bend, so no density needed; spaces, CRLF, a BOM, comments and blank lines
    let toml = TOML.replace("areal_density_g_m2 = 103.6\n", "").replace(
        "\n[[bend]]\nangle_deg = 90\nwidth_mm = 25\noverhang_mm = 61.0\ndrape_angle_deg = 41.5\n",
        "",
    );
    let csv = "\u{feff} elongation_mm , force_n \r\n# zero first\r\n\r\n0 , 0\r\n 1.5, 41\r\n";
    let (d, w) = load("partial", &toml, Some(csv)).unwrap();
    assert!(w.is_empty(), "{w:?}");
    assert_eq!(d.areal_density, None);
    assert!(d.bend.is_empty());
    assert_eq!(d.tensile[0].force, vec![0.0, 41.0]);
}

#[test]
fn written_datasets_read_back() {
    let (mut d, _) = load("write-src", TOML, Some(CSV)).unwrap();
    d.tensile.push(TensileTest {
        angle_deg: 22.5,
        curve: PathBuf::from("more/a22.5-1.csv"),
        ..d.tensile[0].clone()
    });
    d.name = "quote \" and \\ back".into();
    let dir = std::env::temp_dir().join(format!("kshell-dataset-{}-written", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    write_dataset_with_comment(&dir, &d, "synthetic\nsecond line").unwrap();
    let (back, w) = load_dataset(&dir.join("fabric.toml")).unwrap();
    assert!(w.is_empty(), "{w:?}");
    assert_eq!(back.name, d.name);
    assert_eq!(back.tensile.len(), 2);
    assert!(!back.tensile[1].is_fitted());
    for (a, b) in back.tensile.iter().zip(&d.tensile) {
        assert_eq!(a.curve, b.curve);
        assert_eq!(a.force, b.force);
        for (x, y) in a.elongation.iter().zip(&b.elongation) {
            assert!((x - y).abs() <= 1e-15 * y, "{x} {y}");
        }
    }
    assert!((back.bend[0].overhang - d.bend[0].overhang).abs() < 1e-15);
    let text = std::fs::read_to_string(dir.join("fabric.toml")).unwrap();
    assert!(text.starts_with("# synthetic\n# second line\n"), "{text}");
}

#[test]
fn toml_errors_name_file_line_and_key() {
    let cases = [
        (
            TOML.replace("thickness_mm = 0.18", "thickness_mm = = 0.18"),
            "fabric.toml:3: ",
        ),
        (
            format!("{TOML}colour = 3\n"),
            "fabric.toml:16: unknown field `colour`",
        ),
        (
            TOML.replace("gauge_length_mm = 75\n", ""),
            "fabric.toml:5: missing field `gauge_length_mm`",
        ),
        (
            TOML.replace("thickness_mm = 0.18\n", ""),
            "fabric.toml:1: missing field `thickness_mm`",
        ),
        (
            TOML.replace("thickness_mm = 0.18", "thickness_mm = 0"),
            "fabric.toml:3: thickness_mm must be a finite positive number, got 0",
        ),
        (
            TOML.replace("thickness_mm = 0.18", "thickness_mm = nan"),
            "fabric.toml:3: thickness_mm must be",
        ),
        (
            TOML.replace("areal_density_g_m2 = 103.6", "areal_density_g_m2 = -1"),
            "fabric.toml:2: areal_density_g_m2 must be",
        ),
        (
            TOML.replace("width_mm = 50", "width_mm = -50"),
            "fabric.toml:7: tensile test 1: width_mm must be a finite positive number, got -50",
        ),
        (
            TOML.replace("width_mm = 50", "width_mm = inf"),
            "fabric.toml:7: tensile test 1: width_mm must be",
        ),
        (
            TOML.replace("gauge_length_mm = 75", "gauge_length_mm = 0"),
            "fabric.toml:8: tensile test 1: gauge_length_mm must be",
        ),
        (
            TOML.replace("overhang_mm = 61.0", "overhang_mm = 0.0"),
            "fabric.toml:14: bend test 1: overhang_mm must be",
        ),
        (
            TOML.replace("width_mm = 25", "width_mm = 0"),
            "fabric.toml:13: bend test 1: width_mm must be",
        ),
        (
            TOML.replace(
                "angle_deg = 90\nwidth_mm = 50",
                "angle_deg = 180\nwidth_mm = 50",
            ),
            "fabric.toml:6: tensile test 1: angle_deg must be in [0, 180)",
        ),
        (
            TOML.replace(
                "angle_deg = 90\nwidth_mm = 25",
                "angle_deg = -10\nwidth_mm = 25",
            ),
            "fabric.toml:12: bend test 1: angle_deg must be in [0, 180)",
        ),
        (
            TOML.replace("drape_angle_deg = 41.5", "drape_angle_deg = 90"),
            "fabric.toml:15: bend test 1: drape_angle_deg must be in (0, 90), got 90",
        ),
        (
            TOML.replace("drape_angle_deg = 41.5", "drape_angle_deg = 0"),
            "fabric.toml:15: bend test 1: drape_angle_deg must be in (0, 90)",
        ),
        (
            TOML.replace("areal_density_g_m2 = 103.6\n", ""),
            "fabric.toml:10: bend test 1: a bend test needs areal_density_g_m2",
        ),
        (
            TOML.replace("warp-1.csv", "nowhere.csv"),
            "fabric.toml:9: tensile test 1: cannot read curve file",
        ),
        (
            TOML.replace("width_mm = 50", "width_mm = \"wide\""),
            "fabric.toml:7: invalid type",
        ),
    ];
    for (i, (toml, want)) in cases.iter().enumerate() {
        let got = load(&format!("toml{i}"), toml, Some(CSV)).unwrap_err();
        assert!(got.file.ends_with("fabric.toml"), "{got}");
        let shown = got.to_string();
        let tail = &shown[shown.rfind("fabric.toml").unwrap()..];
        assert!(
            tail.starts_with(want),
            "{tail:?} should start with {want:?}"
        );
        assert!(!shown.contains('\n'));
    }
}

#[test]
fn curve_errors_name_file_line_and_column() {
    let cases = [
        ("", "warp-1.csv:1: empty curve file"),
        (
            "elongation,force\n1,2\n",
            "warp-1.csv:1: the header must be `elongation_mm,force_n`",
        ),
        (
            "elongation_mm,force_n\n",
            "warp-1.csv:1: no data rows after the header",
        ),
        (
            "elongation_mm,force_n\n1,2\n2,3,4\n",
            "warp-1.csv:3: expected 2 columns",
        ),
        (
            "elongation_mm,force_n\n1,2\n2\n",
            "warp-1.csv:3: expected 2 columns",
        ),
        (
            "elongation_mm,force_n\n1,2\n2,\n",
            "warp-1.csv:3: column 2 (force_n) is empty",
        ),
        (
            "elongation_mm,force_n\n1,2\nx,3\n",
            "warp-1.csv:3: column 1 (elongation_mm): `x` is not a number",
        ),
        (
            "elongation_mm,force_n\n1,2\n2,inf\n",
            "warp-1.csv:3: column 2 (force_n) must be finite",
        ),
        (
            "elongation_mm,force_n\nNaN,2\n",
            "warp-1.csv:2: column 1 (elongation_mm) must be finite",
        ),
        (
            "elongation_mm,force_n\n1,-2\n",
            "warp-1.csv:2: column 2 (force_n) must not be negative",
        ),
        (
            "elongation_mm,force_n\n-1,2\n",
            "warp-1.csv:2: column 1 (elongation_mm) must not be negative",
        ),
        (
            "elongation_mm,force_n\n2,2\n1,3\n",
            "warp-1.csv:3: column 1 (elongation_mm) = 1 is below the previous row's 2",
        ),
        (
            "\"Extension\",\"Load (N)\"\n1,2\n",
            "warp-1.csv:1: the header must be `elongation_mm,force_n` or name an elongation and a force column with units, e.g. `\"Extension (mm)\",\"Load (N)\"`: column `Extension` has no unit",
        ),
        (
            "Extension (furlong),Load (N)\n1,2\n",
            "warp-1.csv:1: the header must be `elongation_mm,force_n` or name an elongation and a force column with units, e.g. `\"Extension (mm)\",\"Load (N)\"`: column `Extension (furlong)`: unknown length",
        ),
        (
            "elongation_mm,force_n\n1,2\n2,-0.5\n3,4\n",
            "warp-1.csv:3: column 2 (force_n) must not be negative, got -0.5",
        ),
    ];
    for (i, (csv, want)) in cases.iter().enumerate() {
        let got = load(&format!("csv{i}"), TOML, Some(csv)).unwrap_err();
        assert!(got.file.ends_with("warp-1.csv"), "{got}");
        let shown = got.to_string();
        let tail = &shown[shown.rfind("warp-1.csv").unwrap()..];
        assert!(
            tail.starts_with(want),
            "{tail:?} should start with {want:?}"
        );
    }
}

#[test]
fn machine_exports_are_read_with_their_units() {
    // metadata lines, quoted headers with units and other columns, then the data
    let instron = "Test name: warp 1\nDate,2026-11-30\nLoad cell,extensometer\n\"Time (s)\",\"Extension (mm)\",\"Load (kN)\"\n0.0,0.0,0.0\n1.0,0.75,0.0205\n2.0,1.5,0.041\n";
    let (d, w) = load("instron", TOML, Some(instron)).unwrap();
    let t = &d.tensile[0];
    assert_eq!(t.elongation, vec![0.0, 0.75e-3, 1.5e-3]);
    assert!((t.force[1] - 20.5).abs() < 1e-12 && (t.force[2] - 41.0).abs() < 1e-12);
    assert!(w.is_empty(), "{w:?}");
    assert!(
        d.notes
            .iter()
            .any(|n| n.contains("`Extension (mm)`, `Load (kN)`")),
        "{:?}",
        d.notes
    );
    // semicolons with decimal commas, inches and pound-force
    let euro = "Extension [in];Kraft;Load [lbf]\n0,1;9;2,5\n0,2;9;5\n";
    let (d, _) = load("euro", TOML, Some(euro)).unwrap();
    let t = &d.tensile[0];
    assert!((t.elongation[0] - 2.54e-3).abs() < 1e-15);
    assert!((t.force[1] - 5.0 * 4.448_221_615_260_5).abs() < 1e-12);
    // a header we do not recognise, named by `columns`
    let odd = "Weg (mm),F (N)\n1,20\n2,40\n";
    let toml = TOML.replace(
        "curve = \"warp-1.csv\"",
        "curve = \"warp-1.csv\"\ncolumns = [\"Weg (mm)\", \"F (N)\"]",
    );
    let (d, _) = load("columns", &toml, Some(odd)).unwrap();
    assert_eq!(d.tensile[0].force, vec![20.0, 40.0]);
    assert!(load("no-columns", TOML, Some(odd)).is_err());
    // an extensometer's resolution: repeated elongations are averaged, with a note
    let dup = "elongation_mm,force_n\n0.01,1\n0.01,2\n0.01,6\n0.02,8\n";
    let (d, _) = load("dup", TOML, Some(dup)).unwrap();
    assert_eq!(d.tensile[0].force, vec![3.0, 8.0]);
    assert!(
        d.notes.iter().any(|n| n.contains("2 rows repeated")),
        "{:?}",
        d.notes
    );
}

#[test]
fn roles_scales_toes_and_known_values() {
    let toml = TOML.replace(
        "curve = \"warp-1.csv\"",
        "curve = \"warp-1.csv\"\nrole = \"validation\"\nforce_scale = 0.5\ntoe_mm = -0.2",
    ) + "\n[known]\na11_pa = 2e8\na12_pa = -1e7\nthickness_mm = 0.2\n";
    let (d, _) = load("roles", &toml, Some(CSV)).unwrap();
    let t = &d.tensile[0];
    assert_eq!(t.role, Some(Role::Validation));
    assert_eq!(t.role(false), Role::Validation);
    assert_eq!(t.force, vec![10.25, 20.5, 40.0]);
    assert_eq!(t.toe, Some(-0.2e-3));
    assert_eq!(d.known.a11, Some(2e8));
    assert_eq!(d.known.a12, Some(-1e7));
    assert!((d.known.thickness.unwrap() - 2e-4).abs() < 1e-18);
    // written and read back
    let dir = std::env::temp_dir().join(format!("kshell-dataset-{}-roles-w", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    write_dataset(&dir, &d).unwrap();
    let (back, _) = load_dataset(&dir.join("fabric.toml")).unwrap();
    assert_eq!(back.tensile[0].force, d.tensile[0].force);
    assert_eq!(back.known, d.known);
    assert_eq!(back.tensile[0].role, Some(Role::Validation));
    // errors
    for (bad, want) in [
        ("role = \"maybe\"", "role must be \"fit\" or \"validation\""),
        (
            "force_scale = 0",
            "force_scale must be a finite positive number",
        ),
        (
            "toe_mm = 80",
            "toe_mm must be a finite number smaller than the gauge length",
        ),
        ("columns = [\"a\"]", "columns must name two columns"),
    ] {
        let toml = TOML.replace(
            "curve = \"warp-1.csv\"",
            &format!("curve = \"warp-1.csv\"\n{bad}"),
        );
        let e = load("bad-keys", &toml, Some(CSV)).unwrap_err().to_string();
        assert!(
            e.contains("fabric.toml:10: tensile test 1: ") && e.contains(want),
            "{e}"
        );
    }
    for (bad, want) in [
        (
            "a11_pa = 1e8\na22_pa = 1e8\na12_pa = 2e8",
            "breaks a12² < a11·a22",
        ),
        ("poisson_12 = 1.5", "poisson_12 must be in (-1, 1)"),
        ("a12_pa = 1e6\npoisson_12 = 0.1", "not both"),
        ("g12_pa = -3", "g12_pa must be a finite positive number"),
        ("e_pa = 3", "unknown field `e_pa`"),
    ] {
        let e = load("bad-known", &format!("{TOML}\n[known]\n{bad}\n"), Some(CSV))
            .unwrap_err()
            .to_string();
        assert!(e.contains(want), "{e}");
    }
}

#[test]
fn curve_files_must_be_regular_files() {
    let toml = TOML.replace("warp-1.csv", ".");
    let e = load("dir-curve", &toml, Some(CSV)).unwrap_err().to_string();
    assert!(e.contains("not a regular file"), "{e}");
}

#[test]
fn suspicious_data_gives_warnings() {
    let cases = [
        (
            "elongation_mm,force_n\n1.5,40\n",
            "warp-1.csv:2: warning: the curve has a single point",
        ),
        (
            "elongation_mm,force_n\n1.5,40\n90,400\n",
            "warp-1.csv:3: warning: strain 120 %",
        ),
        (
            "elongation_mm,force_n\n1.5,0.04\n3,0.08\n",
            "warp-1.csv:3: warning: the largest force is 0.08 N",
        ),
    ];
    for (i, (csv, want)) in cases.iter().enumerate() {
        let (_, w) = load(&format!("warn{i}"), TOML, Some(csv)).unwrap();
        assert_eq!(w.len(), 1, "{w:?}");
        let shown = w[0].to_string();
        let tail = &shown[shown.rfind("warp-1.csv").unwrap()..];
        assert!(
            tail.starts_with(want),
            "{tail:?} should start with {want:?}"
        );
    }
    // small forces below 1 % strain are not suspicious
    let (_, w) = load(
        "warn-small",
        TOML,
        Some("elongation_mm,force_n\n0.3,0.04\n0.6,0.08\n"),
    )
    .unwrap();
    assert!(w.is_empty(), "{w:?}");
    // the same curve twice, and an empty dataset
    let twice = format!("{TOML}\n[[tensile]]\nangle_deg = 90\nwidth_mm = 50\ngauge_length_mm = 75\ncurve = \"warp-1.csv\"\n");
    let (d, w) = load("warn-twice", &twice, Some(CSV)).unwrap();
    assert_eq!(d.tests_at(90.0).len(), 2);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].to_string().ends_with("fabric.toml:21: warning: tensile test 2: curve warp-1.csv is also used by the test at line 9"), "{}", w[0]);
    let (_, w) = load("warn-empty", "name = \"x\"\nthickness_mm = 0.2\n", None).unwrap();
    assert!(w[0].message.contains("nothing to fit"), "{w:?}");
}

#[test]
fn a_bend_without_its_drape_angle_is_a_warning() {
    let toml = TOML.replace("drape_angle_deg = 41.5\n", "");
    let (d, w) = load("no-drape", &toml, Some(CSV)).unwrap();
    assert_eq!(d.bend[0].drape_angle_deg, 41.5);
    assert_eq!(w.len(), 1, "{w:?}");
    let shown = w[0].to_string();
    assert!(
        shown.contains("fabric.toml:11: warning: bend test 1: no drape_angle_deg: 41.5°"),
        "{shown}"
    );
    assert!(d.notes.iter().any(|n| n.contains("no drape_angle_deg")));
}

const SQUARE_OBJ: &str = "v 0 0 0\nv 100 0 0\nv 100 100 1\nv 0 100 0\nvt 0 0\nvt 0.1 0\nvt 0.1 0.1\nvt 0 0.1\nf 1/1 2/2 3/3 4/4\n";

#[test]
fn shapes_are_read_checked_and_written_back() {
    let shape = "\n[[shape]]\nscene = \"picture-frame\"\nobj = \"frame.obj\"\nunits = \"mm\"\nshear_deg = 30\nforce_n = 17.5\ndescriptor = \"fft\"\nmesh = 10\n";
    let dir = folder("shape", &format!("{TOML}{shape}"), Some(CSV));
    std::fs::write(dir.join("frame.obj"), SQUARE_OBJ).unwrap();
    let (d, w) = load_dataset(&dir.join("fabric.toml")).unwrap();
    assert!(w.is_empty(), "{w:?}");
    let s = &d.shapes[0];
    assert_eq!(
        s.scene,
        ShapeScene::PictureFrame {
            side: 0.1,
            shear_deg: 30.0
        }
    );
    assert_eq!(
        (s.descriptor, s.force, s.mesh),
        (Descriptor::Fft, Some(17.5), Some(10))
    );
    assert_eq!(s.target.positions[2], [0.1, 0.1, 1e-3]);
    assert_eq!(s.target.triangles.len(), 2);
    // the files it comes from: what a command that writes must not overwrite
    assert_eq!(
        d.files(),
        ["fabric.toml", "warp-1.csv", "frame.obj"].map(|f| dir.join(f))
    );
    // written back (OBJ in metres) and read again: the same dataset
    let out = dir.join("copy");
    write_dataset(&out, &d).unwrap();
    let (e, _) = load_dataset(&out.join("fabric.toml")).unwrap();
    assert_eq!(e.shapes, d.shapes);

    // errors name the file, the line and the key
    let bad = |tag: &str, entry: &str, obj: &str| {
        let dir = folder(tag, &format!("{TOML}\n[[shape]]\n{entry}"), Some(CSV));
        std::fs::write(dir.join("s.obj"), obj).unwrap();
        load_dataset(&dir.join("fabric.toml")).unwrap_err()
    };
    let e = bad(
        "shape-noshear",
        "scene = \"picture-frame\"\nobj = \"s.obj\"\n",
        SQUARE_OBJ,
    );
    assert!(e.message.contains("needs shear_deg"), "{e}");
    assert_eq!(e.line, Some(17));
    let e = bad(
        "shape-scene",
        "scene = \"roof\"\nobj = \"s.obj\"\n",
        SQUARE_OBJ,
    );
    assert!(e.message.contains("scene must be"), "{e}");
    let e = bad(
        "shape-stretch",
        "scene = \"picture-frame\"\nobj = \"s.obj\"\nshear_deg = 20\nstretch_pct = 5\n",
        SQUARE_OBJ,
    );
    assert!(e.message.contains("stretch_pct does not apply"), "{e}");
    assert_eq!(e.line, Some(21));
    let e = bad(
        "shape-novt",
        "scene = \"corner-pull\"\nobj = \"s.obj\"\nstretch_pct = 5\ndescriptor = \"fft\"\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    assert!(e.message.contains("needs material coordinates"), "{e}");
    let e = bad(
        "shape-badobj",
        "scene = \"drape\"\nobj = \"s.obj\"\n",
        "v 0 0 0\nv 1 0 0\nf 1 2 9\n",
    );
    assert!(e.file.ends_with("s.obj") && e.line == Some(3), "{e}");
    let e = bad(
        "shape-outside",
        "scene = \"drape\"\nobj = \"../s.obj\"\n",
        SQUARE_OBJ,
    );
    assert!(e.message.contains("outside the dataset folder"), "{e}");
}
