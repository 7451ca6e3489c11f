//! The convexified Hessian of [`super::Want::ProjectedHessian`]: a positive semidefinite
//! stand-in for the exact Hessian, for the fallback step that follows a negative-curvature step
//! (see `solve::newton`). Per Gauss point the section tangent keeps its positive semidefinite
//! part ([`psd_part`]), the membrane stress that weights the strains' own Hessian keeps its
//! tensile part (`RestPoint::add_tensile_membrane_hessian`), and the moments' term is dropped:
//! a sum of positive semidefinite terms (the idea of Teran et al. 2005's definiteness fix, per
//! point rather than per element).

/// The positive semidefinite part of a symmetric 6 × 6 matrix (negative eigenvalues set to 0).
/// A Cholesky attempt (about 60 flops) settles the usual, definite case without an eigensolve.
pub(super) fn psd_part(c: &nalgebra::SMatrix<f64, 6, 6>) -> nalgebra::SMatrix<f64, 6, 6> {
    if nalgebra::Cholesky::new(*c).is_some() {
        return *c;
    }
    let e = nalgebra::SymmetricEigen::new(*c);
    if e.eigenvalues.iter().all(|&l| l >= 0.0) {
        return *c;
    }
    let l = e.eigenvalues.map(|v| v.max(0.0));
    e.eigenvectors * nalgebra::SMatrix::<f64, 6, 6>::from_diagonal(&l) * e.eigenvectors.transpose()
}

#[cfg(test)]
mod tests {
    use super::super::{BlockMatrix, ShellModel, Want};
    use crate::material::OrthotropicStvk;
    use crate::mesh::rectangular_grid;
    use crate::subdiv::{BasisOptions, LimitBasis};
    use crate::Vec3;
    use std::sync::Arc;

    /// The dense symmetric matrix of an assembled Hessian (upper blocks mirrored).
    fn dense(h: &BlockMatrix) -> nalgebra::DMatrix<f64> {
        let p = &h.pattern;
        let n = 3 * p.num_nodes;
        let mut d = nalgebra::DMatrix::zeros(n, n);
        for i in 0..p.num_nodes {
            for k in p.row_ptr[i]..p.row_ptr[i + 1] {
                let j = p.col[k] as usize;
                for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
                    d[(3 * i + r, 3 * j + c)] = h.blocks[k][(r, c)];
                    d[(3 * j + c, 3 * i + r)] = h.blocks[k][(r, c)];
                }
            }
        }
        d
    }

    fn sheet(law: OrthotropicStvk) -> ShellModel {
        let mesh = rectangular_grid(0.05, 0.075, 3, 4);
        let basis = LimitBasis::new(&mesh, BasisOptions::default()).unwrap();
        ShellModel::new(
            basis,
            crate::material::warp_direction(30.0),
            Arc::new(law),
            1.8e-4,
            0.1,
        )
        .unwrap()
    }

    fn hessian(model: &ShellModel, x: &[Vec3], want: Want) -> nalgebra::DMatrix<f64> {
        let mut h = BlockMatrix::zeros(model.pattern.clone());
        model.assemble(x, want, None, Some(&mut h)).unwrap();
        dense(&h)
    }

    const LAW: OrthotropicStvk = OrthotropicStvk {
        a11: 2.0e8,
        a22: 1.2e8,
        a12: 2.0e7,
        g12: 4.0e6,
    };

    /// On a sheet compressed along one side, sheared and curved, the exact Hessian is
    /// indefinite (compression) and the convexified one positive semidefinite, to round-off.
    #[test]
    fn the_convexified_hessian_is_positive_semidefinite_where_the_exact_one_is_not() {
        let model = sheet(LAW);
        let x: Vec<Vec3> = model
            .basis
            .control_points
            .iter()
            .map(|p| {
                [
                    0.9 * p[0] + 0.05 * p[1],
                    1.02 * p[1],
                    3e-3 * (70.0 * p[0]).sin() * (40.0 * p[1]).cos(),
                ]
            })
            .collect();
        let exact = hessian(&model, &x, Want::Hessian).symmetric_eigenvalues();
        let convex = hessian(&model, &x, Want::ProjectedHessian).symmetric_eigenvalues();
        let scale = exact.amax();
        assert!(exact.min() < -1e-6 * scale, "exact {}", exact.min());
        assert!(
            convex.min() >= -1e-12 * scale,
            "convexified {}",
            convex.min()
        );
    }

    /// Where every Gauss point is in tension with a positive definite tangent and carries no
    /// moment (a flat sheet stretched both ways, the paper's section), nothing is projected
    /// away: the convexified Hessian is the exact one.
    #[test]
    fn the_convexified_hessian_is_the_exact_one_in_flat_biaxial_tension() {
        let model = sheet(LAW);
        let x: Vec<Vec3> = model
            .basis
            .control_points
            .iter()
            .map(|p| [1.03 * p[0], 1.02 * p[1], 0.0])
            .collect();
        let exact = hessian(&model, &x, Want::Hessian);
        let convex = hessian(&model, &x, Want::ProjectedHessian);
        assert!((&exact - &convex).amax() <= 1e-12 * exact.amax());
    }
}
