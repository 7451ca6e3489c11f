//! A triangle model's total energy with exact gradient and Hessian ([`ClothModel`]).
//!
//! Elements, each an energy of its nodes differentiated by [`super::jet`]:
//! - **membrane triangle** (not `springs`): with (w_u, w_v) = F's columns along the rest warp
//!   and weft (F the triangle's deformation gradient), strains (E₁₁, E₂₂, 2E₁₂) =
//!   ((|w_u|² − 1)/2, (|w_v|² − 1)/2, w_u·w_v) (Green; `stvk-ds`, `xpbd`) or
//!   (|w_u| − 1, |w_v| − 1, w_u·w_v) (Baraff–Witkin; `soft-constraints`); energy A Σ W_i(ε_i),
//!   plus A C₀₁ ε₁ε₂ for `xpbd`;
//! - **hinge** (not `springs`): the signed dihedral angle θ at an interior edge, curvature
//!   κ = θ/h with h = (A₁ + A₂)/l the mean height of the two triangles, energy l h W(κ) (Miguel's
//!   discrete-shells metric with h three times their h₀, so that W's stiffness is the plate
//!   rigidity: a cylinder along a grid line of this mesh has exactly κ = θ/h);
//!   grid-line hinges take c² W_warp + s² W_weft (c = cosine between the hinge's curvature
//!   direction and the warp), diagonal hinges W_diag;
//! - **spring** (`springs`): ε = l/l₀ − 1, energy A W(ε), A the rest area the spring stands
//!   for ([`super::grid`]); grid-line springs mix warp and weft by c² and s² as hinges do.
//!
//! Gravity acts on the lumped mass ρA/3 per triangle corner.

use super::grid::{EdgeKind, TriGrid};
use super::jet::{cross, dot, point, pull_back, sub, vector, Jet};
use super::params::{TriKind, TriMaterial};
use crate::material::OutOfDomain;
use crate::model::{BlockMatrix, BlockPattern, ClothModel, Want};
use crate::Vec3;
use std::sync::Arc;

/// A membrane triangle: nodes, rest area and the weights that give w_u, w_v from the nodes.
#[derive(Clone, Copy, Debug)]
pub(super) struct Triangle {
    pub(super) nodes: [u32; 3],
    pub(super) area: f64,
    pub(super) cu: [f64; 3],
    pub(super) cv: [f64; 3],
}

/// Which stiffness (by component index) an element uses, mixed by the squared direction
/// cosine with the warp.
#[derive(Clone, Copy, Debug)]
pub(super) struct Mix {
    pub(super) warp: usize,
    pub(super) weft: usize,
    pub(super) c2: f64,
}

#[derive(Clone, Copy, Debug)]
pub(super) struct HingeEl {
    pub(super) nodes: [u32; 4],
    pub(super) length: f64,
    pub(super) height: f64,
    pub(super) mix: Mix,
}

#[derive(Clone, Copy, Debug)]
struct SpringEl {
    nodes: [u32; 2],
    length: f64,
    area: f64,
    mix: Mix,
}

/// A triangle model on a [`TriGrid`].
pub struct TriModel {
    pub grid: TriGrid,
    pub material: TriMaterial,
    /// Warp direction in the rest plane, radians from the x axis.
    pub warp_angle: f64,
    pub(super) triangles: Vec<Triangle>,
    pub(super) hinges: Vec<HingeEl>,
    springs: Vec<SpringEl>,
    pub(super) mass: Vec<f64>,
    pub(super) gravity: Vec3,
    pattern: Arc<BlockPattern>,
}

impl TriModel {
    /// The model of `material` on `grid` with the warp at `warp_angle` (radians from x).
    pub fn new(grid: TriGrid, material: TriMaterial, warp_angle: f64) -> Self {
        let (s, c) = warp_angle.sin_cos();
        let frame = |p: [f64; 2]| [c * p[0] + s * p[1], -s * p[0] + c * p[1]];
        let cos2 = |d: [f64; 2]| (c * d[0] + s * d[1]).powi(2);
        let membrane = material.kind != TriKind::Springs;
        let mut triangles = Vec::new();
        let mut mass = vec![0.0; grid.num_nodes()];
        for (t, nodes) in grid.triangles.iter().enumerate() {
            let [a, b, cc] = nodes.map(|n| frame(grid.rest[n as usize]));
            let (d1, d2) = ([b[0] - a[0], b[1] - a[1]], [cc[0] - a[0], cc[1] - a[1]]);
            let det = d1[0] * d2[1] - d2[0] * d1[1];
            // Dm⁻¹ = [[r00, r01], [r10, r11]] with Dm = [d1 d2] (columns)
            let (r00, r01, r10, r11) = (d2[1] / det, -d2[0] / det, -d1[1] / det, d1[0] / det);
            let area = grid.area(t);
            for &n in nodes {
                mass[n as usize] += material.areal_density * area / 3.0;
            }
            if membrane {
                triangles.push(Triangle {
                    nodes: *nodes,
                    area,
                    cu: [-r00 - r10, r00, r10],
                    cv: [-r01 - r11, r01, r11],
                });
            }
        }
        let hinges = if membrane {
            grid.hinges()
                .iter()
                .map(|h| HingeEl {
                    nodes: h.nodes,
                    length: h.length,
                    height: h.area / h.length,
                    mix: match h.kind {
                        EdgeKind::Axis => Mix {
                            warp: 3,
                            weft: 4,
                            c2: cos2(h.normal),
                        },
                        EdgeKind::Diagonal => Mix {
                            warp: 5,
                            weft: 5,
                            c2: 1.0,
                        },
                    },
                })
                .collect()
        } else {
            Vec::new()
        };
        let mut springs = Vec::new();
        if !membrane {
            let mut add = |list: Vec<super::grid::Spring>, warp: usize, weft: usize, axis: bool| {
                springs.extend(list.iter().map(|s| SpringEl {
                    nodes: s.nodes,
                    length: s.length,
                    area: s.area,
                    mix: Mix {
                        warp,
                        weft,
                        c2: if axis { cos2(s.dir) } else { 1.0 },
                    },
                }))
            };
            add(grid.stretch_springs(), 0, 1, true);
            add(grid.shear_springs(), 2, 2, false);
            add(grid.bend_springs(), 3, 4, true);
            add(grid.diagonal_bend_springs(), 5, 5, false);
        }
        let pattern = Arc::new(Self::pattern_of(&grid, &triangles, &hinges, &springs));
        Self {
            grid,
            material,
            warp_angle,
            triangles,
            hinges,
            springs,
            mass,
            gravity: [0.0; 3],
            pattern,
        }
    }

    fn pattern_of(
        grid: &TriGrid,
        triangles: &[Triangle],
        hinges: &[HingeEl],
        springs: &[SpringEl],
    ) -> BlockPattern {
        let mut lists: Vec<&[u32]> = Vec::new();
        lists.extend(triangles.iter().map(|t| &t.nodes[..]));
        lists.extend(hinges.iter().map(|h| &h.nodes[..]));
        lists.extend(springs.iter().map(|s| &s.nodes[..]));
        BlockPattern::from_elements(grid.num_nodes(), lists)
    }

    /// Gravity, m/s² (off by default).
    pub fn set_gravity(&mut self, g: Vec3) {
        self.gravity = g;
    }

    /// Elements in the model: (triangles, hinges, springs).
    pub fn counts(&self) -> (usize, usize, usize) {
        (self.triangles.len(), self.hinges.len(), self.springs.len())
    }

    /// The energy density W, W′, W″ of component mix `m` at strain `e`.
    fn density(&self, m: Mix, e: f64) -> (f64, f64, f64) {
        let a = self.material.curves[m.warp].density(e);
        if m.warp == m.weft {
            return a;
        }
        let b = self.material.curves[m.weft].density(e);
        let (c2, s2) = (m.c2, 1.0 - m.c2);
        (
            c2 * a.0 + s2 * b.0,
            c2 * a.1 + s2 * b.1,
            c2 * a.2 + s2 * b.2,
        )
    }

    /// The triangle's w_u, w_v (as plain vectors) and the map from its nodes to them.
    fn triangle_vectors(t: &Triangle, x: &[Vec3]) -> ([Vec3; 2], [[f64; 3]; 2]) {
        let mut w = [[0.0; 3]; 2];
        for (k, &n) in t.nodes.iter().enumerate() {
            for c in 0..3 {
                w[0][c] += t.cu[k] * x[n as usize][c];
                w[1][c] += t.cv[k] * x[n as usize][c];
            }
        }
        (w, [t.cu, t.cv])
    }

    /// The membrane energy as a function of (w_u, w_v) (M = 6) or of nothing (M = 0).
    fn triangle_energy<const M: usize>(&self, t: &Triangle, w: [Vec3; 2]) -> Jet<M> {
        let wu = vector::<M>(0, w[0]);
        let wv = vector::<M>(1, w[1]);
        let uu = dot(&wu, &wu);
        let vv = dot(&wv, &wv);
        let e = match self.material.kind {
            TriKind::SoftConstraints => [
                uu.sqrt() + Jet::constant(-1.0),
                vv.sqrt() + Jet::constant(-1.0),
            ],
            _ => [
                (uu + Jet::constant(-1.0)).scale(0.5),
                (vv + Jet::constant(-1.0)).scale(0.5),
            ],
        };
        let es = dot(&wu, &wv);
        let curves = &self.material.curves;
        let mut energy = Jet::constant(0.0);
        for (k, ek) in [e[0], e[1], es].iter().enumerate() {
            let (w, dw, ddw) = curves[k].density(ek.v);
            energy = energy + ek.map(w, dw, ddw);
        }
        if self.material.coupling != 0.0 {
            energy = energy + (e[0] * e[1]).scale(self.material.coupling);
        }
        energy.scale(t.area)
    }

    /// The hinge's edge e = x₂ − x₁ and a = x₃ − x₁, b = x₄ − x₁ (the angle is translation-free)
    /// and the map from its nodes to them.
    fn hinge_vectors(h: &HingeEl, x: &[Vec3]) -> ([Vec3; 3], [[f64; 4]; 3]) {
        let p = h.nodes.map(|n| x[n as usize]);
        let d = |k: usize| [0, 1, 2].map(|c| p[k][c] - p[0][c]);
        (
            [d(1), d(2), d(3)],
            [
                [-1.0, 1.0, 0.0, 0.0],
                [-1.0, 0.0, 1.0, 0.0],
                [-1.0, 0.0, 0.0, 1.0],
            ],
        )
    }

    /// The hinge energy as a function of (e, a, b) (M = 9) or of nothing (M = 0).
    fn hinge_energy<const M: usize>(&self, h: &HingeEl, v: [Vec3; 3]) -> Jet<M> {
        let e = vector::<M>(0, v[0]);
        let a = vector::<M>(1, v[1]);
        let b = vector::<M>(2, v[2]);
        let n1 = cross(&e, &a);
        let n2 = cross(&b, &e);
        // (n₁ × n₂)·e/|e| with the current |e|: the rest length would scale the angle by the
        // edge's stretch
        let sin = dot(&cross(&n1, &n2), &e) * dot(&e, &e).sqrt().recip();
        let theta = sin.atan2(&dot(&n1, &n2));
        let kappa = theta.scale(1.0 / h.height);
        let (w, dw, ddw) = self.density(h.mix, kappa.v);
        kappa.map(w, dw, ddw).scale(h.length * h.height)
    }

    fn spring_energy<const N: usize>(&self, s: &SpringEl, x: &[Vec3]) -> Jet<N> {
        let p: Vec<_> = (0..2)
            .map(|k| point::<N>(k, x[s.nodes[k] as usize]))
            .collect();
        let d = sub(&p[1], &p[0]);
        let eps = dot(&d, &d).sqrt().scale(1.0 / s.length) + Jet::constant(-1.0);
        let (w, dw, ddw) = self.density(s.mix, eps.v);
        eps.map(w, dw, ddw).scale(s.area)
    }
}

/// Adds an element's jet (local nodes `nodes`) into the global gradient and Hessian.
fn scatter<const N: usize>(
    nodes: &[u32],
    jet: &Jet<N>,
    grad: &mut Option<&mut [Vec3]>,
    hess: &mut Option<&mut BlockMatrix>,
) {
    if let Some(g) = grad.as_deref_mut() {
        for (a, &n) in nodes.iter().enumerate() {
            for c in 0..3 {
                g[n as usize][c] += jet.g[3 * a + c];
            }
        }
    }
    if let Some(h) = hess.as_deref_mut() {
        for (a, &i) in nodes.iter().enumerate() {
            for (b, &j) in nodes.iter().enumerate() {
                if i > j {
                    continue;
                }
                let k = h
                    .pattern
                    .find(i, j)
                    .expect("element pairs are in the pattern");
                let blk = &mut h.blocks[k];
                for r in 0..3 {
                    for c in 0..3 {
                        blk[(r, c)] += jet.h[3 * a + r][3 * b + c];
                    }
                }
            }
        }
    }
}

impl ClothModel for TriModel {
    fn pattern(&self) -> &Arc<BlockPattern> {
        &self.pattern
    }

    fn num_nodes(&self) -> usize {
        self.grid.num_nodes()
    }

    fn assemble(
        &self,
        x: &[Vec3],
        want: Want,
        grad: Option<&mut [Vec3]>,
        hess: Option<&mut BlockMatrix>,
    ) -> Result<f64, OutOfDomain> {
        let mut grad = if want == Want::Energy { None } else { grad };
        let mut hess = if want.hessian() { hess } else { None };
        if let Some(g) = grad.as_deref_mut() {
            g.iter_mut().for_each(|v| *v = [0.0; 3]);
        }
        if let Some(h) = hess.as_deref_mut() {
            h.fill_zero();
        }
        let mut energy = 0.0;
        if want == Want::Energy {
            // plain arithmetic: jets over no variables
            for t in &self.triangles {
                energy += self
                    .triangle_energy::<0>(t, Self::triangle_vectors(t, x).0)
                    .v;
            }
            for h in &self.hinges {
                energy += self.hinge_energy::<0>(h, Self::hinge_vectors(h, x).0).v;
            }
            energy += self
                .springs
                .iter()
                .map(|s| self.spring_energy::<0>(s, x).v)
                .sum::<f64>();
        } else {
            for t in &self.triangles {
                let (w, map) = Self::triangle_vectors(t, x);
                let j: Jet<9> = pull_back(&self.triangle_energy::<6>(t, w), &map);
                energy += j.v;
                scatter(&t.nodes, &j, &mut grad, &mut hess);
            }
            for h in &self.hinges {
                let (v, map) = Self::hinge_vectors(h, x);
                let j: Jet<12> = pull_back(&self.hinge_energy::<9>(h, v), &map);
                energy += j.v;
                scatter(&h.nodes, &j, &mut grad, &mut hess);
            }
            for s in &self.springs {
                let j = self.spring_energy::<6>(s, x);
                energy += j.v;
                scatter(&s.nodes, &j, &mut grad, &mut hess);
            }
        }
        for (i, p) in x.iter().enumerate() {
            let f = self.mass[i];
            for c in 0..3 {
                energy -= f * self.gravity[c] * p[c];
            }
            if let Some(g) = grad.as_deref_mut() {
                for c in 0..3 {
                    g[i][c] -= f * self.gravity[c];
                }
            }
        }
        if !energy.is_finite() {
            return Err(OutOfDomain {
                strain: [f64::NAN; 3],
            });
        }
        Ok(energy)
    }

    fn external_load(&self) -> Vec<Vec3> {
        self.mass
            .iter()
            .map(|m| self.gravity.map(|g| m * g))
            .collect()
    }

    fn lumped_mass(&self) -> Vec<f64> {
        let rho = self.material.areal_density;
        if rho > 0.0 {
            self.mass.clone()
        } else {
            // unit density as a metric
            let mut m = vec![0.0; self.num_nodes()];
            for t in 0..self.grid.triangles.len() {
                for &n in &self.grid.triangles[t] {
                    m[n as usize] += self.grid.area(t) / 3.0;
                }
            }
            m
        }
    }
}
