//! Where outputs may go, through the binary: only onto regular files or new paths, never over
//! any file a dataset names, into a folder only when it is new, empty or an earlier output of
//! the same kind, and never while another ks-fit writes the same output.

use crate::common::{folder, ks_fit, s};
use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

const MATERIAL: &str = "examples/materials/cotton.toml";

/// Exit code 2 and a one-line error containing `want`.
fn refused(args: &[&str], want: &str) {
    let (rc, out, err) = ks_fit(args);
    assert_eq!(rc, 2, "{args:?}: expected exit 2, got {rc}\n{out}{err}");
    assert!(
        err.starts_with("ks-fit: error:") && err.trim_end().lines().count() == 1,
        "{args:?}: not a one-line error:\n{err}"
    );
    assert!(err.contains(want), "{args:?}: missing {want:?} in\n{err}");
}

/// A one-strip dataset (a warp curve, 10 points) with a picture-frame `[[shape]]` whose OBJ is
/// a 3 × 3 sheet with a raised centre; returns fabric.toml.
fn dataset(tag: &str) -> PathBuf {
    let dir = folder(tag);
    let mut csv = String::from("elongation_mm,force_n\n");
    for i in 1..=10 {
        let e = 0.5 * i as f64;
        csv.push_str(&format!("{e},{}\n", 2.0 * e + 0.05 * e * e));
    }
    std::fs::write(dir.join("warp.csv"), csv).unwrap();
    let mut obj = String::new();
    for j in 0..3 {
        for i in 0..3 {
            let z = if (i, j) == (1, 1) { 0.005 } else { 0.0 };
            obj.push_str(&format!("v {} {} {z}\n", 0.05 * i as f64, 0.05 * j as f64));
        }
    }
    for j in 0..3 {
        for i in 0..3 {
            obj.push_str(&format!("vt {} {}\n", 0.05 * i as f64, 0.05 * j as f64));
        }
    }
    for j in 0..2 {
        for i in 0..2 {
            let a = j * 3 + i + 1;
            let (b, c, d) = (a + 1, a + 4, a + 3);
            obj.push_str(&format!("f {a}/{a} {b}/{b} {c}/{c} {d}/{d}\n"));
        }
    }
    std::fs::write(dir.join("frame.obj"), obj).unwrap();
    let toml = dir.join("fabric.toml");
    std::fs::write(
        &toml,
        "name = \"f\"\nthickness_mm = 0.2\n[[tensile]]\nangle_deg = 90\nwidth_mm = 50\ngauge_length_mm = 75\ncurve = \"warp.csv\"\n[[shape]]\nscene = \"picture-frame\"\nobj = \"frame.obj\"\nshear_deg = 30\nrole = \"validation\"\n",
    )
    .unwrap();
    toml
}

/// Makes a FIFO at `path`; false where there is no `mkfifo`.
fn mkfifo(path: &Path) -> bool {
    let made = Command::new("mkfifo").arg(path).status();
    made.is_ok_and(|st| st.success())
}

fn is_fifo(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| m.file_type().is_fifo())
}

#[test]
fn outputs_onto_devices_and_fifos_are_refused() {
    let toml = dataset("outputs-special");
    let dir = folder("outputs-special-out");
    let fifo = dir.join("pipe");
    if !mkfifo(&fifo) {
        eprintln!("no mkfifo on this machine: outputs onto FIFOs and devices are not tested");
        return;
    }
    let f = s(&fifo);
    let cube = "meshes/cube.obj";
    let converge = [
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
        "--levels",
        "2",
    ];
    let file_outputs: Vec<Vec<&str>> = vec![
        vec!["fit", s(&toml), "-o", f],
        vec!["fit", s(&toml), "--model", "springs", "-o", f],
        vec![
            "export",
            "--material",
            MATERIAL,
            "--format",
            "arcsim",
            "--out",
            f,
        ],
        vec!["render", cube, "--out", f],
        vec!["mesh", cube, "--write", f],
        [&converge[..], &["--csv", f][..]].concat(),
        [&converge[..], &["--plot", f][..]].concat(),
    ];
    for args in &file_outputs {
        refused(args, "is a FIFO (named pipe), not a regular file");
        // --force allows replacing inputs, never a FIFO
        refused(
            &[&args[..], &["--force"][..]].concat(),
            "not a regular file",
        );
        assert!(is_fifo(&fifo), "{args:?} replaced the FIFO");
    }
    let out = dir.join("m.toml");
    let folder_outputs: Vec<Vec<&str>> = vec![
        vec!["fit", s(&toml), "-o", s(&out), "--report", f],
        vec!["synth", "--material", MATERIAL, "--out", f, "--points", "2"],
        vec![
            "scene",
            "drape",
            "--material",
            MATERIAL,
            "--out",
            f,
            "--mesh",
            "4",
        ],
    ];
    for args in &folder_outputs {
        refused(args, "is a FIFO (named pipe), not a folder");
        assert!(is_fifo(&fifo), "{args:?} replaced the FIFO");
    }
    assert!(!out.exists(), "the material was written before the refusal");
    // a character device (reached only once the FIFO cases hold, so that a regression fails
    // there and no run reaches the device node)
    let full = Path::new("/dev/full");
    if std::fs::metadata(full).is_ok_and(|m| m.file_type().is_char_device()) {
        refused(
            &["fit", s(&toml), "-o", "/dev/full"],
            "is a character device",
        );
        refused(
            &[
                "export",
                "--material",
                MATERIAL,
                "--format",
                "arcsim",
                "--out",
                "/dev/full",
            ],
            "is a character device",
        );
        let kind = std::fs::metadata(full).map(|m| m.file_type().is_char_device());
        assert!(kind.unwrap_or(false), "/dev/full is no longer a device");
    } else {
        eprintln!("no /dev/full here: the character-device case is not run");
    }
}

#[test]
fn every_file_a_dataset_names_is_an_input() {
    let toml = dataset("outputs-inputs");
    let dir = toml.parent().unwrap();
    let obj = dir.join("frame.obj");
    let curve = dir.join("warp.csv");
    let before = std::fs::read(&obj).unwrap();
    let warp = std::fs::read(&curve).unwrap();
    for model in ["kl", "springs"] {
        for target in [&obj, &curve] {
            refused(
                &["fit", s(&toml), "--model", model, "-o", s(target)],
                "input files and would be overwritten",
            );
        }
    }
    assert_eq!(std::fs::read(&obj).unwrap(), before);
    assert_eq!(std::fs::read(&curve).unwrap(), warp);
}

#[test]
fn only_a_reports_own_summary_marks_an_earlier_report() {
    let toml = dataset("outputs-report");
    let work = folder("outputs-report-out");
    let out = work.join("m.toml");
    // someone's folder that happens to hold a summary.txt and an index.html
    let notes = work.join("notes");
    std::fs::create_dir_all(&notes).unwrap();
    std::fs::write(notes.join("summary.txt"), "my notes\n").unwrap();
    std::fs::write(notes.join("index.html"), "<p>mine</p>\n").unwrap();
    refused(
        &["fit", s(&toml), "-o", s(&out), "--report", s(&notes)],
        "its summary.txt is not from an earlier run",
    );
    assert_eq!(
        std::fs::read_to_string(notes.join("summary.txt")).unwrap(),
        "my notes\n"
    );
    assert_eq!(
        std::fs::read_to_string(notes.join("index.html")).unwrap(),
        "<p>mine</p>\n"
    );
    // a report is written over by the next fit's report
    let report = work.join("report");
    for run in 0..2 {
        let (rc, _, err) = ks_fit(&[
            "fit",
            s(&toml),
            "-o",
            s(&out),
            "--report",
            s(&report),
            "--quiet",
        ]);
        assert_eq!(rc, 0, "run {run}: {err}");
    }
    // a scene's folder: its scene.toml must be one a scene wrote
    let other = work.join("other");
    std::fs::create_dir_all(&other).unwrap();
    std::fs::write(other.join("scene.toml"), "mine = 1\n").unwrap();
    refused(
        &[
            "scene",
            "drape",
            "--material",
            MATERIAL,
            "--out",
            s(&other),
            "--mesh",
            "4",
        ],
        "its scene.toml is not from an earlier run",
    );
    assert_eq!(
        std::fs::read_to_string(other.join("scene.toml")).unwrap(),
        "mine = 1\n"
    );
}

/// The lock file of output `name` in `dir`.
fn lock_of(dir: &Path, name: &str) -> PathBuf {
    dir.canonicalize().unwrap().join(format!(".{name}.ks-lock"))
}

#[test]
fn two_writers_of_one_output_do_not_run_at_once() {
    let toml = dataset("outputs-lock");
    let work = folder("outputs-lock-out");
    let out = work.join("m.toml");
    let lock = lock_of(&work, "m.toml");
    let mut first = Command::new(env!("CARGO_BIN_EXE_ks-fit"))
        .args(["fit", s(&toml), "-o", s(&out), "--quiet"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("run ks-fit");
    // the first fit holds the lock from its start to its end
    let t0 = std::time::Instant::now();
    while !lock.exists() && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let held = lock.exists();
    let pid = format!("pid {}", first.id());
    let second = ks_fit(&["fit", s(&toml), "-o", s(&out), "--quiet"]);
    let status = first.wait().unwrap();
    assert!(held, "the first fit took no lock {}", lock.display());
    assert_eq!(second.0, 2, "the second fit ran: {}", second.2);
    assert!(
        second.2.contains(&pid) && second.2.contains(s(&lock)),
        "{}",
        second.2
    );
    assert!(status.success(), "the first fit failed");
    assert!(!lock.exists(), "the lock outlived its fit");

    // a lock whose process no longer runs is stale: taken over with a note, then removed
    let mut gone = Command::new(env!("CARGO_BIN_EXE_ks-fit"))
        .arg("--version")
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let dead = gone.id();
    gone.wait().unwrap();
    let json = work.join("m.json");
    let json_lock = lock_of(&work, "m.json");
    std::fs::write(&json_lock, format!("{dead}\n")).unwrap();
    let export = [
        "export",
        "--material",
        MATERIAL,
        "--format",
        "arcsim",
        "--out",
        s(&json),
    ];
    let (rc, _, err) = ks_fit(&export);
    assert_eq!(rc, 0, "{err}");
    assert!(err.contains("removing a stale lock"), "{err}");
    assert!(json.is_file() && !json_lock.exists());
    // a lock that names no process is left to the user
    std::fs::write(&json_lock, "").unwrap();
    refused(&export, "names no process");
    assert!(json_lock.exists());
}

#[test]
fn render_refuses_a_shape_without_size() {
    let dir = folder("outputs-render-zero");
    let png = dir.join("x.png");
    let dot = dir.join("dot.obj");
    std::fs::write(&dot, "v 0 0 0\nv 0 0 0\nv 0 0 0\nf 1 2 3\n").unwrap();
    refused(
        &["render", s(&dot), "--out", s(&png)],
        "the shape has zero size",
    );
    let line = dir.join("line.obj");
    std::fs::write(&line, "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
    refused(&["render", s(&line), "--out", s(&png)], "zero area");
    let empty = dir.join("empty.obj");
    std::fs::write(&empty, "").unwrap();
    refused(&["render", s(&empty), "--out", s(&png)], "no faces");
    assert!(!png.exists());
}
