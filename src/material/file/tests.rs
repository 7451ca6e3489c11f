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
    let with_fit = format!("{text}\n[fit]\nwall_seconds = 3.5\n[[fit.test]]\nkind = \"bend\"\n");
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
