//! `hc-it`: hierarchical clustering and incremental triangulation after Sritrakulchai &
//! Sangveraphunsiri, "3D Surface Reconstruction by Hierarchical Clustering and
//! Incremental Triangulation" (spec `shared/spec/003_hier_clustering.md`).
//!
//! An interpolating, point-at-a-time sweep: the points are sorted along x (stable y / z
//! tie-breaks) and fed one by one into a two-level clustering, SM (connectivity under
//! rho) and NC (points with at least two rho-neighbours inside the cluster), kept with
//! union-find ([`cluster`]). When a point joins an NC of three or more points with at
//! least two of its members within rho, it is triangulated into that NC's mesh: the
//! first triangle oriented by the reference vector k, later ones attached to the nearest
//! boundary ("winner") edge after the theta / gamma / psi fold tests, with a split of
//! the winner triangle, neighbourhood (ear) triangles and shortest-diagonal flips
//! (`engine`). Every NC grows its own mesh; all go into one output, whose vertices
//! are the input points in input order (unmeshed ones unreferenced and listed as
//! refused). See `docs/methods/hc_it.md`.

pub mod closure;
pub mod cluster;
mod edge_grid;
mod engine;
mod mesh;
pub mod params;

use glam::DVec3;
use reconbench_geom::method::{
    Describe, Diagnostic, Diagnostics, MethodError, ParamDoc, Reconstruction, Reconstructor, RunCtx,
};
use reconbench_geom::spatial::{PointIndex, mean_spacing};
use reconbench_geom::topology::MeshTopology;
use reconbench_geom::{PointCloud, TriMesh};

pub use params::{Closure, ConflictRule, EdgeDistance, HC_IT_DOCS, HcItParams, WinnerScan};

/// The `hc-it` reconstructor.
#[derive(Debug, Clone, Default)]
pub struct HcIt {
    /// Parameters.
    pub params: HcItParams,
}

impl Describe for HcIt {
    const NAME: &'static str = "hc-it";
    const SOURCE: &'static str = "seed 003 (Sritrakulchai & Sangveraphunsiri) §2-3";
    const SUMMARY: &'static str =
        "x-sweep two-level clustering (SM / NC) with incremental triangulation per NC";
    type Params = HcItParams;
    const PARAMS: &'static [ParamDoc] = HC_IT_DOCS;

    fn from_params(params: HcItParams) -> Result<Self, MethodError> {
        params.validate()?;
        Ok(Self { params })
    }
}

/// Processing order of spec §3.1: ascending x, ties by y then z then input index.
// ASSUMPTION H3: one global x-sweep, the state persists from slab to slab (slab
// intervals only restrict which points are processed; they are not implemented here).
pub fn sweep_order(pts: &[DVec3]) -> Vec<u32> {
    let mut order: Vec<u32> = (0..pts.len() as u32).collect();
    order.sort_by(|&a, &b| {
        let (p, q) = (pts[a as usize], pts[b as usize]);
        p.x.total_cmp(&q.x)
            .then(p.y.total_cmp(&q.y))
            .then(p.z.total_cmp(&q.z))
            .then(a.cmp(&b))
    });
    order
}

/// Slab of each point (in sweep order), or -1 outside every slab (paper O2-O3).
fn slab_ids(sorted: &[DVec3], planes: &[f64]) -> Vec<i32> {
    if planes.len() < 2 {
        return vec![0; sorted.len()];
    }
    let (x0, x1) = (sorted[0].x, sorted[sorted.len() - 1].x);
    let ext = x1 - x0;
    sorted
        .iter()
        .map(|p| {
            let f = if ext > 0.0 { (p.x - x0) / ext } else { 0.0 };
            if f == planes[0] {
                return 0;
            }
            planes
                .windows(2)
                .position(|w| w[0] < f && f <= w[1])
                .map_or(-1, |k| k as i32)
        })
        .collect()
}

fn check_input(pts: &[DVec3], order: &[u32]) -> Result<(), MethodError> {
    if pts.len() < 3 {
        return Err(MethodError::InvalidInput(format!(
            "{} points; HC-IT needs at least 3 to make a triangle",
            pts.len()
        )));
    }
    if let Some(i) = pts.iter().position(|p| !p.is_finite()) {
        return Err(MethodError::InvalidInput(format!(
            "point {i} has a non-finite coordinate"
        )));
    }
    for w in order.windows(2) {
        if pts[w[0] as usize] == pts[w[1] as usize] {
            return Err(MethodError::InvalidInput(format!(
                "points {} and {} coincide; HC-IT interpolates the points and needs \
                 distinct positions (remove duplicates first)",
                w[0].min(w[1]),
                w[0].max(w[1])
            )));
        }
    }
    Ok(())
}

/// Points of `ranks` that no triangle of `tris` uses.
fn unmeshed_in(tris: &[[u32; 3]], ranks: &[u32], n: usize) -> usize {
    let mut used = vec![false; n];
    for t in tris {
        for &v in t {
            used[v as usize] = true;
        }
    }
    ranks.iter().filter(|&&r| !used[r as usize]).count()
}

/// ASSUMPTION H14: reverses every face-connected component whose area-weighted normal
/// points away from `k`; returns the number of faces reversed.
fn orient_by_k(p: &[DVec3], tris: &mut [[u32; 3]], k: DVec3) -> usize {
    let topo = MeshTopology::from_faces(p.len(), tris);
    let (n, comp) = topo.face_components();
    let mut sum = vec![0.0f64; n];
    for (f, t) in tris.iter().enumerate() {
        if let Some(s) = sum.get_mut(comp[f] as usize) {
            *s += engine::normal_of(p, *t).dot(k);
        }
    }
    let mut flipped = 0;
    for (f, t) in tris.iter_mut().enumerate() {
        if sum.get(comp[f] as usize).is_some_and(|&s| s < 0.0) {
            t.swap(1, 2);
            flipped += 1;
        }
    }
    flipped
}

impl Reconstructor for HcIt {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn reconstruct(
        &self,
        cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError> {
        crate::scale::reconstruct_at_working_scale(Self::NAME, cloud, |cloud| {
            let p = &self.params;
            p.validate()?;
            let pts = cloud.positions();
            let order = ctx.phase("sort", || sweep_order(pts));
            check_input(pts, &order)?;
            let spacing = mean_spacing(pts, 1)?;
            let rho = p.rho * spacing;
            // The engine works on the points relabelled by their sweep rank, so every tie
            // it breaks by vertex id is broken by position: a shuffled input gives the same
            // mesh (spec §6.7).
            let sorted: Vec<DVec3> = order.iter().map(|&i| pts[i as usize]).collect();
            // ASSUMPTION H2: a spatial index gives the same Lg sets as the paper's all-pairs
            // distances: the points strictly within rho (strict <) processed before P.
            let slab = slab_ids(&sorted, &p.slabs);
            let zipping = p.closure == Closure::Zip;
            let (offs, idx, all_offs, all_idx) = {
                let _g = ctx.phase_guard("neighbours");
                let index = PointIndex::new(&sorted)?;
                let table = index.radius_batch(&sorted, rho)?;
                let mut offs = Vec::with_capacity(pts.len() + 1);
                let mut idx = Vec::with_capacity(table.indices.len() / 2 + 1);
                // Every neighbour of the same run (earlier and later), for the closure.
                let mut all_offs = vec![0usize];
                let mut all_idx = Vec::new();
                offs.push(0usize);
                let r2 = rho * rho;
                for i in 0..pts.len() {
                    for (&j, &d2) in table.indices(i).iter().zip(table.dist2(i)) {
                        let (si, sj) = (slab[i], slab[j as usize]);
                        let same = !p.portions || si == sj;
                        if d2 < r2 && si >= 0 && sj >= 0 && same && j as usize != i {
                            if (j as usize) < i {
                                idx.push(j);
                            }
                            if zipping {
                                all_idx.push(j);
                            }
                        }
                    }
                    offs.push(idx.len());
                    if zipping {
                        all_offs.push(all_idx.len());
                    }
                }
                (offs, idx, all_offs, all_idx)
            };
            ctx.checkpoint()?;
            let k = DVec3::from_array(p.reference).normalize();
            let opts = engine::Opts {
                rho,
                theta: p.theta_rad,
                psi: p.psi_rad,
                k,
                strict_rho: p.strict_rho,
                edge_distance: p.edge_distance,
                winner_scan: p.winner_scan,
                neighbourhood: p.neighbourhood,
                ear_max_edge: if p.ear_max_edge > 0.0 {
                    p.ear_max_edge * rho
                } else {
                    f64::INFINITY
                },
                conflict_rule: p.conflict_rule,
                flips: p.flips,
            };
            let out = {
                let _g = ctx.phase_guard("triangulate");
                let c = &*ctx;
                let nbrs = |i: u32| &idx[offs[i as usize]..offs[i as usize + 1]];
                let n_slabs = p.slabs.len().saturating_sub(1).max(1);
                let runs: Vec<Vec<u32>> = if p.portions {
                    (0..n_slabs as i32)
                        .map(|k| {
                            (0..pts.len() as u32)
                                .filter(|&r| slab[r as usize] == k)
                                .collect()
                        })
                        .collect()
                } else {
                    vec![
                        (0..pts.len() as u32)
                            .filter(|&r| slab[r as usize] >= 0)
                            .collect(),
                    ]
                };
                let all_nbrs = |i: u32| &all_idx[all_offs[i as usize]..all_offs[i as usize + 1]];
                let zip_opts = closure::ZipOpts {
                    rho,
                    theta: p.theta_rad,
                    max_radius: p.zip_radius * rho,
                };
                let mut out: Option<engine::Outcome> = None;
                for ranks in &runs {
                    let mut o = engine::run(&sorted, ranks, nbrs, &opts, &mut || c.checkpoint())?;
                    o.stats.sweep_triangles = o.tris.len();
                    o.stats.sweep_unmeshed = unmeshed_in(&o.tris, ranks, pts.len());
                    if zipping {
                        // Deviation (docs/methods/hc_it.md, "Closure pass"): per run, so
                        // portions stay separate (H15).
                        let tris = std::mem::take(&mut o.tris);
                        let (tris, z) =
                            closure::zip(&sorted, tris, all_nbrs, &zip_opts, &mut || {
                                c.checkpoint()
                            })?;
                        o.tris = tris;
                        o.stats.zip_triangles = z.triangles;
                        o.stats.zip_attached = z.attached;
                        o.stats.zip_unfolded = z.unfolded;
                        o.stats.zip_filled = z.filled;
                        o.stats.zip_slits = z.slits;
                        o.stats.zip_joined = z.joined;
                        o.stats.zip_cut = z.cut;
                    }
                    out = Some(match out {
                        None => o,
                        // ASSUMPTION H15: concatenate the portions' meshes; they share no
                        // vertex (each point is in one slab), so seams stay open.
                        Some(mut acc) => {
                            for &r in ranks {
                                acc.nc[r as usize] = o.nc[r as usize];
                                acc.sm[r as usize] = o.sm[r as usize];
                            }
                            acc.tris.extend(o.tris);
                            acc.stats.add(&o.stats);
                            acc
                        }
                    });
                }
                let mut out = out.expect("at least one run");
                if p.orient_by_k {
                    out.stats.oriented_flips = orient_by_k(&sorted, &mut out.tris, k);
                }
                // Back to input indices.
                for t in &mut out.tris {
                    *t = t.map(|v| order[v as usize]);
                }
                let mut nc = vec![0; pts.len()];
                let mut sm = vec![0; pts.len()];
                for (r, &i) in order.iter().enumerate() {
                    nc[i as usize] = out.nc[r];
                    sm[i as usize] = out.sm[r];
                }
                out.nc = nc;
                out.sm = sm;
                out
            };
            let mut d = Diagnostics::new();
            let mut num = |k: &str, v: f64| {
                d.insert(k.to_string(), Diagnostic::Number(v));
            };
            let distinct = |v: &[u32]| {
                let mut s = v.to_vec();
                s.sort_unstable();
                s.dedup();
                s.len()
            };
            num("rho_abs", rho);
            num("spacing", spacing);
            num("sm_components", distinct(&out.sm) as f64);
            num("nc_components", distinct(&out.nc) as f64);
            let mut used = vec![false; pts.len()];
            for t in &out.tris {
                for &v in t {
                    used[v as usize] = true;
                }
            }
            let meshed_nc: Vec<u32> = (0..pts.len())
                .filter(|&i| used[i])
                .map(|i| out.nc[i])
                .collect();
            num("nc_meshes", distinct(&meshed_nc) as f64);
            let topo = MeshTopology::from_faces(pts.len(), &out.tris);
            num("mesh_components", topo.face_components().0 as f64);
            let refused: Vec<u32> = (0..pts.len() as u32)
                .filter(|&i| !used[i as usize])
                .collect();
            num("unmeshed", refused.len() as f64);
            let s = &out.stats;
            num("first_triangles", s.first_triangles as f64);
            num("created", s.created as f64);
            num("splits", s.splits as f64);
            num("extra_cases", s.extra_cases as f64);
            num("neighbourhood_triangles", s.neighbourhood as f64);
            num("flips", s.flips as f64);
            num("refused_triangles", s.refused as f64);
            num("no_winner", s.no_winner as f64);
            num("sweep_triangles", s.sweep_triangles as f64);
            num("sweep_unmeshed", s.sweep_unmeshed as f64);
            num("zip_triangles", s.zip_triangles as f64);
            num("zip_attached", s.zip_attached as f64);
            num("zip_unfolded", s.zip_unfolded as f64);
            num("zip_filled", s.zip_filled as f64);
            num("zip_slits", s.zip_slits as f64);
            num("zip_joined", s.zip_joined as f64);
            num("zip_cut", s.zip_cut as f64);
            num("oriented_flips", s.oriented_flips as f64);
            num("ignored", slab.iter().filter(|&&k| k < 0).count() as f64);
            let mesh = TriMesh::new(pts.to_vec(), out.tris)?;
            Ok(Reconstruction {
                mesh,
                refused,
                diagnostics: d,
            })
        })
    }
}
