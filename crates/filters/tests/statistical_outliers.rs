//! `statistical-outliers` against closed-form cases and a brute-force kNN.

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reconbench_filters::statistical_outliers::mean_knn_distances;
use reconbench_filters::{StatisticalOutliers, StatisticalOutliersParams};
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Describe, Filter, RunCtx};

fn grid(n: usize, h: f64) -> Vec<DVec3> {
    (0..n * n)
        .map(|i| DVec3::new((i % n) as f64 * h, (i / n) as f64 * h, 0.0))
        .collect()
}

fn run(points: Vec<DVec3>, k: usize, std_ratio: f64) -> (PointCloud, Vec<u32>) {
    let f = StatisticalOutliers::from_params(StatisticalOutliersParams { k, std_ratio }).unwrap();
    let cloud = PointCloud::new(points).unwrap();
    let r = f.filter(&cloud, &mut RunCtx::new(1)).unwrap();
    (r.cloud, r.source.unwrap())
}

#[test]
fn far_points_go_and_the_grid_stays() {
    let mut pts = grid(20, 0.01);
    pts.push(DVec3::new(5.0, 5.0, 5.0));
    pts.push(DVec3::new(-4.0, 3.0, 1.0));
    let (out, src) = run(pts.clone(), 8, 2.0);
    assert_eq!(out.len(), 400);
    assert!(src.iter().all(|&i| i < 400));
    for (q, &i) in out.positions().iter().zip(&src) {
        assert_eq!(*q, pts[i as usize]);
    }
}

#[test]
fn equal_spacing_keeps_everything() {
    // Points on a circle, evenly spaced: every mean neighbour distance is the same.
    let n = 64;
    let pts: Vec<DVec3> = (0..n)
        .map(|i| {
            let a = i as f64 / n as f64 * std::f64::consts::TAU;
            DVec3::new(a.cos(), a.sin(), 0.0)
        })
        .collect();
    let (out, _) = run(pts, 2, 0.0);
    assert_eq!(out.len(), n);
}

#[test]
fn mean_distances_match_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let pts: Vec<DVec3> = (0..300)
        .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()))
        .collect();
    let k = 6;
    let got = mean_knn_distances(&pts, k).unwrap();
    for (i, p) in pts.iter().enumerate() {
        let mut d: Vec<f64> = pts
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .map(|(_, q)| p.distance(*q))
            .collect();
        d.sort_by(f64::total_cmp);
        let want = d[..k].iter().sum::<f64>() / k as f64;
        assert!((got[i] - want).abs() < 1e-12, "{i}: {} vs {want}", got[i]);
    }
}

#[test]
fn bad_parameters_and_tiny_clouds() {
    assert!(
        StatisticalOutliers::from_params(StatisticalOutliersParams {
            k: 0,
            std_ratio: 1.0
        })
        .is_err()
    );
    assert!(
        StatisticalOutliers::from_params(StatisticalOutliersParams {
            k: 3,
            std_ratio: f64::NAN
        })
        .is_err()
    );
    let (out, src) = run(vec![DVec3::ZERO], 3, 2.0);
    assert_eq!((out.len(), src), (1, vec![0]));
}
