//! Reading one force–elongation curve as labs export it.
//!
//! The plain format is `elongation_mm,force_n` and one row per point. Testing machines add
//! metadata lines above the header, quote their headers and put the units there
//! (`"Extension (mm)","Load (N)"`), and in many locales separate fields with semicolons and
//! write decimal commas. The reader (the `csv` crate, for quoting) accepts all of these:
//! - the separator is `;` when the file has one (then `,` is a decimal comma), else a tab when
//!   it has one, else `,`;
//! - lines above the header are metadata and skipped; the header is the first row naming an
//!   elongation column (elongation, extension, displacement, deformation, stroke) and a force
//!   column (force, load), or the two names given by the dataset's `columns` key; other columns
//!   (time, strain…) are ignored;
//! - units come from the header: `(mm)`, `[mm]` or a `_mm` suffix; elongation in mm, cm, m or
//!   in, force in N, cN, mN, kN or lbf; a column without a unit is an error.
//!
//! Rows with the same elongation (an extensometer's resolution) are averaged, with a note;
//! an elongation that decreases is an error. Forces may dip below zero by noise (within 1 % of
//! the largest force); anything more negative is an error.

use super::{DatasetError, CURVE_HEADER};
use crate::limits::{MAX_CURVE_POINTS, MAX_CURVE_ROWS};

/// A curve in lab units (mm, N) with each row's line.
pub(super) struct Curve {
    pub elongation_mm: Vec<f64>,
    pub force_n: Vec<f64>,
    pub lines: Vec<usize>,
    /// rows folded into the preceding row because their elongation repeats it
    pub duplicates: usize,
    /// the header's units, when not the plain format's (for the notes)
    pub units: Option<String>,
}

/// One header column we know how to read: its index and the factor to mm or N.
#[derive(Clone, Copy)]
struct Column {
    index: usize,
    scale: f64,
}

const ELONGATION_WORDS: [&str; 6] = ["elong", "extens", "displac", "deform", "stroke", "extensi"];
const FORCE_WORDS: [&str; 2] = ["force", "load"];

/// The unit written in a header field: `Load (N)`, `Load [N]`, `force_n`, `Load N`.
fn unit_of(field: &str) -> Option<String> {
    let f = field.trim();
    for (open, close) in [('(', ')'), ('[', ']')] {
        if let (Some(a), Some(b)) = (f.rfind(open), f.rfind(close)) {
            if a < b {
                return Some(f[a + 1..b].trim().to_lowercase());
            }
        }
    }
    f.rsplit(['_', ' '])
        .next()
        .filter(|u| u.len() < f.len())
        .map(|u| u.trim().to_lowercase())
}

fn length_scale(unit: &str) -> Option<f64> {
    match unit {
        "mm" => Some(1.0),
        "cm" => Some(10.0),
        "m" => Some(1000.0),
        "in" | "inch" | "inches" | "\"" => Some(25.4),
        _ => None,
    }
}

fn force_scale(unit: &str) -> Option<f64> {
    match unit {
        "n" => Some(1.0),
        "cn" => Some(1e-2),
        "mn" => Some(1e-3),
        "kn" => Some(1e3),
        "lbf" | "lb" | "lbs" => Some(4.448_221_615_260_5),
        _ => None,
    }
}

/// What a header row says, if it is one: `Ok(None)` when the row names no elongation and
/// force columns; an error when it names them without usable units.
fn header_columns(
    fields: &[String],
    named: Option<&[String; 2]>,
) -> Result<Option<(Column, Column, String)>, String> {
    let lower: Vec<String> = fields.iter().map(|f| f.trim().to_lowercase()).collect();
    let find = |pred: &dyn Fn(&str) -> bool| lower.iter().position(|f| pred(f));
    let (ie, iforce) = match named {
        Some([e, f]) => {
            let (e, f) = (e.trim().to_lowercase(), f.trim().to_lowercase());
            match (find(&|x| x == e), find(&|x| x == f)) {
                (Some(a), Some(b)) => (a, b),
                _ => return Ok(None),
            }
        }
        None => {
            let ie = find(&|x| ELONGATION_WORDS.iter().any(|w| x.contains(w)));
            let iforce = find(&|x| FORCE_WORDS.iter().any(|w| x.contains(w)));
            match (ie, iforce) {
                (Some(a), Some(b)) if a != b => (a, b),
                _ => return Ok(None),
            }
        }
    };
    let unit = |i: usize, what: &str, conv: fn(&str) -> Option<f64>| {
        let name = fields[i].trim();
        match unit_of(name) {
            Some(u) => {
                conv(&u).ok_or_else(|| format!("column `{name}`: unknown {what} unit `{u}`"))
            }
            None => Err(format!("column `{name}` has no unit")),
        }
        .map(|scale| Column { index: i, scale })
    };
    let e = unit(ie, "length (mm, cm, m, in)", length_scale);
    let f = unit(iforce, "force (N, cN, mN, kN, lbf)", force_scale);
    match (e, f) {
        (Ok(e), Ok(f)) => {
            let units = format!("`{}`, `{}`", fields[ie].trim(), fields[iforce].trim());
            Ok(Some((e, f, units)))
        }
        (Err(m), _) | (_, Err(m)) => Err(m),
    }
}

/// The field separator: `;` if the text has one, else a tab if it has one, else `,`.
fn separator(text: &str) -> u8 {
    let sample: String = text.lines().take(200).collect();
    if sample.contains(';') {
        b';'
    } else if sample.contains('\t') {
        b'\t'
    } else {
        b','
    }
}

/// A short, printable excerpt of a line for messages (never a whole foreign file's line).
fn excerpt(s: &str) -> String {
    let clean: String = s.chars().filter(|c| !c.is_control()).take(60).collect();
    if s.chars().count() > 60 {
        format!("{clean}…")
    } else {
        clean
    }
}

/// Parses curve CSV; `file` names it in errors; `named` is the dataset's `columns` key.
pub(super) fn parse_curve(
    text: &str,
    file: &str,
    named: Option<&[String; 2]>,
) -> Result<Curve, DatasetError> {
    let err = |line: usize, message: String| DatasetError {
        file: file.to_string(),
        line: Some(line),
        message,
    };
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let sep = separator(text);
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .delimiter(sep)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let mut header: Option<(Column, Column, usize, String)> = None;
    let mut first: Option<(usize, String)> = None;
    let mut pending: Option<(usize, String)> = None;
    let mut c = Curve {
        elongation_mm: Vec::new(),
        force_n: Vec::new(),
        lines: Vec::new(),
        duplicates: 0,
        units: None,
    };
    let mut header_text = String::new();
    // rows averaged into the last kept row
    let mut run = 1usize;
    let mut header_line = 1;
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(1, |p| p.line() as usize);
            err(line, format!("not readable as CSV: {e}"))
        })?;
        let line = record.position().map_or(1, |p| p.line() as usize);
        let fields: Vec<String> = record.iter().map(|s| s.to_string()).collect();
        if fields.iter().all(|f| f.is_empty()) {
            continue;
        }
        let Some((e, f, ncols, _)) = &header else {
            first.get_or_insert((line, fields.join(",")));
            let is_data = fields.iter().all(|f| number(f, sep).is_some());
            match header_columns(&fields, named) {
                Ok(Some((e, f, units))) => {
                    header_text = fields.join(",");
                    header_line = line;
                    header = Some((e, f, fields.len(), units));
                    continue;
                }
                // a metadata line naming the columns without units ("Load cell: 1 kN"):
                // an error only if no better header follows ahead of the data
                Err(m) if !is_data => {
                    pending.get_or_insert((line, m));
                    continue;
                }
                Ok(None) if !is_data => continue, // metadata above the header
                _ => {}
            }
            if let Some((l, m)) = pending.take() {
                return Err(err(
                    l,
                    format!("the header must be `{CURVE_HEADER}` or name an elongation and a force column with units, e.g. `\"Extension (mm)\",\"Load (N)\"`: {m}"),
                ));
            }
            let (fl, fs) = first.clone().unwrap_or((line, String::new()));
            let want = match named {
                Some([a, b]) => format!("the columns `{a}` and `{b}` named by `columns`"),
                None => format!("`{CURVE_HEADER}`, or an elongation and a force column with units (e.g. `\"Extension (mm)\",\"Load (N)\"`)"),
            };
            return Err(err(
                fl,
                format!("the header must be {want}, got `{}`", excerpt(&fs)),
            ));
        };
        if fields.len() != *ncols {
            return Err(err(
                line,
                format!(
                    "expected {ncols} columns ({}), got {}: `{}`",
                    excerpt(&header_text),
                    fields.len(),
                    excerpt(&fields.join(","))
                ),
            ));
        }
        let mut v = [0.0; 2];
        for (k, col) in [e, f].into_iter().enumerate() {
            let name = if k == 0 { "elongation_mm" } else { "force_n" };
            let field = &fields[col.index];
            let n = col.index + 1;
            if field.is_empty() {
                return Err(err(line, format!("column {n} ({name}) is empty")));
            }
            let x = number(field, sep).ok_or_else(|| {
                err(
                    line,
                    format!("column {n} ({name}): `{}` is not a number", excerpt(field)),
                )
            })?;
            if !x.is_finite() {
                return Err(err(
                    line,
                    format!("column {n} ({name}) must be finite, got {field}"),
                ));
            }
            v[k] = x * col.scale;
        }
        if v[0] < 0.0 {
            return Err(err(
                line,
                format!(
                    "column {} (elongation_mm) must not be negative, got {}",
                    e.index + 1,
                    fields[e.index]
                ),
            ));
        }
        if let Some(&prev) = c.elongation_mm.last() {
            if v[0] < prev {
                return Err(err(
                    line,
                    format!(
                        "column {} (elongation_mm) = {} is below the previous row's {prev}: elongation must not decrease",
                        e.index + 1,
                        fields[e.index]
                    ),
                ));
            }
            if v[0] == prev {
                // an extensometer's resolution: average the forces at one elongation
                let n = c.elongation_mm.len();
                run += 1;
                c.force_n[n - 1] += (v[1] - c.force_n[n - 1]) / run as f64;
                c.duplicates += 1;
                continue;
            }
        }
        if c.lines.len() == MAX_CURVE_ROWS {
            return Err(err(
                line,
                format!("the curve has more than {MAX_CURVE_ROWS} points (rows of distinct elongation); decimate it (a fit thins a curve above {MAX_CURVE_POINTS} points to the points that follow it within 0.1 % of its force range)"),
            ));
        }
        c.elongation_mm.push(v[0]);
        c.force_n.push(v[1]);
        c.lines.push(line);
        run = 1;
    }
    let Some((_, f, _, units)) = header else {
        if let Some((l, m)) = pending {
            return Err(err(
                l,
                format!("the header must be `{CURVE_HEADER}` or name an elongation and a force column with units, e.g. `\"Extension (mm)\",\"Load (N)\"`: {m}"),
            ));
        }
        return Err(match first {
            None => err(
                1,
                format!("empty curve file: expected the header `{CURVE_HEADER}`"),
            ),
            Some((l, s)) => err(
                l,
                format!(
                    "the header must be `{CURVE_HEADER}`, or an elongation and a force column with units (e.g. `\"Extension (mm)\",\"Load (N)\"`), got `{}`",
                    excerpt(&s)
                ),
            ),
        });
    };
    if c.lines.is_empty() {
        return Err(err(header_line, "no data rows after the header".into()));
    }
    let fmax = c.force_n.iter().copied().fold(0.0, f64::max);
    if fmax <= 0.0 && c.force_n.iter().all(|&x| x == 0.0) {
        return Err(err(
            header_line,
            format!(
                "column {} (force_n): every force is zero: nothing to fit (is it the force column?)",
                f.index + 1
            ),
        ));
    }
    if let Some(i) = c
        .force_n
        .iter()
        .position(|&x| x < -0.01 * fmax || (x < 0.0 && fmax == 0.0))
    {
        return Err(err(
            c.lines[i],
            format!(
                "column {} (force_n) must not be negative, got {} (noise within 1 % of the largest force is tolerated)",
                f.index + 1,
                c.force_n[i] / f.scale
            ),
        ));
    }
    if let Some((i, why)) = corrupt_point(&c.force_n) {
        return Err(err(
            c.lines[i],
            format!(
                "column {} (force_n) = {:?} N {why}: a corrupt value? remove or fix the row",
                f.index + 1,
                c.force_n[i]
            ),
        ));
    }
    if header_text.replace(' ', "") != CURVE_HEADER {
        c.units = Some(units);
    }
    Ok(c)
}

/// Largest force a strip test can report, N (100 tonnes: no fabric strip comes near it).
pub const MAX_FORCE_N: f64 = 1e6;

/// A force no strip test can give: above [`MAX_FORCE_N`], or an isolated spike more than ten
/// times every other force of a curve of at least five points (one corrupt value would
/// otherwise be the whole objective: its squared relative error swamps the rest).
fn corrupt_point(force: &[f64]) -> Option<(usize, String)> {
    if let Some(i) = force.iter().position(|x| x.abs() > MAX_FORCE_N) {
        return Some((i, format!("is beyond {MAX_FORCE_N:e} N")));
    }
    if force.len() < 5 {
        return None;
    }
    let (imax, fmax) = force
        .iter()
        .copied()
        .enumerate()
        .fold((0, f64::MIN), |a, b| if b.1 > a.1 { b } else { a });
    let others = force
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != imax)
        .map(|(_, &x)| x)
        .fold(0.0, f64::max);
    (others > 0.0 && fmax > 10.0 * others).then(|| {
        (
            imax,
            format!("is more than ten times every other force ({others:?} N at most)"),
        )
    })
}

/// A number, with a decimal comma when fields are separated by semicolons.
fn number(field: &str, sep: u8) -> Option<f64> {
    let f = field.trim();
    if sep == b';' && f.contains(',') && !f.contains('.') {
        f.replace(',', ".").parse().ok()
    } else {
        f.parse().ok()
    }
}
