use super::*;

/// For a model linear in its parameters the step is the exact refit: r(p) = A p − b on
/// the coarse mesh and A p − b′ on the fine one, optimum moves by (AᵀA)⁻¹Aᵀ(b′ − b).
#[test]
fn the_step_is_the_exact_refit_of_a_linear_model() {
    let a = DMatrix::from_row_slice(4, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0, 1.0, 3.0]);
    let b = DVector::from_column_slice(&[0.1, 1.2, 1.9, 3.2]);
    let b2 = DVector::from_column_slice(&[0.15, 1.22, 1.97, 3.3]);
    let solve = |rhs: &DVector<f64>| {
        (a.transpose() * &a)
            .cholesky()
            .unwrap()
            .solve(&(a.transpose() * rhs))
    };
    let (p, p2) = (solve(&b), solve(&b2));
    // Δr at fixed p: (A p − b′) − (A p − b) = b − b′
    let dr: Vec<f64> = (&b - &b2).iter().copied().collect();
    let delta = gauss_newton_step(&a, &dr).unwrap();
    assert!((&p + &delta - &p2).norm() < 1e-12);
}

fn check(changes: &[(&str, f64)], curves: f64) -> MeshCheck {
    let changes: Vec<(String, f64)> = changes.iter().map(|(n, c)| (n.to_string(), *c)).collect();
    let (parameter, change) = changes
        .iter()
        .filter(|(n, _)| n.ends_with("_pa") || n.contains("_tangent_at_"))
        .fold((String::new(), 0.0), |m, (n, c)| {
            if c.abs() > m.1 {
                (n.clone(), c.abs())
            } else {
                m
            }
        });
    MeshCheck {
        mesh: (16, 24),
        solved_on: (16, 24),
        change,
        parameter,
        changes,
        law_change: 0.0,
        law_parameter: String::new(),
        curve_change: curves,
        curve: "bias-1.csv".into(),
        angle_change_deg: Some(0.02),
    }
}

/// The ladder's decisions: the 1 % / 0.3 % / 0.1° rule of `MeshCheck::passes`, its
/// carrying one level finer at order q, and each stage's own change (as a·τ: the
/// thickness's rescaling of a added back).
#[test]
fn the_ladder_decides_by_the_rule_and_by_each_stage() {
    use super::super::map::Direction;
    let m = check(
        &[
            ("a11_pa", -0.002),
            ("warp_tangent_at_50pct", -0.0021),
            ("g12_pa", 0.044),
            ("bias_tangent_at_100pct", 0.03),
            ("a22_pa", -0.0019),
            ("thickness_mm", 0.002),
        ],
        0.009,
    );
    assert!(!m.passes());
    assert_eq!(m.parameter, "g12_pa");
    // the warp and weft strips determine a·τ: a −0.2 % change of a with τ +0.2 % is none
    assert!(m.stage_change(Direction::Warp) < 2e-4);
    assert!(m.stage_change(Direction::Weft) < 2e-4);
    assert!((m.stage_change(Direction::Shear) - 0.046).abs() < 1e-12);
    // one level finer at order 2: a quarter of every change
    let next = m.next_level(2.0);
    assert_eq!(next.mesh, (32, 48));
    assert!((next.change - 0.011).abs() < 1e-12 && !next.passes());
    let further = next.next_level(2.0);
    assert!(further.passes(), "{further:?}");
    // a stage the check did not see is never taken as unchanged
    let only_warp = check(&[("a11_pa", 1e-5)], 0.0);
    assert_eq!(only_warp.stage_change(Direction::Shear), f64::INFINITY);
    // a drape angle moving by 0.1° fails the rule on its own
    let mut bend = check(&[("a11_pa", 1e-5)], 0.0);
    bend.angle_change_deg = Some(0.1);
    assert!(!bend.passes());
}
