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
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTensile {
    angle_deg: Spanned<f64>,
    width_mm: Spanned<f64>,
    gauge_length_mm: Spanned<f64>,
    curve: Spanned<String>,
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
    /// N, non-negative
    pub force: Vec<f64>,
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
    /// Whether the staged fit uses this test (0°, 45°, 90°); other angles validate the fit.
    pub fn is_fitted(&self) -> bool {
        FITTED_ANGLES_DEG
            .iter()
            .any(|a| (self.angle_deg - a).abs() < 1e-9)
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

/// A curve in lab units with each row's line.
struct Curve {
    elongation_mm: Vec<f64>,
    force_n: Vec<f64>,
    lines: Vec<usize>,
}

/// Parses curve CSV; `file` names it in errors.
fn parse_curve(text: &str, file: &str) -> Result<Curve, DatasetError> {
    let err = |line: usize, message: String| DatasetError {
        file: file.to_string(),
        line: Some(line),
        message,
    };
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut rows = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((header_line, header)) = rows.next() else {
        return Err(err(
            1,
            format!("empty curve file: expected the header `{CURVE_HEADER}`"),
        ));
    };
    let fields: Vec<&str> = header.split(',').map(str::trim).collect();
    if fields != ["elongation_mm", "force_n"] {
        return Err(err(
            header_line,
            format!("the header must be `{CURVE_HEADER}`, got `{header}`"),
        ));
    }
    let columns = ["elongation_mm", "force_n"];
    let mut c = Curve {
        elongation_mm: Vec::new(),
        force_n: Vec::new(),
        lines: Vec::new(),
    };
    for (line, row) in rows {
        let fields: Vec<&str> = row.split(',').map(str::trim).collect();
        if fields.len() != 2 {
            return Err(err(
                line,
                format!(
                    "expected 2 columns ({CURVE_HEADER}), got {}: `{row}`",
                    fields.len()
                ),
            ));
        }
        let mut v = [0.0; 2];
        for (k, (field, name)) in fields.iter().zip(columns).enumerate() {
            let col = k + 1;
            if field.is_empty() {
                return Err(err(line, format!("column {col} ({name}) is empty")));
            }
            let x: f64 = field.parse().map_err(|_| {
                err(
                    line,
                    format!("column {col} ({name}): `{field}` is not a number"),
                )
            })?;
            if !x.is_finite() {
                return Err(err(
                    line,
                    format!("column {col} ({name}) must be finite, got {field}"),
                ));
            }
            if x < 0.0 {
                return Err(err(
                    line,
                    format!("column {col} ({name}) must not be negative, got {field}"),
                ));
            }
            v[k] = x;
        }
        if let Some(&prev) = c.elongation_mm.last() {
            if v[0] <= prev {
                return Err(err(
                    line,
                    format!(
                        "column 1 (elongation_mm) = {} does not exceed the previous row's {prev}: elongation must increase strictly",
                        v[0]
                    ),
                ));
            }
        }
        c.elongation_mm.push(v[0]);
        c.force_n.push(v[1]);
        c.lines.push(line);
    }
    if c.lines.is_empty() {
        return Err(err(header_line, "no data rows after the header".into()));
    }
    Ok(c)
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
        let csv = std::fs::read_to_string(&csv_path).map_err(|e| {
            t.err(
                r.curve.span(),
                format!("{what}cannot read curve file {csv_name}: {e}"),
            )
        })?;
        let c = parse_curve(&csv, &csv_name)?;
        curve_warnings(
            &c,
            width * 1e3,
            gauge_length * 1e3,
            &csv_name,
            &mut warnings,
        );
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
        tensile.push(TensileTest {
            angle_deg,
            width,
            gauge_length,
            curve,
            elongation: c.elongation_mm.iter().map(|e| e * 1e-3).collect(),
            force: c.force_n,
        });
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

/// The CSV text of one curve (lab units, every number written to round-trip).
pub fn curve_csv(t: &TensileTest) -> String {
    let mut s = format!("{CURVE_HEADER}\n");
    for (e, f) in t.elongation.iter().zip(&t.force) {
        s.push_str(&format!("{:?},{:?}\n", e * 1e3, f));
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
                "elongation_mm,force_n\n1,2\n\n1,3\n",
                "warp-1.csv:4: column 1 (elongation_mm) = 1 does not exceed the previous row's 1",
            ),
            (
                "elongation_mm,force_n\n2,2\n1,3\n",
                "warp-1.csv:3: column 1 (elongation_mm) = 1 does not exceed",
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
