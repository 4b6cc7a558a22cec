//! Issue 5 performance targets (2 cores):
//! * two-sided Hausdorff between a 1M-triangle mesh and the analytic sphere with 1M
//!   samples per side: < 2 s;
//! * the same mesh against a 200k-triangle reference mesh: < 3 s.
//!
//! Run with `cargo bench -p reconbench-metrics --bench distance`. Prints a phase
//! breakdown once, then lets criterion time the whole `eval_distance` call.

use reconbench_testkit::metric_fixtures as common;

use std::time::{Duration, Instant};

use common::TestSphere;
use criterion::{Criterion, criterion_group, criterion_main};
use reconbench_geom::{MeshBvh, TriMesh};
use reconbench_metrics::distance::{DistanceOptions, eval_distance};
use reconbench_metrics::eval::{MeshEvalOptions, eval_mesh};
use reconbench_metrics::sampling::sample_mesh;
use reconbench_metrics::{Reference, Report, cpu_time_seconds};
use reconbench_testkit::meshes::uv_sphere;

const SAMPLES: usize = 1_000_000;

fn opts() -> DistanceOptions {
    DistanceOptions {
        vertex_error: false,
        ..DistanceOptions::default().with_samples(SAMPLES)
    }
}

/// ~1M triangles: 2 n_lon (n_lat - 1) = 998,000.
fn recon_mesh() -> TriMesh {
    uv_sphere(500, 1000, 1.0)
}

/// Runs `f`, printing its wall and process CPU time (CPU time is the better guide on a
/// shared machine: on 2 idle cores wall ~ CPU / 2 for the parallel phases).
fn timed<T>(what: &str, f: impl FnOnce() -> T) -> T {
    let c0 = cpu_time_seconds().unwrap_or(f64::NAN);
    let t = Instant::now();
    let out = f();
    let wall = t.elapsed().as_secs_f64();
    let cpu = cpu_time_seconds().unwrap_or(f64::NAN) - c0;
    eprintln!("  {what:<40} wall {wall:7.3} s   cpu {cpu:7.2} s");
    out
}

fn breakdown(recon: &TriMesh, reference: &Reference) {
    eprintln!("[{}]", reference.name());
    let s = timed("sample R (1M)", || sample_mesh(recon, SAMPLES, 0).unwrap());
    timed("d(R->S) of 1M samples", || {
        reference.distances(&s.positions).unwrap()
    });
    let q = timed("sample S (1M)", || reference.sample(SAMPLES, 1));
    let bvh = timed("parry MeshBvh build (R)", || MeshBvh::new(recon).unwrap());
    timed("parry d(S->R) 1M, input order", || {
        bvh.closest_points(&q.positions).unwrap()
    });
    timed("parry d(S->R) 1M, Morton order", || {
        reconbench_metrics::reference::bvh_closest_coherent(&bvh, &q.positions).unwrap()
    });
    let e = timed("eval_distance (two-sided, 1M + 1M)", || {
        eval_distance(recon, reference, &opts()).unwrap()
    });
    eprintln!(
        "  hausdorff_abs {:.4e}, samples R {} + {} vertices, S {}",
        e.hausdorff_abs().unwrap(),
        e.recon_area_samples,
        e.recon_vertex_samples,
        e.reference_samples,
    );
    let _ = e.to_row();
}

fn bench(c: &mut Criterion) {
    let recon = recon_mesh();
    eprintln!(
        "recon mesh: {} faces, {} vertices; threads {}",
        recon.n_faces(),
        recon.n_vertices(),
        rayon::current_num_threads()
    );
    let sphere = TestSphere::unit();
    let analytic = Reference::analytic(&sphere);
    breakdown(&recon, &analytic);
    let full = timed("eval_mesh (all families, 1M + 1M samples)", || {
        let o = MeshEvalOptions {
            distance: opts(),
            ..MeshEvalOptions::default()
        };
        eval_mesh(&recon, &analytic, &o).unwrap()
    });
    for (k, v) in full.cost.to_row() {
        eprintln!("    {k} = {v:.3}");
    }

    let ref_mesh = timed("Reference::mesh build (200k faces)", || {
        Reference::mesh(uv_sphere(224, 448, 1.0)).unwrap()
    });
    breakdown(&recon, &ref_mesh);

    let mut g = c.benchmark_group("hausdorff_two_sided_1M_samples");
    g.sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(20));
    g.bench_function("1M_tris_vs_analytic_sphere", |b| {
        b.iter(|| eval_distance(&recon, &analytic, &opts()).unwrap())
    });
    g.bench_function("1M_tris_vs_200k_tri_mesh", |b| {
        b.iter(|| eval_distance(&recon, &ref_mesh, &opts()).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
