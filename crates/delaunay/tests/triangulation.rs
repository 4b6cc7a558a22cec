//! Construction tests: random, degenerate and exactly co-spherical inputs, duplicates,
//! errors, and a property test against brute force.

use std::collections::BTreeSet;

use glam::DVec3;
use proptest::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reconbench_delaunay::{Delaunay, DelaunayError, DelaunayOptions, INFINITE, NO_TET};
use reconbench_testkit::points as samples;

/// Sorted vertex quadruples of the finite tetrahedra, as input indices.
fn tet_set(dt: &Delaunay) -> BTreeSet<[u32; 4]> {
    dt.tets()
        .map(|t| {
            let mut q = t.map(|v| dt.input_of_vertex(v));
            q.sort_unstable();
            q
        })
        .collect()
}

/// Build, validate, check that every input point is a vertex at the same position, and
/// that the counts agree with the facet list.
fn check(pts: &[DVec3]) -> Delaunay {
    let dt = Delaunay::new(pts).expect("triangulation");
    dt.validate().expect("valid triangulation");
    for (i, p) in pts.iter().enumerate() {
        assert_eq!(dt.vertex(dt.vertex_of_input(i)), *p, "input {i}");
    }
    let s = dt.stats();
    assert_eq!(s.tets, dt.n_tets());
    assert_eq!(s.facets, dt.facets().len());
    assert_eq!(
        s.hull_facets,
        dt.facets().iter().filter(|f| f.is_hull()).count()
    );
    assert_eq!(s.walk_fallbacks, 0);
    dt
}

/// Same triangulation whatever the insertion order (only for inputs in general position).
fn check_order_independent(pts: &[DVec3]) {
    let a = Delaunay::new(pts).unwrap();
    let opts = DelaunayOptions {
        spatial_sort: false,
        ..DelaunayOptions::default()
    };
    let b = Delaunay::with_options(pts, &opts).unwrap();
    b.validate().unwrap();
    assert_eq!(tet_set(&a), tet_set(&b));
}

fn shuffled(mut pts: Vec<DVec3>, seed: u64) -> Vec<DVec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for i in (1..pts.len()).rev() {
        let j = rng.random_range(0..=i);
        pts.swap(i, j);
    }
    pts
}

#[test]
fn single_tetrahedron_and_two() {
    let mut pts = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
    ];
    let dt = check(&pts);
    assert_eq!(dt.n_tets(), 1);
    assert_eq!(dt.n_all_tets(), 5);
    assert_eq!(dt.facets().len(), 4);
    assert!(dt.facets().iter().all(|f| f.is_hull() && f.tets[0] == 0));
    assert!((0..5).all(|t| dt.is_infinite(t) == (t > 0)));
    assert!(dt.tet_vertices(3).contains(&INFINITE));
    // (1, 1, 1) would be co-spherical with the first four: then 2 or 3 tetrahedra are
    // both Delaunay. Slightly further out the answer is 2.
    pts.push(DVec3::new(1.2, 1.2, 1.2));
    let dt = check(&pts);
    assert_eq!(dt.n_tets(), 2);
    assert_eq!(dt.facets().len(), 7);
    assert_eq!(dt.n_hull_facets(), 6);
}

#[test]
fn uniform_random() {
    let pts = samples::uniform_cube(3000, 11);
    let dt = check(&pts);
    // About 6.7 tetrahedra per point in a uniform cloud.
    let r = dt.n_tets() as f64 / pts.len() as f64;
    assert!((6.0..7.0).contains(&r), "{r}");
    check_order_independent(&samples::uniform_cube(800, 12));
}

#[test]
fn torus_surface() {
    let pts = samples::torus_surface(4000, 5);
    check(&pts);
    check_order_independent(&samples::torus_surface(1000, 6));
}

#[test]
fn nearly_cospherical_unit_vectors() {
    check(&samples::sphere(2000, 7));
}

#[test]
fn exactly_cospherical() {
    // Cube corners (±3, ±3, ±3) and the permutations of (±1, ±1, ±5): 32 points.
    let pts = samples::integer_sphere(27);
    assert_eq!(pts.len(), 32);
    check(&pts);
    // Octahedron + cube + more, radius² = 1105 (many representations).
    let pts = samples::integer_sphere(1105 * 1105 / 1105);
    assert!(pts.len() > 100);
    check(&pts);
    check(&shuffled(samples::integer_sphere(5525), 3));
    // Cube corners and octahedron vertices on the same sphere (radius² = 3·k², k = 1..):
    // (±1, ±1, ±1) and the rational-free set (±3,±3,±3)/3 cannot both be exact, so use the
    // integer sphere r² = 3·13² = 507 which contains (±13, ±13, ±13) and many others.
    let pts = samples::integer_sphere(507);
    assert!(pts.contains(&DVec3::new(13.0, 13.0, 13.0)));
    check(&pts);
    // Points on a sphere plus its centre: every tetrahedron has the centre as a vertex.
    let mut pts = samples::integer_sphere(1105);
    pts.push(DVec3::ZERO);
    let dt = check(&pts);
    let c = dt.vertex_of_input(pts.len() - 1);
    assert!(dt.tets().all(|t| t.contains(&c)));
}

#[test]
fn regular_grid() {
    let pts = samples::grid(10, 1.0);
    let dt = check(&pts);
    // A convex polytope of volume 9³ in unit cubes: every cube is split into tetrahedra.
    let six_vol: f64 = dt
        .tets()
        .map(|t| {
            let [a, b, c, d] = t.map(|v| dt.vertex(v));
            (b - a).dot((c - a).cross(d - a))
        })
        .sum();
    assert_eq!(six_vol, 6.0 * 729.0);
    check(&shuffled(samples::grid(8, 0.1), 9));
    let opts = DelaunayOptions {
        spatial_sort: false,
        ..DelaunayOptions::default()
    };
    let dt = Delaunay::with_options(&samples::grid(7, 1.0), &opts).unwrap();
    dt.validate().unwrap();
}

#[test]
fn cube_surface_grid() {
    let pts = samples::cube_surface_grid(12);
    let dt = check(&pts);
    // The hull is the cube surface: 6 faces with 12 × 12 squares, 2 triangles each.
    assert_eq!(dt.n_hull_facets(), 6 * 12 * 12 * 2);
    check(&shuffled(samples::cube_surface_grid(9), 4));
}

#[test]
fn grid_in_two_parallel_planes_and_a_line() {
    // Two parallel square grids plus collinear points along an axis.
    let mut pts = Vec::new();
    for x in 0..8 {
        for y in 0..8 {
            pts.push(DVec3::new(x as f64, y as f64, 0.0));
            pts.push(DVec3::new(x as f64, y as f64, 3.0));
        }
    }
    for z in 1..3 {
        pts.push(DVec3::new(3.5, 3.5, z as f64));
    }
    check(&pts);
}

#[test]
fn duplicates_are_merged() {
    let base = samples::uniform_cube(500, 21);
    let mut pts = base.clone();
    for i in (0..500).step_by(7) {
        pts.push(base[i]);
    }
    pts.push(base[3]);
    pts.push(base[3]);
    let pts = shuffled(pts, 8);
    let dt = check(&pts);
    assert_eq!(dt.n_vertices(), 500);
    assert_eq!(dt.duplicates().len(), pts.len() - 500);
    assert_eq!(dt.stats().duplicates_merged, pts.len() - 500);
    for &(i, v) in dt.duplicates() {
        let first = dt.input_of_vertex(v) as usize;
        assert!(first < i as usize);
        assert_eq!(pts[first], pts[i as usize]);
    }
    // Vertices are numbered by first occurrence.
    for v in 1..dt.n_vertices() as u32 {
        assert!(dt.input_of_vertex(v - 1) < dt.input_of_vertex(v));
    }
    // Same triangulation as the distinct points.
    let distinct: Vec<DVec3> = (0..dt.n_vertices() as u32).map(|v| dt.vertex(v)).collect();
    let dt2 = Delaunay::new(&distinct).unwrap();
    let a: BTreeSet<[u32; 4]> = dt
        .tets()
        .map(|t| {
            let mut q = t;
            q.sort_unstable();
            q
        })
        .collect();
    let b: BTreeSet<[u32; 4]> = dt2
        .tets()
        .map(|t| {
            let mut q = t;
            q.sort_unstable();
            q
        })
        .collect();
    assert_eq!(a, b);
    // Duplicates on a grid (degenerate and duplicated at once).
    let mut g = samples::grid(6, 1.0);
    g.extend(samples::grid(6, 1.0));
    let dt = check(&shuffled(g, 1));
    assert_eq!(dt.n_vertices(), 216);
}

#[test]
fn degenerate_inputs_are_errors() {
    let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    assert_eq!(
        Delaunay::new(&[]).unwrap_err(),
        DelaunayError::TooFewPoints { distinct: 0 }
    );
    assert_eq!(
        Delaunay::new(&[p(1.0, 2.0, 3.0); 10]).unwrap_err(),
        DelaunayError::TooFewPoints { distinct: 1 }
    );
    assert_eq!(
        Delaunay::new(&[p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0), p(0.0, 1.0, 0.0)]).unwrap_err(),
        DelaunayError::TooFewPoints { distinct: 3 }
    );
    let line: Vec<DVec3> = (0..100)
        .map(|i| p(i as f64, 2.0 * i as f64, -0.5 * i as f64))
        .collect();
    assert_eq!(
        Delaunay::new(&line).unwrap_err(),
        DelaunayError::AllCollinear
    );
    let plane: Vec<DVec3> = (0..100)
        .map(|i| {
            p(
                (i % 10) as f64,
                (i / 10) as f64,
                (i % 10) as f64 + (i / 10) as f64,
            )
        })
        .collect();
    assert_eq!(
        Delaunay::new(&plane).unwrap_err(),
        DelaunayError::AllCoplanar
    );
    let square = [
        p(0.0, 0.0, 0.0),
        p(1.0, 0.0, 0.0),
        p(0.0, 1.0, 0.0),
        p(1.0, 1.0, 0.0),
    ];
    assert_eq!(
        Delaunay::new(&square).unwrap_err(),
        DelaunayError::AllCoplanar
    );
    let mut bad = samples::uniform_cube(10, 1);
    bad[7].y = f64::NAN;
    assert_eq!(
        Delaunay::new(&bad).unwrap_err(),
        DelaunayError::NonFinite { index: 7 }
    );
    bad[7].y = 0.5;
    bad[2].z = f64::INFINITY;
    assert_eq!(
        Delaunay::new(&bad).unwrap_err(),
        DelaunayError::NonFinite { index: 2 }
    );
    // The messages are readable.
    assert!(DelaunayError::AllCoplanar.to_string().contains("coplanar"));
}

#[test]
fn almost_degenerate_inputs_succeed() {
    let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    // A plane plus one point barely off it.
    let mut pts: Vec<DVec3> = (0..100)
        .map(|i| p((i % 10) as f64, (i / 10) as f64, 0.0))
        .collect();
    pts.push(p(4.5, 4.5, 1e-12));
    let dt = check(&pts);
    assert_eq!(dt.n_vertices(), 101);
    // Collinear points plus two off the line.
    let mut pts: Vec<DVec3> = (0..50).map(|i| p(i as f64, 0.0, 0.0)).collect();
    pts.push(p(3.0, 1.0, 0.0));
    pts.push(p(3.0, 0.0, 1.0));
    check(&pts);
    // Far from the origin with tiny extent, and tiny coordinates.
    let off = DVec3::new(1e6, -2e6, 3e6);
    let pts: Vec<DVec3> = samples::grid(5, 1e-3).iter().map(|&q| q + off).collect();
    check(&pts);
    let pts: Vec<DVec3> = samples::uniform_cube(300, 3)
        .iter()
        .map(|&q| q * 1e-30)
        .collect();
    check(&pts);
    let pts: Vec<DVec3> = samples::uniform_cube(300, 3)
        .iter()
        .map(|&q| q * 1e30)
        .collect();
    check(&pts);
}

#[test]
fn extreme_magnitudes_give_the_same_triangulation() {
    // Exactly scaled copies (powers of two) must triangulate identically, also where the
    // predicates would overflow or underflow without the internal rescaling.
    for base in [samples::uniform_cube(400, 8), samples::grid(5, 1.0)] {
        let a = Delaunay::new(&base).unwrap();
        for e in [600, -600, 200, -200] {
            let s = 2f64.powi(e);
            let pts: Vec<DVec3> = base.iter().map(|&p| p * s).collect();
            let b = Delaunay::new(&pts).unwrap();
            assert!(a.tets().eq(b.tets()), "scale 2^{e}");
            assert_eq!(b.vertex(0), pts[0]);
        }
    }
}

#[test]
fn deterministic() {
    let pts = samples::grid(6, 1.0);
    let a = Delaunay::new(&pts).unwrap();
    let b = Delaunay::new(&pts).unwrap();
    assert!(a.tets().eq(b.tets()));
    assert_eq!(a.facets(), b.facets());
}

/// Brute-force Delaunay tetrahedra of points in general position: 4-subsets whose
/// circumsphere contains no other point.
fn brute_force(pts: &[DVec3]) -> BTreeSet<[u32; 4]> {
    let c = |p: DVec3| robust::Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    };
    let n = pts.len();
    let mut out = BTreeSet::new();
    for a in 0..n {
        for b in a + 1..n {
            for cc in b + 1..n {
                for d in cc + 1..n {
                    let o = robust::orient3d(c(pts[a]), c(pts[b]), c(pts[cc]), c(pts[d]));
                    if o == 0.0 {
                        continue;
                    }
                    let (pa, pb) = if o > 0.0 { (a, b) } else { (b, a) };
                    let empty = (0..n).filter(|&e| ![a, b, cc, d].contains(&e)).all(|e| {
                        robust::insphere(c(pts[pa]), c(pts[pb]), c(pts[cc]), c(pts[d]), c(pts[e]))
                            < 0.0
                    });
                    if empty {
                        out.insert([a as u32, b as u32, cc as u32, d as u32]);
                    }
                }
            }
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn matches_brute_force(
        coords in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0), 5..30),
        sorted in any::<bool>(),
    ) {
        let pts: Vec<DVec3> = coords.iter().map(|&(x, y, z)| DVec3::new(x, y, z)).collect();
        let opts = DelaunayOptions { spatial_sort: sorted, ..DelaunayOptions::default() };
        let dt = match Delaunay::with_options(&pts, &opts) {
            Ok(dt) => dt,
            Err(e) => return Err(TestCaseError::fail(format!("{e}"))),
        };
        prop_assert!(dt.validate().is_ok());
        prop_assert_eq!(tet_set(&dt), brute_force(&pts));
        for f in dt.facets() {
            prop_assert!(f.tets[0] != NO_TET);
        }
    }

    #[test]
    fn small_integer_sets_are_valid(
        coords in proptest::collection::vec((0i32..4, 0i32..4, 0i32..4), 4..40),
    ) {
        // Heavy degeneracy and duplicates: must be valid or a clean error.
        let pts: Vec<DVec3> = coords.iter().map(|&(x, y, z)| DVec3::new(x as f64, y as f64, z as f64)).collect();
        match Delaunay::new(&pts) {
            Ok(dt) => {
                prop_assert_eq!(dt.validate(), Ok(()));
                for (i, p) in pts.iter().enumerate() {
                    prop_assert_eq!(dt.vertex(dt.vertex_of_input(i)), *p);
                }
            }
            Err(DelaunayError::TooFewPoints { .. } | DelaunayError::AllCollinear | DelaunayError::AllCoplanar) => {}
            Err(e) => return Err(TestCaseError::fail(format!("{e}"))),
        }
    }
}
