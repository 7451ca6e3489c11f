//! Reading a dataset: `fabric.toml` and the curve and OBJ files it names, checked and converted
//! to SI units, with the warnings and notes the reader collects on the way.

use super::curve::{parse_curve, Curve};
use super::known::read_known;
use super::thin::{thin, THINNING_TOLERANCE};
use super::{
    line_of, shape, BendTest, DatasetError, DatasetWarning, FabricDataset, RawBend, RawDataset,
    RawTensile, Role, TensileTest, Toml, AREAL_DENSITY_RANGE_G_M2, DEFAULT_DRAPE_ANGLE_DEG,
};
use crate::limits::{MAX_CURVE_POINTS, MAX_DATASET_TESTS};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use toml::Spanned;

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
    let floor = KN_FLOOR_N_PER_MM * width_mm;
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

/// The largest force a tensile curve reaching 1 % strain should carry per mm of strip width
/// (10 N per metre, 0.5 N on a 50 mm strip); below it the curve looks like kN.
const KN_FLOOR_N_PER_MM: f64 = 0.01;

/// Whether some tensile curve carries forces at or above the kN floor for its width: the
/// dataset's forces are then newtons. A testing machine writes every curve of a fabric in
/// one unit, and a fabric's curves differ by far more than the floor's margin: beside yarn
/// strips of tens of newtons, the bias strips of a soft-shear fabric (yarn-to-shear ratio
/// max(a11, a22)/G12 of 1e4 to 2.5e4) carry well under 0.5 N at 10 % strain.
fn some_force_in_newtons(tests: &[TensileTest]) -> bool {
    tests.iter().any(|t| {
        let fmax = t.force.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        !t.suspect_kn && fmax >= KN_FLOOR_N_PER_MM * t.width * 1e3
    })
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

/// The dataset's folder, and whether the files it names may lie outside it.
struct Folder<'a> {
    dir: &'a Path,
    allow_outside: bool,
}

impl Folder<'_> {
    /// Whether the file `p` (as written) is refused for lying outside the folder.
    fn refuses(&self, p: &Path) -> bool {
        let dir_or_here = if self.dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            self.dir
        };
        !self.allow_outside && (p.is_absolute() || !inside(dir_or_here, p))
    }
}

/// What reading the tests collects besides the tests: warnings, notes for the report, and each
/// curve file used so far with the line of the test that first used it.
#[derive(Default)]
struct Log {
    warnings: Vec<DatasetWarning>,
    notes: Vec<String>,
    used: HashMap<PathBuf, usize>,
}

/// Refuses a dataset of more than [`MAX_DATASET_TESTS`] tests, at the first table beyond it.
fn check_test_count(t: &Toml, raw: &RawDataset) -> Result<(), DatasetError> {
    let count = raw.tensile.len() + raw.bend.len() + raw.shape.len();
    if count <= MAX_DATASET_TESTS {
        return Ok(());
    }
    let mut starts: Vec<usize> = (raw.tensile.iter().map(|x| x.span().start))
        .chain(raw.bend.iter().map(|x| x.span().start))
        .chain(raw.shape.iter().map(|x| x.span().start))
        .collect();
    starts.sort_unstable();
    let first_over = starts[MAX_DATASET_TESTS];
    Err(t.err(
        first_over..first_over,
        format!("{count} tests ([[tensile]], [[bend]] and [[shape]] tables) are more than the {MAX_DATASET_TESTS} a dataset may hold (this is the first beyond it); split the dataset"),
    ))
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
    let t = Toml::new(&text, &file);
    check_test_count(&t, &raw)?;
    let folder = Folder {
        dir: path.parent().unwrap_or(Path::new("")),
        allow_outside,
    };
    let mut log = Log::default();
    let thickness = t.positive("", "thickness_mm", &raw.thickness_mm, 1e-3)?;
    let areal_density = match &raw.areal_density_g_m2 {
        Some(v) => Some(read_areal_density(&t, v)?),
        None => None,
    };
    let known = read_known(&t, raw.known.as_ref())?;
    let mut tensile = Vec::with_capacity(raw.tensile.len());
    for (i, spanned) in raw.tensile.iter().enumerate() {
        tensile.push(read_tensile(&t, &folder, i, spanned.get_ref(), &mut log)?);
    }
    // a curve that looks like kN keeps its warning; the fit refuses it only when no curve
    // of the dataset is plainly in newtons (see [`some_force_in_newtons`])
    if some_force_in_newtons(&tensile) {
        tensile.iter_mut().for_each(|t| t.suspect_kn = false);
    }
    let mut bend = Vec::with_capacity(raw.bend.len());
    for (i, spanned) in raw.bend.iter().enumerate() {
        bend.push(read_bend(
            &t,
            i,
            spanned,
            areal_density.is_some(),
            &mut log,
        )?);
    }
    let mut shapes = Vec::with_capacity(raw.shape.len());
    for (i, spanned) in raw.shape.iter().enumerate() {
        let obj = Path::new(spanned.get_ref().obj_path());
        if folder.refuses(obj) {
            return Err(t.err(
                spanned.span(),
                format!("shape {}: {} lies outside the dataset folder (an absolute path, `..` or a symbolic link out of it); pass --allow-outside to read it", i + 1, folder.dir.join(obj).display()),
            ));
        }
        shapes.push(shape::read_shape(&t, folder.dir, i, spanned)?);
    }
    let Log {
        mut warnings,
        notes,
        ..
    } = log;
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

/// `areal_density_g_m2` in kg/m²: finite and within [`AREAL_DENSITY_RANGE_G_M2`] (a value
/// far outside it is a typing or unit slip that would surface later as a failed cantilever).
fn read_areal_density(t: &Toml, v: &Spanned<f64>) -> Result<f64, DatasetError> {
    let rho = t.positive("", "areal_density_g_m2", v, 1e-3)?;
    let (lo, hi) = AREAL_DENSITY_RANGE_G_M2;
    let g_m2 = *v.get_ref();
    if !(lo..=hi).contains(&g_m2) {
        return Err(t.err(
            v.span(),
            format!(
                "areal_density_g_m2 must be in [{lo}, {hi}] g/m² (fabrics weigh about 10 to 1000), got {}: is it in g/m²?",
                crate::io::num(g_m2)
            ),
        ));
    }
    Ok(rho)
}

/// Reads one `[[tensile]]` entry (number `i` from 0) and its curve file.
fn read_tensile(
    t: &Toml,
    folder: &Folder,
    i: usize,
    r: &RawTensile,
    log: &mut Log,
) -> Result<TensileTest, DatasetError> {
    let what = format!("tensile test {}: ", i + 1);
    let angle_deg = t.angle(&what, &r.angle_deg)?;
    let width = t.positive(&what, "width_mm", &r.width_mm, 1e-3)?;
    let gauge_length = t.positive(&what, "gauge_length_mm", &r.gauge_length_mm, 1e-3)?;
    let curve = PathBuf::from(r.curve.get_ref());
    let csv_path = folder.dir.join(&curve);
    let csv_name = csv_path.display().to_string();
    if folder.refuses(&curve) {
        return Err(t.err(
            r.curve.span(),
            format!("{what}curve {csv_name} lies outside the dataset folder (an absolute path, `..` or a symbolic link out of it); pass --allow-outside to read it"),
        ));
    }
    let columns = read_columns(t, &what, &r.columns)?;
    let role = read_role(t, &what, &r.role)?;
    let force_scale = match &r.force_scale {
        Some(v) => t.positive(&what, "force_scale", v, 1.0)?,
        None => 1.0,
    };
    let toe = read_toe(t, &what, &r.toe_mm, gauge_length)?;
    let csv = read_curve_file(&csv_path).map_err(|m| {
        t.err(
            r.curve.span(),
            format!("{what}cannot read curve file {csv_name}: {m}"),
        )
    })?;
    let mut c = parse_curve(&csv, &csv_name, columns.as_ref())?;
    c.force_n.iter_mut().for_each(|f| *f *= force_scale);
    let before = log.warnings.len();
    curve_warnings(
        &c,
        width * 1e3,
        gauge_length * 1e3,
        &csv_name,
        &mut log.warnings,
    );
    let suspect_kn = r.force_scale.is_none()
        && log.warnings[before..]
            .iter()
            .any(|w| w.message.contains("are the forces in kN?"));
    curve_notes(&c, &csv_name, force_scale, &mut log.notes);
    let line = t.line(r.curve.span().start);
    thin_long_curve(&mut c, &what, &csv_name, t.file, line, log);
    if let Some(first) = log.used.get(&curve) {
        log.warnings.push(DatasetWarning {
            file: t.file.to_string(),
            line: Some(line),
            message: format!(
                "{what}curve {} is also used by the test at line {first}",
                curve.display()
            ),
        });
    } else {
        log.used.insert(curve.clone(), line);
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
    Ok(test)
}

/// Thins a curve of more than [`MAX_CURVE_POINTS`] points to those that follow it within
/// [`THINNING_TOLERANCE`] of its force range, with a warning (the test's `line` in `file`) and
/// a note saying how many were kept.
fn thin_long_curve(
    c: &mut Curve,
    what: &str,
    csv_name: &str,
    file: &str,
    line: usize,
    log: &mut Log,
) {
    let n = c.lines.len();
    if n <= MAX_CURVE_POINTS {
        return;
    }
    let (lo, hi) = c
        .force_n
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &f| {
            (lo.min(f), hi.max(f))
        });
    let keep = thin(&c.elongation_mm, &c.force_n, THINNING_TOLERANCE * (hi - lo));
    let pick = |v: &[f64]| keep.iter().map(|&i| v[i]).collect::<Vec<f64>>();
    c.elongation_mm = pick(&c.elongation_mm);
    c.force_n = pick(&c.force_n);
    c.lines = keep.iter().map(|&i| c.lines[i]).collect();
    let pct = 100.0 * THINNING_TOLERANCE;
    let mut message = format!(
        "{what}curve {csv_name} has {n} points, more than the {MAX_CURVE_POINTS} a fit takes as they are: thinned to the {} points that follow it within {pct} % of its force range",
        keep.len()
    );
    if keep.len() > MAX_CURVE_POINTS {
        message.push_str(&format!(
            " (its scatter exceeds {pct} % of the force range, so many remain and the fit is slow: average or smooth the curve)"
        ));
    }
    log.notes.push(format!(
        "{csv_name}: {n} points thinned to {} (within {pct} % of the force range)",
        keep.len()
    ));
    log.warnings.push(DatasetWarning {
        file: file.to_string(),
        line: Some(line),
        message,
    });
}

/// A tensile test's `columns`: the names of its elongation and force columns, when given.
fn read_columns(
    t: &Toml,
    what: &str,
    columns: &Option<Spanned<Vec<String>>>,
) -> Result<Option<[String; 2]>, DatasetError> {
    match columns {
        None => Ok(None),
        Some(c) => match c.get_ref().as_slice() {
            [a, b] => Ok(Some([a.clone(), b.clone()])),
            _ => Err(t.err(
                c.span(),
                format!("{what}columns must name two columns: [elongation, force]"),
            )),
        },
    }
}

/// A tensile test's `role`, when given.
fn read_role(
    t: &Toml,
    what: &str,
    role: &Option<Spanned<String>>,
) -> Result<Option<Role>, DatasetError> {
    match role {
        None => Ok(None),
        Some(v) => match v.get_ref().as_str() {
            "fit" => Ok(Some(Role::Fit)),
            "validation" => Ok(Some(Role::Validation)),
            other => Err(t.err(
                v.span(),
                format!("{what}role must be \"fit\" or \"validation\", got {other:?}"),
            )),
        },
    }
}

/// A tensile test's `toe_mm` in metres, when given; `gauge_length` in metres.
fn read_toe(
    t: &Toml,
    what: &str,
    toe_mm: &Option<Spanned<f64>>,
    gauge_length: f64,
) -> Result<Option<f64>, DatasetError> {
    match toe_mm {
        None => Ok(None),
        Some(v) => {
            let x = *v.get_ref();
            if !x.is_finite() || x.abs() >= gauge_length * 1e3 {
                return Err(t.err(
                    v.span(),
                    format!("{what}toe_mm must be a finite number smaller than the gauge length (negative for a preload), got {x:?}"),
                ));
            }
            Ok(Some(x * 1e-3))
        }
    }
}

/// The report's notes on how a curve file is read: averaged repeats, converted units, scaled
/// forces.
fn curve_notes(c: &Curve, csv_name: &str, force_scale: f64, notes: &mut Vec<String>) {
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
}

/// Reads one `[[bend]]` entry (number `i` from 0); `has_density`: whether the dataset gives the
/// areal density a bend test needs.
fn read_bend(
    t: &Toml,
    i: usize,
    spanned: &Spanned<RawBend>,
    has_density: bool,
    log: &mut Log,
) -> Result<BendTest, DatasetError> {
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
            log.notes.push(format!("warning: {message}"));
            log.warnings.push(DatasetWarning {
                file: t.file.to_string(),
                line: Some(t.line(spanned.span().start)),
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
    if !has_density {
        return Err(t.err(
            spanned.span(),
            format!(
                "{what}a bend test needs areal_density_g_m2 (the strip bends under its own weight)"
            ),
        ));
    }
    Ok(BendTest {
        angle_deg,
        width,
        overhang,
        drape_angle_deg,
    })
}
