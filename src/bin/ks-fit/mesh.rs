//! The mesh commands of `ks-fit`: `mesh` (summary, limit evaluation, refinement) and `demo`.

use kshell::mesh::{read_obj, shapes, write_obj, PolyMesh, Topology};
use kshell::scene::{CantileverBend, TensileStrip};
use kshell::subdiv::{refine_uniform, BoundaryRule, FaceKind, LimitBasis, LimitSurface};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

/// The flags of `ks-fit mesh`.
#[derive(clap::Args)]
pub struct MeshArgs {
    /// Wavefront OBJ file.
    pub file: PathBuf,
    /// Print the limit position and its first and second derivatives at one point as CSV.
    /// FACE is the 0-based face index in the file; u runs from the face's first vertex
    /// towards its second, v from its first towards its last, both in [0, 1].
    #[arg(long, num_args = 3, value_names = ["FACE", "U", "V"], allow_negative_numbers = true)]
    pub limit: Option<Vec<String>>,
    #[arg(long, default_value = "phantom", help = crate::flags::boundary_help(""))]
    pub boundary: BoundaryRule,
    /// Apply N uniform Catmull–Clark steps first, ahead of anything else.
    #[arg(long, default_value_t = 0)]
    pub subdivide: usize,
    /// Write the (possibly refined) mesh to this OBJ file.
    #[arg(long)]
    pub write: Option<PathBuf>,
}

fn refine(mesh: &PolyMesh) -> PolyMesh {
    // the mesh is checked when it is read; refinement keeps it manifold
    match Topology::build(mesh) {
        Ok(t) => refine_uniform(mesh, &t),
        Err(_) => mesh.clone(),
    }
}

pub fn cmd_mesh(
    file: &std::path::Path,
    limit: Option<&[String]>,
    rule: BoundaryRule,
    subdivide: usize,
    write: Option<&std::path::Path>,
    force: bool,
) -> Result<(), String> {
    let name = file.display().to_string();
    let mut guard = crate::guard::Guard::new(force);
    guard.input(file);
    if let Some(out) = write {
        guard.file("--write", out)?;
    }
    let obj = read_obj(file).map_err(|e| e.to_string())?;
    let mut mesh = obj.mesh;
    // each step makes a quad of every corner of every face: check the final count first
    let corners: usize = mesh.faces.iter().map(|f| f.len()).sum();
    let faces = match subdivide {
        0 => mesh.faces.len(),
        n => u32::try_from(n - 1)
            .ok()
            .and_then(|e| 4usize.checked_pow(e))
            .map_or(usize::MAX, |k| corners.saturating_mul(k)),
    };
    kshell::limits::check_faces(&format!("--subdivide {subdivide}"), faces)?;
    for _ in 0..subdivide {
        mesh = refine(&mesh);
    }
    let mut notes = Vec::new();
    if !mesh.is_all_quads() {
        notes.push(format!(
            "the mesh has {} non-quad faces: one Catmull–Clark step turned it into quads; face indices refer to the refined mesh",
            mesh.faces.iter().filter(|f| f.len() != 4).count()
        ));
        mesh = refine(&mesh);
    }
    let surface = LimitSurface::new(&mesh, rule).map_err(|e| format!("{name}: {e}"))?;
    match limit {
        Some(args) => {
            let face: usize = args[0].parse().map_err(|_| {
                format!(
                    "--limit: FACE must be a face index (0, 1, …), got '{}'",
                    args[0]
                )
            })?;
            let uv: Vec<f64> = args[1..]
                .iter()
                .map(|a| {
                    a.parse::<f64>().map_err(|_| {
                        format!("--limit: U and V must be numbers in [0, 1], got '{a}'")
                    })
                })
                .collect::<Result<_, _>>()?;
            let p = surface
                .evaluate(face, uv[0], uv[1])
                .map_err(|e| format!("{name}: {e}"))?;
            if p.d.iter().flatten().any(|x| !x.is_finite()) {
                return Err(format!(
                    "{name}: the limit surface overflows at this point (coordinates too large for double precision)"
                ));
            }
            for n in &notes {
                eprintln!("ks-fit: note: {n}");
            }
            println!("x,y,z,xu,yu,zu,xv,yv,zv,xuu,yuu,zuu,xuv,yuv,zuv,xvv,yvv,zvv");
            let row: Vec<String> = p.d.iter().flatten().map(|x| format!("{x:?}")).collect();
            println!("{}", row.join(","));
        }
        None => {
            println!("mesh: {name}");
            for n in &notes {
                println!("note: {n}");
            }
            print_summary(&mesh, &surface);
        }
    }
    // written last, once everything asked for has worked
    if let Some(out) = write {
        let text = write_obj(&mesh, &format!("written by ks-fit from {name}"));
        kshell::io::write_atomic(out, text)
            .map_err(|e| format!("{}: cannot write: {e}", out.display()))?;
    }
    Ok(())
}

fn print_summary(mesh: &PolyMesh, surface: &LimitSurface) {
    let Ok(topo) = Topology::build(mesh) else {
        return;
    };
    println!("vertices: {}", mesh.num_vertices());
    println!("faces: {}", mesh.num_faces());
    println!("boundary edges: {}", topo.num_boundary_edges());
    let count = |k: FaceKind| surface.face_kinds().iter().filter(|&&x| x == k).count();
    println!(
        "faces by kind: regular {}, boundary {}, extraordinary {}",
        count(FaceKind::Regular),
        count(FaceKind::Boundary),
        count(FaceKind::Extraordinary)
    );
    let mut interior: BTreeMap<u32, usize> = BTreeMap::new();
    let mut boundary: BTreeMap<u32, usize> = BTreeMap::new();
    for v in 0..mesh.num_vertices() {
        if topo.vertex_faces[v].is_empty() {
            continue;
        }
        let map = if topo.on_boundary[v] {
            &mut boundary
        } else {
            &mut interior
        };
        *map.entry(topo.valence[v]).or_default() += 1;
    }
    let list = |m: &BTreeMap<u32, usize>| {
        if m.is_empty() {
            "none".to_string()
        } else {
            m.iter()
                .map(|(v, n)| format!("{v} ({n})"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    println!(
        "valences present: interior {}; boundary {}",
        list(&interior),
        list(&boundary)
    );
    let isolated = topo.isolated_vertices();
    if isolated > 0 {
        println!("isolated vertices (in no face): {isolated}");
    }
}

pub fn cmd_demo() -> Result<(), String> {
    println!("kshell demo: the exact Catmull–Clark limit basis, then the virtual lab");
    println!(
        "(4 × 4 Gauss points per face; every stencil computed once, as the shell FEM will use it)"
    );
    println!();
    println!(
        "{:<22} {:>6} {:>16} {:>8} {:>12} {:>9} {:>14}",
        "shape", "faces", "reg/bnd/extra", "points", "stencil avg", "setup ms", "limit area"
    );
    let strip = kshell::mesh::rectangular_grid(0.05, 0.075, 8, 12);
    let cases: Vec<(&str, PolyMesh)> = vec![
        ("strip 50x75 mm, 8x12", strip.clone()),
        ("cube (valence 3)", shapes::cube()),
        ("star (valence 5)", shapes::star(5, 3)),
        ("L-shape (boundary EV)", shapes::l_shape(3)),
    ];
    for (name, mesh) in &cases {
        let t0 = Instant::now();
        let basis = LimitBasis::new(mesh, Default::default()).map_err(|e| e.to_string())?;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let k = &basis.face_kinds;
        let count = |x: FaceKind| k.iter().filter(|&&y| y == x).count();
        let (mean, _) = basis.stencil_sizes();
        println!(
            "{:<22} {:>6} {:>16} {:>8} {:>12.1} {:>9.2} {:>14.6e}",
            name,
            basis.num_faces,
            format!(
                "{}/{}/{}",
                count(FaceKind::Regular),
                count(FaceKind::Boundary),
                count(FaceKind::Extraordinary)
            ),
            basis.num_points(),
            mean,
            ms,
            basis.area(&basis.control_points)
        );
    }
    let basis = LimitBasis::new(&strip, Default::default()).map_err(|e| e.to_string())?;
    let area = basis.area(&basis.control_points);
    println!();
    println!(
        "check: the strip's limit surface is exactly its 50 × 75 mm rectangle: area {:.10e} m² (relative error {:.1e})",
        area,
        (area / 3.75e-3 - 1.0).abs()
    );
    let cube = LimitBasis::new(&shapes::cube(), Default::default()).map_err(|e| e.to_string())?;
    println!(
        "the unit cube's limit surface encloses {:.6} of the cube's volume",
        cube.enclosed_volume(&cube.control_points)
    );

    // the virtual lab on the bundled example material
    let text = include_str!("../../../examples/materials/cotton.toml");
    let mat = kshell::material::parse_material(text, "examples/materials/cotton.toml")
        .map_err(|e| e.to_string())?;
    println!();
    println!(
        "virtual lab, material '{}' (examples/materials/cotton.toml): 50 x 75 mm strips, 8 x 12 mesh",
        mat.name
    );
    println!(
        "{:<14} {:>12} {:>12} {:>12}",
        "strip", "F @ 2.5 %", "F @ 5 %", "F @ 10 %"
    );
    for (name, angle) in [
        ("weft (0°)", 0.0),
        ("bias (45°)", 45.0),
        ("warp (90°)", 90.0),
    ] {
        let t0 = Instant::now();
        let curve = TensileStrip::new(0.05, 0.075, angle)
            .run(&mat, &[0.001875, 0.00375, 0.0075])
            .map_err(|e| e.to_string())?;
        println!(
            "{:<14} {:>10.3} N {:>10.3} N {:>10.3} N   ({:.0} ms)",
            name,
            curve[0].force,
            curve[1].force,
            curve[2].force,
            t0.elapsed().as_secs_f64() * 1e3
        );
    }
    for (name, angle) in [("warp", 90.0), ("weft", 0.0)] {
        let t0 = Instant::now();
        let r = CantileverBend::new(0.025, 0.06, angle)
            .run(&mat)
            .map_err(|e| e.to_string())?;
        println!(
            "cantilever, {name}, 25 mm wide, 60 mm overhang: drape angle {:.2}° ({:.0} ms)",
            r.drape_angle_deg,
            t0.elapsed().as_secs_f64() * 1e3
        );
    }
    Ok(())
}
