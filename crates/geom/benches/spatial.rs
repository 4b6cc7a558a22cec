//! Spatial-query benchmarks (and mesh topology analysis at scale).
//!
//! Sizes come from environment variables so that a quick run is possible:
//!
//! * `RB_BENCH_POINTS` (default 1,000,000): points for kNN-16 of every point;
//! * `RB_BENCH_TRIS` (default 200,000): triangles of the torus for MeshBvh;
//! * `RB_BENCH_QUERIES` (default 1,000,000): closest-point queries near the surface (and
//!   a tenth of that uniform in the bounding box);
//! * `RB_BENCH_TOPO_TRIS` (default 2,000,000): triangles for topology analysis.
//!
//! e.g. `RB_BENCH_POINTS=100000 RB_BENCH_QUERIES=100000 cargo bench -p reconbench-geom`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use reconbench_geom::DVec3;
use reconbench_geom::spatial::{MeshBvh, PointIndex};
use reconbench_geom::topology::{MeshTopology, analyze};
use reconbench_testkit::meshes as examples;

fn env_size(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.replace('_', "").parse().ok())
        .unwrap_or(default)
}

/// SplitMix64 uniform points in `[-1, 1]^3` (deterministic, no rand dependency).
fn random_points(n: usize, seed: u64) -> Vec<DVec3> {
    let mut s = seed;
    let mut next = move || {
        s = s.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    (0..n).map(|_| DVec3::new(next(), next(), next())).collect()
}

/// A torus grid with about `tris` triangles (aspect 5:2 between the two directions).
fn torus(tris: usize) -> reconbench_geom::TriMesh {
    let quads = (tris / 2).max(9) as f64;
    let nv = (quads / 2.5).sqrt().round().max(3.0) as usize;
    let nu = ((quads / nv as f64).round() as usize).max(3);
    examples::torus_grid(nu, nv, 0.7, 0.25)
}

fn bench_knn(c: &mut Criterion) {
    let n = env_size("RB_BENCH_POINTS", 1_000_000);
    let pts = random_points(n, 1);
    let mut g = c.benchmark_group("point_index");
    g.sample_size(10).warm_up_time(Duration::from_millis(500));
    g.bench_function(format!("build/{n}"), |b| {
        b.iter(|| PointIndex::new(black_box(&pts)).unwrap())
    });
    let idx = PointIndex::new(&pts).unwrap();
    g.bench_function(format!("knn_all_16/{n}"), |b| {
        b.iter(|| idx.knn_all(black_box(16), true).unwrap())
    });
    g.finish();
}

fn bench_bvh(c: &mut Criterion) {
    let tris = env_size("RB_BENCH_TRIS", 200_000);
    let nq = env_size("RB_BENCH_QUERIES", 1_000_000);
    let mesh = torus(tris);
    // Realistic queries (e.g. reconstructed vertices against ground truth): points near
    // the surface, offset by up to 1% of the bounding-box diagonal.
    let offsets = random_points(nq, 2);
    let queries: Vec<DVec3> = offsets
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let v = mesh.vertices()[(i * 7919) % mesh.n_vertices()];
            v + 0.01 * mesh.aabb().diagonal() * *o
        })
        .collect();
    // Uniform in the box: many queries are far from the surface and near the torus axis,
    // where a whole ring of triangles is almost equidistant (the BVH's worst case).
    let uniform = random_points(nq / 10, 3);
    let mut g = c.benchmark_group("mesh_bvh");
    g.sample_size(10).warm_up_time(Duration::from_millis(500));
    let nf = mesh.n_faces();
    g.bench_function(format!("build/{nf}"), |b| {
        b.iter(|| MeshBvh::new(black_box(&mesh)).unwrap())
    });
    let bvh = MeshBvh::new(&mesh).unwrap();
    g.bench_function(format!("closest_points_near/{nf}x{nq}"), |b| {
        b.iter(|| bvh.closest_points(black_box(&queries)).unwrap())
    });
    let nu = uniform.len();
    g.bench_function(format!("closest_points_uniform/{nf}x{nu}"), |b| {
        b.iter(|| bvh.closest_points(black_box(&uniform)).unwrap())
    });
    g.finish();
}

fn bench_topology(c: &mut Criterion) {
    let tris = env_size("RB_BENCH_TOPO_TRIS", 2_000_000);
    let mesh = torus(tris);
    let nf = mesh.n_faces();
    let mut g = c.benchmark_group("topology");
    g.sample_size(10).warm_up_time(Duration::from_millis(500));
    g.bench_function(format!("mesh_topology/{nf}"), |b| {
        b.iter(|| MeshTopology::new(black_box(&mesh)))
    });
    g.bench_function(format!("analyze/{nf}"), |b| {
        b.iter(|| analyze(black_box(&mesh)))
    });
    g.finish();
}

criterion_group!(benches, bench_knn, bench_bvh, bench_topology);
criterion_main!(benches);
