//! Fixtures shared by the suite's modules: running the `ks-fit` binary, temporary folders,
//! hand-made lab data.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The second column of the first data row of a CSV that `ks-fit` printed (a strip's force,
/// a cantilever's drape angle).
pub fn first_value(out: &str) -> f64 {
    let cell = out.lines().nth(1).and_then(|l| l.split(',').nth(1));
    cell.and_then(|c| c.trim().parse().ok())
        .unwrap_or_else(|| panic!("no value in the first row of:\n{out}"))
}

/// Runs `ks-fit` in the crate root: (exit code, stdout, stderr).
pub fn ks_fit(args: &[&str]) -> (i32, String, String) {
    ks_fit_env(args, &[])
}

/// A fresh, empty temporary folder named after the test process, the calling test file and
/// `tag` (every module of the suite runs in one process, so a tag alone could be shared).
#[track_caller]
pub fn folder(tag: &str) -> PathBuf {
    let caller = Path::new(std::panic::Location::caller().file());
    let module = caller
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("test");
    let dir = std::env::temp_dir().join(format!("kshell-{}-{module}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// As [`ks_fit`], with extra environment variables.
pub fn ks_fit_env(args: &[&str], env: &[(&str, &str)]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_ks-fit"))
        .args(args)
        .envs(env.iter().copied())
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run ks-fit");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A headless browser on this machine (Debian's `chromium`, or Chrome), if any.
pub fn browser() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    for dir in std::env::split_paths(&path) {
        for name in ["chromium", "chromium-browser", "google-chrome"] {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

/// Renders a local HTML file to a PNG of `width` × `height` with the headless browser, with
/// no network (flags as this machine's notes give for a root, offline Chromium). Returns the
/// PNG's bytes; None when there is no browser (a panic when KSHELL_REQUIRE_BROWSER is set).
pub fn screenshot(html: &Path, png: &Path, width: u32, height: u32) -> Option<Vec<u8>> {
    let Some(exe) = browser() else {
        assert!(
            std::env::var_os("KSHELL_REQUIRE_BROWSER").is_none(),
            "KSHELL_REQUIRE_BROWSER is set but no chromium is on PATH"
        );
        eprintln!("no headless browser: the page is not rendered (set KSHELL_REQUIRE_BROWSER to require it)");
        return None;
    };
    let profile = png.with_extension("profile");
    let url = format!("file://{}", html.canonicalize().unwrap().display());
    let out = Command::new(exe)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--window-size={width},{height}"))
        .arg(format!("--screenshot={}", png.display()))
        .arg(url)
        .output()
        .expect("run the browser");
    let bytes = std::fs::read(png).unwrap_or_else(|e| {
        panic!(
            "the browser wrote no screenshot ({e}): {}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    let _ = std::fs::remove_dir_all(&profile);
    Some(bytes)
}

/// A scene's force is dW/dq at equilibrium, so along a continuous branch the work of the
/// reported force (trapezoid rule over the steps) equals the change of the total energy
/// within 2 %.
pub fn work_balances(q: &[f64], force: &[f64], energy: &[f64], what: &str) {
    let work: f64 = (1..q.len())
        .map(|k| 0.5 * (force[k] + force[k - 1]) * (q[k] - q[k - 1]))
        .sum();
    let de = energy[q.len() - 1] - energy[0];
    assert!(
        (work - de).abs() < 0.02 * de.abs(),
        "{what}: work {work} J against energy change {de} J"
    );
}

/// Strips of 50 × 75 mm at `angles` pulled to 3 mm (8 × 12 faces) and a warp and a weft
/// cantilever 25 × 50 mm (twice the default mesh), made by the triangle material `m` on the
/// meshes its fit uses: a dataset whose truth is known.
pub fn tri_lab(m: &kshell::tri::TriMaterial, angles: &[f64]) -> kshell::dataset::FabricDataset {
    use kshell::scene::{TriCantilever, TriTensile};
    let pull = |angle: f64, dl: &[f64]| -> Vec<f64> {
        let mut s = TriTensile::new(0.05, 0.075, angle);
        s.mesh = (8, 12);
        s.run(m, dl).unwrap().iter().map(|p| p.force).collect()
    };
    let drape = |angle: f64| -> f64 {
        let mut c = TriCantilever::new(0.025, 0.05, angle);
        c.mesh = (c.mesh.0 * 2, c.mesh.1 * 2);
        c.run(m).unwrap().drape_angle_deg
    };
    made_lab(angles, 3e-4, &pull, &drape, (m.areal_density, 2e-4))
}

/// A dataset whose truth is known: strips of 50 × 75 mm at `angles` pulled in ten steps of
/// `step` (m), their forces from `pull(angle, elongations)`, and a warp and a weft cantilever
/// 25 × 50 mm, their drape angles from `drape(angle)`; (areal density kg/m², thickness m).
pub fn made_lab(
    angles: &[f64],
    step: f64,
    pull: &dyn Fn(f64, &[f64]) -> Vec<f64>,
    drape: &dyn Fn(f64) -> f64,
    (areal_density, thickness): (f64, f64),
) -> kshell::dataset::FabricDataset {
    use kshell::dataset::{BendTest, FabricDataset, TensileTest};
    let tensile = angles
        .iter()
        .map(|&angle| {
            let dl: Vec<f64> = (0..=10).map(|i| step * i as f64).collect();
            let mut force = vec![0.0];
            force.extend(pull(angle, &dl[1..]));
            TensileTest::new(
                angle,
                0.05,
                0.075,
                PathBuf::from(format!("a{angle}.csv")),
                dl,
                force,
            )
        })
        .collect();
    let bend = [90.0, 0.0]
        .map(|angle| BendTest {
            angle_deg: angle,
            width: 0.025,
            overhang: 0.05,
            drape_angle_deg: drape(angle),
        })
        .to_vec();
    FabricDataset {
        name: "made".into(),
        path: PathBuf::from("made/fabric.toml"),
        areal_density: Some(areal_density),
        thickness,
        tensile,
        bend,
        shapes: Vec::new(),
        known: Default::default(),
        notes: Vec::new(),
    }
}

/// `avg_rel_error` of the first fitted tensile test at `angle` in a fitted material file.
pub fn tensile_error_at(doc: &toml::Table, angle: f64) -> f64 {
    doc["fit"]["test"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_table().unwrap())
        .find(|t| t["kind"].as_str() == Some("tensile") && t["angle_deg"].as_float() == Some(angle))
        .and_then(|t| t["avg_rel_error"].as_float())
        .unwrap_or_else(|| panic!("no tensile test at {angle}°"))
}
