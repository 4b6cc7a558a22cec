//! Scale robustness of `ufm`, `ufm-mesh`, `cocone`, `tight-cocone`, `hc-it` and `ebt`: a cloud multiplied by a power of two gives
//! the same faces on the input's own points, at any representable scale; decimal scales
//! give a closed mesh; nothing hangs or collapses to an empty success.

use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{NormalEstimator, Reconstructor, RunCtx};
use reconbench_recon::{Cocone, Ebt, HcIt, TightCocone, Ufm, UfmMesh, UfmMeshParams};
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
