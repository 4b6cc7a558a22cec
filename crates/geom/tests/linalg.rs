//! Eigen-decomposition, covariance and least squares against known solutions.

use reconbench_geom::linalg::{
    covariance, sym_eigen3, sym_eigen3_smallest, sym_eigen3_smallest_planar, weighted_least_squares,
};
use reconbench_geom::{DVec3, GeomError};

use glam::{DMat3, DQuat};

struct Rng(u64);

impl Rng {
    fn f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn rotation(&mut self) -> DMat3 {
        let q = DQuat::from_xyzw(
            self.f64() - 0.5,
            self.f64() - 0.5,
            self.f64() - 0.5,
            self.f64() - 0.5,
        )
        .normalize();
        DMat3::from_quat(q)
    }
}

fn max_abs(m: DMat3) -> f64 {
    m.to_cols_array().iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

fn check_decomposition(m: DMat3, expect: [f64; 3], tol: f64) {
    let e = sym_eigen3(m).unwrap();
    for i in 0..3 {
        assert!(
            (e.values[i] - expect[i]).abs() <= tol,
            "{:?} vs {expect:?}",
            e.values
        );
    }
    let v = DMat3::from_cols(e.vectors[0], e.vectors[1], e.vectors[2]);
    assert!(
        max_abs(v.transpose() * v - DMat3::IDENTITY) < 1e-14,
        "not orthonormal"
    );
    assert!((v.determinant() - 1.0).abs() < 1e-14, "not right-handed");
    assert!(max_abs(e.reconstruct() - m) <= tol, "reconstruction");
    for i in 0..3 {
        let r = m * e.vectors[i] - e.values[i] * e.vectors[i];
        assert!(r.length() <= tol, "residual {r}");
    }
}

#[test]
fn diagonal_matrices() {
    check_decomposition(
        DMat3::from_diagonal(DVec3::new(3.0, -1.0, 2.0)),
        [-1.0, 2.0, 3.0],
        1e-15,
    );
    let e = sym_eigen3(DMat3::from_diagonal(DVec3::new(3.0, 1.0, 2.0))).unwrap();
    assert_eq!(e.vectors[0], DVec3::Y);
    assert_eq!(e.vectors[1], DVec3::Z);
    assert_eq!(e.vectors[2], DVec3::X);
    check_decomposition(DMat3::ZERO, [0.0; 3], 0.0);
}

#[test]
fn repeated_eigenvalues() {
    check_decomposition(DMat3::IDENTITY, [1.0; 3], 1e-15);
    check_decomposition(DMat3::IDENTITY * 7.5, [7.5; 3], 1e-14);
    let mut rng = Rng(11);
    for _ in 0..100 {
        let r = rng.rotation();
        let m = r * DMat3::from_diagonal(DVec3::new(1.0, 1.0, 2.0)) * r.transpose();
        check_decomposition(m, [1.0, 1.0, 2.0], 1e-12);
        let e = sym_eigen3(m).unwrap();
        // The simple eigenvector is the rotated z axis (up to sign).
        assert!((e.vectors[2].dot(r.z_axis).abs() - 1.0).abs() < 1e-12);
        let m = r * DMat3::from_diagonal(DVec3::new(-3.0, 5.0, 5.0)) * r.transpose();
        check_decomposition(m, [-3.0, 5.0, 5.0], 1e-12);
        let m = r * DMat3::from_diagonal(DVec3::splat(0.25)) * r.transpose();
        check_decomposition(m, [0.25; 3], 1e-12);
    }
}

#[test]
fn random_rotations_of_known_spectra() {
    let mut rng = Rng(12);
    for _ in 0..500 {
        let r = rng.rotation();
        let mut s = [
            rng.f64() * 4.0 - 2.0,
            rng.f64() * 4.0 - 2.0,
            rng.f64() * 4.0 - 2.0,
        ];
        let m = r * DMat3::from_diagonal(DVec3::from_array(s)) * r.transpose();
        s.sort_by(f64::total_cmp);
        check_decomposition(m, s, 1e-12);
    }
    // Wide dynamic range: scaled internally, relative accuracy kept.
    let r = rng.rotation();
    let m = r * DMat3::from_diagonal(DVec3::new(1e-8, 1.0, 1e8)) * r.transpose();
    let e = sym_eigen3(m).unwrap();
    assert!((e.values[2] - 1e8).abs() < 1e-6);
    assert!((e.values[1] - 1.0).abs() < 1e-6);
    let m = DMat3::from_diagonal(DVec3::new(1e-300, 2e-300, 3e-300));
    assert_eq!(sym_eigen3(m).unwrap().values, [1e-300, 2e-300, 3e-300]);
    let m = DMat3::from_diagonal(DVec3::new(1e300, -1e300, 0.0));
    assert_eq!(sym_eigen3(m).unwrap().values, [-1e300, 0.0, 1e300]);
}

#[test]
fn non_finite_matrix_is_an_error() {
    let mut m = DMat3::IDENTITY;
    m.y_axis.z = f64::NAN;
    assert!(matches!(
        sym_eigen3(m),
        Err(GeomError::NonFinite { index: 1, .. })
    ));
    m.y_axis.z = f64::INFINITY;
    assert!(sym_eigen3(m).is_err());
}

#[test]
fn covariance_of_known_sets() {
    // Points +-a along x, +-b along y: covariance diag(a^2/2, b^2/2, 0) around the centre.
    let c = DVec3::new(1e6, -2e6, 3.0);
    let pts = [
        c + DVec3::X * 2.0,
        c - DVec3::X * 2.0,
        c + DVec3::Y,
        c - DVec3::Y,
    ];
    let cov = covariance(&pts, None).unwrap();
    assert_eq!(cov.centroid, c);
    assert_eq!(cov.weight_sum, 4.0);
    assert!(max_abs(cov.matrix - DMat3::from_diagonal(DVec3::new(2.0, 0.5, 0.0))) < 1e-12);
    let e = sym_eigen3(cov.matrix).unwrap();
    assert!((e.vectors[0].dot(DVec3::Z).abs() - 1.0).abs() < 1e-12);
    // Weights: only the x pair counts.
    let cov = covariance(&pts, Some(&[1.0, 1.0, 0.0, 0.0])).unwrap();
    assert!(max_abs(cov.matrix - DMat3::from_diagonal(DVec3::new(4.0, 0.0, 0.0))) < 1e-12);
    // Integer weights equal repeated points.
    let w = [3.0, 1.0, 2.0, 5.0];
    let mut rep = Vec::new();
    for (p, &k) in pts.iter().zip(&w) {
        rep.extend(std::iter::repeat_n(*p, k as usize));
    }
    let a = covariance(&pts, Some(&w)).unwrap();
    let b = covariance(&rep, None).unwrap();
    assert!((a.centroid - b.centroid).length() < 1e-9);
    assert!(max_abs(a.matrix - b.matrix) < 1e-9);
}

#[test]
fn covariance_errors() {
    assert!(covariance(&[], None).is_err());
    assert!(covariance(&[DVec3::ZERO], Some(&[1.0, 2.0])).is_err());
    assert!(covariance(&[DVec3::ZERO], Some(&[-1.0])).is_err());
    assert!(covariance(&[DVec3::ZERO], Some(&[0.0])).is_err());
    assert!(covariance(&[DVec3::ZERO], Some(&[f64::NAN])).is_err());
    assert!(covariance(&[DVec3::splat(f64::NAN)], None).is_err());
}

#[test]
fn exact_polynomial_fit() {
    // y = 2 - 3x + 0.5x^2 + 0.25x^3 sampled exactly on x in [90, 110]: badly scaled
    // monomials, still recovered thanks to the column equilibration.
    let coef = [2.0, -3.0, 0.5, 0.25];
    let xs: Vec<f64> = (0..25).map(|i| 90.0 + i as f64 * 20.0 / 24.0).collect();
    let mut a = Vec::new();
    let mut b = Vec::new();
    let mut w = Vec::new();
    for (i, &x) in xs.iter().enumerate() {
        a.extend([1.0, x, x * x, x * x * x]);
        b.push(coef[0] + coef[1] * x + coef[2] * x * x + coef[3] * x * x * x);
        w.push(1.0 + (i % 3) as f64);
    }
    let sol = weighted_least_squares(&a, &b, &w, 4).unwrap();
    for i in 0..4 {
        assert!(
            (sol[i] - coef[i]).abs() < 1e-6 * coef[i].abs().max(1.0),
            "{sol:?}"
        );
    }
    // Well-conditioned: 2D plane fit z = 1 + 2x - y, near machine precision.
    let mut a = Vec::new();
    let mut b = Vec::new();
    for i in 0..5 {
        for j in 0..5 {
            let (x, y) = (i as f64 * 0.1 - 0.2, j as f64 * 0.1 - 0.2);
            a.extend([1.0, x, y]);
            b.push(1.0 + 2.0 * x - y);
        }
    }
    let sol = weighted_least_squares(&a, &b, &[], 3).unwrap();
    assert!((sol[0] - 1.0).abs() < 1e-13 && (sol[1] - 2.0).abs() < 1e-13);
    assert!((sol[2] + 1.0).abs() < 1e-13);
}

#[test]
fn weighted_fit_follows_weights() {
    // Fit a constant to [0, 10] with weights [3, 1]: the weighted mean 2.5.
    let sol = weighted_least_squares(&[1.0, 1.0], &[0.0, 10.0], &[3.0, 1.0], 1).unwrap();
    assert!((sol[0] - 2.5).abs() < 1e-14);
    // Zero weight ignores a row.
    let sol = weighted_least_squares(&[1.0, 1.0], &[0.0, 10.0], &[0.0, 1.0], 1).unwrap();
    assert!((sol[0] - 10.0).abs() < 1e-14);
}

#[test]
fn rank_deficiency_is_reported() {
    // Two identical columns.
    let a = [1.0, 1.0, 2.0, 2.0, 3.0, 3.0];
    assert!(matches!(
        weighted_least_squares(&a, &[1.0, 2.0, 3.0], &[], 2),
        Err(GeomError::RankDeficient { rank: 1, cols: 2 })
    ));
    // Fewer rows than unknowns.
    assert!(matches!(
        weighted_least_squares(&[1.0, 2.0, 3.0], &[1.0], &[], 3),
        Err(GeomError::RankDeficient { .. })
    ));
    // A line fit through samples at a single x.
    let a = [1.0, 2.0, 1.0, 2.0, 1.0, 2.0];
    assert!(weighted_least_squares(&a, &[1.0, 2.0, 3.0], &[], 2).is_err());
    // All weights but one zero for a 2-parameter fit.
    let a = [1.0, 0.0, 1.0, 1.0, 1.0, 2.0];
    assert!(matches!(
        weighted_least_squares(&a, &[1.0, 2.0, 3.0], &[0.0, 0.0, 1.0], 2),
        Err(GeomError::RankDeficient { .. })
    ));
    // A zero column.
    let a = [1.0, 0.0, 1.0, 0.0];
    assert!(weighted_least_squares(&a, &[1.0, 2.0], &[], 2).is_err());
}

#[test]
fn least_squares_input_errors() {
    assert!(weighted_least_squares(&[1.0], &[1.0], &[], 0).is_err());
    assert!(weighted_least_squares(&[1.0, 2.0, 3.0], &[1.0], &[], 2).is_err());
    assert!(weighted_least_squares(&[1.0, 2.0], &[1.0], &[], 1).is_err());
    assert!(weighted_least_squares(&[1.0, 2.0], &[1.0, 2.0], &[1.0], 1).is_err());
    assert!(weighted_least_squares(&[1.0, f64::NAN], &[1.0, 2.0], &[], 1).is_err());
    assert!(weighted_least_squares(&[1.0, 1.0], &[1.0, f64::INFINITY], &[], 1).is_err());
    assert!(weighted_least_squares(&[1.0, 1.0], &[1.0, 2.0], &[1.0, -1.0], 1).is_err());
}

/// Compares the closed-form smallest eigenpair with the iterative solver on `m`; returns
/// `sin(angle) * gap / (eps * max|l|)` (the vector error in units of the perturbation
/// bound every backward-stable solver obeys) so callers can check the worst case.
fn compare_smallest(m: DMat3) -> f64 {
    let fast = sym_eigen3_smallest(m).unwrap();
    let full = sym_eigen3(m).unwrap();
    let mag = full.values[0].abs().max(full.values[2].abs());
    for i in 0..3 {
        assert!(
            (fast.values[i] - full.values[i]).abs() <= 1e-13 * mag,
            "eigenvalue {i}: {:?} vs {:?} for {m:?}",
            fast.values,
            full.values
        );
    }
    let v = fast.vector;
    assert!((v.length() - 1.0).abs() < 1e-14, "not unit: {v}");
    let gap = full.values[1] - full.values[0];
    // Residual of the fast pair itself, independent of the other solver (on the matrix
    // scaled to unit magnitude, so that 1e200 entries do not overflow the check). The
    // cross-product vector is accurate to eps * |l|max / gap, not backward stable: for
    // rod-like spectra (l1 << l2) its error along the largest axis gives a residual of
    // that order, not eps.
    if gap > 1e-4 * mag {
        let r = (m * (1.0 / mag)) * v - (fast.values[0] / mag) * v;
        assert!(
            r.length() <= 64.0 * f64::EPSILON * mag / gap,
            "residual {r} for {m:?}: fast {fast:?} full {full:?}"
        );
    }
    let u = full.vectors[0];
    let sin = v.cross(u).length();
    // Same sign convention, unless the two largest components are (nearly) tied.
    let mut a = u.abs().to_array();
    a.sort_by(f64::total_cmp);
    if a[2] - a[1] > 1e-6 {
        assert!(v.dot(u) > 0.0, "sign differs: {v} vs {u}");
    }
    if gap > 1e-4 * mag {
        sin * gap / (f64::EPSILON * mag)
    } else {
        // The iterative solver's answer is returned unchanged.
        assert_eq!((fast.values, fast.vector), (full.values, full.vectors[0]));
        0.0
    }
}

fn spectrum(rng: &mut Rng, l: [f64; 3]) -> DMat3 {
    let r = rng.rotation();
    r * DMat3::from_diagonal(DVec3::from_array(l)) * r.transpose()
}

#[test]
fn smallest_eigenpair_matches_the_iterative_solver() {
    let mut rng = Rng(11);
    let mut worst: f64 = 0.0;
    // Covariances of random, anisotropic 16-point sets.
    for _ in 0..2000 {
        let s = DVec3::new(rng.f64(), rng.f64(), rng.f64()) * 3.0;
        let pts: Vec<DVec3> = (0..16)
            .map(|_| DVec3::new(rng.f64() - 0.5, rng.f64() - 0.5, rng.f64() - 0.5) * s)
            .collect();
        let c = covariance(&pts, None).unwrap().matrix;
        let r = rng.rotation();
        worst = worst.max(compare_smallest(r * c * r.transpose()));
    }
    // Nearly planar neighbourhoods (disc-like: the two large eigenvalues equal, where
    // the cubic's root alone is only sqrt(eps) accurate), exactly planar ones, and
    // well-separated, nearly repeated-smallest, rod-like and isotropic spectra (the
    // last two go to the fallback).
    let spectra: [[f64; 3]; 14] = [
        [1e-6, 1.0, 1.0],
        [1e-10, 1.0, 1.0],
        [1e-14, 1.0, 1.0],
        [0.0, 1.0, 1.0],
        [0.0, 1.0, 2.0],
        [1e-8, 0.5, 1.0],
        [1e-3, 1.0, 1.0 + 1e-12],
        [1.0, 1.001, 2.0],
        [1.0, 1.0 + 1e-6, 2.0],
        [1.0, 1.0, 2.0],
        [1e-9, 1e-9, 1.0],
        [0.0, 0.0, 1.0],
        [2.0, 2.0, 2.0],
        [3.0, 3.0, 3.0 + 1e-9],
    ];
    for l in spectra {
        for scale in [1.0, 1e-200, 1e200] {
            for _ in 0..50 {
                let m = spectrum(&mut rng, l) * scale;
                worst = worst.max(compare_smallest(m));
            }
        }
    }
    // Exactly planar points (z = 0, no rotation: the smallest eigenvalue is exactly 0).
    for _ in 0..200 {
        let pts: Vec<DVec3> = (0..16)
            .map(|_| DVec3::new(rng.f64(), rng.f64(), 0.0))
            .collect();
        let c = covariance(&pts, None).unwrap().matrix;
        let e = sym_eigen3_smallest(c).unwrap();
        assert_eq!(e.vector, DVec3::Z);
        assert_eq!(e.values[0], 0.0);
        worst = worst.max(compare_smallest(c));
    }
    eprintln!("worst vector error: {worst} x eps * |l|max / gap");
    // Measured worst case: about 3 (the bound itself is 1 up to a small constant).
    assert!(worst < 64.0, "vector error {worst} x eps * |l|max / gap");
    assert!(sym_eigen3_smallest(DMat3::from_diagonal(DVec3::new(f64::NAN, 1.0, 2.0))).is_err());
    let z = sym_eigen3_smallest(DMat3::ZERO).unwrap();
    assert_eq!((z.values, z.vector), ([0.0; 3], DVec3::X));
}

/// `sym_eigen3_smallest_planar` is `sym_eigen3_smallest` plus the plane test, bit for
/// bit: on its fast path it skips the two larger eigenvalues, which must never change
/// the answer (including where the test fails: collinear, coincident, negative-definite
/// and rank-one matrices, and ratios above the fast path's limit).
#[test]
fn planar_smallest_vector_equals_the_full_answer() {
    let mut rng = Rng(23);
    let spectra: [[f64; 3]; 10] = [
        [0.0, 1.0, 2.0],
        [1e-9, 0.3, 1.0],
        [0.0, 0.0, 1.0],
        [0.0, 1e-13, 1.0],
        [0.0, 1e-7, 1.0],
        [-1.0, -0.5, 1.0],
        [-2.0, -1.0, -0.5],
        [-1e-15, 1e-5, 1.0],
        [1.0, 1.0, 1.0],
        [0.0, 0.0, 0.0],
    ];
    let mut mats: Vec<DMat3> = spectra.iter().map(|&l| spectrum(&mut rng, l)).collect();
    for _ in 0..500 {
        let s = DVec3::new(rng.f64(), rng.f64(), rng.f64() * 0.1);
        let pts: Vec<DVec3> = (0..16)
            .map(|_| DVec3::new(rng.f64() - 0.5, rng.f64() - 0.5, rng.f64() - 0.5) * s)
            .collect();
        mats.push(covariance(&pts, None).unwrap().matrix);
        let l = [rng.f64() - 0.5, rng.f64(), rng.f64() + 1.0];
        mats.push(spectrum(&mut rng, l));
    }
    let mut fast_and_planar = 0;
    for m in mats {
        let e = sym_eigen3_smallest(m).unwrap();
        for ratio in [1e-12, 1e-6, 1e-4, 0.5] {
            let expected =
                (e.values[1] > ratio * e.values[2].max(f64::MIN_POSITIVE)).then_some(e.vector);
            let got = sym_eigen3_smallest_planar(m, ratio).unwrap();
            assert_eq!(
                got.map(|v| v.to_array().map(f64::to_bits)),
                expected.map(|v| v.to_array().map(f64::to_bits)),
                "ratio {ratio}, values {:?}, matrix {m:?}",
                e.values
            );
            fast_and_planar += usize::from(got.is_some());
        }
    }
    assert!(
        fast_and_planar > 1000,
        "only {fast_and_planar} planar answers"
    );
    assert!(
        sym_eigen3_smallest_planar(DMat3::from_diagonal(DVec3::new(1.0, f64::NAN, 2.0)), 1e-12)
            .is_err()
    );
}
