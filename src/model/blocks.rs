//! The sparse Hessian's storage: 3 × 3 blocks on the node pairs (i ≤ j) that share a Gauss
//! point, a pattern built once per mesh.

use crate::subdiv::LimitBasis;
use crate::Vec3;
use nalgebra::{Matrix3, Vector3};
use std::sync::Arc;

/// Upper-triangular node-pair pattern in compressed rows: row i lists the nodes j ≥ i that share
/// a Gauss point with i.
#[derive(Clone, Debug)]
pub struct BlockPattern {
    pub num_nodes: usize,
    pub row_ptr: Vec<usize>,
    pub col: Vec<u32>,
}

impl BlockPattern {
    /// Pattern of every pair of nodes within one face's stencils.
    pub fn from_basis(basis: &LimitBasis) -> Self {
        let npf = basis.points_per_face;
        let faces: Vec<Vec<u32>> = (0..basis.num_faces)
            .map(|face| {
                let mut nodes: Vec<u32> = Vec::new();
                for q in face * npf..(face + 1) * npf {
                    nodes.extend_from_slice(basis.stencil(q).0);
                }
                nodes
            })
            .collect();
        Self::from_elements(basis.control_points.len(), faces.iter().map(|f| &f[..]))
    }

    /// Pattern of every pair of nodes within one element (node lists may repeat nodes).
    pub fn from_elements<'a>(n: usize, elements: impl IntoIterator<Item = &'a [u32]>) -> Self {
        let mut rows: Vec<Vec<u32>> = vec![Vec::new(); n];
        let mut nodes: Vec<u32> = Vec::new();
        for element in elements {
            nodes.clear();
            nodes.extend_from_slice(element);
            nodes.sort_unstable();
            nodes.dedup();
            for (a, &i) in nodes.iter().enumerate() {
                rows[i as usize].extend_from_slice(&nodes[a..]);
            }
        }
        let mut row_ptr = vec![0];
        let mut col = Vec::new();
        for mut r in rows {
            r.sort_unstable();
            r.dedup();
            col.extend(r);
            row_ptr.push(col.len());
        }
        Self {
            num_nodes: n,
            row_ptr,
            col,
        }
    }

    /// Index of block (i, j), i ≤ j.
    pub fn find(&self, i: u32, j: u32) -> Option<usize> {
        let r = self.row_ptr[i as usize]..self.row_ptr[i as usize + 1];
        self.col[r.clone()]
            .binary_search(&j)
            .ok()
            .map(|k| r.start + k)
    }

    pub fn num_blocks(&self) -> usize {
        self.col.len()
    }
}

/// Symmetric matrix of 3 × 3 blocks on a [`BlockPattern`] (upper triangle stored).
#[derive(Clone, Debug)]
pub struct BlockMatrix {
    pub pattern: Arc<BlockPattern>,
    pub blocks: Vec<Matrix3<f64>>,
}

impl BlockMatrix {
    pub fn zeros(pattern: Arc<BlockPattern>) -> Self {
        let blocks = vec![Matrix3::zeros(); pattern.num_blocks()];
        Self { pattern, blocks }
    }

    pub fn fill_zero(&mut self) {
        self.blocks.iter_mut().for_each(|b| *b = Matrix3::zeros());
    }

    /// y = A x over all nodes.
    pub fn mul(&self, x: &[Vec3], y: &mut [Vec3]) {
        y.iter_mut().for_each(|v| *v = [0.0; 3]);
        let p = &self.pattern;
        for i in 0..p.num_nodes {
            for k in p.row_ptr[i]..p.row_ptr[i + 1] {
                let j = p.col[k] as usize;
                let b = &self.blocks[k];
                let xj = Vector3::from(x[j]);
                let yi = b * xj;
                for c in 0..3 {
                    y[i][c] += yi[c];
                }
                if j != i {
                    let yj = b.transpose() * Vector3::from(x[i]);
                    for c in 0..3 {
                        y[j][c] += yj[c];
                    }
                }
            }
        }
    }
}
