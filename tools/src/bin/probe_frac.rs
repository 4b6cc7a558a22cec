//! Diagnostic probe (not part of the API): `gauss-map` (k = 16, sigma = 0.6) against the
//! small-cluster fraction (W-06) and the flatness sine floor (W-18) on the grid box, the
//! random box, a Fibonacci sphere and a valence-4 apex (z = -(|x| + |y|)), grid and
//! random. Prints the evidence table of docs/methods/features.md.
//!
//! `cargo run --release -p reconbench-tools --bin probe_frac`

use reconbench_testkit::feature_fixtures as common;

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reconbench_features::{GaussMap, GaussMapParams};
use reconbench_geom::PointCloud;
use reconbench_geom::method::{FeatureClass, FeatureDetector, RunCtx};

fn apex(grid: bool, n: usize) -> Vec<DVec3> {
    let z = |x: f64, y: f64| DVec3::new(x, y, -(x.abs() + y.abs()));
    if grid {
        let m = (n as f64).sqrt() as i64 / 2;
        let h = 1.0 / m as f64;
        (-m..=m)
            .flat_map(|i| (-m..=m).map(move |j| z(i as f64 * h, j as f64 * h)))
            .collect()
    } else {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut v: Vec<DVec3> = (0..n)
            .map(|_| {
                z(
                    rng.random::<f64>() * 2.0 - 1.0,
                    rng.random::<f64>() * 2.0 - 1.0,
                )
            })
            .collect();
        v.push(DVec3::ZERO);
        v
    }
}

fn main() {
    let gb = common::grid_box(1.0, 20);
    let rb = common::random_box(1.0, 6000, 3);
    let sph = common::sphere(3000);
    println!(
        "| frac | flat_min_sine | grid box R / P / corners | random box coverage / P(2s) / corners | sphere found | apex grid / random class |"
    );
    for frac in [0.03, 0.05, 0.08, 0.10, 0.12] {
        for fms in [0.0, 0.2] {
            let d = GaussMap::new(GaussMapParams {
                min_cluster_frac: frac,
                flat_min_sine: fms,
                ..Default::default()
            });
            let run = |pts: &[DVec3]| {
                d.detect(&PointCloud::new(pts.to_vec()).unwrap(), &mut RunCtx::new(1))
                    .unwrap()
            };
            let corner_hits = |t: &common::Truth, labels: &[FeatureClass]| {
                t.corners
                    .iter()
                    .filter(|c| {
                        let i = (0..t.points.len())
                            .min_by(|&a, &b| {
                                (t.points[a] - **c)
                                    .length()
                                    .total_cmp(&(t.points[b] - **c).length())
                            })
                            .unwrap();
                        labels[i] == FeatureClass::Corner
                    })
                    .count()
            };
            let og = run(&gb.points);
            let sg = common::score(&gb, &og.labels, gb.spacing);
            let orb = run(&rb.points);
            let sr = common::score(&rb, &orb.labels, 2.0 * rb.spacing);
            let os = run(&sph);
            let nsph = os
                .labels
                .iter()
                .filter(|c| **c != FeatureClass::None)
                .count();
            let ag = apex(true, 1681);
            let oa = run(&ag);
            let ia = ag.iter().position(|p| p.length() < 1e-12).unwrap();
            let ar = apex(false, 1681);
            let oar = run(&ar);
            println!(
                "| {frac} | {fms} | {:.2} / {:.2} / {}/8 | {:.2} / {:.2} / {}/8 | {nsph} | {:?} / {:?} |",
                sg.recall_on_curve,
                sg.precision,
                corner_hits(&gb, &og.labels),
                sr.coverage,
                sr.precision,
                corner_hits(&rb, &orb.labels),
                oa.labels[ia],
                oar.labels[ar.len() - 1]
            );
        }
    }
}
