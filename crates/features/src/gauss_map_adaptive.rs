//! `gauss-map-adaptive`: the local-adaptive refinement of the Gauss-map detector (Weber
//! 2011, ch. 3.6; seed 002 §4).
//!
//! 1. First pass: the global method with a low sigma0 and a large k0, giving an
//!    over-complete candidate set (about 10 % of the cloud in the thesis).
//! 2. Refinement, candidate by candidate in ascending index order: while at least
//!    `ceil(stop_share * |M|)` points of the candidate's neighbourhood M are candidates,
//!    make the test locally stricter (sigma *= 1.1, k -= 1) and re-test the candidate and
//!    every candidate of M with it; failures are removed (points are never added).
//!    Passes repeat until one removes nothing (or `max_outer`).
//! 3. Isolated-outlier rule: a candidate with at most one other candidate among its k0
//!    neighbours is removed.
//!
//! The re-tests of one refinement step are independent of each other, so they run in
//! parallel; the loop itself is sequential (it is order dependent by design), so results
//! do not depend on the thread count.

use std::cell::RefCell;
use std::f64::consts::FRAC_PI_2;
use std::time::Instant;

use rayon::prelude::*;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{
    Describe, Diagnostic, Diagnostics, FeatureClass, FeatureDetector, FeatureLabels, MethodError,
    ParamDoc, RunCtx, Unit,
};
use serde::{Deserialize, Serialize};

use crate::common::{bad_param, check_range, count_labels, knn_excluding_self, num};
use crate::gauss_map::{
    FLAT_DOCS, FlatReference, GaussTest, GaussWorkspace, PointOutcome, THESIS_FLAT_TAU,
    stage_counts, test_all, trivial_labels,
};

thread_local! {
    /// One Gauss-map workspace per thread for the small parallel re-test batches (no
    /// allocation per re-test once grown).
    static WORKSPACE: RefCell<GaussWorkspace> = RefCell::new(GaussWorkspace::new());
}

/// Parameters of `gauss-map-adaptive` (angles in radians; sizes in points).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GaussMapAdaptiveParams {
    /// Initial (and first-pass) neighbourhood size; thesis 20 (§3.7.4).
    pub k0: usize,
    /// Initial (and first-pass) clustering distance; thesis 0.1 (§3.7.4).
    #[serde(rename = "sigma0_rad", alias = "sigma0")]
    pub sigma0: f64,
    /// Factor applied to sigma per refinement step; thesis 1.10 ("raise sigma by 10 %").
    pub sigma_growth: f64,
    /// Decrement of k per refinement step; thesis 1.
    pub k_step: usize,
    /// Refinement continues while at least `ceil(stop_share * |M|)` neighbours are
    /// candidates; thesis 0.30.
    pub stop_share: f64,
    /// Refinement of a candidate stops once sigma would exceed this; thesis 1.2.
    #[serde(rename = "sigma_max_rad", alias = "sigma_max")]
    pub sigma_max: f64,
    /// Floor of k; thesis 8.
    pub k_min: usize,
    /// ASSUMPTION W-11: true (default) ends the loop when k would drop below `k_min`
    /// (the thesis lists "a minimal size for the neighborhood (k = 8)" among the break
    /// conditions, §3.6); false clamps k at `k_min` and lets `sigma_max` end the loop.
    pub kmin_is_break: bool,
    /// ASSUMPTION W-12: most refinement steps per candidate (30).
    pub max_inner: usize,
    /// ASSUMPTION W-12: most passes over the candidates (10).
    pub max_outer: usize,
    /// ASSUMPTION W-13: remove candidates with at most one other candidate among their k0
    /// neighbours (true).
    pub isolated_rule: bool,
    /// ASSUMPTION W-13: false (default) applies the isolated rule to the refined set all
    /// at once; true removes in ascending index order with immediate effect (cascades
    /// along open feature lines, see docs/methods/features.md).
    pub isolated_sequential: bool,
    /// ASSUMPTION W-10: false (default, literal pseudo-code) counts candidates in the
    /// fixed k0-neighbourhood; true recounts in the current-k neighbourhood with
    /// `ceil(stop_share * k)`.
    pub recount_with_current_k: bool,
    /// Flatness threshold in radians (ASSUMPTION W-05: 0.15 pi/2); negative disables it.
    #[serde(rename = "flat_tau_rad", alias = "flat_tau")]
    pub flat_tau: f64,
    /// Flatness reference line (ASSUMPTION W-04).
    pub flat_reference: FlatReference,
    /// ASSUMPTION W-18: sine floor for triangles in the flatness statistic (default 0.2,
    /// a deviation; 0 = all triangles, spec-literal).
    pub flat_min_sine: f64,
    /// Minimum cluster size as a fraction of the normals (ASSUMPTION W-06: 0.10).
    pub min_cluster_frac: f64,
    /// Minimum cluster size in normals (ASSUMPTION W-06: 3).
    pub min_cluster_abs: usize,
    /// Fewest surviving clusters for a feature (thesis: 2).
    pub min_clusters: usize,
    /// Most surviving clusters for a feature (thesis: 4).
    pub max_clusters: usize,
    /// Degenerate-triangle threshold (ASSUMPTION W-02: 1e-6).
    #[serde(alias = "eps_deg")]
    pub eps_sine: f64,
}

impl Default for GaussMapAdaptiveParams {
    fn default() -> Self {
        Self {
            k0: 20,
            sigma0: 0.1,
            sigma_growth: 1.10,
            k_step: 1,
            stop_share: 0.30,
            sigma_max: 1.2,
            k_min: 8,
            // ASSUMPTION W-11: k_min is a break condition (seed 002 thesis §3.6). With
            // the clamp reading (false) sigma climbs to 1.2 and merges the sheets of
            // ridges below ~70 degrees (angle sweep, docs/methods/features.md).
            kmin_is_break: true,
            max_inner: 30,
            max_outer: 10,
            isolated_rule: true,
            isolated_sequential: false,
            recount_with_current_k: false,
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

impl GaussMapAdaptiveParams {
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
        if self.k0 < 2 {
            return Err(bad_param(
                "k0",
                format!("must be at least 2, got {}", self.k0),
            ));
        }
        if self.k_min < 2 || self.k_min > self.k0 {
            return Err(bad_param(
                "k_min",
                format!("must be in [2, k0 = {}], got {}", self.k0, self.k_min),
            ));
        }
        check_range("sigma0_rad", self.sigma0, 0.0, FRAC_PI_2)?;
        check_range("sigma_max_rad", self.sigma_max, 0.0, FRAC_PI_2)?;
        check_range("sigma_growth", self.sigma_growth, 1.0, 10.0)?;
        check_range("stop_share", self.stop_share, 0.0, 1.0)?;
        if !self.flat_tau.is_finite() {
            return Err(bad_param("flat_tau_rad", "must be finite"));
        }
        if self.max_inner > u16::MAX as usize - 1 {
            return Err(bad_param(
                "max_inner",
                format!("must be below {}", u16::MAX),
            ));
        }
        self.test().validate()
    }

    /// The refinement schedule: `(k, sigma)` of steps 1, 2, ... (seed 002 §4.3 lines
    /// 11-12): sigma *= growth and k -= k_step until k would drop below `k_min` (or, with
    /// `kmin_is_break = false`, clamped there; ASSUMPTION W-11), sigma exceeds
    /// `sigma_max` or `max_inner` steps.
    pub fn schedule(&self, k0_eff: usize) -> Vec<(usize, f64)> {
        let mut out = Vec::new();
        let (mut k, mut sigma) = (k0_eff, self.sigma0);
        let k_min = self.k_min.min(k0_eff);
        for _ in 0..self.max_inner {
            sigma *= self.sigma_growth;
            if k < k_min + self.k_step {
                if self.kmin_is_break && self.k_step > 0 {
                    break;
                }
                k = k_min.max(k.saturating_sub(self.k_step));
            } else {
                k -= self.k_step;
            }
            if sigma > self.sigma_max {
                break;
            }
            out.push((k, sigma));
        }
        out
    }
}

/// The `gauss-map-adaptive` detector.
#[derive(Debug, Clone, Default)]
pub struct GaussMapAdaptive {
    /// Parameters.
    pub params: GaussMapAdaptiveParams,
}

impl GaussMapAdaptive {
    /// A detector with `params`.
    pub fn new(params: GaussMapAdaptiveParams) -> Self {
        Self { params }
    }
}

/// Number of candidates refined between two time-budget checkpoints.
const CHECK_EVERY: usize = 64;

/// Refinement steps whose passed outcomes are memoised per candidate (one byte each).
const MEMO_STEPS: usize = 64;

/// Class of a passed Gauss-map test from its surviving cluster count (ASSUMPTION W-09:
/// up to 2 = edge, more = corner), as in [`GaussTest::test_point`].
fn class_of(clusters: u32) -> FeatureClass {
    if clusters <= 2 {
        FeatureClass::Edge
    } else {
        FeatureClass::Corner
    }
}

impl Describe for GaussMapAdaptive {
    const NAME: &'static str = "gauss-map-adaptive";
    const SOURCE: &'static str = "seed 002 §4";
    const SUMMARY: &'static str =
        "Gauss-map clustering, local-adaptive refinement (Weber 2011 ch. 3.6)";
    type Params = GaussMapAdaptiveParams;
    const PARAMS: &'static [ParamDoc] = &[
        ParamDoc::new("k0", Unit::Count, "initial neighbourhood size (thesis 20)"),
        ParamDoc::new(
            "sigma0_rad",
            Unit::Rad,
            "initial clustering distance (thesis 0.1)",
        ),
        ParamDoc::new(
            "sigma_growth",
            Unit::None,
            "factor on sigma per refinement step (thesis 1.1)",
        ),
        ParamDoc::new(
            "k_step",
            Unit::Count,
            "decrement of k per refinement step (thesis 1)",
        ),
        ParamDoc::new(
            "stop_share",
            Unit::Fraction,
            "refine while this share of the neighbours are candidates (thesis 0.30)",
        ),
        ParamDoc::new(
            "sigma_max_rad",
            Unit::Rad,
            "refinement stops once sigma would exceed this (thesis 1.2)",
        ),
        ParamDoc::new("k_min", Unit::Count, "floor of k (thesis 8)"),
        ParamDoc::new(
            "kmin_is_break",
            Unit::Flag,
            "ASSUMPTION W-11: end the loop (true, default: thesis break condition) or clamp (false) at k_min",
        ),
        ParamDoc::new(
            "max_inner",
            Unit::Count,
            "ASSUMPTION W-12: most refinement steps per candidate",
        ),
        ParamDoc::new(
            "max_outer",
            Unit::Count,
            "ASSUMPTION W-12: most passes over the candidates",
        ),
        ParamDoc::new(
            "isolated_rule",
            Unit::Flag,
            "ASSUMPTION W-13: drop candidates with at most one candidate neighbour",
        ),
        ParamDoc::new(
            "isolated_sequential",
            Unit::Flag,
            "ASSUMPTION W-13: apply the isolated rule in index order with immediate effect (cascades along lines) instead of all at once",
        ),
        ParamDoc::new(
            "recount_with_current_k",
            Unit::Flag,
            "ASSUMPTION W-10: count candidates in the current-k neighbourhood",
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

    fn from_params(params: GaussMapAdaptiveParams) -> Result<Self, MethodError> {
        params.validate()?;
        Ok(Self { params })
    }
}

impl FeatureDetector for GaussMapAdaptive {
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
        let table = knn_excluding_self(points, p.k0, ctx)?;
        let k0 = table.k;
        let test = p.test();

        // 1. First pass: global method with (k0, sigma0).
        let first = test_all(points, &table, k0, p.sigma0, &test, "first-pass", ctx)?;
        let mut cand: Vec<bool> = first
            .iter()
            .map(|o| o.class != FeatureClass::None)
            .collect();
        let mut class: Vec<FeatureClass> = first.iter().map(|o| o.class).collect();
        let mut clusters: Vec<u32> = first.iter().map(|o| o.clusters).collect();
        let first_count = cand.iter().filter(|&&c| c).count();

        // 2. Refinement.
        let t0 = Instant::now();
        let schedule = p.schedule(k0);
        // Exact memo of passed re-tests: the outcome of the test of q at step s depends
        // only on (q, s) (q's first k_s neighbours and sigma_s are fixed), so every
        // (q, s) is computed at most once. memo[slot(q) * S + s] = surviving clusters of
        // the passed test (0 = not yet tested; a failed test removes q for good). Only
        // the first MEMO_STEPS steps are memoised (steps beyond are re-run).
        let memo_steps = schedule.len().min(MEMO_STEPS);
        let mut slot: Vec<u32> = vec![u32::MAX; n];
        let mut n_slots = 0u32;
        for (i, _) in cand.iter().enumerate().filter(|(_, c)| **c) {
            slot[i] = n_slots;
            n_slots += 1;
        }
        let mut memo: Vec<u8> = vec![0; n_slots as usize * memo_steps];
        let memo_at = |q: usize, s: usize| -> Option<usize> {
            (s < memo_steps).then(|| slot[q] as usize * memo_steps + s)
        };
        let mut removed_per_pass = Vec::new();
        let mut tests_run = 0usize;
        let mut tests_skipped = 0usize;
        let mut batch: Vec<u32> = Vec::with_capacity(k0 + 1);
        let mut results: Vec<PointOutcome> = Vec::with_capacity(k0 + 1);
        for _pass in 0..p.max_outer {
            let mut removed = 0usize;
            let snapshot: Vec<usize> = (0..n).filter(|&i| cand[i]).collect();
            for (ci, &c) in snapshot.iter().enumerate() {
                if ci % CHECK_EVERY == 0 {
                    ctx.checkpoint()?;
                }
                if !cand[c] {
                    continue;
                }
                let row = table.indices(c);
                let mut k_cur = k0;
                let mut step = 0usize;
                loop {
                    // ASSUMPTION W-10: the counting neighbourhood M is fixed at k0 (literal
                    // pseudo-code) unless `recount_with_current_k`.
                    let m = if p.recount_with_current_k {
                        &row[..k_cur]
                    } else {
                        row
                    };
                    let thr = (p.stop_share * m.len() as f64).ceil() as usize;
                    let count = m.iter().filter(|&&q| cand[q as usize]).count();
                    if count < thr || step >= schedule.len() {
                        break;
                    }
                    let (k, sigma) = schedule[step];
                    let s = step;
                    step += 1;
                    k_cur = k;
                    // Re-test c and every still-candidate neighbour with (k, sigma); a
                    // memoised pass replays its stored outcome.
                    batch.clear();
                    for q in std::iter::once(c as u32).chain(m.iter().copied()) {
                        let qi = q as usize;
                        if !cand[qi] {
                            continue;
                        }
                        match memo_at(qi, s).map(|a| memo[a]) {
                            Some(cl) if cl > 0 => {
                                tests_skipped += 1;
                                clusters[qi] = u32::from(cl);
                                class[qi] = class_of(u32::from(cl));
                            }
                            _ => batch.push(q),
                        }
                    }
                    tests_run += batch.len();
                    batch
                        .par_iter()
                        .map(|&q| {
                            let q = q as usize;
                            let nb = &table.indices(q)[..k];
                            WORKSPACE.with_borrow_mut(|ws| {
                                test.test_point(points, points[q], nb, sigma, ws)
                            })
                        })
                        .collect_into_vec(&mut results);
                    for (&q, o) in batch.iter().zip(&results) {
                        let q = q as usize;
                        clusters[q] = o.clusters;
                        if o.class == FeatureClass::None {
                            cand[q] = false;
                            class[q] = FeatureClass::None;
                            removed += 1;
                        } else {
                            class[q] = o.class;
                            if let (Some(a), Ok(cl)) = (memo_at(q, s), u8::try_from(o.clusters)) {
                                memo[a] = cl;
                            }
                        }
                    }
                }
            }
            removed_per_pass.push(removed as f64);
            if removed == 0 {
                break;
            }
        }
        ctx.record_phase("refine", t0.elapsed().as_secs_f64());

        // 3. ASSUMPTION W-13: isolated-outlier rule on the k0-neighbourhood (self
        // excluded). Default: evaluated on the candidate set left by the refinement, all
        // at once. `isolated_sequential` removes in ascending index order with immediate
        // effect, which cascades: the end point of an open line has one candidate
        // neighbour, its removal isolates the next point, and so on, erasing whole
        // feature lines when k0 is small (measured: 35 of 41 ridge points of a grid wedge
        // at k0 = 8).
        let mut isolated = 0usize;
        if p.isolated_rule {
            ctx.phase("isolated", || {
                let snapshot = cand.clone();
                let others = |c: usize, set: &[bool]| {
                    table
                        .indices(c)
                        .iter()
                        .filter(|&&q| set[q as usize])
                        .count()
                };
                for c in 0..n {
                    let isolated_now = if p.isolated_sequential {
                        cand[c] && others(c, &cand) <= 1
                    } else {
                        snapshot[c] && others(c, &snapshot) <= 1
                    };
                    if isolated_now {
                        cand[c] = false;
                        class[c] = FeatureClass::None;
                        isolated += 1;
                    }
                }
            });
        }

        let mut diagnostics = Diagnostics::new();
        num(&mut diagnostics, "points", n as f64);
        num(&mut diagnostics, "k0_effective", k0 as f64);
        stage_counts(&first, "first_pass_", &mut diagnostics);
        num(&mut diagnostics, "first_pass_features", first_count as f64);
        num(
            &mut diagnostics,
            "first_pass_share",
            first_count as f64 / n as f64,
        );
        num(&mut diagnostics, "passes", removed_per_pass.len() as f64);
        diagnostics.insert(
            "removed_per_pass".into(),
            Diagnostic::Series(removed_per_pass),
        );
        num(&mut diagnostics, "retests", tests_run as f64);
        num(&mut diagnostics, "retests_skipped", tests_skipped as f64);
        num(&mut diagnostics, "isolated_removed", isolated as f64);
        count_labels(&class, &mut diagnostics);
        Ok(FeatureLabels {
            labels: class,
            scores: Some(clusters.iter().map(|&c| f64::from(c)).collect()),
            diagnostics,
        })
    }
}
