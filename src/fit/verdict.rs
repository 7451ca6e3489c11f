//! The fit's verdict: every test's error set against the paper's fit errors (Clyde et al. 2017,
//! Table 3: 1–3 % for warp and weft, 2.6–5.1 % for bias, mean |relative error|) and against the
//! user's `--max-error`. A fitted test above `--max-error` makes the fit a failure (`ks-fit fit`
//! exits 3); a validation test above it is reported, not failed: it is a prediction.
//!
//! What is judged. A curve fitted alone at its angle (or a validation curve, or any curve with
//! `--repeat largest`) is judged by its mean |relative error| at the nominal angle. Repeats
//! fitted together at one angle differ from each other by a force scale (strip width, yarns per
//! strip: the table's `scale` s, measured ≈ s·model; 0.76–1.22 on the bundled canvas) that no
//! law can follow, and the fit passes through their middle. Each such repeat is judged by the
//! larger of its shape error (the mean |relative error| after its own scale: `scaled_error`)
//! and how far the model lies outside the repeats' scatter band (0 when the smallest s ≤ 1 ≤
//! the largest s, else the distance from 1 to the nearest s). Its raw error, scatter included,
//! stays in the table. A bend is judged by |drape angle − measured| / measured.

use super::{FitResult, TestOutcome};

/// Largest warp/weft fit error of the paper's Table 3.
pub const TABLE3_AXIS: f64 = 0.03;
/// Largest bias fit error of the paper's Table 3 (the bound used for every off-axis angle).
pub const TABLE3_OFF_AXIS: f64 = 0.051;

/// The paper's Table 3 bound for a tensile test at `angle_deg`.
fn table3_bound(angle_deg: f64) -> f64 {
    let a = angle_deg.rem_euclid(180.0);
    if a.abs() < 1e-9 || (a - 90.0).abs() < 1e-9 {
        TABLE3_AXIS
    } else {
        TABLE3_OFF_AXIS
    }
}

/// One test judged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Judgement {
    /// the error judged (see the module doc), `None` for a test without one
    pub error: Option<f64>,
    /// `T3` within the paper's Table 3 bound (tensile), `ok` within `--max-error`, `OVER` a
    /// fitted test above it, `high` a test not fitted (validation, or a repeat left out) above
    /// it, `-` nothing to judge
    pub mark: &'static str,
}

/// The force scale s with measured ≈ s·model that best explains a curve's ratios
/// q = model/measured (s = Σq/Σq² minimises Σ(s q − 1)²), and the mean |relative error| left
/// after it: (s, scaled error). NaN for both when `q` is empty.
pub(crate) fn force_scale(q: &[f64]) -> (f64, f64) {
    let scale = q.iter().sum::<f64>() / q.iter().map(|v| v * v).sum::<f64>();
    let scaled = q.iter().map(|v| (scale * v - 1.0).abs()).sum::<f64>() / q.len() as f64;
    (scale, scaled)
}

/// A repeat's judged error (see the module doc): the larger of its error after its own scale
/// and how far the model lies outside the repeats' scale band (0 when the smallest scale ≤ 1 ≤
/// the largest).
pub(crate) fn repeat_error(scaled: f64, scales: &[f64]) -> f64 {
    let lo = scales.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = scales.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let outside = (lo - 1.0).max(1.0 - hi).max(0.0);
    scaled.max(outside)
}

/// A fitted repeat whose force scale lies more than this factor from every other repeat's at
/// its angle is no scatter of one fabric (the bundled canvas's repeats span 0.76–1.22) but a
/// curve with slack or a preload left in, another strip width or another force unit.
pub const REPEAT_OUTLIER_FACTOR: f64 = 2.0;

/// Warnings naming each fitted repeat whose force scale lies more than
/// [`REPEAT_OUTLIER_FACTOR`] from every other fitted repeat's at its angle (two others or
/// more). Such a curve pulls the stages that fit it (`z0002-law` of the lab zoo: one 75° curve
/// with 2 mm of slack left in, scale 0.19 against 0.89–1.13, and its 45° strips ended 49 %
/// outside their band).
pub(crate) fn outlier_repeats(tests: &[TestOutcome]) -> Vec<String> {
    let fitted =
        |t: &&TestOutcome| t.used_in_fit && t.kind == "tensile" && t.repeat_scale.is_some();
    let mut notes = Vec::new();
    for (i, t) in tests.iter().enumerate() {
        let Some(s) = t.repeat_scale.filter(|_| fitted(&t)) else {
            continue;
        };
        let others: Vec<f64> = tests
            .iter()
            .enumerate()
            .filter(|(j, o)| *j != i && fitted(o) && (o.angle_deg - t.angle_deg).abs() < 1e-9)
            .filter_map(|(_, o)| o.repeat_scale)
            .collect();
        let far = |o: &f64| (s / o).max(o / s) > REPEAT_OUTLIER_FACTOR;
        if others.len() >= 2 && others.iter().all(far) {
            let lo = others.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = others.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            notes.push(format!(
                "warning: tensile {}° {}: its force scale {s:.3} lies more than {REPEAT_OUTLIER_FACTOR} times from each of its other {} repeats' ({lo:.3}–{hi:.3}): no scatter of one fabric; check its toe (slack, preload), strip width and force unit",
                t.angle_deg,
                t.curve.as_deref().unwrap_or("-"),
                others.len()
            ));
        }
    }
    notes
}

/// A bend's judged error: |drape angle − measured| / measured.
pub(crate) fn drape_error(angle: f64, measured: f64) -> f64 {
    (angle - measured).abs() / measured
}

/// Whether an error is over `max_error`; one that is not a number (a test that does not
/// solve) always is.
pub(crate) fn is_over(error: f64, max_error: f64) -> bool {
    error > max_error || error.is_nan()
}

/// The error the verdict reads for test `i` of `r` (see the module doc).
fn judged_error(r: &FitResult, i: usize) -> Option<f64> {
    let t = &r.tests[i];
    if let (Some(a), Some(g)) = (t.drape_angle_deg, t.target_drape_deg) {
        return Some(drape_error(a, g));
    }
    let siblings: Vec<&TestOutcome> = r
        .tests
        .iter()
        .filter(|o| {
            o.used_in_fit
                && o.drape_angle_deg.is_none()
                && o.kind == t.kind
                && (o.angle_deg - t.angle_deg).abs() < 1e-9
        })
        .collect();
    if !t.used_in_fit || siblings.len() < 2 {
        return t.avg_rel_error;
    }
    let scales: Vec<f64> = siblings.iter().filter_map(|o| o.repeat_scale).collect();
    match t.avg_rel_error_scaled {
        Some(shape) if !scales.is_empty() => Some(repeat_error(shape, &scales)),
        _ => t.avg_rel_error,
    }
}

/// Every test of `r` judged against `max_error` (a fraction: 0.1 is 10 %), in table order.
pub fn judge(r: &FitResult, max_error: f64) -> Vec<Judgement> {
    (0..r.tests.len())
        .map(|i| {
            let t = &r.tests[i];
            let error = judged_error(r, i);
            let mark = match error {
                None => "-",
                Some(e) if is_over(e, max_error) => {
                    if t.used_in_fit {
                        "OVER"
                    } else {
                        "high"
                    }
                }
                Some(e) if t.drape_angle_deg.is_none() && e <= table3_bound(t.angle_deg) => "T3",
                Some(_) => "ok",
            };
            Judgement { error, mark }
        })
        .collect()
}

/// The fit as a whole.
#[derive(Clone, Debug)]
pub struct Verdict {
    /// fitted tests above `--max-error`: "kind angle° curve: error"
    pub failed: Vec<String>,
    /// one line for the user
    pub line: String,
}

impl Verdict {
    pub fn passed(&self) -> bool {
        self.failed.is_empty()
    }
}

/// The verdict on `r` against `max_error`.
pub fn verdict(r: &FitResult, max_error: f64) -> Verdict {
    let name = |t: &TestOutcome| {
        format!(
            "{} {}° {}",
            t.kind,
            t.angle_deg,
            t.curve.as_deref().unwrap_or("")
        )
        .trim_end()
        .to_string()
    };
    let judged = judge(r, max_error);
    let pairs: Vec<(&TestOutcome, &Judgement)> = r.tests.iter().zip(&judged).collect();
    let failed: Vec<String> = pairs
        .iter()
        .filter(|(_, j)| j.mark == "OVER")
        .map(|(t, j)| format!("{}: {:.2} %", name(t), 100.0 * j.error.unwrap_or(f64::NAN)))
        .collect();
    let strips = pairs
        .iter()
        .filter(|(t, j)| t.used_in_fit && t.drape_angle_deg.is_none() && j.error.is_some())
        .count();
    let in_t3 = pairs
        .iter()
        .filter(|(t, j)| t.used_in_fit && j.mark == "T3")
        .count();
    let high: Vec<String> = pairs
        .iter()
        .filter(|(_, j)| j.mark == "high")
        .map(|(t, _)| name(t))
        .collect();
    let pct = 100.0 * max_error;
    let mut line = if failed.is_empty() {
        format!(
            "verdict: fit within --max-error {pct} % on every fitted test; {in_t3} of {strips} fitted strips within the paper's Table 3 errors (3 % warp/weft, 5.1 % other angles)"
        )
    } else {
        format!(
            "verdict: FIT FAILED: {} fitted test(s) above --max-error {pct} %: {}",
            failed.len(),
            failed.join("; ")
        )
    };
    if !high.is_empty() {
        // validation runs, and repeats left out of the fit (`--repeat largest`)
        line.push_str(&format!(
            "; not fitted and above {pct} % (predictions, not failures): {}",
            high.join(", ")
        ));
    }
    Verdict { failed, line }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strip(angle_deg: f64, raw: f64, scale: f64, shape: f64) -> TestOutcome {
        TestOutcome {
            kind: "tensile",
            angle_deg,
            curve: Some(format!("a{angle_deg}-{scale}.csv")),
            repeat: Some(1),
            avg_rel_error: Some(raw),
            drape_angle_deg: None,
            target_drape_deg: None,
            misalign_deg: None,
            avg_rel_error_aligned: None,
            repeat_scale: Some(scale),
            avg_rel_error_scaled: Some(shape),
            toe: None,
            mesh: None,
            mesh_error_est: None,
            points: Vec::new(),
            used_in_fit: true,
        }
    }

    fn result(tests: Vec<TestOutcome>) -> FitResult {
        let material = crate::material::parse_material(
            "name = \"t\"\nareal_density_g_m2 = 100\nthickness_mm = 0.2\na11_pa = 1e8\na22_pa = 1e8\ng12_pa = 1e6\n",
            "t.toml",
        )
        .unwrap();
        FitResult {
            material,
            method: "bfgs".into(),
            meshes: vec![(8, 12)],
            stats: Default::default(),
            degree_log: Vec::new(),
            notes: Vec::new(),
            identifiability: Vec::new(),
            a12_dependence: [None; 3],
            uncertainty: Vec::new(),
            tests,
            max_error: 0.1,
            mesh_check: None,
            shapes_fitted: false,
            yarn_rule: crate::assembly::YarnRule::Full,
            shear_coupling: crate::fit::coupling::CouplingOutcome::Off,
            objective: crate::fit::Misfit::Relative,
            joint: false,
            test_meshes: crate::fit::TestMeshes::Own,
        }
    }

    #[test]
    fn a_repeat_far_from_every_other_is_named() {
        // z0002-law's 75° repeats with one curve's slack left in; the canvas's 22.5° scatter
        let tests = vec![
            strip(75.0, 0.02, 1.017, 0.02),
            strip(75.0, 2.74, 0.191, 0.43),
            strip(75.0, 0.11, 1.122, 0.04),
            strip(75.0, 0.10, 1.105, 0.05),
            strip(75.0, 0.13, 0.887, 0.02),
            strip(22.5, 0.063, 1.066, 0.018),
            strip(22.5, 0.204, 0.830, 0.017),
            strip(22.5, 0.320, 0.758, 0.016),
        ];
        let notes = outlier_repeats(&tests);
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(notes[0].contains("75° a75-0.191.csv") && notes[0].contains("0.887–1.122"));
        // two repeats that disagree by a factor 3 cannot tell which one is off
        assert!(outlier_repeats(&tests[..2]).is_empty());
        // a repeat left out of the fit is not named, nor counted
        let mut left_out = tests.clone();
        left_out[1].used_in_fit = false;
        assert!(outlier_repeats(&left_out).is_empty());
    }

    #[test]
    fn repeats_are_judged_by_shape_and_the_scatter_band() {
        // three repeats at 22.5° scattered 0.76–1.07 around the fit (the bundled canvas): raw
        // errors up to 32 %, but the fit lies inside their band and follows their shape
        let r = result(vec![
            strip(22.5, 0.063, 1.066, 0.018),
            strip(22.5, 0.204, 0.830, 0.017),
            strip(22.5, 0.320, 0.758, 0.016),
            // one curve alone at 90°: its raw error is what counts
            strip(90.0, 0.025, 1.0, 0.01),
        ]);
        let j = judge(&r, 0.1);
        assert_eq!(j[0].error, Some(0.018));
        assert_eq!(j[2].mark, "T3");
        assert_eq!(j[3].error, Some(0.025));
        assert_eq!(j[3].mark, "T3");
        assert!(verdict(&r, 0.1).passed());
        // all repeats 15–25 % above the model: it misses the band by 15 %
        let r = result(vec![
            strip(45.0, 0.15, 1.15, 0.01),
            strip(45.0, 0.25, 1.25, 0.01),
        ]);
        let j = judge(&r, 0.1);
        assert!((j[0].error.unwrap() - 0.15).abs() < 1e-12);
        assert_eq!(j[0].mark, "OVER");
        let v = verdict(&r, 0.1);
        assert!(
            !v.passed() && v.line.starts_with("verdict: FIT FAILED: 2 fitted"),
            "{}",
            v.line
        );
        // a validation curve above the bound is reported, not failed
        let mut t = strip(67.5, 0.3, 1.0, 0.3);
        t.used_in_fit = false;
        t.kind = "validation";
        let r = result(vec![strip(90.0, 0.02, 1.0, 0.02), t]);
        assert_eq!(judge(&r, 0.1)[1].mark, "high");
        assert!(verdict(&r, 0.1).passed());
        // a repeat left out of the fit (--repeat largest) is neither a failure nor in the tally
        let mut left_out = strip(90.0, 0.02, 1.0, 0.02);
        left_out.used_in_fit = false;
        let r = result(vec![strip(90.0, 0.02, 1.0, 0.02), left_out]);
        let v = verdict(&r, 0.1);
        assert!(v.line.contains("1 of 1 fitted strips"), "{}", v.line);
    }
}
