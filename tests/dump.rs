//! A failed solve dumped in Matrix Market (`kshell::solve::dump`): what is written reads back
//! through nalgebra-sparse's reader as the reduced tangent, which is checked against central
//! differences of the reduced gradient (so the file is the system the solver saw), and a solve
//! that fails with KSHELL_DUMP_FAILED set writes its folder.

use kshell::material::load_material;
use kshell::model::ClothModel;
use kshell::solve::dump::{dump_system, reduced_system};
use kshell::solve::{newton, FreeSystem, NewtonOptions};
use kshell::tri::{TriGrid, TriKind, TriMaterial, TriModel};
use nalgebra_sparse::io::load_coo_from_matrix_market_file;
use nalgebra_sparse::CsrMatrix;

/// A 6 × 3 stvk-ds cantilever of the example cotton under gravity, its first column clamped,
/// moved off its rest state so that the tangent is not trivial.
fn cantilever() -> (TriModel, FreeSystem, Vec<kshell::Vec3>) {
    let cotton = load_material(std::path::Path::new("examples/materials/cotton.toml")).unwrap();
    let mat = TriMaterial::equivalent(TriKind::StvkDs, &cotton, 0.01, 100.0).unwrap();
    let mut model = TriModel::new(TriGrid::rectangle(0.06, 0.03, 6, 3), mat, 0.0);
    model.set_gravity([0.0, 0.0, -9.81]);
    let n = model.num_nodes();
    let rest = model.grid.positions();
    let fixed: Vec<bool> = (0..3 * n).map(|d| rest[d / 3][0] < 1e-9).collect();
    let system = FreeSystem::new(&model, &fixed).unwrap();
    let x: Vec<kshell::Vec3> = rest
        .iter()
        .map(|p| [p[0] * 1.01, p[1], -0.2 * p[0] * p[0] + 0.01 * p[1] * p[0]])
        .collect();
    (model, system, x)
}

/// Tᵀ ∇E at `x`.
fn reduced_gradient(model: &TriModel, system: &FreeSystem, x: &[kshell::Vec3]) -> Vec<f64> {
    let mut full = vec![[0.0; 3]; x.len()];
    model
        .assemble(x, kshell::assembly::Want::Gradient, Some(&mut full), None)
        .unwrap();
    system.reduced(&full)
}

#[test]
fn the_dumped_matrix_is_the_reduced_tangent() {
    let (model, system, x) = cantilever();
    let dir = std::env::temp_dir().join(format!("kshell-dump-{}", std::process::id()));
    let folder = dump_system(&model, &system, &x, "a test", &dir).unwrap();
    let k = load_coo_from_matrix_market_file::<f64, _>(folder.join("K.mtx")).unwrap();
    let g = load_coo_from_matrix_market_file::<f64, _>(folder.join("g.mtx")).unwrap();
    let n = system.num_free;
    assert_eq!((k.nrows(), k.ncols()), (n, n));
    assert_eq!((g.nrows(), g.ncols()), (n, 1));
    let k = CsrMatrix::from(&k);
    // symmetric, and K e_j = (g(x + h e_j) − g(x − h e_j)) / 2h for a few free DOFs
    let (_, g0) = reduced_system(&model, &system, &x).unwrap();
    let gnorm = g0.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!(gnorm > 0.0);
    for j in [0, n / 3, n / 2, n - 1] {
        let h = 1e-7;
        let mut d = vec![0.0; n];
        d[j] = h;
        let mut xp = x.clone();
        system.advance(&mut xp, &d);
        d[j] = -h;
        let mut xm = x.clone();
        system.advance(&mut xm, &d);
        let (gp, gm) = (
            reduced_gradient(&model, &system, &xp),
            reduced_gradient(&model, &system, &xm),
        );
        let col: Vec<f64> = (0..n)
            .map(|i| k.get_entry(i, j).map_or(0.0, |e| e.into_value()))
            .collect();
        let scale = col.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..n {
            let fd = (gp[i] - gm[i]) / (2.0 * h);
            assert!(
                (fd - col[i]).abs() <= 1e-5 * scale,
                "K[{i},{j}] = {} but the gradient's difference gives {fd}",
                col[i]
            );
            let kji = k.get_entry(j, i).map_or(0.0, |e| e.into_value());
            assert_eq!(col[i], kji, "symmetric");
        }
    }
    let what = std::fs::read_to_string(folder.join("what.txt")).unwrap();
    assert!(what.starts_with("a test\n") && what.contains(&format!("free DOFs {n}")));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_failing_solve_dumps_itself_when_asked() {
    let (model, system, mut x) = cantilever();
    let dir = std::env::temp_dir().join(format!("kshell-dump-env-{}", std::process::id()));
    // the only test of this binary that fails a solve, so the variable affects nothing else
    std::env::set_var("KSHELL_DUMP_FAILED", &dir);
    let opts = NewtonOptions {
        max_iterations: 1,
        ..NewtonOptions::plain()
    };
    assert!(newton(&model, &system, &mut x, &opts).is_err());
    std::env::remove_var("KSHELL_DUMP_FAILED");
    let dumps: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(dumps.len(), 1);
    let folder = dumps[0].as_ref().unwrap().path();
    for f in ["K.mtx", "g.mtx", "x.csv", "what.txt"] {
        assert!(folder.join(f).exists(), "{f}");
    }
    let what = std::fs::read_to_string(folder.join("what.txt")).unwrap();
    assert!(what.starts_with("solve failed: "), "{what}");
    let _ = std::fs::remove_dir_all(dir);
}
