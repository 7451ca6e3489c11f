//! The face loop of assembly (Clyde et al. 2017 §3): faces in fixed parallel groups, each Gauss
//! point's y-terms expanded through its limit stencil into the group's gradient and dense face
//! blocks, and the groups summed in order (see [`super`]'s module docs).

use super::{BlockMatrix, ShellModel, Want};
use crate::material::OutOfDomain;
use crate::shell::{kinematic_vector, YMat, YVec};
use crate::Vec3;
use nalgebra::Matrix3;

/// Number of fixed face groups assembled in parallel (fixed so that sums are reproducible).
pub const CHUNKS: usize = 8;

/// Per-group partial sums.
pub(super) struct Accumulator {
    pub energy: f64,
    pub grad: Vec<Vec3>,
    pub blocks: Vec<Matrix3<f64>>,
}

/// Reused buffers of one face's Hessian.
#[derive(Default)]
pub(super) struct FaceScratch {
    /// R_a = Σ_k W_ak H_k· per stencil node a, as 5 column-major 3 × 3 blocks
    pub r: Vec<[f64; 45]>,
    pub local: Vec<Matrix3<f64>>,
}

impl ShellModel {
    /// Assembles the energy and, as asked, the gradient (over all nodes, into `grad`) and the
    /// Hessian (into `hess`). Gravity and dead loads are included.
    ///
    /// Faces are processed in [`CHUNKS`] fixed contiguous groups in parallel, each group
    /// accumulating into its own arrays, which are then summed in group order: the result does
    /// not depend on the number of threads. Within a face, Gauss-point Hessians are summed into
    /// a dense face block first and scattered once.
    pub fn assemble(
        &self,
        x: &[Vec3],
        want: Want,
        grad: Option<&mut [Vec3]>,
        hess: Option<&mut BlockMatrix>,
    ) -> Result<f64, OutOfDomain> {
        use rayon::prelude::*;
        let nf = self.basis.num_faces;
        let chunks = CHUNKS.min(nf.max(1));
        let nn = self.num_nodes();
        let nb = self.pattern.num_blocks();
        let want_g = grad.is_some() && want != Want::Energy;
        let want_h = hess.is_some() && want.hessian();
        let parts: Vec<Result<Accumulator, OutOfDomain>> = (0..chunks)
            .into_par_iter()
            .map(|c| {
                let faces = c * nf / chunks..(c + 1) * nf / chunks;
                let mut acc = Accumulator {
                    energy: 0.0,
                    grad: if want_g {
                        vec![[0.0; 3]; nn]
                    } else {
                        Vec::new()
                    },
                    blocks: if want_h {
                        vec![Matrix3::zeros(); nb]
                    } else {
                        Vec::new()
                    },
                };
                self.faces_dispatch(faces, x, want, &mut acc)?;
                Ok(acc)
            })
            .collect();
        let mut energy: f64 = self
            .external_gradient
            .iter()
            .zip(x)
            .map(|(f, p)| f[0] * p[0] + f[1] * p[1] + f[2] * p[2])
            .sum();
        let mut grad = grad;
        let mut hess = hess;
        if let Some(g) = grad.as_deref_mut() {
            g.copy_from_slice(&self.external_gradient);
        }
        if let Some(h) = hess.as_deref_mut() {
            h.fill_zero();
        }
        energy += self.edge_moment_terms(
            x,
            if want_g { grad.as_deref_mut() } else { None },
            if want_h { hess.as_deref_mut() } else { None },
        );
        for part in parts {
            let part = part?;
            energy += part.energy;
            if let (Some(g), true) = (grad.as_deref_mut(), want_g) {
                for (a, b) in g.iter_mut().zip(&part.grad) {
                    for k in 0..3 {
                        a[k] += b[k];
                    }
                }
            }
            if let (Some(h), true) = (hess.as_deref_mut(), want_h) {
                for (a, b) in h.blocks.iter_mut().zip(&part.blocks) {
                    *a += b;
                }
            }
        }
        Ok(energy)
    }

    /// Adds the terms of `faces` to `acc`, with the face loop compiled for AVX2 + FMA when the
    /// CPU has them (checked at run time; the same operations in the same order, so the same
    /// results, about 1.4× faster on the Hessian) and for baseline x86-64 otherwise.
    fn faces_dispatch(
        &self,
        faces: std::ops::Range<usize>,
        x: &[Vec3],
        want: Want,
        acc: &mut Accumulator,
    ) -> Result<(), OutOfDomain> {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                // SAFETY: the CPU has the features `faces_avx2` was compiled for
                return unsafe { self.faces_avx2(faces, x, want, acc) };
            }
        }
        self.faces(faces, x, want, acc)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn faces_avx2(
        &self,
        faces: std::ops::Range<usize>,
        x: &[Vec3],
        want: Want,
        acc: &mut Accumulator,
    ) -> Result<(), OutOfDomain> {
        self.faces(faces, x, want, acc)
    }

    #[inline(always)]
    fn faces(
        &self,
        faces: std::ops::Range<usize>,
        x: &[Vec3],
        want: Want,
        acc: &mut Accumulator,
    ) -> Result<(), OutOfDomain> {
        let mut scratch = FaceScratch::default();
        for face in faces {
            self.face_terms(face, x, want, acc, &mut scratch)?;
        }
        Ok(())
    }

    /// Adds one face's energy, gradient and Hessian to `acc`.
    #[inline(always)]
    fn face_terms(
        &self,
        face: usize,
        x: &[Vec3],
        want: Want,
        acc: &mut Accumulator,
        s: &mut FaceScratch,
    ) -> Result<(), OutOfDomain> {
        let npf = self.basis.points_per_face;
        let nodes = &self.face_nodes[face];
        let n = nodes.len();
        let tri = n * (n + 1) / 2;
        let want_h = want.hessian() && !acc.blocks.is_empty();
        let want_g = want != Want::Energy && !acc.grad.is_empty();
        if want_h {
            s.local.clear();
            s.local.resize(tri, Matrix3::zeros());
        }
        for q in face * npf..(face + 1) * npf {
            let (idx, w) = self.basis.stencil(q);
            let off = self.basis.stencils.offsets[q] as usize;
            let local = &self.local_index[off..off + idx.len()];
            let mut d = [[0.0; 3]; 6];
            for (&i, wi) in idx.iter().zip(w) {
                let p = x[i as usize];
                for k in 1..6 {
                    for c in 0..3 {
                        d[k][c] += wi[k] * p[c];
                    }
                }
            }
            let y = kinematic_vector(&d);
            let (e, gy, hy) = self.point_terms(q, &y, want)?;
            acc.energy += e;
            if self.pressure != 0.0 {
                self.pressure_terms(q, x, want_g, want_h, local, n, acc, s);
            }
            self.scatter(idx, w, local, n, &gy, hy, want, acc, s);
        }
        self.centre_terms(face, x, want, acc, s)?;
        if want_h {
            for (k, blk) in self.face_blocks[face].iter().zip(&s.local) {
                acc.blocks[*k as usize] += blk;
            }
        }
        Ok(())
    }

    /// Adds a point's y-gradient and y-Hessian, expanded through its stencil (`local`: the
    /// entries' positions in the face's `n` nodes), to the accumulator and the face block.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn scatter(
        &self,
        idx: &[u32],
        w: &[[f64; 6]],
        local: &[u16],
        n: usize,
        gy: &YVec,
        hy: Option<YMat>,
        want: Want,
        acc: &mut Accumulator,
        s: &mut FaceScratch,
    ) {
        let want_h = want.hessian() && !acc.blocks.is_empty();
        let want_g = want != Want::Energy && !acc.grad.is_empty();
        if want_g {
            for (&i, wi) in idx.iter().zip(w) {
                for k in 0..5 {
                    for c in 0..3 {
                        acc.grad[i as usize][c] += wi[k + 1] * gy[3 * k + c];
                    }
                }
            }
        }
        if let (true, Some(hy)) = (want_h, hy) {
            let m = idx.len();
            s.r.clear();
            s.r.resize(m, [0.0; 45]);
            // R_al = Σ_k W_ak H_kl  (3 × 3 blocks)
            // row k of 3 × 3 blocks of H_y, flattened: ht[k][9l + 3j + i] = H_y[3k + i, 3l + j]
            let mut ht = [[0.0f64; 45]; 5];
            for (k, row) in ht.iter_mut().enumerate() {
                for l in 0..5 {
                    for j in 0..3 {
                        for i in 0..3 {
                            row[9 * l + 3 * j + i] = hy[(3 * k + i, 3 * l + j)];
                        }
                    }
                }
            }
            // R_a = Σ_k W_ak H_k· : five length-45 multiply-adds per node
            for a in 0..m {
                let mut r = [0.0f64; 45];
                for k in 0..5 {
                    let c = w[a][k + 1];
                    for (x, h) in r.iter_mut().zip(&ht[k]) {
                        *x += c * h;
                    }
                }
                s.r[a] = r;
            }
            // H_ab = Σ_l R_al W_bl, into the face's packed upper triangle
            for a in 0..m {
                let la = local[a] as usize;
                let ra = &s.r[a];
                for b in a..m {
                    let mut blk = [0.0f64; 9];
                    for l in 0..5 {
                        let c = w[b][l + 1];
                        for (x, r) in blk.iter_mut().zip(&ra[9 * l..9 * l + 9]) {
                            *x += c * r;
                        }
                    }
                    let lb = local[b] as usize;
                    // stencil and face node lists are both sorted, so la ≤ lb
                    let dst = &mut s.local[la * n - la * (la + 1) / 2 + lb];
                    for (x, v) in dst.as_mut_slice().iter_mut().zip(&blk) {
                        *x += v;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::OrthotropicStvk;
    use crate::mesh::rectangular_grid;
    use crate::subdiv::BasisOptions;
    use crate::subdiv::LimitBasis;
    use std::sync::Arc;

    /// The AVX2 + FMA build of the face loop gives the baseline build's numbers bit for bit
    /// (no contraction into fused multiply-adds, no reordering).
    #[test]
    fn vectorised_face_loop_matches_the_baseline_bit_for_bit() {
        #[cfg(target_arch = "x86_64")]
        {
            if !(std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma"))
            {
                return;
            }
            let law = OrthotropicStvk {
                a11: 2.0e8,
                a22: 1.2e8,
                a12: 2.0e7,
                g12: 4.0e6,
            };
            let mesh = rectangular_grid(0.05, 0.075, 4, 6);
            let basis = LimitBasis::new(&mesh, BasisOptions::default()).unwrap();
            let model = ShellModel::new(
                basis,
                crate::material::warp_direction(30.0),
                Arc::new(law),
                1.8e-4,
                0.1,
            )
            .unwrap();
            let x: Vec<Vec3> = model
                .basis
                .control_points
                .iter()
                .map(|p| [p[0] * 0.98, p[1] * 1.07, 2e-3 * (60.0 * p[0]).sin()])
                .collect();
            let nf = model.basis.num_faces;
            let fresh = || Accumulator {
                energy: 0.0,
                grad: vec![[0.0; 3]; model.num_nodes()],
                blocks: vec![Matrix3::zeros(); model.pattern.num_blocks()],
            };
            let (mut plain, mut fast) = (fresh(), fresh());
            model.faces(0..nf, &x, Want::Hessian, &mut plain).unwrap();
            // SAFETY: the features were detected above
            unsafe { model.faces_avx2(0..nf, &x, Want::Hessian, &mut fast) }.unwrap();
            assert!(plain.energy != 0.0);
            assert_eq!(plain.energy.to_bits(), fast.energy.to_bits());
            assert_eq!(plain.grad, fast.grad);
            assert_eq!(plain.blocks, fast.blocks);
        }
    }
}
