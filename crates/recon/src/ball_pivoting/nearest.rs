//! The nearest other point of every point, from a dense uniform grid: the mean spacing
//! and the orientation check of the input preparation need exactly the rows of
//! `knn_self_table(pos, 1, true)`, which a grid gives for a fraction of a tree's cost.

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::{GeomError, PointIndex};

/// At most this many cells per point (the grid's side grows until it fits).
const MAX_CELLS_PER_POINT: f64 = 32.0;
/// A block holding more candidates than this sends its point to the k-d tree (bounds
/// the scan on clustered input).
const MAX_SCAN: usize = 1024;
/// Blocks of `(2r + 1)^3` cells tried, `r` from 1 to this, before the k-d tree.
const MAX_RING: i64 = 3;

/// The nearest other point of every point of `pos` (at least two points; an exact
/// duplicate is a nearest point at distance 0): `(index, squared distance)`, the lowest
/// index among equidistant ones, the squared distance as
/// `(pos[i] - pos[j]).length_squared()`. Exactly the rows of
/// `knn_self_table(pos, 1, true)`.
///
/// A point is settled by the block of cells around its own when the best candidate
/// there is closer than any point outside the block can be; the rare others (isolated
/// or crowded points) are queried on a k-d tree. Each row depends only on `pos`, so
/// the result is the same at any thread count.
pub(crate) fn nearest_others(pos: &[DVec3]) -> Result<Vec<(u32, f64)>, GeomError> {
    let unresolved = (u32::MAX, f64::INFINITY);
    let mut out = vec![unresolved; pos.len()];
    if let Some(g) = Grid::new(pos) {
        let rows: Vec<(u32, f64)> = (0..g.ids.len())
            .into_par_iter()
            .with_min_len(1024)
            .map(|k| g.nearest(k))
            .collect();
        for (&id, r) in g.ids.iter().zip(rows) {
            out[id as usize] = r;
        }
    }
    let rest: Vec<usize> = (0..pos.len()).filter(|&i| out[i].0 == u32::MAX).collect();
    if !rest.is_empty() {
        let index = PointIndex::new(pos)?;
        for i in rest {
            // The two nearest by (distance, index), `i` itself among them unless
            // duplicates of it have lower indices: the first other one is the answer.
            let nb = index.knn(pos[i], 2)?;
            if let Some(o) = nb.iter().find(|nb| nb.index as usize != i) {
                out[i] = (o.index, o.dist2);
            }
        }
    }
    Ok(out)
}

/// Points sorted into a dense grid of cubes, x fastest, then by index.
struct Grid {
    lo: DVec3,
    side: f64,
    inv: f64,
    dims: [i64; 3],
    /// Cell `c` holds the sorted points `start[c]..start[c + 1]`.
    start: Vec<u32>,
    /// Sorted positions and their indices.
    pts: Vec<DVec3>,
    ids: Vec<u32>,
    /// Absolute rounding slack of the cell bounds against the points placed in them.
    slack: f64,
}

impl Grid {
    /// The grid, or `None` (every point to the k-d tree) when no usable cell size
    /// comes out. The side is a first guess of the spacing from the bounding box (as
    /// if the points covered its faces evenly), grown until there are at most
    /// [`MAX_CELLS_PER_POINT`] cells per point.
    fn new(pos: &[DVec3]) -> Option<Self> {
        let n = pos.len();
        if n < 2 || n >= u32::MAX as usize {
            return None;
        }
        let (lo, hi) = pos.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(a, b), &p| (a.min(p), b.max(p)),
        );
        let e = hi - lo;
        let mut side = ((e.x * e.y + e.y * e.z + e.z * e.x) / n as f64).sqrt();
        if !(side.is_finite() && side > 0.0) {
            return None;
        }
        let max_cells = MAX_CELLS_PER_POINT * n as f64 + 64.0;
        let cells = |s: f64| ((e / s).floor() + 1.0).element_product();
        while cells(side) > max_cells {
            side *= 1.25;
        }
        let inv = 1.0 / side;
        let d = (e * inv).to_array().map(|x| x as i64 + 1);
        let ncell = (d[0] * d[1] * d[2]) as usize;
        let cell = |p: DVec3| -> usize {
            let c = ((p - lo) * inv).to_array();
            let x = (c[0] as i64).min(d[0] - 1);
            let y = (c[1] as i64).min(d[1] - 1);
            let z = (c[2] as i64).min(d[2] - 1);
            ((z * d[1] + y) * d[0] + x) as usize
        };
        let of: Vec<u32> = pos.iter().map(|&p| cell(p) as u32).collect();
        let mut start = vec![0u32; ncell + 1];
        for &c in &of {
            start[c as usize + 1] += 1;
        }
        for c in 0..ncell {
            start[c + 1] += start[c];
        }
        let mut next = start.clone();
        let mut pts = vec![DVec3::ZERO; n];
        let mut ids = vec![0u32; n];
        for (i, &c) in of.iter().enumerate() {
            let k = next[c as usize] as usize;
            next[c as usize] += 1;
            pts[k] = pos[i];
            ids[k] = i as u32;
        }
        let mag = lo.abs().max(hi.abs()).max_element();
        Some(Self {
            lo,
            side,
            inv,
            dims: d,
            start,
            pts,
            ids,
            slack: mag * 1e-13 + side * 1e-9,
        })
    }

    /// The nearest other point of sorted point `k`, or `(u32::MAX, inf)` when it could
    /// not be settled on the grid.
    fn nearest(&self, k: usize) -> (u32, f64) {
        let p = self.pts[k];
        let id = self.ids[k];
        let c = ((p - self.lo) * self.inv)
            .to_array()
            .map(|x| x as i64)
            .map(|x| x.max(0));
        let c = [0, 1, 2].map(|a| c[a].min(self.dims[a] - 1));
        let clo = self.lo + DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * self.side;
        // Distance from `p` to its own cell's boundary.
        let inner = (p - clo).min(clo + self.side - p).min_element().max(0.0);
        for r in 1..=MAX_RING {
            let Some(best) = self.scan_block(c, r, id, p) else {
                return (u32::MAX, f64::INFINITY);
            };
            // Every point outside the block is at least `r` sides plus `inner` away.
            let bound = r as f64 * self.side + inner - self.slack;
            if bound > 0.0 && best.1 < bound * bound * (1.0 - 1e-9) {
                return best;
            }
        }
        (u32::MAX, f64::INFINITY)
    }

    /// The nearest other point (lowest index among equidistant ones) in the cells within
    /// `r` cells of `c` per axis; `None` when they hold more than [`MAX_SCAN`] points.
    fn scan_block(&self, c: [i64; 3], r: i64, id: u32, p: DVec3) -> Option<(u32, f64)> {
        let [dx, dy, dz] = self.dims;
        let (x0, x1) = ((c[0] - r).max(0), (c[0] + r).min(dx - 1));
        let (y0, y1) = ((c[1] - r).max(0), (c[1] + r).min(dy - 1));
        let (z0, z1) = ((c[2] - r).max(0), (c[2] + r).min(dz - 1));
        let range = |y: i64, z: i64| {
            let row = ((z * dy + y) * dx) as usize;
            self.start[row + x0 as usize] as usize..self.start[row + x1 as usize + 1] as usize
        };
        let mut total = 0;
        for z in z0..=z1 {
            for y in y0..=y1 {
                total += range(y, z).len();
            }
        }
        if total > MAX_SCAN {
            return None;
        }
        let mut best = (u32::MAX, f64::INFINITY);
        for z in z0..=z1 {
            for y in y0..=y1 {
                for j in range(y, z) {
                    let q = self.ids[j];
                    let d2 = (p - self.pts[j]).length_squared();
                    if q != id && (d2 < best.1 || (d2 == best.1 && q < best.0)) {
                        best = (q, d2);
                    }
                }
            }
        }
        Some(best)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute-force nearest other point: lowest index among equidistant ones.
    fn brute_nearest(pos: &[DVec3], i: usize) -> (u32, f64) {
        let mut best = (u32::MAX, f64::INFINITY);
        for (j, q) in pos.iter().enumerate() {
            let d2 = (pos[i] - *q).length_squared();
            if j != i && (d2 < best.1 || (d2 == best.1 && (j as u32) < best.0)) {
                best = (j as u32, d2);
            }
        }
        best
    }

    #[test]
    fn nearest_others_match_brute_force_bit_for_bit() {
        let mut x = 0x1234_5678_9abc_def1u64;
        let mut r = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        // Tiny clouds.
        let mut clouds: Vec<Vec<DVec3>> = vec![
            vec![DVec3::ZERO, DVec3::X],
            vec![DVec3::ZERO, DVec3::X, DVec3::Y],
        ];
        // A volume, a thin sheet, a cluster with a far outlier.
        clouds.push((0..1500).map(|_| DVec3::new(r(), r(), r())).collect());
        clouds.push(
            (0..1500)
                .map(|_| DVec3::new(r(), r(), r() * 1e-3))
                .collect(),
        );
        let mut c: Vec<DVec3> = (0..1500)
            .map(|_| DVec3::new(r(), r(), r()) * 1e-4)
            .collect();
        c.push(DVec3::splat(1e4));
        clouds.push(c);
        // Exact duplicates.
        let mut d: Vec<DVec3> = (0..500).map(|_| DVec3::new(r(), r(), r() * 0.1)).collect();
        d.extend_from_within(..200);
        d.push(d[3]);
        clouds.push(d);
        // A regular grid (many ties), far from the origin; a planar one.
        let mut g = Vec::new();
        let mut h = Vec::new();
        for i in 0..12 {
            for j in 0..12 {
                for k in 0..3 {
                    g.push(DVec3::new(
                        1e5 + i as f64 * 0.1,
                        j as f64 * 0.1,
                        k as f64 * 0.1,
                    ));
                }
                h.push(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        clouds.push(g);
        clouds.push(h);
        for (ci, pos) in clouds.iter().enumerate() {
            let got = nearest_others(pos).unwrap();
            for i in 0..pos.len() {
                let want = brute_nearest(pos, i);
                assert_eq!(got[i].0, want.0, "cloud {ci} point {i}");
                assert_eq!(got[i].1.to_bits(), want.1.to_bits(), "cloud {ci} point {i}");
            }
            // The same rows, and so the same mean spacing, as the k-d tree's table.
            let table = reconbench_geom::spatial::knn_self_table(pos, 1, true).unwrap();
            for (i, &(j, d2)) in got.iter().enumerate() {
                assert_eq!(table.indices(i)[0], j, "cloud {ci} point {i}");
                assert_eq!(
                    table.dist2(i)[0].to_bits(),
                    d2.to_bits(),
                    "cloud {ci} point {i}"
                );
            }
            let mean = |v: &mut dyn Iterator<Item = f64>| v.sum::<f64>() / pos.len() as f64;
            let a = mean(&mut got.iter().map(|g| g.1.sqrt()));
            let b = mean(&mut table.dist2.iter().map(|d| d.sqrt()));
            assert_eq!(a.to_bits(), b.to_bits(), "cloud {ci}");
        }
    }
}
