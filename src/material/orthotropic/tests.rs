//! Checks of the orthotropic law: parameter counts, the StVK limit, strain and parameter
//! derivatives against differences, continuity across the cut-offs, and the tension–shear
//! coupling.

use super::*;
use crate::material::OrthotropicStvk;

fn sample() -> Orthotropic {
    Orthotropic {
        a11: 3.0e7,
        a22: 1.5e7,
        a12: 4.0e6,
        g12: 1.0e6,
        warp: Eta {
            mu: vec![0.7, 0.3],
            alpha: vec![1.0, 12.0],
        },
        weft: Eta {
            mu: vec![1.0],
            alpha: vec![4.0],
        },
        shear: Eta {
            mu: vec![1.4, -0.4],
            alpha: vec![2.0, -3.0],
        },
        cutoffs: Cutoffs {
            e11: (0.0, 0.12),
            e22: (0.0, 0.15),
            e12: (-0.2, 0.2),
        },
        coupling: None,
    }
}

/// The sample law with a tension–shear coupling of either sign.
fn coupled() -> Orthotropic {
    Orthotropic {
        coupling: Some(ShearCoupling {
            warp: -9.0,
            weft: 6.0,
        }),
        ..sample()
    }
}

/// Strains inside the box, outside it on either side, and on each face.
fn strains() -> Vec<Vector3<f64>> {
    vec![
        Vector3::new(0.05, 0.08, 0.1),
        Vector3::new(0.2, 0.1, -0.05),
        Vector3::new(-0.03, 0.3, 0.35),
        Vector3::new(0.11, -0.02, -0.3),
        Vector3::new(0.07, 0.04, 0.0),
    ]
}

#[test]
fn the_parameter_count_is_that_of_the_parameters() {
    for law in [
        sample(),
        coupled(),
        Orthotropic::from(OrthotropicStvk {
            a11: 1.0,
            a22: 2.0,
            a12: 0.5,
            g12: 0.3,
        }),
    ] {
        assert_eq!(law.num_params(), law.params().len());
        assert_eq!(law.num_params(), law.names().len());
    }
}

#[test]
fn linear_eta_is_stvk_exactly() {
    let s = OrthotropicStvk {
        a11: 3.0e7,
        a22: 1.2e7,
        a12: 4.0e6,
        g12: 9.0e5,
    };
    let o: Orthotropic = s.into();
    for e in strains() {
        let (a, b) = (s.response(&e).unwrap(), o.response(&e).unwrap());
        assert!(
            (a.psi - b.psi).abs() <= 4e-16 * a.psi.abs().max(1.0),
            "{} vs {}",
            a.psi,
            b.psi
        );
        assert!((a.stress - b.stress).norm() <= 4e-16 * a.stress.norm().max(1.0));
        assert!((a.tangent - b.tangent).norm() <= 1e-9);
    }
}

#[test]
fn strain_derivatives_match_differences_inside_and_outside_the_box() {
    for law in [sample(), coupled()] {
        strain_derivatives_match(&law);
    }
}

fn strain_derivatives_match(law: &Orthotropic) {
    let h = 1e-7;
    for e in strains() {
        let r = law.response(&e).unwrap();
        for i in 0..3 {
            let (mut ep, mut em) = (e, e);
            ep[i] += h;
            em[i] -= h;
            let (p, m) = (law.response(&ep).unwrap(), law.response(&em).unwrap());
            let fd = (p.psi - m.psi) / (2.0 * h);
            assert!(
                (fd - r.stress[i]).abs() <= 1e-6 * r.stress.norm(),
                "stress {i} at {e:?}"
            );
            for j in 0..3 {
                let fd = (p.stress[j] - m.stress[j]) / (2.0 * h);
                let scale = r.tangent.norm();
                assert!(
                    (fd - r.tangent[(j, i)]).abs() <= 1e-6 * scale,
                    "tangent ({j},{i}) at {e:?}"
                );
            }
        }
    }
}

#[test]
fn parameter_derivatives_match_differences() {
    for law in [sample(), coupled()] {
        parameter_derivatives_match(&law);
    }
}

fn parameter_derivatives_match(law: &Orthotropic) {
    let k0 = law.params();
    let names = law.names();
    assert_eq!(names.len(), k0.len());
    for e in strains() {
        let pr = law.sensitivities(&e).unwrap();
        for (j, name) in names.iter().enumerate() {
            // fourth-order differences with a step large enough to keep ψ's round-off out
            let h = 1e-4 * k0[j].abs().max(1e-3);
            let at = |t: f64| {
                let mut k = k0.clone();
                k[j] += t;
                let mut l = law.clone();
                l.set_params(&k);
                l.response(&e).unwrap()
            };
            let (p2, p, m, m2) = (at(2.0 * h), at(h), at(-h), at(-2.0 * h));
            let d4 = |f: &dyn Fn(&Response) -> f64| {
                (-f(&p2) + 8.0 * f(&p) - 8.0 * f(&m) + f(&m2)) / (12.0 * h)
            };
            // differences carry ~ε ψ / h ≈ 1e-12 ψ/|k| of noise: derivatives below 1e-5 ψ/|k| are
            // checked to that absolute level, all others to 1e-6 relative
            let r0 = law.response(&e).unwrap();
            let kscale = k0[j].abs().max(1e-3);
            let fd = d4(&|r| r.psi);
            let scale = pr.dpsi[j].abs().max(1e-5 * r0.psi.abs() / kscale);
            assert!(
                (fd - pr.dpsi[j]).abs() <= 1e-6 * scale,
                "∂ψ/∂{name} at {e:?}: {fd} vs {}",
                pr.dpsi[j]
            );
            let fds = Vector3::from_fn(|i, _| d4(&|r| r.stress[i]));
            let sscale = pr.dstress[j].norm().max(1e-5 * r0.stress.norm() / kscale);
            assert!(
                (fds - pr.dstress[j]).norm() <= 1e-6 * sscale,
                "∂S/∂{name} at {e:?}: {fds:?} vs {:?}",
                pr.dstress[j]
            );
        }
    }
}

#[test]
fn value_gradient_and_hessian_are_continuous_across_each_cutoff() {
    for law in [sample(), coupled()] {
        continuous_across_cutoffs(&law);
    }
}

fn continuous_across_cutoffs(law: &Orthotropic) {
    let faces = [
        (0, 0.12),
        (0, 0.0),
        (1, 0.15),
        (1, 0.0),
        (2, 0.2),
        (2, -0.2),
    ];
    for (k, at) in faces {
        let mut e = Vector3::new(0.05, 0.07, 0.03);
        let eps = 1e-9;
        e[k] = at - eps;
        let a = law.response(&e).unwrap();
        e[k] = at + eps;
        let b = law.response(&e).unwrap();
        assert!(
            (a.psi - b.psi).abs() <= 1e-6 * a.psi.abs(),
            "ψ at component {k} = {at}"
        );
        assert!(
            (a.stress - b.stress).norm() <= 1e-6 * a.stress.norm(),
            "S at {k} = {at}"
        );
        assert!(
            (a.tangent - b.tangent).norm() <= 1e-6 * a.tangent.norm(),
            "C at {k} = {at}"
        );
    }
}

/// The law separates into the yarn part and the shear term: ψ − ψ_y depends on Ẽ₁₂ alone
/// (inside and outside the cut-off box), and the yarn part carries no shear.
#[test]
fn the_yarn_part_leaves_the_shear_term_alone() {
    let law = sample();
    for e in strains() {
        let (r, y) = (law.response(&e).unwrap(), law.yarn_response(&e).unwrap());
        let s = law.response(&Vector3::new(0.0, 0.0, e[2])).unwrap();
        assert!(
            (r.psi - y.psi - s.psi).abs() <= 1e-12 * r.psi.abs(),
            "{e:?}"
        );
        assert!((r.stress - y.stress - s.stress).amax() <= 1e-9 * r.stress.amax());
        let mut shear = Matrix3::zeros();
        shear[(2, 2)] = s.tangent[(2, 2)];
        assert!((r.tangent - y.tangent - shear).amax() <= 1e-9 * r.tangent.amax());
        assert_eq!(y.stress[2], 0.0);
        let (p, py) = (
            law.param_response(&e).unwrap(),
            law.yarn_param_response(&e).unwrap(),
        );
        let ps = law.param_response(&Vector3::new(0.0, 0.0, e[2])).unwrap();
        for j in 0..p.dpsi.len() {
            let scale = p.dpsi[j].abs().max(p.dstress[j].amax()).max(1e-30);
            assert!((p.dpsi[j] - py.dpsi[j] - ps.dpsi[j]).abs() <= 1e-9 * scale);
            assert!((p.dstress[j] - py.dstress[j] - ps.dstress[j]).amax() <= 1e-9 * scale);
        }
    }
}

/// The coupling leaves the yarns alone (the warp and weft strips, and the centre rule's
/// yarn part), scales the shear stiffness by exp(κ₁Ẽ₁₁ + κ₂Ẽ₂₂) inside the box, and
/// names its two parameters last.
#[test]
fn the_coupling_scales_the_shear_stiffness_and_nothing_else() {
    let (plain, law) = (sample(), coupled());
    for e in strains() {
        let (a, b) = (
            plain.yarn_response(&e).unwrap(),
            law.yarn_response(&e).unwrap(),
        );
        assert_eq!(a, b, "{e:?}");
        // on the yarn axes only the shear stiffness differs
        let y = Vector3::new(e[0], e[1], 0.0);
        let (a, b) = (plain.response(&y).unwrap(), law.response(&y).unwrap());
        assert_eq!((a.psi, a.stress), (b.psi, b.stress));
        let (mut ta, mut tb) = (a.tangent, b.tangent);
        ta[(2, 2)] = 0.0;
        tb[(2, 2)] = 0.0;
        assert_eq!(ta, tb);
    }
    let e = Vector3::new(0.05, 0.08, 1e-4);
    let (a, b) = (plain.response(&e).unwrap(), law.response(&e).unwrap());
    let want = (-9.0 * 0.05 + 6.0 * 0.08f64).exp();
    let ratio = b.tangent[(2, 2)] / a.tangent[(2, 2)];
    assert!((ratio - want).abs() < 1e-12 * want, "{ratio} vs {want}");
    let names = law.names();
    assert_eq!(
        &names[names.len() - 2..],
        ["coupling.warp", "coupling.weft"]
    );
    let mut back = sample();
    back.coupling = Some(ShearCoupling {
        warp: 0.0,
        weft: 0.0,
    });
    back.set_params(&law.params());
    assert_eq!(back, law);
    // a zero coupling is the separable law
    back.set_params(&[&plain.params()[..], &[0.0, 0.0]].concat());
    for e in strains() {
        assert_eq!(back.response(&e).unwrap(), plain.response(&e).unwrap());
    }
}

/// Convex while the yarns outweigh the coupled shear term (module doc): the sample's
/// κ = −9, 6 keep the tangent positive over the box; κ = 300 does not.
#[test]
fn the_convexity_check_sees_a_coupling_too_strong_for_the_yarns() {
    let (lo, hi) = ([0.0, 0.0, -0.1], [0.1, 0.1, 0.1]);
    assert!(sample().tangent_positive(lo, hi));
    assert!(coupled().tangent_positive(lo, hi));
    let mut strong = coupled();
    strong.coupling = Some(ShearCoupling {
        warp: 300.0,
        weft: 0.0,
    });
    assert!(!strong.tangent_positive(lo, hi));
}

#[test]
fn shear_sign_does_not_matter() {
    for law in [sample(), coupled()] {
        shear_sign_does_not_matter_for(&law);
    }
}

fn shear_sign_does_not_matter_for(law: &Orthotropic) {
    for e in strains() {
        let f = Vector3::new(e[0], e[1], -e[2]);
        let (a, b) = (law.response(&e).unwrap(), law.response(&f).unwrap());
        assert!((a.psi - b.psi).abs() <= 1e-14 * a.psi.abs());
    }
}
