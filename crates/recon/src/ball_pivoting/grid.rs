//! A uniform grid of the points for one ball radius: cells of side `2ρ`, so every point
//! within `2ρ` of a point lies in that point's cell or one of the 26 around it. It gives
//! the neighbour rows of a pass without a tree walk or sorting the results. The cells
//! are a dense array over the points' box, or a hash map of the occupied ones when the
//! box would need too many.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};

use glam::DVec3;
use rayon::prelude::*;

/// Integer cell coordinates as a hash key. Equality is on the three coordinates; the
/// hash feeds one mixed `u64` to the hasher instead of the 24 bytes of the array (which
/// `foldhash` hashes with its long-input path): the 27 look-ups per run of points are
/// a large share of the neighbour rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct CellKey([i64; 3]);

impl Hash for CellKey {
    #[inline]
    fn hash<H: Hasher>(&self, state: &mut H) {
        let [x, y, z] = self.0.map(|c| c as u64);
        // Odd multipliers: distinct small cells rarely share the mixed value, and a
        // collision only costs a probe (equality decides).
        state.write_u64(
            x.wrapping_mul(0x9E37_79B9_7F4A_7C15)
                ^ y.wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
                ^ z.wrapping_mul(0x1656_67B1_9E37_79F9),
        );
    }
}

type CellMap = HashMap<CellKey, (u32, u32), foldhash::fast::FixedState>;

/// A dense cell array is used while the points' box holds at most this many cells per
/// point (plus [`DENSE_EXTRA`]); a sampled surface with cells of twice the ball
/// radius has a few per point (the 100k torus: 3.7 in the first pass).
const DENSE_CELLS_PER_POINT: f64 = 16.0;
/// See [`DENSE_CELLS_PER_POINT`].
const DENSE_EXTRA: f64 = 4096.0;

/// Where each cell's points are in `items`.
#[derive(Debug, PartialEq)]
enum Cells {
    /// IMPL-CHOICE: an array over the points' box, `(x * dims[1] + y) * dims[2] + z`
    /// (lexicographic like the cell coordinates): cell `c` holds
    /// `items[start[c]..start[c + 1]]`. A look-up is an index instead of a hash, and
    /// the points are ordered by a counting sort. For the boxes that would need too
    /// many cells (scattered or very elongated input) the hash map below.
    Dense { dims: [i64; 3], start: Vec<u32> },
    /// Occupied cell -> `(start, len)`.
    Hashed(CellMap),
}

impl Cells {
    /// `(start, len)` of the points of cell `k`, `None` when it has none.
    #[inline]
    fn get(&self, k: [i64; 3]) -> Option<(u32, u32)> {
        match self {
            Cells::Dense { dims, start } => {
                if (0..3).any(|a| k[a] < 0 || k[a] >= dims[a]) {
                    return None;
                }
                let c = ((k[0] * dims[1] + k[1]) * dims[2] + k[2]) as usize;
                let (s, e) = (start[c], start[c + 1]);
                (e > s).then_some((s, e - s))
            }
            Cells::Hashed(m) => m.get(&CellKey(k)).copied(),
        }
    }
}

/// Points bucketed by cell.
#[derive(Debug)]
pub(crate) struct CellGrid {
    origin: DVec3,
    inv: f64,
    /// `1 / inv`, the cell side.
    side: f64,
    /// Cell -> `(start, len)` into `items`.
    cells: Cells,
    /// The occupied cells in lexicographic order: `(cell, start, len)` into `items`.
    runs: Vec<([i64; 3], u32, u32)>,
    /// Point ids sorted by cell, then by id.
    items: Vec<u32>,
}

/// The 13 neighbour offsets `(dx, dy, dz)` that come after `(0, 0, 0)` in `(dz, dy, dx)`
/// order: with the cell itself, every unordered pair of neighbouring cells once.
const FORWARD: [[i64; 3]; 13] = [
    [1, 0, 0],
    [-1, 1, 0],
    [0, 1, 0],
    [1, 1, 0],
    [-1, -1, 1],
    [0, -1, 1],
    [1, -1, 1],
    [-1, 0, 1],
    [0, 0, 1],
    [1, 0, 1],
    [-1, 1, 1],
    [0, 1, 1],
    [1, 1, 1],
];

impl CellGrid {
    /// The grid of `pos` with cells of side `side` (finite, positive).
    pub fn new(pos: &[DVec3], side: f64) -> Self {
        let origin = pos
            .iter()
            .fold(DVec3::splat(f64::INFINITY), |a, &p| a.min(p));
        let hi = pos
            .iter()
            .fold(DVec3::splat(f64::NEG_INFINITY), |a, &p| a.max(p));
        let inv = 1.0 / side;
        let cell: Vec<[i64; 3]> = pos.par_iter().map(|&p| cell_of(origin, inv, p)).collect();
        // Every point's cell is at most the top corner's (the truncation is monotone).
        let span = ((hi - origin) * inv).floor() + 1.0;
        let dense =
            span.element_product() <= DENSE_CELLS_PER_POINT * pos.len() as f64 + DENSE_EXTRA;
        let (items, cells) = if dense {
            let top = cell_of(origin, inv, hi);
            let dims = top.map(|t| t + 1);
            let (items, start) = counting_sort(&cell, dims);
            (items, Cells::Dense { dims, start })
        } else {
            (sorted_by_cell(&cell), Cells::Hashed(CellMap::default()))
        };
        let mut cells = cells;
        let mut runs = Vec::new();
        let mut i = 0;
        while i < items.len() {
            let k = cell[items[i] as usize];
            let start = i as u32;
            while i < items.len() && cell[items[i] as usize] == k {
                i += 1;
            }
            if let Cells::Hashed(m) = &mut cells {
                m.insert(CellKey(k), (start, i as u32 - start));
            }
            runs.push((k, start, i as u32 - start));
        }
        Self {
            origin,
            inv,
            side: 1.0 / inv,
            cells,
            runs,
            items,
        }
    }

    /// This grid for the points reordered by [`Self::items`] (`pos2[j] = pos[items[j]]`):
    /// the same origin, cells and spans, and the items become `0..n` (the grid that
    /// [`Self::new`] would build on `pos2` with the same side, without rebuilding it).
    pub fn into_permuted(mut self) -> Self {
        for (j, it) in self.items.iter_mut().enumerate() {
            *it = j as u32;
        }
        self
    }

    /// Point ids sorted by cell, then by id.
    pub fn items(&self) -> &[u32] {
        &self.items
    }

    /// The rows (as [`Self::near_into`]: every point within `sqrt(r2)`, itself
    /// included; `r2` at most the squared cell side) of all points of `pos` (the grid's
    /// own points) as `(start, idx)`: point `i`'s row is `idx[start[i]..start[i + 1]]`,
    /// in no particular order.
    ///
    /// IMPL-CHOICE: each unordered pair of points in neighbouring cells is tested once
    /// (the cell itself and its 13 forward neighbours, [`FORWARD`]) and the hit goes
    /// to both rows, half the distance tests of one query per point. The squared
    /// distance is symmetric bit for bit (`p - q` is `-(q - p)` exactly) and the box
    /// test only skips, so the rows are the same sets as [`Self::near_into`]'s.
    pub fn all_rows(&self, pos: &[DVec3], r2: f64) -> (Vec<u32>, Vec<u32>) {
        let n = pos.len();
        let side = self.side;
        let lim = r2 * (1.0 + 1e-9);
        let pairs: Vec<Vec<(u32, u32)>> = self
            .runs
            .par_chunks(256)
            .map(|runs| {
                let mut out = Vec::new();
                for &(c, s, l) in runs {
                    let own = &self.items[s as usize..(s + l) as usize];
                    for (x, &p) in own.iter().enumerate() {
                        let pp = pos[p as usize];
                        for &q in &own[x + 1..] {
                            if pos[q as usize].distance_squared(pp) <= r2 {
                                out.push((p, q));
                            }
                        }
                    }
                    for d in FORWARD {
                        let k = [
                            c[0].saturating_add(d[0]),
                            c[1].saturating_add(d[1]),
                            c[2].saturating_add(d[2]),
                        ];
                        let Some((s2, l2)) = self.cells.get(k) else {
                            continue;
                        };
                        let lo =
                            self.origin + DVec3::new(k[0] as f64, k[1] as f64, k[2] as f64) * side;
                        let other = &self.items[s2 as usize..(s2 + l2) as usize];
                        for &p in own {
                            let pp = pos[p as usize];
                            let gap = (lo - pp).max(pp - (lo + side)).max(DVec3::ZERO);
                            // A margin of a few ulps: the box test only skips, never decides.
                            if gap.length_squared() > lim {
                                continue;
                            }
                            for &q in other {
                                if pos[q as usize].distance_squared(pp) <= r2 {
                                    out.push((p, q));
                                }
                            }
                        }
                    }
                }
                out
            })
            .collect();
        // Each point's own entry plus its pairs, then the rows filled in place.
        let mut start = vec![1u32; n + 1];
        start[n] = 0;
        for &(p, q) in pairs.iter().flatten() {
            start[p as usize] += 1;
            start[q as usize] += 1;
        }
        let mut acc = 0u32;
        for v in start.iter_mut() {
            let c = *v;
            *v = acc;
            acc += c;
        }
        let mut idx = vec![0u32; acc as usize];
        let mut fill: Vec<u32> = start[..n].to_vec();
        for (i, f) in fill.iter_mut().enumerate() {
            idx[*f as usize] = i as u32;
            *f += 1;
        }
        for &(p, q) in pairs.iter().flatten() {
            idx[fill[p as usize] as usize] = q;
            fill[p as usize] += 1;
            idx[fill[q as usize] as usize] = p;
            fill[q as usize] += 1;
        }
        (start, idx)
    }

    /// Appends to `out` every point of `pos` within distance `sqrt(r2)` of `p` (`r2` at
    /// most the squared cell side), in cell order.
    pub fn near_into(&self, pos: &[DVec3], p: DVec3, r2: f64, out: &mut Vec<u32>) {
        let mut spans = [(0u32, 0u32, DVec3::ZERO); 27];
        let n = self.spans_around(cell_of(self.origin, self.inv, p), &mut spans);
        self.scan(pos, p, r2, &spans[..n], out);
    }

    /// The ids of `pos` whose flag in `mark` is set, in cell order (consecutive points
    /// then share their neighbour cells, which [`Self::rows`] reuses).
    pub fn in_cell_order(&self, mark: &[bool]) -> Vec<u32> {
        self.items
            .iter()
            .copied()
            .filter(|&i| mark[i as usize])
            .collect()
    }

    /// The rows (as [`Self::near_into`]) of `pts`, appended to `out` with their lengths
    /// in `lens`. The 27 cell look-ups are done once per run of points in the same cell.
    pub fn rows(
        &self,
        pos: &[DVec3],
        pts: &[u32],
        r2: f64,
        out: &mut Vec<u32>,
        lens: &mut Vec<u32>,
    ) {
        let mut spans = [(0u32, 0u32, DVec3::ZERO); 27];
        let mut n = 0;
        let mut cur = None;
        for &i in pts {
            let p = pos[i as usize];
            let c = cell_of(self.origin, self.inv, p);
            if cur != Some(c) {
                n = self.spans_around(c, &mut spans);
                cur = Some(c);
            }
            let before = out.len();
            self.scan(pos, p, r2, &spans[..n], out);
            lens.push((out.len() - before) as u32);
        }
    }

    /// The occupied cells among the 27 around cell `c`: `(start, len, lowest corner)`.
    /// The corner is computed here, once per run of points in one cell, not per point.
    fn spans_around(&self, c: [i64; 3], spans: &mut [(u32, u32, DVec3); 27]) -> usize {
        let mut n = 0;
        for dz in -1..=1i64 {
            for dy in -1..=1i64 {
                for dx in -1..=1i64 {
                    let k = [
                        c[0].saturating_add(dx),
                        c[1].saturating_add(dy),
                        c[2].saturating_add(dz),
                    ];
                    if let Some((s, l)) = self.cells.get(k) {
                        let lo = self.origin
                            + DVec3::new(k[0] as f64, k[1] as f64, k[2] as f64) * self.side;
                        spans[n] = (s, l, lo);
                        n += 1;
                    }
                }
            }
        }
        n
    }

    /// Appends the points of the cells in `spans` within `sqrt(r2)` of `p`, skipping the
    /// cells whose box is farther than that.
    #[inline]
    fn scan(
        &self,
        pos: &[DVec3],
        p: DVec3,
        r2: f64,
        spans: &[(u32, u32, DVec3)],
        out: &mut Vec<u32>,
    ) {
        let side = self.side;
        for &(s, l, lo) in spans {
            let gap = (lo - p).max(p - (lo + side)).max(DVec3::ZERO);
            // A margin of a few ulps: the box test only skips, never decides.
            if gap.length_squared() > r2 * (1.0 + 1e-9) {
                continue;
            }
            for &q in &self.items[s as usize..(s + l) as usize] {
                if pos[q as usize].distance_squared(p) <= r2 {
                    out.push(q);
                }
            }
        }
    }
}

/// The indices `0..cell.len()` sorted by cell coordinates (lexicographically), then by
/// index: a counting sort. The points of each distinct cell are counted in a hash map,
/// only the distinct cells (several points each) are sorted, and the indices are then
/// placed in increasing order into their cell's range. The same order as sorting all
/// `(cell, index)` pairs, for a fraction of the cost.
fn sorted_by_cell(cell: &[[i64; 3]]) -> Vec<u32> {
    let mut slot: HashMap<CellKey, u32, foldhash::fast::FixedState> = HashMap::default();
    for &k in cell {
        *slot.entry(CellKey(k)).or_insert(0) += 1;
    }
    let mut distinct: Vec<[i64; 3]> = slot.keys().map(|k| k.0).collect();
    distinct.sort_unstable();
    let mut start = 0u32;
    for k in distinct {
        let c = slot.get_mut(&CellKey(k)).expect("counted cell");
        let n = *c;
        *c = start;
        start += n;
    }
    let mut items = vec![0u32; cell.len()];
    for (i, &k) in cell.iter().enumerate() {
        let s = slot.get_mut(&CellKey(k)).expect("counted cell");
        items[*s as usize] = i as u32;
        *s += 1;
    }
    items
}

/// The indices `0..cell.len()` sorted by cell (lexicographically), then by index, and
/// the start of each cell of the `dims` box in that order (`start[c]..start[c + 1]`,
/// `c = (x * dims[1] + y) * dims[2] + z`): a counting sort over the dense array, the
/// same order as [`sorted_by_cell`].
fn counting_sort(cell: &[[i64; 3]], dims: [i64; 3]) -> (Vec<u32>, Vec<u32>) {
    let lin = |k: [i64; 3]| ((k[0] * dims[1] + k[1]) * dims[2] + k[2]) as usize;
    let n = (dims[0] * dims[1] * dims[2]) as usize;
    let mut start = vec![0u32; n + 1];
    for &k in cell {
        start[lin(k) + 1] += 1;
    }
    for c in 0..n {
        start[c + 1] += start[c];
    }
    let mut next = start.clone();
    let mut items = vec![0u32; cell.len()];
    for (i, &k) in cell.iter().enumerate() {
        let c = lin(k);
        items[next[c] as usize] = i as u32;
        next[c] += 1;
    }
    (items, start)
}

/// Integer cell coordinates (the float-to-integer casts saturate, so absurd ratios of
/// extent to cell side lump points together instead of failing; rows stay exact
/// because every candidate is filtered by distance).
///
/// Only the grid's own points are located (`pos` of [`CellGrid::new`]), never below
/// `origin`, their componentwise minimum: the scaled offset is non-negative, so the
/// cast's truncation is the floor (without the libm `floor` call, which the compiler
/// does not inline on the baseline x86-64 target).
#[inline]
fn cell_of(origin: DVec3, inv: f64, p: DVec3) -> [i64; 3] {
    ((p - origin) * inv).to_array().map(|x| {
        debug_assert!(x >= 0.0, "a point below the grid's origin");
        x as i64
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_order_is_the_lexicographic_order_then_the_index() {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut r = |m: u64| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x % m) as i64
        };
        // Many points per cell (7^3 cells), and nearly one cell per point.
        for m in [7, 1 << 40] {
            let cell: Vec<[i64; 3]> = (0..3000).map(|_| [r(m), r(m), r(m)]).collect();
            let mut want: Vec<u32> = (0..cell.len() as u32).collect();
            want.sort_by_key(|&i| (cell[i as usize], i));
            assert_eq!(sorted_by_cell(&cell), want, "cells per axis {m}");
            if m == 7 {
                let (items, start) = counting_sort(&cell, [7, 7, 7]);
                assert_eq!(items, want);
                assert_eq!(start.len(), 7 * 7 * 7 + 1);
                assert_eq!(start[7 * 7 * 7] as usize, cell.len());
            }
        }
    }

    #[test]
    fn rows_match_brute_force() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut r = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let pos: Vec<DVec3> = (0..2000).map(|_| DVec3::new(r(), r(), r() * 0.1)).collect();
        let rad = 0.07;
        let g = CellGrid::new(&pos, rad);
        let mut row = Vec::new();
        for (i, &p) in pos.iter().enumerate().step_by(7) {
            row.clear();
            g.near_into(&pos, p, rad * rad, &mut row);
            row.sort_unstable();
            let brute: Vec<u32> = (0..pos.len() as u32)
                .filter(|&q| pos[q as usize].distance_squared(p) <= rad * rad)
                .collect();
            assert_eq!(row, brute, "point {i}");
        }
        // The batched rows in cell order are the same sets.
        let order = g.in_cell_order(&vec![true; pos.len()]);
        assert_eq!(order.len(), pos.len());
        let (mut out, mut lens) = (Vec::new(), Vec::new());
        g.rows(&pos, &order, rad * rad, &mut out, &mut lens);
        let mut s = 0;
        for (&i, &l) in order.iter().zip(&lens) {
            let mut row = out[s..s + l as usize].to_vec();
            s += l as usize;
            row.sort_unstable();
            let p = pos[i as usize];
            let brute: Vec<u32> = (0..pos.len() as u32)
                .filter(|&q| pos[q as usize].distance_squared(p) <= rad * rad)
                .collect();
            assert_eq!(row, brute, "point {i}");
        }
    }

    #[test]
    fn all_rows_are_the_single_rows_and_the_permuted_grid_is_rebuilt_exactly() {
        let mut x = 0x3c6e_f372_fe94_f82bu64;
        let mut r = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        // A thin slab (many empty neighbour cells) and a cube (full ones), on the dense
        // array; the slab with a far point, on the hash map.
        for (zs, far) in [(0.1, false), (1.0, false), (0.1, true)] {
            let mut pos: Vec<DVec3> = (0..3000)
                .map(|_| DVec3::new(r(), r(), r() * zs) * 3.0 - 1.0)
                .collect();
            if far {
                pos.push(DVec3::splat(1e3));
            }
            let rad = 0.25;
            let g = CellGrid::new(&pos, rad);
            assert_eq!(matches!(g.cells, Cells::Hashed(_)), far);
            let (start, idx) = g.all_rows(&pos, rad * rad);
            assert_eq!(start.len(), pos.len() + 1);
            assert_eq!(start[pos.len()] as usize, idx.len());
            let mut total = 0;
            for (i, &p) in pos.iter().enumerate() {
                let mut got = idx[start[i] as usize..start[i + 1] as usize].to_vec();
                got.sort_unstable();
                let mut want = Vec::new();
                g.near_into(&pos, p, rad * rad, &mut want);
                want.sort_unstable();
                assert_eq!(got, want, "slab {zs} point {i}");
                assert!(got.contains(&(i as u32)));
                total += got.len();
            }
            // Not only the points themselves.
            assert!(total > 3 * pos.len(), "{total}");
            let mut brute = 0;
            for p in &pos {
                brute += pos
                    .iter()
                    .filter(|q| q.distance_squared(*p) <= rad * rad)
                    .count();
            }
            assert_eq!(total, brute);
            // The grid moved to the cell order is the grid of the moved points.
            let moved: Vec<DVec3> = g.items().iter().map(|&i| pos[i as usize]).collect();
            let fresh = CellGrid::new(&moved, rad);
            let permuted = g.into_permuted();
            assert_eq!(permuted.items, fresh.items);
            assert_eq!(permuted.runs, fresh.runs);
            assert_eq!(permuted.cells, fresh.cells);
            assert_eq!(permuted.origin, fresh.origin);
            assert_eq!(permuted.side.to_bits(), fresh.side.to_bits());
        }
    }
}
