//! Each metric against a number known in closed form (issue 5), plus brute-force
//! cross-checks on small inputs.

use reconbench_testkit::metric_fixtures as common;

use common::{
    Lcg, TestSphere, brute_distance, concat, icosahedron, translate, unweld, without_face,
};
use glam::{DQuat, DVec3};
use reconbench_geom::method::PhaseTimer;
use reconbench_geom::{Channel, PointCloud, TriMesh};
use reconbench_metrics::distance::{DistanceOptions, Sides, eval_distance};
use reconbench_metrics::eval::{MeshEvalOptions, eval_cloud_features, eval_mesh};
use reconbench_metrics::features::{
    CleanPositions, FeatureOptions, eval_features, eval_mesh_features,
};
use reconbench_metrics::normals::{NormalOptions, eval_normals};
use reconbench_metrics::quality::{QualityOptions, eval_quality, triangle_quality};
use reconbench_metrics::topology::{
    GroundTruthTopology, TopologyOptions, count_self_intersections, eval_topology,
};
use reconbench_metrics::{CostReport, Reference, Report, peak_rss_bytes};
use reconbench_synth::FeatureCurve;
use reconbench_testkit::meshes::{cube, square_grid, torus_grid, uv_sphere};

fn small_opts() -> DistanceOptions {
    DistanceOptions {
        min_samples: 20_000,
        ..DistanceOptions::default()
    }
}

// ---------------------------------------------------------------- geometry

#[test]
fn icosahedron_in_unit_sphere_has_the_sagitta_hausdorff() {
    // Inradius of the icosahedron with circumradius 1: sqrt((5 + 2 sqrt 5) / 15).
    let sagitta = 1.0 - ((5.0 + 2.0 * 5f64.sqrt()) / 15.0).sqrt();
    let sphere = TestSphere::unit();
    let reference = Reference::analytic(&sphere);
    let e = eval_distance(&icosahedron(), &reference, &DistanceOptions::default()).unwrap();
    let h = e.hausdorff_abs().unwrap();
    assert!((h - sagitta).abs() < 0.01 * sagitta, "{h} vs {sagitta}");
    // Each side alone reaches the sagitta too (face centres / points above them).
    assert!((e.accuracy.unwrap().max - sagitta).abs() < 0.01 * sagitta);
    assert!((e.completeness.unwrap().max - sagitta).abs() < 0.01 * sagitta);
    // Relative keys are divided by the diagonal of the sphere's box, 2 sqrt 3.
    let row = e.to_row();
    assert!((row["hausdorff"] - h / (2.0 * 3f64.sqrt())).abs() < 1e-15);
}

#[test]
fn uv_sphere_hausdorff_is_the_largest_face_sagitta() {
    // Every vertex lies on the unit sphere, so the deepest point of face f is at depth
    // 1 - h_f with h_f the distance from the centre to its plane.
    let mesh = uv_sphere(16, 32, 1.0);
    let min_h = (0..mesh.n_faces())
        .map(|f| mesh.face_normal(f).dot(mesh.triangle(f)[0]).abs())
        .fold(f64::INFINITY, f64::min);
    let sagitta = 1.0 - min_h;
    let sphere = TestSphere::unit();
    let e = eval_distance(
        &mesh,
        &Reference::analytic(&sphere),
        &DistanceOptions::default(),
    )
    .unwrap();
    let h = e.hausdorff_abs().unwrap();
    assert!((h - sagitta).abs() < 0.01 * sagitta, "{h} vs {sagitta}");
    // Against the same sphere as a (much finer) mesh reference: same number within 1%.
    let fine = Reference::mesh(uv_sphere(128, 256, 1.0)).unwrap();
    let e2 = eval_distance(&mesh, &fine, &small_opts()).unwrap();
    let h2 = e2.hausdorff_abs().unwrap();
    assert!((h2 - sagitta).abs() < 0.03 * sagitta, "{h2} vs {sagitta}");
}

#[test]
fn plane_translated_by_d_has_chamfer_and_hausdorff_d() {
    let s = square_grid(4);
    let reference = Reference::mesh(s.clone()).unwrap();
    let diag = 2f64.sqrt();
    for d in [0.003, 0.02] {
        let r = translate(&s, DVec3::new(0.0, 0.0, d));
        let e = eval_distance(&r, &reference, &small_opts()).unwrap();
        let c = e.chamfer_l1_abs().unwrap();
        assert!((c - d).abs() < 1e-12, "chamfer {c} vs {d}");
        assert!((e.hausdorff_abs().unwrap() - d).abs() < 1e-12);
        assert!((e.accuracy.unwrap().rms - d).abs() < 1e-12);
        assert!((e.completeness.unwrap().p95 - d).abs() < 1e-12);
        let row = e.to_row();
        assert!((row["chamfer_l1"] - d / diag).abs() < 1e-12);
        assert!((row["chamfer_l1_abs"] - d).abs() < 1e-12);
        // tau = 0.005 diag = 0.00707 and 0.01 diag = 0.01414.
        let (f5, f10) = (row["fscore_0.005"], row["fscore_0.01"]);
        if d < 0.005 * diag {
            assert_eq!((f5, f10), (100.0, 100.0));
        } else {
            assert_eq!((f5, f10), (0.0, 0.0));
            assert_eq!(row["precision_0.01"], 0.0);
        }
    }
}

#[test]
fn identical_mesh_has_zero_distances_and_full_fscore() {
    let m = torus_grid(24, 12, 1.0, 0.3);
    let e = eval_distance(&m, &Reference::mesh(m.clone()).unwrap(), &small_opts()).unwrap();
    assert!(e.hausdorff_abs().unwrap() < 1e-12);
    assert_eq!(e.fscore(0.01).unwrap().fscore, 100.0);
    assert_eq!(e.vertex_error.as_ref().unwrap().len(), m.n_vertices());
    assert!(e.vertex_error.unwrap().iter().all(|&x| x < 1e-12));
}

#[test]
fn mesh_reference_distances_match_brute_force() {
    let m = torus_grid(20, 10, 1.0, 0.35);
    let reference = Reference::mesh(m.clone()).unwrap();
    let mut rng = Lcg(3);
    // More than 4096 queries: goes through the Morton-ordered batch path.
    let q: Vec<DVec3> = (0..5000)
        .map(|_| {
            DVec3::new(
                3.0 * rng.next_f64() - 1.5,
                3.0 * rng.next_f64() - 1.5,
                rng.next_f64() - 0.5,
            )
        })
        .collect();
    let d = reference.distances(&q).unwrap();
    let hits = reference.closest_batch(&q[..100]).unwrap();
    for (i, p) in q.iter().enumerate() {
        let bf = brute_distance(&m, *p);
        assert!((d[i] - bf).abs() < 1e-12, "query {i}: {} vs {bf}", d[i]);
        if i < 100 {
            assert!((hits[i].distance - bf).abs() < 1e-12);
            assert!((hits[i].normal.length() - 1.0).abs() < 1e-12);
        }
    }
}

#[test]
fn one_sided_options_compute_one_side() {
    let sphere = TestSphere::unit();
    let reference = Reference::analytic(&sphere);
    let m = icosahedron();
    let acc = eval_distance(
        &m,
        &reference,
        &DistanceOptions {
            sides: Sides::Accuracy,
            ..small_opts()
        },
    )
    .unwrap();
    assert!(acc.accuracy.is_some() && acc.completeness.is_none());
    assert!(acc.hausdorff_abs().is_none() && acc.fscores.is_empty());
    let comp = eval_distance(
        &m,
        &reference,
        &DistanceOptions {
            sides: Sides::Completeness,
            ..small_opts()
        },
    )
    .unwrap();
    assert!(comp.accuracy.is_none() && comp.completeness.is_some());
    let json = serde_json::to_value(&comp).unwrap();
    assert!(json["chamfer_l1"].is_null());
    assert!(json["completeness_max"].is_number());
}

#[test]
fn distances_are_deterministic_across_thread_counts() {
    let sphere = TestSphere::unit();
    let m = uv_sphere(12, 24, 1.0);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            eval_distance(&m, &Reference::analytic(&sphere), &small_opts())
                .unwrap()
                .to_row()
        })
    };
    assert_eq!(run(1), run(2));
    // And the seed matters.
    let other = eval_distance(
        &m,
        &Reference::analytic(&sphere),
        &DistanceOptions {
            seed: 7,
            ..small_opts()
        },
    )
    .unwrap()
    .to_row();
    assert_ne!(run(2)["accuracy_mean_abs"], other["accuracy_mean_abs"]);
}

// ---------------------------------------------------------------- normals

#[test]
fn normals_rotated_by_ten_degrees() {
    let mut rng = Lcg(11);
    let g: Vec<DVec3> = (0..2000).map(|_| rng.unit_vector()).collect();
    let n: Vec<DVec3> = g
        .iter()
        .map(|&g| {
            let axis = g.any_orthonormal_vector();
            DQuat::from_axis_angle(axis, 10f64.to_radians()) * g
        })
        .collect();
    let e = eval_normals(&n, &g, &NormalOptions { oriented: true }).unwrap();
    let u = e.unoriented;
    assert!((u.mean_deg - 10.0).abs() < 1e-6, "{}", u.mean_deg);
    assert!((u.rms_deg - 10.0).abs() < 1e-6);
    assert!((u.median_deg - 10.0).abs() < 1e-6);
    assert!((u.max_deg - 10.0).abs() < 1e-6);
    assert!(u.std_deg < 1e-6);
    assert_eq!(e.pgp5, 0.0);
    assert_eq!(e.flip_rate, Some(0.0));
    let row = e.to_row();
    assert!((row["normal_mean_rad"] - 10f64.to_radians()).abs() < 1e-8);
    assert!((row["normal_rms_deg"] - 10.0).abs() < 1e-6);

    // Flipped estimates: same unoriented error, oriented 170 degrees, all flipped.
    let flipped: Vec<DVec3> = n.iter().map(|&v| -v).collect();
    let e = eval_normals(&flipped, &g, &NormalOptions { oriented: true }).unwrap();
    assert!((e.unoriented.mean_deg - 10.0).abs() < 1e-6);
    assert!((e.oriented.unwrap().mean_deg - 170.0).abs() < 1e-6);
    assert_eq!(e.flip_rate, Some(1.0));
    // Unoriented only: oriented keys are null.
    let e = eval_normals(&flipped, &g, &NormalOptions::default()).unwrap();
    assert!(e.to_json()["normal_oriented_mean_deg"].is_null());
}

#[test]
fn invalid_normals_count_as_ninety_degrees() {
    let g = vec![DVec3::Z; 4];
    let n = vec![DVec3::Z, DVec3::ZERO, DVec3::Z * 3.0, DVec3::X];
    let e = eval_normals(&n, &g, &NormalOptions::default()).unwrap();
    assert_eq!(e.invalid, 1);
    assert!((e.unoriented.mean_deg - 45.0).abs() < 1e-12);
    assert_eq!(e.pgp5, 50.0);
    // A missing ground truth leaves the point out.
    let mut g2 = g.clone();
    g2[3] = DVec3::ZERO;
    let e = eval_normals(&n, &g2, &NormalOptions::default()).unwrap();
    assert_eq!((e.points, e.gt_missing), (3, 1));
}

#[test]
fn ground_truth_normals_by_source_id_and_at_the_closest_point() {
    use reconbench_metrics::normals::{NormalGroundTruth, eval_cloud_normals};
    // Ground-truth cloud: 4 points of the unit sphere with exact normals, ids 10..13.
    let dirs = [DVec3::X, DVec3::Y, DVec3::Z, -DVec3::X];
    let mut gt = PointCloud::new(dirs.to_vec())
        .unwrap()
        .with_normals(dirs.to_vec())
        .unwrap();
    gt.set_source_ids(Some(vec![10, 11, 12, 13])).unwrap();
    // Estimated cloud: reordered, one outlier (no source), positions pushed outwards,
    // normals exact except point 0 (off by 90 degrees).
    let mut est = PointCloud::new(vec![DVec3::Z * 1.1, DVec3::X * 1.1, DVec3::splat(3.0)])
        .unwrap()
        .with_normals(vec![DVec3::X, DVec3::X, DVec3::X])
        .unwrap();
    est.set_source_ids(Some(vec![12, 10, u32::MAX])).unwrap();
    let e = eval_cloud_normals(
        &est,
        NormalGroundTruth::SourceSamples(&gt),
        &NormalOptions::default(),
    )
    .unwrap();
    assert_eq!(
        (e.points, e.gt_missing, e.gt_kind.as_str()),
        (2, 1, "source")
    );
    assert!((e.unoriented.mean_deg - 45.0).abs() < 1e-12);
    let sphere = TestSphere::unit();
    let reference = Reference::analytic(&sphere);
    let e = eval_cloud_normals(
        &est,
        NormalGroundTruth::ClosestPoint(&reference),
        &NormalOptions::default(),
    )
    .unwrap();
    // Closest-point normals of (0,0,1.1), (1.1,0,0), (3,3,3): Z, X, diagonal.
    let diag = (1.0 / 3f64.sqrt()).acos().to_degrees();
    assert_eq!(e.points, 3);
    assert!((e.unoriented.mean_deg - (90.0 + 0.0 + diag) / 3.0).abs() < 1e-9);
}

// ---------------------------------------------------------------- features

/// The 12 edges of the unit cube as curves (dihedral 90 degrees).
fn cube_edges() -> Vec<FeatureCurve> {
    let mut out = Vec::new();
    for axis in 0..3 {
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
            let mk = |t: f64| {
                let mut p = [0.0; 3];
                p[axis] = t;
                p[(axis + 1) % 3] = u;
                p[(axis + 2) % 3] = v;
                DVec3::from_array(p)
            };
            out.push(FeatureCurve {
                points: vec![mk(0.0), mk(1.0)],
                dihedral_deg: 90.0,
                is_corner: false,
            });
        }
    }
    out
}

/// A regular grid of `(n + 1)^2` points on each face of the unit cube (edges shared).
fn cube_surface_grid(n: usize) -> Vec<DVec3> {
    let mut pts = Vec::new();
    let h = 1.0 / n as f64;
    for i in 0..=n {
        for j in 0..=n {
            for k in 0..=n {
                let p = DVec3::new(i as f64 * h, j as f64 * h, k as f64 * h);
                let on = [i, j, k].iter().any(|&c| c == 0 || c == n);
                if on {
                    pts.push(p);
                }
            }
        }
    }
    pts
}

#[test]
fn labelling_everything_gives_recall_one_and_precision_the_gt_share() {
    let pts = cube_surface_grid(20);
    let curves = cube_edges();
    let diag = 3f64.sqrt();
    let all = vec![true; pts.len()];
    // r = 1.5 x spacing keeps the grid rows at exactly 1 spacing away off the boundary.
    let opts = FeatureOptions {
        radius_factor: 1.5,
        ..FeatureOptions::default()
    };
    let e = eval_features(&pts, &pts, &all, &curves, diag, &opts).unwrap();
    // Spacing of the grid is 1/20.
    assert!((e.spacing - 0.05).abs() < 1e-12);
    let share = e.positives[0] as f64 / pts.len() as f64;
    assert_eq!(e.recall(0), Some(1.0));
    assert!((e.precision(0).unwrap() - share).abs() < 1e-15);
    assert_eq!(e.to_row()["feature_gt_share"], share);
    assert_eq!(e.to_row()["feature_recall_2r"], 1.0);
    assert_eq!(e.coverage, 1.0);
    // A surface point is within d < 1/2 of an edge iff a second coordinate is within d
    // of 0 or 1: the edge points and the next row on both faces.
    let direct = pts
        .iter()
        .filter(|p| {
            let near = |c: f64| c <= 0.075 || c >= 0.925;
            let k = [p.x, p.y, p.z].iter().filter(|&&c| near(c)).count();
            k >= 2
        })
        .count();
    assert_eq!(e.positives[0], direct);
}

#[test]
fn perfect_labels_score_one_and_stay_within_r() {
    let pts = cube_surface_grid(20);
    let curves = cube_edges();
    // Detect exactly the points on an edge (distance 0).
    let det: Vec<bool> = pts
        .iter()
        .map(|p| {
            [p.x, p.y, p.z]
                .iter()
                .filter(|&&c| c == 0.0 || c == 1.0)
                .count()
                >= 2
        })
        .collect();
    // r = 0.03: below the grid step (only edge points are positive) and above half the
    // curve sampling step (every curve sample has an edge point within r).
    let opts = FeatureOptions {
        radius: Some(0.03),
        ..FeatureOptions::default()
    };
    let e = eval_features(&pts, &pts, &det, &curves, 3f64.sqrt(), &opts).unwrap();
    assert_eq!(
        (e.precision(0), e.recall(0), e.f1(0)),
        (Some(1.0), Some(1.0), Some(1.0))
    );
    assert_eq!(e.dist_max, 0.0);
    assert_eq!(e.coverage, 1.0);
    assert!((e.curve_length - 12.0).abs() < 1e-12);
    // Curves below the feature angle do not count: deviation 10 < 20.
    let soft: Vec<FeatureCurve> = curves
        .iter()
        .map(|c| FeatureCurve {
            dihedral_deg: 170.0,
            ..c.clone()
        })
        .collect();
    let e = eval_features(&pts, &pts, &det, &soft, 3f64.sqrt(), &opts).unwrap();
    assert_eq!((e.curves, e.positives[0]), (0, 0));
    assert_eq!(e.precision(0), Some(0.0));
}

#[test]
fn feature_distances_of_detected_points_are_exact() {
    // One curve along x; detected points at known heights above it.
    let curve = vec![FeatureCurve {
        points: vec![DVec3::ZERO, DVec3::X],
        dihedral_deg: 90.0,
        is_corner: false,
    }];
    let pts: Vec<DVec3> = (0..11)
        .map(|i| DVec3::new(i as f64 / 10.0, 0.0, 0.01 * i as f64))
        .collect();
    let det = vec![true; 11];
    let e = eval_features(&pts, &pts, &det, &curve, 1.0, &FeatureOptions::default()).unwrap();
    assert!((e.dist_mean - 0.05).abs() < 1e-12);
    assert!((e.dist_max - 0.1).abs() < 1e-12);
}

#[test]
fn cube_mesh_recovers_every_cube_edge() {
    let m = cube();
    let reference = Reference::mesh(m.clone()).unwrap();
    let e = eval_mesh_features(
        &m,
        &reference,
        &cube_edges(),
        None,
        &FeatureOptions::default(),
    )
    .unwrap();
    assert_eq!(e.recovery, 1.0);
    assert_eq!(e.sharp_edges, 12);
    assert!(e.faces_near == 12 && e.face_normal_max_deg < 1e-9);
    // A sphere mesh has no sharp edge near the cube's curves.
    let s = translate(&uv_sphere(24, 48, 0.5), DVec3::splat(0.5));
    let e = eval_mesh_features(
        &s,
        &reference,
        &cube_edges(),
        Some(0.05),
        &FeatureOptions::default(),
    )
    .unwrap();
    assert_eq!(e.recovery, 0.0);
}

#[test]
fn cloud_features_read_the_label_channel() {
    let pts = cube_surface_grid(10);
    let n = pts.len();
    let mut cloud = PointCloud::new(pts).unwrap();
    cloud
        .set_channel("feature", Channel::Label(vec![2; n]))
        .unwrap();
    let reference = Reference::mesh(cube()).unwrap();
    // The cube mesh's sharp edges are its 12 edges (its diagonals are flat).
    let e = eval_cloud_features(
        &cloud,
        &reference,
        CleanPositions::Observed,
        &FeatureOptions::default(),
    )
    .unwrap();
    assert_eq!(e.curves, 12);
    assert_eq!(e.recall(0), Some(1.0));
    let missing = PointCloud::new(vec![DVec3::ZERO, DVec3::X]).unwrap();
    assert!(
        eval_cloud_features(
            &missing,
            &reference,
            CleanPositions::Observed,
            &FeatureOptions::default()
        )
        .is_err()
    );
}

// ---------------------------------------------------------------- topology

#[test]
fn removing_one_face_gives_one_boundary_loop_and_not_watertight() {
    let sphere = TestSphere::unit();
    let reference = Reference::analytic(&sphere);
    let gt = GroundTruthTopology::of(&reference);
    let closed = uv_sphere(8, 16, 1.0);
    let t = eval_topology(&closed, Some(gt), &TopologyOptions::default());
    assert!(t.report.watertight);
    assert_eq!((t.topology_ok(), t.delta_f()), (Some(true), Some(0)));
    let open = without_face(&closed, 5);
    let t = eval_topology(&open, Some(gt), &TopologyOptions::default());
    assert_eq!(t.report.n_boundary_loops(), 1);
    assert!(!t.report.watertight);
    assert_eq!(t.topology_ok(), Some(false));
    // Delta F = |2V + 4(G - 1) - F| = |2V - 4 - (F_closed - 1)| = 1.
    assert_eq!(t.delta_f(), Some(1));
    let row = t.to_row();
    assert_eq!((row["boundary_loops"], row["watertight"]), (1.0, 0.0));
}

#[test]
fn delta_f_of_a_torus_with_known_genus() {
    let m = torus_grid(16, 8, 1.0, 0.3);
    let gt = GroundTruthTopology {
        genus: Some(1),
        components: 1,
        closed: true,
    };
    let t = eval_topology(&m, Some(gt), &TopologyOptions::default());
    assert_eq!(t.delta_f(), Some(0));
    assert_eq!(t.topology_ok(), Some(true));
    // Against a sphere's genus: |2V - 4 - F| = 4.
    let t = eval_topology(
        &m,
        Some(GroundTruthTopology {
            genus: Some(0),
            ..gt
        }),
        &TopologyOptions::default(),
    );
    assert_eq!((t.delta_f(), t.topology_ok()), (Some(4), Some(false)));
}

#[test]
fn two_intersecting_boxes_self_intersect_and_a_clean_torus_does_not() {
    let a = cube();
    let b = translate(&cube(), DVec3::splat(0.5));
    let both = concat(&a, &b);
    let n = count_self_intersections(&both);
    assert!(n > 0, "{n}");
    // Brute force over all non-adjacent pairs gives the same count.
    let mut bf = 0;
    for f in 0..both.n_faces() {
        for g in f + 1..both.n_faces() {
            let (ff, gg) = (both.faces()[f], both.faces()[g]);
            if ff.iter().any(|v| gg.contains(v)) {
                continue;
            }
            if reconbench_metrics::topology::tri_tri_intersect(&both.triangle(f), &both.triangle(g))
            {
                bf += 1;
            }
        }
    }
    assert_eq!(n, bf);
    assert_eq!(count_self_intersections(&torus_grid(48, 24, 1.0, 0.3)), 0);
    assert_eq!(count_self_intersections(&cube()), 0);
    assert_eq!(
        count_self_intersections(&unweld(&torus_grid(12, 6, 1.0, 0.3))),
        0
    );
    // Two disjoint boxes: none.
    let far = concat(&a, &translate(&cube(), DVec3::splat(2.0)));
    assert_eq!(count_self_intersections(&far), 0);
    // Boxes touching face to face (coplanar contact) do intersect.
    let touch = concat(&a, &translate(&cube(), DVec3::new(1.0, 0.25, 0.25)));
    assert!(count_self_intersections(&touch) > 0);
}

// ---------------------------------------------------------------- quality

#[test]
fn triangle_quality_closed_forms() {
    let eq = [
        DVec3::ZERO,
        DVec3::X,
        DVec3::new(0.5, 3f64.sqrt() / 2.0, 0.0),
    ];
    let (ang, asp) = triangle_quality(eq);
    assert!(ang.iter().all(|a| (a - 60.0).abs() < 1e-9));
    assert!((asp.unwrap() - 1.0).abs() < 1e-12);
    // Right isosceles: R = sqrt2 / 2, r = (2 - sqrt2) / 2, R / 2r = (1 + sqrt2) / 2.
    let (ang, asp) = triangle_quality([DVec3::ZERO, DVec3::X, DVec3::Y]);
    assert!((ang[0] - 90.0).abs() < 1e-9 && (ang[1] - 45.0).abs() < 1e-9);
    assert!((asp.unwrap() - (1.0 + 2f64.sqrt()) / 2.0).abs() < 1e-12);
    assert_eq!(
        triangle_quality([DVec3::ZERO, DVec3::X, DVec3::X * 2.0]).1,
        None
    );
}

#[test]
fn cube_mesh_quality() {
    let q = eval_quality(
        &cube(),
        &QualityOptions {
            target_edge_length: Some(1.2),
        },
    );
    assert_eq!(q.triangles, 12);
    assert!((q.min_angle.min - 45.0).abs() < 1e-9);
    assert!((q.max_angle.max - 90.0).abs() < 1e-9);
    assert_eq!(q.share_min_angle_below_12, 0.0);
    // 12 unit edges and 6 diagonals of length sqrt 2.
    assert_eq!(q.edge_length.count, 18);
    assert_eq!(q.share_edges_above_target, Some(6.0 / 18.0));
    let sliver = TriMesh::new(
        vec![DVec3::ZERO, DVec3::X, DVec3::new(0.5, 0.01, 0.0)],
        vec![[0, 1, 2]],
    )
    .unwrap();
    assert_eq!(
        eval_quality(&sliver, &QualityOptions::default()).share_min_angle_below_12,
        1.0
    );
}

// ---------------------------------------------------------------- entry points

#[test]
fn eval_mesh_reports_the_documented_keys() {
    let sphere = TestSphere::unit();
    let reference = Reference::analytic(&sphere);
    let opts = MeshEvalOptions {
        distance: small_opts(),
        ..MeshEvalOptions::default()
    };
    let e = eval_mesh(&uv_sphere(12, 24, 1.0), &reference, &opts).unwrap();
    let json = e.to_json();
    for key in [
        "chamfer_l1",
        "chamfer_l1_abs",
        "hausdorff",
        "fscore_0.01",
        "fscore_0.005",
        "genus",
        "watertight",
        "delta_f",
        "topology_ok",
        "self_intersections",
        "aspect_ratio_mean",
        "eval_time_distance_s",
    ] {
        assert!(json.get(key).is_some(), "missing key {key}");
    }
    assert_eq!(json["genus"], 0);
    assert_eq!(json["watertight"], true);
    assert_eq!(json["delta_f"], 0);
    assert_eq!(json["self_intersections"], 0);
    // A smooth reference has no feature curves: recovery is null.
    assert!(json["feature_recovery"].is_null());
    // serde and to_json agree.
    assert_eq!(serde_json::to_value(&e).unwrap(), json);
    let row = e.to_row();
    assert_eq!(row["topology_ok"], 1.0);
    assert!(!row.contains_key("reference"));
}

#[test]
fn cost_helpers() {
    let mut t = PhaseTimer::default();
    let v = t.time("spin", || (0..100_000u64).sum::<u64>());
    assert_eq!(v, 4_999_950_000);
    let r = CostReport::from_run_timer(&t);
    assert_eq!(r.phases.len(), 1);
    assert!(r.phases[0].wall_s >= 0.0);
    if cfg!(target_os = "linux") {
        assert!(peak_rss_bytes().unwrap() > 1 << 20);
        assert!(r.total_cpu_s.is_some());
    }
    assert!(r.to_row().contains_key("time_spin_s"));
}

#[test]
fn every_reported_key_is_documented() {
    let doc = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../docs/METRICS.md"
    ))
    .unwrap();
    let documented = |k: &str| doc.contains(&format!("`{k}`"));
    let check = |key: &str| {
        let k = key.strip_prefix("eval_").unwrap_or(key);
        let ok = documented(k)
            || k.strip_suffix("_abs").is_some_and(documented)
            || k.strip_suffix("_rad")
                .is_some_and(|b| documented(&format!("{b}_deg")))
            || (k.starts_with("time_") && k.ends_with("_s"));
        assert!(ok, "key `{key}` is not documented in docs/METRICS.md");
    };
    let reference = Reference::mesh(cube()).unwrap();
    let opts = MeshEvalOptions {
        distance: small_opts(),
        ..MeshEvalOptions::default()
    };
    let e = eval_mesh(&cube(), &reference, &opts).unwrap();
    assert!(e.features.is_some());
    for (k, _) in e.entries() {
        check(&k);
    }
    let g = vec![DVec3::Z; 3];
    let n = eval_normals(&g, &g, &NormalOptions { oriented: true }).unwrap();
    for (k, _) in n.entries() {
        check(&k);
    }
    let pts = cube_surface_grid(4);
    let det = vec![true; pts.len()];
    let f = eval_features(
        &pts,
        &pts,
        &det,
        &cube_edges(),
        1.0,
        &FeatureOptions::default(),
    )
    .unwrap();
    for (k, _) in f.entries() {
        check(&k);
    }
    let r = reconbench_metrics::eval_refused(&[0], &[true, false]).unwrap();
    for (k, _) in r.entries() {
        check(&k);
    }
}

/// Sample counts beyond what memory holds are refused before sampling, with the
/// estimate (issue 28: `min_samples = 1e11` used to die of memory inside the cell).
#[test]
fn sample_counts_beyond_memory_are_refused_with_the_estimate() {
    let mut o = MeshEvalOptions::default();
    assert!(o.validate().is_ok());
    o.distance.min_samples = 100_000_000_000;
    let e = o.validate().unwrap_err().to_string();
    assert!(
        e.contains("distance.min_samples") && e.contains("TB"),
        "{e}"
    );
    let o = DistanceOptions::default().with_samples(200_000_000);
    let e = o.validate().unwrap_err().to_string();
    assert!(
        e.contains("distance.recon_samples") && e.contains("GB"),
        "{e}"
    );
    let o = DistanceOptions {
        samples_per_face: 1_000_000,
        ..Default::default()
    };
    assert!(o.validate().is_err());
}
