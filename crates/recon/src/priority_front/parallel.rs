//! Deterministic multi-threaded growth (paper §3.7.1, Table 3).
//!
//! The paper's own design (spec A19: shared fronts, per-cell locks, atomic point claims)
//! is order-dependent. This one is deterministic for a fixed thread count: the points
//! are split into `threads` slabs of equal count along the longest box axis; every slab
//! runs the sequential algorithm (seed, growth, restarts; no refusal) on its own points
//! in parallel; then one sequential *stitch* imports all slab meshes and live fronts into
//! a single state, pushes every live front edge again, and grows on — the fronts of
//! neighbouring slabs meet through join / link / glue / fill exactly as fronts of
//! different seeds do in the sequential algorithm (M8).

use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use reconbench_geom::method::{MethodError, RunCtx};

use super::grid::{Grid, NONE};
use super::mesher::{ACCEPTED, Cfg, Mesher, Stats};
use super::run::DomainCfg;

/// The result of one slab, in global grid indices.
#[derive(Debug, Default)]
pub(crate) struct SlabOut {
    pub tris: Vec<[u32; 3]>,
    pub accepted: Vec<u32>,
    /// Live front edges `(a, b, index of the next edge in this list, normal, cost)`.
    pub edges: Vec<(u32, u32, u32, DVec3, f64)>,
    pub stats: Stats,
}

/// Splits the non-refused grid points into `t` slabs of equal count along the longest
/// axis (ties by index). Points closer than `band` to a cut between two slabs belong to
/// no slab: they stay Free for the sequential stitch, so that the fronts of the two
/// slabs approach the cut through Free points and meet there by join / link / glue /
/// fill as fronts of different seeds do. (Without the band the slab fronts face each
/// other with no Free point in between and glue repairs fail: a 200k torus kept four
/// 50-vertex strips along the cuts.)
pub(crate) fn slabs(pts: &[DVec3], refused: &[bool], t: usize, band: f64) -> Vec<Vec<u32>> {
    let (lo, hi) = super::grid::bounds(pts);
    let ext = hi - lo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mut idx: Vec<u32> = (0..pts.len() as u32)
        .filter(|&i| !refused[i as usize])
        .collect();
    idx.sort_unstable_by(|&a, &b| {
        pts[a as usize][axis]
            .total_cmp(&pts[b as usize][axis])
            .then(a.cmp(&b))
    });
    let n = idx.len();
    let coord = |k: usize| pts[idx[k] as usize][axis];
    // Cut k (between slab k - 1 and k) at the first coordinate of slab k.
    let cut = |k: usize| coord((k * n / t).min(n.saturating_sub(1)));
    (0..t)
        .map(|k| {
            let (s, e) = (k * n / t, (k + 1) * n / t);
            let lo_c = (k > 0).then(|| cut(k) + band);
            let hi_c = (k + 1 < t).then(|| cut(k + 1) - band);
            let mut v: Vec<u32> = idx[s..e]
                .iter()
                .copied()
                .filter(|&i| {
                    let c = pts[i as usize][axis];
                    lo_c.is_none_or(|l| c >= l) && hi_c.is_none_or(|h| c <= h)
                })
                .collect();
            v.sort_unstable();
            v
        })
        .collect()
}

/// Runs one slab: its own grid and state over `members` (global grid indices).
fn run_slab(
    all: &[DVec3],
    members: &[u32],
    h: f64,
    cfg: Cfg,
    dcfg: &DomainCfg,
    seed: u64,
    ctx: &RunCtx,
) -> Result<SlabOut, MethodError> {
    if members.len() < 3 {
        return Ok(SlabOut::default());
    }
    let sub: Vec<DVec3> = members.iter().map(|&i| all[i as usize]).collect();
    let (grid, order) = Grid::build(&sub, h);
    let pts: Vec<DVec3> = order.iter().map(|&i| sub[i as usize]).collect();
    // local grid index -> global grid index
    let to_global: Vec<u32> = order.iter().map(|&i| members[i as usize]).collect();
    let refused = vec![false; pts.len()];
    // No revisit passes inside a slab: they would close the slab's cut boundaries.
    let cfg = Cfg {
        revisit_passes: 0,
        ..cfg
    };
    let mut m = Mesher::new(&pts, &grid, cfg, &refused);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let dc = DomainCfg {
        first_centre: None,
        ..dcfg.clone()
    };
    m.run_domain(&dc, &mut rng, ctx)?;
    let g = |i: u32| to_global[i as usize];
    let tris = m.tris.iter().map(|t| t.map(g)).collect();
    let accepted = (0..pts.len() as u32)
        .filter(|&i| m.state[i as usize] == ACCEPTED)
        .map(g)
        .collect();
    // Live edges in slot order; `next` re-indexed into that list.
    let mut slot_to_k = vec![NONE; m.e_a.len()];
    let mut k = 0u32;
    for e in 0..m.e_a.len() {
        if m.e_alive[e] {
            slot_to_k[e] = k;
            k += 1;
        }
    }
    let edges = (0..m.e_a.len())
        .filter(|&e| m.e_alive[e])
        .map(|e| {
            (
                g(m.e_a[e]),
                g(m.e_b[e]),
                slot_to_k[m.e_next[e] as usize],
                m.e_nrm[e],
                m.e_cost[e],
            )
        })
        .collect();
    Ok(SlabOut {
        tris,
        accepted,
        edges,
        stats: m.stats.clone(),
    })
}

/// Grows all slabs in parallel on a pool of `threads` workers; results in slab order.
pub(crate) fn grow_slabs(
    pts: &[DVec3],
    refused: &[bool],
    h: f64,
    cfg: &Cfg,
    dcfg: &DomainCfg,
    threads: usize,
    seed: u64,
    ctx: &RunCtx,
) -> Result<Vec<SlabOut>, MethodError> {
    // Band of R on each side of every cut (see `slabs`).
    let parts = slabs(pts, refused, threads, cfg.r);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| MethodError::Failed(format!("thread pool: {e}")))?;
    pool.install(|| {
        parts
            .par_iter()
            .enumerate()
            .map(|(k, members)| {
                let s = seed ^ (0x9E37_79B9_7F4A_7C15u64.wrapping_mul(k as u64 + 1));
                run_slab(pts, members, h, cfg.clone(), dcfg, s, ctx)
            })
            .collect()
    })
}

/// Imports slab results into `m` (the global state) and re-activates the fronts of the
/// even-numbered slabs only. Each Free band between two slabs is then grown from one
/// side (the even slab's), so that front sweeps across the band and meets the other
/// slab's front, which stays still, at the far edge of the band; the caller grows, then
/// pushes every live edge again ([`Mesher::repush_all`]) and grows on. (When both
/// fronts grew into the band at the same pace they met in its middle, facing each
/// other, and the zipping failed: 36k / 100k tori kept four 80-90-vertex strips.)
pub(crate) fn stitch_import(m: &mut Mesher, outs: &[SlabOut], one_sided: bool) {
    let mut even = Vec::new();
    for (k, o) in outs.iter().enumerate() {
        let base = m.e_a.len() as u32;
        m.import(&o.tris, &o.accepted, &o.edges);
        m.stats.add(&o.stats);
        if k % 2 == 0 || !one_sided {
            even.extend(base..m.e_a.len() as u32);
        }
    }
    m.push_only(&even);
}
