//! A hashed uniform grid of the points for one ball radius: cells of side `2ρ`, so every
//! point within `2ρ` of a point lies in that point's cell or one of the 26 around it.
//! It gives the neighbour rows of a pass without a tree walk or sorting the results.

use std::collections::HashMap;

use glam::DVec3;
use rayon::prelude::*;

type CellMap = HashMap<[i64; 3], (u32, u32), foldhash::fast::FixedState>;

/// Points bucketed by cell.
#[derive(Debug)]
pub(crate) struct CellGrid {
    origin: DVec3,
    inv: f64,
    /// Cell -> `(start, len)` into `items`.
    cells: CellMap,
    /// Point ids sorted by cell, then by id.
    items: Vec<u32>,
}

impl CellGrid {
    /// The grid of `pos` with cells of side `side` (finite, positive).
    pub fn new(pos: &[DVec3], side: f64) -> Self {
        let origin = pos
            .iter()
            .fold(DVec3::splat(f64::INFINITY), |a, &p| a.min(p));
        let inv = 1.0 / side;
        let mut keyed: Vec<([i64; 3], u32)> = pos
            .par_iter()
            .enumerate()
            .map(|(i, &p)| (cell_of(origin, inv, p), i as u32))
            .collect();
        keyed.par_sort_unstable();
        let mut cells = CellMap::default();
        let mut items = Vec::with_capacity(keyed.len());
        let mut i = 0;
        while i < keyed.len() {
            let k = keyed[i].0;
            let start = items.len() as u32;
            while i < keyed.len() && keyed[i].0 == k {
                items.push(keyed[i].1);
                i += 1;
            }
            cells.insert(k, (start, items.len() as u32 - start));
        }
        Self {
            origin,
            inv,
            cells,
            items,
        }
    }

    /// Appends to `out` every point of `pos` within distance `sqrt(r2)` of `p` (`r2` at
    /// most the squared cell side), in cell order.
    pub fn near_into(&self, pos: &[DVec3], p: DVec3, r2: f64, out: &mut Vec<u32>) {
        let c = cell_of(self.origin, self.inv, p);
        for dz in -1..=1i64 {
            for dy in -1..=1i64 {
                for dx in -1..=1i64 {
                    let k = [
                        c[0].saturating_add(dx),
                        c[1].saturating_add(dy),
                        c[2].saturating_add(dz),
                    ];
                    let Some(&(s, l)) = self.cells.get(&k) else {
                        continue;
                    };
                    for &q in &self.items[s as usize..(s + l) as usize] {
                        if pos[q as usize].distance_squared(p) <= r2 {
                            out.push(q);
                        }
                    }
                }
            }
        }
    }
}

/// Integer cell coordinates (the float-to-integer casts saturate, so absurd ratios of
/// extent to cell side lump points together instead of failing; rows stay exact
/// because every candidate is filtered by distance).
#[inline]
fn cell_of(origin: DVec3, inv: f64, p: DVec3) -> [i64; 3] {
    ((p - origin) * inv).floor().to_array().map(|x| x as i64)
}

#[cfg(test)]
mod tests {
    use super::*;

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
    }
}
