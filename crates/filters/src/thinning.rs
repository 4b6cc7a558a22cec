//! Thinning filters: the error-bounded voxel thinning of EBT (seed 004, Sun et al. 2001,
//! stages 1-3) as a filter usable before any reconstructor, and its two baselines
//! without error control at an equal vertex budget (spec §5: Weir et al. 1996, Chivate &
//! Jablokow 1993):
//!
//! * `ebt-thinning`: quadric curvature -> Omega -> bin size B -> one point per bin, the
//!   one nearest the bin centre (`reconbench_recon::ebt::thin`);
//! * `random-thinning`: `target` points drawn uniformly without replacement (seeded);
//! * `grid-thinning`: a uniform grid whose cell size is chosen (bisection) so that the
//!   number of occupied cells is as close to `target` as possible; each cell keeps its
//!   point nearest the cell's centroid (the PCL VoxelGrid rule, with a real point).
//!
//! All three keep a subset of the input points, so the ground truth follows exactly.

use std::collections::HashMap;

use glam::DVec3;
use rand::SeedableRng;
use rand::seq::index;
use rand_chacha::ChaCha8Rng;
use reconbench_geom::method::{
    Describe, Diagnostic, Diagnostics, Filter, Filtered, MethodError, ParamDoc, RunCtx, Unit,
};
use reconbench_geom::{Aabb, PointCloud};
use reconbench_recon::ebt::{self, THINNING_DOCS, ThinningParams};
use serde::{Deserialize, Serialize};

/// Bisection steps of `grid-thinning` on the log of the cell size.
const GRID_STEPS: usize = 48;

fn keep(cloud: &PointCloud, kept: Vec<u32>, d: Diagnostics) -> Result<Filtered, MethodError> {
    let idx: Vec<usize> = kept.iter().map(|&i| i as usize).collect();
    Ok(Filtered {
        cloud: cloud.select(&idx)?,
        source: Some(kept),
        diagnostics: d,
    })
}

fn check_cloud(cloud: &PointCloud) -> Result<(), MethodError> {
    if cloud.is_empty() {
        return Err(MethodError::InvalidInput("the cloud has no points".into()));
    }
    if let Some(i) = cloud.positions().iter().position(|p| !p.is_finite()) {
        return Err(MethodError::InvalidInput(format!(
            "point {i} has a non-finite coordinate"
        )));
    }
    Ok(())
}

/// The `ebt-thinning` filter.
#[derive(Debug, Clone, Default)]
pub struct EbtThinning {
    /// Parameters (those of `ebt`'s thinning stage).
    pub params: ThinningParams,
}

impl Describe for EbtThinning {
    const NAME: &'static str = "ebt-thinning";
    const SOURCE: &'static str = "seed 004 (Sun et al. 2001) §4.1-4.3";
    const SUMMARY: &'static str = "error-bounded voxel thinning: quadric curvature -> Omega -> B, the point nearest each bin centre";
    type Params = ThinningParams;
    const PARAMS: &'static [ParamDoc] = THINNING_DOCS;

    fn from_params(params: ThinningParams) -> Result<Self, MethodError> {
        params.validate()?;
        Ok(Self { params })
    }
}

impl Filter for EbtThinning {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn filter(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Filtered, MethodError> {
        check_cloud(cloud)?;
        let t = ebt::thin(cloud, &self.params, ctx)?;
        let mut d = Diagnostics::new();
        ebt::thinning_diagnostics(&t, &self.params, &mut d);
        keep(cloud, t.kept, d)
    }
}

/// Parameters of the budget baselines.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BudgetParams {
    /// Points to keep (all when the cloud has fewer).
    pub target: usize,
}

impl Default for BudgetParams {
    fn default() -> Self {
        Self { target: 5000 }
    }
}

const BUDGET_DOCS: &[ParamDoc] = &[ParamDoc::new(
    "target",
    Unit::Count,
    "points to keep (the vertex budget, e.g. EBT's |Q|)",
)];

fn check_target(p: &BudgetParams) -> Result<(), MethodError> {
    if p.target == 0 {
        return Err(MethodError::InvalidParameter {
            name: "target".into(),
            message: "must be at least 1".into(),
        });
    }
    Ok(())
}

/// The `random-thinning` filter.
#[derive(Debug, Clone, Default)]
pub struct RandomThinning {
    /// Parameters.
    pub params: BudgetParams,
}

impl Describe for RandomThinning {
    const NAME: &'static str = "random-thinning";
    const SOURCE: &'static str = "baseline (seed 004 §5: random decimation)";
    const SUMMARY: &'static str = "keep `target` points drawn uniformly at random (seeded)";
    type Params = BudgetParams;
    const PARAMS: &'static [ParamDoc] = BUDGET_DOCS;

    fn from_params(params: BudgetParams) -> Result<Self, MethodError> {
        check_target(&params)?;
        Ok(Self { params })
    }
}

impl Filter for RandomThinning {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn filter(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Filtered, MethodError> {
        check_cloud(cloud)?;
        let n = cloud.len();
        let k = self.params.target.min(n);
        let mut rng = ChaCha8Rng::seed_from_u64(ctx.seed);
        let mut kept: Vec<u32> = index::sample(&mut rng, n, k)
            .into_iter()
            .map(|i| i as u32)
            .collect();
        kept.sort_unstable();
        let mut d = Diagnostics::new();
        d.insert("q_points".into(), Diagnostic::Number(k as f64));
        keep(cloud, kept, d)
    }
}

/// The `grid-thinning` filter.
#[derive(Debug, Clone, Default)]
pub struct GridThinning {
    /// Parameters.
    pub params: BudgetParams,
}

impl Describe for GridThinning {
    const NAME: &'static str = "grid-thinning";
    const SOURCE: &'static str = "baseline (seed 004 §5: uniform-grid decimation)";
    const SUMMARY: &'static str =
        "uniform grid sized for `target` occupied cells; each keeps the point nearest its centroid";
    type Params = BudgetParams;
    const PARAMS: &'static [ParamDoc] = BUDGET_DOCS;

    fn from_params(params: BudgetParams) -> Result<Self, MethodError> {
        check_target(&params)?;
        Ok(Self { params })
    }
}

/// Occupied cells of edge `h` (cell key -> (sum of positions, count)), from `lo`.
fn grid_cells(p: &[DVec3], lo: DVec3, h: f64) -> HashMap<[i64; 3], (DVec3, u32)> {
    let mut m: HashMap<[i64; 3], (DVec3, u32)> = HashMap::new();
    for &x in p {
        let c = ((x - lo) / h).floor();
        let e = m
            .entry([c.x as i64, c.y as i64, c.z as i64])
            .or_insert((DVec3::ZERO, 0));
        e.0 += x;
        e.1 += 1;
    }
    m
}

/// Keeps, per occupied cell of edge `h`, the point nearest the cell's centroid (ties to
/// the lower index); ascending indices.
pub fn grid_thin(p: &[DVec3], h: f64) -> Vec<u32> {
    let lo = Aabb::from_points(p).min;
    let cells = grid_cells(p, lo, h);
    let mut best: HashMap<[i64; 3], (u32, f64)> = HashMap::with_capacity(cells.len());
    for (i, &x) in p.iter().enumerate() {
        let c = ((x - lo) / h).floor();
        let key = [c.x as i64, c.y as i64, c.z as i64];
        let (s, n) = cells[&key];
        let d = (x - s / f64::from(n)).length_squared();
        let e = best.entry(key).or_insert((i as u32, d));
        if d < e.1 {
            *e = (i as u32, d);
        }
    }
    let mut kept: Vec<u32> = best.into_values().map(|(i, _)| i).collect();
    kept.sort_unstable();
    kept
}

impl Filter for GridThinning {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn filter(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Filtered, MethodError> {
        check_cloud(cloud)?;
        // Cells are picked on the cloud moved exactly by a power of two into the working
        // range (a subnormal cloud's diagonal would underflow to 0): the same indices
        // at every scale; `cell_size` is a fraction of the diagonal either way.
        let moved = reconbench_geom::cloud::working_scale_exponent(cloud.positions())
            .map(|s| reconbench_geom::cloud::scale_pow2(cloud.positions(), s));
        let p = moved.as_deref().unwrap_or(cloud.positions());
        let target = self.params.target;
        let bb = Aabb::from_points(p);
        let diag = bb.diagonal();
        let mut d = Diagnostics::new();
        if target >= p.len() || diag.is_nan() || diag <= 0.0 {
            let kept: Vec<u32> = if diag > 0.0 {
                (0..p.len() as u32).collect()
            } else {
                vec![0]
            };
            d.insert("q_points".into(), Diagnostic::Number(kept.len() as f64));
            return keep(cloud, kept, d);
        }
        // Bisection on log(h): the count of occupied cells falls as h grows.
        let count = |h: f64| grid_cells(p, bb.min, h).len();
        let (mut lo, mut hi) = ((diag * 1e-7).ln(), (diag * 2.0).ln());
        let mut best = (usize::MAX, hi.exp());
        for _ in 0..GRID_STEPS {
            ctx.checkpoint()?;
            let mid = 0.5 * (lo + hi);
            let c = count(mid.exp());
            let gap = c.abs_diff(target);
            if gap < best.0 {
                best = (gap, mid.exp());
            }
            if c > target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let kept = grid_thin(p, best.1);
        d.insert("cell_size".into(), Diagnostic::Number(best.1 / diag));
        d.insert("q_points".into(), Diagnostic::Number(kept.len() as f64));
        keep(cloud, kept, d)
    }
}
