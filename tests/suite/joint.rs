//! The joint sweep (`fit --joint`) and the log misfit (`fit --objective`) end to end, on data
//! that the fit's own mesh did not make (strips at 90°, 0°, 45°, 22.5° and 67.5° synthesised
//! on graded 16 × 24 cages, fitted on 8 × 12).
//!
//! The warp curve is scaled by 0.8 after synthesis: a warp sample that came out weak (a strip
//! cut narrow, fewer yarns in it), as the bundled denim's three warp repeats did (0.62–1.15 of
//! the law that made them). The staged fit takes a11 from the warp strip alone, so it comes out
//! 20 % low, and the 67.5° strip (mostly warp) inherits that while the shear stage, which holds
//! the yarns, cannot correct it. The joint sweep refits the warp over the off-axis strips too:
//! a11 then lies between what the warp strip and the off-axis strips say, and the off-axis
//! strips follow.

use crate::common::{folder, ks_fit, s, tensile_error_at as error_at};

const TRUE_A11: f64 = 3.0e7;

const MATERIAL: &str = "name = \"weak-warp-sample\"
areal_density_g_m2 = 150.0
thickness_mm = 0.3
a11_pa = 3.0e7
a22_pa = 2.0e7
g12_pa = 1.0e6
";

/// `ks-fit synth` of [`MATERIAL`] into `dir/data` with `extra` options; its fabric.toml.
fn synth(dir: &std::path::Path, extra: &[&str]) -> std::path::PathBuf {
    let m = dir.join("material.toml");
    std::fs::write(&m, MATERIAL).unwrap();
    let data = dir.join("data");
    let mut args = vec!["synth", "--material", s(&m), "--out", s(&data)];
    args.extend_from_slice(extra);
    let (rc, out, err) = ks_fit(&args);
    assert_eq!(rc, 0, "{out}{err}");
    data.join("fabric.toml")
}

/// [`synth`] on graded 16 × 24 cages to 5 % strain, one repeat per angle; then the warp curve's
/// forces times `factor`.
fn synth_weak_warp(dir: &std::path::Path, factor: f64) -> std::path::PathBuf {
    let fabric = synth(
        dir,
        &[
            "--points",
            "6",
            "--mesh",
            "16x24",
            "--grading",
            "0.8,0.8",
            "--max-strain",
            "0.05",
        ],
    );
    let data = fabric.parent().unwrap();
    let warp = data.join("warp-1.csv");
    let text = std::fs::read_to_string(&warp).unwrap();
    let mut scaled = String::new();
    for (i, line) in text.lines().enumerate() {
        if i == 0 {
            scaled += line;
        } else {
            let (e, f) = line.split_once(',').unwrap();
            let f: f64 = f.trim().parse().unwrap();
            scaled += &format!("{e},{}", factor * f);
        }
        scaled.push('\n');
    }
    std::fs::write(&warp, scaled).unwrap();
    fabric
}

/// The fitted material (degree 1, the 8 × 12 level only, no coupling) with `extra` options.
fn fit(fabric: &std::path::Path, tag: &str, extra: &[&str]) -> toml::Table {
    let out_file = fabric.with_file_name(format!("fit-{tag}.toml"));
    let mut args = vec![
        "fit",
        s(fabric),
        "-o",
        s(&out_file),
        "--degree",
        "1",
        "--mesh-ladder",
        "8x12",
        "--test-meshes",
        "ladder",
        "--shear-coupling",
        "off",
    ];
    args.extend_from_slice(extra);
    let (rc, out, err) = ks_fit(&args);
    assert!(rc == 0 || rc == 3, "{out}{err}");
    std::fs::read_to_string(&out_file).unwrap().parse().unwrap()
}

#[test]
fn the_joint_sweep_lets_the_off_axis_strips_correct_a_weak_warp_sample() {
    let dir = folder("joint");
    let fabric = synth_weak_warp(&dir, 0.8);
    let staged = fit(&fabric, "staged", &["--joint", "off"]);
    let joint = fit(&fabric, "joint", &[]);
    assert_eq!(staged["fit"]["joint"].as_bool(), Some(false));
    assert_eq!(joint["fit"]["joint"].as_bool(), Some(true));
    // one curve per angle: the relative misfit under auto
    assert_eq!(joint["fit"]["objective"].as_str(), Some("relative"));
    let a11 = |d: &toml::Table| d["a11_pa"].as_float().unwrap() / TRUE_A11 - 1.0;
    let (a_staged, a_joint) = (a11(&staged), a11(&joint));
    // the staged fit follows the weak warp strip (−20 %, less what the 8 × 12 cage adds:
    // −15 % measured); the joint optimum weighs it against three off-axis strips (−12 %
    // measured; one sweep of the stages reaches it: two and four sweeps moved a11 by 0.5 %)
    assert!(
        (-0.20..-0.10).contains(&a_staged),
        "staged a11 off by {a_staged}"
    );
    assert!(
        a_joint.abs() < 0.85 * a_staged.abs(),
        "joint a11 off by {a_joint}, staged by {a_staged}"
    );
    // the 67.5° strip (22.5° from the warp) follows (13.6 % -> 9.7 % measured); the warp strip
    // pays some of it
    let (e_staged, e_joint) = (error_at(&staged, 67.5), error_at(&joint, 67.5));
    assert!(e_staged > 0.08, "staged 67.5° error {e_staged}");
    assert!(
        e_joint < 0.8 * e_staged,
        "67.5°: joint {e_joint} against staged {e_staged}"
    );
    assert!(error_at(&joint, 90.0) > error_at(&staged, 90.0));
    // and a11's standard error says that the strips disagree: from the spread of the joint
    // stage's curves (7 % measured) where the warp strip alone fitted itself to 0.002 %
    let rel_se = |d: &toml::Table| {
        let u = d["fit"]["uncertainty"]["a11_pa"].as_table().unwrap();
        u["std_error"].as_float().unwrap() / u["value"].as_float().unwrap()
    };
    assert!(rel_se(&staged) < 0.01, "staged a11 ± {}", rel_se(&staged));
    assert!(rel_se(&joint) > 0.03, "joint a11 ± {}", rel_se(&joint));
}

/// A warp sample at a quarter of the force the off-axis strips ask of the warp (a sample from
/// another bolt): the joint optimum would put the model far above the warp strip, more than
/// `--max-error` outside it, so the sweep's warp stiffness is not kept and the warp strip keeps
/// its own fit, as in the staged fit; the note says so.
#[test]
fn a_joint_sweep_that_would_fail_the_yarn_strips_is_not_kept() {
    let dir = folder("joint-guard");
    let fabric = synth_weak_warp(&dir, 0.25);
    let staged = fit(&fabric, "staged", &["--joint", "off"]);
    let joint = fit(&fabric, "joint", &[]);
    let notes = joint["fit"]["notes"].as_array().unwrap();
    let said = notes
        .iter()
        .filter_map(|n| n.as_str())
        .any(|n| n.starts_with("joint sweep: the warp stiffness") && n.contains("not kept"));
    assert!(said, "{notes:?}");
    let a11 = |d: &toml::Table| d["a11_pa"].as_float().unwrap();
    let moved = a11(&joint) / a11(&staged) - 1.0;
    assert!(moved.abs() < 0.01, "joint a11 against staged: {moved}");
    assert!(
        error_at(&joint, 90.0) < 0.03,
        "warp {}",
        error_at(&joint, 90.0)
    );
}

/// The log misfit, chosen by auto where an angle has repeats, names itself in `[fit]`; the
/// relative one can be forced.
#[test]
fn repeats_make_auto_take_the_log_misfit() {
    let dir = folder("objective");
    let fabric = synth(
        &dir,
        &[
            "--points",
            "4",
            "--mesh",
            "8x12",
            "--max-strain",
            "0.03",
            "--repeats",
            "2",
            "--noise",
            "0.1",
        ],
    );
    let quick = ["--joint", "off", "--mesh-check", "off"];
    let auto = fit(&fabric, "auto", &quick);
    assert_eq!(auto["fit"]["objective"].as_str(), Some("log"));
    let mut forced = quick.to_vec();
    forced.extend_from_slice(&["--objective", "relative"]);
    let relative = fit(&fabric, "relative", &forced);
    assert_eq!(relative["fit"]["objective"].as_str(), Some("relative"));
    // equal to first order: the two laws differ by the repeats' scatter, not by more
    let a = |d: &toml::Table| d["a11_pa"].as_float().unwrap();
    let d = a(&auto) / a(&relative) - 1.0;
    assert!(d.abs() < 0.1 && d != 0.0, "log against relative a11: {d}");
}
