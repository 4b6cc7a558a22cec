//! Estimators against closed-form normals.

use std::f64::consts::TAU;

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{NormalEstimator, RunCtx};
use reconbench_normals::*;

fn estimators(orient_k: usize) -> Vec<Box<dyn NormalEstimator>> {
    vec![
        Box::new(PlaneFit {
            params: PlaneFitParams { k: 30, orient_k },
        }),
        Box::new(WeightedPlaneFit {
            params: WeightedPlaneFitParams {
                orient_k,
                ..Default::default()
            },
        }),
        Box::new(Jet {
            params: JetParams { k: 18, orient_k },
        }),
        Box::new(LvmApprox {
            params: LvmApproxParams { k: 15, orient_k },
        }),
    ]
}

/// Unoriented angle, accurate near zero (acos loses half the digits there).
fn angle_deg(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b).abs()).to_degrees()
}

fn run(e: &dyn NormalEstimator, pts: Vec<DVec3>) -> Vec<DVec3> {
    let cloud = PointCloud::new(pts).unwrap();
    e.estimate(&cloud, &mut RunCtx::new(0)).unwrap().normals
}

/// Random points on the plane through `o` with normal `n`.
fn tilted_plane(n_pts: usize, seed: u64) -> (Vec<DVec3>, DVec3) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = DVec3::new(0.3, -0.5, 0.8).normalize();
    let (a, b) = n.any_orthonormal_pair();
    let o = DVec3::new(1.0, 2.0, -3.0);
    let pts = (0..n_pts)
        .map(|_| o + rng.random_range(-1.0..1.0) * a + rng.random_range(-1.0..1.0) * b)
        .collect();
    (pts, n)
}

#[test]
fn every_estimator_is_exact_on_a_plane() {
    let (pts, n) = tilted_plane(2000, 1);
    for e in estimators(0) {
        let normals = run(e.as_ref(), pts.clone());
        let worst = normals.iter().map(|&m| angle_deg(m, n)).fold(0.0, f64::max);
        assert!(
            worst < 1e-6,
            "{}: worst error {worst} deg on a plane",
            e.name()
        );
    }
}

/// A pole with rings of points at polar angles `i * step`: every neighbourhood of the
/// pole is rotationally symmetric, so the exact normal is +z for each estimator.
#[test]
fn symmetric_sphere_cap_gives_the_exact_pole_normal() {
    let mut pts = vec![DVec3::Z];
    for ring in 1..=6 {
        let theta = ring as f64 * 0.05;
        for s in 0..12 {
            let phi = TAU * s as f64 / 12.0;
            pts.push(DVec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ));
        }
    }
    // k = 1 + 12 m takes whole rings (a partial ring would break the symmetry).
    let sym: Vec<Box<dyn NormalEstimator>> = vec![
        Box::new(PlaneFit {
            params: PlaneFitParams { k: 25, orient_k: 0 },
        }),
        Box::new(WeightedPlaneFit {
            params: WeightedPlaneFitParams {
                k: 37,
                orient_k: 0,
                ..Default::default()
            },
        }),
        Box::new(Jet {
            params: JetParams { k: 25, orient_k: 0 },
        }),
        Box::new(LvmApprox {
            params: LvmApproxParams { k: 13, orient_k: 0 },
        }),
    ];
    for e in sym {
        let normals = run(e.as_ref(), pts.clone());
        assert!(
            angle_deg(normals[0], DVec3::Z) < 1e-9,
            "{}: {:?}",
            e.name(),
            normals[0]
        );
    }
}

#[test]
fn dense_random_sphere_errors_are_small_and_jet_beats_plane_fit() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let pts: Vec<DVec3> = (0..4000)
        .map(|_| {
            let z: f64 = rng.random_range(-1.0..1.0);
            let phi: f64 = rng.random_range(0.0..TAU);
            let s = (1.0 - z * z).sqrt();
            DVec3::new(s * phi.cos(), s * phi.sin(), z)
        })
        .collect();
    let mean = |e: &dyn NormalEstimator| {
        let normals = run(e, pts.clone());
        pts.iter()
            .zip(&normals)
            .map(|(&p, &n)| angle_deg(n, p))
            .sum::<f64>()
            / pts.len() as f64
    };
    let pf = mean(&PlaneFit {
        params: PlaneFitParams { k: 30, orient_k: 0 },
    });
    let jet = mean(&Jet {
        params: JetParams { k: 30, orient_k: 0 },
    });
    assert!(pf < 1.0, "pf mean error {pf} deg");
    assert!(jet < pf, "jet {jet} should beat pf {pf} on a sphere");
}

/// Seed 000 §1.2.4: on a torus parameter grid the neighbourhood of a point on the top
/// circle is denser towards the hole, so the plane-fit normal tilts inwards; a
/// symmetric-in-u but asymmetric-in-v sampling makes the bias visible.
#[test]
fn plane_fit_is_biased_on_the_top_of_a_torus_grid() {
    let (big_r, r) = (1.0, 0.5);
    let (nu, nv) = (60, 60);
    let mut pts = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (u, v) = (TAU * i as f64 / nu as f64, TAU * j as f64 / nv as f64);
            let c = big_r + r * v.cos();
            pts.push(DVec3::new(c * u.cos(), c * u.sin(), r * v.sin()));
        }
    }
    // Top circle: v = pi/2, i.e. j = 15; exact normal +z.
    let top: Vec<usize> = (0..nu).map(|i| i * nv + 15).collect();
    let pf = run(
        &PlaneFit {
            params: PlaneFitParams { k: 30, orient_k: 0 },
        },
        pts.clone(),
    );
    let bias: f64 = top.iter().map(|&t| angle_deg(pf[t], DVec3::Z)).sum::<f64>() / top.len() as f64;
    assert!(
        bias > 0.1,
        "expected a visible PF bias on the torus top, got {bias} deg"
    );
    // At every point of the circle the tilt points away from the hole, mostly in the
    // meridian plane (index tie-breaking among equidistant grid neighbours adds a small
    // tangential part). Measured: 0.23 deg mean for R = 1, r = 0.5, k = 30.
    for &t in &top {
        let radial = DVec3::new(pts[t].x, pts[t].y, 0.0).normalize();
        let n = pf[t] * pf[t].z.signum();
        let (rad, tan) = (n.dot(radial), n.dot(DVec3::Z.cross(radial)).abs());
        assert!(rad > 0.0, "tilt must point away from the hole at {t}");
        assert!(
            tan < rad,
            "tilt must be mostly radial at {t}: {tan} vs {rad}"
        );
    }
    // Note: a degree-2 jet does not remove this bias here (measured 0.44 deg at k = 30):
    // near the top circle the torus has a u^2 v cubic term that the fit over an
    // asymmetric grid neighbourhood folds into the slope.
}

#[test]
fn orientation_makes_sphere_normals_outward() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let pts: Vec<DVec3> = (0..3000)
        .map(|_| {
            let z: f64 = rng.random_range(-1.0..1.0);
            let phi: f64 = rng.random_range(0.0..TAU);
            let s = (1.0 - z * z).sqrt();
            DVec3::new(s * phi.cos(), s * phi.sin(), z)
        })
        .collect();
    for e in estimators(18) {
        let out = e
            .estimate(&PointCloud::new(pts.clone()).unwrap(), &mut RunCtx::new(0))
            .unwrap();
        assert!(out.oriented);
        let inward = pts
            .iter()
            .zip(&out.normals)
            .filter(|(p, n)| p.dot(**n) <= 0.0)
            .count();
        assert_eq!(
            inward,
            0,
            "{}: {inward} inward normals after orientation",
            e.name()
        );
    }
}

#[test]
fn orient_mst_fixes_random_flips_and_counts_them() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let pts: Vec<DVec3> = (0..500)
        .map(|_| {
            DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                0.0,
            )
        })
        .collect();
    let mut normals: Vec<DVec3> = (0..500)
        .map(|i| if i % 3 == 0 { -DVec3::Z } else { DVec3::Z })
        .collect();
    let report = orient_mst(&pts, &mut normals, 12).unwrap();
    assert_eq!(report.components, 1);
    assert_eq!(report.flipped, 167);
    assert!(normals.iter().all(|n| *n == DVec3::Z));
}

#[test]
fn degenerate_inputs_give_errors_or_zero_normals_not_panics() {
    for e in estimators(18) {
        // Too few points.
        let c = PointCloud::new(vec![DVec3::ZERO, DVec3::X]).unwrap();
        assert!(e.estimate(&c, &mut RunCtx::new(0)).is_err(), "{}", e.name());
        // Collinear: the normal is undetermined.
        let line: Vec<DVec3> = (0..50).map(|i| DVec3::X * i as f64).collect();
        let out = e
            .estimate(&PointCloud::new(line).unwrap(), &mut RunCtx::new(0))
            .unwrap();
        assert!(
            out.normals.iter().all(|n| *n == DVec3::ZERO),
            "{}",
            e.name()
        );
        // Exact duplicates of a plane: finite normals.
        let (mut pts, n) = tilted_plane(300, 2);
        pts.extend(pts.clone());
        let out = e
            .estimate(&PointCloud::new(pts).unwrap(), &mut RunCtx::new(0))
            .unwrap();
        assert!(
            out.normals.iter().all(|m| angle_deg(*m, n) < 1e-6),
            "{}",
            e.name()
        );
    }
}

/// The fused `pf` fit over kNN hits gives bit for bit the normal of the general
/// weighted fit over the row (point itself first), also where exact duplicates move the
/// point out of first place or out of its own result.
#[test]
fn fused_pf_fit_equals_the_row_fit_bit_for_bit() {
    use reconbench_geom::spatial::knn_self_map;
    use reconbench_normals::neighbors::row_points;
    use reconbench_normals::plane_fit::{plane_normal_of, unweighted_normal_of_hits};
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut pts: Vec<DVec3> = (0..3000)
        .map(|_| {
            let (u, v): (f64, f64) = (rng.random_range(0.0..TAU), rng.random_range(0.0..TAU));
            let c = 1.0 + 0.4 * v.cos();
            DVec3::new(c * u.cos(), c * u.sin(), 0.4 * v.sin())
        })
        .collect();
    // Twenty copies of a few points, so some rows are all duplicates of the point.
    for j in 0..5 {
        let p = pts[j * 100];
        pts.extend(std::iter::repeat_n(p, 20));
    }
    for k in [3, 16, 30] {
        let mismatches = knn_self_map(
            &pts,
            k,
            false,
            || (),
            |_, i, hits| {
                let fused = unweighted_normal_of_hits(hits);
                let row = plane_normal_of(row_points(&pts, i, hits), |_| 1.0);
                (fused.to_array().map(f64::to_bits) != row.to_array().map(f64::to_bits)) as usize
            },
        )
        .unwrap()
        .into_iter()
        .sum::<usize>();
        assert_eq!(mismatches, 0, "k = {k}");
    }
}

/// A neighbourhood size no machine could hold a kNN table for is refused by name when
/// the parameters are checked (issue 28: `k = 1e12` passed `run --dry-run`).
#[test]
fn an_absurd_k_is_refused_with_the_limit() {
    use reconbench_normals::neighbors::{MAX_K, check_k};
    assert!(check_k("k", 16, 3).is_ok());
    assert!(check_k("k", MAX_K, 3).is_ok());
    let e = check_k("k", 1_000_000_000_000, 3).unwrap_err().to_string();
    assert!(e.contains("'k'") && e.contains("at most 100000"), "{e}");
    assert!(check_k("k", 2, 3).is_err());
}
