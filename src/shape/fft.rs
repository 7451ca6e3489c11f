//! The FFT shape descriptor of Larionov et al. 2022 (§5): a sheet resampled on an n × n grid of
//! its material coordinates, each coordinate's mean removed, and the magnitude of its 2-D
//! discrete Fourier transform divided by n². Dropping the phase makes the descriptor blind to
//! where a wrinkle sits and to which way it bulges, and keeps it sensitive to the wrinkles'
//! amplitude and wavelength, which is what a material determines.
//!
//! Only the low frequencies are compared (waves at least four grid cells long, see
//! [`Spectrum::kept`]).
//!
//! The grid covers the bounding box of the mesh's (u, v) at cell centres; a grid point is
//! interpolated linearly in the triangle of (u, v) that holds it (or, past the border, the
//! nearest one, its weights clamped). The transform is separable, rows then columns, in
//! 2 n³ complex multiply–adds per coordinate (65 k at n = 32): cheaper than a simulation by
//! far, so no fast transform is needed.

use super::ShapeMesh;
use crate::Vec3;

/// Barycentric weights of (u, v) in the triangle with corners t.
fn barycentric(t: [[f64; 2]; 3], p: [f64; 2]) -> [f64; 3] {
    let (a, b, c) = (t[0], t[1], t[2]);
    let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    if det.abs() < f64::MIN_POSITIVE {
        return [f64::NEG_INFINITY; 3];
    }
    let s = ((p[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (p[1] - a[1])) / det;
    let r = ((b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1])) / det;
    [1.0 - s - r, s, r]
}

/// The mesh's positions at the n × n cell centres of its (u, v) bounding box, row by row
/// (v slow, u fast).
pub fn resample(mesh: &ShapeMesh, n: usize) -> Result<Vec<Vec3>, String> {
    let uv = mesh.uv.as_ref().map_err(|e| e.clone())?;
    if uv.iter().flatten().any(|x| !x.is_finite()) {
        return Err("a vertex in no face has no texture coordinates".into());
    }
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for t in &mesh.triangles {
        for &i in t {
            (0..2).for_each(|k| {
                lo[k] = lo[k].min(uv[i][k]);
                hi[k] = hi[k].max(uv[i][k]);
            });
        }
    }
    if !(hi[0] > lo[0] && hi[1] > lo[1]) {
        return Err("the texture coordinates span no area".into());
    }
    let corners: Vec<[[f64; 2]; 3]> = mesh.triangles.iter().map(|t| t.map(|i| uv[i])).collect();
    let mut out = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let p = [
                lo[0] + (i as f64 + 0.5) / n as f64 * (hi[0] - lo[0]),
                lo[1] + (j as f64 + 0.5) / n as f64 * (hi[1] - lo[1]),
            ];
            // the triangle that holds p best (largest smallest weight)
            let mut best = (f64::NEG_INFINITY, 0, [0.0; 3]);
            for (k, c) in corners.iter().enumerate() {
                let w = barycentric(*c, p);
                let m = w[0].min(w[1]).min(w[2]);
                if m > best.0 {
                    best = (m, k, w);
                    if m >= 0.0 {
                        break;
                    }
                }
            }
            let w = best.2.map(|x| x.max(0.0));
            let sum: f64 = w.iter().sum();
            let t = mesh.triangles[best.1];
            out.push(
                [0, 1, 2]
                    .map(|k| (0..3).map(|c| w[c] * mesh.positions[t[c]][k]).sum::<f64>() / sum),
            );
        }
    }
    Ok(out)
}

/// The FFT magnitudes of a resampled sheet, one n × n array per coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct Spectrum {
    pub n: usize,
    pub magnitude: [Vec<f64>; 3],
}

impl Spectrum {
    /// From the n × n grid of [`resample`].
    pub fn of_grid(grid: &[Vec3], n: usize) -> Self {
        assert_eq!(grid.len(), n * n, "an n × n grid");
        let (cos, sin): (Vec<f64>, Vec<f64>) = (0..n)
            .map(|m| {
                let a = 2.0 * std::f64::consts::PI * m as f64 / n as f64;
                (a.cos(), -a.sin())
            })
            .unzip();
        let magnitude = [0, 1, 2].map(|c| {
            let mean = grid.iter().map(|p| p[c]).sum::<f64>() / (n * n) as f64;
            // rows: y[j][l] = Σ_i f[j][i] w^{l i}
            let mut y = vec![(0.0, 0.0); n * n];
            for j in 0..n {
                for l in 0..n {
                    let (mut re, mut im) = (0.0, 0.0);
                    for i in 0..n {
                        let f = grid[j * n + i][c] - mean;
                        let m = (l * i) % n;
                        re += f * cos[m];
                        im += f * sin[m];
                    }
                    y[j * n + l] = (re, im);
                }
            }
            // columns: x[k][l] = Σ_j y[j][l] w^{k j}
            let mut out = vec![0.0; n * n];
            for k in 0..n {
                for l in 0..n {
                    let (mut re, mut im) = (0.0, 0.0);
                    for j in 0..n {
                        let (a, b) = y[j * n + l];
                        let m = (k * j) % n;
                        re += a * cos[m] - b * sin[m];
                        im += a * sin[m] + b * cos[m];
                    }
                    out[k * n + l] = re.hypot(im) / (n * n) as f64;
                }
            }
            out
        });
        Self { n, magnitude }
    }

    /// Of a mesh, on an n × n grid.
    pub fn of_mesh(mesh: &ShapeMesh, n: usize) -> Result<Self, String> {
        Ok(Self::of_grid(&resample(mesh, n)?, n))
    }

    /// Whether bin `i` (k·n + l) is one of the kept low frequencies: |k|, |l| ≤ n/4 (signed
    /// frequencies), waves at least four cells long. Measurement noise spreads evenly over all
    /// n² bins while a sheet's wrinkles sit in the low ones, so dropping the rest cuts the
    /// noise's share about fourfold (a 0.05 mm noise on 1 mm frame wrinkles moved the best
    /// shear 30 % with every bin kept).
    pub fn kept(&self, i: usize) -> bool {
        let n = self.n;
        let f = |k: usize| k.min(n - k) <= n / 4;
        f(i / n) && f(i % n)
    }

    /// (self − target) over the kept bins, coordinate by coordinate over the target's norm of
    /// that coordinate (floored at 1e-3 of the largest), over √3: the sum of squares is the
    /// mean of the three coordinates' squared relative errors.
    pub fn residuals(&self, target: &Spectrum) -> Vec<f64> {
        let norms = target.magnitude.each_ref().map(|m| {
            m.iter()
                .enumerate()
                .filter(|(i, _)| self.kept(*i))
                .map(|(_, v)| v * v)
                .sum::<f64>()
                .sqrt()
        });
        let floor = 1e-3 * norms.iter().fold(0.0f64, |a, &b| a.max(b));
        let mut r = Vec::with_capacity(3 * self.n * self.n);
        for c in 0..3 {
            let s = 1.0 / (norms[c].max(floor).max(f64::MIN_POSITIVE) * 3f64.sqrt());
            r.extend(
                self.magnitude[c]
                    .iter()
                    .zip(&target.magnitude[c])
                    .enumerate()
                    .filter(|(i, _)| self.kept(*i))
                    .map(|(_, (a, b))| (a - b) * s),
            );
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid_of(n: usize, f: impl Fn(f64, f64) -> f64) -> Vec<Vec3> {
        let mut g = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                g.push([x, y, f(x, y)]);
            }
        }
        g
    }

    /// A cosine of 3 waves along u has two spectral lines of half its amplitude; moving it
    /// (phase) or flipping it changes no magnitude.
    #[test]
    fn a_cosine_has_two_lines_and_no_phase() {
        let n = 16;
        let tau = 2.0 * std::f64::consts::PI;
        let s = Spectrum::of_grid(&grid_of(n, |x, _| 0.2 * (tau * 3.0 * x).cos()), n);
        let z = &s.magnitude[2];
        assert!((z[3] - 0.1).abs() < 1e-12 && (z[n - 3] - 0.1).abs() < 1e-12);
        let rest: f64 = z.iter().map(|v| v * v).sum::<f64>() - 2.0 * 0.01;
        assert!(rest.abs() < 1e-15, "{rest}");
        let moved = Spectrum::of_grid(&grid_of(n, |x, _| -0.2 * (tau * 3.0 * x + 1.0).cos()), n);
        assert!(moved.residuals(&s).iter().all(|r| r.abs() < 1e-12));
        // a wavelength changed is seen
        let other = Spectrum::of_grid(&grid_of(n, |x, _| 0.2 * (tau * 4.0 * x).cos()), n);
        let e: f64 = other.residuals(&s).iter().map(|r| r * r).sum::<f64>();
        assert!(e.sqrt() > 0.5, "{e}");
    }

    /// Resampling a mesh whose positions are linear in (u, v) is exact, whatever the mesh.
    #[test]
    fn resampling_is_exact_for_linear_positions() {
        let mut m = ShapeMesh::default();
        let mut uv = Vec::new();
        let k = 7;
        for j in 0..=k {
            for i in 0..=k {
                let (u, v) = (2.0 * i as f64 / k as f64, j as f64 / k as f64);
                uv.push([u, v]);
                m.positions.push([u, v, 0.3 * u - 0.7 * v + 0.1]);
            }
        }
        for j in 0..k {
            for i in 0..k {
                let a = j * (k + 1) + i;
                m.triangles.push([a, a + 1, a + k + 2]);
                m.triangles.push([a, a + k + 2, a + k + 1]);
            }
        }
        m.uv = Ok(uv);
        let g = resample(&m, 5).unwrap();
        let p = g[5 + 3];
        let (u, v) = (2.0 * 3.5 / 5.0, 1.5 / 5.0);
        assert!((p[0] - u).abs() < 1e-12 && (p[1] - v).abs() < 1e-12);
        assert!((p[2] - (0.3 * u - 0.7 * v + 0.1)).abs() < 1e-12);
    }
}
