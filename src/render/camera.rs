//! A perspective camera that frames a bounding box, z up (the scenes' convention: gravity along
//! −z, flat sheets in the xy plane). Matrices follow wgpu's clip space (depth in [0, 1]).

use crate::Vec3;

/// Where the camera looks from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// `Front` for shapes that hang (taller than a third of their width), `Above` for flat ones.
    Auto,
    /// From the −y side, a little above and to the right: the drape's view (Figure 1).
    Front,
    /// From above at about 60°: sheets lying in the xy plane (Figure 5).
    Above,
}

/// Vertical field of view, degrees.
const FOV_Y_DEG: f64 = 30.0;

/// A camera framing a box, with its 4 × 4 view–projection matrix (row-major, column vectors).
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub view: View,
    pub width: u32,
    pub height: u32,
    pub view_proj: [[f64; 4]; 4],
}

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn unit(a: Vec3) -> Vec3 {
    let l = dot(a, a).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

/// Whether a box is a hanging shape (its height over a third of its width).
pub fn hangs(lo: Vec3, hi: Vec3) -> bool {
    let d = sub(hi, lo);
    d[2] > d[0].max(d[1]) / 3.0
}

impl Camera {
    /// Frames the box `lo`–`hi` (its bounding sphere fills the narrower field of view).
    pub fn frame(lo: Vec3, hi: Vec3, view: View, width: u32, height: u32) -> Self {
        let view = match view {
            View::Auto if hangs(lo, hi) => View::Front,
            View::Auto => View::Above,
            v => v,
        };
        let c = [
            0.5 * (lo[0] + hi[0]),
            0.5 * (lo[1] + hi[1]),
            0.5 * (lo[2] + hi[2]),
        ];
        let r = (0.5 * dot(sub(hi, lo), sub(hi, lo)).sqrt()).max(1e-9);
        let dir = unit(match view {
            View::Above => [0.45, -0.75, 1.5],
            _ => [0.35, -1.0, 0.35],
        });
        let aspect = width as f64 / height as f64;
        let half_y = 0.5 * FOV_Y_DEG.to_radians();
        let (ty, tx) = (half_y.tan(), half_y.tan() * aspect);
        // the nearest distance along `dir` at which every corner of the box is in the picture,
        // with a 6 % margin
        let f = [-dir[0], -dir[1], -dir[2]];
        let s = unit(cross(f, [0.0, 0.0, 1.0]));
        let u = cross(s, f);
        let mut dist: f64 = 1e-9;
        for k in 0..8 {
            let p = [
                if k & 1 == 0 { lo[0] } else { hi[0] } - c[0],
                if k & 2 == 0 { lo[1] } else { hi[1] } - c[1],
                if k & 4 == 0 { lo[2] } else { hi[2] } - c[2],
            ];
            let depth = dot(f, p);
            dist = dist
                .max(depth + 1.06 * dot(s, p).abs() / tx)
                .max(depth + 1.06 * dot(u, p).abs() / ty);
        }
        let eye = [
            c[0] + dist * dir[0],
            c[1] + dist * dir[1],
            c[2] + dist * dir[2],
        ];
        let view_m = [
            [s[0], s[1], s[2], -dot(s, eye)],
            [u[0], u[1], u[2], -dot(u, eye)],
            [-f[0], -f[1], -f[2], dot(f, eye)],
            [0.0, 0.0, 0.0, 1.0],
        ];
        let (near, far) = ((dist - 3.0 * r).max(0.01 * dist), dist + 14.0 * r);
        let fy = 1.0 / half_y.tan();
        let proj = [
            [fy / aspect, 0.0, 0.0, 0.0],
            [0.0, fy, 0.0, 0.0],
            [0.0, 0.0, far / (near - far), near * far / (near - far)],
            [0.0, 0.0, -1.0, 0.0],
        ];
        let mut view_proj = [[0.0; 4]; 4];
        for i in 0..4 {
            for j in 0..4 {
                view_proj[i][j] = (0..4).map(|k| proj[i][k] * view_m[k][j]).sum();
            }
        }
        Self {
            eye,
            view,
            width,
            height,
            view_proj,
        }
    }

    /// Pixel column, row (from the top) and depth in [0, 1] of a point, or None behind the eye.
    pub fn project(&self, p: Vec3) -> Option<[f64; 3]> {
        let h = [p[0], p[1], p[2], 1.0];
        let clip: Vec<f64> = (0..4)
            .map(|i| (0..4).map(|k| self.view_proj[i][k] * h[k]).sum())
            .collect();
        if clip[3] <= 0.0 {
            return None;
        }
        let (x, y, z) = (clip[0] / clip[3], clip[1] / clip[3], clip[2] / clip[3]);
        Some([
            0.5 * (x + 1.0) * self.width as f64,
            0.5 * (1.0 - y) * self.height as f64,
            z,
        ])
    }

    /// The matrix as WGSL's `mat4x4<f32>` wants it: four columns.
    pub fn columns_f32(&self) -> [[f32; 4]; 4] {
        let mut m = [[0f32; 4]; 4];
        for (j, col) in m.iter_mut().enumerate() {
            for (i, v) in col.iter_mut().enumerate() {
                *v = self.view_proj[i][j] as f32;
            }
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_box_is_inside_the_picture_and_its_centre_in_the_middle() {
        let (lo, hi) = ([-0.5, -0.5, 0.0], [0.5, 0.5, 0.0]);
        let cam = Camera::frame(lo, hi, View::Auto, 160, 120);
        assert_eq!(cam.view, View::Above);
        let c = cam.project([0.0, 0.0, 0.0]).unwrap();
        assert!((c[0] - 80.0).abs() < 1e-9 && (c[1] - 60.0).abs() < 1e-9);
        for p in [[-0.5, -0.5, 0.0], [0.5, 0.5, 0.0], [0.5, -0.5, 0.0]] {
            let q = cam.project(p).unwrap();
            assert!(q[0] > 0.0 && q[0] < 160.0 && q[1] > 0.0 && q[1] < 120.0);
            assert!(q[2] > 0.0 && q[2] < 1.0);
        }
        // +z is up in the picture
        let up = cam.project([0.0, 0.0, 0.1]).unwrap();
        assert!(up[1] < c[1]);
    }

    #[test]
    fn a_hanging_box_is_seen_from_the_front() {
        let cam = Camera::frame([0.0, -0.1, -1.0], [1.0, 0.1, 0.0], View::Auto, 100, 100);
        assert_eq!(cam.view, View::Front);
        assert!(cam.eye[1] < -0.1);
    }
}
