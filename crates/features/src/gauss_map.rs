//! `gauss-map`: sharp-feature detection by Gauss-map clustering, global method (Weber 2011,
//! ch. 3.4-3.5; seed 002 §3).
//!
//! Per point p with its k nearest other points:
//! 1. discrete Gauss map: the unit normal of every triangle (p, p_i, p_j), i < j
//!    (zero-area and near-degenerate triangles skipped);
//! 2. flatness pre-test: RMS angle of the normals about their principal line below
//!    `flat_tau` -> flat, not a feature (prunes most points before the `O(k^4)` step);
//! 3. average-linkage clustering of the normals as unoriented lines, stopped when the
//!    closest clusters are more than `sigma` apart ([`crate::clustering`]);
//! 4. clusters with fewer than `max(min_cluster_abs, ceil(min_cluster_frac * L))` lines
//!    are dropped; `min_clusters..=max_clusters` (2..=4) surviving clusters = feature:
//!    2 = edge, 3 or more = corner.
//!
//! `FeatureLabels::scores` holds the surviving cluster count per point (0 = undecidable or
//! no dominant cluster, 1 = flat or one cluster), so sweeps can re-threshold it.

use std::f64::consts::FRAC_PI_2;

use glam::{DMat3, DVec3};
use reconbench_geom::PointCloud;
use reconbench_geom::linalg::sym_eigen3;
use reconbench_geom::method::{
    Describe, Diagnostic, Diagnostics, FeatureClass, FeatureDetector, FeatureLabels, MethodError,
    ParamDoc, RunCtx, Unit,
};
use serde::{Deserialize, Serialize};

use crate::clustering::{AverageLinkage, line_distance};
use crate::common::{
    bad_param, check_range, count_labels, knn_excluding_self, num, par_map_chunked,
};

/// The thesis's flatness threshold: "15 %, about 13 degrees" read as 15 % of the largest
/// line angle pi/2, i.e. 0.2356 rad = 13.5 degrees (seed 002 §3.1).
pub const THESIS_FLAT_TAU: f64 = 0.15 * FRAC_PI_2;

/// Reference line of the flatness statistic (ASSUMPTION W-04).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FlatReference {
    /// Principal eigenvector of `sum n n^T` (sign-invariant mean line). Default.
    PrincipalAxis,
    /// The medoid line (smallest summed line distance to all others): a literal "median";
    /// costs the `O(L^2)` distance matrix for every point (no pruning benefit).
    Medoid,
    /// The mean of the normals after flipping each to the side of the principal axis
    /// (the spec's `flat_stat = std_about_mean`: the deviation is measured about the mean
    /// direction). Differs from `principal-axis` only under noise.
    Mean,
}

/// Per-point test settings shared by `gauss-map` and `gauss-map-adaptive` (everything but
/// the neighbourhood size and sigma). Built from either detector's `Params`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaussTest {
    /// Flatness threshold in radians (`None` disables the pre-test).
    pub flat_tau: Option<f64>,
    /// Flatness reference direction.
    pub flat_reference: FlatReference,
    /// Triangles whose angle at p has a sine below this are left out of the flatness
    /// statistic (not out of the clustering); 0 = all (spec-literal).
    pub flat_min_sine: f64,
    /// Minimum cluster size as a fraction of the number of lines.
    pub min_cluster_frac: f64,
    /// Minimum cluster size in lines.
    pub min_cluster_abs: usize,
    /// Fewest surviving clusters for a feature.
    pub min_clusters: usize,
    /// Most surviving clusters for a feature.
    pub max_clusters: usize,
    /// Triangles with `|n| <= eps_sine |u| |v|` (sine of the angle at p) are skipped.
    pub eps_sine: f64,
}

/// Which stage decided a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Stage {
    /// Fewer than 3 non-degenerate triangles: undecidable, not a feature.
    Degenerate,
    /// Passed the flatness pre-test: flat, not a feature.
    Flat,
    /// Clustered (a "candidate" of the pre-test).
    Clustered,
}

/// Result of the Gauss-map test of one point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PointOutcome {
    /// Class assigned.
    pub class: FeatureClass,
    /// Surviving clusters (0 when degenerate, 1 when flat).
    pub clusters: u32,
    /// Deciding stage.
    pub stage: Stage,
}

/// Per-thread buffers of the Gauss-map test (reused: no heap allocation per point once
/// grown).
#[derive(Debug, Default, Clone)]
pub struct GaussWorkspace {
    offsets: Vec<(DVec3, f64)>,
    lines: Vec<DVec3>,
    sines: Vec<f64>,
    flat_idx: Vec<usize>,
    linkage: AverageLinkage,
}

impl GaussWorkspace {
    /// Empty buffers.
    pub fn new() -> Self {
        Self::default()
    }
}

impl GaussTest {
    /// Tests point `p` against its neighbours `nbrs` (indices into `points`, p excluded)
    /// with clustering distance `sigma`.
    pub fn test_point(
        &self,
        points: &[DVec3],
        p: DVec3,
        nbrs: &[u32],
        sigma: f64,
        ws: &mut GaussWorkspace,
    ) -> PointOutcome {
        // 1. Discrete Gauss map over unordered neighbour pairs (seed 002 §3.2-3.3).
        ws.offsets.clear();
        for &j in nbrs {
            let u = points[j as usize] - p;
            let ul = u.length();
            if ul > 0.0 {
                ws.offsets.push((u, ul));
            }
        }
        ws.lines.clear();
        ws.sines.clear();
        let offs = &ws.offsets;
        for a in 0..offs.len() {
            let (u, ul) = offs[a];
            for &(v, vl) in &offs[a + 1..] {
                let n = u.cross(v);
                let nl = n.length();
                // ASSUMPTION W-02: skip (near-)collinear triples, |n| <= eps_sine |u||v|
                // (sine of the angle at p); zero-area triangles from duplicates included.
                if nl > self.eps_sine * ul * vl {
                    ws.lines.push(n / nl);
                    ws.sines.push(nl / (ul * vl));
                }
            }
        }
        let l = ws.lines.len();
        // ASSUMPTION W-03: fewer than 3 normals is undecidable -> not a feature.
        if l < 3 {
            return PointOutcome {
                class: FeatureClass::None,
                clusters: 0,
                stage: Stage::Degenerate,
            };
        }
        // 2. Flatness pre-test (seed 002 §3.4).
        let mut loaded = false;
        if let Some(tau) = self.flat_tau {
            // ASSUMPTION W-18: optionally leave skinny triangles out of the statistic.
            ws.flat_idx.clear();
            ws.flat_idx
                .extend((0..l).filter(|&j| ws.sines[j] >= self.flat_min_sine));
            if ws.flat_idx.len() < 3 {
                ws.flat_idx.clear();
                ws.flat_idx.extend(0..l);
            }
            let (lines, idx) = (&ws.lines, &ws.flat_idx);
            let f = idx.len();
            let flat = match self.flat_reference {
                FlatReference::PrincipalAxis => principal_line(idx.iter().map(|&j| lines[j]))
                    .map(|m| rms(idx.iter().map(|&j| line_distance(lines[j], m)), f) < tau),
                FlatReference::Mean => {
                    principal_line(idx.iter().map(|&j| lines[j])).and_then(|m| {
                        let s: DVec3 = idx
                            .iter()
                            .map(|&j| {
                                if lines[j].dot(m) < 0.0 {
                                    -lines[j]
                                } else {
                                    lines[j]
                                }
                            })
                            .sum();
                        let mean = s.try_normalize()?;
                        Some(rms(idx.iter().map(|&j| line_distance(lines[j], mean)), f) < tau)
                    })
                }
                FlatReference::Medoid => {
                    ws.linkage.load(lines);
                    loaded = true;
                    let lk = &ws.linkage;
                    idx.iter()
                        .map(|&i| (i, idx.iter().map(|&j| lk.distance(i, j)).sum::<f64>()))
                        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
                        .map(|(m, _)| rms(idx.iter().map(|&j| lk.distance(m, j)), f) < tau)
                }
            };
            // An eigen-solver failure (not expected for finite input) means "not flat".
            if flat == Some(true) {
                return PointOutcome {
                    class: FeatureClass::None,
                    clusters: 1,
                    stage: Stage::Flat,
                };
            }
        }
        // 3. Average-linkage clustering with the sigma cut (seed 002 §3.5), and
        // 4. ASSUMPTION W-06: "clusters containing only a few points are discarded" =
        // fewer than max(min_cluster_abs, ceil(min_cluster_frac * L)) lines.
        let min_size = (self.min_cluster_frac * l as f64)
            .ceil()
            .max(self.min_cluster_abs as f64) as usize;
        let big = if loaded {
            ws.linkage
                .cut(sigma)
                .iter()
                .filter(|&&s| s as usize >= min_size)
                .count()
        } else {
            // Exact component pruning (see `AverageLinkage::count_big`).
            ws.linkage.count_big(&ws.lines, sigma, min_size)
        };
        // ASSUMPTION W-07: zero surviving clusters (sparse normals: smooth curved region)
        // -> not a feature. ASSUMPTION W-09: 2 clusters = edge, 3 or more = corner.
        let class = if big >= self.min_clusters && big <= self.max_clusters && big > 0 {
            if big <= 2 {
                FeatureClass::Edge
            } else {
                FeatureClass::Corner
            }
        } else {
            FeatureClass::None
        };
        PointOutcome {
            class,
            clusters: big as u32,
            stage: Stage::Clustered,
        }
    }

    /// Checks the shared settings.
    pub fn validate(&self) -> Result<(), MethodError> {
        if let Some(t) = self.flat_tau {
            check_range("flat_tau_rad", t, 0.0, FRAC_PI_2)?;
        }
        check_range("min_cluster_frac", self.min_cluster_frac, 0.0, 1.0)?;
        check_range("flat_min_sine", self.flat_min_sine, 0.0, 1.0)?;
        check_range("eps_sine", self.eps_sine, 0.0, 1.0)?;
        if self.min_clusters == 0 || self.max_clusters < self.min_clusters {
            return Err(bad_param(
                "max_clusters",
                format!(
                    "need 1 <= min_clusters <= max_clusters, got {} and {}",
                    self.min_clusters, self.max_clusters
                ),
            ));
        }
        Ok(())
    }
}

/// ASSUMPTION W-04: the flatness statistic is the RMS angle about the reference line,
/// `sqrt(mean theta^2)` (a standard deviation about a known centre).
fn rms(thetas: impl Iterator<Item = f64>, l: usize) -> f64 {
    (thetas.map(|t| t * t).sum::<f64>() / l as f64).sqrt()
}

/// Principal line of unit normals: eigenvector of the largest eigenvalue of `sum n n^T`.
fn principal_line(lines: impl Iterator<Item = DVec3>) -> Option<DVec3> {
    let (mut xx, mut xy, mut xz, mut yy, mut yz, mut zz) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for n in lines {
        let n = &n;
        xx += n.x * n.x;
        xy += n.x * n.y;
        xz += n.x * n.z;
        yy += n.y * n.y;
        yz += n.y * n.z;
        zz += n.z * n.z;
    }
    let m = DMat3::from_cols(
        DVec3::new(xx, xy, xz),
        DVec3::new(xy, yy, yz),
        DVec3::new(xz, yz, zz),
    );
    sym_eigen3(m).ok().map(|e| e.vectors[2])
}

/// Parameters of `gauss-map` (lengths are unit-free: the method uses angles only).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GaussMapParams {
    /// Neighbourhood size: the k nearest *other* points (ASSUMPTION W-01). Thesis: 16 is
    /// the best general value (8 and 32 acceptable bounds); ASSUMPTION W-08 default 16.
    pub k: usize,
    /// Clustering stop distance sigma in radians, `[0, pi/2]`. ASSUMPTION W-08 default 0.6
    /// (the thesis's cube optimum; fandisk 0.7).
    #[serde(rename = "sigma_rad", alias = "sigma")]
    pub sigma: f64,
    /// Flatness threshold in radians; thesis "15 %, about 13 degrees" = 0.15 pi/2 =
    /// 0.2356 (ASSUMPTION W-05). Negative disables the pre-test (ablation; slower).
    #[serde(rename = "flat_tau_rad", alias = "flat_tau")]
    pub flat_tau: f64,
    /// Flatness reference line: `principal-axis` (default), `medoid` or `mean`
    /// (ASSUMPTION W-04).
    pub flat_reference: FlatReference,
    /// ASSUMPTION W-18 (not in the spec): triangles whose angle at p has a sine below
    /// this are left out of the flatness statistic (they stay in the clustering).
    /// Default 0.2 (a deviation, see docs/methods/features.md: it reproduces the thesis's
    /// noise-free Table 2 and keeps smooth curved regions flat); 0 is the spec-literal
    /// statistic over all triangles.
    pub flat_min_sine: f64,
    /// Clusters smaller than this fraction of the normals are dropped (ASSUMPTION W-06:
    /// 0.10; the spec's default 0.05 lets the mixed-sheet normals of regular grids form
    /// extra clusters, see docs/methods/features.md).
    pub min_cluster_frac: f64,
    /// ... or smaller than this many normals (ASSUMPTION W-06: 3).
    pub min_cluster_abs: usize,
    /// Fewest surviving clusters for a feature (thesis: 2).
    pub min_clusters: usize,
    /// Most surviving clusters for a feature (thesis: 4).
    pub max_clusters: usize,
    /// Degenerate-triangle threshold on the sine of the angle at p (ASSUMPTION W-02:
    /// 1e-6).
    #[serde(alias = "eps_deg")]
    pub eps_sine: f64,
}

impl Default for GaussMapParams {
    fn default() -> Self {
        Self {
            k: 16,
            sigma: 0.6,
            flat_tau: THESIS_FLAT_TAU,
            flat_reference: FlatReference::PrincipalAxis,
            flat_min_sine: 0.2,
            min_cluster_frac: 0.10,
            min_cluster_abs: 3,
            min_clusters: 2,
            max_clusters: 4,
            eps_sine: 1e-6,
        }
    }
}

impl GaussMapParams {
    /// The shared per-point test settings.
    pub fn test(&self) -> GaussTest {
        GaussTest {
            flat_tau: (self.flat_tau >= 0.0).then_some(self.flat_tau),
            flat_reference: self.flat_reference,
            flat_min_sine: self.flat_min_sine,
            min_cluster_frac: self.min_cluster_frac,
            min_cluster_abs: self.min_cluster_abs,
            min_clusters: self.min_clusters,
            max_clusters: self.max_clusters,
            eps_sine: self.eps_sine,
        }
    }

    /// Checks ranges.
    pub fn validate(&self) -> Result<(), MethodError> {
        if self.k < 2 {
            return Err(bad_param(
                "k",
                format!("must be at least 2, got {}", self.k),
            ));
        }
        check_range("sigma_rad", self.sigma, 0.0, FRAC_PI_2)?;
        if !self.flat_tau.is_finite() {
            return Err(bad_param("flat_tau_rad", "must be finite"));
        }
        self.test().validate()
    }
}

/// The `gauss-map` detector (global method).
#[derive(Debug, Clone, Default)]
pub struct GaussMap {
    /// Parameters.
    pub params: GaussMapParams,
}

impl GaussMap {
    /// A detector with `params`.
    pub fn new(params: GaussMapParams) -> Self {
        Self { params }
    }
}

/// Runs the Gauss-map test on every point with the first `k` neighbours of each row of
/// `table` (a kNN table excluding self), in parallel; timed as phase `phase`.
pub(crate) fn test_all(
    points: &[DVec3],
    table: &reconbench_geom::spatial::KnnTable,
    k: usize,
    sigma: f64,
    test: &GaussTest,
    phase: &str,
    ctx: &mut RunCtx,
) -> Result<Vec<PointOutcome>, MethodError> {
    let k = k.min(table.k);
    par_map_chunked(points.len(), phase, ctx, GaussWorkspace::new, |ws, i| {
        test.test_point(points, points[i], &table.indices(i)[..k], sigma, ws)
    })
}

/// Labels for clouds too small to form a triangle.
pub(crate) fn trivial_labels(n: usize, name: &str) -> FeatureLabels {
    let mut diagnostics = Diagnostics::new();
    num(&mut diagnostics, "points", n as f64);
    diagnostics.insert(
        "note".into(),
        Diagnostic::Text(format!(
            "{name}: fewer than 3 points, nothing can be a feature"
        )),
    );
    count_labels(&vec![FeatureClass::None; n], &mut diagnostics);
    FeatureLabels {
        labels: vec![FeatureClass::None; n],
        scores: Some(vec![0.0; n]),
        diagnostics,
    }
}

/// Adds the per-stage counts of `outcomes` under `prefix`.
pub(crate) fn stage_counts(outcomes: &[PointOutcome], prefix: &str, diagnostics: &mut Diagnostics) {
    let count = |s: Stage| outcomes.iter().filter(|o| o.stage == s).count() as f64;
    num(
        diagnostics,
        &format!("{prefix}candidates"),
        count(Stage::Clustered),
    );
    num(diagnostics, &format!("{prefix}flat"), count(Stage::Flat));
    num(
        diagnostics,
        &format!("{prefix}degenerate"),
        count(Stage::Degenerate),
    );
}

/// Docs of the flatness and cluster settings `gauss-map` and `gauss-map-adaptive` share.
pub(crate) const FLAT_DOCS: [ParamDoc; 8] = [
    ParamDoc::new(
        "flat_tau_rad",
        Unit::Rad,
        "flatness pre-test threshold (ASSUMPTION W-05: 0.15 pi/2); negative disables it",
    ),
    ParamDoc::new(
        "flat_reference",
        Unit::Choice,
        "flatness reference line: principal-axis, medoid or mean (ASSUMPTION W-04)",
    ),
    ParamDoc::new(
        "flat_min_sine",
        Unit::None,
        "ASSUMPTION W-18: sine floor for triangles in the flatness statistic (default 0.2, a deviation; 0 = all, spec-literal)",
    ),
    ParamDoc::new(
        "min_cluster_frac",
        Unit::Fraction,
        "drop clusters smaller than this share of the normals (ASSUMPTION W-06: 0.10)",
    ),
    ParamDoc::new(
        "min_cluster_abs",
        Unit::Count,
        "drop clusters with fewer normals (ASSUMPTION W-06: 3)",
    ),
    ParamDoc::new(
        "min_clusters",
        Unit::Count,
        "fewest surviving clusters for a feature (thesis: 2)",
    ),
    ParamDoc::new(
        "max_clusters",
        Unit::Count,
        "most surviving clusters for a feature (thesis: 4)",
    ),
    ParamDoc::new(
        "eps_sine",
        Unit::None,
        "degenerate-triangle threshold on the sine of the angle at p (ASSUMPTION W-02)",
    ),
];

impl Describe for GaussMap {
    const NAME: &'static str = "gauss-map";
    const SOURCE: &'static str = "seed 002 §3";
    const SUMMARY: &'static str = "Gauss-map clustering, global method (Weber 2011 ch. 3.4-3.5)";
    type Params = GaussMapParams;
    const PARAMS: &'static [ParamDoc] = &[
        ParamDoc::new(
            "k",
            Unit::Count,
            "neighbours, the point excluded (ASSUMPTION W-01/W-08: 16)",
        ),
        ParamDoc::new(
            "sigma_rad",
            Unit::Rad,
            "average-linkage stop distance on the Gauss sphere (ASSUMPTION W-08: 0.6)",
        ),
        FLAT_DOCS[0],
        FLAT_DOCS[1],
        FLAT_DOCS[2],
        FLAT_DOCS[3],
        FLAT_DOCS[4],
        FLAT_DOCS[5],
        FLAT_DOCS[6],
        FLAT_DOCS[7],
    ];

    fn from_params(params: GaussMapParams) -> Result<Self, MethodError> {
        params.validate()?;
        Ok(Self { params })
    }
}

impl FeatureDetector for GaussMap {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn detect(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<FeatureLabels, MethodError> {
        let p = &self.params;
        p.validate()?;
        // Scale robustness: detect on the exact power-of-two working-scale copy (labels,
        // scores and every parameter are scale-free).
        let scaled = cloud.at_working_scale();
        let cloud = scaled.as_ref().map_or(cloud, |(c, _)| c);
        let points = cloud.positions();
        let n = points.len();
        if n < 3 {
            return Ok(trivial_labels(n, self.name()));
        }
        let table = knn_excluding_self(points, p.k, ctx)?;
        let test = p.test();
        let outcomes = test_all(points, &table, table.k, p.sigma, &test, "gauss-map", ctx)?;
        let labels: Vec<FeatureClass> = outcomes.iter().map(|o| o.class).collect();
        let scores: Vec<f64> = outcomes.iter().map(|o| f64::from(o.clusters)).collect();
        let mut diagnostics = Diagnostics::new();
        num(&mut diagnostics, "points", n as f64);
        num(&mut diagnostics, "k_effective", table.k as f64);
        stage_counts(&outcomes, "", &mut diagnostics);
        count_labels(&labels, &mut diagnostics);
        Ok(FeatureLabels {
            labels,
            scores: Some(scores),
            diagnostics,
        })
    }
}
