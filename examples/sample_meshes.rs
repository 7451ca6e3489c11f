//! Writes the sample cages in `meshes/` from their generators in `kshell::mesh::shapes`.
//! Run: `cargo run --example sample_meshes` (a test checks the files match the generators).

use kshell::mesh::{rectangular_grid, shapes, write_obj, PolyMesh};
use std::f64::consts::PI;

fn main() -> std::io::Result<()> {
    for (file, header, mesh) in samples() {
        std::fs::write(format!("meshes/{file}"), write_obj(&mesh, header))?;
        println!("wrote meshes/{file}");
    }
    Ok(())
}

/// (file name, description, mesh) of every shipped sample.
fn samples() -> Vec<(&'static str, &'static str, PolyMesh)> {
    vec![
        (
            "strip_8x12.obj",
            "ASTM D5035 strip, 50 x 75 mm (in metres), 8 x 12 regular quads",
            rectangular_grid(0.05, 0.075, 8, 12),
        ),
        ("cube.obj", "unit cube: closed, every vertex valence 3", shapes::cube()),
        (
            "star5.obj",
            "curved disc around an interior vertex of valence 5 (5 sectors of 3 x 3 quads)",
            shapes::star(5, 3),
        ),
        (
            "fan4_boundary.obj",
            "open three-quarter disc: boundary vertex with 4 faces (extraordinary, on the boundary)",
            shapes::fan(4, 1.5 * PI, 3),
        ),
        (
            "l_shape.obj",
            "flat L-shaped plate, 3 blocks of 3 x 3: re-entrant corner with 3 faces",
            shapes::l_shape(3),
        ),
        (
            "tetra.obj",
            "tetrahedron: triangles, refined once into quads when read",
            PolyMesh::new(
                vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                vec![vec![0, 2, 1], vec![0, 1, 3], vec![1, 2, 3], vec![2, 0, 3]],
            ),
        ),
    ]
}
