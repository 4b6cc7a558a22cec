//! A uniform hash grid over a fixed point set (flat arrays: one sorted item list and a
//! map from occupied cell to its range), for the fixed-radius searches of the mesh
//! growth and the validator.

use std::collections::HashMap;

use glam::DVec3;
use reconbench_geom::Aabb;
use reconbench_geom::method::MethodError;

/// Cells per axis above which the grid refuses (coordinates must fit an `i32`).
const MAX_CELLS: f64 = 1.0e9;

/// The grid.
#[derive(Debug, Clone)]
pub struct Grid {
    h: f64,
    lo: DVec3,
    cells: HashMap<[i32; 3], (u32, u32)>,
    items: Vec<u32>,
}

impl Grid {
    /// A grid of cell edge `h` over `points[i]` for every `i` in `ids`.
    pub fn new(points: &[DVec3], ids: &[u32], h: f64) -> Result<Self, MethodError> {
        let bb = Aabb::from_points(points);
        let lo = if bb.is_empty() { DVec3::ZERO } else { bb.min };
        if !(h.is_finite() && h > 0.0) || (bb.max - lo).max_element() / h > MAX_CELLS {
            return Err(MethodError::InvalidInput(format!(
                "search cell {h:.3e} is unusable for a box of extent {:.3e}",
                (bb.max - lo).max_element()
            )));
        }
        let key = |p: DVec3| {
            let c = ((p - lo) / h).floor();
            [c.x as i32, c.y as i32, c.z as i32]
        };
        let mut keyed: Vec<([i32; 3], u32)> =
            ids.iter().map(|&i| (key(points[i as usize]), i)).collect();
        keyed.sort_unstable();
        let mut cells = HashMap::with_capacity(keyed.len() / 2 + 1);
        let mut items = Vec::with_capacity(keyed.len());
        let mut s = 0;
        while s < keyed.len() {
            let mut e = s;
            while e < keyed.len() && keyed[e].0 == keyed[s].0 {
                items.push(keyed[e].1);
                e += 1;
            }
            cells.insert(keyed[s].0, (s as u32, e as u32));
            s = e;
        }
        Ok(Self {
            h,
            lo,
            cells,
            items,
        })
    }

    /// Calls `f` for every item in the cells overlapping the cube of half-width `r`
    /// around `p` (a superset of the items within `r`; the caller filters by distance).
    pub fn for_each_near(&self, p: DVec3, r: f64, mut f: impl FnMut(u32)) {
        let a = ((p - DVec3::splat(r) - self.lo) / self.h).floor();
        let b = ((p + DVec3::splat(r) - self.lo) / self.h).floor();
        for z in a.z as i32..=b.z as i32 {
            for y in a.y as i32..=b.y as i32 {
                for x in a.x as i32..=b.x as i32 {
                    if let Some(&(s, e)) = self.cells.get(&[x, y, z]) {
                        for &i in &self.items[s as usize..e as usize] {
                            f(i);
                        }
                    }
                }
            }
        }
    }
}
