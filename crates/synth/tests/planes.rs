//! `planes` (seed 002's varying-angle sheets): the opening angle varies monotonically
//! from a0 to a1 along the ridge, grid ridge samples lie on the feature, and the
//! numerical closest point is never beaten by a dense set of exact surface samples.

use glam::DVec3;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reconbench_geom::PointIndex;
use reconbench_synth::Shape;
use reconbench_synth::shapes::from_spec;

fn shape() -> Box<dyn Shape> {
    from_spec("planes").unwrap()
}

#[test]
fn opening_angle_varies_from_45_to_140_degrees() {
    let s = shape();
    let f = s.feature_curves();
    assert_eq!(f.len(), 32);
    let angles: Vec<f64> = f.iter().map(|c| c.dihedral_deg).collect();
    assert!(angles.windows(2).all(|w| w[1] > w[0]), "{angles:?}");
    assert!((angles[0] - 45.0).abs() < 1e-9, "{}", angles[0]);
    assert!(angles[31] < 140.0 && angles[31] > 130.0, "{}", angles[31]);
    // At the end rulings the angle between the two sheets' normals is 180 minus the
    // opening angle: normals of the first sample row (s = w / 2000, negligible twist).
    let (nu, nv) = (41, 2001);
    let g = s.parametric_grid(nu, nv).unwrap();
    for (i, want) in [(0usize, 45.0f64), (nu - 1, 140.0)] {
        let a = g[nu + i].normal; // sheet A, row 1
        let b = g[nu + (nv - 1) * nu + i].normal; // sheet B, row 1
        let between = a.dot(b).clamp(-1.0, 1.0).acos().to_degrees();
        assert!((180.0 - between - want).abs() < 0.05, "{i}: {between}");
        let c = s.closest_point(g[nu + i].position);
        assert!((c.normal - a).length() < 1e-9);
    }
}

#[test]
fn grid_ridge_samples_lie_on_the_ridge() {
    let s = shape();
    let g = s.parametric_grid(41, 21).unwrap();
    assert_eq!(g.len(), 41 * 41);
    let on = g
        .iter()
        .filter(|x| s.feature_distance(x.position) < 1e-12)
        .count();
    assert_eq!(on, 41);
    for x in &g {
        assert!(s.distance(x.position) < 1e-12);
    }
}

#[test]
fn closest_points_beat_dense_samples() {
    let s = shape();
    let dense: Vec<DVec3> = s
        .parametric_grid(601, 301)
        .unwrap()
        .into_iter()
        .map(|x| x.position)
        .collect();
    let idx = PointIndex::new(&dense).unwrap();
    let b = s.aabb();
    let (lo, hi) = (b.min - DVec3::splat(0.1), b.max + DVec3::splat(0.1));
    let mut r = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..3000 {
        let q = lo + (hi - lo) * DVec3::new(r.random(), r.random(), r.random());
        let c = s.closest_point(q);
        let nn = idx.knn(q, 1).unwrap()[0].dist2.sqrt();
        assert!(c.distance <= nn + 1e-12, "{q}: {} > {nn}", c.distance);
        assert!(s.distance(c.point) < 1e-12, "closest point off the surface");
        // The dense grid is within half a cell diagonal of every surface point.
        assert!(nn - c.distance < 5e-3, "{q}");
    }
}
