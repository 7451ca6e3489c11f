//! External loads of a shell: gravity on the areal density, dead loads on the control points, a
//! follower pressure (potential −p V) and an end moment on a limit curve (potential −m ∫ θ ds),
//! with their contributions to the energy, gradient and Hessian.

use super::{Accumulator, BlockMatrix, FaceScratch, ShellModel};
use crate::quadrature::GaussLegendre;
use crate::Vec3;
use nalgebra::{Matrix3, Vector3};

/// Edge points of an end moment (stencil, weight × rest length element, reference angle) and
/// the moment per unit length.
#[derive(Clone, Debug)]
pub(super) struct EdgeMoment {
    points: Vec<(crate::subdiv::LimitStencil, f64, f64)>,
    per_length: f64,
}

/// The angle equal to `a` modulo 2π nearest to `reference`.
fn unwrap(a: f64, reference: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    a + tau * ((reference - a) / tau).round()
}

impl ShellModel {
    /// Sets the gravitational acceleration (m/s²), e.g. [0, 0, −9.80665], or zero.
    pub fn set_gravity(&mut self, g: Vec3) {
        self.gravity = g;
        let f = &mut self.gravity_gradient;
        f.iter_mut().for_each(|v| *v = [0.0; 3]);
        for (q, rest) in self.rest.iter().enumerate() {
            let (idx, w) = self.basis.stencil(q);
            for (&i, w) in idx.iter().zip(w) {
                for c in 0..3 {
                    f[i as usize][c] -= self.areal_density * rest.d_area * w[0] * g[c];
                }
            }
        }
        self.update_external();
    }

    /// Sets dead (fixed-direction) loads on the control points, N; `load.len()` must be the
    /// number of control points.
    pub fn set_dead_load(&mut self, load: Vec<Vec3>) {
        assert_eq!(load.len(), self.num_nodes(), "one load per control point");
        self.dead_load = load;
        self.update_external();
    }

    pub(super) fn update_external(&mut self) {
        for ((e, g), f) in self
            .external_gradient
            .iter_mut()
            .zip(&self.gravity_gradient)
            .zip(&self.dead_load)
        {
            *e = std::array::from_fn(|c| g[c] - f[c]);
        }
    }

    /// Sets a pressure (Pa) on the side x_u × x_v points to. It follows the surface: its
    /// potential is −p V with V = ⅓ ∫ x·(x_u × x_v) du dv, the enclosed volume of a closed
    /// surface.
    pub fn set_pressure(&mut self, p: f64) {
        self.pressure = p;
    }

    pub fn pressure(&self) -> f64 {
        self.pressure
    }

    /// Puts a moment `per_length` (N·m/m) about the x axis on the limit curve v = `v` of
    /// `faces`, conjugate to the angle θ = atan2(x_v·e_z, x_v·e_y) of the tangent across that
    /// edge: its potential is −m ∫ θ ds, so it follows the rotation (a pure end moment rolls a
    /// strip into a circle). θ is single-valued for rotations below ±180°.
    pub fn set_edge_moment(&mut self, faces: &[usize], v: f64, per_length: f64) {
        let surface = self.basis.surface();
        let rule = GaussLegendre::new(4)
            .expect("4 is a valid rule")
            .on_interval(0.0, 1.0);
        let x = &self.basis.control_points;
        let mut points = Vec::new();
        for &face in faces {
            let uvs: Vec<[f64; 2]> = rule.iter().map(|&(u, _)| [u, v]).collect();
            let Ok(stencils) = surface.stencils(face, &uvs) else {
                continue;
            };
            for (s, &(_, w)) in stencils.into_iter().zip(&rule) {
                let t = s.apply(x).d[1];
                let ds = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
                let tv = s.apply(x).d[2];
                let theta = tv[2].atan2(tv[1]);
                points.push((s, w * ds, theta));
            }
        }
        self.edge_moment = Some(EdgeMoment { points, per_length });
    }

    /// Moves each edge point's reference angle to its (unwrapped) angle at `x`.
    pub fn update_edge_angles(&mut self, x: &[Vec3]) {
        if let Some(em) = &mut self.edge_moment {
            for (s, _, reference) in em.points.iter_mut() {
                let t = s.apply(x).d[2];
                *reference = unwrap(t[2].atan2(t[1]), *reference);
            }
        }
    }

    /// Scales the edge moment set by [`ShellModel::set_edge_moment`].
    pub fn scale_edge_moment(&mut self, per_length: f64) {
        if let Some(em) = &mut self.edge_moment {
            em.per_length = per_length;
        }
    }

    /// The edge moment's potential and, as asked, gradient and Hessian.
    pub(super) fn edge_moment_terms(
        &self,
        x: &[Vec3],
        grad: Option<&mut [Vec3]>,
        hess: Option<&mut BlockMatrix>,
    ) -> f64 {
        let Some(EdgeMoment {
            points,
            per_length: m,
        }) = &self.edge_moment
        else {
            return 0.0;
        };
        let mut grad = grad;
        let mut hess = hess;
        let mut energy = 0.0;
        for (s, wds, reference) in points {
            let t = s.apply(x).d[2];
            let (ty, tz) = (t[1], t[2]);
            let r2 = ty * ty + tz * tz;
            let theta = unwrap(tz.atan2(ty), *reference);
            let c = -m * wds;
            energy += c * theta;
            // ∂θ/∂t = (0, −t_z, t_y)/ρ²; ∂²θ/∂t² in (y, z): [[2 t_y t_z, t_z² − t_y²], [., −2 t_y t_z]]/ρ⁴
            let dt = [0.0, -tz / r2, ty / r2];
            let r4 = r2 * r2;
            let h = Matrix3::new(
                0.0,
                0.0,
                0.0,
                0.0,
                2.0 * ty * tz / r4,
                (tz * tz - ty * ty) / r4,
                0.0,
                (tz * tz - ty * ty) / r4,
                -2.0 * ty * tz / r4,
            );
            if let Some(g) = grad.as_deref_mut() {
                for (&i, w) in s.indices.iter().zip(&s.weights) {
                    for k in 0..3 {
                        g[i as usize][k] += c * w[2] * dt[k];
                    }
                }
            }
            if let Some(hm) = hess.as_deref_mut() {
                for (a, (&i, wi)) in s.indices.iter().zip(&s.weights).enumerate() {
                    for (&j, wj) in s.indices[a..].iter().zip(&s.weights[a..]) {
                        if let Some(k) = hm.pattern.find(i, j) {
                            hm.blocks[k] += (c * wi[2] * wj[2]) * h;
                        }
                    }
                }
            }
        }
        energy
    }

    /// ⅓ ∫ x·(x_u × x_v) du dv over the limit surface (the enclosed volume when closed).
    pub fn volume(&self, x: &[Vec3]) -> f64 {
        (0..self.basis.num_points())
            .map(|q| {
                let p = self.basis.limit_stencil(q).apply(x);
                let (c, a, b) = (
                    Vector3::from(p.d[0]),
                    Vector3::from(p.d[1]),
                    Vector3::from(p.d[2]),
                );
                self.basis.quad_weight[q] * c.dot(&a.cross(&b)) / 3.0
            })
            .sum()
    }

    pub fn gravity(&self) -> Vec3 {
        self.gravity
    }

    /// Constant external force on each control point (gravity and dead loads).
    pub fn external_load(&self) -> Vec<Vec3> {
        self.external_gradient
            .iter()
            .map(|f| [-f[0], -f[1], -f[2]])
            .collect()
    }

    /// Consistent nodal loads of a force per unit rest length `per_length` (N/m) applied along
    /// the limit curve v = `v` (0 or 1) of `faces`.
    pub fn edge_load(&self, faces: &[usize], v: f64, per_length: Vec3) -> Vec<Vec3> {
        let surface = self.basis.surface();
        let rule = GaussLegendre::new(4)
            .expect("4 is a valid rule")
            .on_interval(0.0, 1.0);
        let x = &self.basis.control_points;
        let mut f = vec![[0.0; 3]; self.num_nodes()];
        for &face in faces {
            let uvs: Vec<[f64; 2]> = rule.iter().map(|&(u, _)| [u, v]).collect();
            let Ok(stencils) = surface.stencils(face, &uvs) else {
                continue;
            };
            for (s, &(_, w)) in stencils.iter().zip(&rule) {
                let ds = {
                    let t = s.apply(x).d[1];
                    (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt()
                };
                for (&i, wi) in s.indices.iter().zip(&s.weights) {
                    for c in 0..3 {
                        f[i as usize][c] += w * ds * wi[0] * per_length[c];
                    }
                }
            }
        }
        f
    }

    /// The follower pressure's share of Gauss point q: −p w/3 x·(x_u × x_v), its gradient and
    /// Hessian (the triple product is trilinear: ∂²/∂x∂x_u = −[x_v]×, ∂²/∂x∂x_v = [x_u]×,
    /// ∂²/∂x_u∂x_v = −[x]×).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn pressure_terms(
        &self,
        q: usize,
        x: &[Vec3],
        want_g: bool,
        want_h: bool,
        local: &[u16],
        n: usize,
        acc: &mut Accumulator,
        s: &mut FaceScratch,
    ) {
        let (idx, w) = self.basis.stencil(q);
        let mut d = [Vector3::zeros(); 3];
        for (&i, wi) in idx.iter().zip(w) {
            let p = Vector3::from(x[i as usize]);
            for k in 0..3 {
                d[k] += wi[k] * p;
            }
        }
        let [c, a, b] = d;
        let scale = -self.pressure * self.basis.quad_weight[q] / 3.0;
        acc.energy += scale * c.dot(&a.cross(&b));
        if want_g {
            let parts = [a.cross(&b), b.cross(&c), c.cross(&a)];
            for (&i, wi) in idx.iter().zip(w) {
                let g = wi[0] * parts[0] + wi[1] * parts[1] + wi[2] * parts[2];
                for k in 0..3 {
                    acc.grad[i as usize][k] += scale * g[k];
                }
            }
        }
        if want_h {
            let skew = |v: &Vector3<f64>| {
                Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)
            };
            let (sc, sa, sb) = (skew(&c), skew(&a), skew(&b));
            // B[k][l]: ∂²T/∂d_k∂d_l for d = (x, x_u, x_v)
            let z = Matrix3::zeros();
            let blocks = [[z, -sb, sa], [sb, z, -sc], [-sa, sc, z]];
            for ai in 0..idx.len() {
                let la = local[ai] as usize;
                for bi in ai..idx.len() {
                    let mut blk = Matrix3::zeros();
                    for k in 0..3 {
                        for l in 0..3 {
                            let f = w[ai][k] * w[bi][l];
                            if f != 0.0 && k != l {
                                blk += f * blocks[k][l];
                            }
                        }
                    }
                    let lb = local[bi] as usize;
                    s.local[la * n - la * (la + 1) / 2 + lb] += scale * blk;
                }
            }
        }
    }
}
