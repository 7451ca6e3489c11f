//! Export to the ARCSim cloth material format (Wang, Ramamoorthi & O'Brien 2011, "Data-Driven
//! Elastic Models for Cloth"; the simulator of Narain, Samii & O'Brien 2012), and a reader that
//! evaluates such a file as ARCSim does, for the round trip.
//!
//! The format, as ARCSim 0.3.1's source uses it (`dde.cpp`, `conf.cpp`, `physics.cpp`):
//! - `density`: areal density, kg/m².
//! - `stretching`: six rows [D₀, D₁, D₂, D₃], N/m. The energy per rest area is
//!   W = ½k₀G₀₀² + k₁G₀₀G₁₁ + ½k₂G₁₁² + k₃G₀₁², G the Green strain in the material (u, v)
//!   frame, k = 2D(G) held fixed when W is differentiated (a secant model), so the stress is
//!   ∂W/∂(G₀₀, G₁₁, G₀₁) = (k₀G₀₀ + k₁G₁₁, k₁G₀₀ + k₂G₁₁, 2k₃G₀₁). D is row 0 while the largest
//!   principal stretch λ₁ ≤ 1 and the row of the principal direction (rows 1–5: 0°, 22.5°, 45°,
//!   67.5°, 90° from u) once λ₁ ≥ 7/6, linear in λ₁ and in angle between, clamped at ≥ 0.
//!   ARCSim tabulates this on a 30³ grid of G; [`ArcsimMaterial::stretching`] evaluates it
//!   exactly.
//! - `bending`: three rows (hinge edge along u, at 45°, along v) of five bending stiffnesses
//!   k_e, N·m, at edge curvatures 0, 10, 20, 30, 40 m⁻¹.
//!
//! Our export puts the warp on u and the weft on v. Row 0 is our small-strain tangent, so ARCSim
//! reproduces our stress to first order. Along the uniaxial path G = g n⊗n (n at a row's angle,
//! 1 < λ ≤ 7/6) ARCSim's stiffness is the straight ramp from row 0 to row i; each entry of row i
//! is the ramp's end that fits, in relative least squares along the path, the secant of our
//! matching one-component term (our law is a sum of such terms and a bilinear coupling, which
//! ARCSim holds exactly). Making the rows exact at λ = 7/6 instead left 28–38 % errors at
//! fabric strains on fitted materials; [`stress_deviation`] reports what remains.
//! Bending rows hold the plate rigidity for cylindrical bending across the hinge, the secant
//! M(κ)/κ at each sample curvature; ARCSim's own example (`paper.json`) stores Eh³/12 as k_e,
//! and so do we. Its hinge energy turns k_e into a mesh-dependent effective rigidity; that
//! factor has not been checked against ARCSim runs.

use super::json::{parse, Json};
use super::{FabricMaterial, Law};
use nalgebra::Vector3;
use std::fmt::Write;

/// The principal stretch at which the rows 1–5 apply in full.
pub const ROW_STRETCH: f64 = 7.0 / 6.0;
/// Principal directions of the rows 1–5, degrees from u (the warp).
pub const ROW_ANGLES_DEG: [f64; 5] = [0.0, 22.5, 45.0, 67.5, 90.0];
/// Edge curvatures of the five bending samples, 1/m.
pub const CURVATURES: [f64; 5] = [0.0, 10.0, 20.0, 30.0, 40.0];

/// An ARCSim material: what its JSON file holds.
#[derive(Clone, Debug, PartialEq)]
pub struct ArcsimMaterial {
    /// kg/m²
    pub density: f64,
    /// N/m
    pub stretching: [[f64; 4]; 6],
    /// N·m
    pub bending: [[f64; 5]; 3],
}

/// The uniaxial Green strain (G₀₀, G₁₁, G₀₁) of stretch `lambda` along `deg` from u.
pub fn uniaxial(lambda: f64, deg: f64) -> [f64; 3] {
    let g = 0.5 * (lambda * lambda - 1.0);
    let (s, c) = deg.to_radians().sin_cos();
    [g * c * c, g * s * s, g * s * c]
}

/// Our membrane stress per unit rest length, τ ∂ψ/∂(Ẽ₁₁, Ẽ₂₂, Ẽ₁₂), at Green strain `g`.
pub fn our_stress(m: &FabricMaterial, g: [f64; 3]) -> Result<[f64; 3], String> {
    let r = m
        .law
        .response(&Vector3::from(g))
        .map_err(|e| e.to_string())?;
    Ok(std::array::from_fn(|i| m.thickness * r.stress[i]))
}

/// Exports `m` (warp on u); also returns warnings about what ARCSim cannot hold.
///
/// Rows 1–5 are fitted on uniaxial stretches 1 < λ ≤ 1 + `max_strain` (the range the material
/// was measured over: beyond it our law is an extrapolation, and fabric laws stiffen steeply).
pub fn export(
    m: &FabricMaterial,
    max_strain: f64,
) -> Result<(ArcsimMaterial, Vec<String>), String> {
    if !(max_strain > 0.0 && max_strain <= ROW_STRETCH - 1.0) {
        return Err(format!(
            "the strain range must be in (0, 1/6], got {}",
            crate::io::num(max_strain)
        ));
    }
    let tau = m.thickness;
    let zero = m
        .law
        .response(&Vector3::zeros())
        .map_err(|e| e.to_string())?
        .tangent;
    let k1 = tau * zero[(0, 1)];
    let mut warnings = Vec::new();
    if k1 < 0.0 {
        warnings.push(format!(
            "a12 < 0: ARCSim clamps its coupling stiffness at 0 (exported {:.4e} N/m, used as 0)",
            k1 / 2.0
        ));
    }
    // the secant of each one-component term at one strain component (its tangent at zero)
    let secant = |i: usize, e: f64| -> Result<f64, String> {
        if e.abs() < 1e-12 {
            return Ok(tau * zero[(i, i)]);
        }
        let mut v = [0.0; 3];
        v[i] = e;
        Ok(our_stress(m, v)?[i] / e)
    };
    let mut stretching = [[0.0; 4]; 6];
    stretching[0] = [
        tau * zero[(0, 0)] / 2.0,
        k1 / 2.0,
        tau * zero[(1, 1)] / 2.0,
        tau * zero[(2, 2)] / 4.0,
    ];
    for (r, deg) in (1..6).zip(ROW_ANGLES_DEG) {
        // k = 2D: k₀ is the secant of the warp term at G₀₀ (k₀G₀₀ = σ₀₀ − k₁G₁₁), k₂ of the
        // weft term, 2k₃ of the shear term; each row entry is fitted to it along the path
        let row0 = stretching[0];
        let mut row = [0.0, k1 / 2.0, 0.0, 0.0];
        for (c, (i, scale)) in [(0, (0, 0.5)), (2, (1, 0.5)), (3, (2, 0.25))] {
            let path: Result<Vec<(f64, f64)>, String> = (1..=PATH_POINTS)
                .map(|k| {
                    let lambda = 1.0 + max_strain * k as f64 / PATH_POINTS as f64;
                    let g = uniaxial(lambda, deg);
                    Ok((6.0 * (lambda - 1.0), scale * secant(i, g[i])?))
                })
                .collect();
            row[c] = ramp_end(row0[c], &path?);
        }
        stretching[r] = row;
    }
    let mut bending = [[0.0; 5]; 3];
    for (row, deg) in bending.iter_mut().zip([90.0, 45.0, 0.0]) {
        // hinge along u (row 0) bends the sheet across it, along v; and so on
        for (b, &kappa) in row.iter_mut().zip(&CURVATURES) {
            *b = plate_rigidity(m, deg, kappa)?;
        }
    }
    let a = ArcsimMaterial {
        density: m.areal_density,
        stretching,
        bending,
    };
    Ok((a, warnings))
}

/// Points along each row's uniaxial path, 1 < λ ≤ 1 + max strain, at which it is fitted.
const PATH_POINTS: usize = 32;

/// The end value r of ARCSim's ramp d(t) = (1 − t) r₀ + t r that best matches the targets
/// (t, d) in relative least squares: min Σ ((d(t) − d)/d)² is linear in r.
fn ramp_end(r0: f64, path: &[(f64, f64)]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for &(t, d) in path {
        let w = 1.0 / (d * d).max(f64::MIN_POSITIVE);
        num += w * t * (d - (1.0 - t) * r0);
        den += w * t * t;
    }
    if den > 0.0 {
        num / den
    } else {
        r0
    }
}

/// Rigidity of cylindrical bending with curvature `kappa` (1/m) along `deg` from the warp:
/// the secant M/κ, or the tangent at κ = 0.
fn plate_rigidity(m: &FabricMaterial, deg: f64, kappa: f64) -> Result<f64, String> {
    let (s, c) = deg.to_radians().sin_cos();
    let v = Vector3::new(c * c, s * s, s * c);
    if let Some(b) = m.bending {
        return Ok(v.dot(&(b.matrix() * v)));
    }
    let tau = m.thickness;
    if kappa == 0.0 {
        let t = m
            .law
            .response(&Vector3::zeros())
            .map_err(|e| e.to_string())?;
        return Ok(tau.powi(3) / 12.0 * v.dot(&(t.tangent * v)));
    }
    // M = ∫ ξ vᵀσ(ξκv) dξ over the thickness, 8-point Gauss–Legendre (exact to degree 15)
    let rule = crate::quadrature::GaussLegendre::new(8).map_err(|e| format!("{e:?}"))?;
    let mut moment = 0.0;
    for (xi, w) in rule.on_interval(-tau / 2.0, tau / 2.0) {
        let r = m
            .law
            .response(&(v * (xi * kappa)))
            .map_err(|e| e.to_string())?;
        moment += w * xi * v.dot(&r.stress);
    }
    Ok(moment / kappa)
}

impl ArcsimMaterial {
    /// The JSON file ARCSim reads, with `comment` as `//` lines (its reader accepts them).
    pub fn json(&self, comment: &str) -> String {
        let mut s = String::new();
        for line in comment.lines() {
            let _ = writeln!(s, "// {line}");
        }
        let rows = |rows: &[&[f64]]| -> String {
            let r: Vec<String> = rows
                .iter()
                .map(|r| {
                    let v: Vec<String> = r.iter().map(|x| format!("{x:.9e}")).collect();
                    format!("[{}]", v.join(", "))
                })
                .collect();
            r.join(",\n    ")
        };
        let st: Vec<&[f64]> = self.stretching.iter().map(|r| &r[..]).collect();
        let be: Vec<&[f64]> = self.bending.iter().map(|r| &r[..]).collect();
        let _ = write!(
            s,
            "{{\n  \"density\": {:.9e},\n  \"stretching\": [\n    {}\n  ],\n  \"bending\": [\n    {}\n  ]\n}}\n",
            self.density,
            rows(&st),
            rows(&be)
        );
        s
    }

    /// Reads an ARCSim material file (its three keys; others are ignored, as ARCSim does).
    pub fn parse(text: &str) -> Result<Self, String> {
        let Json::Object(map) = parse(text)? else {
            return Err("the file is not a JSON object".into());
        };
        let get = |key: &str| map.get(key).ok_or_else(|| format!("no \"{key}\" key"));
        let number = |v: &Json, what: &str| match v {
            Json::Number(x) => Ok(*x),
            _ => Err(format!("{what} must be a number")),
        };
        let table = |key: &str, rows: usize, cols: usize| -> Result<Vec<Vec<f64>>, String> {
            let bad = || format!("\"{key}\" must be {rows} rows of {cols} numbers");
            let Json::Array(r) = get(key)? else {
                return Err(bad());
            };
            r.iter()
                .take(rows)
                .map(|row| match row {
                    Json::Array(v) if v.len() == cols => v.iter().map(|x| number(x, key)).collect(),
                    _ => Err(bad()),
                })
                .collect::<Result<Vec<_>, _>>()
                .and_then(|t| if t.len() == rows { Ok(t) } else { Err(bad()) })
        };
        let st = table("stretching", 6, 4)?;
        let be = table("bending", 3, 5)?;
        Ok(Self {
            density: number(get("density")?, "\"density\"")?,
            stretching: std::array::from_fn(|i| std::array::from_fn(|j| st[i][j])),
            bending: std::array::from_fn(|i| std::array::from_fn(|j| be[i][j])),
        })
    }

    /// ARCSim's k(G) (`evaluate_stretching_sample`), evaluated exactly rather than tabulated.
    pub fn stiffness(&self, g: [f64; 3]) -> [f64; 4] {
        // C = 2G + I, its largest eigenvalue and eigenvector (ARCSim's closed form)
        let (a, b, d) = (2.0 * g[0] + 1.0, 2.0 * g[2], 2.0 * g[1] + 1.0);
        let l1 = 0.5 * (a + d + (4.0 * b * b + (a - d) * (a - d)).sqrt());
        let v = if b == 0.0 {
            if a >= d {
                [1.0, 0.0]
            } else {
                [0.0, 1.0]
            }
        } else {
            [l1 - d, b]
        };
        let angle = (v[1].atan2(v[0]).abs() / std::f64::consts::PI * 8.0).clamp(0.0, 4.0 - 1e-6);
        let (ia, wa) = (angle.floor() as usize, angle - angle.floor());
        let t = (6.0 * (l1.sqrt() - 1.0)).clamp(0.0, 1.0 - 1e-6);
        let r = &self.stretching;
        std::array::from_fn(|c| {
            let top = (1.0 - wa) * r[1 + ia][c] + wa * r[2 + ia][c];
            2.0 * ((1.0 - t) * r[0][c] + t * top).max(0.0)
        })
    }

    /// ARCSim's membrane stress ∂W/∂(G₀₀, G₁₁, G₀₁) at Green strain `g`, k held fixed, N/m.
    pub fn stress(&self, g: [f64; 3]) -> [f64; 3] {
        let k = self.stiffness(g);
        [
            k[0] * g[0] + k[1] * g[1],
            k[1] * g[0] + k[2] * g[1],
            2.0 * k[3] * g[2],
        ]
    }
}

/// Largest relative difference |S_arcsim − S_ours| / |S_ours| over uniaxial stretches
/// 1 < λ ≤ 1 + `max_strain` along the five row angles and halfway between them: what the
/// format (stiffness linear in λ, in angle between rows) loses of our law.
pub fn stress_deviation(
    m: &FabricMaterial,
    a: &ArcsimMaterial,
    max_strain: f64,
) -> Result<f64, String> {
    let mut worst = 0.0f64;
    for deg in (0..=8).map(|i| 11.25 * i as f64) {
        for k in 1..=40 {
            let g = uniaxial(1.0 + max_strain * k as f64 / 40.0, deg);
            let (ours, theirs) = (our_stress(m, g)?, a.stress(g));
            let norm = |s: [f64; 3]| (s[0] * s[0] + s[1] * s[1] + 2.0 * s[2] * s[2]).sqrt();
            let diff: [f64; 3] = std::array::from_fn(|i| theirs[i] - ours[i]);
            worst = worst.max(norm(diff) / norm(ours));
        }
    }
    Ok(worst)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::parse_material;

    fn material(extra: &str) -> FabricMaterial {
        let text = format!(
            "name = \"t\"\nareal_density_g_m2 = 103.6\nthickness_mm = 0.18\na11_pa = 2.0e8\na22_pa = 1.2e8\na12_pa = 1.0e7\ng12_pa = 4.0e6\n{extra}"
        );
        parse_material(&text, "test").unwrap()
    }

    fn rel(a: [f64; 3], b: [f64; 3]) -> f64 {
        let d: f64 = (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt();
        d / (0..3).map(|i| b[i] * b[i]).sum::<f64>().sqrt()
    }

    /// A linear law (St. Venant–Kirchhoff in the warp/weft frame) is what ARCSim's format
    /// holds exactly: k = 2·row 0 everywhere, W = ½k₀G₀₀² + k₁G₀₀G₁₁ + ½k₂G₁₁² + k₃G₀₁².
    #[test]
    fn a_linear_law_goes_through_the_file_and_back_exactly() {
        let m = material("");
        let (a, warnings) = export(&m, 0.08).unwrap();
        assert!(warnings.is_empty());
        let back = ArcsimMaterial::parse(&a.json("a comment\nover two lines")).unwrap();
        for (r, q) in back.stretching.iter().zip(&a.stretching) {
            for (x, y) in r.iter().zip(q) {
                assert!(
                    (x - y).abs() <= 1e-9 * y.abs(),
                    "ten significant digits survive"
                );
            }
        }
        assert!((back.density - 0.1036).abs() < 1e-12);
        for g in [
            [0.01, 0.0, 0.0],
            [0.0, 0.05, 0.02],
            [0.03, -0.01, -0.04],
            [-0.02, -0.02, 0.0],
            [0.1, 0.08, 0.06],
        ] {
            let (ours, theirs) = (our_stress(&m, g).unwrap(), back.stress(g));
            assert!(
                rel(theirs, ours) < 1e-8,
                "{g:?}: {theirs:?} against {ours:?}"
            );
        }
        assert!(stress_deviation(&m, &back, 0.08).unwrap() < 1e-8);
        // plate rigidities of the paper's section, τ³/12 · C₁₁₁₁ along the warp (row 2: the
        // hinge along v bends the warp), τ³/12 · C₂₂₂₂ along the weft (row 0)
        let d = 0.18e-3f64.powi(3) / 12.0;
        assert!((back.bending[2][0] - d * 2.0e8).abs() < 1e-9 * d * 2.0e8);
        assert!((back.bending[0][4] - d * 1.2e8).abs() < 1e-9 * d * 1.2e8);
        // at 45°: (a₁₁ + a₂₂ + 2a₁₂ + 2G₁₂)/4
        let bias = d * (2.0e8 + 1.2e8 + 2.0e7 + 8.0e6) / 4.0;
        assert!((back.bending[1][0] - bias).abs() < 1e-9 * bias);
    }

    /// A stiffening law: exact at small strain; elsewhere the format's ramp (stiffness linear
    /// in the principal stretch) is an approximation whose size the export reports.
    #[test]
    fn a_stiffening_law_is_exact_at_small_strain_and_its_deviation_is_reported() {
        let m = material("[warp]\nmu = [0.5, 0.5]\nalpha = [1.0, 30.0]\n");
        let (a, _) = export(&m, 0.08).unwrap();
        for deg in ROW_ANGLES_DEG {
            let g = uniaxial(1.0 + 1e-5, deg);
            let (ours, theirs) = (our_stress(&m, g).unwrap(), a.stress(g));
            assert!(
                rel(theirs, ours) < 1e-4,
                "{deg}°: {theirs:?} against {ours:?}"
            );
        }
        let dev = stress_deviation(&m, &a, 0.08).unwrap();
        let warp_end = uniaxial(1.08, 0.0);
        let miss = rel(a.stress(warp_end), our_stress(&m, warp_end).unwrap());
        assert!(miss <= dev && dev > 1e-3 && dev < 0.2, "{miss} {dev}");
        // the fitted ramp beats holding the small-strain stiffness
        let mut flat = a.clone();
        flat.stretching[1] = flat.stretching[0];
        assert!(miss < rel(flat.stress(warp_end), our_stress(&m, warp_end).unwrap()));
    }

    #[test]
    fn a_negative_coupling_is_exported_with_a_warning_and_bad_files_are_refused() {
        let m = material("").clone();
        let mut neg = m.clone();
        neg.law.a12 = -1.0e7;
        let (_, warnings) = export(&neg, 0.08).unwrap();
        assert!(warnings[0].contains("a12 < 0"), "{warnings:?}");
        assert!(export(&m, 0.5).is_err());
        for bad in [
            "{\"density\": 0.1, \"stretching\": [[1,2,3,4]], \"bending\": []}",
            "{\"stretching\": [], \"bending\": []}",
            "[1, 2]",
        ] {
            assert!(ArcsimMaterial::parse(bad).is_err(), "{bad}");
        }
    }
}
