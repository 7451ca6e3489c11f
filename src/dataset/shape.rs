//! `[[shape]]` entries of `fabric.toml`: a captured static shape of one of the showcase scenes
//! (an OBJ in the scene's coordinates, as `ks-fit scene` writes it), fitted by the triangle
//! models with the position or the FFT descriptor (see [`crate::shape`]).
//!
//! ```toml
//! [[shape]]
//! scene = "picture-frame"   # "picture-frame", "corner-pull" or "drape" (as `ks-fit scene`)
//! obj = "frame-30.obj"      # relative to this file's folder
//! units = "m"               # of the OBJ's positions: "m" (default) or "mm"
//! shear_deg = 30            # picture-frame: the frame's final shear (required)
//! stretch_pct = 10          # corner-pull: the diagonal's final stretch (required)
//! side_mm = 100             # the square's side (default 100; the drape's 1000)
//! span_mm = 600             # drape: the held corners' final distance (default 600)
//! force_n = 17.8            # optional: the frame's shear force or the corner pull's force at the end
//! descriptor = "positions"  # or "fft" (needs the OBJ's vt: material coordinates)
//! role = "fit"              # or "validation"
//! mesh = 12                 # optional: the model's mesh, faces each way
//! ```

use super::{DatasetError, Role, Toml};
use crate::shape::ShapeMesh;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use toml::Spanned;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawShape {
    scene: Spanned<String>,
    obj: Spanned<String>,
    units: Option<Spanned<String>>,
    shear_deg: Option<Spanned<f64>>,
    stretch_pct: Option<Spanned<f64>>,
    side_mm: Option<Spanned<f64>>,
    span_mm: Option<Spanned<f64>>,
    force_n: Option<Spanned<f64>>,
    descriptor: Option<Spanned<String>>,
    role: Option<Spanned<String>>,
    mesh: Option<Spanned<i64>>,
}

impl RawShape {
    pub(super) fn obj_path(&self) -> &str {
        self.obj.get_ref()
    }
}

/// The scene a shape was captured in, SI units.
#[derive(Clone, Debug, PartialEq)]
pub enum ShapeScene {
    /// side, final shear (degrees)
    PictureFrame { side: f64, shear_deg: f64 },
    /// side, final stretch of the diagonal (fraction)
    CornerPull { side: f64, stretch: f64 },
    /// side, final distance of the held corners
    Drape { side: f64, span: f64 },
}

impl ShapeScene {
    pub fn name(&self) -> &'static str {
        match self {
            ShapeScene::PictureFrame { .. } => "picture-frame",
            ShapeScene::CornerPull { .. } => "corner-pull",
            ShapeScene::Drape { .. } => "drape",
        }
    }

    /// One line naming the scene and its setting.
    pub fn describe(&self) -> String {
        match self {
            ShapeScene::PictureFrame { side, shear_deg } => {
                format!("picture-frame {shear_deg}° ({} mm)", side * 1e3)
            }
            ShapeScene::CornerPull { side, stretch } => {
                format!("corner-pull {} % ({} mm)", stretch * 100.0, side * 1e3)
            }
            ShapeScene::Drape { side, span } => {
                format!("drape ({} mm, corners {} mm apart)", side * 1e3, span * 1e3)
            }
        }
    }
}

/// How a simulated sheet is compared with the captured one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Descriptor {
    /// Distances of the simulated vertices to the captured surface.
    Positions,
    /// FFT magnitudes over the material coordinates.
    Fft,
}

impl Descriptor {
    pub fn name(self) -> &'static str {
        match self {
            Descriptor::Positions => "positions",
            Descriptor::Fft => "fft",
        }
    }
}

/// A captured shape, read and checked.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeTest {
    pub scene: ShapeScene,
    /// As written in fabric.toml (relative to its folder).
    pub obj: PathBuf,
    pub target: ShapeMesh,
    pub descriptor: Descriptor,
    /// N
    pub force: Option<f64>,
    pub role: Option<Role>,
    /// Faces each way of the model's sheet, when given.
    pub mesh: Option<usize>,
}

/// Largest OBJ read, bytes.
const MAX_OBJ_BYTES: u64 = 256 << 20;

fn choice<'a>(
    t: &Toml,
    what: &str,
    key: &str,
    v: &'a Option<Spanned<String>>,
    allowed: &[&str],
) -> Result<Option<&'a str>, DatasetError> {
    match v {
        None => Ok(None),
        Some(s) if allowed.contains(&s.get_ref().as_str()) => Ok(Some(s.get_ref().as_str())),
        Some(s) => Err(t.err(
            s.span(),
            format!(
                "{what}{key} must be one of {}, got {:?}",
                allowed.join(", "),
                s.get_ref()
            ),
        )),
    }
}

/// Reads one `[[shape]]` entry (number `i` from 0) and its OBJ.
pub(super) fn read_shape(
    t: &Toml,
    dir: &Path,
    i: usize,
    spanned: &Spanned<RawShape>,
) -> Result<ShapeTest, DatasetError> {
    let r = spanned.get_ref();
    let what = format!("shape {}: ", i + 1);
    let scene = read_scene(t, &what, spanned)?;
    let scale = match choice(t, &what, "units", &r.units, &["m", "mm"])? {
        Some("mm") => 1e-3,
        _ => 1.0,
    };
    let descriptor = match choice(t, &what, "descriptor", &r.descriptor, &["positions", "fft"])? {
        Some("fft") => Descriptor::Fft,
        _ => Descriptor::Positions,
    };
    let role = match choice(t, &what, "role", &r.role, &["fit", "validation"])? {
        Some("fit") => Some(Role::Fit),
        Some(_) => Some(Role::Validation),
        None => None,
    };
    let force = match &r.force_n {
        Some(v) => Some(t.positive(&what, "force_n", v, 1.0)?),
        None => None,
    };
    let mesh = match &r.mesh {
        None => None,
        Some(v) => {
            let m = *v.get_ref();
            if !(2..=128).contains(&m) {
                return Err(t.err(
                    v.span(),
                    format!("{what}mesh must be 2 to 128 faces each way, got {m}"),
                ));
            }
            Some(m as usize)
        }
    };
    let obj = PathBuf::from(r.obj.get_ref());
    let target = read_target(t, &what, &dir.join(&obj), &r.obj, scale, descriptor)?;
    Ok(ShapeTest {
        scene,
        obj,
        target,
        descriptor,
        force,
        role,
        mesh,
    })
}

/// A shape entry's scene with its size and its loading (shear, stretch or span), checked.
fn read_scene(
    t: &Toml,
    what: &str,
    spanned: &Spanned<RawShape>,
) -> Result<ShapeScene, DatasetError> {
    let r = spanned.get_ref();
    let need = |v: &Option<Spanned<f64>>, key: &str, scene: &str| match v {
        Some(v) => Ok(v.clone()),
        None => Err(t.err(spanned.span(), format!("{what}a {scene} shape needs {key}"))),
    };
    let refuse = |v: &Option<Spanned<f64>>, key: &str, scene: &str| match v {
        Some(v) => Err(t.err(
            v.span(),
            format!("{what}{key} does not apply to a {scene} shape"),
        )),
        None => Ok(()),
    };
    let side_default = if r.scene.get_ref() == "drape" {
        1000.0
    } else {
        100.0
    };
    let side = match &r.side_mm {
        Some(v) => t.positive(what, "side_mm", v, 1e-3)?,
        None => side_default * 1e-3,
    };
    let scene = match r.scene.get_ref().as_str() {
        "picture-frame" => {
            refuse(&r.stretch_pct, "stretch_pct", "picture-frame")?;
            refuse(&r.span_mm, "span_mm", "picture-frame")?;
            let s = need(&r.shear_deg, "shear_deg", "picture-frame")?;
            let shear_deg = *s.get_ref();
            if !(shear_deg.abs() > 0.0 && shear_deg.abs() < 80.0) {
                return Err(t.err(
                    s.span(),
                    format!("{what}shear_deg must be in (-80, 80) and not 0, got {shear_deg:?}"),
                ));
            }
            ShapeScene::PictureFrame { side, shear_deg }
        }
        "corner-pull" => {
            refuse(&r.shear_deg, "shear_deg", "corner-pull")?;
            refuse(&r.span_mm, "span_mm", "corner-pull")?;
            let s = need(&r.stretch_pct, "stretch_pct", "corner-pull")?;
            let pct = *s.get_ref();
            if !(pct > 0.0 && pct < 100.0) {
                return Err(t.err(
                    s.span(),
                    format!("{what}stretch_pct must be in (0, 100), got {pct:?}"),
                ));
            }
            ShapeScene::CornerPull {
                side,
                stretch: pct / 100.0,
            }
        }
        "drape" => {
            refuse(&r.shear_deg, "shear_deg", "drape")?;
            refuse(&r.stretch_pct, "stretch_pct", "drape")?;
            if let Some(f) = &r.force_n {
                return Err(t.err(
                    f.span(),
                    format!("{what}force_n does not apply to a drape (no boundary force is measured)"),
                ));
            }
            let span = match &r.span_mm {
                Some(v) => t.positive(what, "span_mm", v, 1e-3)?,
                None => 0.6 * side,
            };
            if span > side {
                return Err(t.err(
                    spanned.span(),
                    format!("{what}span_mm must not exceed side_mm"),
                ));
            }
            ShapeScene::Drape { side, span }
        }
        other => {
            return Err(t.err(
                r.scene.span(),
                format!("{what}scene must be \"picture-frame\", \"corner-pull\" or \"drape\", got {other:?}"),
            ))
        }
    };
    Ok(scene)
}

/// The target mesh read from the OBJ file `obj_path` (`obj` as written, for its line), in metres
/// (`scale` per unit of the file); the fft descriptor checks it has material coordinates.
fn read_target(
    t: &Toml,
    what: &str,
    obj_path: &Path,
    obj: &Spanned<String>,
    scale: f64,
    descriptor: Descriptor,
) -> Result<ShapeMesh, DatasetError> {
    let name = obj_path.display().to_string();
    let text = crate::io::read_text(obj_path, MAX_OBJ_BYTES).map_err(|e| {
        t.err(
            obj.span(),
            format!("{what}cannot read shape file {name}: {e}"),
        )
    })?;
    let target = ShapeMesh::from_obj(&text, scale).map_err(|e| DatasetError {
        file: name.clone(),
        line: e.line,
        message: e.message,
    })?;
    if descriptor == Descriptor::Fft {
        if let Err(why) = crate::shape::fft::resample(&target, 4) {
            return Err(DatasetError {
                file: t.file.to_string(),
                line: Some(t.line(obj.span().start)),
                message: format!(
                    "{what}the fft descriptor needs material coordinates: {name}: {why}"
                ),
            });
        }
    }
    Ok(target)
}
