//! Diagnostic probe (not part of the API): outcome histograms of the Gauss-map test on a
//! noisy grid box (seed 002 Table 2 regime: ball noise 0.136 and 0.41 spacings = 0.4 %
//! and 1.2 % of R at the thesis's spacing 0.25, R = 8.5), split by point class (on an
//! edge, one row off, interior), for the first-pass settings and larger sigma.
//!
//! `cargo run --release -p reconbench-tools --bin probe_table2`

use reconbench_testkit::feature_fixtures as common;

use reconbench_features::{GaussMapParams, GaussWorkspace, Stage};
use reconbench_geom::spatial::PointIndex;

fn main() {
    let m = 40;
    let t = common::grid_box(1.0, m);
    let h = t.spacing;
    for rel in [0.0, 0.136, 0.41] {
        let pts = common::add_noise(&t.points, rel * h, 7);
        let index = PointIndex::new(&pts).unwrap();
        for (k, sigma, fms, frac) in [
            (20, 0.1, 0.2, 0.10),
            (20, 0.1, 0.0, 0.10),
            (20, 0.1, 0.2, 0.05),
            (20, 0.2, 0.2, 0.10),
            (20, 0.2, 0.2, 0.05),
            (20, 0.4, 0.2, 0.10),
            (16, 0.6, 0.2, 0.10),
            (10, 0.6, 0.2, 0.10),
        ] {
            let table = index.knn_all(k, true).unwrap();
            let test = GaussMapParams {
                k,
                sigma,
                flat_min_sine: fms,
                min_cluster_frac: frac,
                ..Default::default()
            }
            .test();
            let mut ws = GaussWorkspace::new();
            // class 0 on edge, 1 one row off, 2 interior; hist: flat, 0/1 clusters, 2-4, >4
            let mut hist = [[0usize; 4]; 3];
            for (i, &c) in t.points.iter().enumerate() {
                let d = t.edge_distance(c) / h;
                let cls = if d < 0.01 {
                    0
                } else if d < 1.01 {
                    1
                } else {
                    2
                };
                let o = test.test_point(&pts, pts[i], table.indices(i), sigma, &mut ws);
                let b = match (o.stage, o.clusters) {
                    (Stage::Flat, _) => 0,
                    (_, 0..=1) => 1,
                    (_, 2..=4) => 2,
                    _ => 3,
                };
                hist[cls][b] += 1;
            }
            println!(
                "noise {rel:.3} sp  k {k} sigma {sigma} fms {fms} frac {frac}: [flat, <=1, 2-4, >4] edge {:?} row1 {:?} interior {:?}",
                hist[0], hist[1], hist[2]
            );
        }
    }
}
