//! Tests of `poisson` (issue 21): distance to the true sphere within a bound from the
//! grid depth, screening closer than the unscreened equation, genus on a sphere and a
//! torus, outward orientation, the non-interpolating marker, trimming of the bulge over
//! a missing half, determinism for 1 and 2 threads, and bad input.

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

/// Largest and mean distance of the vertices to the unit sphere.
fn sphere_error(r: &Reconstruction) -> (f64, f64) {
    let d: Vec<f64> = r
        .mesh
        .vertices()
        .iter()
        .map(|p| (p.length() - 1.0).abs())
        .collect();
    let max = d.iter().cloned().fold(0.0, f64::max);
    (max, d.iter().sum::<f64>() / d.len() as f64)
}

/// The distance of every vertex to the unit sphere is below a bound from the depth.
/// The grid cell is `h = scale * 2 / 2^depth` (the sample's bounding cube has side just
/// under 2). The grid resolves the surface to its node spacing: a level set through
/// values sampled at the nodes is placed by linear interpolation along grid edges, so
/// an error of a fraction of `h` is what the depth buys. Bounds: every vertex within
/// half a cell, the mean within a tenth (measured: 0.28 h and 0.04 h at depth 5, 0.35 h
/// and 0.045 h at depth 6).
#[test]
fn sphere_is_within_a_fraction_of_a_cell_and_genus_zero() {
    let c = sphere(8000, 1);
    for depth in [5, 6] {
        let r = run_with(&c, params(depth)).unwrap();
        let h = diag(&r, "cell_size");
        // Side 1.1 x the bounding cube, or more to keep 2.25 cells of padding.
        let cells = f64::from(1u32 << depth);
        let nominal = 1.1f64.max(1.0 / (1.0 - 4.5 / cells)) * 2.0 / cells;
        assert!(h <= nominal && h > 0.99 * nominal, "{h} vs {nominal}");
        let (max, mean) = sphere_error(&r);
        eprintln!(
            "depth {depth}: max {:.4} h, mean {:.4} h, cycles {}, res {:e}, beta {}",
            max / h,
            mean / h,
            diag(&r, "v_cycles"),
            diag(&r, "relative_residual"),
            diag(&r, "screening_weight")
        );
        assert!(max < 0.5 * h, "depth {depth}: max {max} vs h {h}");
        assert!(mean < 0.1 * h, "depth {depth}: mean {mean} vs h {h}");
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
        assert!(diag(&r, "relative_residual") < 1e-4);
        assert!(r.refused.is_empty());
    }
}

/// Screening pins the level set to the samples: on the same input, the screened
/// surface is strictly closer to the true sphere on average (by at least 5 %) than the
/// unscreened one, and its largest error is no worse (1 % slack: the largest error
/// sits where the grid, not the equation, limits the fit).
#[test]
fn screening_brings_the_surface_closer_than_the_2006_equation() {
    let c = sphere(8000, 3);
    let screened = run_with(&c, params(5)).unwrap();
    let plain = run_with(
        &c,
        PoissonParams {
            screening: 0.0,
            ..params(5)
        },
    )
    .unwrap();
    let (smax, smean) = sphere_error(&screened);
    let (pmax, pmean) = sphere_error(&plain);
    eprintln!("screened {smax} {smean}, unscreened {pmax} {pmean}");
    assert!(
        smean < 0.95 * pmean && smax < 1.01 * pmax,
        "{smax} {smean} vs {pmax} {pmean}"
    );
    assert_eq!(diag(&plain, "screening_weight"), 0.0);
    assert_eq!(analyze(&plain.mesh).genus, Some(0));
}

#[test]
fn torus_has_genus_one() {
    let r = run_with(&torus(5000, 2), params(6)).unwrap();
    let t = analyze(&r.mesh);
    assert!(t.watertight, "{t:?}");
    assert_eq!((t.components, t.genus), (1, Some(1)), "{t:?}");
    assert!(volume(&r) > 0.0);
}

/// Root-mean-square and largest distance of the vertices to the torus of `torus()`
/// (closed form: `| (rho - 1, z) | - 0.4`).
fn torus_error(r: &Reconstruction) -> (f64, f64) {
    let d: Vec<f64> = r
        .mesh
        .vertices()
        .iter()
        .map(|p| (DVec3::new(p.x.hypot(p.y) - 1.0, p.z, 0.0).length() - 0.4).abs())
        .collect();
    let max = d.iter().cloned().fold(0.0, f64::max);
    (
        (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt(),
        max,
    )
}

/// The torus gap of issue 21 at a small scale: 20,000 uniform samples with exact
/// normals at depth 6 have about the sample spacing per cell (0.6 cells) of the
/// 100,000-point torus at depth 8. Before the tricubic vertex fit and the B-spline
/// representation of the normal field, the vertices on the cells' face and body
/// diagonals (two thirds of them, placed by a cubic through nodes `sqrt 2` or
/// `sqrt 3` cells apart) and the cell-scale noise of the point-sampled splat left the
/// surface several times farther from the truth than PoissonRecon's. Each change is
/// checked against its old behaviour on the same input, and the default against
/// absolute bounds in cells (measured: rms 0.0100 h, max 0.040 h; old 0.050 h and
/// 0.273 h).
#[test]
fn torus_vertices_are_close_with_tricubic_fit_and_smoothed_field() {
    let c = torus(20_000, 5);
    let new = run_with(&c, params(6)).unwrap();
    let cubic_edge = run_with(
        &c,
        PoissonParams {
            vertex_fit: reconbench_recon::PoissonVertexFit::EdgeCubic,
            ..params(6)
        },
    )
    .unwrap();
    let point_splat = run_with(
        &c,
        PoissonParams {
            field_smoothing: 0.0,
            ..params(6)
        },
    )
    .unwrap();
    let old = run_with(
        &c,
        PoissonParams {
            field_smoothing: 0.0,
            vertex_fit: reconbench_recon::PoissonVertexFit::EdgeCubic,
            ..params(6)
        },
    )
    .unwrap();
    let h = diag(&new, "cell_size");
    let [e_new, e_cubic, e_point, e_old] = [&new, &cubic_edge, &point_splat, &old].map(torus_error);
    eprintln!(
        "rms / max in cells: default {:.4} {:.4}, edge-cubic {:.4} {:.4}, \
         point splat {:.4} {:.4}, old {:.4} {:.4}",
        e_new.0 / h,
        e_new.1 / h,
        e_cubic.0 / h,
        e_cubic.1 / h,
        e_point.0 / h,
        e_point.1 / h,
        e_old.0 / h,
        e_old.1 / h
    );
    // The tricubic fit against the cubic on the edge's line, each field kind.
    assert!(e_new.0 < 0.7 * e_cubic.0, "{e_new:?} vs {e_cubic:?}");
    assert!(e_point.0 < 0.7 * e_old.0, "{e_point:?} vs {e_old:?}");
    // The B-spline field against the point-sampled splat, with the tricubic fit.
    assert!(e_new.0 < 0.8 * e_point.0, "{e_new:?} vs {e_point:?}");
    // Absolute bounds (the old behaviour fails both by a factor of 2.7 or more).
    assert!(e_new.0 < 0.015 * h && e_new.1 < 0.1 * h, "{e_new:?}, h {h}");
    let t = analyze(&new.mesh);
    assert!(t.watertight, "{t:?}");
    assert_eq!((t.components, t.genus), (1, Some(1)), "{t:?}");
}

/// A hemisphere: Poisson closes the open rim with a cap far from every sample (about
/// half the vertices); trimming by density removes it and leaves an open surface.
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
            trim_quantile: 0.6,
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
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run_with(&c, params(5)).unwrap())
    };
    let (a, b) = (on(1), on(2));
    assert_eq!(a.mesh, b.mesh);
    assert_eq!(diag(&a, "v_cycles"), diag(&b, "v_cycles"));
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
    // Three points of a triangle and a fourth with a zero normal: fewer than 4 used.
    let c = PointCloud::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z])
        .unwrap()
        .with_normals(vec![DVec3::Z, DVec3::Z, DVec3::Z, DVec3::ZERO])
        .unwrap();
    assert!(err_text(run_with(&c, p())).contains("at least 4"));
    // A planar patch (a degenerate box): no solid to bound.
    let plane: Vec<DVec3> = (0..100)
        .map(|i| DVec3::new((i % 10) as f64, (i / 10) as f64 * 0.7, 0.0))
        .collect();
    let c = PointCloud::new(plane)
        .unwrap()
        .with_normals(vec![DVec3::Z; 100])
        .unwrap();
    assert!(err_text(run_with(&c, p())).contains("one plane"));
    // NaN in a position or a normal is refused when the cloud is built or run.
    let mut pts = sphere(100, 1).positions().to_vec();
    pts[7].x = f64::NAN;
    assert!(PointCloud::new(pts).is_err());
    let mut nrm = sphere(100, 1).normals().unwrap().to_vec();
    nrm[3].y = f64::NAN;
    match sphere(100, 1).with_normals(nrm) {
        Err(_) => {}
        Ok(c) => {
            let e = err_text(run_with(&c, p()));
            assert!(e.contains("poisson"), "{e}");
        }
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
        (params(10), "depth"),
        (
            PoissonParams {
                screening: -1.0,
                ..Default::default()
            },
            "screening",
        ),
        (
            PoissonParams {
                scale: 0.5,
                ..Default::default()
            },
            "scale",
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
                max_cycles: 0,
                ..Default::default()
            },
            "max_cycles",
        ),
        (
            PoissonParams {
                field_smoothing: 0.3,
                ..Default::default()
            },
            "field_smoothing",
        ),
        (
            PoissonParams {
                field_smoothing: f64::NAN,
                ..Default::default()
            },
            "field_smoothing",
        ),
    ] {
        match Poisson::from_params(p) {
            Err(MethodError::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{other:?}"),
        }
    }
}
