//! Scratch.
use kshell::tri::{Stiffness, TriCantilever, TriKind, TriMaterial};
fn main() {
    let (data, _) = kshell::dataset::load_dataset(std::path::Path::new(
        "paper_repro/fabrics/cotton/fabric.toml",
    ))
    .unwrap();
    let m = kshell::material::load_material(std::path::Path::new(
        "paper_repro/fabrics/materials/cotton.toml",
    ))
    .unwrap();
    let mut tm = TriMaterial::equivalent(TriKind::StvkDs, &m, 0.003, 100.0).unwrap();
    let b = &data.bend[0];
    println!(
        "target {} overhang {} astm {}",
        b.drape_angle_deg,
        b.overhang,
        kshell::tri::fit::astm_rigidity(b.overhang, b.drape_angle_deg, 0.1036)
    );
    let d0 = tm.curves[3].k[0];
    for f in [0.5, 1.0, 2.0, 4.0] {
        tm.curves[3] = Stiffness::constant(d0 * f);
        let mut c = TriCantilever::new(b.width, b.overhang, b.angle_deg);
        c.mesh = (c.mesh.0 * 2, c.mesh.1 * 2);
        let t = std::time::Instant::now();
        let r = c.run(&tm);
        println!(
            "D {:.3e}: {:?} {:.2}s",
            d0 * f,
            r.map(|r| (r.drape_angle_deg, r.iterations))
                .map_err(|e| e.to_string()),
            t.elapsed().as_secs_f64()
        );
    }
}
