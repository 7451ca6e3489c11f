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
    let err = |table: Option<&str>, key: &str, message: String| MaterialFileError {
        path: path.to_string(),
        line: line_of_key(text, table, key),
        message,
    };
    let check = |key: &str, v: f64, allow_zero: bool| -> Result<f64, MaterialFileError> {
        let ok = v.is_finite() && (v > 0.0 || (allow_zero && v == 0.0));
        if ok {
            Ok(v)
        } else {
            Err(MaterialFileError {
                path: path.to_string(),
                line: line_of_key(text, None, key),
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
    };
    let a11 = check("a11_pa", raw.a11_pa, false)?;
    let a22 = check("a22_pa", raw.a22_pa, false)?;
    let g12 = check("g12_pa", raw.g12_pa, false)?;
    // a12 may be negative (a negative Poisson coupling); convexity is the only bound
    let a12 = match raw.a12_pa {
        Some(v) if v.is_finite() => v,
        Some(v) => {
            return Err(err(
                None,
                "a12_pa",
                format!("a12_pa must be a finite number, got {v:?}"),
            ))
        }
        None => 0.5 * a11.min(a22),
    };
    if a12 * a12 >= a11 * a22 {
        return Err(err(
            None,
            "a12_pa",
            format!(
                "a12_pa = {a12} makes the membrane law indefinite: need a12² < a11·a22 = {}",
                a11 * a22
            ),
        ));
    }
    let eta = |table: &str, raw: Option<RawEta>| -> Result<Eta, MaterialFileError> {
        let Some(r) = raw else {
            return Ok(Eta::linear());
        };
        if r.mu.is_empty() || r.mu.len() != r.alpha.len() {
            return Err(err(
                Some(table),
                "alpha",
                format!(
                    "[{table}] needs mu and alpha of the same, non-zero length (got {} and {})",
                    r.mu.len(),
                    r.alpha.len()
                ),
            ));
        }
        for (key, values) in [("mu", &r.mu), ("alpha", &r.alpha)] {
            if let Some(v) = values.iter().find(|v| !v.is_finite()) {
                return Err(err(
                    Some(table),
                    key,
                    format!("[{table}] {key} holds {v}: every entry must be finite"),
                ));
            }
        }
        if r.alpha.contains(&0.0) {
            return Err(err(
                Some(table),
                "alpha",
                format!("[{table}] alpha must not contain 0"),
            ));
        }
        let sum: f64 = r.mu.iter().sum();
        if (sum - 1.0).abs() > 1e-12 {
            return Err(err(
                Some(table),
                "mu",
                format!("[{table}] mu must sum to 1 (so that η'(0) = 1), got {sum:?}"),
            ));
        }
        Ok(Eta {
            mu: r.mu,
            alpha: r.alpha,
        })
    };
    let mut cutoffs = Cutoffs::none();
    if let Some(c) = raw.cutoffs {
        let pick = |key: &str, v: Option<f64>, default: f64| -> Result<f64, MaterialFileError> {
            match v {
                None => Ok(default),
                // ±inf: no cut-off on that side
                Some(x) if !x.is_nan() => Ok(x),
                Some(x) => Err(err(
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
                return Err(err(
                    Some("cutoffs"),
                    key,
                    format!("[cutoffs] {key} = {max} leaves an empty range (min {min})"),
                ));
            }
        }
        cutoffs = Cutoffs {
            e11: (e11_min, e11_max),
            e22: (e22_min, e22_max),
            e12: (-e12_max, e12_max),
        };
    }
    for (key, v) in [("a11_pa", a11), ("a22_pa", a22), ("g12_pa", g12)] {
        if !(MODULUS_RANGE.0..=MODULUS_RANGE.1).contains(&v) {
            return Err(err(
                None,
                key,
                format!(
                    "{key} = {v:?} is outside [{:e}, {:e}] Pa, the range this engine solves (woven fabrics: about 1e4 to 1e10)",
                    MODULUS_RANGE.0, MODULUS_RANGE.1
                ),
            ));
        }
    }
    let stvk = OrthotropicStvk { a11, a22, a12, g12 };
    let mut law: Orthotropic = stvk.into();
    law.warp = eta("warp", raw.warp)?;
    law.weft = eta("weft", raw.weft)?;
    law.shear = eta("shear", raw.shear)?;
    law.cutoffs = cutoffs;
    if let Some(c) = raw.shear_coupling {
        for (key, v) in [("warp", c.warp), ("weft", c.weft)] {
            if !(v.is_finite() && v.abs() <= COUPLING_MAX) {
                return Err(err(
                    Some("shear_coupling"),
                    key,
                    format!("[shear_coupling] {key} must be a finite number in [-{COUPLING_MAX}, {COUPLING_MAX}], got {v:?}"),
                ));
            }
        }
        law.coupling = Some(super::ShearCoupling {
            warp: c.warp,
            weft: c.weft,
        });
    }
    // the stress must rise with strain wherever the law is its own (inside the cut-offs; Green
    // strain up to 1 where there is none): a falling branch has no stable equilibrium
    for (table, key, eta, (lo, hi)) in [
        ("warp", "e11_max", &law.warp, law.cutoffs.e11),
        ("weft", "e22_max", &law.weft, law.cutoffs.e22),
        ("shear", "e12_max", &law.shear, law.cutoffs.e12),
    ] {
        let e_max = lo.abs().max(hi.abs()).min(1.0);
        if let Some(e) = eta.stress_peak(e_max) {
            return Err(err(
                Some(table),
                "mu",
                format!(
                    "[{table}] the stress stops rising at Green strain {e:.4}, inside the law's valid range (up to {e_max}): lower [cutoffs] {key} below it or change mu and alpha"
                ),
            ));
        }
    }
    let bending = match raw.bending {
        None => None,
        Some(b) => {
            Some(bending(b, &law).map_err(|(key, message)| err(Some("bending"), key, message))?)
        }
    };
    Ok(FabricMaterial {
        bending,
        name: raw.name,
        areal_density: check("areal_density_g_m2", raw.areal_density_g_m2, false)? * 1e-3,
        thickness: check("thickness_mm", raw.thickness_mm, false)? * 1e-3,
        law,
    })
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
mod tests {
    use super::*;

    const GOOD: &str = "name = \"example\"\nareal_density_g_m2 = 103.6\nthickness_mm = 0.18\na11_pa = 2.0e7\na22_pa = 1.5e7\ng12_pa = 1.0e6\n";

    #[test]
    fn bending_tables_are_read_and_checked() {
        let with = |table: &str| format!("{GOOD}\n[bending]\n{table}");
        let m = parse_material(
            &with("warp_n_m = 2e-5\nweft_n_m = 6e-6\nbias_n_m = 3e-6\n"),
            "m",
        )
        .unwrap();
        let b = m.bending.unwrap();
        assert!((b.at_angle(45.0) / 3e-6 - 1.0).abs() < 1e-12);
        // no bias: the twist follows the membrane law (soft in shear here: softer than the mean)
        let b = parse_material(&with("warp_n_m = 2e-5\nweft_n_m = 6e-6\n"), "m")
            .unwrap()
            .bending
            .unwrap();
        assert!(b.at_angle(45.0) < 0.5 * (2e-5 + 6e-6));
        for (table, key) in [
            ("warp_n_m = -2e-5\nweft_n_m = 6e-6\n", "warp_n_m"),
            (
                "warp_n_m = 2e-5\nweft_n_m = 6e-6\nbias_n_m = 1e-4\n",
                "bias_n_m",
            ),
            (
                "warp_n_m = 2e-5\nweft_n_m = 6e-6\nbias_n_m = 1e-6\ntwist_n_m = 1e-6\n",
                "twist_n_m",
            ),
        ] {
            let e = parse_material(&with(table), "m").unwrap_err();
            assert!(e.message.contains(key), "{e}");
            assert!(e.line.is_some(), "{e}");
        }
        assert!(parse_material(&with("warp_n_m = 2e-5\n"), "m").is_err());
    }

    #[test]
    fn written_materials_read_back_exactly() {
        let mut m = parse_material(GOOD, "m.toml").unwrap();
        m.law.warp = Eta {
            mu: vec![0.3, 0.7],
            alpha: vec![1.0 / 3.0, 171.5],
        };
        m.law.cutoffs.e11 = (f64::NEG_INFINITY, 0.0625);
        m.law.cutoffs.e12 = (-0.1, 0.1);
        m.bending = Some(BendingRigidity::from_bias(2e-5, 6e-6, 3e-6).unwrap());
        m.law.coupling = Some(crate::material::ShearCoupling {
            warp: -8.25,
            weft: 1.0 / 3.0,
        });
        let text = material_toml(&m);
        let back = parse_material(&text, "w.toml").unwrap();
        assert_eq!(back, m, "{text}");
        // with a [fit] table as ks-fit fit writes it
        let with_fit =
            format!("{text}\n[fit]\nwall_seconds = 3.5\n[[fit.test]]\nkind = \"bend\"\n");
        assert_eq!(parse_material(&with_fit, "w.toml").unwrap(), m);
    }

    #[test]
    fn a_shear_coupling_is_read_and_checked() {
        let m = parse_material(
            &format!("{GOOD}[shear_coupling]\nwarp = -8.0\nweft = 3.5\n"),
            "m",
        )
        .unwrap();
        let c = m.law.coupling.unwrap();
        assert_eq!((c.warp, c.weft), (-8.0, 3.5));
        assert_eq!(parse_material(GOOD, "m").unwrap().law.coupling, None);
        for (table, key) in [
            ("warp = -8.0\nweft = 300.0\n", "weft"),
            ("warp = nan\nweft = 0.0\n", "warp"),
        ] {
            let e = parse_material(&format!("{GOOD}[shear_coupling]\n{table}"), "m").unwrap_err();
            assert!(e.message.contains(key) && e.line.is_some(), "{e}");
        }
        assert!(parse_material(&format!("{GOOD}[shear_coupling]\nwarp = 1.0\n"), "m").is_err());
    }

    #[test]
    fn reads_and_converts_to_si_with_the_default_a12() {
        let m = parse_material(GOOD, "m.toml").unwrap();
        assert!((m.areal_density - 0.1036).abs() < 1e-15);
        assert!((m.thickness - 1.8e-4).abs() < 1e-18);
        assert_eq!(m.law.a12, 0.75e7);
        assert_eq!(m.law.warp, Eta::linear());
        assert_eq!(m.law.cutoffs, Cutoffs::none());
    }

    #[test]
    fn reads_the_nonlinear_tables_and_cutoffs() {
        let text = format!(
            "{GOOD}[warp]\nmu = [0.7, 0.3]\nalpha = [1.0, 12.0]\n[shear]\nmu = [1.5, -0.5]\nalpha = [2.0, -3.0]\n[cutoffs]\ne11_max = 0.12\ne12_max = 0.2\n"
        );
        let m = parse_material(&text, "m.toml").unwrap();
        assert_eq!(m.law.warp.alpha, vec![1.0, 12.0]);
        assert_eq!(m.law.weft, Eta::linear());
        assert_eq!(m.law.shear.mu, vec![1.5, -0.5]);
        assert_eq!(m.law.cutoffs.e11, (0.0, 0.12));
        assert_eq!(m.law.cutoffs.e12, (-0.2, 0.2));
        assert_eq!(m.law.cutoffs.e22.1, f64::INFINITY);
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
            (
                format!("{GOOD}[warp]\nmu = [0.7, 0.2]\nalpha = [1.0, 12.0]\n"),
                "m.toml:8: [warp] mu must sum to 1",
            ),
            (
                format!("{GOOD}[weft]\nmu = [1.0]\nalpha = [4.0, 2.0]\n"),
                "m.toml:9: [weft] needs mu and alpha of the same",
            ),
            (
                format!("{GOOD}[shear]\nmu = [1.0]\nalpha = [0.0]\n"),
                "m.toml:9: [shear] alpha must not contain 0",
            ),
            (
                format!("{GOOD}[shear]\nmu = [1.0]\nalpha = [nan]\n"),
                "m.toml:9: [shear] alpha holds NaN",
            ),
            (
                format!("{GOOD}[cutoffs]\ne11_max = -0.1\n"),
                "m.toml:8: [cutoffs] e11_max = -0.1 leaves an empty range",
            ),
            (
                format!("{GOOD}[cutoffs]\ne13_max = 0.1\n"),
                "m.toml:8: unknown field `e13_max`",
            ),
        ];
        for (text, want) in cases {
            let got = parse_material(&text, "m.toml").unwrap_err().to_string();
            assert!(got.starts_with(want), "{got:?} should start with {want:?}");
            assert!(!got.contains('\n'));
        }
    }
}
