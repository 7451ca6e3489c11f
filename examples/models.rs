//! Scratch.
use kshell::tri::{TriKind, TriMaterial, TriTensile};
use std::time::Instant;
fn main() {
    let (data, _) = kshell::dataset::load_dataset(std::path::Path::new(
        "paper_repro/fabrics/cotton/fabric.toml",
    ))
    .unwrap();
    let m = kshell::material::load_material(std::path::Path::new("examples/materials/cotton.toml"))
        .unwrap();
    let tm = TriMaterial::equivalent(TriKind::StvkDs, &m, 0.003, 100.0).unwrap();
    for t in &data.tensile {
        let mut s = TriTensile::new(t.width, t.gauge_length, t.angle_deg);
        s.mesh = (8, 12);
        let n = t.elongation.len();
        let idx: Vec<usize> = (1..=8).map(|k| (k * (n - 1)).div_ceil(8)).collect();
        let dl: Vec<f64> = idx.iter().map(|&i| t.elongation[i]).collect();
        let t0 = Instant::now();
        let r = s.run(&tm, &dl);
        println!(
            "{} {:?} {:.3}s {:?}",
            t.angle_deg,
            dl.last(),
            t0.elapsed().as_secs_f64(),
            r.map(|p| p.iter().map(|q| q.report.iterations).collect::<Vec<_>>())
                .map_err(|e| e.to_string())
        );
    }
}
