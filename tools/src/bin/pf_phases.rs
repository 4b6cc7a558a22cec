//! Phase split of `pf` (tree build, Morton order, kNN, fit) on N random torus points, for
//! the performance notes in docs/methods/normals.md.
//!
//! `cargo run --release -p reconbench-tools --bin pf_phases -- [N] [k] [reps] [mode]`
//!
//! `mode` 0 (default) prints the phase split; 1 runs `pf` only and 2 runs nothing after
//! generating the points (for callgrind: the difference of the two instruction counts
//! is the cost of `pf`); 3 and 4 run `wpf` and `jet` at their default k.

use std::f64::consts::TAU;
use std::time::Instant;

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{NormalEstimator, RunCtx};
use reconbench_geom::spatial::{PointIndex, morton_order};
use reconbench_normals::{
    Jet, JetParams, PlaneFit, PlaneFitParams, WeightedPlaneFit, WeightedPlaneFitParams,
};

fn torus_points(n: usize) -> Vec<DVec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    (0..n)
        .map(|_| {
            let (u, v): (f64, f64) = (rng.random_range(0.0..TAU), rng.random_range(0.0..TAU));
            let c = 1.0 + 0.4 * v.cos();
            DVec3::new(c * u.cos(), c * u.sin(), 0.4 * v.sin())
        })
        .collect()
}

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("numeric argument"))
        .collect();
    let n = args.first().copied().unwrap_or(1_000_000);
    let k = args.get(1).copied().unwrap_or(16);
    let reps = args.get(2).copied().unwrap_or(3);
    let mode = args.get(3).copied().unwrap_or(0);
    let pts = torus_points(n);
    let cloud = PointCloud::new(pts.clone()).expect("finite points");
    let pf = PlaneFit {
        params: PlaneFitParams { k, orient_k: 0 },
    };
    let est: Option<Box<dyn NormalEstimator>> = match mode {
        0 => None,
        1 => Some(Box::new(pf.clone())),
        2 => return,
        3 => Some(Box::new(WeightedPlaneFit {
            params: WeightedPlaneFitParams {
                orient_k: 0,
                ..Default::default()
            },
        })),
        _ => Some(Box::new(Jet {
            params: JetParams {
                orient_k: 0,
                ..Default::default()
            },
        })),
    };
    if let Some(e) = est {
        for _ in 0..reps {
            let mut ctx = RunCtx::new(0);
            let t = Instant::now();
            let out = e.estimate(&cloud, &mut ctx).expect("estimate");
            std::hint::black_box(&out);
            println!("{} n={n}: {:.3} s", e.name(), t.elapsed().as_secs_f64());
        }
        return;
    }
    for _ in 0..reps {
        let t = Instant::now();
        let idx = PointIndex::new(&pts).expect("index");
        let t_build = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let order = morton_order(&pts);
        let t_morton = t.elapsed().as_secs_f64();
        std::hint::black_box(&order);
        let t = Instant::now();
        let tab = idx.knn_all(k, false).expect("knn");
        let t_knn = t.elapsed().as_secs_f64();
        std::hint::black_box(&tab);
        let mut ctx = RunCtx::new(0);
        let t = Instant::now();
        let out = pf.estimate(&cloud, &mut ctx).expect("pf");
        let t_pf = t.elapsed().as_secs_f64();
        std::hint::black_box(&out);
        let phases: Vec<String> = ctx
            .phases()
            .iter()
            .map(|(p, s)| format!("{p} {s:.3}"))
            .collect();
        println!(
            "n={n} k={k}: build {t_build:.3} morton {t_morton:.3} knn_all(incl. morton) {t_knn:.3} | pf total {t_pf:.3} [{}]",
            phases.join(", ")
        );
    }
}
