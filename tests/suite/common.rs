//! Fixtures shared by the suite's modules: running the `ks-fit` binary, temporary folders,
//! hand-made lab data.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

use kshell::material::{Cutoffs, Eta, FabricMaterial, Orthotropic, OrthotropicStvk};

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

/// One builder for the suite's hand-written laws. It starts from the orthotropic St. Venant–
/// Kirchhoff law (every η linear, no cut-offs, no coupling) on a 100 g/m², 0.2 mm fabric named
/// "test", and a test adds the η terms, cut-offs, density and thickness it is about. The same
/// law comes out as the library's types ([`TestLaw::material`], [`TestLaw::law`]) or as a
/// material file ([`TestLaw::toml`]) for the CLI.
#[derive(Clone, Debug)]
pub struct TestLaw {
    pub name: String,
    /// kg/m²
    pub areal_density: f64,
    /// m
    pub thickness: f64,
    pub law: Orthotropic,
}

impl TestLaw {
    /// The orthotropic St. Venant–Kirchhoff law with these moduli (Pa).
    pub fn stvk(a11: f64, a22: f64, a12: f64, g12: f64) -> Self {
        let law = OrthotropicStvk { a11, a22, a12, g12 };
        Self {
            name: "test".into(),
            areal_density: 0.1,
            thickness: 2.0e-4,
            law: law.into(),
        }
    }

    /// The isotropic St. Venant–Kirchhoff law of Young's modulus `e` (Pa) and Poisson ratio `nu`.
    pub fn isotropic(e: f64, nu: f64) -> Self {
        let s = OrthotropicStvk::isotropic(e, nu);
        Self::stvk(s.a11, s.a22, s.a12, s.g12)
    }

    pub fn named(mut self, name: &str) -> Self {
        self.name = name.into();
        self
    }

    /// Areal density in kg/m².
    pub fn density(mut self, kg_m2: f64) -> Self {
        self.areal_density = kg_m2;
        self
    }

    /// Thickness in m.
    pub fn thickness(mut self, m: f64) -> Self {
        self.thickness = m;
        self
    }

    /// η1 = Σ μ/α ((x+1)^α − 1) (Clyde et al. 2017, Eq. 2).
    pub fn warp(mut self, mu: &[f64], alpha: &[f64]) -> Self {
        self.law.warp = eta(mu, alpha);
        self
    }

    /// η3, as [`TestLaw::warp`].
    pub fn weft(mut self, mu: &[f64], alpha: &[f64]) -> Self {
        self.law.weft = eta(mu, alpha);
        self
    }

    /// η4, as [`TestLaw::warp`].
    pub fn shear(mut self, mu: &[f64], alpha: &[f64]) -> Self {
        self.law.shear = eta(mu, alpha);
        self
    }

    /// Green-strain cut-offs in the warp/weft frame, each (min, max).
    pub fn cutoffs(mut self, e11: (f64, f64), e22: (f64, f64), e12: (f64, f64)) -> Self {
        self.law.cutoffs = Cutoffs { e11, e22, e12 };
        self
    }

    /// The paper's fabric: bending from the law integrated through the thickness.
    pub fn material(&self) -> FabricMaterial {
        FabricMaterial::paper(
            &self.name,
            self.areal_density,
            self.thickness,
            self.law.clone(),
        )
    }

    /// The law alone.
    pub fn law(&self) -> Orthotropic {
        self.law.clone()
    }

    /// The moduli as a St. Venant–Kirchhoff law (the η terms left out).
    pub fn stvk_law(&self) -> OrthotropicStvk {
        let l = &self.law;
        OrthotropicStvk {
            a11: l.a11,
            a22: l.a22,
            a12: l.a12,
            g12: l.g12,
        }
    }

    /// The law as a material file (docs/material-format.md); cut-offs and coupling are not
    /// written.
    pub fn toml(&self) -> String {
        let l = &self.law;
        let mut text = format!(
            "name = \"{}\"\nareal_density_g_m2 = {}\nthickness_mm = {}\na11_pa = {:e}\na22_pa = {:e}\na12_pa = {:e}\ng12_pa = {:e}\n",
            self.name,
            short(self.areal_density * 1e3),
            short(self.thickness * 1e3),
            l.a11,
            l.a22,
            l.a12,
            l.g12
        );
        for (table, e) in [("warp", &l.warp), ("weft", &l.weft), ("shear", &l.shear)] {
            if *e != Eta::linear() {
                text += &format!("[{table}]\nmu = {:?}\nalpha = {:?}\n", e.mu, e.alpha);
            }
        }
        text
    }
}

/// `x` to 12 significant digits, as short as Rust writes it: the unit conversion's last-digit
/// noise (0.3e-3 · 1e3 = 0.30000000000000004) stays out of the file.
fn short(x: f64) -> String {
    let rounded: f64 = format!("{x:.11e}").parse().unwrap();
    format!("{rounded}")
}

fn eta(mu: &[f64], alpha: &[f64]) -> Eta {
    assert_eq!(mu.len(), alpha.len(), "one α for every μ");
    Eta {
        mu: mu.to_vec(),
        alpha: alpha.to_vec(),
    }
}

/// `ks-fit fit` flags of a quick fit: the 4 × 6 mesh alone, no mesh check, every test on the
/// ladder's mesh (a test about what the fit does, not how accurate its mesh is).
pub const QUICK_FIT: [&str; 6] = [
    "--mesh-ladder",
    "4x6",
    "--mesh-check",
    "off",
    "--test-meshes",
    "ladder",
];
