use super::curves::{pchip, Family};
use super::*;

#[test]
fn a_fabric_depends_on_the_seed_and_its_index_only() {
    assert_eq!(draw(58, 7), draw(58, 7));
    assert_ne!(draw(58, 7), draw(59, 7));
    assert_ne!(draw(58, 6), draw(58, 8));
    assert!(draw(58, 4).name.ends_with("-law") && draw(58, 7).name.ends_with("-analytic"));
    // one law fabric in four is measured by a triangle model
    let tri = draw(58, 6);
    assert!(tri.lab.is_some() && tri.name.ends_with(tri.lab.unwrap().name()));
    assert!(draw(58, 4).lab.is_none() && draw(58, 7).lab.is_none());
}

#[test]
fn drawn_materials_stay_in_their_ranges_and_are_valid() {
    for i in (0..400).step_by(2) {
        let f = draw(1, i);
        let Source::Law(m) = &f.source else {
            panic!("even indices are law fabrics")
        };
        let l = &m.law;
        let (e1, e2) = (l.a11 * m.thickness, l.a22 * m.thickness);
        assert!((2e3..2e6 * 5.0).contains(&e1.max(e2)), "{e1} {e2}");
        assert!((0.2..=5.0).contains(&(e1 / e2)), "warp/weft {}", e1 / e2);
        let ratio = l.a11.max(l.a22) / l.g12;
        assert!((10.0..=1e5).contains(&ratio), "yarn/shear {ratio}");
        assert!(l.g12 * m.thickness >= MIN_SHEAR * (1.0 - 1e-12));
        assert!(l.a12 * l.a12 < l.a11 * l.a22);
        assert!((0.05..=0.7).contains(&m.areal_density));
        assert!((0.08e-3..=1.3e-3).contains(&m.thickness));
        for eta in [&l.warp, &l.weft, &l.shear] {
            assert!((1..=4).contains(&eta.degree()));
            assert!((eta.mu.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
        let b = m.bending.expect("a rigidity for every law fabric");
        assert!(b.warp > 0.0 && b.weft > 0.0 && b.twist > 0.0);
        // the truth's material file loads (a law whose stress stops rising is cut off first)
        let text = crate::material::material_toml(m);
        crate::material::parse_material(&text, &f.name).unwrap_or_else(|e| panic!("{e}"));
        let p = &f.protocol;
        assert!(p.bias_only || (3..=9).contains(&p.angles.len()));
        assert!((1..=5).contains(&p.repeats) && (5..=2000).contains(&p.points));
    }
}

#[test]
fn the_protocols_cover_what_labs_do() {
    let all: Vec<Protocol> = (0..400).map(|i| draw(3, i).protocol).collect();
    let share = |f: &dyn Fn(&Protocol) -> bool| all.iter().filter(|p| f(p)).count();
    assert!(share(&|p| p.slack > 0.0) > 80);
    assert!(share(&|p| p.preload > 0.0) > 20);
    assert!(share(&|p| p.export != Export::Newtons) > 40);
    assert!(share(&|p| p.bias_only) > 5);
    assert!(share(&|p| p.bends) > 150);
    assert!(share(&|p| p.points > 500) > 40 && share(&|p| p.points < 20) > 40);
    assert!(share(&|p| p.strip.0 == 0.025) > 40 && share(&|p| p.strip.0 == 0.1) > 40);
}

#[test]
fn every_family_starts_at_zero_and_stiffens_or_stays_linear() {
    let mut rng = Rng(5);
    for _ in 0..200 {
        let f = Family::draw(&mut rng, 1e4);
        assert!(
            f.force(0.05, 0.0).abs() < 1e-12 * f.force(0.05, 0.1),
            "{f:?}"
        );
        let strains: Vec<f64> = (1..=100).map(|i| 0.002 * i as f64).collect();
        let forces: Vec<f64> = strains.iter().map(|&e| f.force(0.05, e)).collect();
        assert!(forces.windows(2).all(|w| w[1] > w[0]), "{f:?}");
        // slopes never fall (each family stiffens or stays linear)
        let slopes: Vec<f64> = forces.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(
            slopes.windows(2).all(|s| s[1] >= s[0] * (1.0 - 1e-9)),
            "{f:?}"
        );
    }
    // the newcomer's F = k e (1 + c e): 21 N/mm and c = 0.08 /mm on a 75 mm gauge, 50 mm wide
    let k = 21.0e3 * 0.075 / 0.05;
    let q = Family::Quadratic {
        stiffness: k,
        c: 0.08 * 75.0,
    };
    let e_mm = 6.0;
    let want = 21.0 * e_mm * (1.0 + 0.08 * e_mm);
    assert!((q.force(0.05, e_mm / 75.0) / want - 1.0).abs() < 1e-12);
}

#[test]
fn pchip_is_exact_on_lines_and_never_overshoots() {
    let xs = [0.0, 1.0, 2.5, 4.0];
    let line: Vec<f64> = xs.iter().map(|x| 3.0 * x - 1.0).collect();
    for x in [0.0, 0.3, 1.0, 2.0, 3.9, 4.0] {
        assert!((pchip(&xs, &line, x) - (3.0 * x - 1.0)).abs() < 1e-12);
    }
    let step = [0.0, 0.0, 1.0, 1.0];
    for i in 0..=400 {
        let y = pchip(&xs, &step, 0.01 * i as f64);
        assert!((-1e-15..=1.0 + 1e-15).contains(&y), "{y}");
    }
}

#[test]
fn an_analytic_fabric_builds_a_dataset_with_its_artefacts() {
    let mut f = draw(11, 1);
    f.protocol.slack = 1e-3;
    f.protocol.preload = 0.0;
    f.protocol.points = 40;
    f.protocol.export = Export::KiloNewtonsScaled;
    let z = build(&f, &mut |_| {}).unwrap();
    let n = f.protocol.angles.len() * f.protocol.repeats;
    assert_eq!(z.data.tensile.len(), n);
    assert_eq!(z.curves.len(), n);
    assert!(z.truth.is_none());
    let t = &z.data.tensile[0];
    assert_eq!(t.force_scale, 1e3);
    assert_eq!(t.elongation.len(), 40);
    // the slack's points carry only the load cell's noise
    let fmax = t.force.iter().fold(0.0f64, |a, &b| a.max(b));
    let in_slack = t
        .elongation
        .iter()
        .zip(&t.force)
        .filter(|(e, _)| **e < 1e-3);
    assert!(in_slack.clone().count() > 0);
    assert!(in_slack.into_iter().all(|(_, f)| f.abs() < 0.02 * fmax));
    assert!(z.curves[0].1.starts_with("elongation_mm,force_n\n"));
    assert_eq!(z.data.bend.len(), if f.protocol.bends { 2 } else { 0 });
}

#[test]
fn a_strip_that_carries_no_force_is_not_written() {
    let mut f = draw(11, 1);
    if let Source::Analytic { warp, .. } = &mut f.source {
        *warp = Family::Quadratic {
            stiffness: 0.0,
            c: 1.0,
        };
    }
    f.protocol.angles = vec![90.0];
    let err = build(&f, &mut |_| {}).unwrap_err().to_string();
    assert!(err.contains("carries no force"), "{err}");
}

#[test]
fn no_strip_is_pulled_past_the_tension_that_breaks_it() {
    let mut stiffening = 0;
    for i in 0..400 {
        let f = draw(1, i);
        let e = f.protocol.max_strain;
        let t = yarn_tension(&f.source, e);
        assert!(
            e <= 0.01 || t <= BREAK_TENSION.1 * (1.0 + 1e-9),
            "{}: {t} N/m at strain {e}",
            f.name
        );
        // a stiffening law stops the pull before its small-strain stiffness would
        if let Source::Law(m) = &f.source {
            let small = m.law.a11.max(m.law.a22) * m.thickness * e;
            stiffening += usize::from(t > 2.0 * small);
        }
    }
    assert!(stiffening > 20, "{stiffening} law fabrics stiffen twofold");
}

/// A law fabric's strips are solved on the coarsest mesh of the lab's ladder whose estimated
/// end-force error meets the tolerance, and `lab.csv` says which: a warp strip (its force
/// barely depends on the mesh) keeps the ladder's first level.
#[test]
fn a_law_strip_is_solved_on_a_mesh_that_meets_the_lab_tolerance() {
    let mut f = draw(58, 0);
    let Source::Law(m) = &mut f.source else {
        panic!("even draws are law fabrics")
    };
    for eta in [&mut m.law.warp, &mut m.law.weft, &mut m.law.shear] {
        *eta = crate::material::Eta::linear();
    }
    f.protocol = f.protocol.clean();
    f.protocol.angles = vec![90.0];
    f.protocol.strip = (0.025, 0.025);
    f.protocol.points = 12;
    f.protocol.bends = false;
    let z = build(&f, &mut |_| {}).unwrap();
    assert_eq!(z.lab_meshes.len(), 1);
    let kept = &z.lab_meshes[0];
    assert!(kept.converged(), "{kept:?}");
    assert_eq!(kept.mesh, (12, 12), "{kept:?}");
    let dir = std::env::temp_dir().join(format!("kshell-zoo-lab-{}", std::process::id()));
    z.write(&dir, "lab mesh").unwrap();
    let csv = std::fs::read_to_string(dir.join("lab.csv")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        csv.starts_with("angle_deg,mesh,estimated_error\n90,12x12,"),
        "{csv}"
    );
}
