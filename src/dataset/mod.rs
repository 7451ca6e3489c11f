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

use curve::{parse_curve, Curve};
use serde::Deserialize;
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

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
    /// the forces look like kN (tiny for the strip's width) and no `force_scale` was given
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
/// the blank line before its header).
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
                format!("{what}{key} must be a finite positive number, got {x}"),
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
                format!("{what}angle_deg must be in [0, 180) (from the weft), got {a}"),
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
}

/// Largest curve file read (a million rows of a machine export are about 40 MB).
const MAX_CURVE_BYTES: u64 = 256 << 20;

/// A curve file's text: regular files only (not a FIFO or a device), of bounded size.
fn read_curve_file(path: &Path) -> Result<String, String> {
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err("not a regular file".into());
    }
    if meta.len() > MAX_CURVE_BYTES {
        return Err(format!(
            "{} bytes, more than the {} MiB a curve may have",
            meta.len(),
            MAX_CURVE_BYTES >> 20
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    String::from_utf8(bytes).map_err(|_| "not UTF-8 text".to_string())
}

/// The `[known]` table in SI units.
fn read_known(t: &Toml, raw: Option<&RawKnown>) -> Result<Known, DatasetError> {
    let Some(k) = raw else {
        return Ok(Known::default());
    };
    let pos =
        |key: &str, v: &Option<Spanned<f64>>, scale: f64| -> Result<Option<f64>, DatasetError> {
            v.as_ref()
                .map(|v| t.positive("[known] ", key, v, scale))
                .transpose()
        };
    let a12 = match &k.a12_pa {
        Some(v) if !v.get_ref().is_finite() => {
            return Err(t.err(
                v.span(),
                format!("[known] a12_pa must be finite, got {}", v.get_ref()),
            ))
        }
        v => v.as_ref().map(|v| *v.get_ref()),
    };
    let poisson_12 = match &k.poisson_12 {
        Some(v) if !(v.get_ref().is_finite() && v.get_ref().abs() < 1.0) => {
            return Err(t.err(
                v.span(),
                format!("[known] poisson_12 must be in (-1, 1), got {}", v.get_ref()),
            ))
        }
        v => v.as_ref().map(|v| *v.get_ref()),
    };
    let known = Known {
        a11: pos("a11_pa", &k.a11_pa, 1.0)?,
        a22: pos("a22_pa", &k.a22_pa, 1.0)?,
        a12,
        g12: pos("g12_pa", &k.g12_pa, 1.0)?,
        thickness: pos("thickness_mm", &k.thickness_mm, 1e-3)?,
        poisson_12,
    };
    if let (Some(a11), Some(a22), Some(a12)) = (known.a11, known.a22, known.a12) {
        if a12 * a12 >= a11 * a22 {
            let span = k.a12_pa.as_ref().map_or(0..0, |v| v.span());
            return Err(t.err(
                span,
                format!(
                    "[known] a12_pa = {a12} breaks a12² < a11·a22 (the law would not be convex)"
                ),
            ));
        }
    }
    if known.a12.is_some() && known.poisson_12.is_some() {
        let span = k.poisson_12.as_ref().map_or(0..0, |v| v.span());
        return Err(t.err(
            span,
            "[known] give a12_pa or poisson_12, not both (ν12 = a12/a22)".into(),
        ));
    }
    Ok(known)
}

/// Reads and checks a dataset: `fabric.toml` and the curves it names (relative to its folder).
pub fn load_dataset(path: &Path) -> Result<(FabricDataset, Vec<DatasetWarning>), DatasetError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| DatasetError {
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
                        format!("{what}toe_mm must be a finite number smaller than the gauge length (negative for a preload), got {x}"),
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
            None => DEFAULT_DRAPE_ANGLE_DEG,
            Some(v) => {
                let a = *v.get_ref();
                if !(a > 0.0 && a < 90.0) {
                    return Err(t.err(
                        v.span(),
                        format!("{what}drape_angle_deg must be in (0, 90), got {a}"),
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
    if tensile.is_empty() && bend.is_empty() {
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
            known,
            notes,
        },
        warnings,
    ))
}

/// A TOML string literal.
fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

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
    s
}

/// The CSV text of one curve (lab units as `elongation_mm,force_n`, forces before
/// `force_scale`, every number written to round-trip).
pub fn curve_csv(t: &TensileTest) -> String {
    let mut s = format!("{CURVE_HEADER}\n");
    for (e, f) in t.elongation.iter().zip(&t.force) {
        s.push_str(&format!("{:?},{:?}\n", e * 1e3, f / t.force_scale));
    }
    s
}

/// Writes `dir/fabric.toml` and each tensile test's curve (named by [`TensileTest::curve`],
/// relative to `dir`), creating folders as needed.
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
        std::fs::write(p, curve_csv(t))?;
    }
    std::fs::write(dir.join("fabric.toml"), dataset_toml(data, comment))
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOML: &str = "name = \"poplin\"\nareal_density_g_m2 = 103.6\nthickness_mm = 0.18\n\n[[tensile]]\nangle_deg = 90\nwidth_mm = 50\ngauge_length_mm = 75\ncurve = \"warp-1.csv\"\n\n[[bend]]\nangle_deg = 90\nwidth_mm = 25\noverhang_mm = 61.0\n";
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
            "\n[[bend]]\nangle_deg = 90\nwidth_mm = 25\noverhang_mm = 61.0\n",
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
        let dir =
            std::env::temp_dir().join(format!("kshell-dataset-{}-written", std::process::id()));
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
                "fabric.toml:15: unknown field `colour`",
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
                format!("{TOML}drape_angle_deg = 90\n"),
                "fabric.toml:15: bend test 1: drape_angle_deg must be in (0, 90), got 90",
            ),
            (
                format!("{TOML}drape_angle_deg = 0\n"),
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
        let dir =
            std::env::temp_dir().join(format!("kshell-dataset-{}-roles-w", std::process::id()));
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
        assert!(w[0].to_string().ends_with("fabric.toml:20: warning: tensile test 2: curve warp-1.csv is also used by the test at line 9"), "{}", w[0]);
        let (_, w) = load("warn-empty", "name = \"x\"\nthickness_mm = 0.2\n", None).unwrap();
        assert!(w[0].message.contains("nothing to fit"), "{w:?}");
    }
}
