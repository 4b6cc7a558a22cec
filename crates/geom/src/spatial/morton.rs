//! Morton (Z-order) ordering of query points, for cache-friendly batch queries.

use glam::DVec3;
use rayon::prelude::*;

use crate::aabb::Aabb;

/// Interleaves the low 21 bits of `x` with two zero bits between each.
fn spread21(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | (x << 32)) & 0x1f00000000ffff;
    x = (x | (x << 16)) & 0x1f0000ff0000ff;
    x = (x | (x << 8)) & 0x100f00f00f00f00f;
    x = (x | (x << 4)) & 0x10c30c30c30c30c3;
    x = (x | (x << 2)) & 0x1249249249249249;
    x
}

/// Query order along a Morton (Z-order) curve over the queries' bounding box.
pub fn morton_order(points: &[DVec3]) -> Vec<u32> {
    let b = Aabb::from_points(points);
    let size = b.size().max(DVec3::splat(1e-300));
    let scale = DVec3::splat((1u64 << 21) as f64 - 1.0) / size;
    let mut keyed: Vec<(u64, u32)> = points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let q = ((*p - b.min) * scale).max(DVec3::ZERO);
            let k =
                spread21(q.x as u64) | (spread21(q.y as u64) << 1) | (spread21(q.z as u64) << 2);
            (k, i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}
