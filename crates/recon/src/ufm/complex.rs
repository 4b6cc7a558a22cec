//! The Delaunay complex UFM works on: the triangles around every vertex as one CSR array
//! (`off`, `items`, items increasing per vertex), the CSR slots of every facet's corners
//! and the per-triangle attributes computed once (diameter ranks, Gabriel flags).

use glam::DVec3;
use rayon::prelude::*;
use reconbench_delaunay::{Delaunay, Facet};
use reconbench_geom::method::MethodError;

use super::params::SizeOrder;
use super::umbrella::LinkGraph;

/// Bit layout of a removal key: level (4 bits) << [`LEVEL_SHIFT`] | size rank (32 bits)
/// << [`RANK_SHIFT`] | local index (28 bits). The level is the class of Table 3.1
/// (0..=5), or with NVC filtering the tier-and-class of Algorithm C (0..=10).
pub(super) const RANK_SHIFT: u32 = 28;
/// See [`RANK_SHIFT`].
pub(super) const LEVEL_SHIFT: u32 = 60;
/// Most triangles at one vertex the key layout supports (checked in [`Complex::new`]).
pub(super) const MAX_ROW: usize = 1 << RANK_SHIFT;

/// The Delaunay complex with the per-triangle attributes UFM needs (computed once).
#[derive(Debug)]
pub struct Complex {
    /// The triangulation (vertices = deduplicated input points).
    pub dt: Delaunay,
    /// CSR offsets of `DT_v` (one row per vertex).
    pub off: Vec<u32>,
    /// CSR items: facet ids, increasing per row.
    pub items: Vec<u32>,
    /// Per facet: the CSR slots of its three vertices (order of `Facet::v`).
    pub slot: Vec<[u32; 3]>,
    /// Per facet: rank by (diam descending, id) — the initial queue (Step 2.2, A-02).
    pub rank_init: Vec<u32>,
    /// Per facet: rank used inside a class during the update.
    pub rank_update: Vec<u32>,
    /// Per facet: the exact Gabriel flag.
    pub gabriel: Vec<bool>,
}

impl Complex {
    /// Triangles incident to `v` (facet ids).
    pub fn row(&self, v: usize) -> &[u32] {
        &self.items[self.off[v] as usize..self.off[v + 1] as usize]
    }

    /// Facets of the triangulation.
    pub fn facets(&self) -> &[Facet] {
        self.dt.facets()
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.off.len() - 1
    }

    /// Prepares the link graph of `v` over `DT_v`.
    pub fn prepare(&self, v: usize, g: &mut LinkGraph) {
        let facets = self.facets();
        g.prepare(
            v as u32,
            self.row(v).iter().map(move |&f| facets[f as usize].v),
        );
    }
}

/// Diameter of the circumcircle of triangle `abc`: `|ab||bc||ca| / (2 Area)`;
/// `+∞` when the area is (numerically) zero.
pub fn circum_diameter(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let cross = (b - a).cross(c - a).length();
    let prod = (b - a).length() * (c - b).length() * (a - c).length();
    if cross <= 0.0 || !cross.is_finite() {
        return f64::INFINITY;
    }
    let d = prod / cross;
    if d.is_finite() { d } else { f64::INFINITY }
}

/// Rank of every facet under (diameter in the given direction, then id), from a
/// parallel sort of flat `(key, id)` pairs (no indirection in the comparisons).
/// Diameters are non-negative or `+∞`, so their IEEE bits order like the values.
fn ranks(diam: &[f64], large_first: bool) -> Vec<u32> {
    let mut keyed: Vec<(u64, u32)> = diam
        .par_iter()
        .enumerate()
        .map(|(i, &d)| {
            let bits = d.max(0.0).to_bits();
            (if large_first { !bits } else { bits }, i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    let mut rank = vec![0u32; diam.len()];
    for (r, &(_, f)) in keyed.iter().enumerate() {
        rank[f as usize] = r as u32;
    }
    rank
}

impl Complex {
    /// Step 1 after the triangulation: CSR of `DT_v`, slots, diameters, ranks, Gabriel
    /// flags, all in parallel (per vertex for the CSR, per facet for the rest).
    pub fn new(dt: Delaunay, size_order: SizeOrder) -> Result<Self, MethodError> {
        let nv = dt.n_vertices();
        let facets = dt.facets();
        if facets.len() >= u32::MAX as usize / 2 {
            return Err(MethodError::InvalidInput(format!(
                "{} Delaunay triangles exceed the supported range",
                facets.len()
            )));
        }
        // CSR of DT_v: row lengths in parallel, prefix sum, then one parallel copy per
        // vertex block into disjoint ranges.
        let lens: Vec<u32> = (0..nv as u32)
            .into_par_iter()
            .map(|v| dt.facets_of_vertex(v).len() as u32)
            .collect();
        if lens.iter().any(|&n| n as usize >= MAX_ROW) {
            return Err(MethodError::InvalidInput(format!(
                "a vertex has more than {MAX_ROW} Delaunay triangles"
            )));
        }
        let mut off = Vec::with_capacity(nv + 1);
        off.push(0u32);
        let mut acc = 0u32;
        for &n in &lens {
            acc += n;
            off.push(acc);
        }
        let mut items = vec![0u32; acc as usize];
        {
            let mut parts: Vec<(usize, &mut [u32])> = Vec::with_capacity(nv);
            let mut rest = items.as_mut_slice();
            for v in 0..nv {
                let (a, b) = rest.split_at_mut(lens[v] as usize);
                parts.push((v, a));
                rest = b;
            }
            parts
                .into_par_iter()
                .with_min_len(256)
                .for_each(|(v, dst)| dst.copy_from_slice(dt.facets_of_vertex(v as u32)));
        }
        // Per facet, in parallel: the CSR slots of its three corners (binary search in
        // the increasing rows), the diameter and the exact Gabriel flag.
        let pts = dt.vertices();
        type PerFacet = (Vec<[u32; 3]>, (Vec<f64>, Vec<bool>));
        let (slot, (diam, gabriel)): PerFacet = (0..facets.len())
            .into_par_iter()
            .map(|f| {
                let fv = facets[f].v;
                let slot = fv.map(|x| {
                    let (a, b) = (off[x as usize] as usize, off[x as usize + 1] as usize);
                    let k = items[a..b]
                        .binary_search(&(f as u32))
                        .expect("facet is in the rows of its vertices");
                    (a + k) as u32
                });
                let [a, b, c] = fv.map(|x| pts[x as usize]);
                (slot, (circum_diameter(a, b, c), dt.is_gabriel(f as u32)))
            })
            .unzip();
        let rank_init = ranks(&diam, true);
        let rank_update = match size_order {
            SizeOrder::LargeFirst => rank_init.clone(),
            SizeOrder::SmallFirst => ranks(&diam, false),
        };
        Ok(Self {
            dt,
            off,
            items,
            slot,
            rank_init,
            rank_update,
            gabriel,
        })
    }
}

/// Vertex blocks with their disjoint slot ranges of `out`, for the parallel update.
pub(super) fn blocks<'a>(
    cx: &Complex,
    out: &'a mut [bool],
    per: usize,
) -> Vec<(usize, usize, &'a mut [bool])> {
    let nv = cx.n_vertices();
    let mut res = Vec::with_capacity(nv / per + 1);
    let mut rest = out;
    let mut v0 = 0;
    while v0 < nv {
        let v1 = (v0 + per).min(nv);
        let len = (cx.off[v1] - cx.off[v0]) as usize;
        let (a, b) = rest.split_at_mut(len);
        res.push((v0, v1, a));
        rest = b;
        v0 = v1;
    }
    res
}
