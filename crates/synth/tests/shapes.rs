//! Shape ground truth: reference meshes are watertight with the declared genus, closest
//! points are exact (on the surface and globally closest), samplers are area-uniform,
//! feature distances are exact on the box.

use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use reconbench_geom::{MeshBvh, topology};
use reconbench_synth::shapes::{definitions, from_spec};
use reconbench_synth::{Shape, catalog};

/// The resolution at which every reference mesh is documented to have the right
/// topology.
const MIN_RES: usize = 48;

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn all_shapes() -> Vec<Box<dyn Shape>> {
    definitions()
        .iter()
        .map(|d| from_spec(d.name).unwrap())
        .collect()
}

#[test]
fn reference_meshes_have_declared_topology() {
    for s in all_shapes() {
        let m = s.reference_mesh(MIN_RES);
        let r = topology::analyze(&m);
        assert_eq!(r.non_manifold_edges, 0, "{}", s.name());
        assert_eq!(r.non_manifold_vertices, 0, "{}", s.name());
        assert_eq!(r.components as u32, s.components(), "{}", s.name());
        assert_eq!(r.genus, Some(s.genus()), "{}: {r:?}", s.name());
        assert!(r.consistently_oriented, "{}", s.name());
        if s.is_closed() {
            assert!(r.watertight, "{}: {r:?}", s.name());
        } else {
            assert_eq!(
                r.n_boundary_loops() as u32,
                s.boundary_loops(),
                "{}",
                s.name()
            );
        }
        // Outward orientation: positive signed volume for closed shapes.
        if s.is_closed() {
            let vol: f64 = (0..m.n_faces())
                .map(|f| {
                    let [a, b, c] = m.triangle(f);
                    a.dot(b.cross(c)) / 6.0
                })
                .sum();
            assert!(vol > 0.0, "{} volume {vol}", s.name());
        }
        // Every vertex lies on the surface.
        for &v in m.vertices().iter().step_by(7) {
            assert!(
                s.distance(v) < 1e-9,
                "{}: vertex {v} off surface by {}",
                s.name(),
                s.distance(v)
            );
        }
        // Area of a fine mesh approaches the exact area.
        let tol = if s.feature_curves().is_empty() {
            0.01
        } else {
            0.03
        };
        let rel = (s.reference_mesh(64).area() - s.area()).abs() / s.area();
        assert!(
            rel < tol,
            "{}: mesh area off by {rel} (marching tetrahedra cut sharp edges)",
            s.name()
        );
    }
}

#[test]
fn shapes_are_normalised() {
    for s in all_shapes() {
        let d = s.aabb().diagonal();
        assert!((d - 1.0).abs() < 1e-12, "{}: diagonal {d}", s.name());
        let cl = s.sample_uniform(2000, &mut rng(3));
        let b =
            reconbench_geom::Aabb::from_points(&cl.iter().map(|x| x.position).collect::<Vec<_>>());
        assert!(
            b.diagonal() <= 1.0 + 1e-12 && b.diagonal() > 0.8,
            "{}",
            s.name()
        );
    }
    assert_eq!(catalog().len(), definitions().len());
}

#[test]
fn samples_lie_on_the_surface_with_their_normals() {
    for s in all_shapes() {
        for x in s.sample_uniform(500, &mut rng(5)) {
            let c = s.closest_point(x.position);
            assert!(
                c.distance < 1e-12,
                "{}: sample off by {}",
                s.name(),
                c.distance
            );
            assert!((x.normal.length() - 1.0).abs() < 1e-12, "{}", s.name());
            // Moving along the normal leaves the solid; against it enters.
            let eps = 1e-4;
            if s.feature_distance(x.position) > 10.0 * eps {
                assert!(!s.is_inside(x.position + eps * x.normal), "{}", s.name());
                assert!(s.is_inside(x.position - eps * x.normal), "{}", s.name());
                assert!(c.normal.dot(x.normal) > 1.0 - 1e-9, "{}", s.name());
            }
        }
    }
}

#[test]
fn closest_points_are_exact_and_global() {
    for s in all_shapes() {
        let dense: Vec<DVec3> = s
            .sample_uniform(20_000, &mut rng(7))
            .into_iter()
            .map(|x| x.position)
            .collect();
        let bvh = MeshBvh::new(&s.reference_mesh(64)).unwrap();
        // Chordal error; marching-tetrahedra meshes of sharp shapes also cut edges.
        let tol = if s.feature_curves().is_empty() {
            3e-3
        } else {
            1.5e-2
        };
        let b = s.aabb();
        let mut r = rng(11);
        for q in s.sample_uniform(150, &mut r) {
            // Queries off the surface on both sides, and far away.
            for off in [-0.03, 0.01, 0.2] {
                let p = q.position
                    + q.normal * off
                    + reconbench_synth::util::unit_vector(&mut r) * 0.01;
                let c = s.closest_point(p);
                assert!(
                    (c.distance - (p - c.point).length()).abs() < 1e-14,
                    "{}",
                    s.name()
                );
                assert!(
                    s.distance(c.point) < 1e-12,
                    "{}: closest point off surface",
                    s.name()
                );
                // No dense sample is closer (global minimum).
                let dmin = dense
                    .iter()
                    .map(|d| (*d - p).length())
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    c.distance <= dmin + 1e-12,
                    "{}: {} > sample {}",
                    s.name(),
                    c.distance,
                    dmin
                );
                // Agrees with the dense reference mesh within its chordal error (away
                // from sharp features, which a marching-tetrahedra mesh rounds off).
                let dm = bvh.distance(p).unwrap();
                assert!(
                    (c.distance - dm).abs() < tol || s.feature_distance(c.point) < 0.05,
                    "{}: exact {} mesh {dm} at {p}",
                    s.name(),
                    c.distance
                );
            }
        }
        let _ = b;
    }
}

#[test]
fn uniform_sampling_passes_chi_square_over_area_bins() {
    for s in all_shapes() {
        let m = s.reference_mesh(64);
        let bvh = MeshBvh::new(&m).unwrap();
        let bins = 40;
        let nf = m.n_faces();
        let bin_of = |f: usize| f * bins / nf;
        let mut expected = vec![0.0; bins];
        for f in 0..nf {
            expected[bin_of(f)] += m.face_area(f);
        }
        let total: f64 = expected.iter().sum();
        let n = 20_000;
        let mut counts = vec![0.0; bins];
        for x in s.sample_uniform(n, &mut rng(13)) {
            let f = bvh.closest_point(x.position).unwrap().face as usize;
            counts[bin_of(f)] += 1.0;
        }
        let chi2: f64 = (0..bins)
            .map(|b| {
                let e = expected[b] / total * n as f64;
                (counts[b] - e).powi(2) / e
            })
            .sum();
        // 39 degrees of freedom: the 0.1% critical value is 72.1.
        assert!(chi2 < 72.1, "{}: chi2 = {chi2}", s.name());
    }
}

#[test]
fn box_feature_distances_are_exact() {
    let s = from_spec("box:a=1,b=2,c=3").unwrap();
    let h = s.aabb().max;
    assert_eq!(s.feature_curves().len(), 20);
    for x in s.sample_uniform(2000, &mut rng(17)) {
        let p = x.position;
        // On face `axis`, the distance to the nearest edge is the smaller gap in-plane.
        let axis = (0..3)
            .max_by(|&i, &j| (x.normal[i].abs()).total_cmp(&x.normal[j].abs()))
            .unwrap();
        let gaps: Vec<f64> = (0..3)
            .filter(|&i| i != axis)
            .map(|i| h[i] - p[i].abs())
            .collect();
        let expect = gaps[0].min(gaps[1]);
        assert!((s.feature_distance(p) - expect).abs() < 1e-15, "{p}");
    }
}

#[test]
fn parametric_grids_match_seed_000_counts() {
    assert_eq!(
        from_spec("torus")
            .unwrap()
            .parametric_grid(60, 60)
            .unwrap()
            .len(),
        3600
    );
    let cube = from_spec("box").unwrap();
    assert_eq!(cube.parametric_grid(13, 13).unwrap().len(), 866);
    assert_eq!(cube.grid_dims_for_count(866), (13, 13));
    assert_eq!(
        from_spec("ellipsoid")
            .unwrap()
            .parametric_grid(199, 50)
            .unwrap()
            .len(),
        9950
    );
    for s in all_shapes() {
        if let Some(g) = s.parametric_grid(10, 10) {
            for x in g {
                assert!(s.distance(x.position) < 1e-12, "{}", s.name());
            }
        }
    }
}

#[test]
fn specs_round_trip_and_errors_list_choices() {
    let s: reconbench_synth::ShapeSpec = "torus:R=0.5,r=0.2".parse().unwrap();
    assert_eq!(s.to_string(), "torus:R=0.5,r=0.2");
    let json = serde_json_like(&s);
    assert!(json.contains("torus"));
    let e = from_spec("tours").unwrap_err().to_string();
    assert!(e.contains("torus") && e.contains("sphere"), "{e}");
    let e = from_spec("torus:q=1").unwrap_err().to_string();
    assert!(e.contains("R=2") && e.contains("r=1"), "{e}");
    assert!(from_spec("torus:R=1,r=2").is_err());
}

fn serde_json_like(s: &reconbench_synth::ShapeSpec) -> String {
    format!("{s:?}")
}

#[test]
fn ray_intersections_land_on_the_surface() {
    for s in all_shapes() {
        let mut r = rng(19);
        let mut hits = 0;
        for q in s.sample_uniform(100, &mut r) {
            let o =
                q.position + q.normal * 0.3 + reconbench_synth::util::unit_vector(&mut r) * 0.05;
            let dir = (q.position - o).normalize();
            if let Some(t) = s.ray_intersect(o, dir, 10.0) {
                let p = o + dir * t;
                assert!(
                    s.distance(p) < 1e-11,
                    "{}: hit off by {}",
                    s.name(),
                    s.distance(p)
                );
                // No earlier crossing: the segment before the hit stays outside.
                for k in 1..20 {
                    let pp = o + dir * (t * k as f64 / 20.0);
                    assert!(s.distance(pp) > 0.0, "{}", s.name());
                }
                hits += 1;
            }
        }
        assert!(hits > 80, "{}: only {hits} hits", s.name());
    }
}
