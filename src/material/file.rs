//! The material file (TOML), lab units in the key names, converted to SI here:
//!
//! ```toml
//! name = "example"
//! areal_density_g_m2 = 103.6
//! thickness_mm = 0.18
//! a11_pa = 2.0e7    # warp
//! a22_pa = 1.5e7    # weft
//! a12_pa = 0.0      # optional; default 0.5 * min(a11, a22)
//! g12_pa = 1.0e6
//! ```
//!
//! Unknown keys, missing keys and non-positive or non-finite values are errors that name the
//! file, the line and the key.

use super::OrthotropicStvk;
use serde::Deserialize;
use std::fmt;
use std::path::Path;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    name: String,
    areal_density_g_m2: f64,
    thickness_mm: f64,
    a11_pa: f64,
    a22_pa: f64,
    a12_pa: Option<f64>,
    g12_pa: f64,
}

/// A cloth material in SI units.
#[derive(Clone, Debug, PartialEq)]
pub struct FabricMaterial {
    pub name: String,
    /// kg/m²
    pub areal_density: f64,
    /// m
    pub thickness: f64,
    pub law: OrthotropicStvk,
}

/// What is wrong with a material file.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub struct MaterialFileError {
    pub path: String,
    pub line: Option<usize>,
    pub message: String,
}

impl fmt::Display for MaterialFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}:{}: {}", self.path, l, self.message),
            None => write!(f, "{}: {}", self.path, self.message),
        }
    }
}

/// Reads and checks a material file.
pub fn load_material(path: &Path) -> Result<FabricMaterial, MaterialFileError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| MaterialFileError {
        path: name.clone(),
        line: None,
        message: format!("cannot read file: {e}"),
    })?;
    parse_material(&text, &name)
}

/// 1-based line of byte offset `at`.
fn line_of(text: &str, at: usize) -> usize {
    text[..at.min(text.len())].matches('\n').count() + 1
}

/// Line where `key = …` is written, if it is.
fn line_of_key(text: &str, key: &str) -> Option<usize> {
    text.lines()
        .position(|l| {
            let l = l.trim_start();
            l.strip_prefix(key)
                .is_some_and(|rest| rest.trim_start().starts_with('='))
        })
        .map(|i| i + 1)
}

/// Parses and checks material TOML; `path` names it in errors.
pub fn parse_material(text: &str, path: &str) -> Result<FabricMaterial, MaterialFileError> {
    let raw: RawMaterial = toml::from_str(text).map_err(|e| MaterialFileError {
        path: path.to_string(),
        line: e.span().map(|s| line_of(text, s.start)),
        message: e.message().trim().replace('\n', " "),
    })?;
    let check = |key: &str, v: f64, allow_zero: bool| -> Result<f64, MaterialFileError> {
        let ok = v.is_finite() && (v > 0.0 || (allow_zero && v == 0.0));
        if ok {
            Ok(v)
        } else {
            Err(MaterialFileError {
                path: path.to_string(),
                line: line_of_key(text, key),
                message: format!(
                    "{key} must be a finite {} number, got {v}",
                    if allow_zero {
                        "non-negative"
                    } else {
                        "positive"
                    }
                ),
            })
        }
    };
    let a11 = check("a11_pa", raw.a11_pa, false)?;
    let a22 = check("a22_pa", raw.a22_pa, false)?;
    let g12 = check("g12_pa", raw.g12_pa, false)?;
    let a12 = match raw.a12_pa {
        Some(v) => check("a12_pa", v, true)?,
        None => 0.5 * a11.min(a22),
    };
    if a12 * a12 >= a11 * a22 {
        return Err(MaterialFileError {
            path: path.to_string(),
            line: line_of_key(text, "a12_pa"),
            message: format!(
                "a12_pa = {a12} makes the membrane law indefinite: need a12² < a11·a22 = {}",
                a11 * a22
            ),
        });
    }
    Ok(FabricMaterial {
        name: raw.name,
        areal_density: check("areal_density_g_m2", raw.areal_density_g_m2, false)? * 1e-3,
        thickness: check("thickness_mm", raw.thickness_mm, false)? * 1e-3,
        law: OrthotropicStvk { a11, a22, a12, g12 },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "name = \"example\"\nareal_density_g_m2 = 103.6\nthickness_mm = 0.18\na11_pa = 2.0e7\na22_pa = 1.5e7\ng12_pa = 1.0e6\n";

    #[test]
    fn reads_and_converts_to_si_with_the_default_a12() {
        let m = parse_material(GOOD, "m.toml").unwrap();
        assert!((m.areal_density - 0.1036).abs() < 1e-15);
        assert!((m.thickness - 1.8e-4).abs() < 1e-18);
        assert_eq!(m.law.a12, 0.75e7);
    }

    #[test]
    fn errors_name_file_line_and_key() {
        let cases = [
            (
                format!("{GOOD}colour = 3\n"),
                "m.toml:7: unknown field `colour`",
            ),
            (
                GOOD.replace("g12_pa = 1.0e6\n", ""),
                "m.toml:1: missing field `g12_pa`",
            ),
            (
                GOOD.replace("a22_pa = 1.5e7", "a22_pa = -1.5e7"),
                "m.toml:5: a22_pa must be a finite positive",
            ),
            (
                GOOD.replace("thickness_mm = 0.18", "thickness_mm = 0"),
                "m.toml:3: thickness_mm must be",
            ),
            (
                GOOD.replace("a11_pa = 2.0e7", "a11_pa = nan"),
                "m.toml:4: a11_pa must be",
            ),
            (
                format!("{GOOD}a12_pa = 3e7\n"),
                "m.toml:7: a12_pa = 30000000 makes the membrane law indefinite",
            ),
            (
                GOOD.replace("a11_pa = 2.0e7", "a11_pa = \"big\""),
                "m.toml:4: invalid type",
            ),
        ];
        for (text, want) in cases {
            let got = parse_material(&text, "m.toml").unwrap_err().to_string();
            assert!(got.starts_with(want), "{got:?} should start with {want:?}");
            assert!(!got.contains('\n'));
        }
    }
}
