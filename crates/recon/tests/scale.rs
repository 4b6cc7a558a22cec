//! Scale robustness of `ufm`, `ufm-mesh`, `cocone`, `tight-cocone`, `hc-it`, `ebt`,
//! `priority-front`, `ball-pivoting` and `poisson`: a cloud multiplied by a power of two
//! gives the same faces on the input's own points, at any representable scale; decimal scales
//! give a closed mesh; nothing hangs or collapses to an empty success.

use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_geom::method::Diagnostic;
use reconbench_geom::method::{NormalEstimator, Reconstructor, RunCtx};
use reconbench_recon::{
    BallPivoting, BallPivotingParams, Cocone, Ebt, HcIt, Poisson, PoissonParams, PriorityFront,
    TightCocone, Ufm, UfmMesh, UfmMeshParams,
};
use reconbench_testkit::points as samples;

/// A sphere sample on the dyadic grid 2^-40 (exact under 2^e down to e = -1030).
fn sphere() -> Vec<DVec3> {
    let g = 2f64.powi(40);
    samples::sphere(400, 7)
        .iter()
        .map(|p| (*p * g).round() / g)
        .collect()
}

fn times_pow2(p: DVec3, e: i32) -> DVec3 {
    let h = e / 2;
    p * 2f64.powi(h) * 2f64.powi(e - h)
}

fn ufm_faces(pts: &[DVec3]) -> Vec<[u32; 3]> {
    let cloud = PointCloud::new(pts.to_vec()).unwrap();
    let r = Ufm::default()
        .reconstruct(&cloud, &mut RunCtx::new(1))
        .unwrap_or_else(|e| panic!("ufm: {e}"));
    assert_eq!(r.mesh.vertices(), pts, "vertices are the input points");
    r.mesh.faces().to_vec()
}

#[test]
fn ufm_is_the_same_at_every_power_of_two_scale() {
    let base = sphere();
    let want = ufm_faces(&base);
    assert!(
        want.len() >= 2 * base.len() - 4 - 20,
        "{} faces",
        want.len()
    );
    for e in [-1030, -532, -199, 266, 664, 1022] {
        let pts: Vec<DVec3> = base.iter().map(|&p| times_pow2(p, e)).collect();
        assert_eq!(ufm_faces(&pts), want, "2^{e}");
    }
}

#[test]
fn ufm_and_ufm_mesh_work_at_decimal_extremes() {
    let base = sphere();
    let est = UfmMesh::new(UfmMeshParams::default()).unwrap();
    for f in [1e-300, 1e-160, 1e-60, 1e80, 1e200, 1e300] {
        let pts: Vec<DVec3> = base.iter().map(|&p| p * f).collect();
        assert!(ufm_faces(&pts).len() > base.len(), "{f:e}");
        let cloud = PointCloud::new(pts).unwrap();
        let n = est.estimate(&cloud, &mut RunCtx::new(1)).unwrap();
        for (v, p) in n.normals.iter().zip(&base) {
            assert!((v.length() - 1.0).abs() < 1e-9, "{f:e}");
            // Sphere: the normal is radial (up to orientation).
            assert!(v.dot(p.normalize()).abs() > 0.9, "{f:e}");
        }
    }
}

fn others() -> Vec<Box<dyn Reconstructor>> {
    vec![
        Box::new(Cocone::default()),
        Box::new(TightCocone::default()),
        Box::new(HcIt::default()),
        Box::new(Ebt::default()),
        Box::new(PriorityFront::default()),
    ]
}

fn faces(m: &dyn Reconstructor, pts: &[DVec3]) -> Vec<[u32; 3]> {
    let cloud = PointCloud::new(pts.to_vec()).unwrap();
    let r = m
        .reconstruct(&cloud, &mut RunCtx::new(1))
        .unwrap_or_else(|e| panic!("{}: {e}", m.name()));
    assert!(
        r.mesh.n_faces() > 0,
        "{}: empty mesh returned as success",
        m.name()
    );
    for v in r.mesh.vertices() {
        assert!(
            pts.contains(v),
            "{}: vertex {v} is not an input point",
            m.name()
        );
    }
    r.mesh.faces().to_vec()
}

#[test]
fn delaunay_and_sweep_reconstructors_are_the_same_at_every_power_of_two_scale() {
    let base = sphere();
    for m in others() {
        let want = faces(m.as_ref(), &base);
        for e in [-1030, -532, 266, 1022] {
            let pts: Vec<DVec3> = base.iter().map(|&p| times_pow2(p, e)).collect();
            assert_eq!(faces(m.as_ref(), &pts), want, "{} at 2^{e}", m.name());
        }
    }
}

#[test]
fn delaunay_and_sweep_reconstructors_never_return_an_empty_success() {
    let base = sphere();
    for m in others() {
        for f in [1e-300, 1e-60, 1e200, 1.7e308] {
            let pts: Vec<DVec3> = base.iter().map(|&p| p * f).collect();
            faces(m.as_ref(), &pts);
        }
    }
}

/// The sphere sample with its exact outward normals, multiplied by `f`.
fn oriented(pts: &[DVec3], f: impl Fn(DVec3) -> DVec3) -> PointCloud {
    let nrm = pts.iter().map(|p| p.normalize()).collect();
    PointCloud::new(pts.iter().map(|&p| f(p)).collect())
        .unwrap()
        .with_normals(nrm)
        .unwrap()
}

fn number(r: &reconbench_geom::method::Reconstruction, k: &str) -> f64 {
    match r.diagnostics.get(k) {
        Some(Diagnostic::Number(x)) => *x,
        other => panic!("diagnostic {k}: {other:?}"),
    }
}

#[test]
fn ball_pivoting_is_the_same_at_every_scale() {
    let base = sphere();
    let bp = BallPivoting::default();
    let run = |c: &PointCloud| {
        bp.reconstruct(c, &mut RunCtx::new(1))
            .unwrap_or_else(|e| panic!("ball-pivoting: {e}"))
    };
    let want = run(&oriented(&base, |p| p));
    assert!(
        want.mesh.n_faces() > base.len(),
        "{} faces",
        want.mesh.n_faces()
    );
    let spacing = number(&want, "spacing");
    for e in [-1030, -199, 266, 1022] {
        let c = oriented(&base, |p| times_pow2(p, e));
        let r = run(&c);
        assert_eq!(r.mesh.faces(), want.mesh.faces(), "2^{e}");
        assert_eq!(r.mesh.vertices(), c.positions(), "2^{e}: the input points");
    }
    for f in [1e-60, 1e80] {
        let c = oriented(&base, |p| p * f);
        let r = run(&c);
        // Decimal factors round the points, so a few pivots may differ; the mesh is
        // still the sphere's, and the spacing is reported in the cloud's units.
        let n = r.mesh.n_faces() as f64;
        assert!(
            (n / want.mesh.n_faces() as f64 - 1.0).abs() < 0.05,
            "{f:e}: {n} faces"
        );
        assert_eq!(r.mesh.vertices(), c.positions(), "{f:e}");
        let sp = number(&r, "spacing");
        assert!(
            (sp / (spacing * f) - 1.0).abs() < 1e-9,
            "{f:e}: spacing {sp:e}"
        );
    }
    // Explicit radii are in the cloud's units: the same ball, moved with the cloud.
    let radius = 3.0 * spacing;
    let explicit = |f: f64| {
        let p = BallPivotingParams {
            radii: vec![radius * f],
            ..Default::default()
        };
        BallPivoting::new(p)
            .unwrap()
            .reconstruct(&oriented(&base, |q| q * f), &mut RunCtx::new(1))
            .unwrap_or_else(|e| panic!("ball-pivoting radii at {f:e}: {e}"))
    };
    let at1 = explicit(1.0).mesh.n_faces() as f64;
    for f in [1e-60, 1e80] {
        let n = explicit(f).mesh.n_faces() as f64;
        assert!((n / at1 - 1.0).abs() < 0.05, "{f:e}: {n} faces of {at1}");
    }
}

#[test]
fn poisson_is_the_same_at_every_scale() {
    let base = sphere();
    let p = Poisson::new(PoissonParams {
        depth: 5,
        ..Default::default()
    })
    .unwrap();
    let run = |c: &PointCloud| {
        p.reconstruct(c, &mut RunCtx::new(1))
            .unwrap_or_else(|e| panic!("poisson: {e}"))
    };
    // 3/4 of the sphere: its largest coordinate lies in [1/2, 1), where a moved cloud
    // lands, so the unscaled run is the reference bit for bit.
    let base: Vec<DVec3> = base.iter().map(|&p| p * 0.75).collect();
    let want = run(&oriented(&base, |p| p));
    assert!(want.mesh.n_faces() > 100, "{} faces", want.mesh.n_faces());
    for e in [-1030, -199, 266, 1022] {
        let r = run(&oriented(&base, |p| times_pow2(p, e)));
        assert_eq!(r.mesh.faces(), want.mesh.faces(), "2^{e}");
        let back: Vec<DVec3> = want
            .mesh
            .vertices()
            .iter()
            .map(|&v| times_pow2(v, e))
            .collect();
        assert_eq!(r.mesh.vertices(), &back[..], "2^{e}");
        let cell = number(&r, "cell_size");
        assert_eq!(
            cell,
            number(&want, "cell_size") * 2f64.powi(e / 2) * 2f64.powi(e - e / 2)
        );
    }
    for f in [1e-60, 1e80] {
        let r = run(&oriented(&base, |p| p * f));
        // The level set of a sampled sphere of radius 0.75 f: every vertex within a
        // few grid cells of it.
        let cell = number(&r, "cell_size");
        assert!(cell > 0.0 && (cell / f) < 0.1, "{f:e}: cell {cell:e}");
        assert!(r.mesh.n_faces() > 100, "{f:e}");
        for v in r.mesh.vertices() {
            assert!(
                (v.length() - 0.75 * f).abs() < 3.0 * cell,
                "{f:e}: vertex {v}"
            );
        }
    }
}
