//! The dataset's `[known]` table: values a lab knows from elsewhere (yarn moduli, thickness,
//! Poisson coupling), checked and converted to SI; the fit holds them.

use super::{DatasetError, Known, RawKnown, Toml};
use toml::Spanned;

/// The `[known]` table in SI units.
pub(super) fn read_known(t: &Toml, raw: Option<&RawKnown>) -> Result<Known, DatasetError> {
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
                format!("[known] a12_pa must be finite, got {:?}", v.get_ref()),
            ))
        }
        v => v.as_ref().map(|v| *v.get_ref()),
    };
    let poisson_12 = match &k.poisson_12 {
        Some(v) if !(v.get_ref().is_finite() && v.get_ref().abs() < 1.0) => {
            return Err(t.err(
                v.span(),
                format!(
                    "[known] poisson_12 must be in (-1, 1), got {:?}",
                    v.get_ref()
                ),
            ))
        }
        v => v.as_ref().map(|v| *v.get_ref()),
    };
    // moduli within what a material file may hold (the fit writes one)
    let modulus = |key: &str, v: &Option<Spanned<f64>>| -> Result<Option<f64>, DatasetError> {
        let x = pos(key, v, 1.0)?;
        let (lo, hi) = crate::material::MODULUS_RANGE;
        match (x, v) {
            (Some(x), Some(v)) if !(lo..=hi).contains(&x) => Err(t.err(
                v.span(),
                format!("[known] {key} = {x:?} is outside [{lo:e}, {hi:e}] Pa"),
            )),
            _ => Ok(x),
        }
    };
    let known = Known {
        a11: modulus("a11_pa", &k.a11_pa)?,
        a22: modulus("a22_pa", &k.a22_pa)?,
        a12,
        g12: modulus("g12_pa", &k.g12_pa)?,
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
