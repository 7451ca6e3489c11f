//! The uniform cubic B-spline basis on one knot span, with first and second derivatives.
//!
//! On t ∈ [0, 1] the four basis functions are
//! N₀ = (1−t)³/6, N₁ = (3t³ − 6t² + 4)/6, N₂ = (−3t³ + 3t² + 3t + 1)/6, N₃ = t³/6;
//! a regular Catmull–Clark face is their tensor product over its 4 × 4 one-ring.

/// Values, first and second derivatives of the four cubic B-spline basis functions at `t`.
pub fn cubic(t: f64) -> [[f64; 4]; 3] {
    let s = 1.0 - t;
    let t2 = t * t;
    let t3 = t2 * t;
    [
        [
            s * s * s / 6.0,
            (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
            (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
            t3 / 6.0,
        ],
        [
            -0.5 * s * s,
            0.5 * (3.0 * t2 - 4.0 * t),
            0.5 * (-3.0 * t2 + 2.0 * t + 1.0),
            0.5 * t2,
        ],
        [s, 3.0 * t - 2.0, 1.0 - 3.0 * t, t],
    ]
}

/// Tensor-product weights of the 16 control points (index `4 j + i`, i along u, j along v) for
/// [x, x_u, x_v, x_uu, x_uv, x_vv] at (u, v). `du` scales one parametric derivative (2^depth
/// when the patch is a sub-patch at refinement depth `depth`).
pub fn bicubic_weights(u: f64, v: f64, du: f64) -> [[f64; 16]; 6] {
    let bu = cubic(u);
    let bv = cubic(v);
    let mut w = [[0.0; 16]; 6];
    // (order in u, order in v, scale) for each output
    let kinds = [
        (0, 0, 1.0),
        (1, 0, du),
        (0, 1, du),
        (2, 0, du * du),
        (1, 1, du * du),
        (0, 2, du * du),
    ];
    for (k, &(a, b, s)) in kinds.iter().enumerate() {
        for j in 0..4 {
            for i in 0..4 {
                w[k][4 * j + i] = s * bu[a][i] * bv[b][j];
            }
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_of_unity_and_derivatives_by_differences() {
        for &t in &[0.0, 0.1, 0.37, 0.5, 0.99, 1.0] {
            let b = cubic(t);
            assert!((b[0].iter().sum::<f64>() - 1.0).abs() < 1e-15);
            assert!(b[1].iter().sum::<f64>().abs() < 1e-15);
            assert!(b[2].iter().sum::<f64>().abs() < 1e-15);
            let h = 1e-6;
            let (p, m) = (cubic(t + h), cubic(t - h));
            for i in 0..4 {
                assert!(((p[0][i] - m[0][i]) / (2.0 * h) - b[1][i]).abs() < 1e-9);
                assert!(((p[1][i] - m[1][i]) / (2.0 * h) - b[2][i]).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn reproduces_the_identity_on_integer_knots() {
        // Σ (i − 1) N_i(t) = t: cubic B-splines reproduce linear functions.
        for &t in &[0.0, 0.25, 0.8] {
            let b = cubic(t);
            let x: f64 = (0..4).map(|i| (i as f64 - 1.0) * b[0][i]).sum();
            assert!((x - t).abs() < 1e-15);
        }
    }
}
