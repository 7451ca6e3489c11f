//! What a fit shows its user: the interpolation check it prints compares like with like.

use crate::common::folder;

/// The largest interpolation error a fit's notes print, in percent.
fn interpolation_error(out: &str) -> f64 {
    let at = out
        .find("largest interpolation error ")
        .unwrap_or_else(|| panic!("no interpolation check in:\n{out}"));
    let rest = &out[at + "largest interpolation error ".len()..];
    rest.split(' ').next().unwrap().parse().unwrap()
}

/// The interpolation check compares each strip's interpolated curve with solves between its
/// nodes on the same discretisation: on a two-level ladder the first level's strips keep the
/// centre rule's β pinned on that level, and the check solves with it, not with the β pinned
/// later. Its error on the walk-through (yarn-to-shear ratio 40, centre rule; 8 nodes for 9
/// points, so the curves are interpolated) is then that of the one-level fit on the same
/// first mesh, within a factor of 1.5 (the two laws differ by what the second level refits),
/// not the two βs' difference (8.4 % against 0.73 %).
#[test]
fn the_interpolation_check_solves_on_the_nodes_discretisation() {
    let dir = folder("interpolation");
    let run = |ladder: &str| {
        let out_file = dir.join(format!("fit-{ladder}.toml"));
        let (rc, out, err) = crate::common::ks_fit(&[
            "fit",
            "docs/walkthrough/fabric.toml",
            "-o",
            crate::common::s(&out_file),
            "--nodes",
            "8",
            "--mesh-ladder",
            ladder,
            "--mesh-check",
            "off",
            "--test-meshes",
            "ladder",
            "--quiet",
        ]);
        assert_eq!(rc, 0, "{out}{err}");
        assert!(
            out.contains("yarn terms integrated on the face centres"),
            "{out}"
        );
        interpolation_error(&out)
    };
    let one = run("4x6");
    let two = run("4x6,8x12");
    assert!(
        two <= 1.5 * one && one <= 1.5 * two,
        "interpolation error {two} % on the two-level ladder against {one} % on its first level alone"
    );
}
