//! A seeded sample of the fabric zoo (`paper_repro/zoo/`): the analytic fabrics, whose curves
//! the paper's law did not make, each checked, two fitted to the end on a coarse mesh, and the
//! smallest fitted by every triangle model.
//! (The law fabrics need the virtual lab to write them, minutes each; `paper_repro/zoo/run.sh`
//! writes and fits them.)

use crate::common::{folder, ks_fit, s, QUICK_FIT};
use kshell::synth::zoo::{build, draw};

/// The zoo's seed in `paper_repro/zoo/run.sh`.
const SEED: u64 = 58;

/// Writes analytic fabric `index` of the zoo into `dir`, returning its fabric.toml.
fn write(dir: &std::path::Path, index: usize) -> String {
    let fabric = draw(SEED, index);
    let z = build(&fabric, &mut |_| {}).expect("analytic fabrics build without a solve");
    let folder = dir.join(&fabric.name);
    z.write(&folder, "zoo sample").unwrap();
    s(&folder.join("fabric.toml")).to_string()
}

#[test]
fn every_analytic_fabric_of_a_seeded_sample_is_checked_without_a_panic() {
    let dir = folder("sample");
    for index in (1..40).step_by(2) {
        let path = write(&dir, index);
        let (rc, out, err) = ks_fit(&["check", &path]);
        assert!(rc == 0 || rc == 2, "{path}: exit {rc}\n{out}{err}");
        assert!(!err.contains("panicked"), "{path}: {err}");
        if rc == 2 {
            let first = err.lines().next().unwrap_or("");
            assert!(first.starts_with("ks-fit: error: "), "{path}: {err}");
        } else {
            assert!(out.contains("valid"), "{path}: {out}");
        }
    }
}

/// The first twenty analytic fabrics' indices, fewest curves first (to keep CI short).
fn fewest_curves_first() -> Vec<usize> {
    let mut picks: Vec<(usize, usize)> = (1..40)
        .step_by(2)
        .map(|i| {
            let p = draw(SEED, i).protocol;
            (p.angles.len() * p.repeats, i)
        })
        .collect();
    picks.sort();
    picks.into_iter().map(|(_, i)| i).collect()
}

#[test]
fn two_analytic_fabrics_fit_to_a_material_with_finite_numbers() {
    let dir = folder("fit");
    for &index in &fewest_curves_first()[..2] {
        let path = write(&dir, index);
        let out = dir.join(format!("m{index}.toml"));
        let mut args = vec!["fit", &path, "-o", s(&out), "--max-degree", "1", "--quiet"];
        args.extend(QUICK_FIT);
        let (rc, stdout, err) = ks_fit(&args);
        assert!(rc == 0 || rc == 3, "{path}: exit {rc}\n{stdout}{err}");
        let text = std::fs::read_to_string(&out).unwrap();
        // no value (comments aside) is NaN or infinite
        let values = text.lines().map(|l| l.split('#').next().unwrap_or(""));
        let bad = |v: &str| v.contains("nan") || v.contains("inf");
        assert!(!values.map(str::to_lowercase).any(|v| bad(&v)), "{text}");
        let m = kshell::material::load_material(&out).unwrap_or_else(|e| panic!("{e}"));
        let l = &m.law;
        assert!([l.a11, l.a22, l.a12, l.g12, m.thickness]
            .iter()
            .all(|x| x.is_finite()));
    }
}

/// Every triangle model fits the analytic fabric with the fewest curves (`z0015-analytic`:
/// exponential warp and bias, a long toe on the weft) to a material whose every stiffness and
/// every test's error is a finite number, whatever its verdict.
#[test]
fn every_triangle_model_fits_an_analytic_fabric_to_finite_numbers() {
    let dir = folder("tri-fit");
    let index = fewest_curves_first()[0];
    let path = write(&dir, index);
    for model in ["springs", "soft-constraints", "stvk-ds", "xpbd"] {
        let out = dir.join(format!("{model}.toml"));
        let (rc, stdout, err) = ks_fit(&["fit", &path, "--model", model, "-o", s(&out), "--quiet"]);
        assert!(rc == 0 || rc == 3, "{model}: exit {rc}\n{stdout}{err}");
        assert!(!err.contains("panicked"), "{model}: {err}");
        let text = std::fs::read_to_string(&out).unwrap();
        let values = text.lines().map(|l| l.split('#').next().unwrap_or(""));
        let bad = |v: &str| v.contains("nan") || v.contains("inf");
        assert!(
            !values.map(str::to_lowercase).any(|v| bad(&v)),
            "{model}:\n{text}"
        );
        assert!(
            text.contains("[model]") && text.contains("avg_rel_error"),
            "{model}:\n{text}"
        );
    }
}
