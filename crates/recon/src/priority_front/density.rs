//! Pre-processing (spec §4.1): exact-duplicate detection, the density ρ (P2, ASSUMPTION
//! A1), and exact nearest-neighbour searches on the grid by expanding cube shells.

use glam::DVec3;
use rand::seq::index;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::grid::{Grid, bounds};
use super::params::RhoSample;

/// Sample size s of the ρ estimate for `n` eligible points.
// ASSUMPTION A1: s = min(N, max(100, ceil(0.05 N))); the alternative min(N, 100) is the
// `rho_sample = "fixed100"` parameter.
pub(crate) fn sample_size(n: usize, rule: RhoSample) -> usize {
    match rule {
        RhoSample::Max100Or5Percent => n.min(100.max((n as f64 * 0.05).ceil() as usize)),
        RhoSample::Fixed100 => n.min(100),
    }
}

/// Squared distance to the nearest point `i` of the grid with `keep(i)`, searched by
/// expanding shells (exact for any cell size). `None` when no point qualifies.
pub(crate) fn nearest(
    grid: &Grid,
    pts: &[DVec3],
    q: DVec3,
    keep: impl Fn(usize) -> bool,
) -> Option<(f64, usize)> {
    let mut best = (f64::INFINITY, usize::MAX);
    let mut level = 0;
    loop {
        let more = grid.for_shell(q, level, |range| {
            for i in range {
                if keep(i) {
                    let d2 = (pts[i] - q).length_squared();
                    if d2 < best.0 || (d2 == best.0 && i < best.1) {
                        best = (d2, i);
                    }
                }
            }
        });
        if !more {
            break;
        }
        let cov = grid.covered(q, level);
        if best.0 <= cov * cov {
            break;
        }
        level += 1;
    }
    (best.1 != usize::MAX).then_some(best)
}

/// The `k` nearest points with `keep(i)` within distance `rmax` of `q`, sorted by
/// (distance, index), written into `out` (cleared first).
pub(crate) fn knn(
    grid: &Grid,
    pts: &[DVec3],
    q: DVec3,
    k: usize,
    rmax: f64,
    keep: impl Fn(usize) -> bool,
    out: &mut Vec<(f64, u32)>,
) {
    out.clear();
    if k == 0 {
        return;
    }
    let r2max = rmax * rmax;
    let mut level = 0;
    loop {
        let more = grid.for_shell(q, level, |range| {
            for i in range {
                if keep(i) {
                    let d2 = (pts[i] - q).length_squared();
                    if d2 <= r2max {
                        out.push((d2, i as u32));
                    }
                }
            }
        });
        out.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        out.truncate(k);
        if !more {
            break;
        }
        let cov = grid.covered(q, level);
        if cov >= rmax || (out.len() == k && out[k - 1].0 <= cov * cov) {
            break;
        }
        level += 1;
    }
}

/// Flags exact duplicates (bitwise equal positions); the lowest input index of each
/// group is kept. `grid`/`order` are any grid over `pts`.
pub(crate) fn duplicates(grid: &Grid, order: &[u32], pts: &[DVec3]) -> Vec<bool> {
    let mut dup = vec![false; pts.len()];
    let mut buf: Vec<([u64; 3], u32)> = Vec::new();
    for c in 0..grid.n_cells() as u32 {
        let r = grid.range(c);
        if r.len() < 2 {
            continue;
        }
        buf.clear();
        buf.extend(r.map(|s| {
            let i = order[s];
            let p = pts[i as usize];
            ([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()], i)
        }));
        buf.sort_unstable();
        for w in 1..buf.len() {
            if buf[w].0 == buf[w - 1].0 {
                dup[buf[w].1 as usize] = true;
            }
        }
    }
    dup
}

/// A grid for neighbour searches over `pts` whose cells hold ~16 points of a surface
/// sample: cell edge `4 sqrt(A / n)` with `A` half the box's surface area.
pub(crate) fn search_grid(pts: &[DVec3]) -> (Grid, Vec<u32>) {
    let (lo, hi) = bounds(pts);
    let e = hi - lo;
    let area = e.x * e.y + e.y * e.z + e.z * e.x;
    let n = pts.len().max(1) as f64;
    let mut h = 4.0 * (area / n).sqrt();
    if !(h.is_finite() && h > 0.0) {
        // Collinear or coincident input: fall back to the length scale.
        h = (e.max_element() / n).max(f64::MIN_POSITIVE);
    }
    Grid::build(pts, h)
}

/// Mean nearest-neighbour distance of `s` random points among those with
/// `eligible(i)`, the neighbours also restricted to `eligible` (P2). Grid indices.
/// Returns `None` when fewer than two points are eligible.
pub(crate) fn mean_nn(
    grid: &Grid,
    pts: &[DVec3],
    eligible: &(dyn Fn(usize) -> bool + Sync),
    rule: RhoSample,
    rng: &mut ChaCha8Rng,
) -> Option<f64> {
    let idx: Vec<usize> = (0..pts.len()).filter(|&i| eligible(i)).collect();
    if idx.len() < 2 {
        return None;
    }
    let s = sample_size(idx.len(), rule);
    let mut picks: Vec<usize> = index::sample(rng, idx.len(), s)
        .into_iter()
        .map(|k| idx[k])
        .collect();
    picks.sort_unstable();
    let d: Vec<f64> = picks
        .par_iter()
        .map(|&i| {
            nearest(grid, pts, pts[i], |j| j != i && eligible(j))
                .map(|(d2, _)| d2.sqrt())
                .unwrap_or(0.0)
        })
        .collect();
    let mean = d.iter().sum::<f64>() / d.len() as f64;
    (mean.is_finite() && mean > 0.0).then_some(mean)
}
