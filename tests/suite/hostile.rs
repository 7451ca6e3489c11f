//! Careless and hostile input through the binary: every case ends in exit code 2 and one line
//! naming the file and line or the flag and its range, without a panic, a runaway allocation,
//! a hang, a silently wrong answer or an overwritten input. Each case here was once one of those.

use crate::common::{folder, ks_fit, s};
use std::path::Path;

const MATERIAL: &str = "examples/materials/cotton.toml";

/// Exit code 2 and a one-line message containing `want` (no panic, no backtrace).
fn refused(args: &[&str], want: &str) -> String {
    let (rc, out, err) = ks_fit(args);
    assert_eq!(rc, 2, "{args:?}: expected exit 2, got {rc}\n{out}{err}");
    assert!(
        err.starts_with("ks-fit: error:") && err.trim_end().lines().count() == 1,
        "{args:?}: not a one-line error:\n{err}"
    );
    assert!(err.contains(want), "{args:?}: missing {want:?} in\n{err}");
    err
}

/// `ks-fit tensile` on the example material (50 × 75 mm, 1 mm in 3 steps), with the flags in
/// `extra` replacing those defaults or added to them.
fn tensile<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec![
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
        "3",
    ];
    let mut i = 0;
    while i < extra.len() {
        let flag = extra[i];
        let value = extra
            .get(i + 1)
            .copied()
            .filter(|x| !x.starts_with("--") || x.len() < 3);
        match (v.iter().position(|a| *a == flag), value) {
            (Some(at), Some(x)) => v[at + 1] = x,
            (None, Some(x)) => v.extend([flag, x]),
            (_, None) => v.push(flag),
        }
        i += if value.is_some() { 2 } else { 1 };
    }
    v
}

#[test]
fn sizes_are_checked_before_anything_is_allocated() {
    refused(
        &tensile(&["--steps", "18446744073709551615"]),
        "--steps must be in [1, 10000]",
    );
    refused(&tensile(&["--steps", "1000000"]), "--steps");
    refused(&tensile(&["--mesh", "1000x1000"]), "--max-faces");
    refused(
        &tensile(&["--width", "1e-300"]),
        "--width must be at least 0.1 mm",
    );
    refused(
        &[
            "bend",
            "--material",
            MATERIAL,
            "--angle",
            "0",
            "--overhang",
            "50",
            "--mesh",
            "1000x1000",
        ],
        "--max-faces",
    );
    refused(
        &[
            "bend",
            "--material",
            MATERIAL,
            "--angle",
            "0",
            "--overhang",
            "100000",
        ],
        "--overhang must be",
    );
    refused(
        &["mesh", "meshes/cube.obj", "--subdivide", "20"],
        "--max-faces",
    );
    refused(
        &[
            "mesh",
            "meshes/cube.obj",
            "--subdivide",
            "18446744073709551615",
        ],
        "--max-faces",
    );
    let converge = |extra: &[&str]| {
        let mut v = vec![
            "converge",
            "tensile",
            "--material",
            MATERIAL,
            "--angle",
            "0",
            "--width",
            "50",
            "--length",
            "75",
            "--elongation",
            "1",
        ];
        v.extend_from_slice(extra);
        v.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let args = converge(&["--levels", "100"]);
    refused(
        &args.iter().map(|a| a.as_str()).collect::<Vec<_>>(),
        "--levels must be in [1, 10]",
    );
    // a ladder that does not refine would report a zero error estimate
    let args = converge(&["--mesh-ladder", "4x6,4x6,4x6"]);
    refused(
        &args.iter().map(|a| a.as_str()).collect::<Vec<_>>(),
        "twice as fine",
    );
    // the face limit is an override, not a wall: a 2 x 3 mesh under --max-faces 6 runs
    let (rc, _, err) = ks_fit(&tensile(&["--mesh", "2x3", "--max-faces", "6"]));
    assert_eq!(rc, 0, "{err}");
    refused(
        &tensile(&["--mesh", "2x4", "--max-faces", "6"]),
        "more than the limit of 6",
    );
}

#[test]
fn flags_out_of_range_are_named_with_their_range() {
    refused(
        &tensile(&["--angle", "1e308"]),
        "--angle must be in [-360, 360]",
    );
    // a negative number reaches the range check (not clap's "unexpected argument")
    refused(
        &tensile(&["--width", "-1"]),
        "--width must be a positive number of millimetres up to 2000",
    );
    let err = refused(&tensile(&["--angle", "1e300"]), "--angle");
    assert!(err.len() < 200, "a 300-digit number was printed: {err}");
    let dir = folder("hostile-synth-misalign");
    refused(
        &[
            "synth",
            "--material",
            MATERIAL,
            "--out",
            s(&dir.join("d")),
            "--misalign",
            "1e308",
        ],
        "misalignment must be",
    );
    refused(&tensile(&["--to", "500"]), "twice the gauge length");
    refused(
        &[
            "fit",
            "paper_repro/fabrics/cotton/fabric.toml",
            "--degree",
            "50",
        ],
        "degrees go up to 8",
    );
    refused(
        &[
            "synth",
            "--material",
            MATERIAL,
            "--out",
            s(&dir.join("d")),
            "--points",
            "100000",
        ],
        "at most 2000 points",
    );
}

#[test]
fn input_files_that_never_end_are_refused() {
    refused(&tensile(&["--material", "/dev/zero"]), "not a regular file");
    refused(&["mesh", "/dev/zero"], "not a regular file");
    let dir = folder("hostile-fifo");
    let fifo = dir.join("curve.csv");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|st| st.success()) {
        std::fs::write(
            dir.join("fabric.toml"),
            "name = \"f\"\nthickness_mm = 0.2\n[[tensile]]\nangle_deg = 90\nwidth_mm = 50\ngauge_length_mm = 75\ncurve = \"curve.csv\"\n",
        )
        .unwrap();
        refused(
            &["check", s(&dir.join("fabric.toml"))],
            "not a regular file",
        );
    }
}

#[test]
fn obj_files_cannot_wrap_indices_or_hide_vertices() {
    let dir = folder("hostile-obj");
    let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
    let wrap = dir.join("wrap.obj");
    std::fs::write(&wrap, format!("{quad}f 1 2 3 4294967300\n")).unwrap();
    refused(&["mesh", s(&wrap)], "wrap.obj:5: vertex index 4294967300");
    // a byte-order mark before the first `v` line must not drop that vertex
    let bom = dir.join("bom.obj");
    std::fs::write(&bom, format!("\u{feff}{quad}f 1 2 3 4\n")).unwrap();
    let (rc, out, err) = ks_fit(&["mesh", s(&bom)]);
    assert_eq!(rc, 0, "{err}");
    assert!(out.contains("vertices: 4"), "{out}");
    let huge = dir.join("huge.obj");
    std::fs::write(
        &huge,
        "v 0 0 0\nv 1e308 0 0\nv 1e308 1e308 0\nv 0 1e308 0\nf 1 2 3 4\n",
    )
    .unwrap();
    refused(
        &["mesh", s(&huge), "--limit", "0", "0.5", "0.5"],
        "huge.obj:2: vertex coordinate",
    );
}

/// A one-test dataset (warp strip) whose curve file holds `csv`.
fn dataset(tag: &str, csv: &str) -> std::path::PathBuf {
    let dir = folder(tag);
    std::fs::write(dir.join("warp.csv"), csv).unwrap();
    let toml = dir.join("fabric.toml");
    std::fs::write(
        &toml,
        "name = \"f\"\nthickness_mm = 0.2\n[[tensile]]\nangle_deg = 90\nwidth_mm = 50\ngauge_length_mm = 75\ncurve = \"warp.csv\"\n",
    )
    .unwrap();
    toml
}

/// A plausible warp curve: 10 points, 2 N per mm with a little stiffening; the force of row
/// `spike` (1-based data row, if any) replaced by `value`.
fn curve_with(spike: Option<(usize, &str)>) -> String {
    let mut c = String::from("elongation_mm,force_n\n");
    for i in 1..=10 {
        let e = 0.5 * i as f64;
        match spike {
            Some((row, value)) if row == i => c.push_str(&format!("{e},{value}\n")),
            _ => c.push_str(&format!("{e},{}\n", 2.0 * e + 0.05 * e * e)),
        }
    }
    c
}

fn curve() -> String {
    curve_with(None)
}

#[test]
fn a_corrupt_force_is_an_error_naming_its_line() {
    // row 5 of the data is line 6 of the file (the header is line 1)
    let toml = dataset("hostile-spike", &curve_with(Some((5, "1e308"))));
    refused(
        &["check", s(&toml)],
        "warp.csv:6: column 2 (force_n) = 1e308 N",
    );
    refused(
        &["fit", s(&toml), "-o", s(&toml.with_file_name("out.toml"))],
        "corrupt value",
    );
    // an isolated spike far above every other point, though finite and plausible alone
    let toml = dataset("hostile-spike2", &curve_with(Some((5, "900"))));
    refused(
        &["check", s(&toml)],
        "more than ten times every other force",
    );
    // a curve typed in metres ends at 0.007 % strain: check warns
    let metres: String = curve()
        .lines()
        .map(|l| match l.split_once(',') {
            Some((e, f)) if e.parse::<f64>().is_ok() => {
                format!("{},{f}\n", e.parse::<f64>().unwrap() / 1000.0)
            }
            _ => format!("{l}\n"),
        })
        .collect();
    let toml = dataset("hostile-metres", &metres);
    let (rc, out, err) = ks_fit(&["check", s(&toml)]);
    assert_eq!(rc, 0, "{err}");
    assert!(
        out.contains("warp.csv:11: warning: the curve ends at 0.0067 % strain"),
        "{out}"
    );
    assert!(out.contains("are the elongations in metres?"), "{out}");
    let zero: String = (1..=5).fold("elongation_mm,force_n\n".into(), |c, i| {
        c + &format!("{i},0\n")
    });
    let toml = dataset("hostile-zero", &zero);
    refused(&["fit", s(&toml)], "every force is zero");
}

#[test]
fn materials_that_cannot_be_solved_are_refused() {
    let dir = folder("hostile-material");
    let base =
        "name = \"m\"\nareal_density_g_m2 = 100\nthickness_mm = 0.2\na22_pa = 1e8\ng12_pa = 1e6\n";
    let write = |name: &str, text: String| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let accepted = |p: &Path| {
        let (rc, _, err) = ks_fit(&tensile(&["--material", s(p)]));
        assert_eq!(rc, 0, "{err}");
    };
    let tiny = write("tiny.toml", format!("{base}a11_pa = 1e-300\n"));
    refused(
        &tensile(&["--material", s(&tiny)]),
        "tiny.toml:6: a11_pa = 1e-300 is outside",
    );
    // the stress of this law peaks near 7 % Green strain and falls after it, with no cut-off
    let peak = write(
        "peak.toml",
        format!("{base}a11_pa = 1e8\n[warp]\nmu = [3.0, -2.0]\nalpha = [1.0, 40.0]\n"),
    );
    refused(
        &tensile(&["--material", s(&peak)]),
        "[warp] the stress stops rising at Green strain 0.0",
    );
    // the same law is legal when a cut-off ends its own range before the peak
    let cut = write(
        "cut.toml",
        format!("{base}a11_pa = 1e8\n[warp]\nmu = [3.0, -2.0]\nalpha = [1.0, 40.0]\n[cutoffs]\ne11_max = 0.03\n"),
    );
    accepted(&cut);
    // the same bound on a dataset's [known] moduli (the fit would write them into a material)
    let toml = dataset("hostile-known", &curve());
    let text = std::fs::read_to_string(&toml).unwrap();
    std::fs::write(&toml, format!("{text}[known]\na22_pa = 1e-300\n")).unwrap();
    refused(
        &["check", s(&toml)],
        "fabric.toml:9: [known] a22_pa = 1e-300 is outside",
    );
    // negative mu or alpha are legitimate as such: a softening term that keeps the stress rising
    let soft = write(
        "soft.toml",
        format!("{base}a11_pa = 1e8\n[warp]\nmu = [1.2, -0.2]\nalpha = [1.0, -2.0]\n"),
    );
    accepted(&soft);
}

#[test]
fn outputs_never_overwrite_inputs() {
    let toml = dataset("hostile-overwrite", &curve());
    let before = std::fs::read_to_string(&toml).unwrap();
    refused(
        &["fit", s(&toml), "-o", s(&toml)],
        "input files and would be overwritten",
    );
    assert_eq!(std::fs::read_to_string(&toml).unwrap(), before);
    // the report may not go into the dataset folder, nor into a folder of other files
    let dir = toml.parent().unwrap();
    refused(
        &[
            "fit",
            s(&toml),
            "-o",
            s(&dir.join("x.toml")),
            "--report",
            s(dir),
        ],
        "holds this command's input",
    );
    // a bad path is an error before the fit starts (no progress line was printed)
    let (rc, _, err) = ks_fit(&["fit", s(&toml), "-o", "/no/such/folder/x.toml"]);
    assert_eq!(rc, 2);
    assert!(
        err.contains("does not exist") && !err.contains("fit: ["),
        "{err}"
    );
    // --report naming a file: refused before the fit, and no material written
    let file = dir.join("notes.txt");
    std::fs::write(&file, "x").unwrap();
    refused(
        &[
            "fit",
            s(&toml),
            "-o",
            s(&dir.join("y.toml")),
            "--report",
            s(&file),
        ],
        "is a file, not a folder",
    );
    assert!(!dir.join("y.toml").exists());
    std::fs::remove_file(&file).unwrap();
    // mesh --write over its own input: refused, and the file is left as it was
    let work = folder("hostile-mesh-write");
    let obj = work.join("cube.obj");
    std::fs::copy("meshes/cube.obj", &obj).unwrap();
    let original = std::fs::read_to_string(&obj).unwrap();
    refused(&["mesh", s(&obj), "--write", s(&obj)], "--write");
    assert_eq!(std::fs::read_to_string(&obj).unwrap(), original);
    // with --force it is allowed, and written whole
    let (rc, _, err) = ks_fit(&[
        "mesh",
        s(&obj),
        "--subdivide",
        "1",
        "--write",
        s(&obj),
        "--force",
    ]);
    assert_eq!(rc, 0, "{err}");
    assert_eq!(
        std::fs::read_to_string(&obj)
            .unwrap()
            .matches("\nf ")
            .count(),
        24
    );
    // converge --csv onto the material
    let material = work.join("m.toml");
    std::fs::copy(MATERIAL, &material).unwrap();
    refused(
        &[
            "converge",
            "tensile",
            "--material",
            s(&material),
            "--angle",
            "0",
            "--width",
            "50",
            "--length",
            "75",
            "--elongation",
            "1",
            "--levels",
            "2",
            "--csv",
            s(&material),
        ],
        "--csv",
    );
    // synth into an existing dataset
    refused(
        &[
            "synth",
            "--material",
            MATERIAL,
            "--out",
            s(dir),
            "--points",
            "2",
        ],
        "holds a dataset already",
    );
    assert_eq!(std::fs::read_to_string(&toml).unwrap(), before);
    let names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| !n.contains("ks-tmp")), "{names:?}");
}

#[test]
fn curve_paths_stay_inside_the_dataset_folder() {
    let dir = folder("hostile-outside");
    let data = dir.join("data");
    std::fs::create_dir_all(&data).unwrap();
    std::fs::write(dir.join("secret.csv"), curve()).unwrap();
    let toml = data.join("fabric.toml");
    let write = |curve: &str| {
        std::fs::write(
            &toml,
            format!("name = \"f\"\nthickness_mm = 0.2\n[[tensile]]\nangle_deg = 90\nwidth_mm = 50\ngauge_length_mm = 75\ncurve = \"{curve}\"\n"),
        )
        .unwrap()
    };
    write("../secret.csv");
    refused(&["check", s(&toml)], "outside the dataset folder");
    let (rc, out, err) = ks_fit(&["check", s(&toml), "--allow-outside"]);
    assert_eq!(rc, 0, "{out}{err}");
    // a triangle model's fit refuses it too, and honours --allow-outside (it ignored the flag)
    refused(
        &["fit", s(&toml), "--model", "springs"],
        "outside the dataset folder",
    );
    let fitted = dir.join("outside-springs.toml");
    let (_, out, err) = ks_fit(&[
        "fit",
        s(&toml),
        "--model",
        "springs",
        "--allow-outside",
        "-o",
        s(&fitted),
    ]);
    assert!(!err.contains("outside the dataset folder"), "{out}{err}");
    write("/etc/passwd");
    let err = refused(&["check", s(&toml)], "outside the dataset folder");
    assert!(!err.contains("root:"), "the error echoes the file: {err}");
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(dir.join("secret.csv"), data.join("link.csv")).unwrap();
        write("link.csv");
        refused(&["check", s(&toml)], "outside the dataset folder");
    }
}

#[test]
fn a_fit_that_misses_its_target_says_so_and_exits_3() {
    // a strongly stiffening warp curve that a linear law (--degree 1) cannot follow: the fit
    // misses it by about 34 %; it still writes the material, then exits 3
    let mut c = String::from("elongation_mm,force_n\n");
    for i in 1..=20 {
        let e = 0.3 * i as f64;
        c.push_str(&format!("{e:.2},{:.5}\n", 0.5 * e + 0.4 * e * e * e));
    }
    let toml = dataset("hostile-miss", &c);
    let out = toml.with_file_name("fit.toml");
    let fit = |max_error: &str| {
        ks_fit(&[
            "fit",
            s(&toml),
            "-o",
            s(&out),
            "--degree",
            "1",
            "--mesh-ladder",
            "8x12",
            "--max-error",
            max_error,
        ])
    };
    let (rc, stdout, err) = fit("20");
    assert_eq!(rc, 3, "{stdout}{err}");
    assert!(
        stdout.contains("verdict: FIT FAILED: 1 fitted test(s) above --max-error 20 %"),
        "{stdout}"
    );
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with("tensile") && l.split_whitespace().any(|c| c == "OVER")),
        "{stdout}"
    );
    assert!(out.exists(), "the material must be written all the same");
    // the same fit judged against a looser bound passes
    let (rc, stdout, err) = fit("90");
    assert_eq!(rc, 0, "{stdout}{err}");
    assert!(
        stdout.contains("verdict: fit within --max-error 90 %"),
        "{stdout}"
    );
    refused(
        &["fit", s(&toml), "--max-error", "0"],
        "--max-error must be a percentage",
    );
    // a triangle model's fit checks it too (it took any value)
    refused(
        &["fit", s(&toml), "--model", "springs", "--max-error", "2000"],
        "--max-error must be a percentage",
    );
}

/// `recommend` checks its strip and cantilever sizes and its angle as `tensile` and `bend` do
/// (it took any positive size and any angle), and a triangle model's sheet keeps to
/// `--max-faces` as the shell's does (it built any grid).
#[test]
fn recommend_and_triangle_sheets_check_their_inputs() {
    fn recommend<'a>(extra: &[&'a str]) -> Vec<&'a str> {
        let mut v = vec!["recommend", "--material", MATERIAL];
        v.extend_from_slice(extra);
        v
    }
    refused(
        &recommend(&["--scene", "tensile", "--angle", "1000"]),
        "--angle must be in [-360, 360]",
    );
    refused(
        &recommend(&["--scene", "bend", "--width", "0.01"]),
        "--width must be at least 0.1 mm",
    );
    refused(
        &recommend(&["--scene", "tensile", "--to", "500"]),
        "more than twice the gauge length",
    );
    refused(
        &recommend(&["--scene", "picture-frame", "--shear-deg", "85"]),
        "--shear-deg must be within ±80",
    );
    // (a note that the springs were converted from the shell law comes first)
    let dir = folder("hostile-tri-sheet");
    let (rc, out, err) = ks_fit(&[
        "scene",
        "picture-frame",
        "--material",
        MATERIAL,
        "--model",
        "springs",
        "--mesh",
        "1000",
        "--out",
        s(&dir.join("frame")),
    ]);
    assert_eq!(rc, 2, "{out}{err}");
    let last = err.trim_end().lines().last().unwrap_or_default();
    assert!(
        last.starts_with("ks-fit: error:") && last.contains("--max-faces"),
        "{err}"
    );
}
