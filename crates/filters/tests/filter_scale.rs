//! Scale robustness of the point-selecting filters (issue 28): `statistical-outliers`,
//! `grid-thinning` and `ebt-thinning` keep the same points of a cloud multiplied by a
//! power of two at any representable scale (they used to keep none at 1e200, one of a
//! subnormal cloud, or refuse every scale but the unit one).

use glam::DVec3;
use reconbench_filters::thinning::BudgetParams;
use reconbench_filters::{EbtThinning, GridThinning, StatisticalOutliers};
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Describe, Filter, RunCtx};
use reconbench_testkit::points;

/// A unit sphere sample on the dyadic grid 2^-40 plus a few far points (so the
/// outlier filter has something to remove), exact under 2^e down to e = -1030.
fn cloud() -> Vec<DVec3> {
    let g = 2f64.powi(40);
    let mut p: Vec<DVec3> = points::sphere(600, 5)
        .iter()
        .map(|p| (*p * g).round() / g)
        .collect();
    p.extend([DVec3::X * 3.0, DVec3::Y * -2.5, DVec3::Z * 4.0]);
    p
}

fn times_pow2(p: DVec3, e: i32) -> DVec3 {
    p * 2f64.powi(e / 2) * 2f64.powi(e - e / 2)
}

fn kept(f: &dyn Filter, pts: &[DVec3]) -> Vec<u32> {
    let c = PointCloud::new(pts.to_vec()).unwrap();
    let r = f
        .filter(&c, &mut RunCtx::new(1))
        .unwrap_or_else(|e| panic!("{}: {e}", f.name()));
    r.source.expect("a selecting filter names its sources")
}

#[test]
fn selecting_filters_keep_the_same_points_at_every_scale() {
    let base = cloud();
    let filters: Vec<Box<dyn Filter>> = vec![
        Box::new(StatisticalOutliers::default()),
        Box::new(GridThinning::from_params(BudgetParams { target: 200 }).unwrap()),
        Box::new(EbtThinning::default()),
    ];
    for f in &filters {
        let want = kept(f.as_ref(), &base);
        assert!(
            want.len() > 100 && want.len() < base.len(),
            "{}: kept {} of {}",
            f.name(),
            want.len(),
            base.len()
        );
        for e in [-1030, -532, -199, 266, 664, 1020] {
            let pts: Vec<DVec3> = base.iter().map(|&p| times_pow2(p, e)).collect();
            assert_eq!(kept(f.as_ref(), &pts), want, "{} at 2^{e}", f.name());
        }
    }
}
