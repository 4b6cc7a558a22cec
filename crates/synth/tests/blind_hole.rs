//! `cube-with-blind-hole` (seed 002's cube with hole, §10.2): closed-form distances,
//! inside test, and a grid with samples exactly on every feature curve.

use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use reconbench_synth::Shape;
use reconbench_synth::shapes::from_spec;

fn shape() -> Box<dyn Shape> {
    from_spec("cube-with-blind-hole").unwrap()
}

/// Natural units (half side 1) -> unit diagonal.
fn s() -> f64 {
    1.0 / (2.0 * 3f64.sqrt())
}

#[test]
fn closed_form_distances_and_inside() {
    let sh = shape();
    let k = s();
    // Centre of the hole at mid depth: the wall is 0.5 away, the floor (z = 0) 0.5.
    let q = DVec3::new(0.0, 0.0, 0.5) * k;
    assert!((sh.distance(q) - 0.5 * k).abs() < 1e-14);
    assert!(!sh.is_inside(q), "the hole is outside the solid");
    // Just below the floor: inside, 0.1 from the floor.
    let q = DVec3::new(0.1, 0.0, -0.1) * k;
    assert!(sh.is_inside(q));
    assert!((sh.distance(q) - 0.1 * k).abs() < 1e-14);
    // Above the hole, outside the cube: the top rim is the closest, at distance
    // hypot(0.5 - 0.2, 0.3) (radial gap to the rim, height above the top face).
    let q = DVec3::new(0.2, 0.0, 1.3) * k;
    let c = sh.closest_point(q);
    assert!(
        (c.distance - 0.3f64.hypot(0.3) * k).abs() < 1e-14,
        "{}",
        c.distance
    );
    // Feature distance: the floor centre (the origin) is r = 0.5 from the floor rim
    // (cube edges: sqrt(2)).
    assert!((sh.feature_distance(DVec3::ZERO) - 0.5 * k).abs() < 1e-14);
    let area = 24.0 + 2.0 * std::f64::consts::PI * 0.5 * 1.0;
    assert!((sh.area() - area * k * k).abs() < 1e-12);
    assert_eq!(sh.genus(), 0);
    assert_eq!(sh.feature_curves().len(), 12 + 8 + 2);
}

#[test]
fn grid_samples_lie_on_every_feature_curve() {
    let sh = shape();
    let n = 41; // spacing h = 0.05 (natural units): 40 intervals per edge
    let g = sh.parametric_grid(n, n).unwrap();
    let h = 2.0 / 40.0 * s();
    let on: Vec<DVec3> = g
        .iter()
        .map(|x| x.position)
        .filter(|&p| sh.feature_distance(p) < 1e-12)
        .collect();
    // 12 edges x 39 interior + 8 corners; two rims of round(2 pi 0.5 / 0.05) = 63.
    assert_eq!(on.len(), 12 * 39 + 8 + 2 * 63);
    for x in &g {
        assert!(sh.distance(x.position) < 1e-12);
        assert!((x.normal.length() - 1.0).abs() < 1e-12);
    }
    // No two samples closer than 0.3 h (the rim clearance of the top-face lattice), and
    // every surface point has a sample within 1.2 h (no gaps).
    let idx = reconbench_geom::PointIndex::new(&g.iter().map(|x| x.position).collect::<Vec<_>>())
        .unwrap();
    for (i, x) in g.iter().enumerate() {
        let nn = idx.knn(x.position, 2).unwrap();
        let j = nn.iter().find(|nb| nb.index as usize != i).unwrap();
        assert!(j.dist2.sqrt() > 0.3 * h, "near-duplicate at {}", x.position);
    }
    for x in sh.sample_uniform(3000, &mut ChaCha8Rng::seed_from_u64(5)) {
        let nn = idx.knn(x.position, 1).unwrap();
        assert!(nn[0].dist2.sqrt() < 1.2 * h, "gap at {}", x.position);
    }
    assert_eq!(sh.grid_dims_for_count(g.len()), (n, n));
}

#[test]
fn half_smooth_star_has_sharp_tips_and_smooth_inner_walls() {
    // star-half: the k tips are vertical sharp edges (at radius 1), the filleted inner
    // corners are tangent (no vertical feature), the two cap rims are 90-degree loops.
    for k in [4usize, 5, 7] {
        let s = from_spec(&format!("star-half:k={k}")).unwrap();
        let curves = s.feature_curves();
        let vertical: Vec<_> = curves
            .iter()
            .filter(|c| {
                !c.is_corner
                    && c.points.len() == 2
                    && (c.points[0].truncate() - c.points[1].truncate()).length() < 1e-12
            })
            .collect();
        assert_eq!(vertical.len(), k, "k = {k}");
        let tip_r = vertical[0].points[0].truncate().length();
        for v in &vertical {
            assert!((v.points[0].truncate().length() - tip_r).abs() < 1e-12);
            assert!(v.dihedral_deg < 90.0, "tips are acute: {}", v.dihedral_deg);
        }
        // A point on the middle of a filleted inner wall is smooth: far from features
        // compared with the sampling scale.
        let g = s.sample_uniform(4000, &mut ChaCha8Rng::seed_from_u64(k as u64));
        let smooth = g
            .iter()
            .filter(|x| x.normal.z.abs() < 1e-9 && s.feature_distance(x.position) > 0.02)
            .count();
        assert!(smooth > 100, "k = {k}: {smooth}");
        assert_eq!(s.genus(), 0);
    }
}
