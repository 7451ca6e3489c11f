//! The triangulated grid of Miguel et al. 2012: a rectangle of nx × ny cells in the x–y plane,
//! each cell split into two triangles along alternating diagonals (a checkerboard, so that the
//! mesh has no preferred shear direction), with the derived element lists every triangle model
//! needs: interior edges as dihedral hinges, and the spring rings.

use crate::Vec3;

/// How a hinge's edge lies in the grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeKind {
    /// Along a grid line (x or y).
    Axis,
    /// A cell diagonal.
    Diagonal,
}

/// An interior edge with its two triangles: nodes (x1, x2) on the edge, x3 opposite in the
/// first triangle, x4 in the second; `normal` the unit in-plane direction across the edge.
#[derive(Clone, Copy, Debug)]
pub struct Hinge {
    pub nodes: [u32; 4],
    pub kind: EdgeKind,
    pub normal: [f64; 2],
    pub length: f64,
    /// Rest area of the two triangles together, m².
    pub area: f64,
}

/// A spring of the Springs model with the rest area it stands for.
#[derive(Clone, Copy, Debug)]
pub struct Spring {
    pub nodes: [u32; 2],
    /// Rest direction (unit, in plane).
    pub dir: [f64; 2],
    pub length: f64,
    pub area: f64,
}

/// The grid.
#[derive(Clone, Debug)]
pub struct TriGrid {
    pub nx: usize,
    pub ny: usize,
    /// m
    pub length: f64,
    pub width: f64,
    /// Rest positions in the plane.
    pub rest: Vec<[f64; 2]>,
    /// Counter-clockwise triangles.
    pub triangles: Vec<[u32; 3]>,
}

impl TriGrid {
    /// [0, length] × [0, width] in nx × ny cells.
    pub fn rectangle(length: f64, width: f64, nx: usize, ny: usize) -> Self {
        let mut rest = Vec::with_capacity((nx + 1) * (ny + 1));
        for j in 0..=ny {
            for i in 0..=nx {
                rest.push([length * i as f64 / nx as f64, width * j as f64 / ny as f64]);
            }
        }
        let node = |i: usize, j: usize| (i + (nx + 1) * j) as u32;
        let mut triangles = Vec::with_capacity(2 * nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let (p00, p10, p01, p11) = (
                    node(i, j),
                    node(i + 1, j),
                    node(i, j + 1),
                    node(i + 1, j + 1),
                );
                if (i + j) % 2 == 0 {
                    triangles.push([p00, p10, p11]);
                    triangles.push([p00, p11, p01]);
                } else {
                    triangles.push([p00, p10, p01]);
                    triangles.push([p10, p11, p01]);
                }
            }
        }
        Self {
            nx,
            ny,
            length,
            width,
            rest,
            triangles,
        }
    }

    pub fn node(&self, i: usize, j: usize) -> usize {
        i + (self.nx + 1) * j
    }

    pub fn num_nodes(&self) -> usize {
        self.rest.len()
    }

    /// The rest positions as 3-D points (z = 0).
    pub fn positions(&self) -> Vec<Vec3> {
        self.rest.iter().map(|p| [p[0], p[1], 0.0]).collect()
    }

    /// Rest area of triangle `t`.
    pub fn area(&self, t: usize) -> f64 {
        let [a, b, c] = self.triangles[t].map(|n| self.rest[n as usize]);
        0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))
    }

    /// Every edge shared by two triangles.
    pub fn hinges(&self) -> Vec<Hinge> {
        use std::collections::BTreeMap;
        // (triangle, edge start, edge end, opposite node) for each side of an edge
        type Sides = Vec<(usize, u32, u32, u32)>;
        let mut edges: BTreeMap<(u32, u32), Sides> = BTreeMap::new();
        for (t, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
                edges
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push((t, a, b, c));
            }
        }
        let mut out = Vec::new();
        for sides in edges.values() {
            if let [(t1, a, b, c), (t2, _, _, d)] = sides[..] {
                let (pa, pb) = (self.rest[a as usize], self.rest[b as usize]);
                let (dx, dy) = (pb[0] - pa[0], pb[1] - pa[1]);
                let length = dx.hypot(dy);
                let axis = dx.abs() < 1e-12 * length || dy.abs() < 1e-12 * length;
                out.push(Hinge {
                    nodes: [a, b, c, d],
                    kind: if axis {
                        EdgeKind::Axis
                    } else {
                        EdgeKind::Diagonal
                    },
                    normal: [dy / length, -dx / length],
                    length,
                    area: self.area(t1) + self.area(t2),
                });
            }
        }
        out
    }

    /// Springs between nodes (i, j) and (i + di, j + dj); `area` is what each spring stands
    /// for: the cell area times `per_cell`, halved for springs along the boundary (they border
    /// one row of cells rather than two).
    fn springs(&self, di: isize, dj: isize, per_cell: f64) -> Vec<Spring> {
        let (nx, ny) = (self.nx as isize, self.ny as isize);
        let cell = self.length * self.width / (self.nx * self.ny) as f64;
        let mut out = Vec::new();
        for j in 0..=ny {
            for i in 0..=nx {
                let (k, l) = (i + di, j + dj);
                if k < 0 || k > nx || l < 0 || l > ny {
                    continue;
                }
                let (a, b) = (
                    self.node(i as usize, j as usize),
                    self.node(k as usize, l as usize),
                );
                let (pa, pb) = (self.rest[a], self.rest[b]);
                let (dx, dy) = (pb[0] - pa[0], pb[1] - pa[1]);
                let length = dx.hypot(dy);
                let on_edge = (dj == 0 && (j == 0 || j == ny)) || (di == 0 && (i == 0 || i == nx));
                let area = cell * per_cell * if on_edge { 0.5 } else { 1.0 };
                out.push(Spring {
                    nodes: [a as u32, b as u32],
                    dir: [dx / length, dy / length],
                    length,
                    area,
                });
            }
        }
        out
    }

    /// Ring-1 springs along the grid lines (stretch).
    pub fn stretch_springs(&self) -> Vec<Spring> {
        let mut s = self.springs(1, 0, 1.0);
        s.extend(self.springs(0, 1, 1.0));
        s
    }

    /// Both diagonals of every cell (shear); each stands for half its cell.
    pub fn shear_springs(&self) -> Vec<Spring> {
        let mut s = self.springs(1, 1, 0.5);
        s.extend(self.springs(-1, 1, 0.5));
        s
    }

    /// Ring-2 springs along the grid lines (bending); each stands for two cells' worth of
    /// length, so the ring covers the area once.
    pub fn bend_springs(&self) -> Vec<Spring> {
        let mut s = self.springs(2, 0, 1.0);
        s.extend(self.springs(0, 2, 1.0));
        s
    }

    /// Ring-2 diagonal springs (diagonal bending) in both directions, each standing for half a
    /// cell (the 2 × 2 blocks overlap, so each ring covers the area about once).
    pub fn diagonal_bend_springs(&self) -> Vec<Spring> {
        let mut s = self.springs(2, 2, 0.5);
        s.extend(self.springs(-2, 2, 0.5));
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_areas() {
        let g = TriGrid::rectangle(0.3, 0.2, 3, 2);
        assert_eq!(g.num_nodes(), 12);
        assert_eq!(g.triangles.len(), 12);
        let total: f64 = (0..12).map(|t| g.area(t)).sum();
        assert!((total - 0.06).abs() < 1e-15);
        assert!((0..12).all(|t| g.area(t) > 0.0), "counter-clockwise");
        // interior edges: one interior row of 3 horizontal edges, two interior columns of 2
        // vertical ones, and the 6 cell diagonals
        assert_eq!(g.hinges().len(), 3 + 2 * 2 + 6);
        // each stretch direction and the shear ring cover the area once
        let springs = g.stretch_springs();
        let along_x: f64 = springs
            .iter()
            .filter(|s| s.dir[1] == 0.0)
            .map(|s| s.area)
            .sum();
        let along_y: f64 = springs
            .iter()
            .filter(|s| s.dir[0] == 0.0)
            .map(|s| s.area)
            .sum();
        let shear: f64 = g.shear_springs().iter().map(|s| s.area).sum();
        for a in [along_x, along_y, shear] {
            assert!((a - 0.06).abs() < 1e-15, "{a}");
        }
    }
}
