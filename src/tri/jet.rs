//! Second-order forward differentiation over a fixed number of variables: a [`Jet`] carries a
//! value with its exact gradient and Hessian, so every element energy of the triangle models is
//! written once, as a formula, and its force and stiffness follow without hand-derived
//! (error-prone) second derivatives. Each operation costs O(N²) flops: 81 per product for a
//! triangle (N = 9), 144 for a dihedral hinge (N = 12).

use std::ops::{Add, Mul, Neg, Sub};

/// f(x) with ∂f/∂x and ∂²f/∂x² over N variables.
#[derive(Clone, Copy, Debug)]
pub struct Jet<const N: usize> {
    pub v: f64,
    pub g: [f64; N],
    pub h: [[f64; N]; N],
}

impl<const N: usize> Jet<N> {
    pub fn constant(v: f64) -> Self {
        Self {
            v,
            g: [0.0; N],
            h: [[0.0; N]; N],
        }
    }

    /// The variable x_i at value v.
    pub fn variable(i: usize, v: f64) -> Self {
        let mut j = Self::constant(v);
        j.g[i] = 1.0;
        j
    }

    /// f(self) given f, f′ and f″ at self's value (the chain rule).
    pub fn map(&self, f: f64, df: f64, ddf: f64) -> Self {
        let mut out = Self::constant(f);
        for i in 0..N {
            out.g[i] = df * self.g[i];
            for j in 0..N {
                out.h[i][j] = df * self.h[i][j] + ddf * self.g[i] * self.g[j];
            }
        }
        out
    }

    /// f(a, b) given f and its first and second partials at (a, b).
    pub fn map2(a: &Self, b: &Self, f: f64, d: [f64; 2], dd: [f64; 3]) -> Self {
        let mut out = Self::constant(f);
        for i in 0..N {
            out.g[i] = d[0] * a.g[i] + d[1] * b.g[i];
            for j in 0..N {
                out.h[i][j] = d[0] * a.h[i][j]
                    + d[1] * b.h[i][j]
                    + dd[0] * a.g[i] * a.g[j]
                    + dd[1] * (a.g[i] * b.g[j] + b.g[i] * a.g[j])
                    + dd[2] * b.g[i] * b.g[j];
            }
        }
        out
    }

    pub fn sqrt(&self) -> Self {
        let s = self.v.sqrt();
        self.map(s, 0.5 / s, -0.25 / (s * self.v))
    }

    pub fn recip(&self) -> Self {
        let r = 1.0 / self.v;
        self.map(r, -r * r, 2.0 * r * r * r)
    }

    /// atan2(self, x): the angle of (x, self).
    pub fn atan2(&self, x: &Self) -> Self {
        let (y, xv) = (self.v, x.v);
        let r2 = xv * xv + y * y;
        let r4 = r2 * r2;
        Self::map2(
            self,
            x,
            y.atan2(xv),
            [xv / r2, -y / r2],
            [
                -2.0 * xv * y / r4,
                (y * y - xv * xv) / r4,
                2.0 * xv * y / r4,
            ],
        )
    }

    pub fn scale(&self, s: f64) -> Self {
        let mut out = *self;
        out.v *= s;
        out.g.iter_mut().for_each(|g| *g *= s);
        out.h.iter_mut().flatten().for_each(|h| *h *= s);
        out
    }
}

impl<const N: usize> Add for Jet<N> {
    type Output = Self;
    fn add(mut self, o: Self) -> Self {
        self.v += o.v;
        for i in 0..N {
            self.g[i] += o.g[i];
            for j in 0..N {
                self.h[i][j] += o.h[i][j];
            }
        }
        self
    }
}

impl<const N: usize> Sub for Jet<N> {
    type Output = Self;
    fn sub(mut self, o: Self) -> Self {
        self.v -= o.v;
        for i in 0..N {
            self.g[i] -= o.g[i];
            for j in 0..N {
                self.h[i][j] -= o.h[i][j];
            }
        }
        self
    }
}

impl<const N: usize> Neg for Jet<N> {
    type Output = Self;
    fn neg(self) -> Self {
        self.scale(-1.0)
    }
}

impl<const N: usize> Mul for Jet<N> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        let mut out = Self::constant(self.v * o.v);
        for i in 0..N {
            out.g[i] = self.v * o.g[i] + o.v * self.g[i];
            for j in 0..N {
                out.h[i][j] = self.v * o.h[i][j]
                    + o.v * self.h[i][j]
                    + self.g[i] * o.g[j]
                    + o.g[i] * self.g[j];
            }
        }
        out
    }
}

/// The jet over N = 3Q node coordinates of a function whose jet `j` is over M = 3P vectors
/// v_p = Σ_n a[p][n] x_n (a linear map acting alike on each coordinate): g_n = Σ_p a_pn g_p and
/// H_nm = Σ_pq a_pn a_qm H_pq, per coordinate pair. Writing an element over the few vectors it
/// depends on (a triangle's w_u, w_v; a hinge's edge vectors) and pulling back costs far less
/// than differentiating over every node coordinate.
pub fn pull_back<const M: usize, const N: usize, const Q: usize>(
    j: &Jet<M>,
    a: &[[f64; Q]],
) -> Jet<N> {
    let p = a.len();
    debug_assert!(3 * p == M && 3 * Q == N);
    let mut out = Jet::<N>::constant(j.v);
    for n in 0..Q {
        for c in 0..3 {
            out.g[3 * n + c] = (0..p).map(|k| a[k][n] * j.g[3 * k + c]).sum();
        }
    }
    // t[3k + c][3n + d] = Σ_q H[3k + c][3q + d] a[q][n]
    let mut t = vec![[0.0; N]; M];
    for (row, trow) in j.h.iter().zip(t.iter_mut()) {
        for n in 0..Q {
            for d in 0..3 {
                trow[3 * n + d] = (0..p).map(|q| row[3 * q + d] * a[q][n]).sum();
            }
        }
    }
    for m in 0..Q {
        for c in 0..3 {
            for col in 0..N {
                out.h[3 * m + c][col] = (0..p).map(|k| a[k][m] * t[3 * k + c][col]).sum();
            }
        }
    }
    out
}

/// Vector `k` of an element's reduced variables as jets (variables 3k … 3k + 2), or constants
/// when M = 0.
pub fn vector<const M: usize>(k: usize, v: [f64; 3]) -> JetVec<M> {
    point::<M>(k, v)
}

/// A 3-vector of jets.
pub type JetVec<const N: usize> = [Jet<N>; 3];

/// The position of local node `node` as jets (variables 3·node … 3·node + 2; constants when
/// N = 0, which evaluates an element's energy alone at plain arithmetic's cost).
pub fn point<const N: usize>(node: usize, x: [f64; 3]) -> JetVec<N> {
    [0, 1, 2].map(|c| {
        if N == 0 {
            Jet::constant(x[c])
        } else {
            Jet::variable(3 * node + c, x[c])
        }
    })
}

pub fn sub<const N: usize>(a: &JetVec<N>, b: &JetVec<N>) -> JetVec<N> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn dot<const N: usize>(a: &JetVec<N>, b: &JetVec<N>) -> Jet<N> {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross<const N: usize>(a: &JetVec<N>, b: &JetVec<N>) -> JetVec<N> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Σ c_k p_k: a fixed linear combination of jet vectors.
pub fn combine<const N: usize>(c: &[f64], p: &[JetVec<N>]) -> JetVec<N> {
    let mut out = [Jet::constant(0.0); 3];
    for (ck, pk) in c.iter().zip(p) {
        for d in 0..3 {
            out[d] = out[d] + pk[d].scale(*ck);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// f(x, y) = atan2(y, x) · sqrt(x² + y²) · x against central differences.
    #[test]
    fn derivatives_match_finite_differences() {
        let f = |x: f64, y: f64| {
            let a = Jet::<2>::variable(0, x);
            let b = Jet::<2>::variable(1, y);
            b.atan2(&a) * (a * a + b * b).sqrt() * a
        };
        let (x, y) = (0.7, -1.3);
        let j = f(x, y);
        let h = 1e-5;
        let fd = |dx: f64, dy: f64| f(x + dx, y + dy);
        let gx = (fd(h, 0.0).v - fd(-h, 0.0).v) / (2.0 * h);
        let gy = (fd(0.0, h).v - fd(0.0, -h).v) / (2.0 * h);
        assert!((j.g[0] - gx).abs() < 1e-8 && (j.g[1] - gy).abs() < 1e-8);
        let hxy = (fd(0.0, h).g[0] - fd(0.0, -h).g[0]) / (2.0 * h);
        let hxx = (fd(h, 0.0).g[0] - fd(-h, 0.0).g[0]) / (2.0 * h);
        let hyy = (fd(0.0, h).g[1] - fd(0.0, -h).g[1]) / (2.0 * h);
        assert!((j.h[0][1] - hxy).abs() < 1e-7, "{} {hxy}", j.h[0][1]);
        assert!((j.h[1][0] - hxy).abs() < 1e-7);
        assert!((j.h[0][0] - hxx).abs() < 1e-7 && (j.h[1][1] - hyy).abs() < 1e-7);
    }
}
