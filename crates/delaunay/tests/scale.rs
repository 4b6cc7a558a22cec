//! Scale robustness: the construction and its validation at any representable scale.
//!
//! Multiplying a cloud by a power of two is exact and keeps every predicate's sign, so
//! the triangulation of a scaled copy must equal the original one tetrahedron for
//! tetrahedron, and `validate` (which evaluates the predicates again) must accept it.

use glam::DVec3;
use reconbench_delaunay::{Delaunay, DelaunayError, MAX_SPAN_BITS};
use reconbench_testkit::points as samples;

/// A sphere sample snapped to the dyadic grid `2^-40`: every coordinate's lowest set bit
/// is at least `2^-40`, so scaling by `2^e` stays exact down to `e = -1034`.
fn dyadic_sphere(n: usize) -> Vec<DVec3> {
    let g = 2f64.powi(40);
    samples::sphere(n, 11)
        .iter()
        .map(|p| (*p * g).round() / g)
        .collect()
}

/// `p · 2^e` for `|e|` beyond one double's exponent range, exactly (two steps).
fn times_pow2(p: DVec3, e: i32) -> DVec3 {
    let h = e / 2;
    p * 2f64.powi(h) * 2f64.powi(e - h)
}

#[test]
fn power_of_two_scaled_spheres_triangulate_identically_and_validate() {
    let base = dyadic_sphere(1000);
    let a = Delaunay::new(&base).unwrap();
    a.validate().unwrap();
    // 2^-1030 (vertices near 1e-310, subnormal), 1e-300, 1e-160, 1e-60, 1e80, 1e200, 1e300.
    for e in [-1030, -997, -532, -199, 266, 664, 996, 1022] {
        let pts: Vec<DVec3> = base.iter().map(|&p| times_pow2(p, e)).collect();
        let b = Delaunay::new(&pts).unwrap_or_else(|err| panic!("2^{e}: {err}"));
        b.validate().unwrap_or_else(|err| panic!("2^{e}: {err}"));
        assert!(a.tets().eq(b.tets()), "2^{e}: different tetrahedra");
        assert_eq!(a.n_all_tets(), b.n_all_tets(), "2^{e}");
        // Public coordinates are the input's, not the internally rescaled ones.
        assert_eq!(b.vertices(), &pts[..], "2^{e}");
    }
}

#[test]
fn decimal_scales_and_offsets_give_valid_triangulations() {
    // Not powers of two (inexact scaling, so not the same triangulation), but each is a
    // valid Delaunay triangulation of the points it was given.
    let base = samples::sphere(1000, 5);
    for f in [1e-300, 1e-160, 1e-60, 1e80, 1e200, 1e300] {
        let pts: Vec<DVec3> = base.iter().map(|&p| p * f).collect();
        let dt = Delaunay::new(&pts).unwrap_or_else(|err| panic!("{f:e}: {err}"));
        dt.validate().unwrap_or_else(|err| panic!("{f:e}: {err}"));
        assert_eq!(dt.n_vertices(), 1000, "{f:e}");
    }
    // Near the top of the range, off-centre: 1e308 plus a sphere of radius 1e300.
    let pts: Vec<DVec3> = base
        .iter()
        .map(|&p| DVec3::splat(1e308) + p * 1e300)
        .collect();
    let dt = Delaunay::new(&pts).unwrap();
    dt.validate().unwrap();
}

#[test]
fn subnormal_integer_clouds_validate() {
    // Coordinates k · 2^-1074 with small integers k: all subnormal, exactly representable.
    let tiny = f64::from_bits(1);
    let pts: Vec<DVec3> = samples::uniform_cube(300, 4)
        .iter()
        .map(|p| (*p * 1e6).round() * tiny)
        .collect();
    assert!(
        pts.iter()
            .all(|p| p.abs().max_element() < f64::MIN_POSITIVE)
    );
    let dt = Delaunay::new(&pts).unwrap();
    dt.validate().unwrap();
    let distinct: std::collections::BTreeSet<[u64; 3]> =
        pts.iter().map(|p| p.to_array().map(f64::to_bits)).collect();
    assert_eq!(dt.n_vertices(), distinct.len());
}

#[test]
fn spans_beyond_the_exact_window_are_refused_with_the_limit() {
    let mut pts = samples::uniform_cube(50, 2);
    pts.push(DVec3::new(1e-200, 0.5, 0.5));
    let err = Delaunay::new(&pts).unwrap_err();
    let DelaunayError::SpanTooWide { bits, .. } = err else {
        panic!("{err:?}");
    };
    assert!(bits > MAX_SPAN_BITS);
    assert!(
        err.to_string().contains(&MAX_SPAN_BITS.to_string()),
        "{err}"
    );
    // The same cloud without the outlying coordinate is fine.
    pts.pop();
    Delaunay::new(&pts).unwrap().validate().unwrap();
}
