//! Picture speed: the stencil table of a tessellation (CPU), the limit evaluation on the GPU
//! against the same sums on the CPU, a whole render at 1600 × 1200 (4× multisampled, read back)
//! and the PNG encoding, for the 1 m drape's cage at 32 × 32 with 4 × 4 to 16 × 16 samples per face.
//!
//! Run: `cargo bench --bench render` (needs a GPU adapter; a software one will do). Prints the
//! median, min and max over repeated runs (the machine is shared: quote medians).

#[cfg(feature = "render")]
fn main() {
    use kshell::mesh::rectangular_grid;
    use kshell::render::{RenderOptions, Renderer, Tessellation};
    use kshell::subdiv::{BoundaryRule, LimitSurface};
    use std::hint::black_box;
    use std::time::Instant;

    fn time<F: FnMut()>(runs: usize, mut f: F) -> (f64, f64, f64) {
        f();
        let mut t: Vec<f64> = (0..runs)
            .map(|_| {
                let s = Instant::now();
                f();
                s.elapsed().as_secs_f64()
            })
            .collect();
        t.sort_by(f64::total_cmp);
        (t[runs / 2], t[0], t[runs - 1])
    }
    let r = match Renderer::new() {
        Ok(r) => r,
        Err(e) => {
            eprintln!("no GPU adapter: {e}");
            return;
        }
    };
    println!("adapter: {}", r.adapter_name());
    let mesh = rectangular_grid(1.0, 1.0, 32, 32);
    let x: Vec<kshell::Vec3> = mesh
        .positions
        .iter()
        .map(|p| [p[0], 0.05 * (9.0 * p[0]).sin(), -p[1]])
        .collect();
    let surface = LimitSurface::new(&mesh, BoundaryRule::Phantom).unwrap();
    println!(
        "{:>5} {:>8} {:>12} {:>12} {:>12} {:>14} {:>10}",
        "k", "samples", "table ms", "gpu eval ms", "cpu eval ms", "render ms", "png ms"
    );
    let ms = |t: (f64, f64, f64)| format!("{:.1} ({:.1}..{:.1})", t.0 * 1e3, t.1 * 1e3, t.2 * 1e3);
    for k in [4, 8, 16] {
        let table = time(5, || {
            black_box(Tessellation::new(&surface, &mesh.positions, k).unwrap());
        });
        let tess = Tessellation::new(&surface, &mesh.positions, k).unwrap();
        let gpu = time(7, || {
            black_box(r.evaluate(&tess, &x).unwrap());
        });
        let cpu = time(7, || {
            black_box(tess.evaluate_cpu(&x));
        });
        let opts = RenderOptions::default();
        let render = time(7, || {
            black_box(r.render_limit(&tess, &x, &opts).unwrap());
        });
        let img = r.render_limit(&tess, &x, &opts).unwrap();
        let png = time(5, || {
            black_box(img.png().unwrap());
        });
        println!(
            "{k:>5} {:>8} {:>12} {:>12} {:>12} {:>14} {:>10}",
            tess.num_points(),
            ms(table),
            ms(gpu),
            ms(cpu),
            ms(render),
            ms(png)
        );
    }
}

#[cfg(not(feature = "render"))]
fn main() {
    eprintln!("built without the `render` feature");
}
