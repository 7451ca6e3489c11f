//! Exact force and drape-angle sensitivities through the equilibrium (Clyde et al. 2017, Eq. 6)
//! against central differences of full equilibrium solves.

use crate::common::TestLaw;
use kshell::material::FabricMaterial;
use kshell::scene::TensileStrip;

fn material() -> FabricMaterial {
    TestLaw::stvk(2.0e8, 1.2e8, 0.6e8, 4.0e6)
        .named("degree-2")
        .density(0.1)
        .thickness(3.0e-4)
        .warp(&[0.6, 0.4], &[1.0, 300.0])
        .weft(&[0.8, 0.2], &[2.0, 150.0])
        .shear(&[0.7, 0.3], &[1.0, 40.0])
        .material()
}

fn forces(
    m: &FabricMaterial,
    angle: f64,
    elongations: &[f64],
    sens: bool,
    grading: kshell::mesh::Grading,
) -> Vec<(f64, Vec<f64>)> {
    let mut strip = TensileStrip::new(0.05, 0.075, angle);
    strip.mesh = (4, 6);
    strip.grading = grading;
    strip.solver.rtol = 1e-13;
    // one discretisation for every perturbed law, as the sensitivities assume: the centre
    // rule's β (`auto` at this material's yarn-to-shear ratio) pinned at the base law's
    strip.yarn_ratio = kshell::material::Law::yarn_shear_ratio(&material().law);
    strip
        .run_with_sensitivities(m, elongations, sens)
        .unwrap()
        .into_iter()
        .map(|p| (p.force, p.dforce))
        .collect()
}

#[test]
fn strip_force_sensitivities_match_differences_of_full_solves() {
    let m = material();
    let elongations = [1.5e-3, 4.0e-3];
    // uniform and graded cages (the fit's default)
    let gradings = [kshell::mesh::Grading::UNIFORM, kshell::scene::STRIP_GRADING];
    for (angle, grading) in [90.0, 45.0, 22.5]
        .into_iter()
        .flat_map(|a| gradings.map(|g| (a, g)))
    {
        let exact = forces(&m, angle, &elongations, true, grading);
        let mut k = m.law.params();
        k.push(m.thickness);
        for j in 0..k.len() {
            let h = 1e-6 * k[j].abs().max(1e-3);
            let at = |v: f64| {
                let mut kk = k.clone();
                kk[j] = v;
                let mut mm = m.clone();
                mm.law.set_params(&kk[..kk.len() - 1]);
                mm.thickness = kk[kk.len() - 1];
                forces(&mm, angle, &elongations, false, grading)
            };
            let (plus, minus) = (at(k[j] + h), at(k[j] - h));
            for (i, (f, df)) in exact.iter().enumerate() {
                let fd = (plus[i].0 - minus[i].0) / (2.0 * h);
                // compare in relative terms of the force per unit of relative parameter change
                let scale = f.abs() / k[j].abs().max(1e-3);
                assert!(
                    (df[j] - fd).abs() <= 1e-5 * scale + 1e-7 * df[j].abs(),
                    "angle {angle}, {grading:?}, parameter {j} ({}), point {i}: exact {} vs differences {fd}",
                    m.law.names().get(j).cloned().unwrap_or("thickness".into()),
                    df[j]
                );
            }
        }
    }
}

#[test]
fn drape_angle_sensitivities_match_differences_of_full_solves() {
    use kshell::scene::{BendRig, CantileverBend};
    let m = material();
    let mut bend = CantileverBend::new(0.025, 0.15, 90.0);
    bend.mesh = (4, 10);
    bend.solver.rtol = 1e-13;
    let angle = |mm: &FabricMaterial, sens: bool| {
        let mut rig = BendRig::new(&bend, mm).unwrap();
        rig.run(sens).unwrap()
    };
    let exact = angle(&m, true);
    assert!(exact.drape_angle_deg > 5.0, "{}", exact.drape_angle_deg);
    let mut k = m.law.params();
    k.push(m.thickness);
    // a11, a22, a12, g12, warp μ₂ and α₂, thickness (each a full load ramp twice)
    for j in [0, 1, 2, 3, 5, 7, k.len() - 1] {
        let h = 1e-6 * k[j].abs().max(1e-3);
        let at = |v: f64| {
            let mut kk = k.clone();
            kk[j] = v;
            let mut mm = m.clone();
            mm.law.set_params(&kk[..kk.len() - 1]);
            mm.thickness = kk[kk.len() - 1];
            angle(&mm, false).drape_angle_deg
        };
        let fd = (at(k[j] + h) - at(k[j] - h)) / (2.0 * h);
        let scale = exact.drape_angle_deg / k[j].abs().max(1e-3);
        assert!(
            (exact.dangle[j] - fd).abs() <= 1e-5 * scale + 1e-6 * fd.abs(),
            "parameter {j}: exact {} vs differences {fd}",
            exact.dangle[j]
        );
    }
    // a warm-started rerun with the same material lands on the same angle
    let mut rig = BendRig::new(&bend, &m).unwrap();
    let first = rig.run(false).unwrap().drape_angle_deg;
    let second = rig.run(false).unwrap().drape_angle_deg;
    assert!((first - second).abs() < 1e-9 && (first - exact.drape_angle_deg).abs() < 1e-9);
}

/// A bend rerun after a run with sensitivities starts from q + ∂q/∂k Δk: for a 5 % change of
/// the thickness (the bend's strongest parameter) it needs fewer Newton iterations than a rerun
/// from the last equilibrium alone, and lands where a fresh rig does.
#[test]
fn a_bend_rerun_starts_from_its_parameter_tangent() {
    use kshell::scene::{BendRig, CantileverBend};
    let m = material();
    let mut bend = CantileverBend::new(0.025, 0.15, 90.0);
    bend.mesh = (4, 10);
    let mut moved = m.clone();
    moved.thickness *= 1.05;
    let rerun = |sens: bool| {
        let mut rig = BendRig::new(&bend, &m).unwrap();
        rig.run(sens).unwrap();
        rig.set_material(&moved.law, moved.thickness).unwrap();
        rig.run(false).unwrap()
    };
    let (tangent, plain) = (rerun(true), rerun(false));
    let fresh = BendRig::new(&bend, &moved).unwrap().run(false).unwrap();
    for p in [&tangent, &plain] {
        assert!(
            (p.drape_angle_deg - fresh.drape_angle_deg).abs() < 1e-7,
            "{} vs {}",
            p.drape_angle_deg,
            fresh.drape_angle_deg
        );
    }
    assert!(
        tangent.report.iterations < plain.report.iterations,
        "{} vs {}",
        tangent.report.iterations,
        plain.report.iterations
    );
}

/// Bending of its own: ∂angle/∂B for the three rigidities (and a11, τ) against differences.
#[test]
fn drape_angle_sensitivities_to_own_rigidities_match_differences() {
    use kshell::material::BendingRigidity;
    use kshell::scene::{BendRig, CantileverBend};
    let mut m = material();
    let b0 = BendingRigidity {
        warp: 4.0e-4,
        weft: 1.5e-4,
        twist: 5.0e-6,
    };
    m.bending = Some(b0);
    let nlaw = m.law.params().len();
    // a strip cut at 30° from the weft bends, twists and (through the clamp) couples all three
    for angle_cut in [30.0] {
        let mut bend = CantileverBend::new(0.025, 0.15, angle_cut);
        bend.mesh = (4, 10);
        bend.solver.rtol = 1e-13;
        let angle = |mm: &FabricMaterial, sens: bool| {
            let mut rig = BendRig::new(&bend, mm).unwrap();
            rig.run(sens).unwrap()
        };
        let exact = angle(&m, true);
        assert_eq!(exact.dangle.len(), nlaw + 4);
        assert!(exact.drape_angle_deg > 5.0, "{}", exact.drape_angle_deg);
        for j in [0, nlaw, nlaw + 1, nlaw + 2, nlaw + 3] {
            let at = |rel: f64| {
                let mut mm = m.clone();
                let b = mm.bending.as_mut().unwrap();
                match j - nlaw.min(j) {
                    _ if j == 0 => mm.law.a11 *= 1.0 + rel,
                    0 => mm.thickness *= 1.0 + rel,
                    1 => b.warp *= 1.0 + rel,
                    2 => b.weft *= 1.0 + rel,
                    _ => b.twist *= 1.0 + rel,
                }
                angle(&mm, false).drape_angle_deg
            };
            let k = match j - nlaw.min(j) {
                _ if j == 0 => m.law.a11,
                0 => m.thickness,
                1 => b0.warp,
                2 => b0.weft,
                _ => b0.twist,
            };
            let h = 1e-6;
            let fd = (at(h) - at(-h)) / (2.0 * h * k);
            let scale = exact.drape_angle_deg / k;
            assert!(
                (exact.dangle[j] - fd).abs() <= 1e-5 * scale + 1e-6 * fd.abs(),
                "cut {angle_cut}°, parameter {j}: exact {} vs differences {fd}",
                exact.dangle[j]
            );
        }
    }
}
