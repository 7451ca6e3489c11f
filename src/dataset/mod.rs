//! The fabric dataset: what the lab measured, as `fabric.toml` beside CSV curves, read into SI
//! units and checked here. This module owns the format, its reader and writer; the fitter
//! (`crate::fit`) and `ks-fit check` / `ks-fit synth` use it.
//!
//! ```toml
//! name = "cotton-poplin"
//! areal_density_g_m2 = 103.6     # optional unless there are bend tests
//! thickness_mm = 0.18            # measured (ASTM D1777); the fit's initial guess
//! [[tensile]]                    # ASTM D5035 strip; several at one angle are repeats
//! angle_deg = 90                 # from the weft: 0 weft, 90 warp, 45 bias
//! width_mm = 50
//! gauge_length_mm = 75
//! curve = "warp-1.csv"           # relative to this file's folder
//! [[bend]]                       # ASTM D1388 cantilever
//! angle_deg = 90
//! width_mm = 25
//! overhang_mm = 61.0             # overhang at which the tip reaches the drape angle
//! drape_angle_deg = 41.5         # optional, default 41.5
//! [[shape]]                      # a captured static shape (triangle-model fits; see `shape`)
//! scene = "picture-frame"
//! obj = "frame-30.obj"
//! shear_deg = 30
//! ```
//!
//! A curve is CSV with the header `elongation_mm,force_n` (spaces around fields tolerated;
//! blank lines and lines starting with `#` are skipped), then one row per point: elongation
//! non-negative and strictly increasing, force non-negative, both finite. Any subset of tests is
//! legal (no bend, no bias…).
//!
//! Errors name the file and line: TOML syntax, missing or unknown keys, a missing or malformed
//! curve, a non-increasing elongation, a negative or non-finite value, a non-positive width,
//! gauge length, overhang, thickness or areal density, a bend test without areal density, an
//! angle outside [0°, 180°), a drape angle outside (0°, 90°), a curve without data rows.
//!
//! Warnings (legal but suspicious): a curve with one point; a strain above 100 %; forces that
//! look like kN: the largest force is below 10 N per metre of width (0.5 N on a 50 mm strip)
//! although the curve reaches 1 % strain (woven fabrics carry tens to hundreds of newtons
//! there); a curve file used by two tests; a dataset with no tests.

mod curve;
mod known;
mod shape;
mod write;

use curve::{parse_curve, Curve};
use known::read_known;
use serde::Deserialize;
pub use shape::{Descriptor, ShapeScene, ShapeTest};
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;
pub use write::{curve_csv, dataset_toml, write_dataset, write_dataset_with_comment};

/// The drape angle of ASTM D1388 (tan⁻¹ 0.5 ≈ 26.6° is the other convention; we use 41.5°).
pub const DEFAULT_DRAPE_ANGLE_DEG: f64 = 41.5;

/// Tensile angles the staged fit uses (weft, bias, warp); others are validation tests.
pub const FITTED_ANGLES_DEG: [f64; 3] = [0.0, 45.0, 90.0];

/// The header every curve file starts with.
pub const CURVE_HEADER: &str = "elongation_mm,force_n";

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDataset {
    name: String,
    areal_density_g_m2: Option<Spanned<f64>>,
    thickness_mm: Spanned<f64>,
    #[serde(default)]
    tensile: Vec<Spanned<RawTensile>>,
    #[serde(default)]
    bend: Vec<Spanned<RawBend>>,
    #[serde(default)]
    shape: Vec<Spanned<shape::RawShape>>,
    known: Option<RawKnown>,
}

/// Values the lab knows from elsewhere; the fit holds them.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawKnown {
    a11_pa: Option<Spanned<f64>>,
    a22_pa: Option<Spanned<f64>>,
    a12_pa: Option<Spanned<f64>>,
    g12_pa: Option<Spanned<f64>>,
    thickness_mm: Option<Spanned<f64>>,
    poisson_12: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTensile {
    angle_deg: Spanned<f64>,
    width_mm: Spanned<f64>,
    gauge_length_mm: Spanned<f64>,
    curve: Spanned<String>,
    role: Option<Spanned<String>>,
    force_scale: Option<Spanned<f64>>,
    toe_mm: Option<Spanned<f64>>,
    columns: Option<Spanned<Vec<String>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBend {
    angle_deg: Spanned<f64>,
    width_mm: Spanned<f64>,
    overhang_mm: Spanned<f64>,
    drape_angle_deg: Option<Spanned<f64>>,
}

/// A fabric's lab data in SI units.
#[derive(Clone, Debug, PartialEq)]
pub struct FabricDataset {
    pub name: String,
    /// The `fabric.toml` it came from.
    pub path: PathBuf,
    /// kg/m²
    pub areal_density: Option<f64>,
    /// m (measured; an initial guess for the fit)
    pub thickness: f64,
    pub tensile: Vec<TensileTest>,
    pub bend: Vec<BendTest>,
    /// Captured static shapes (`[[shape]]`), fitted by the triangle models.
    pub shapes: Vec<ShapeTest>,
    /// values known from elsewhere, held by the fit (`[known]`)
    pub known: Known,
    /// what the reader did to the data (averaged duplicates, units read from headers)
    pub notes: Vec<String>,
}

/// Values known from elsewhere (`[known]` in fabric.toml), in SI units; the fit holds them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Known {
    pub a11: Option<f64>,
    pub a22: Option<f64>,
    pub a12: Option<f64>,
    pub g12: Option<f64>,
    /// m
    pub thickness: Option<f64>,
    /// ν12 = a12 / a22 (a measured Poisson ratio pins a12)
    pub poisson_12: Option<f64>,
}

impl Known {
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// Whether a tensile test is fitted or only predicted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    Fit,
    Validation,
}

/// One ASTM D5035 strip test.
#[derive(Clone, Debug, PartialEq)]
pub struct TensileTest {
    /// From the weft: 0 weft, 90 warp, 45 bias; in [0, 180).
    pub angle_deg: f64,
    /// m
    pub width: f64,
    /// m
    pub gauge_length: f64,
    /// As written in the TOML (relative to the TOML's folder).
    pub curve: PathBuf,
    /// m, non-negative, strictly increasing
    pub elongation: Vec<f64>,
    /// N (after `force_scale`); noise may dip below zero by 1 % of the largest force
    pub force: Vec<f64>,
    /// `role` as written; `None`: the protocol decides (every angle fitted by default)
    pub role: Option<Role>,
    /// the toe (slack or preload) to remove, m, when given (`toe_mm`); `None`: automatic
    pub toe: Option<f64>,
    /// the factor the curve's forces were multiplied by (`force_scale`, default 1)
    pub force_scale: f64,
    /// `columns` as written: the elongation and force columns' header names
    pub columns: Option<[String; 2]>,
    /// the forces look like kN (tiny for the strip's width) and no `force_scale` is given
    pub suspect_kn: bool,
}

/// One ASTM D1388 cantilever: the overhang at which the tip reaches the drape angle.
#[derive(Clone, Debug, PartialEq)]
pub struct BendTest {
    pub angle_deg: f64,
    /// m
    pub width: f64,
    /// m
    pub overhang: f64,
    pub drape_angle_deg: f64,
}

/// Something legal but suspicious in a dataset.
#[derive(Clone, Debug, PartialEq)]
pub struct DatasetWarning {
    pub file: String,
    pub line: Option<usize>,
    pub message: String,
}

impl fmt::Display for DatasetWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}:{}: warning: {}", self.file, l, self.message),
            None => write!(f, "{}: warning: {}", self.file, self.message),
        }
    }
}

/// What is wrong with a dataset.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub struct DatasetError {
    pub file: String,
    pub line: Option<usize>,
    pub message: String,
}

impl fmt::Display for DatasetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}:{}: {}", self.file, l, self.message),
            None => write!(f, "{}: {}", self.file, self.message),
        }
    }
}

impl FabricDataset {
    /// The tensile tests (repeats) at `angle_deg` (within 1e-9°).
    pub fn tests_at(&self, angle_deg: f64) -> Vec<&TensileTest> {
        self.tensile
            .iter()
            .filter(|t| (t.angle_deg - angle_deg).abs() < 1e-9)
            .collect()
    }
}

impl TensileTest {
    /// A test with the default options (role by protocol, automatic toe, no force scale).
    pub fn new(
        angle_deg: f64,
        width: f64,
        gauge_length: f64,
        curve: PathBuf,
        elongation: Vec<f64>,
        force: Vec<f64>,
    ) -> Self {
        Self {
            angle_deg,
            width,
            gauge_length,
            curve,
            elongation,
            force,
            role: None,
            toe: None,
            force_scale: 1.0,
            columns: None,
            suspect_kn: false,
        }
    }

    /// Whether the paper's protocol fits this test (0°, 45°, 90°); other angles validate it.
    pub fn is_fitted(&self) -> bool {
        FITTED_ANGLES_DEG
            .iter()
            .any(|a| (self.angle_deg - a).abs() < 1e-9)
    }

    /// The test's role: as written, else fitted (`paper = false`, every angle) or by the
    /// paper's split (`paper = true`: 0°, 45°, 90° fitted, the rest validation).
    pub fn role(&self, paper: bool) -> Role {
        match self.role {
            Some(r) => r,
            None if !paper || self.is_fitted() => Role::Fit,
            None => Role::Validation,
        }
    }
}

/// 1-based line of byte offset `at`, moved past any whitespace (a table's span may start on
/// the blank line above its header).
fn line_of(text: &str, at: usize) -> usize {
    let at = at.min(text.len());
    let skip = text
        .get(at..)
        .map_or(0, |rest| rest.len() - rest.trim_start().len());
    text[..(at + skip).min(text.len())].matches('\n').count() + 1
}

/// Errors located in the TOML text.
struct Toml<'a> {
    text: &'a str,
    file: &'a str,
}

impl Toml<'_> {
    fn err(&self, span: Range<usize>, message: String) -> DatasetError {
        DatasetError {
            file: self.file.to_string(),
            line: Some(line_of(self.text, span.start)),
            message,
        }
    }

    /// A finite positive value, converted by `scale`.
    fn positive(
        &self,
        what: &str,
        key: &str,
        v: &Spanned<f64>,
        scale: f64,
    ) -> Result<f64, DatasetError> {
        let x = *v.get_ref();
        if x.is_finite() && x > 0.0 {
            Ok(x * scale)
        } else {
            Err(self.err(
                v.span(),
                format!("{what}{key} must be a finite positive number, got {x:?}"),
            ))
        }
    }

    /// A cut angle in [0, 180).
    fn angle(&self, what: &str, v: &Spanned<f64>) -> Result<f64, DatasetError> {
        let a = *v.get_ref();
        if (0.0..180.0).contains(&a) {
            Ok(a)
        } else {
            Err(self.err(
                v.span(),
                format!("{what}angle_deg must be in [0, 180) (from the weft), got {a:?}"),
            ))
        }
    }
}

/// Warnings about one tensile curve (lab units).
fn curve_warnings(
    c: &Curve,
    width_mm: f64,
    gauge_mm: f64,
    file: &str,
    out: &mut Vec<DatasetWarning>,
) {
    let warn = |line: usize, message: String| DatasetWarning {
        file: file.to_string(),
        line: Some(line),
        message,
    };
    if c.lines.len() == 1 {
        out.push(warn(
            c.lines[0],
            "the curve has a single point (a fit needs its shape)".into(),
        ));
    }
    if let Some(i) = c.elongation_mm.iter().position(|&e| e > gauge_mm) {
        out.push(warn(
            c.lines[i],
            format!(
                "strain {:.0} % (elongation {} mm over a {} mm gauge length) is above 100 %: are the elongations in mm?",
                100.0 * c.elongation_mm[i] / gauge_mm,
                c.elongation_mm[i],
                gauge_mm
            ),
        ));
    }
    let max_strain = c.elongation_mm.last().copied().unwrap_or(0.0) / gauge_mm;
    let (imax, fmax) =
        c.force_n
            .iter()
            .copied()
            .enumerate()
            .fold(
                (0, f64::NEG_INFINITY),
                |a, (i, f)| if f > a.1 { (i, f) } else { a },
            );
    let floor = 0.01 * width_mm; // 10 N per metre of width
    if max_strain > 0.01 && fmax < floor {
        out.push(warn(
            c.lines[imax],
            format!(
                "the largest force is {fmax} N at up to {:.1} % strain, below {floor} N for a {width_mm} mm strip (fabrics carry tens to hundreds of newtons): are the forces in kN?",
                100.0 * max_strain
            ),
        ));
    }
    // a strip test runs to a few percent strain at least; a curve that ends below 0.1 % with
    // the largest force of a real test was most likely typed in metres
    if c.lines.len() > 1 && max_strain < 1e-3 && fmax >= floor {
        let last = c.lines.len() - 1;
        out.push(warn(
            c.lines[last],
            format!(
                "the curve ends at {:.4} % strain ({} mm over a {gauge_mm} mm gauge length) with forces up to {fmax} N: are the elongations in metres? (the header's unit must be mm)",
                100.0 * max_strain,
                crate::io::num(c.elongation_mm[last])
            ),
        ));
    }
}

/// Largest curve file read (a million rows of a machine export are about 40 MB).
const MAX_CURVE_BYTES: u64 = 256 << 20;

/// A curve file's text: regular files only (not a FIFO or a device), of bounded size.
fn read_curve_file(path: &Path) -> Result<String, String> {
    crate::io::read_text(path, MAX_CURVE_BYTES)
}

/// Largest `fabric.toml` read.
const MAX_TOML_BYTES: u64 = 16 << 20;

/// Reads and checks a dataset: `fabric.toml` and the curves it names (relative to its folder,
/// which they may not leave: see [`load_dataset_with`]).
pub fn load_dataset(path: &Path) -> Result<(FabricDataset, Vec<DatasetWarning>), DatasetError> {
    load_dataset_with(path, false)
}

/// Whether the curve path `curve` (as written, relative to `dir`), resolved with every symbolic
/// link, lies inside the folder `dir`.
fn inside(dir: &Path, curve: &Path) -> bool {
    match (dir.canonicalize(), dir.join(curve).canonicalize()) {
        (Ok(d), Ok(c)) => c.starts_with(d),
        // a missing file is reported when it is read; judge the path as written meanwhile
        _ => {
            !curve.is_absolute()
                && !curve
                    .components()
                    .any(|c| matches!(c, std::path::Component::ParentDir))
        }
    }
}

/// As [`load_dataset`]; with `allow_outside`, curve paths may also be absolute, climb out of the
/// dataset folder with `..`, or be symbolic links to files elsewhere.
pub fn load_dataset_with(
    path: &Path,
    allow_outside: bool,
) -> Result<(FabricDataset, Vec<DatasetWarning>), DatasetError> {
    let file = path.display().to_string();
    let text = crate::io::read_text(path, MAX_TOML_BYTES).map_err(|e| DatasetError {
        file: file.clone(),
        line: None,
        message: format!("cannot read file: {e}"),
    })?;
    let raw: RawDataset = toml::from_str(&text).map_err(|e| DatasetError {
        file: file.clone(),
        line: e.span().map(|s| line_of(&text, s.start)),
        message: e.message().trim().replace('\n', " "),
    })?;
    let t = Toml {
        text: &text,
        file: &file,
    };
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut warnings = Vec::new();
    let thickness = t.positive("", "thickness_mm", &raw.thickness_mm, 1e-3)?;
    let areal_density = match &raw.areal_density_g_m2 {
        Some(v) => Some(t.positive("", "areal_density_g_m2", v, 1e-3)?),
        None => None,
    };
    let known = read_known(&t, raw.known.as_ref())?;
    let mut notes = Vec::new();
    let mut tensile = Vec::with_capacity(raw.tensile.len());
    let mut used: Vec<(PathBuf, usize)> = Vec::new();
    for (i, spanned) in raw.tensile.iter().enumerate() {
        let r = spanned.get_ref();
        let what = format!("tensile test {}: ", i + 1);
        let angle_deg = t.angle(&what, &r.angle_deg)?;
        let width = t.positive(&what, "width_mm", &r.width_mm, 1e-3)?;
        let gauge_length = t.positive(&what, "gauge_length_mm", &r.gauge_length_mm, 1e-3)?;
        let curve = PathBuf::from(r.curve.get_ref());
        let csv_path = dir.join(&curve);
        let csv_name = csv_path.display().to_string();
        let dir_or_here = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        if !allow_outside && (curve.is_absolute() || !inside(dir_or_here, &curve)) {
            return Err(t.err(
                r.curve.span(),
                format!("{what}curve {csv_name} lies outside the dataset folder (an absolute path, `..` or a symbolic link out of it); pass --allow-outside to read it"),
            ));
        }
        let columns = match &r.columns {
            None => None,
            Some(c) => match c.get_ref().as_slice() {
                [a, b] => Some([a.clone(), b.clone()]),
                _ => {
                    return Err(t.err(
                        c.span(),
                        format!("{what}columns must name two columns: [elongation, force]"),
                    ))
                }
            },
        };
        let role = match &r.role {
            None => None,
            Some(v) => match v.get_ref().as_str() {
                "fit" => Some(Role::Fit),
                "validation" => Some(Role::Validation),
                other => {
                    return Err(t.err(
                        v.span(),
                        format!("{what}role must be \"fit\" or \"validation\", got {other:?}"),
                    ))
                }
            },
        };
        let force_scale = match &r.force_scale {
            Some(v) => t.positive(&what, "force_scale", v, 1.0)?,
            None => 1.0,
        };
        let toe = match &r.toe_mm {
            None => None,
            Some(v) => {
                let x = *v.get_ref();
                if !x.is_finite() || x.abs() >= gauge_length * 1e3 {
                    return Err(t.err(
                        v.span(),
                        format!("{what}toe_mm must be a finite number smaller than the gauge length (negative for a preload), got {x:?}"),
                    ));
                }
                Some(x * 1e-3)
            }
        };
        let csv = read_curve_file(&csv_path).map_err(|m| {
            t.err(
                r.curve.span(),
                format!("{what}cannot read curve file {csv_name}: {m}"),
            )
        })?;
        let mut c = parse_curve(&csv, &csv_name, columns.as_ref())?;
        c.force_n.iter_mut().for_each(|f| *f *= force_scale);
        let before = warnings.len();
        curve_warnings(
            &c,
            width * 1e3,
            gauge_length * 1e3,
            &csv_name,
            &mut warnings,
        );
        let suspect_kn = r.force_scale.is_none()
            && warnings[before..]
                .iter()
                .any(|w| w.message.contains("are the forces in kN?"));
        if c.duplicates > 0 {
            notes.push(format!(
                "{csv_name}: {} rows repeated the elongation of the row before and were averaged into it",
                c.duplicates
            ));
        }
        if let Some(u) = &c.units {
            notes.push(format!(
                "{csv_name}: read the columns {u}, converted to mm and N"
            ));
        }
        if force_scale != 1.0 {
            notes.push(format!(
                "{csv_name}: forces multiplied by force_scale = {force_scale}"
            ));
        }
        let line = line_of(&text, r.curve.span().start);
        if let Some((_, first)) = used.iter().find(|(p, _)| *p == curve) {
            warnings.push(DatasetWarning {
                file: file.clone(),
                line: Some(line),
                message: format!(
                    "{what}curve {} is also used by the test at line {first}",
                    curve.display()
                ),
            });
        } else {
            used.push((curve.clone(), line));
        }
        let mut test = TensileTest::new(
            angle_deg,
            width,
            gauge_length,
            curve,
            c.elongation_mm.iter().map(|e| e * 1e-3).collect(),
            c.force_n,
        );
        test.role = role;
        test.toe = toe;
        test.force_scale = force_scale;
        test.columns = columns;
        test.suspect_kn = suspect_kn;
        tensile.push(test);
    }
    let mut bend = Vec::with_capacity(raw.bend.len());
    for (i, spanned) in raw.bend.iter().enumerate() {
        let r = spanned.get_ref();
        let what = format!("bend test {}: ", i + 1);
        let angle_deg = t.angle(&what, &r.angle_deg)?;
        let width = t.positive(&what, "width_mm", &r.width_mm, 1e-3)?;
        let overhang = t.positive(&what, "overhang_mm", &r.overhang_mm, 1e-3)?;
        let drape_angle_deg = match &r.drape_angle_deg {
            None => {
                let message = format!(
                    "{what}no drape_angle_deg: {DEFAULT_DRAPE_ANGLE_DEG}° (the ASTM D1388 target) is assumed; give the measured angle if it differs (the fitted bending rigidity goes with it)"
                );
                notes.push(format!("warning: {message}"));
                warnings.push(DatasetWarning {
                    file: file.clone(),
                    line: Some(line_of(&text, spanned.span().start)),
                    message,
                });
                DEFAULT_DRAPE_ANGLE_DEG
            }
            Some(v) => {
                let a = *v.get_ref();
                if !(a > 0.0 && a < 90.0) {
                    return Err(t.err(
                        v.span(),
                        format!("{what}drape_angle_deg must be in (0, 90), got {a:?}"),
                    ));
                }
                a
            }
        };
        if areal_density.is_none() {
            return Err(t.err(
                spanned.span(),
                format!(
                    "{what}a bend test needs areal_density_g_m2 (the strip bends under its own weight)"
                ),
            ));
        }
        bend.push(BendTest {
            angle_deg,
            width,
            overhang,
            drape_angle_deg,
        });
    }
    let mut shapes = Vec::with_capacity(raw.shape.len());
    for (i, spanned) in raw.shape.iter().enumerate() {
        let obj = Path::new(spanned.get_ref().obj_path());
        let dir_or_here = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        if !allow_outside && (obj.is_absolute() || !inside(dir_or_here, obj)) {
            return Err(t.err(
                spanned.span(),
                format!("shape {}: {} lies outside the dataset folder (an absolute path, `..` or a symbolic link out of it); pass --allow-outside to read it", i + 1, dir.join(obj).display()),
            ));
        }
        shapes.push(shape::read_shape(&t, dir, i, spanned)?);
    }
    if tensile.is_empty() && bend.is_empty() && shapes.is_empty() {
        warnings.push(DatasetWarning {
            file: file.clone(),
            line: None,
            message: "no [[tensile]] or [[bend]] tests: nothing to fit".into(),
        });
    }
    Ok((
        FabricDataset {
            name: raw.name,
            path: path.to_path_buf(),
            areal_density,
            thickness,
            tensile,
            bend,
            shapes,
            known,
            notes,
        },
        warnings,
    ))
}

#[cfg(test)]
mod tests;
