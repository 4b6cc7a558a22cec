//! A uniform grid of the sweep's boundary edges, for the winner fallback (the nearest
//! boundary edge of a whole NC when none is at P's rho-neighbours).
//!
//! Every directed edge that became a boundary edge (the mesh's boundary log) is listed
//! in every cell its bounding box meets; entries that stopped being boundary edges are
//! dropped when a search meets them. A search visits the cells ring by ring around P's
//! cell: after ring k, every edge not yet seen lies outside the block of cells within k
//! of P's cell, so it is at least k cell sizes from P. Once the best distance found is
//! below that bound (less a margin far above rounding), no unseen edge can be as near,
//! so the result is the minimum over all of the NC's boundary edges, exactly as a full
//! scan finds it. This holds for a true distance (`edge_distance = "segment"`); the
//! paper's formula and `strict_rho` keep the full scan.

use glam::DVec3;

/// A boundary edge a -> b with its slot 3 t + k in the mesh.
pub type Entry = (u32, u32, u32);

/// The grid (cells of at least rho, at most `max_cells` of them).
#[derive(Debug)]
pub struct EdgeGrid {
    origin: DVec3,
    /// Cell size.
    pub h: f64,
    dims: [i64; 3],
    /// Entries per cell, x fastest.
    pub cells: Vec<Vec<Entry>>,
    /// Log entries taken so far.
    fed: usize,
}

impl EdgeGrid {
    /// A grid over the bounding box of `p` with cells of size `rho`, made coarser until
    /// there are at most `max_cells`.
    pub fn new(p: &[DVec3], rho: f64, max_cells: usize) -> Self {
        let lo = p.iter().copied().fold(DVec3::INFINITY, DVec3::min);
        let hi = p.iter().copied().fold(DVec3::NEG_INFINITY, DVec3::max);
        let ext = (hi - lo).max(DVec3::ZERO);
        let mut h = rho;
        let dims = loop {
            let d = (ext / h).floor() + DVec3::ONE;
            let count = d.x * d.y * d.z;
            if count <= max_cells.max(1) as f64 {
                break [d.x as i64, d.y as i64, d.z as i64];
            }
            h *= (count / max_cells.max(1) as f64).cbrt().max(1.01);
        };
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        Self {
            origin: lo,
            h,
            dims,
            cells: vec![Vec::new(); n],
            fed: 0,
        }
    }

    /// Cell of a point, clamped to the grid.
    #[inline]
    pub fn cell(&self, x: DVec3) -> [i64; 3] {
        let c = ((x - self.origin) / self.h).floor();
        let clamp = |v: f64, d: i64| (v.max(0.0) as i64).min(d - 1);
        [
            clamp(c.x, self.dims[0]),
            clamp(c.y, self.dims[1]),
            clamp(c.z, self.dims[2]),
        ]
    }

    #[inline]
    fn index(&self, c: [i64; 3]) -> usize {
        ((c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]) as usize
    }

    /// Lists the log entries not taken yet that `current` accepts (those still boundary
    /// edges: one that becomes a boundary edge again is logged again) in the cells of
    /// their bounding boxes.
    pub fn feed(&mut self, p: &[DVec3], log: &[Entry], current: impl Fn(&Entry) -> bool) {
        for &e in &log[self.fed..] {
            if !current(&e) {
                continue;
            }
            let (pa, pb) = (p[e.0 as usize], p[e.1 as usize]);
            let (lo, hi) = (self.cell(pa.min(pb)), self.cell(pa.max(pb)));
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        let i = self.index([x, y, z]);
                        self.cells[i].push(e);
                    }
                }
            }
        }
        self.fed = log.len();
    }

    /// Pushes to `out` the index of every cell at Chebyshev distance exactly `k` from
    /// cell `c` (within the grid); returns whether the block within `k` of `c` covers
    /// the whole grid.
    pub fn ring(&self, c: [i64; 3], k: i64, out: &mut Vec<usize>) -> bool {
        let lo = |a: usize| (c[a] - k).max(0);
        let hi = |a: usize| (c[a] + k).min(self.dims[a] - 1);
        for y in lo(1)..=hi(1) {
            for x in lo(0)..=hi(0) {
                if (x - c[0]).abs() == k || (y - c[1]).abs() == k {
                    for z in lo(2)..=hi(2) {
                        out.push(self.index([x, y, z]));
                    }
                } else {
                    for z in [c[2] - k, c[2] + k] {
                        if (0..self.dims[2]).contains(&z) {
                            out.push(self.index([x, y, z]));
                        }
                    }
                }
            }
        }
        (0..3).all(|a| lo(a) == 0 && hi(a) == self.dims[a] - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rings_cover_every_cell_once_and_end_at_the_whole_grid() {
        // A 5 x 3 x 4 grid (cells of 1 over a box of 4.5 x 2.5 x 3.5).
        let p = [DVec3::ZERO, DVec3::new(4.5, 2.5, 3.5)];
        let g = EdgeGrid::new(&p, 1.0, 1000);
        assert_eq!(g.dims, [5, 3, 4]);
        for c in [[0, 0, 0], [2, 1, 2], [4, 2, 3], [1, 2, 0]] {
            let mut seen = vec![0u32; g.cells.len()];
            let mut ring = Vec::new();
            let mut k = 0;
            loop {
                ring.clear();
                let all = g.ring(c, k, &mut ring);
                for &i in &ring {
                    seen[i] += 1;
                    // Cell i is at Chebyshev distance k from c.
                    let (x, y, z) = (i as i64 % 5, i as i64 / 5 % 3, i as i64 / 15);
                    let d = (x - c[0]).abs().max((y - c[1]).abs()).max((z - c[2]).abs());
                    assert_eq!(d, k);
                }
                if all {
                    break;
                }
                k += 1;
                assert!(k < 10, "rings never cover the grid");
            }
            assert!(seen.iter().all(|&s| s == 1), "from {c:?}: {seen:?}");
        }
    }

    #[test]
    fn edges_are_listed_in_every_cell_their_box_meets_and_grids_stay_small() {
        let p = [
            DVec3::ZERO,
            DVec3::new(4.5, 2.5, 3.5),
            DVec3::new(0.5, 0.5, 0.5),
            DVec3::new(2.5, 1.5, 0.5),
        ];
        let mut g = EdgeGrid::new(&p, 1.0, 1000);
        g.feed(&p, &[(2, 3, 0), (3, 2, 1)], |e| e.2 == 0);
        let listed: Vec<usize> = (0..g.cells.len())
            .filter(|&i| !g.cells[i].is_empty())
            .collect();
        // Cells x 0..=2, y 0..=1, z 0 (the second entry is not current).
        assert_eq!(listed, vec![0, 1, 2, 5, 6, 7]);
        assert!(g.cells.iter().flatten().all(|e| e.2 == 0));
        // A cap on the cell count makes the cells larger.
        let small = EdgeGrid::new(&p, 0.01, 64);
        assert!(small.cells.len() <= 64 && small.h > 0.01);
    }
}
