//! Tests of `poisson` (issue 21): distance to the true sphere within a bound from the
//! grid depth, genus on a sphere and a torus, outward orientation, the
//! non-interpolating marker, trimming of the bulge over a missing half, determinism, and
//! bad input.

use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{
    Describe, Diagnostic, INTERPOLATING_DIAGNOSTIC, MethodError, Reconstruction, Reconstructor,
    RunCtx,
};
use reconbench_geom::topology::analyze;
use reconbench_recon::{Poisson, PoissonParams};
use reconbench_testkit::surfaces::Surface;

fn sphere(n: usize, seed: u64) -> PointCloud {
    let pts = Surface::Sphere(1.0).sample_uniform(n, &mut ChaCha8Rng::seed_from_u64(seed));
    let nrm = pts.iter().map(|p| p.normalize()).collect();
    PointCloud::new(pts).unwrap().with_normals(nrm).unwrap()
}

fn torus(n: usize, seed: u64) -> PointCloud {
    let pts = Surface::Torus(1.0, 0.4).sample_uniform(n, &mut ChaCha8Rng::seed_from_u64(seed));
    let nrm = pts
        .iter()
        .map(|&p| (p - DVec3::new(p.x, p.y, 0.0).normalize()).normalize())
        .collect();
    PointCloud::new(pts).unwrap().with_normals(nrm).unwrap()
}

fn params(depth: usize) -> PoissonParams {
    PoissonParams {
        depth,
        ..Default::default()
    }
}

fn run_with(c: &PointCloud, p: PoissonParams) -> Result<Reconstruction, MethodError> {
    Poisson::new(p)?.reconstruct(c, &mut RunCtx::new(3))
}

fn diag(r: &Reconstruction, k: &str) -> f64 {
    match r.diagnostics.get(k) {
        Some(Diagnostic::Number(x)) => *x,
        other => panic!("diagnostic {k}: {other:?}"),
    }
}

/// Signed volume by the divergence theorem (positive for outward faces).
fn volume(r: &Reconstruction) -> f64 {
    let v = r.mesh.vertices();
    r.mesh
        .faces()
        .iter()
        .map(|f| v[f[0] as usize].dot(v[f[1] as usize].cross(v[f[2] as usize])) / 6.0)
        .sum()
}

/// The distance of every vertex to the unit sphere is below a bound from the depth:
/// the finest cell is `h = extent / 2^depth` (extent 2 here), and the iso-surface of a
/// well-sampled sphere stays within a fraction of a cell of it.
#[test]
fn sphere_is_within_a_fraction_of_a_cell_and_genus_zero() {
    let c = sphere(4000, 1);
    for depth in [5, 6] {
        let r = run_with(&c, params(depth)).unwrap();
        // Grid of 2^depth nodes over 1.2 x the extent (just under 2 for the sample).
        let h = diag(&r, "cell_size");
        let nominal = 1.2 * 2.0 / f64::from((1u32 << depth) - 1);
        assert!(h <= nominal && h > 0.99 * nominal, "{h} vs {nominal}");
        let d: Vec<f64> = r
            .mesh
            .vertices()
            .iter()
            .map(|p| (p.length() - 1.0).abs())
            .collect();
        let max = d.iter().cloned().fold(0.0, f64::max);
        let mean = d.iter().sum::<f64>() / d.len() as f64;
        assert!(max < 0.5 * h, "depth {depth}: max {max} vs h {h}");
        assert!(mean < 0.2 * h, "depth {depth}: mean {mean} vs h {h}");
        let t = analyze(&r.mesh);
        assert!(t.watertight, "{t:?}");
        assert_eq!((t.components, t.genus), (1, Some(0)), "{t:?}");
        assert!(t.consistently_oriented);
        // Outward faces: the volume is close to 4/3 pi.
        let vol = volume(&r);
        assert!(
            (vol - 4.0 / 3.0 * std::f64::consts::PI).abs() < 0.05,
            "{vol}"
        );
        assert_eq!(diag(&r, INTERPOLATING_DIAGNOSTIC), 0.0);
        assert!(r.refused.is_empty());
    }
}

#[test]
fn torus_has_genus_one() {
    let r = run_with(&torus(5000, 2), params(6)).unwrap();
    let t = analyze(&r.mesh);
    assert!(t.watertight, "{t:?}");
    assert_eq!((t.components, t.genus), (1, Some(1)), "{t:?}");
    assert!(volume(&r) > 0.0);
}

/// A hemisphere: Poisson closes the open rim with a cap far from every sample;
/// trimming by density removes it and leaves an open surface.
#[test]
fn trimming_removes_the_bulge_over_a_missing_half() {
    let full = sphere(6000, 4);
    let keep: Vec<usize> = (0..full.len())
        .filter(|&i| full.positions()[i].z > 0.0)
        .collect();
    let pts: Vec<DVec3> = keep.iter().map(|&i| full.positions()[i]).collect();
    let nrm: Vec<DVec3> = pts.iter().map(|p| p.normalize()).collect();
    let c = PointCloud::new(pts).unwrap().with_normals(nrm).unwrap();
    // Vertices farther than 0.2 from every sample: the cap over the open rim.
    let samples = c.positions().to_vec();
    let low = |r: &Reconstruction| {
        r.mesh
            .vertices()
            .iter()
            .filter(|v| samples.iter().all(|q| q.distance(**v) > 0.2))
            .count()
    };
    let untrimmed = run_with(&c, params(5)).unwrap();
    assert!(low(&untrimmed) > 50, "no cap to trim: {}", low(&untrimmed));
    let trimmed = run_with(
        &c,
        PoissonParams {
            trim_quantile: 0.4,
            ..params(5)
        },
    )
    .unwrap();
    assert_eq!(low(&trimmed), 0);
    assert!(diag(&trimmed, "trimmed_vertices") > 0.0);
    let t = analyze(&trimmed.mesh);
    assert!(t.boundary_edges > 0 && t.non_manifold_edges == 0, "{t:?}");
}

#[test]
fn runs_are_deterministic_whatever_the_thread_count() {
    let c = sphere(2000, 5);
    let a = run_with(&c, params(5)).unwrap();
    let b = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| run_with(&c, params(5)).unwrap());
    assert_eq!(a.mesh, b.mesh);
}

fn err_text(r: Result<Reconstruction, MethodError>) -> String {
    match r {
        Err(e @ MethodError::InvalidInput(_)) => e.to_string(),
        Err(e) => panic!("wrong error kind: {e}"),
        Ok(_) => panic!("expected an error"),
    }
}

#[test]
fn bad_input_gives_named_errors() {
    let p = || params(5);
    let bare = PointCloud::new(sphere(100, 1).positions().to_vec()).unwrap();
    let e = err_text(run_with(&bare, p()));
    assert!(
        e.contains("poisson") && e.contains("needs oriented normals"),
        "{e}"
    );
    for n in 0..3 {
        let c = PointCloud::new(vec![DVec3::Y * n as f64; n])
            .unwrap()
            .with_normals(vec![DVec3::Z; n])
            .unwrap();
        assert!(err_text(run_with(&c, p())).contains("at least 3"), "{n}");
    }
    let c = PointCloud::new(vec![DVec3::ONE; 20])
        .unwrap()
        .with_normals(vec![DVec3::Z; 20])
        .unwrap();
    assert!(err_text(run_with(&c, p())).contains("distinct"));
    let line: Vec<DVec3> = (0..30).map(|i| DVec3::splat(i as f64)).collect();
    let c = PointCloud::new(line)
        .unwrap()
        .with_normals(vec![DVec3::Z; 30])
        .unwrap();
    assert!(err_text(run_with(&c, p())).contains("one line"));
    let good = sphere(1000, 2);
    let alt: Vec<DVec3> = good
        .normals()
        .unwrap()
        .iter()
        .enumerate()
        .map(|(i, &v)| if (i * 2654435761) % 7 < 3 { -v } else { v })
        .collect();
    let c = good.clone().with_normals(alt).unwrap();
    assert!(err_text(run_with(&c, p())).contains("unoriented"));
}

#[test]
fn bad_parameters_are_refused_by_name() {
    for (p, name) in [
        (params(2), "depth"),
        (params(9), "depth"),
        (
            PoissonParams {
                smoothing: -1.0,
                ..Default::default()
            },
            "smoothing",
        ),
        (
            PoissonParams {
                trim_quantile: 1.0,
                ..Default::default()
            },
            "trim_quantile",
        ),
        (
            PoissonParams {
                cg_iterations: 0,
                ..Default::default()
            },
            "cg_iterations",
        ),
    ] {
        match Poisson::from_params(p) {
            Err(MethodError::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{other:?}"),
        }
    }
}
