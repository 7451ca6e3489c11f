//! Scratch comparison (will become the models chart).
use kshell::material::load_material;
use kshell::scene::{CantileverBend, TensileStrip};
use kshell::tri::{TriCantilever, TriKind, TriMaterial, TriTensile};
use std::time::Instant;

fn main() {
    let m = load_material(std::path::Path::new("examples/materials/cotton.toml")).unwrap();
    let (w, l) = (0.05, 0.075);
    let dl: Vec<f64> = (1..=4).map(|i| 0.75e-3 * i as f64).collect();
    for angle in [90.0, 0.0, 45.0] {
        let mut s = TensileStrip::new(w, l, angle);
        s.mesh = (16, 24);
        let t = Instant::now();
        let f = s.run(&m, &dl).unwrap();
        println!(
            "kl {angle}: {:?} {:.3}s",
            f.iter().map(|p| p.force).collect::<Vec<_>>(),
            t.elapsed().as_secs_f64()
        );
        for (name, kind) in TriKind::ALL {
            for mesh in [(8, 12), (16, 24), (32, 48)] {
                let tm = TriMaterial::equivalent(kind, &m, w / mesh.0 as f64, 100.0).unwrap();
                let mut s = TriTensile::new(w, l, angle);
                s.mesh = mesh;
                let t = Instant::now();
                match s.run(&tm, &dl) {
                    Ok(f) => println!(
                        "{name} {mesh:?}: {:?} {:.3}s",
                        f.iter().map(|p| p.force).collect::<Vec<_>>(),
                        t.elapsed().as_secs_f64()
                    ),
                    Err(e) => println!("{name} {mesh:?}: {e}"),
                }
            }
        }
    }
    let tm = TriMaterial::equivalent(TriKind::StvkDs, &m, 0.006, 100.0).unwrap();
    println!("{:?}", tm.curves.iter().map(|c| c.k[0]).collect::<Vec<_>>());
    for k in 0..4 {
        let mut light = tm.clone();
        light.areal_density *= 1e-3;

        let mut c = TriCantilever::new(0.025, 0.0477, 90.0);
        c.mesh = (c.mesh.0 << k, c.mesh.1 << k);
        let r = c.run(&light).unwrap();
        let wl = light.areal_density * 9.80665;
        println!(
            "light {:?}: tip z {:.6e} beam {:.6e}",
            c.mesh,
            r.tip[2],
            -wl * 0.0477f64.powi(4) / (8.0 * tm.curves[3].k[0])
        );
    }
    let b = CantileverBend::new(0.025, 0.0477, 90.0);
    let heavy = m.clone();
    let t = Instant::now();
    let r = b.run(&heavy).unwrap();
    println!(
        "kl bend {:?}: {:.4} {:.3}s",
        b.mesh,
        r.drape_angle_deg,
        t.elapsed().as_secs_f64()
    );
    for (name, kind) in TriKind::ALL {
        for k in 0..3 {
            let mut c = TriCantilever::new(0.025, 0.0477, 90.0);
            c.mesh = (c.mesh.0 << k, c.mesh.1 << k);
            let tm = TriMaterial::equivalent(kind, &heavy, 0.025 / c.mesh.0 as f64, 100.0).unwrap();
            let t = Instant::now();
            match c.run(&tm) {
                Ok(r) => println!(
                    "{name} bend {:?}: {:.4} {:.3}s",
                    c.mesh,
                    r.drape_angle_deg,
                    t.elapsed().as_secs_f64()
                ),
                Err(e) => println!("{name} bend {:?}: {e}", c.mesh),
            }
        }
    }
}
