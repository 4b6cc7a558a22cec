//! `ebt`: error-bounded thinning and seed-grown triangulation after Sun, Bradley, Zhang
//! & Loh, "Cloud data modelling employing a unified, non-redundant triangular mesh",
//! CAD 33 (2001) 183-193 (spec `shared/spec/004_error_based.md`).
//!
//! Four stages: local quadrics on random neighbourhoods give the maximum second
//! derivatives M1, M2, M3 ([`curvature`]); the linear-interpolation error bound turns
//! the tolerance epsilon into the maximum edge length Omega and the bin size B
//! ([`bound`]); voxel binning keeps the point nearest each bin centre ([`binning`]); a
//! mesh grows from a seed over the kept points under five rules (`grow`). Optional
//! edge swaps (E21 feature alignment, E20 near-equilateral; `enhance`) follow, and the
//! "incorrect facets" of Table 1 are counted by category ([`validate`]).
//!
//! Output: a mesh whose vertices are exactly the thinned set Q (unmeshed ones are
//! unreferenced and listed as refused), with diagnostics M1-M3, Omega, B, |Q|, the bad
//! facets by category and, by default, the distance of every input point to the mesh
//! (the paper's central claim, `dev_*`). See `docs/methods/ebt.md`.

pub mod binning;
pub mod bound;
pub mod curvature;
mod enhance;
mod geometry;
mod grid;
mod grow;
pub mod params;
pub mod qem;
pub mod validate;

use glam::DVec3;
use reconbench_geom::method::{
    Describe, Diagnostic, Diagnostics, MethodError, ParamDoc, Reconstruction, Reconstructor, RunCtx,
};
use reconbench_geom::spatial::{MeshBvh, PointIndex};
use reconbench_geom::{PointCloud, TriMesh};

pub use params::{
    Aggregation, BinRule, Derivatives, EBT_DOCS, EbtParams, Neighborhood, OmegaRule, THINNING_DOCS,
    ThinningParams,
};

use curvature::{Curvature, CurvatureOpts};

/// Result of the thinning stage (stages 1-3).
#[derive(Debug, Clone, PartialEq)]
pub struct Thinned {
    /// Kept input indices (Q), ascending.
    pub kept: Vec<u32>,
    /// The curvature estimate (empty when B was forced).
    pub curvature: Option<Curvature>,
    /// Omega in input units.
    pub omega: f64,
    /// B in input units.
    pub bin: f64,
    /// Whether Omega hit `omega_cap`.
    pub capped: bool,
    /// The input's bounding-box diagonal (the unit of the parameters).
    pub diag: f64,
}

/// Checks the cloud for the thinning stage: enough points, finite, not all coincident.
fn check_input(cloud: &PointCloud, need: usize) -> Result<f64, MethodError> {
    let n = cloud.len();
    if n < need {
        return Err(MethodError::InvalidInput(format!(
            "{n} points; EBT needs at least {need} (n_neighbors) for its quadric fits"
        )));
    }
    if let Some(i) = cloud.positions().iter().position(|p| !p.is_finite()) {
        return Err(MethodError::InvalidInput(format!(
            "point {i} has a non-finite coordinate"
        )));
    }
    let diag = cloud.aabb().diagonal();
    if diag.is_nan() || diag <= 0.0 {
        return Err(MethodError::InvalidInput(
            "all points coincide (zero bounding-box diagonal)".into(),
        ));
    }
    Ok(diag)
}

/// Stages 1-3 of EBT on `cloud`: M's, Omega, B and the kept points. Runs on the
/// cloud moved exactly by a power of two into the working range when it lies outside
/// (`PointCloud::at_working_scale`: the quadric fits' squared coordinates neither
/// overflow nor vanish), so the kept points are the same at every scale; lengths come
/// back in the input's units, curvatures in their inverse.
pub fn thin(
    cloud: &PointCloud,
    p: &ThinningParams,
    ctx: &mut RunCtx,
) -> Result<Thinned, MethodError> {
    let Some((scaled, s)) = cloud.at_working_scale() else {
        return thin_in_range(cloud, p, ctx);
    };
    let mut t = thin_in_range(&scaled, p, ctx)?;
    let back = |x: f64, e: i32| crate::scale::times_pow2(x, e);
    t.omega = back(t.omega, -s);
    t.bin = back(t.bin, -s);
    t.diag = back(t.diag, -s);
    if let Some(c) = &mut t.curvature {
        c.m = c.m.map(|m| back(m, s));
        for q in &mut c.per_patch {
            *q = q.map(|m| back(m, s));
        }
    }
    Ok(t)
}

/// [`thin`] on a cloud already in the working range.
fn thin_in_range(
    cloud: &PointCloud,
    p: &ThinningParams,
    ctx: &mut RunCtx,
) -> Result<Thinned, MethodError> {
    p.validate()?;
    let diag = check_input(cloud, p.n_neighbors.max(3))?;
    let pts = cloud.positions();
    let eps = p.epsilon * diag;
    let cap = p.omega_cap * diag;
    let (curv, omega, bin, capped) = if p.bin_size > 0.0 {
        // B forced: Omega follows from B, no curvature estimate is needed.
        let b = p.bin_size * diag;
        (None, bound::omega_from_bin(b, p.bin_rule), b, false)
    } else {
        let index = ctx.phase("index", || PointIndex::new(pts))?;
        ctx.checkpoint()?;
        let opts = CurvatureOpts {
            n: p.n_neighbors,
            neighborhood: p.neighborhood,
            patches: p.patches,
            derivatives: p.derivatives,
            aggregation: p.aggregation,
        };
        let c = ctx.phase("fit", || curvature::estimate(pts, &index, &opts, ctx.seed))?;
        if c.per_patch.is_empty() {
            return Err(MethodError::InvalidInput(format!(
                "none of the {} local quadric fits is well conditioned (duplicate or \
                 collinear points?)",
                c.drawn
            )));
        }
        let raw = bound::omega(eps, c.sum(), p.omega_rule);
        let omega = raw.min(cap);
        (
            Some(c),
            omega,
            bound::bin_from_omega(omega, p.bin_rule),
            raw > cap,
        )
    };
    ctx.checkpoint()?;
    let binned = ctx.phase("bin", || binning::voxel_thin(pts, bin, p.tol * diag))?;
    Ok(Thinned {
        kept: binned.kept,
        curvature: curv,
        omega,
        bin,
        capped,
        diag,
    })
}

/// Inserts the thinning diagnostics (lengths as fractions of the diagonal).
pub fn thinning_diagnostics(t: &Thinned, p: &ThinningParams, d: &mut Diagnostics) {
    let mut num = |k: &str, v: f64| {
        d.insert(k.to_string(), Diagnostic::Number(v));
    };
    num("omega", t.omega / t.diag);
    num("bin_size", t.bin / t.diag);
    num("q_points", t.kept.len() as f64);
    num("omega_capped", f64::from(u8::from(t.capped)));
    if let Some(c) = &t.curvature {
        // Curvatures in 1/diag units (the inverse of the length unit).
        let s = t.diag;
        num("m1", c.m[0] * s);
        num("m2", c.m[1] * s);
        num("m3", c.m[2] * s);
        num("m_sum", c.sum() * s);
        num("patches", c.drawn as f64);
        num("patches_skipped", c.skipped as f64);
        // Both conventions and all four formulas, for the Table 1 comparison.
        let (lit, exa) = match p.derivatives {
            Derivatives::Literal => (c.sum(), 2.0 * c.m[0] + 2.0 * c.m[1] + 2.0 * c.m[2]),
            Derivatives::Exact => (0.5 * c.m[0] + 2.0 * c.m[1] + 0.5 * c.m[2], c.sum()),
        };
        let eps = p.epsilon * t.diag;
        for (name, m) in [("literal", lit), ("exact", exa)] {
            for (rule, rn) in [(OmegaRule::Eq13, "eq13"), (OmegaRule::Eq11, "eq11")] {
                let om = bound::omega(eps, m, rule);
                num(&format!("omega_{name}_{rn}"), om / t.diag);
            }
        }
        let om = bound::omega(eps, c.sum(), p.omega_rule);
        num("bin_eq1", bound::bin_from_omega(om, BinRule::Eq1) / t.diag);
        num(
            "bin_eq16",
            bound::bin_from_omega(om, BinRule::Eq16) / t.diag,
        );
    }
}

/// Distances of `pts` to `mesh`: (max, p99, RMS, share above `eps`), or `None` for an
/// empty mesh.
pub fn deviation(pts: &[DVec3], mesh: &TriMesh, eps: f64) -> Result<Option<[f64; 4]>, MethodError> {
    if mesh.n_faces() == 0 || pts.is_empty() {
        return Ok(None);
    }
    let bvh = MeshBvh::new(mesh)?;
    let mut d = bvh.distances(pts)?;
    let n = d.len() as f64;
    let rms = (d.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
    let above = d.iter().filter(|&&x| x > eps).count() as f64 / n;
    d.sort_by(f64::total_cmp);
    let rank = ((0.99 * n).ceil() as usize).clamp(1, d.len());
    Ok(Some([d[d.len() - 1], d[rank - 1], rms, above]))
}

/// Bins of the smallest-angle histogram (degrees; spec §6 item 4) and their names.
const ANGLE_BINS: [(f64, &str); 5] = [
    (12.0, "min_angle_hist_0_12"),
    (20.0, "min_angle_hist_12_20"),
    (30.0, "min_angle_hist_20_30"),
    (45.0, "min_angle_hist_30_45"),
    (f64::INFINITY, "min_angle_hist_45_60"),
];

/// Bins of the edge-length histogram (length / Omega; spec §6 item 4) and their names.
const EDGE_BINS: [(f64, &str); 4] = [
    (0.5, "edge_hist_0_050"),
    (0.75, "edge_hist_050_075"),
    (1.0 + 1e-6, "edge_hist_075_100"),
    (f64::INFINITY, "edge_hist_above_100"),
];

/// Inserts the shares of facets per smallest-angle bin and of edges (each counted once)
/// per length / Omega bin (spec §6 item 4).
fn quality_histograms(q: &[DVec3], faces: &[[u32; 3]], omega: f64, d: &mut Diagnostics) {
    if faces.is_empty() {
        return;
    }
    let mut ang = [0usize; ANGLE_BINS.len()];
    let mut keys: Vec<u64> = Vec::with_capacity(3 * faces.len());
    for f in faces {
        let [a, b, c] = f.map(|i| q[i as usize]);
        let m = geometry::min_angle(a, b, c).to_degrees();
        ang[ANGLE_BINS.iter().position(|b| m < b.0).unwrap_or(0)] += 1;
        keys.extend((0..3).map(|k| geometry::edge_key(f[k], f[(k + 1) % 3])));
    }
    // Each undirected edge once.
    keys.sort_unstable();
    keys.dedup();
    let mut edge = [0usize; EDGE_BINS.len()];
    for &k in &keys {
        let (u, v) = ((k >> 32) as usize, (k & 0xffff_ffff) as usize);
        let l = (q[u] - q[v]).length() / omega;
        edge[EDGE_BINS.iter().position(|b| l < b.0).unwrap_or(0)] += 1;
    }
    let edges = keys.len();
    let nf = faces.len() as f64;
    for (k, (_, name)) in ANGLE_BINS.iter().enumerate() {
        d.insert((*name).into(), Diagnostic::Number(ang[k] as f64 / nf));
    }
    for (k, (_, name)) in EDGE_BINS.iter().enumerate() {
        d.insert(
            (*name).into(),
            Diagnostic::Number(edge[k] as f64 / edges.max(1) as f64),
        );
    }
}

/// The `ebt` reconstructor.
#[derive(Debug, Clone, Default)]
pub struct Ebt {
    /// Parameters.
    pub params: EbtParams,
}

impl Describe for Ebt {
    const NAME: &'static str = "ebt";
    const SOURCE: &'static str = "seed 004 (Sun et al. 2001) §4-5";
    const SUMMARY: &'static str =
        "error-bounded voxel thinning (quadric curvature -> Omega -> B) and seed-grown mesh";
    type Params = EbtParams;
    const PARAMS: &'static [ParamDoc] = EBT_DOCS;

    fn from_params(params: EbtParams) -> Result<Self, MethodError> {
        params.validate()?;
        Ok(Self { params })
    }
}

impl Reconstructor for Ebt {
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
            let tp = p.thinning();
            let t = thin(cloud, &tp, ctx)?;
            let pts = cloud.positions();
            let q: Vec<DVec3> = t.kept.iter().map(|&i| pts[i as usize]).collect();
            let seed = if p.seed_point >= 0 {
                let s = p.seed_point as usize;
                if s >= pts.len() {
                    return Err(MethodError::InvalidParameter {
                        name: "seed_point".into(),
                        message: format!("index {s} is outside the {} input points", pts.len()),
                    });
                }
                // A user seed that binning dropped: the kept point nearest to it.
                Some(grow::default_seed_near(&q, pts[s]))
            } else {
                None
            };
            let theta = p.min_angle_deg.to_radians();
            let opts = grow::GrowOpts {
                omega: t.omega,
                min_angle: theta,
                ear_filling: p.ear_filling,
                ear_angle: p.ear_angle_deg.to_radians(),
                wake_deferred: p.wake_deferred,
                seed,
                crack_edge: (p.crack_closing > 0.0).then_some(p.crack_closing * t.omega),
                link_edge: p.link_edge * t.omega,
                sliver_flip: p.sliver_flip,
                // 0 = off: the floor is Rule 2's theta itself.
                sliver_angle: if p.sliver_angle_deg > 0.0 {
                    p.sliver_angle_deg.to_radians()
                } else {
                    theta
                },
            };
            let grown = {
                let _g = ctx.phase_guard("mesh");
                let c = &*ctx;
                grow::grow(&q, &opts, &mut || c.checkpoint())?
            };
            let mut faces = grown.faces;
            let mut d = Diagnostics::new();
            thinning_diagnostics(&t, &tp, &mut d);
            let num = |d: &mut Diagnostics, k: &str, v: f64| {
                d.insert(k.to_string(), Diagnostic::Number(v));
            };
            // With crack closing, R1 is checked against the closing edge.
            // With longer growth links, against the longest link edge.
            let closure = match opts.crack_edge {
                Some(e) => Some(e.max(opts.link_edge)),
                None => (p.link_edge > 1.0).then_some(opts.link_edge),
            };
            let before = validate::bad_facets_with_closure(&q, &faces, t.omega, theta, closure)?;
            if p.feature_align || p.equilateral {
                let _g = ctx.phase_guard("enhance");
                let eps = p.epsilon * t.diag;
                let cfg = enhance::SwapCfg {
                    omega: t.omega,
                    min_angle: theta,
                    eps,
                    feature_angle: p.feature_angle_deg.to_radians(),
                };
                let st = enhance::enhance(&q, &mut faces, &cfg, p.feature_align, p.equilateral);
                num(&mut d, "swaps_e21", st.feature_swaps as f64);
                num(&mut d, "swaps_e20", st.equilateral_swaps as f64);
                num(&mut d, "feature_edges", st.feature_edges as f64);
                num(&mut d, "bad_facets_before_enhance", before.total as f64);
            }
            let bad = if p.feature_align || p.equilateral {
                ctx.phase("validate", || {
                    validate::bad_facets_with_closure(&q, &faces, t.omega, theta, closure)
                })?
            } else {
                before
            };
            num(&mut d, "bad_facets", bad.total as f64);
            num(&mut d, "bad_r1_long_edge", bad.r1 as f64);
            num(&mut d, "bad_r2_small_angle", bad.r2 as f64);
            num(&mut d, "bad_r3_non_manifold", bad.r3 as f64);
            num(&mut d, "bad_overlap", bad.overlap as f64);
            let unmeshed: Vec<u32> = t
                .kept
                .iter()
                .zip(&grown.meshed)
                .filter(|(_, m)| !**m)
                .map(|(&i, _)| i)
                .collect();
            num(&mut d, "meshed", (q.len() - unmeshed.len()) as f64);
            num(&mut d, "unmeshed", unmeshed.len() as f64);
            num(&mut d, "seed_point", f64::from(t.kept[grown.seed as usize]));
            num(&mut d, "passes", grown.passes as f64);
            num(&mut d, "ears", grown.ears as f64);
            num(&mut d, "crack_facets", grown.crack_facets as f64);
            num(&mut d, "crack_flips", grown.crack_flips as f64);
            num(&mut d, "sliver_facets", grown.sliver_facets as f64);
            for (name, k) in grow::REASONS.iter().zip(grown.unmeshed_by_reason) {
                num(&mut d, &format!("unmeshed_{name}"), k as f64);
            }
            let long = faces
                .iter()
                .filter(|f| {
                    (0..3).any(|k| {
                        (q[f[k] as usize] - q[f[(k + 1) % 3] as usize]).length()
                            > t.omega * (1.0 + 1e-6)
                    })
                })
                .count();
            num(&mut d, "long_edge_facets", long as f64);
            num(&mut d, "deferrals", grown.deferrals as f64);
            quality_histograms(&q, &faces, t.omega, &mut d);
            let min_ang = faces
                .iter()
                .map(|f| geometry::min_angle(q[f[0] as usize], q[f[1] as usize], q[f[2] as usize]))
                .fold(f64::INFINITY, f64::min);
            if min_ang.is_finite() {
                num(&mut d, "min_angle_deg", min_ang.to_degrees());
            }
            let mesh = TriMesh::new(q, faces)?;
            if p.deviation {
                let eps = p.epsilon * t.diag;
                if let Some([mx, p99, rms, above]) =
                    ctx.phase("deviation", || deviation(pts, &mesh, eps))?
                {
                    num(&mut d, "dev_max", mx / t.diag);
                    num(&mut d, "dev_p99", p99 / t.diag);
                    num(&mut d, "dev_rms", rms / t.diag);
                    num(&mut d, "dev_above_eps", above);
                    num(&mut d, "dev_max_over_eps", mx / eps);
                }
            }
            Ok(Reconstruction {
                mesh,
                refused: unmeshed,
                diagnostics: d,
            })
        })
    }
}
