//! The `[model]` table of a material file: a triangle model's parameters, lab-free SI units in
//! the key names.
//!
//! ```toml
//! name = "cotton"
//! areal_density_g_m2 = 103.6
//! [model]
//! kind = "stvk-ds"                   # springs, soft-constraints, stvk-ds or xpbd
//! stretch_warp_n_per_m = [30600.0]   # one value: linear; several: a spline k(ε)
//! stretch_weft_n_per_m = [18000.0, 21000.0, 26000.0]
//! stretch_weft_range = [0.0, 0.05]   # the strain range of a spline (needed with several values)
//! shear_n_per_m = [364.0]
//! bend_warp_n_m = [8.3e-5]           # plate rigidity, N·m; curvature ranges in 1/m
//! bend_weft_n_m = [5.0e-5]
//! bend_diag_n_m = [6.4e-5]
//! coupling_n_per_m = 0.0             # xpbd only: the Poisson coupling C₀₁
//! ```
//!
//! The springs model's bending springs have a spring strain, so its bending keys are
//! `bend_warp_n_per_m` and so on. A file with a `[model]` table needs no shell law; a file
//! without one gives any model through [`TriMaterial::equivalent`] (the shell's zero-strain
//! moduli). Unknown keys, missing components and non-positive values are errors naming the
//! file, the line and the key.

use super::curve::Stiffness;
use super::params::{TriKind, TriMaterial, COMPONENTS};
pub use crate::material::file::model_only;
use crate::material::file::{line_of_key, parse_material};
use crate::material::{FabricMaterial, MaterialFileError};

/// Where a triangle model's parameters come from.
#[derive(Clone, Debug)]
pub enum TriSource {
    /// A `[model]` table.
    Table(TriMaterial),
    /// A shell material, converted on use (the springs' bending depends on the grid spacing).
    Shell(FabricMaterial),
}

impl TriSource {
    /// The parameters for a grid of spacing `cell` (m).
    pub fn material(&self, kind: TriKind, cell: f64) -> Result<TriMaterial, String> {
        match self {
            TriSource::Table(m) => Ok(m.clone()),
            TriSource::Shell(m) => TriMaterial::equivalent(kind, m, cell, SPRING_CURVATURE),
        }
    }
}

/// Curvature (1/m) at which the springs' bending energy is matched to the plate's when a
/// shell material is converted (a 1 cm radius: a cantilever's or a fold's).
pub const SPRING_CURVATURE: f64 = 100.0;

/// Key suffix of component `c` of `kind`.
fn unit(kind: TriKind, c: usize) -> &'static str {
    if c >= 3 && kind != TriKind::Springs {
        "_n_m"
    } else {
        "_n_per_m"
    }
}

/// Reads a material file's parameters for model `kind`.
pub fn parse_tri(text: &str, path: &str, kind: TriKind) -> Result<TriSource, MaterialFileError> {
    let err = |key: &str, message: String| MaterialFileError {
        path: path.to_string(),
        line: line_of_key(text, Some("model"), key),
        message,
    };
    let value: toml::Value = toml::from_str(text).map_err(|e| MaterialFileError {
        path: path.to_string(),
        line: e
            .span()
            .map(|s| crate::material::file::line_of(text, s.start)),
        message: e.message().trim().replace('\n', " "),
    })?;
    let Some(table) = value.get("model").and_then(|m| m.as_table()) else {
        return parse_material(text, path).map(TriSource::Shell);
    };
    let named = table.get("kind").and_then(|k| k.as_str()).ok_or_else(|| {
        err(
            "kind",
            "[model] needs kind = \"springs\" (or soft-constraints, stvk-ds, xpbd)".into(),
        )
    })?;
    let file_kind: TriKind = named.parse().map_err(|e: String| err("kind", e))?;
    if file_kind != kind {
        return Err(err(
            "kind",
            format!(
                "this file holds a {named} model; it cannot be used as {} (run with --model {named})",
                kind.name()
            ),
        ));
    }
    let density = value
        .get("areal_density_g_m2")
        .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
        .filter(|v| v.is_finite() && *v > 0.0)
        .ok_or_else(|| MaterialFileError {
            path: path.to_string(),
            line: line_of_key(text, None, "areal_density_g_m2"),
            message: "areal_density_g_m2 must be a positive number".into(),
        })?;
    let number = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
    let numbers = |key: &str| -> Result<Option<Vec<f64>>, MaterialFileError> {
        match table.get(key) {
            None => Ok(None),
            Some(v) => v
                .as_array()
                .and_then(|a| a.iter().map(number).collect::<Option<Vec<f64>>>())
                .map(Some)
                .ok_or_else(|| err(key, format!("{key} must be an array of numbers"))),
        }
    };
    let mut known = vec!["kind".to_string(), "coupling_n_per_m".to_string()];
    let mut curves = Vec::new();
    for (c, name) in COMPONENTS.iter().enumerate() {
        let key = format!("{name}{}", unit(kind, c));
        let range_key = format!("{name}_range");
        known.push(key.clone());
        known.push(range_key.clone());
        let values =
            numbers(&key)?.ok_or_else(|| err("kind", format!("[model] is missing {key}")))?;
        let (lo, hi) = match numbers(&range_key)? {
            Some(r) if r.len() == 2 => (r[0], r[1]),
            Some(_) => return Err(err(&range_key, format!("{range_key} must be [lo, hi]"))),
            None if values.len() > 1 => {
                return Err(err(
                    &key,
                    format!("{key} has several values: give {range_key} = [lo, hi]"),
                ))
            }
            None => (0.0, 1.0),
        };
        curves
            .push(Stiffness::spline(lo, hi, values).map_err(|e| err(&key, format!("{key}: {e}")))?);
    }
    if let Some(bad) = table.keys().find(|k| !known.contains(k)) {
        return Err(err(
            bad,
            format!("unknown key {bad} in [model] of a {} model", kind.name()),
        ));
    }
    let coupling = match table.get("coupling_n_per_m") {
        None => 0.0,
        Some(v) => number(v).filter(|v| v.is_finite()).ok_or_else(|| {
            err(
                "coupling_n_per_m",
                "coupling_n_per_m must be a number".into(),
            )
        })?,
    };
    if coupling != 0.0 && kind != TriKind::Xpbd {
        return Err(err(
            "coupling_n_per_m",
            "only the xpbd model has a Poisson coupling".into(),
        ));
    }
    let curves: [Stiffness; 6] = curves.try_into().expect("six components");
    Ok(TriSource::Table(TriMaterial {
        kind,
        curves,
        coupling,
        areal_density: density * 1e-3,
    }))
}

/// Reads a material file for model `kind`.
pub fn load_tri(path: &std::path::Path, kind: TriKind) -> Result<TriSource, MaterialFileError> {
    let name = path.display().to_string();
    let text = crate::io::read_text(path, 16 << 20).map_err(|e| MaterialFileError {
        path: name.clone(),
        line: None,
        message: format!("cannot read file: {e}"),
    })?;
    parse_tri(&text, &name, kind)
}

/// The material file text of a triangle model (read back by [`parse_tri`]).
pub fn tri_toml(name: &str, m: &TriMaterial) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(s, "name = {name:?}");
    let _ = writeln!(s, "areal_density_g_m2 = {:?}", m.areal_density * 1e3);
    let _ = writeln!(s, "\n[model]\nkind = {:?}", m.kind.name());
    for (c, name) in COMPONENTS.iter().enumerate() {
        let curve = &m.curves[c];
        let _ = writeln!(s, "{name}{} = {:?}", unit(m.kind, c), curve.k);
        if curve.k.len() > 1 {
            let _ = writeln!(s, "{name}_range = [{:?}, {:?}]", curve.lo, curve.hi);
        }
    }
    if m.kind == TriKind::Xpbd {
        let _ = writeln!(s, "coupling_n_per_m = {:?}", m.coupling);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_round_trip_and_errors_name_the_line() {
        let shell = "name = \"x\"\nareal_density_g_m2 = 100.0\nthickness_mm = 0.2\na11_pa = 2e8\na22_pa = 1e8\ng12_pa = 4e6\n";
        let eq = match parse_tri(shell, "f", TriKind::StvkDs).unwrap() {
            TriSource::Shell(m) => {
                TriMaterial::equivalent(TriKind::StvkDs, &m, 0.005, 100.0).unwrap()
            }
            TriSource::Table(_) => panic!("no table"),
        };
        let mut m = eq.clone();
        m.curves[1] = Stiffness::spline(0.0, 0.05, vec![1.0e4, 2.0e4, 2.5e4]).unwrap();
        let text = tri_toml("x", &m);
        match parse_tri(&text, "f", TriKind::StvkDs).unwrap() {
            TriSource::Table(back) => assert_eq!(back, m),
            TriSource::Shell(_) => panic!("a table"),
        }
        // the shell reader refuses a model-only file, pointing at the model
        let e = parse_material(&text, "f").unwrap_err();
        assert!(
            e.message.contains("--model stvk-ds") && e.line == Some(5),
            "{e}"
        );
        // another kind, a missing component, an unknown key
        let e = parse_tri(&text, "f", TriKind::Springs).unwrap_err();
        assert!(e.message.contains("--model stvk-ds"), "{e}");
        let e = parse_tri(
            &text.replace("shear_n_per_m", "shear_x"),
            "f",
            TriKind::StvkDs,
        )
        .unwrap_err();
        assert!(e.message.contains("missing shear_n_per_m"), "{e}");
        let e = parse_tri(&format!("{text}oops = 1\n"), "f", TriKind::StvkDs).unwrap_err();
        assert!(
            e.message.contains("unknown key oops") && e.line == Some(13),
            "{e}"
        );
        let bad = text.replace("stretch_weft_range = [0.0, 0.05]\n", "");
        let e = parse_tri(&bad, "f", TriKind::StvkDs).unwrap_err();
        assert!(e.message.contains("stretch_weft_range"), "{e}");
    }
}
