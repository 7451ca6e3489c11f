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
//! gauge length, overhang, thickness or areal density, an areal density outside
//! [`AREAL_DENSITY_RANGE_G_M2`], a bend test without areal density, an angle outside
//! [0°, 180°), a drape angle outside (0°, 90°), a curve without data rows, more tests than
//! [`crate::limits::MAX_DATASET_TESTS`], a curve of more points than
//! [`crate::limits::MAX_CURVE_ROWS`].
//!
//! A curve of more than [`crate::limits::MAX_CURVE_POINTS`] points is thinned to those that
//! follow it within [`THINNING_TOLERANCE`] of its force range (see `thin`), with a warning.
//!
//! Warnings (legal but suspicious): a curve with one point; a strain above 100 %; forces that
//! look like kN: the largest force is below 10 N per metre of width (0.5 N on a 50 mm strip)
//! although the curve reaches 1 % strain (woven fabrics carry tens to hundreds of newtons
//! there); a curve file used by two tests; a dataset with no tests.

mod curve;
mod known;
mod load;
mod shape;
mod thin;
mod write;

pub use load::{load_dataset, load_dataset_with};
use serde::Deserialize;
pub use shape::{Descriptor, ShapeScene, ShapeTest};
use std::fmt;
use std::ops::Range;
use std::path::PathBuf;
pub use thin::THINNING_TOLERANCE;
use toml::Spanned;
pub use write::{curve_csv, dataset_toml, write_dataset, write_dataset_with_comment};

/// The drape angle of ASTM D1388 (tan⁻¹ 0.5 ≈ 26.6° is the other convention; we use 41.5°).
pub const DEFAULT_DRAPE_ANGLE_DEG: f64 = 41.5;

/// Areal densities a dataset may give, g/m²: from the lightest nonwovens and tissues to the
/// heaviest canvases and carpets, with room on both sides.
pub const AREAL_DENSITY_RANGE_G_M2: (f64, f64) = (1.0, 5000.0);

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
    /// the forces look like kN (tiny for the strip's width), no `force_scale` is given and no
    /// curve of the dataset carries forces plainly in newtons: the fit refuses the test
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
    /// The files the dataset comes from: its `fabric.toml`, each tensile curve and each
    /// `[[shape]]` OBJ (the latter two joined to the TOML's folder, as they were read). A
    /// command that writes counts all of them as its inputs.
    pub fn files(&self) -> Vec<PathBuf> {
        let dir = self.path.parent().unwrap_or(std::path::Path::new(""));
        let curves = self.tensile.iter().map(|t| dir.join(&t.curve));
        let objs = self.shapes.iter().map(|sh| dir.join(&sh.obj));
        std::iter::once(self.path.clone())
            .chain(curves)
            .chain(objs)
            .collect()
    }

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
    /// byte offsets of the text's newlines, so that a line is found by bisection (a dataset
    /// of many tables is read in time linear in its size)
    newlines: Vec<usize>,
}

impl<'a> Toml<'a> {
    fn new(text: &'a str, file: &'a str) -> Self {
        let newlines = text.match_indices('\n').map(|(i, _)| i).collect();
        Toml {
            text,
            file,
            newlines,
        }
    }

    /// As [`line_of`] on the text.
    fn line(&self, at: usize) -> usize {
        let at = at.min(self.text.len());
        let skip = self.text.get(at..).map_or(0, |rest| {
            let trimmed = rest.trim_start();
            rest.len() - trimmed.len()
        });
        let end = (at + skip).min(self.text.len());
        self.newlines.partition_point(|&p| p < end) + 1
    }

    fn err(&self, span: Range<usize>, message: String) -> DatasetError {
        DatasetError {
            file: self.file.to_string(),
            line: Some(self.line(span.start)),
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

#[cfg(test)]
mod tests;
