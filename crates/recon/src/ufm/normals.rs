//! `ufm-mesh`: normal estimation from local mesh matching, Algorithm B of Ma's thesis,
//! chapter 4 (spec 000 §1.2.3, Eq. 4.5–4.7).
//!
//! UFM runs up to the chosen state (ASSUMPTION B-01: `final` by default, or `initial`);
//! then, per point, if at least 3 facets of its umbrella are fully matched, the normal
//! is the `M_f`-times-angle weighted average of *all* its umbrella facet normals taken in
//! the umbrella's cyclic order (Eq. 4.5/4.6); otherwise (or when the average cancels,
//! B-03) a Gaussian-weighted plane fit (Eq. 4.7, `reconbench-normals`' WPF) over the
//! points of the Delaunay triangles at the point that belong to any umbrella
//! (`DT(U)_v`, B-02). With `rings = 2` (B-05) every normal is the weighted plane fit over
//! the point and its two-ring neighbours. Optional MST orientation (Hoppe; B-04).

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{
    Describe, Diagnostic, Diagnostics, MethodError, NormalEstimator, Normals, ParamDoc, RunCtx,
    Unit,
};
use reconbench_geom::spatial::PointIndex;
use reconbench_normals::orient_mst;
use serde::{Deserialize, Serialize};

use super::engine::UfmState;
use super::facet_fit::wpf;
pub use super::facet_fit::{dtu_plane_fit, facet_average};
use super::params::{Init, UfmParams};
use super::umbrella::LinkGraph;

/// Registry name.
pub const NAME: &str = "ufm-mesh";

/// Which UFM state the normals are computed from (ASSUMPTION B-01).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum MatchState {
    /// The initial umbrellas (iteration 0).
    Initial,
    /// The state UFM stops in (the default).
    #[default]
    Final,
}

/// Parameters of [`UfmMesh`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct UfmMeshParams {
    /// ASSUMPTION B-01: UFM state used.
    pub state: MatchState,
    /// 1 = Algorithm B; 2 = the two-ring variant (ASSUMPTION B-05: weighted plane fit
    /// over the point and its two-ring neighbours).
    pub rings: u32,
    /// Neighbours of the MST orientation graph (ASSUMPTION B-04: 10); 0 leaves normals
    /// unoriented.
    pub orient_k: usize,
    /// UFM: most update iterations (A-07 iv).
    pub max_iter: usize,
    /// UFM: starting cluster of the initial umbrellas.
    pub init: Init,
    /// UFM: lock (3) facets during the update.
    pub lock_matched: bool,
}

impl Default for UfmMeshParams {
    fn default() -> Self {
        Self {
            state: MatchState::Final,
            rings: 1,
            orient_k: 10,
            max_iter: 200,
            init: Init::Gabriel,
            lock_matched: true,
        }
    }
}

/// Docs of every parameter of [`UfmMeshParams`], in `list` order.
pub const PARAM_DOCS: &[ParamDoc] = &[
    ParamDoc::new(
        "state",
        Unit::Choice,
        "B-01: UFM state the normals use: final (default) or initial",
    ),
    ParamDoc::new(
        "rings",
        Unit::Count,
        "1 = Algorithm B; 2 = two-ring weighted plane fit (B-05)",
    ),
    ParamDoc::new(
        "orient_k",
        Unit::Count,
        "neighbours of the MST orientation graph (B-04: 10); 0 leaves normals unoriented",
    ),
    ParamDoc::new(
        "max_iter",
        Unit::Count,
        "UFM: most update iterations (A-07)",
    ),
    ParamDoc::new(
        "init",
        Unit::Choice,
        "UFM: initial cluster, gabriel or delaunay",
    ),
    ParamDoc::new(
        "lock_matched",
        Unit::Flag,
        "UFM: (3) facets non-removable during the update (A-09)",
    ),
];

/// The `ufm-mesh` normal estimator.
#[derive(Debug, Clone, Default)]
pub struct UfmMesh {
    /// Parameters.
    pub params: UfmMeshParams,
}

impl UfmMesh {
    /// An estimator with validated parameters.
    pub fn new(params: UfmMeshParams) -> Result<Self, MethodError> {
        params.validate()?;
        Ok(Self { params })
    }
}

impl UfmMeshParams {
    /// Checks ranges.
    pub fn validate(&self) -> Result<(), MethodError> {
        if !(1..=2).contains(&self.rings) {
            return Err(MethodError::InvalidParameter {
                name: "rings".into(),
                message: format!("must be 1 or 2, got {}", self.rings),
            });
        }
        self.ufm().validate()
    }

    fn ufm(&self) -> UfmParams {
        UfmParams {
            max_iter: match self.state {
                MatchState::Initial => 0,
                MatchState::Final => self.max_iter,
            },
            init: self.init,
            lock_matched: self.lock_matched,
            ..UfmParams::default()
        }
    }
}

/// Which branch produced a normal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Branch {
    /// Matching-weighted facet average (Eq. 4.5).
    FacetAverage,
    /// Weighted plane fit over `DT(U)_v` (Eq. 4.7) or the two-ring set.
    PlaneFit,
    /// Degenerate neighbourhood: 10 nearest neighbours (B-02's last fallback).
    Knn,
}

/// Per-vertex result of the first pass.
struct Local {
    ring: Vec<u32>,
    normal: DVec3,
    branch: Branch,
}

/// Algorithm B on a UFM state: one normal per Delaunay vertex (unoriented) and its
/// branch. `rings` = 1 or 2.
pub fn estimate_from_state(st: &UfmState, rings: u32) -> (Vec<DVec3>, Vec<Branch>) {
    let cx = &st.cx;
    let pts = cx.dt.vertices();
    let nv = cx.n_vertices();
    let m = &st.m;
    let locals: Vec<Local> = (0..nv)
        .into_par_iter()
        .map_init(
            || (LinkGraph::default(), Vec::new(), Vec::new(), Vec::new()),
            |(g, fl, ring, q), v| {
                cx.prepare(v, g);
                let base = cx.off[v] as usize;
                let row = cx.row(v);
                g.cycle(|i| st.inu[base + i], fl, ring);
                if rings == 2 {
                    return Local {
                        ring: ring.clone(),
                        normal: DVec3::ZERO,
                        branch: Branch::PlaneFit,
                    };
                }
                let pv = pts[v];
                // Line 1-2: |U(f̄)_v| >= 3 (half the average valence).
                let ubar = fl
                    .iter()
                    .filter(|&&i| m[row[i as usize] as usize] == 3)
                    .count();
                if ubar >= 3
                    && let Some(nn) =
                        facet_average(pts, pv, ring, |j| m[row[fl[j] as usize] as usize] as f64)
                {
                    return Local {
                        ring: ring.clone(),
                        normal: nn,
                        branch: Branch::FacetAverage,
                    };
                }
                // Lines 11-12 (ASSUMPTION B-02): WPF over {v} ∪ points of DT(U)_v.
                Local {
                    ring: ring.clone(),
                    normal: dtu_plane_fit(cx, m, v, ring, q),
                    branch: Branch::PlaneFit,
                }
            },
        )
        .collect();
    let mut normals: Vec<DVec3>;
    let mut branch: Vec<Branch>;
    if rings == 2 {
        // ASSUMPTION B-05: WPF over {v} ∪ Ring2(v), Ring2 from the current umbrellas.
        let res: Vec<DVec3> = (0..nv)
            .into_par_iter()
            .map_init(Vec::new, |q: &mut Vec<u32>, v| {
                q.clear();
                q.push(v as u32);
                for &p in &locals[v].ring {
                    q.push(p);
                    q.extend_from_slice(&locals[p as usize].ring);
                }
                q.sort_unstable();
                q.dedup();
                wpf(pts, q, v as u32)
            })
            .collect();
        normals = res;
        branch = vec![Branch::PlaneFit; nv];
    } else {
        normals = locals.iter().map(|l| l.normal).collect();
        branch = locals.iter().map(|l| l.branch).collect();
    }
    // B-02's last fallback: 10 nearest neighbours for degenerate neighbourhoods.
    let bad: Vec<usize> = (0..nv).filter(|&v| normals[v] == DVec3::ZERO).collect();
    if !bad.is_empty()
        && let Ok(index) = PointIndex::new(pts)
    {
        for v in bad {
            if let Ok(nb) = index.knn(pts[v], 10) {
                let q: Vec<u32> = nb.iter().map(|x| x.index).collect();
                normals[v] = wpf(pts, &q, v as u32);
                branch[v] = Branch::Knn;
            }
        }
    }
    (normals, branch)
}

impl Describe for UfmMesh {
    const NAME: &'static str = NAME;
    const SOURCE: &'static str = "seed 000 §1.2.3";
    const SUMMARY: &'static str =
        "local-mesh matching normals (Ma 2011 ch. 4, Algorithm B) on the UFM state";
    type Params = UfmMeshParams;
    const PARAMS: &'static [ParamDoc] = PARAM_DOCS;

    fn from_params(params: UfmMeshParams) -> Result<Self, MethodError> {
        Self::new(params)
    }
}

impl NormalEstimator for UfmMesh {
    fn name(&self) -> &str {
        NAME
    }

    fn estimate(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Normals, MethodError> {
        let p = &self.params;
        p.validate()?;
        // Normals are scale-free: run at the exact working scale, nothing to map back.
        let scaled = cloud.at_working_scale();
        let input = crate::scale::working(cloud, &scaled).positions();
        let st = super::run_ufm(input, &p.ufm(), ctx)?;
        ctx.checkpoint()?;
        let (nv_normals, branch) = ctx.phase("normals", || estimate_from_state(&st, p.rings));
        let dt = &st.cx.dt;
        let mut normals: Vec<DVec3> = (0..input.len())
            .map(|i| nv_normals[dt.vertex_of_input(i) as usize])
            .collect();
        let mut d = Diagnostics::new();
        let count = |b: Branch| branch.iter().filter(|&&x| x == b).count() as f64;
        d.insert(
            "facet_average".into(),
            Diagnostic::Number(count(Branch::FacetAverage)),
        );
        d.insert(
            "plane_fit".into(),
            Diagnostic::Number(count(Branch::PlaneFit)),
        );
        d.insert(
            "knn_fallback".into(),
            Diagnostic::Number(count(Branch::Knn)),
        );
        d.insert(
            "matching".into(),
            Diagnostic::Number(100.0 * st.trace.last().copied().unwrap_or(0.0)),
        );
        d.insert(
            "iterations".into(),
            Diagnostic::Number(st.iterations as f64),
        );
        d.insert(
            "degenerate_neighbourhoods".into(),
            Diagnostic::Number(normals.iter().filter(|n| **n == DVec3::ZERO).count() as f64),
        );
        crate::scale::check_normals_not_collapsed(NAME, &normals, input)?;
        let oriented = p.orient_k > 0;
        if oriented {
            ctx.checkpoint()?;
            let r = ctx.phase("orient", || orient_mst(input, &mut normals, p.orient_k))?;
            d.insert(
                "orient_components".into(),
                Diagnostic::Number(r.components as f64),
            );
            d.insert(
                "orient_flipped".into(),
                Diagnostic::Number(r.flipped as f64),
            );
        }
        Ok(Normals {
            normals,
            oriented,
            diagnostics: d,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn facet_average_of_a_fan() {
        // A regular hexagon fan around the origin, tilted out of z = 0 on one side.
        let mut pts = crate::ufm::geometry::hexagon_fan();
        let ring: Vec<u32> = (1..=6).collect();
        let n = facet_average(&pts, DVec3::ZERO, &ring, |_| 3.0).unwrap();
        assert!((n - DVec3::Z).length() < 1e-12, "{n}");
        // Weights scale out; zero weights give no normal.
        let n2 = facet_average(&pts, DVec3::ZERO, &ring, |j| 1.0 + j as f64).unwrap();
        assert!((n2 - DVec3::Z).length() < 1e-12);
        assert!(facet_average(&pts, DVec3::ZERO, &ring, |_| 0.0).is_none());
        // Weighted towards a tilted facet: lift p1 and p2, the facet (0, p1, p2) tilts
        // and the average follows the heavier weight.
        pts[1].z = 0.5;
        pts[2].z = 0.5;
        let light = facet_average(&pts, DVec3::ZERO, &ring, |_| 1.0).unwrap();
        let heavy = facet_average(
            &pts,
            DVec3::ZERO,
            &ring,
            |j| if j == 0 { 10.0 } else { 1.0 },
        )
        .unwrap();
        assert!(heavy.dot(DVec3::Z) < light.dot(DVec3::Z), "{heavy} {light}");
        // A fan folded onto itself cancels (ASSUMPTION B-03): None.
        let pts = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::X, DVec3::Y];
        assert!(facet_average(&pts, DVec3::ZERO, &[1, 2, 3, 4], |_| 1.0).is_none());
    }
}
