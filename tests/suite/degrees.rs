//! The shear degree chosen on the shell model (`fit::degrees`): noise-free data of a law whose
//! shear has two terms, made on cages twice as fine as the fit's, must come back with a
//! degree-2 shear close to the law that made them.

use crate::common::{folder, ks_fit, s};

/// The bundled cotton: degree-2 η everywhere, at a yarn-to-shear ratio of 50 (`--yarn-rule
/// auto` puts the yarn terms of its off-axis strips on the face centres).
const COTTON: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/paper_repro/fabrics/materials/cotton.toml"
);

/// Made on 16 × 24 and fitted on 8 × 12 alone, the raise to degree 2 must find the
/// two-term shear. Measured when written: the raise's space-mapped start stopped at shape
/// error 0.97 % against degree 1's 1.35 % (28 %, under the 30 % a degree must pay), so degree
/// 1 was kept and G12 came back −9.9 %; from the stiff second start the shell's iterations
/// reached 0.39 %, degree 2 was kept and G12 came back −3.7 % (the rest is the 8 × 12
/// strips' mesh error, which the ladder's finer level would take out).
#[test]
fn a_two_term_shear_made_on_a_finer_mesh_is_found_on_the_coarse_one() {
    let dir = folder("degrees-cotton");
    let data = dir.join("data");
    let (rc, out, err) = ks_fit(&[
        "synth",
        "--material",
        COTTON,
        "--out",
        s(&data),
        "--max-strain",
        "0.08",
        "--points",
        "10",
        "--mesh",
        "16x24",
        "--grading",
        "0.8,0.8",
    ]);
    assert_eq!(rc, 0, "{out}{err}");
    let fitted = dir.join("fitted.toml");
    let (rc, out, err) = ks_fit(&[
        "fit",
        s(&data.join("fabric.toml")),
        "-o",
        s(&fitted),
        "--mesh-ladder",
        "8x12",
        "--test-meshes",
        "ladder",
        "--mesh-check",
        "off",
        // the degree choice alone: no third term, no coupling trial
        "--max-degree",
        "2",
        "--shear-coupling",
        "off",
    ]);
    assert!(rc == 0 || rc == 3, "{out}{err}");
    let doc: toml::Table = std::fs::read_to_string(&fitted).unwrap().parse().unwrap();
    let degrees = doc["fit"]["degrees"].as_table().unwrap();
    assert_eq!(degrees["shear"].as_integer(), Some(2), "{degrees:?}\n{err}");
    let g12 = doc["g12_pa"].as_float().unwrap();
    // degree 2 measured −3.7 %, degree 1 −9.9 % (doc above)
    assert!((g12 / 7.6e6 - 1.0).abs() < 0.05, "G12 {g12:e}\n{err}");
}
