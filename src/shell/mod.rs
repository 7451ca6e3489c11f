//! Kirchhoff–Love thin-shell kinematics at one Gauss point (Clyde et al. 2017 §3; Cirak, Ortiz &
//! Schröder 2000).
//!
//! The limit surface x(θ¹, θ²) gives the tangents a_α = x,_α, the unit normal
//! a₃ = a₁ × a₂ / |a₁ × a₂|, the metric a_αβ = a_α · a_β and the curvature b_αβ = x,_αβ · a₃.
//! With capitals for the rest shape, the membrane strain is ε_αβ = ½(a_αβ − A_αβ) and the bending
//! strain κ_αβ = B_αβ − b_αβ, so that the Green strain at height ξ through the thickness is
//! E(ξ) ≈ ε + ξ κ. Both are expressed in the warp/weft frame of the rest tangent plane,
//! Ẽ_ij = E_αβ c_i^α c_j^β with c_i^α = d_i · A^α (d₁ warp, d₂ weft, A^α the contravariant rest
//! basis); this map is linear and precomputed per point ([`RestPoint::to_material`]).
//!
//! Everything here is a function of the *kinematic vector* y = (a₁, a₂, x,₁₁, x,₁₂, x,₂₂) ∈ ℝ¹⁵,
//! which is linear in the control points through the limit stencil; [`StrainJet`] carries the
//! value, gradient and Hessian of each strain with respect to y, in closed form. Strain vectors
//! are (E₁₁, E₂₂, E₁₂) with tensor (not engineering) shear.

use crate::Vec3;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// Length of the kinematic vector y.
pub const NY: usize = 15;
pub type YVec = SVector<f64, NY>;
pub type YMat = SMatrix<f64, NY, NY>;

/// Offsets of a₁, a₂, x,₁₁, x,₁₂, x,₂₂ in y.
const A1: usize = 0;
const A2: usize = 3;
const H: [usize; 3] = [6, 9, 12];

/// Three strain components with their gradients with respect to y. Their Hessians are never
/// formed one by one: Newton needs only the stress-weighted sum Σ_k s_k ∂²E_k/∂y²
/// ([`add_membrane_hessian`], [`add_bending_hessian`]), which costs about as much as one of them.
#[derive(Clone, Debug)]
pub struct StrainJet {
    pub value: [f64; 3],
    pub grad: [YVec; 3],
}

impl StrainJet {
    fn zero() -> Self {
        Self {
            value: [0.0; 3],
            grad: [YVec::zeros(); 3],
        }
    }

    /// The jet of T·E (a fixed linear map of the components).
    #[inline]
    pub fn mapped(&self, t: &Matrix3<f64>) -> StrainJet {
        let mut out = StrainJet::zero();
        for k in 0..3 {
            for j in 0..3 {
                let a = t[(k, j)];
                out.value[k] += a * self.value[j];
                out.grad[k] += a * self.grad[j];
            }
        }
        out
    }
}

#[inline]
fn v3(y: &YVec, at: usize) -> Vector3<f64> {
    Vector3::new(y[at], y[at + 1], y[at + 2])
}

#[inline]
fn add_block(m: &mut YMat, r: usize, c: usize, b: &Matrix3<f64>) {
    let mut v = m.fixed_view_mut::<3, 3>(r, c);
    v += b;
}

/// Adds s·I to the 3 × 3 block (r, c).
#[inline]
fn add_diagonal(m: &mut YMat, r: usize, c: usize, s: f64) {
    for i in 0..3 {
        m[(r + i, c + i)] += s;
    }
}

/// Membrane strain ε_αβ = ½(a_α·a_β − A_αβ) and its gradient; `rest` is (A₁₁, A₂₂, A₁₂).
#[inline]
pub fn membrane(y: &YVec, rest: [f64; 3]) -> StrainJet {
    let (a1, a2) = (v3(y, A1), v3(y, A2));
    let mut j = StrainJet::zero();
    j.value = [
        0.5 * (a1.dot(&a1) - rest[0]),
        0.5 * (a2.dot(&a2) - rest[1]),
        0.5 * (a1.dot(&a2) - rest[2]),
    ];
    j.grad[0].fixed_rows_mut::<3>(A1).copy_from(&a1);
    j.grad[1].fixed_rows_mut::<3>(A2).copy_from(&a2);
    j.grad[2].fixed_rows_mut::<3>(A1).copy_from(&(0.5 * a2));
    j.grad[2].fixed_rows_mut::<3>(A2).copy_from(&(0.5 * a1));
    j
}

/// h += Σ_k s_k ∂²ε_k/∂y²: constant, s₁ I on (a₁, a₁), s₂ I on (a₂, a₂) and s₃/2 I on the
/// (a₁, a₂) blocks.
#[inline]
pub fn add_membrane_hessian(s: &[f64; 3], h: &mut YMat) {
    add_diagonal(h, A1, A1, s[0]);
    add_diagonal(h, A2, A2, s[1]);
    add_diagonal(h, A1, A2, 0.5 * s[2]);
    add_diagonal(h, A2, A1, 0.5 * s[2]);
}

/// Skew matrix [v]× with [v]× w = v × w.
#[inline]
fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)
}

/// The second derivatives x,₁₁, x,₂₂, x,₁₂ in y, in strain component order (11, 22, 12).
const H_OF_COMPONENT: [usize; 3] = [H[0], H[2], H[1]];

/// Bending strain κ_αβ = B_αβ − x,_αβ · a₃ and its gradient; `rest` is (B₁₁, B₂₂, B₁₂).
///
/// With m = a₁ × a₂, l = |m|, n = m / l and h = x,_αβ, the curvature b = h·m/l has
/// ∂b/∂m = v = (h − (h·n) n)/l; the chain rule through m (∂m/∂a₁ = −[a₂]×, ∂m/∂a₂ = [a₁]×)
/// gives the rest.
#[inline]
pub fn bending(y: &YVec, rest: [f64; 3]) -> StrainJet {
    let (a1, a2) = (v3(y, A1), v3(y, A2));
    let m = a1.cross(&a2);
    let l = m.norm();
    let n = m / l;
    let mut j = StrainJet::zero();
    for (k, &hk) in H_OF_COMPONENT.iter().enumerate() {
        let h = v3(y, hk);
        let hn = h.dot(&n);
        let v = (h - hn * n) / l;
        j.value[k] = rest[k] - hn;
        let g = &mut j.grad[k];
        g.fixed_rows_mut::<3>(A1).copy_from(&(-a2.cross(&v)));
        g.fixed_rows_mut::<3>(A2).copy_from(&(-v.cross(&a1)));
        g.fixed_rows_mut::<3>(hk).copy_from(&(-n));
    }
    j
}

/// h += Σ_k s_k ∂²κ_k/∂y².
///
/// Every term of ∂²b/∂y² is linear in h = x,_αβ: ∂²b/∂m² = −(h nᵀ + n hᵀ + (h·n)(I − 3 n nᵀ))/l²
/// and ∂b/∂m = v, while ∂²b/∂m∂h = (I − n nᵀ)/l does not depend on h. So the weighted sum is
/// one curvature's Hessian evaluated at h̄ = Σ_k s_k h_k (the a₁, a₂ blocks, through
/// ∂m/∂a₁ = −[a₂]×, ∂m/∂a₂ = [a₁]× and ∂²m/∂a₁∂a₂ contracted with v̄ = −[v̄]×), plus s_k times
/// the fixed (a_α, h_k) coupling blocks.
#[inline]
pub fn add_bending_hessian(y: &YVec, s: &[f64; 3], out: &mut YMat) {
    let (a1, a2) = (v3(y, A1), v3(y, A2));
    let m = a1.cross(&a2);
    let l = m.norm();
    let n = m / l;
    let p = Matrix3::identity() - n * n.transpose();
    let (s1, s2) = (skew(&a1), skew(&a2));
    let mut hbar = Vector3::zeros();
    for (k, &hk) in H_OF_COMPONENT.iter().enumerate() {
        hbar += s[k] * v3(y, hk);
    }
    let hn = hbar.dot(&n);
    let v = (hbar - hn * n) / l;
    let mm = -(hbar * n.transpose()
        + n * hbar.transpose()
        + hn * (Matrix3::identity() - 3.0 * n * n.transpose()))
        / (l * l);
    // the curvature enters κ with a minus sign
    let b11 = s2 * mm * s2;
    let b22 = s1 * mm * s1;
    let b12 = -(s2 * mm * s1 - skew(&v));
    add_block(out, A1, A1, &b11);
    add_block(out, A2, A2, &b22);
    add_block(out, A1, A2, &b12);
    add_block(out, A2, A1, &b12.transpose());
    let b1h = -(s2 * p / l);
    let b2h = s1 * p / l;
    for (k, &hk) in H_OF_COMPONENT.iter().enumerate() {
        let (c1, c2) = (s[k] * b1h, s[k] * b2h);
        add_block(out, A1, hk, &c1);
        add_block(out, hk, A1, &c1.transpose());
        add_block(out, A2, hk, &c2);
        add_block(out, hk, A2, &c2.transpose());
    }
}

/// Per-Gauss-point rest data.
#[derive(Clone, Debug)]
pub struct RestPoint {
    /// Rest metric (A₁₁, A₂₂, A₁₂).
    pub metric: [f64; 3],
    /// Rest curvature (B₁₁, B₂₂, B₁₂).
    pub curvature: [f64; 3],
    /// Quadrature weight × rest area element √det A.
    pub d_area: f64,
    /// Maps (E₁₁, E₂₂, E₁₂) in surface coordinates to (Ẽ₁₁, Ẽ₂₂, Ẽ₁₂) in the warp/weft frame.
    pub to_material: Matrix3<f64>,
}

/// A rest point could not be set up.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RestError {
    #[error("degenerate rest surface at a Gauss point (tangents parallel or zero)")]
    Degenerate,
    #[error("the warp direction is normal to the rest surface at a Gauss point")]
    WarpAlongNormal,
}

/// The kinematic vector y at a point from its limit derivatives [x, x_u, x_v, x_uu, x_uv, x_vv].
pub fn kinematic_vector(d: &[Vec3; 6]) -> YVec {
    let mut y = YVec::zeros();
    for k in 0..5 {
        for c in 0..3 {
            y[3 * k + c] = d[k + 1][c];
        }
    }
    y
}

impl RestPoint {
    /// Rest data from the rest limit derivatives `d`, the quadrature weight and the warp
    /// direction (projected onto the tangent plane).
    pub fn new(d: &[Vec3; 6], weight: f64, warp: Vec3) -> Result<Self, RestError> {
        let y = kinematic_vector(d);
        let (a1, a2) = (v3(&y, A1), v3(&y, A2));
        let m = a1.cross(&a2);
        let l = m.norm();
        if !l.is_finite() || l <= 1e-300 {
            return Err(RestError::Degenerate);
        }
        let n = m / l;
        let metric = [a1.dot(&a1), a2.dot(&a2), a1.dot(&a2)];
        let b = |k: usize| v3(&y, H[k]).dot(&n);
        let curvature = [b(0), b(2), b(1)];
        let det = metric[0] * metric[1] - metric[2] * metric[2];
        // contravariant basis A^α = A^{αβ} A_β
        let (i11, i22, i12) = (metric[1] / det, metric[0] / det, -metric[2] / det);
        let c1 = i11 * a1 + i12 * a2;
        let c2 = i12 * a1 + i22 * a2;
        let w = Vector3::new(warp[0], warp[1], warp[2]);
        let d1 = w - w.dot(&n) * n;
        let len = d1.norm();
        if !len.is_finite() || len <= 1e-12 * w.norm() || len == 0.0 {
            return Err(RestError::WarpAlongNormal);
        }
        let d1 = d1.normalize();
        let d2 = n.cross(&d1);
        // c_i^α = d_i · A^α
        let (p1, p2) = ([d1.dot(&c1), d1.dot(&c2)], [d2.dot(&c1), d2.dot(&c2)]);
        let to_material = Matrix3::new(
            p1[0] * p1[0],
            p1[1] * p1[1],
            2.0 * p1[0] * p1[1],
            p2[0] * p2[0],
            p2[1] * p2[1],
            2.0 * p2[0] * p2[1],
            p1[0] * p2[0],
            p1[1] * p2[1],
            p1[0] * p2[1] + p1[1] * p2[0],
        );
        Ok(Self {
            metric,
            curvature,
            d_area: weight * det.sqrt(),
            to_material,
        })
    }

    /// Membrane and bending strain jets in the warp/weft frame.
    #[inline]
    pub fn strains(&self, y: &YVec) -> (StrainJet, StrainJet) {
        (
            membrane(y, self.metric).mapped(&self.to_material),
            bending(y, self.curvature).mapped(&self.to_material),
        )
    }

    /// h += Σ_k n_k ∂²Ẽm_k/∂y² + mo_k ∂²Ẽb_k/∂y² for weights n, mo on the warp/weft-frame
    /// membrane and bending strains (the stress resultants in Newton's Hessian). Since
    /// Ẽ = T E, the weights are pulled back to surface coordinates once, Tᵀn, and the
    /// surface strains' weighted Hessians are added.
    #[inline]
    pub fn add_weighted_hessian(
        &self,
        y: &YVec,
        n: &Vector3<f64>,
        mo: &Vector3<f64>,
        h: &mut YMat,
    ) {
        let t = self.to_material.transpose();
        add_membrane_hessian(&(t * n).into(), h);
        add_bending_hessian(y, &(t * mo).into(), h);
    }

    /// h += Σ_k n⁺_k ∂²Ẽm_k/∂y² with n⁺ the tensile part of the membrane stress n: the weights
    /// pulled back to surface coordinates act on the strains' Hessian as the 2 × 2 tensor
    /// [[t₁, t₃/2], [t₃/2, t₂]] ⊗ I₃, whose negative eigenvalues (compression) are dropped.
    /// The bending moments' term is left out. What remains is positive semidefinite.
    #[inline]
    pub fn add_tensile_membrane_hessian(&self, n: &Vector3<f64>, h: &mut YMat) {
        let t = self.to_material.transpose() * n;
        let s = nalgebra::Matrix2::new(t[0], 0.5 * t[2], 0.5 * t[2], t[1]);
        let e = nalgebra::SymmetricEigen::new(s);
        let l = e.eigenvalues.map(|v| v.max(0.0));
        let p = e.eigenvectors * nalgebra::Matrix2::from_diagonal(&l) * e.eigenvectors.transpose();
        add_membrane_hessian(&[p[(0, 0)], p[(1, 1)], 2.0 * p[(0, 1)]], h);
    }

    /// Membrane and bending strains alone, in the warp/weft frame (the energy needs no more).
    pub fn strain_values(&self, y: &YVec) -> (Vector3<f64>, Vector3<f64>) {
        let (a1, a2) = (v3(y, A1), v3(y, A2));
        let m = a1.cross(&a2);
        let n = m / m.norm();
        let eps = Vector3::new(
            0.5 * (a1.dot(&a1) - self.metric[0]),
            0.5 * (a2.dot(&a2) - self.metric[1]),
            0.5 * (a1.dot(&a2) - self.metric[2]),
        );
        let kap = Vector3::new(
            self.curvature[0] - v3(y, H[0]).dot(&n),
            self.curvature[1] - v3(y, H[2]).dot(&n),
            self.curvature[2] - v3(y, H[1]).dot(&n),
        );
        (self.to_material * eps, self.to_material * kap)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_y() -> YVec {
        YVec::from_iterator([
            1.1, 0.2, -0.1, 0.15, 0.9, 0.3, 0.05, -0.2, 0.4, 0.1, 0.3, -0.25, -0.3, 0.12, 0.6,
        ])
    }

    /// A curved rest point with the warp off the surface axes.
    fn sample_rest() -> RestPoint {
        let d = [
            [0.0; 3],
            [1.0, 0.1, 0.0],
            [0.2, 0.9, 0.1],
            [0.0, 0.1, 0.3],
            [0.1, 0.0, -0.2],
            [0.0; 3],
        ];
        RestPoint::new(&d, 1.0, [1.0, 0.3, 0.0]).unwrap()
    }

    /// Gradients against central differences of the values, and the weighted Hessian
    /// (weights s) against central differences of the weighted gradients.
    fn check_jet(f: impl Fn(&YVec) -> StrainJet, hess: impl Fn(&YVec, &[f64; 3], &mut YMat)) {
        let y0 = sample_y();
        let j0 = f(&y0);
        let s = [0.7, -1.3, 0.45];
        let mut h0 = YMat::zeros();
        hess(&y0, &s, &mut h0);
        let h = 1e-6;
        for i in 0..NY {
            let mut yp = y0;
            let mut ym = y0;
            yp[i] += h;
            ym[i] -= h;
            let (jp, jm) = (f(&yp), f(&ym));
            for k in 0..3 {
                let fd = (jp.value[k] - jm.value[k]) / (2.0 * h);
                assert!(
                    (fd - j0.grad[k][i]).abs() < 1e-8,
                    "grad k={k} i={i}: {fd} vs {}",
                    j0.grad[k][i]
                );
            }
            for r in 0..NY {
                let fd: f64 = (0..3)
                    .map(|k| s[k] * (jp.grad[k][r] - jm.grad[k][r]) / (2.0 * h))
                    .sum();
                assert!(
                    (fd - h0[(r, i)]).abs() < 1e-7,
                    "hess ({r},{i}): {fd} vs {}",
                    h0[(r, i)]
                );
            }
        }
    }

    #[test]
    fn membrane_and_bending_derivatives_match_differences() {
        check_jet(
            |y| membrane(y, [1.0, 0.8, 0.1]),
            |_, s, h| add_membrane_hessian(s, h),
        );
        check_jet(|y| bending(y, [0.1, -0.2, 0.05]), add_bending_hessian);
    }

    #[test]
    fn weighted_hessian_in_the_material_frame_matches_differences() {
        let rest = sample_rest();
        let (n, mo) = (Vector3::new(0.3, -0.8, 1.1), Vector3::new(-0.5, 0.2, 0.9));
        let combined = |y: &YVec| {
            let (m, b) = rest.strains(y);
            let mut j = StrainJet::zero();
            for k in 0..3 {
                j.value[k] = m.value[k] * n[k] + b.value[k] * mo[k];
                j.grad[k] = m.grad[k] * n[k] + b.grad[k] * mo[k];
            }
            j
        };
        // component k of `combined` is n_k Ẽm_k + mo_k Ẽb_k, so weighting it by s_k is
        // weighting the strains by s_k n_k and s_k mo_k
        check_jet(combined, |y, s, h| {
            let w = |v: &Vector3<f64>| Vector3::new(s[0] * v[0], s[1] * v[1], s[2] * v[2]);
            rest.add_weighted_hessian(y, &w(&n), &w(&mo), h);
        });
    }

    #[test]
    fn strain_values_agree_with_the_jets() {
        let rest = sample_rest();
        let y = sample_y();
        let (m, b) = rest.strains(&y);
        let (em, eb) = rest.strain_values(&y);
        for k in 0..3 {
            assert!((m.value[k] - em[k]).abs() < 1e-14);
            assert!((b.value[k] - eb[k]).abs() < 1e-14);
        }
    }

    #[test]
    fn material_frame_of_an_orthonormal_patch_is_a_rotation() {
        // tangents along x and y, warp at 30° from x: Ẽ₁₁ is the strain along the warp
        let d = [
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0; 3],
            [0.0; 3],
            [0.0; 3],
        ];
        let t = 30f64.to_radians();
        let r = RestPoint::new(&d, 1.0, [t.cos(), t.sin(), 0.0]).unwrap();
        // uniaxial strain along x: E = diag(1, 0) → Ẽ₁₁ = cos², Ẽ₂₂ = sin², Ẽ₁₂ = −sin cos
        let e = r.to_material * Vector3::new(1.0, 0.0, 0.0);
        assert!((e[0] - t.cos().powi(2)).abs() < 1e-15);
        assert!((e[1] - t.sin().powi(2)).abs() < 1e-15);
        assert!((e[2] + t.sin() * t.cos()).abs() < 1e-15);
        assert_eq!(
            RestPoint::new(&d, 1.0, [0.0, 0.0, 1.0]).unwrap_err(),
            RestError::WarpAlongNormal
        );
    }
}
