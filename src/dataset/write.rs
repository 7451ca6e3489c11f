//! Writing a dataset back: `fabric.toml` (lab units) and its curves as `elongation_mm,force_n`.

use super::{FabricDataset, Role, ShapeScene, TensileTest, CURVE_HEADER};
use crate::io::toml_string;
use std::path::Path;

/// The `fabric.toml` text of `data` (lab units), each line of `comment` as a `#` line on top.
pub fn dataset_toml(data: &FabricDataset, comment: &str) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    for l in comment.lines() {
        let _ = writeln!(s, "# {l}");
    }
    let _ = writeln!(s, "name = {}", toml_string(&data.name));
    if let Some(rho) = data.areal_density {
        let _ = writeln!(s, "areal_density_g_m2 = {:?}", rho * 1e3);
    }
    let _ = writeln!(s, "thickness_mm = {:?}", data.thickness * 1e3);
    for t in &data.tensile {
        let _ = writeln!(s, "\n[[tensile]]");
        let _ = writeln!(s, "angle_deg = {:?}", t.angle_deg);
        let _ = writeln!(s, "width_mm = {:?}", t.width * 1e3);
        let _ = writeln!(s, "gauge_length_mm = {:?}", t.gauge_length * 1e3);
        let _ = writeln!(s, "curve = {}", toml_string(&t.curve.to_string_lossy()));
        match t.role {
            Some(Role::Fit) => s.push_str("role = \"fit\"\n"),
            Some(Role::Validation) => s.push_str("role = \"validation\"\n"),
            None => {}
        }
        if t.force_scale != 1.0 {
            let _ = writeln!(s, "force_scale = {:?}", t.force_scale);
        }
        if let Some(toe) = t.toe {
            let _ = writeln!(s, "toe_mm = {:?}", toe * 1e3);
        }
    }
    let k = &data.known;
    if !k.is_empty() {
        let _ = writeln!(s, "\n[known]");
        for (key, v, scale) in [
            ("a11_pa", k.a11, 1.0),
            ("a22_pa", k.a22, 1.0),
            ("a12_pa", k.a12, 1.0),
            ("g12_pa", k.g12, 1.0),
            ("thickness_mm", k.thickness, 1e3),
            ("poisson_12", k.poisson_12, 1.0),
        ] {
            if let Some(v) = v {
                let _ = writeln!(s, "{key} = {:?}", v * scale);
            }
        }
    }
    for b in &data.bend {
        let _ = writeln!(s, "\n[[bend]]");
        let _ = writeln!(s, "angle_deg = {:?}", b.angle_deg);
        let _ = writeln!(s, "width_mm = {:?}", b.width * 1e3);
        let _ = writeln!(s, "overhang_mm = {:?}", b.overhang * 1e3);
        let _ = writeln!(s, "drape_angle_deg = {:?}", b.drape_angle_deg);
    }
    for sh in &data.shapes {
        let _ = writeln!(s, "\n[[shape]]");
        let _ = writeln!(s, "scene = {}", toml_string(sh.scene.name()));
        let _ = writeln!(s, "obj = {}", toml_string(&sh.obj.to_string_lossy()));
        match sh.scene {
            ShapeScene::PictureFrame { side, shear_deg } => {
                let _ = writeln!(s, "side_mm = {:?}\nshear_deg = {shear_deg:?}", side * 1e3);
            }
            ShapeScene::CornerPull { side, stretch } => {
                let _ = writeln!(
                    s,
                    "side_mm = {:?}\nstretch_pct = {:?}",
                    side * 1e3,
                    stretch * 100.0
                );
            }
            ShapeScene::Drape { side, span } => {
                let _ = writeln!(s, "side_mm = {:?}\nspan_mm = {:?}", side * 1e3, span * 1e3);
            }
        }
        if let Some(f) = sh.force {
            let _ = writeln!(s, "force_n = {f:?}");
        }
        let _ = writeln!(s, "descriptor = {}", toml_string(sh.descriptor.name()));
        match sh.role {
            Some(Role::Fit) => s.push_str("role = \"fit\"\n"),
            Some(Role::Validation) => s.push_str("role = \"validation\"\n"),
            None => {}
        }
        if let Some(m) = sh.mesh {
            let _ = writeln!(s, "mesh = {m}");
        }
    }
    s
}

/// The CSV text of one curve (lab units as `elongation_mm,force_n`, forces without
/// `force_scale` applied, every number written to round-trip).
pub fn curve_csv(t: &TensileTest) -> String {
    let mut s = format!("{CURVE_HEADER}\n");
    for (e, f) in t.elongation.iter().zip(&t.force) {
        s.push_str(&format!("{:?},{:?}\n", e * 1e3, f / t.force_scale));
    }
    s
}

/// Writes `dir/fabric.toml`, each tensile test's curve (named by [`TensileTest::curve`],
/// relative to `dir`) and each shape's OBJ (in metres), creating folders as needed.
pub fn write_dataset(dir: &Path, data: &FabricDataset) -> std::io::Result<()> {
    write_dataset_with_comment(dir, data, "")
}

/// As [`write_dataset`], with `comment` (one `#` line per line) at the top of `fabric.toml`.
pub fn write_dataset_with_comment(
    dir: &Path,
    data: &FabricDataset,
    comment: &str,
) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    for t in &data.tensile {
        let p = dir.join(&t.curve);
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent)?;
        }
        crate::io::write_atomic(&p, curve_csv(t))?;
    }
    for sh in &data.shapes {
        let p = dir.join(&sh.obj);
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent)?;
        }
        crate::io::write_atomic(&p, sh.target.obj())?;
    }
    crate::io::write_atomic(&dir.join("fabric.toml"), dataset_toml(data, comment))
}
