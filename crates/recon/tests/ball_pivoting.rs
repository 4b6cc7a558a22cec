//! Tests of `ball-pivoting` (issue 21): genus on a sphere and a torus with exact normals,
//! one boundary loop on an open sheet, the empty-ball property against brute force,
//! orientation, diagnostics against the mesh, determinism, and bad input.

use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{
    Describe, Diagnostic, MethodError, Reconstruction, Reconstructor, RunCtx,
};
use reconbench_geom::topology::{TopologyReport, analyze};
use reconbench_recon::{BallPivoting, BallPivotingParams};
use reconbench_testkit::surfaces::Surface;

fn normal_of(s: Surface, p: DVec3) -> DVec3 {
    match s {
        Surface::Sphere(_) => p.normalize(),
        Surface::Torus(rr, _) => {
            let c = DVec3::new(p.x, p.y, 0.0).normalize() * rr;
            (p - c).normalize()
        }
        Surface::Sheet { amp, .. } => {
            let (fx, fy) = (amp * p.x.cos() * p.y.cos(), -amp * p.x.sin() * p.y.sin());
            DVec3::new(-fx, -fy, 1.0).normalize()
        }
        Surface::TwoSheets { .. } => DVec3::Z,
    }
}

fn cloud(s: Surface, n: usize, seed: u64, blue: bool) -> PointCloud {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let pts = if blue {
        s.sample_blue_noise(n, &mut rng)
    } else {
        s.sample_uniform(n, &mut rng)
    };
    let nrm = pts.iter().map(|&p| normal_of(s, p)).collect();
    PointCloud::new(pts).unwrap().with_normals(nrm).unwrap()
}

fn run_with(c: &PointCloud, params: BallPivotingParams) -> Result<Reconstruction, MethodError> {
    BallPivoting::new(params)?.reconstruct(c, &mut RunCtx::new(7))
}

fn run(c: &PointCloud) -> Reconstruction {
    run_with(c, BallPivotingParams::default()).expect("reconstruction")
}

fn diag(r: &Reconstruction, k: &str) -> f64 {
    match r.diagnostics.get(k) {
        Some(Diagnostic::Number(x)) => *x,
        other => panic!("diagnostic {k}: {other:?}"),
    }
}

fn assert_clean(t: &TopologyReport) {
    assert_eq!(t.non_manifold_edges, 0, "{t:?}");
    assert!(t.consistently_oriented, "{t:?}");
    assert_eq!(t.duplicate_faces, 0, "{t:?}");
    assert_eq!(t.degenerate_faces, 0, "{t:?}");
}

/// Outward orientation: the face normals agree with the input normals at their
/// vertices (the input normals point outward).
fn assert_outward(r: &Reconstruction, c: &PointCloud) {
    let n = c.normals().unwrap();
    let bad = (0..r.mesh.n_faces())
        .filter(|&f| {
            let fnrm = r.mesh.face_cross(f);
            r.mesh.faces()[f]
                .iter()
                .any(|&v| fnrm.dot(n[v as usize]) <= 0.0)
        })
        .count();
    assert_eq!(bad, 0, "faces disagreeing with the point normals");
}

/// The diagnostics agree with the mesh's own topology report.
fn assert_diagnostics_match(r: &Reconstruction, t: &TopologyReport) {
    assert_eq!(diag(r, "boundary_edges") as usize, t.boundary_edges);
    assert_eq!(diag(r, "boundary_loops") as usize, t.n_boundary_loops());
    let per: f64 = match r.diagnostics.get("triangles_per_radius") {
        Some(Diagnostic::Series(v)) => v.iter().sum(),
        other => panic!("{other:?}"),
    };
    assert_eq!(per as usize, r.mesh.n_faces());
    // Every refused point is unreferenced and every unreferenced point refused.
    let mut used = vec![false; r.mesh.n_vertices()];
    for f in r.mesh.faces() {
        for &v in f {
            used[v as usize] = true;
        }
    }
    let unref: Vec<u32> = (0..used.len() as u32)
        .filter(|&i| !used[i as usize])
        .collect();
    assert_eq!(unref, r.refused);
}

#[test]
fn sphere_with_exact_normals_is_closed_genus_zero() {
    for (seed, blue) in [(1, true), (2, true), (3, false)] {
        let c = cloud(Surface::Sphere(1.0), 3000, seed, blue);
        let r = run(&c);
        let t = analyze(&r.mesh);
        assert_clean(&t);
        assert_outward(&r, &c);
        assert_diagnostics_match(&r, &t);
        assert_eq!(t.components, 1, "seed {seed}: {t:?}");
        assert!(t.watertight, "seed {seed} blue {blue}: {t:?}");
        assert_eq!(t.genus, Some(0), "seed {seed}");
        // Interpolating: every face vertex is an input point, almost all are used.
        assert!(r.refused.len() <= 3, "refused {}", r.refused.len());
    }
}

#[test]
fn torus_with_exact_normals_has_genus_one() {
    for (seed, blue) in [(4, true), (5, false)] {
        let c = cloud(Surface::Torus(1.0, 0.4), 4000, seed, blue);
        let r = run(&c);
        let t = analyze(&r.mesh);
        assert_clean(&t);
        assert_outward(&r, &c);
        assert_diagnostics_match(&r, &t);
        assert_eq!(t.components, 1, "{t:?}");
        assert_eq!(t.genus, Some(1), "seed {seed}: {t:?}");
        // Closed up to a few small holes where no empty ball of the largest radius
        // fits on the outer side (saddle region), reported as boundary loops.
        assert!(t.boundary_edges * 50 < t.edges, "seed {seed}: {t:?}");
    }
}

#[test]
fn open_sheet_keeps_exactly_one_boundary_loop() {
    for (seed, blue) in [(6, true), (7, false)] {
        let s = Surface::Sheet {
            size: 2.0,
            amp: 0.3,
        };
        let c = cloud(s, 2500, seed, blue);
        let r = run(&c);
        let t = analyze(&r.mesh);
        assert_clean(&t);
        assert_outward(&r, &c);
        assert_diagnostics_match(&r, &t);
        assert_eq!(t.non_manifold_edges, 0);
        assert_eq!(t.components, 1, "{t:?}");
        assert_eq!(t.n_boundary_loops(), 1, "seed {seed}: {t:?}");
        assert_eq!(t.genus, Some(0));
    }
}

/// Bernardini's invariant, checked by brute force: the ball of radius rho resting on
/// each triangle (on its outward side) holds no input point, for a single radius.
#[test]
fn every_triangle_has_an_empty_ball_brute_force() {
    let c = cloud(Surface::Sphere(1.0), 800, 9, false);
    let rho = 0.12;
    let r = run_with(
        &c,
        BallPivotingParams {
            radii: vec![rho],
            ..Default::default()
        },
    )
    .unwrap();
    assert!(r.mesh.n_faces() > 1000, "{}", r.mesh.n_faces());
    let p = c.positions();
    for f in r.mesh.faces() {
        let [a, b, d] = f.map(|v| p[v as usize]);
        let n = (b - a).cross(d - a);
        // Circumcentre and lift along the outward normal.
        let (ab, ad) = (b - a, d - a);
        let cc = a
            + (n.cross(ab) * ad.length_squared() + ad.cross(n) * ab.length_squared())
                / (2.0 * n.length_squared());
        let h2 = rho * rho - cc.distance_squared(a);
        assert!(h2 >= -1e-12, "circumradius above rho");
        let centre = cc + n.normalize() * h2.max(0.0).sqrt();
        for (i, q) in p.iter().enumerate() {
            if f.contains(&(i as u32)) {
                continue;
            }
            assert!(
                q.distance(centre) >= rho * (1.0 - 1e-6),
                "point {i} inside the ball of {f:?}"
            );
        }
    }
}

#[test]
fn runs_are_deterministic_and_follow_the_thread_count() {
    let c = cloud(Surface::Torus(1.0, 0.4), 3000, 11, false);
    let a = run(&c);
    let b = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| run(&c));
    assert_eq!(a.mesh.faces(), b.mesh.faces());
    assert_eq!(a.refused, b.refused);
}

#[test]
fn duplicates_are_refused_and_do_not_change_the_mesh() {
    let c = cloud(Surface::Sphere(1.0), 1500, 12, true);
    let base = run(&c);
    let mut pts = c.positions().to_vec();
    let mut nrm = c.normals().unwrap().to_vec();
    for i in 0..100 {
        pts.push(pts[i * 7]);
        nrm.push(nrm[i * 7]);
    }
    let d = PointCloud::new(pts).unwrap().with_normals(nrm).unwrap();
    let r = run(&d);
    assert_eq!(r.mesh.faces(), base.mesh.faces());
    assert_eq!(diag(&r, "duplicates"), 100.0);
    assert!(r.refused.len() >= 100);
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
    let d = BallPivotingParams::default;
    // No normals.
    let bare = PointCloud::new(
        Surface::Sphere(1.0).sample_uniform(100, &mut ChaCha8Rng::seed_from_u64(1)),
    )
    .unwrap();
    assert!(err_text(run_with(&bare, d())).contains("needs oriented normals"));
    // 0, 1, 2 points.
    for n in 0..3 {
        let c = PointCloud::new(vec![DVec3::X * n as f64; n])
            .unwrap()
            .with_normals(vec![DVec3::Z; n])
            .unwrap();
        assert!(err_text(run_with(&c, d())).contains("at least 3"), "{n}");
    }
    // All duplicates.
    let c = PointCloud::new(vec![DVec3::ONE; 50])
        .unwrap()
        .with_normals(vec![DVec3::Z; 50])
        .unwrap();
    assert!(err_text(run_with(&c, d())).contains("distinct"));
    // Collinear.
    let line: Vec<DVec3> = (0..50)
        .map(|i| DVec3::new(i as f64, 2.0 * i as f64, 0.0))
        .collect();
    let c = PointCloud::new(line)
        .unwrap()
        .with_normals(vec![DVec3::Z; 50])
        .unwrap();
    assert!(err_text(run_with(&c, d())).contains("one line"));
    // Unoriented normals: exact normals with random signs.
    let good = cloud(Surface::Sphere(1.0), 1000, 2, false);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let flipped: Vec<DVec3> = good
        .normals()
        .unwrap()
        .iter()
        .map(|&v| {
            if rand::RngExt::random_bool(&mut rng, 0.5) {
                -v
            } else {
                v
            }
        })
        .collect();
    let c = good.clone().with_normals(flipped).unwrap();
    assert!(err_text(run_with(&c, d())).contains("unoriented"));
    // All-zero normals.
    let c = good.clone().with_normals(vec![DVec3::ZERO; 1000]).unwrap();
    assert!(err_text(run_with(&c, d())).contains("zero"));
    // NaN cannot enter a cloud: the constructor refuses it, naming the point.
    assert!(PointCloud::new(vec![DVec3::new(f64::NAN, 0.0, 0.0)]).is_err());
}

#[test]
fn bad_parameters_are_refused_by_name() {
    for (p, name) in [
        (
            BallPivotingParams {
                radii_spacing: vec![2.0, 1.0],
                ..Default::default()
            },
            "radii_spacing",
        ),
        (
            BallPivotingParams {
                radii: vec![-1.0],
                ..Default::default()
            },
            "radii",
        ),
        (
            BallPivotingParams {
                radii_spacing: vec![],
                ..Default::default()
            },
            "radii_spacing",
        ),
        (
            BallPivotingParams {
                max_flipped_share: 1.5,
                ..Default::default()
            },
            "max_flipped_share",
        ),
    ] {
        match BallPivoting::from_params(p) {
            Err(MethodError::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{other:?}"),
        }
    }
}
