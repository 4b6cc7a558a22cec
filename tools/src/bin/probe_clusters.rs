//! Diagnostic probe (not part of the API): prints the Gauss-map cluster sizes at chosen
//! points of the grid box and the random box, to study the small-cluster threshold
//! (docs/methods/features.md, W-06).
//!
//! `cargo run --release -p reconbench-tools --bin probe_clusters`

use reconbench_testkit::feature_fixtures as common;

use glam::DVec3;
use reconbench_features::AverageLinkage;
use reconbench_geom::spatial::PointIndex;

fn sizes_at(points: &[DVec3], i: usize, k: usize, sigma: f64) -> (usize, Vec<u32>) {
    let index = PointIndex::new(points).unwrap();
    let table = index.knn_all(k, true).unwrap();
    let p = points[i];
    let nb: Vec<DVec3> = table
        .indices(i)
        .iter()
        .map(|&j| points[j as usize] - p)
        .collect();
    let mut lines = Vec::new();
    for a in 0..nb.len() {
        for b in a + 1..nb.len() {
            let n = nb[a].cross(nb[b]);
            if n.length() > 1e-6 * nb[a].length() * nb[b].length() {
                lines.push(n.normalize());
            }
        }
    }
    let mut ws = AverageLinkage::new();
    ws.load(&lines);
    let mut s = ws.cut(sigma).to_vec();
    s.sort_unstable_by(|a, b| b.cmp(a));
    (lines.len(), s)
}

fn main() {
    let g = common::grid_box(1.0, 20);
    let find = |pts: &[DVec3], q: DVec3| {
        (0..pts.len())
            .min_by(|&a, &b| (pts[a] - q).length().total_cmp(&(pts[b] - q).length()))
            .unwrap()
    };
    for (name, q) in [
        ("mid-edge", DVec3::new(0.5, 0.0, 0.0)),
        ("edge 0.3", DVec3::new(0.3, 0.0, 0.0)),
        ("corner", DVec3::ZERO),
        ("near-corner edge", DVec3::new(0.05, 0.0, 0.0)),
        ("one row off edge", DVec3::new(0.5, 0.05, 0.0)),
    ] {
        let i = find(&g.points, q);
        let (l, s) = sizes_at(&g.points, i, 16, 0.6);
        println!("grid  {name:18} L={l:4} sizes {:?}", s);
    }
    let r = common::random_box(1.0, 6000, 3);
    let mut shown = 0;
    for i in 0..r.points.len() {
        if r.edge_distance(r.points[i]) < 0.1 * r.spacing && shown < 6 {
            let (l, s) = sizes_at(&r.points, i, 16, 0.6);
            println!(
                "random edge d={:.4} L={l:4} sizes {:?}",
                r.edge_distance(r.points[i]) / r.spacing,
                s
            );
            shown += 1;
        }
    }
}
