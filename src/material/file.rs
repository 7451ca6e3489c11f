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
//! Optional tables make the law nonlinear (absent = linear) and add strain cut-offs:
//!
//! ```toml
//! [warp]            # eta1
//! mu = [0.7, 0.3]
//! alpha = [1.0, 12.0]
//! [weft]            # eta3
//! mu = [1.0]
//! alpha = [4.0]
//! [shear]           # eta4
//! mu = [0.5, 0.5]
//! alpha = [1.0, 6.0]
//! [cutoffs]         # Green strain, warp/weft frame; e11_min, e22_min default 0
//! e11_max = 0.12
//! e22_max = 0.15
//! e12_max = 0.20    # e12_min = -e12_max
//! ```
//!
//! An optional `[shear_coupling]` table couples the shear stiffness to the yarn strains
//! (see the law's module doc; not in the paper): the shear term is multiplied by
//! exp(warp·Ẽ₁₁ + weft·Ẽ₂₂), |κ| ≤ 200.
//!
//! ```toml
//! [shear_coupling]  # dimensionless, per unit Green strain; negative: shear softens under tension
//! warp = -8.0
//! weft = -12.0
//! ```
//!
//! An optional `[bending]` table gives the bending its own rigidities (see [`super::bending`])
//! in place of the paper's τ³/12 link to the membrane law:
//!
//! ```toml
//! [bending]         # flexural rigidity per unit width, N·m (ASTM D1388's G = ρ g c³)
//! warp_n_m = 2.0e-5
//! weft_n_m = 6.0e-6
//! bias_n_m = 4.0e-6 # optional (45°); or twist_n_m; absent: follows the membrane's anisotropy
//! ```
//!
//! Unknown keys, missing keys, non-positive or non-finite values, Σμ ≠ 1 (beyond 1e-12),
//! arrays of different lengths and α = 0 are errors that name the file, the line and the key.

use super::{BendingRigidity, Cutoffs, Eta, Orthotropic, OrthotropicStvk};
use crate::limits::MAX_LAW_TERMS;
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
    warp: Option<RawEta>,
    weft: Option<RawEta>,
    shear: Option<RawEta>,
    cutoffs: Option<RawCutoffs>,
    shear_coupling: Option<RawCoupling>,
    bending: Option<RawBending>,
    /// written by `ks-fit fit` (how the material was obtained); read past, not used
    #[allow(dead_code)]
    fit: Option<toml::Value>,
    /// a triangle model's parameters (`crate::tri::file`); read past by the shell
    #[allow(dead_code)]
    model: Option<toml::Value>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEta {
    mu: Vec<f64>,
    alpha: Vec<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCoupling {
    warp: f64,
    weft: f64,
}

/// The largest |κ| of a `[shear_coupling]` (exp(200 · 0.1) is already 5e8).
pub const COUPLING_MAX: f64 = 200.0;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBending {
    warp_n_m: f64,
    weft_n_m: f64,
    bias_n_m: Option<f64>,
    twist_n_m: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCutoffs {
    e11_min: Option<f64>,
    e11_max: Option<f64>,
    e22_min: Option<f64>,
    e22_max: Option<f64>,
    e12_max: Option<f64>,
}

/// A cloth material in SI units.
#[derive(Clone, Debug, PartialEq)]
pub struct FabricMaterial {
    pub name: String,
    /// kg/m²
    pub areal_density: f64,
    /// m
    pub thickness: f64,
    pub law: Orthotropic,
    /// Bending of its own (`[bending]`); `None`: the paper's section, τ³/12 times the law.
    pub bending: Option<BendingRigidity>,
}

impl FabricMaterial {
    /// The paper's model: bending from the law integrated through the thickness.
    pub fn paper(name: &str, areal_density: f64, thickness: f64, law: Orthotropic) -> Self {
        Self {
            name: name.to_string(),
            areal_density,
            thickness,
            law,
            bending: None,
        }
    }
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
    // regular files of at most 16 MiB: a FIFO or /dev/zero is refused, not read forever
    let text = crate::io::read_text(path, 16 << 20).map_err(|e| MaterialFileError {
        path: name.clone(),
        line: None,
        message: format!("cannot read file: {e}"),
    })?;
    parse_material(&text, &name)
}

/// 1-based line of byte offset `at`.
pub(crate) fn line_of(text: &str, at: usize) -> usize {
    text[..at.min(text.len())].matches('\n').count() + 1
}

/// Line where `key = …` is written (within `[table]` when given), if it is.
pub(crate) fn line_of_key(text: &str, table: Option<&str>, key: &str) -> Option<usize> {
    let mut current: Option<String> = None;
    for (i, l) in text.lines().enumerate() {
        let l = l.trim_start();
        if let Some(rest) = l.strip_prefix('[') {
            current = rest.split(']').next().map(|t| t.trim().to_string());
            continue;
        }
        let here = match table {
            None => current.is_none(),
            Some(t) => current.as_deref() == Some(t),
        };
        if here
            && l.strip_prefix(key)
                .is_some_and(|rest| rest.trim_start().starts_with('='))
        {
            return Some(i + 1);
        }
    }
    None
}

/// Moduli a material file may give, Pa: far below and above any fabric, but within what the
/// solver's tolerances and double precision handle (1e-300 Pa gives negative forces).
pub const MODULUS_RANGE: (f64, f64) = (1.0, 1e13);

/// The model kind of a file that has a `[model]` table and no shell law, if it is one.
pub fn model_only(text: &str) -> Option<String> {
    let v: toml::Value = toml::from_str(text).ok()?;
    let t = v.as_table()?;
    if t.contains_key("a11_pa") {
        return None;
    }
    Some(t.get("model")?.get("kind")?.as_str()?.to_string())
}

/// Parses and checks material TOML; `path` names it in errors.
pub fn parse_material(text: &str, path: &str) -> Result<FabricMaterial, MaterialFileError> {
    if let Some(kind) = model_only(text) {
        return Err(MaterialFileError {
            path: path.to_string(),
            line: line_of_key(text, Some("model"), "kind"),
            message: format!(
                "this file holds a {kind} model ([model] table) and no shell law (a11_pa …); use it with --model {kind}"
            ),
        });
    }
    let raw: RawMaterial = toml::from_str(text).map_err(|e| MaterialFileError {
        path: path.to_string(),
        line: e.span().map(|s| line_of(text, s.start)),
        message: e.message().trim().replace('\n', " "),
    })?;
    let e = Errs { text, path };
    let a11 = e.check("a11_pa", raw.a11_pa, false)?;
    let a22 = e.check("a22_pa", raw.a22_pa, false)?;
    let g12 = e.check("g12_pa", raw.g12_pa, false)?;
    let a12 = read_a12(&e, raw.a12_pa, a11, a22)?;
    let cutoffs = match raw.cutoffs {
        Some(c) => read_cutoffs(&e, c)?,
        None => Cutoffs::none(),
    };
    check_moduli_range(&e, a11, a22, g12)?;
    let stvk = OrthotropicStvk { a11, a22, a12, g12 };
    let mut law: Orthotropic = stvk.into();
    law.warp = read_eta(&e, "warp", raw.warp)?;
    law.weft = read_eta(&e, "weft", raw.weft)?;
    law.shear = read_eta(&e, "shear", raw.shear)?;
    law.cutoffs = cutoffs;
    if let Some(c) = raw.shear_coupling {
        law.coupling = Some(read_coupling(&e, c)?);
    }
    check_rising(&e, &law)?;
    let bending = match raw.bending {
        None => None,
        Some(b) => {
            Some(bending(b, &law).map_err(|(key, message)| e.err(Some("bending"), key, message))?)
        }
    };
    Ok(FabricMaterial {
        bending,
        name: raw.name,
        areal_density: e.check("areal_density_g_m2", raw.areal_density_g_m2, false)? * 1e-3,
        thickness: e.check("thickness_mm", raw.thickness_mm, false)? * 1e-3,
        law,
    })
}

/// Errors located in the material text `text` of the file `path`.
struct Errs<'a> {
    text: &'a str,
    path: &'a str,
}

impl Errs<'_> {
    /// An error at the line of `key` (within `[table]` when given).
    fn err(&self, table: Option<&str>, key: &str, message: String) -> MaterialFileError {
        MaterialFileError {
            path: self.path.to_string(),
            line: line_of_key(self.text, table, key),
            message,
        }
    }

    /// The top-level value `v` of `key`: finite and positive (or zero, with `allow_zero`).
    fn check(&self, key: &str, v: f64, allow_zero: bool) -> Result<f64, MaterialFileError> {
        let ok = v.is_finite() && (v > 0.0 || (allow_zero && v == 0.0));
        if ok {
            Ok(v)
        } else {
            Err(MaterialFileError {
                path: self.path.to_string(),
                line: line_of_key(self.text, None, key),
                message: format!(
                    "{key} must be a finite {} number, got {v:?}",
                    if allow_zero {
                        "non-negative"
                    } else {
                        "positive"
                    }
                ),
            })
        }
    }
}

/// The coupling modulus `a12_pa` (default `0.5 · min(a11, a22)`), which keeps the membrane law
/// definite.
fn read_a12(e: &Errs, a12_pa: Option<f64>, a11: f64, a22: f64) -> Result<f64, MaterialFileError> {
    // a12 may be negative (a negative Poisson coupling); convexity is the only bound
    let a12 = match a12_pa {
        Some(v) if v.is_finite() => v,
        Some(v) => {
            return Err(e.err(
                None,
                "a12_pa",
                format!("a12_pa must be a finite number, got {v:?}"),
            ))
        }
        None => 0.5 * a11.min(a22),
    };
    if a12 * a12 >= a11 * a22 {
        return Err(e.err(
            None,
            "a12_pa",
            format!(
                "a12_pa = {a12} makes the membrane law indefinite: need a12² < a11·a22 = {}",
                a11 * a22
            ),
        ));
    }
    Ok(a12)
}

/// The η of the table `[table]` (linear when absent): mu and alpha of one length, at most
/// [`MAX_LAW_TERMS`] terms, finite, no zero alpha, mu summing to 1.
fn read_eta(e: &Errs, table: &str, raw: Option<RawEta>) -> Result<Eta, MaterialFileError> {
    let Some(r) = raw else {
        return Ok(Eta::linear());
    };
    if r.mu.is_empty() || r.mu.len() != r.alpha.len() {
        return Err(e.err(
            Some(table),
            "alpha",
            format!(
                "[{table}] needs mu and alpha of the same, non-zero length (got {} and {})",
                r.mu.len(),
                r.alpha.len()
            ),
        ));
    }
    if r.mu.len() > MAX_LAW_TERMS {
        return Err(e.err(
            Some(table),
            "mu",
            format!(
                "[{table}] has {} terms, more than the {MAX_LAW_TERMS} a law may have (a fit uses at most 8; every term is evaluated at every quadrature point of every solve)",
                r.mu.len()
            ),
        ));
    }
    for (key, values) in [("mu", &r.mu), ("alpha", &r.alpha)] {
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(e.err(
                Some(table),
                key,
                format!("[{table}] {key} holds {v}: every entry must be finite"),
            ));
        }
    }
    if r.alpha.contains(&0.0) {
        return Err(e.err(
            Some(table),
            "alpha",
            format!("[{table}] alpha must not contain 0"),
        ));
    }
    let sum: f64 = r.mu.iter().sum();
    if (sum - 1.0).abs() > 1e-12 {
        return Err(e.err(
            Some(table),
            "mu",
            format!("[{table}] mu must sum to 1 (so that η'(0) = 1), got {sum:?}"),
        ));
    }
    Ok(Eta {
        mu: r.mu,
        alpha: r.alpha,
    })
}

/// The `[cutoffs]` table: each side's bound (unbounded when absent; a given maximum sets the
/// minimum to 0), each range non-empty.
fn read_cutoffs(e: &Errs, c: RawCutoffs) -> Result<Cutoffs, MaterialFileError> {
    let pick = |key: &str, v: Option<f64>, default: f64| -> Result<f64, MaterialFileError> {
        match v {
            None => Ok(default),
            // ±inf: no cut-off on that side
            Some(x) if !x.is_nan() => Ok(x),
            Some(x) => Err(e.err(
                Some("cutoffs"),
                key,
                format!("[cutoffs] {key} must be a number, got {x:?}"),
            )),
        }
    };
    let (lo, hi) = (f64::NEG_INFINITY, f64::INFINITY);
    let e11_max = pick("e11_max", c.e11_max, hi)?;
    let e22_max = pick("e22_max", c.e22_max, hi)?;
    let e12_max = pick("e12_max", c.e12_max, hi)?;
    // tensile-only data: compression is extrapolated from zero strain unless told otherwise
    let e11_min = pick(
        "e11_min",
        c.e11_min,
        if c.e11_max.is_some() { 0.0 } else { lo },
    )?;
    let e22_min = pick(
        "e22_min",
        c.e22_min,
        if c.e22_max.is_some() { 0.0 } else { lo },
    )?;
    for (key, min, max) in [
        ("e11_max", e11_min, e11_max),
        ("e22_max", e22_min, e22_max),
        ("e12_max", -e12_max, e12_max),
    ] {
        if min >= max {
            return Err(e.err(
                Some("cutoffs"),
                key,
                format!("[cutoffs] {key} = {max} leaves an empty range (min {min})"),
            ));
        }
    }
    Ok(Cutoffs {
        e11: (e11_min, e11_max),
        e22: (e22_min, e22_max),
        e12: (-e12_max, e12_max),
    })
}

/// Refuses a stiffness outside [`MODULUS_RANGE`].
fn check_moduli_range(e: &Errs, a11: f64, a22: f64, g12: f64) -> Result<(), MaterialFileError> {
    for (key, v) in [("a11_pa", a11), ("a22_pa", a22), ("g12_pa", g12)] {
        if !(MODULUS_RANGE.0..=MODULUS_RANGE.1).contains(&v) {
            return Err(e.err(
                None,
                key,
                format!(
                    "{key} = {v:?} is outside [{:e}, {:e}] Pa, the range this engine solves (woven fabrics: about 1e4 to 1e10)",
                    MODULUS_RANGE.0, MODULUS_RANGE.1
                ),
            ));
        }
    }
    Ok(())
}

/// The `[shear_coupling]` table, each exponent finite and within [`COUPLING_MAX`].
fn read_coupling(e: &Errs, c: RawCoupling) -> Result<super::ShearCoupling, MaterialFileError> {
    for (key, v) in [("warp", c.warp), ("weft", c.weft)] {
        if !(v.is_finite() && v.abs() <= COUPLING_MAX) {
            return Err(e.err(
                Some("shear_coupling"),
                key,
                format!("[shear_coupling] {key} must be a finite number in [-{COUPLING_MAX}, {COUPLING_MAX}], got {v:?}"),
            ));
        }
    }
    Ok(super::ShearCoupling {
        warp: c.warp,
        weft: c.weft,
    })
}

/// Refuses a law whose stress stops rising with strain where the law is its own (inside the
/// cut-offs; Green strain up to 1 where there is none): a falling branch has no stable
/// equilibrium.
fn check_rising(e: &Errs, law: &Orthotropic) -> Result<(), MaterialFileError> {
    for (table, key, eta, (lo, hi)) in [
        ("warp", "e11_max", &law.warp, law.cutoffs.e11),
        ("weft", "e22_max", &law.weft, law.cutoffs.e22),
        ("shear", "e12_max", &law.shear, law.cutoffs.e12),
    ] {
        let e_max = lo.abs().max(hi.abs()).min(1.0);
        if let Some(strain) = eta.stress_peak(e_max) {
            return Err(e.err(
                Some(table),
                "mu",
                format!(
                    "[{table}] the stress stops rising at Green strain {strain:.4}, inside the law's valid range (up to {e_max}): lower [cutoffs] {key} below it or change mu and alpha"
                ),
            ));
        }
    }
    Ok(())
}

/// The rigidities of a `[bending]` table, or the key at fault and why.
fn bending(b: RawBending, law: &Orthotropic) -> Result<BendingRigidity, (&'static str, String)> {
    for (key, v) in [
        ("warp_n_m", Some(b.warp_n_m)),
        ("weft_n_m", Some(b.weft_n_m)),
        ("bias_n_m", b.bias_n_m),
        ("twist_n_m", b.twist_n_m),
    ] {
        if let Some(v) = v {
            if !(v > 0.0 && v.is_finite() && v < 1e3) {
                return Err((
                    key,
                    format!("[bending] {key} must be a positive rigidity below 1e3 N·m, got {v:?}"),
                ));
            }
        }
    }
    let (warp, weft) = (b.warp_n_m, b.weft_n_m);
    match (b.bias_n_m, b.twist_n_m) {
        (Some(_), Some(_)) => Err((
            "twist_n_m",
            "[bending] give bias_n_m or twist_n_m, not both (each determines the other)".into(),
        )),
        (Some(bias), None) => BendingRigidity::from_bias(warp, weft, bias)
            .map_err(|e| ("bias_n_m", format!("[bending] bias_n_m: {e}"))),
        (None, Some(twist)) => Ok(BendingRigidity { warp, weft, twist }),
        (None, None) => BendingRigidity::following(warp, weft, law)
            .map_err(|e| ("warp_n_m", format!("[bending] warp_n_m: {e}"))),
    }
}

/// The material file text of `m` (lab units in the key names, as read by [`parse_material`]),
/// every number written to round-trip exactly. Unbounded cut-offs are left out.
pub fn material_toml(m: &FabricMaterial) -> String {
    use std::fmt::Write;
    let law = &m.law;
    let mut s = String::new();
    let _ = writeln!(s, "name = {}", crate::io::toml_string(&m.name));
    let _ = writeln!(s, "areal_density_g_m2 = {:?}", m.areal_density * 1e3);
    let _ = writeln!(s, "thickness_mm = {:?}", m.thickness * 1e3);
    let _ = writeln!(s, "a11_pa = {:?}    # warp", law.a11);
    let _ = writeln!(s, "a22_pa = {:?}    # weft", law.a22);
    let _ = writeln!(s, "a12_pa = {:?}", law.a12);
    let _ = writeln!(s, "g12_pa = {:?}", law.g12);
    for (name, eta, what) in [
        ("warp", &law.warp, "eta1"),
        ("weft", &law.weft, "eta3"),
        ("shear", &law.shear, "eta4"),
    ] {
        let _ = writeln!(s, "\n[{name}]    # {what}, degree {}", eta.degree());
        let _ = writeln!(s, "mu = {:?}", eta.mu);
        let _ = writeln!(s, "alpha = {:?}", eta.alpha);
    }
    if let Some(c) = &law.coupling {
        let _ = writeln!(
            s,
            "\n[shear_coupling]    # shear stiffness times exp(warp·E11 + weft·E22)"
        );
        let _ = writeln!(s, "warp = {:?}", c.warp);
        let _ = writeln!(s, "weft = {:?}", c.weft);
    }
    if let Some(b) = &m.bending {
        let _ = writeln!(
            s,
            "\n[bending]    # flexural rigidity per unit width, N·m; bias (45°) beam rigidity {:.6e}",
            b.at_angle(45.0)
        );
        let _ = writeln!(s, "warp_n_m = {:?}", b.warp);
        let _ = writeln!(s, "weft_n_m = {:?}", b.weft);
        let _ = writeln!(s, "twist_n_m = {:?}", b.twist);
    }
    let c = &law.cutoffs;
    let bounds = [
        ("e11_min", c.e11.0),
        ("e11_max", c.e11.1),
        ("e22_min", c.e22.0),
        ("e22_max", c.e22.1),
        ("e12_max", c.e12.1),
    ];
    if bounds.iter().any(|(_, v)| v.is_finite()) {
        let _ = writeln!(s, "\n[cutoffs]    # Green strain; inf: none on that side");
        for (key, v) in bounds {
            let _ = writeln!(s, "{key} = {v:?}");
        }
    }
    s
}

#[cfg(test)]
mod tests;
