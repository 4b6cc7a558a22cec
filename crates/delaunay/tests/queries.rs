//! Query tests: facets, incidences, circumspheres, the Gabriel test, statistics.

use std::collections::{BTreeSet, HashSet};

use glam::DVec3;
use reconbench_delaunay::{Delaunay, DelaunayStats, NO_TET};
use reconbench_testkit::points as samples;

fn facets_are_consistent(dt: &Delaunay) {
    let facets = dt.facets();
    // Lexicographic, unique, sorted triples.
    for w in facets.windows(2) {
        assert!(w[0].v < w[1].v);
    }
    for (id, f) in facets.iter().enumerate() {
        assert!(f.v[0] < f.v[1] && f.v[1] < f.v[2]);
        assert!((f.tets[0] as usize) < dt.n_tets());
        assert!(f.is_hull() || (f.tets[0] < f.tets[1] && (f.tets[1] as usize) < dt.n_tets()));
        for &t in &f.tets {
            if t != NO_TET {
                let tv = dt.tet_vertices(t);
                assert!(f.v.iter().all(|x| tv.contains(x)));
            }
        }
        for &x in &f.v {
            assert!(dt.facets_of_vertex(x).binary_search(&(id as u32)).is_ok());
        }
    }
    // Every face of every finite tetrahedron is listed.
    let set: HashSet<[u32; 3]> = facets.iter().map(|f| f.v).collect();
    assert_eq!(set.len(), facets.len());
    for t in dt.tets() {
        for i in 0..4 {
            let mut f: Vec<u32> = (0..4).filter(|&k| k != i).map(|k| t[k]).collect();
            f.sort_unstable();
            assert!(set.contains(&[f[0], f[1], f[2]]));
        }
    }
    // CSR sizes and edges.
    let total: usize = (0..dt.n_vertices() as u32)
        .map(|v| dt.facets_of_vertex(v).len())
        .sum();
    assert_eq!(total, 3 * facets.len());
    let mut edges = BTreeSet::new();
    for t in dt.tets() {
        for a in 0..4 {
            for b in a + 1..4 {
                edges.insert((t[a].min(t[b]), t[a].max(t[b])));
            }
        }
    }
    for v in 0..dt.n_vertices() as u32 {
        let e = dt.edges_of_vertex(v);
        assert!(e.windows(2).all(|w| w[0] < w[1]));
        for &w in e {
            assert!(edges.contains(&(v.min(w), v.max(w))));
            assert!(dt.edges_of_vertex(w).contains(&v));
        }
    }
    let n_e: usize = (0..dt.n_vertices() as u32)
        .map(|v| dt.edges_of_vertex(v).len())
        .sum();
    assert_eq!(n_e, 2 * edges.len());
}

#[test]
fn facets_and_incidences() {
    facets_are_consistent(&Delaunay::new(&samples::uniform_cube(1500, 1)).unwrap());
    facets_are_consistent(&Delaunay::new(&samples::grid(7, 1.0)).unwrap());
    facets_are_consistent(&Delaunay::new(&samples::cube_surface_grid(8)).unwrap());
}

#[test]
fn circumspheres() {
    let dt = Delaunay::new(&samples::uniform_cube(1000, 2)).unwrap();
    for t in 0..dt.n_tets() as u32 {
        let c = dt.circumcenter(t);
        let r = dt.circumradius(t);
        for v in dt.tet_vertices(t) {
            let d = c.distance(dt.vertex(v));
            assert!((d - r).abs() <= 1e-9 * r.max(1.0), "{d} vs {r}");
        }
    }
    let ghost = dt.n_tets() as u32;
    assert!(dt.is_infinite(ghost));
    assert!(!dt.circumcenter(ghost).is_finite());
    assert_eq!(dt.circumradius(ghost), f64::INFINITY);
    for f in 0..dt.facets().len() as u32 {
        let (c, r) = dt.facet_circumsphere(f);
        let v = dt.facets()[f as usize].v.map(|x| dt.vertex(x));
        for p in v {
            assert!((c.distance(p) - r).abs() <= 1e-9 * r.max(1.0));
        }
        let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
        assert!((c - v[0]).dot(n).abs() <= 1e-9);
    }
}

/// Exact brute-force Gabriel test for integer coordinates (every quantity below is an
/// integer < 2^53, so f64 arithmetic is exact).
fn gabriel_brute_integer(dt: &Delaunay, f: u32) -> bool {
    let v = dt.facets()[f as usize].v;
    let a = dt.vertex(v[0]);
    let u = dt.vertex(v[1]) - a;
    let w = dt.vertex(v[2]) - a;
    let n = u.cross(w);
    (0..dt.n_vertices() as u32).all(|x| {
        let q = dt.vertex(x) - a;
        let g = u.length_squared() * q.dot(w.cross(n)) + w.length_squared() * q.dot(n.cross(u))
            - q.length_squared() * n.length_squared();
        g <= 0.0
    })
}

#[test]
fn gabriel_exact_on_grids() {
    for pts in [
        samples::grid(6, 1.0),
        samples::cube_surface_grid(6)
            .iter()
            .map(|p| (*p * 6.0).round())
            .collect(),
        samples::integer_sphere(27),
        {
            // A jittered integer cloud with duplicates of structure.
            let mut p = samples::grid(5, 2.0);
            p.extend(
                samples::grid(4, 2.0)
                    .iter()
                    .map(|&x| x + DVec3::new(1.0, 1.0, 0.0)),
            );
            p
        },
    ] {
        let dt = Delaunay::new(&pts).unwrap();
        dt.validate().unwrap();
        let flags = dt.gabriel_flags();
        let mut n_gabriel = 0;
        for f in 0..dt.facets().len() as u32 {
            assert_eq!(
                flags[f as usize],
                gabriel_brute_integer(&dt, f),
                "facet {f}"
            );
            n_gabriel += usize::from(flags[f as usize]);
        }
        assert!(n_gabriel > 0);
    }
}

#[test]
fn gabriel_random_against_brute_force() {
    let dt = Delaunay::new(&samples::torus_surface(1500, 3)).unwrap();
    let pts = dt.vertices();
    let mut n_gabriel = 0;
    for f in 0..dt.facets().len() as u32 {
        let (c, r) = dt.facet_circumsphere(f);
        let r2 = r * r;
        let mut inside = false;
        let mut ambiguous = false;
        for p in pts {
            let d2 = c.distance_squared(*p);
            if d2 < r2 * (1.0 - 1e-9) {
                inside = true;
            } else if d2 < r2 * (1.0 + 1e-9)
                && !dt.facets()[f as usize]
                    .v
                    .iter()
                    .any(|&x| dt.vertex(x) == *p)
            {
                ambiguous = true;
            }
        }
        if !ambiguous {
            assert_eq!(dt.is_gabriel(f), !inside, "facet {f}");
        }
        n_gabriel += usize::from(dt.is_gabriel(f));
    }
    // Most facets of a dense surface sample are not Gabriel, some are.
    assert!(n_gabriel > 100 && n_gabriel < dt.facets().len());
}

#[test]
fn stats_serialize_and_print() {
    let mut pts = samples::uniform_cube(400, 5);
    pts.push(pts[0]);
    let dt = Delaunay::new(&pts).unwrap();
    let s = dt.stats();
    assert_eq!(s.input_points, 401);
    assert_eq!(s.vertices, 400);
    assert_eq!(s.duplicates_merged, 1);
    assert!(s.total_s >= s.insert_s && s.insert_s >= 0.0);
    let json = serde_json::to_string(s).unwrap();
    let back: DelaunayStats = serde_json::from_str(&json).unwrap();
    assert_eq!(&back, s);
    let text = s.to_string();
    for key in [
        "tetrahedra",
        "facets",
        "hull facets",
        "duplicates merged",
        "sort",
        "insert",
        "total",
    ] {
        assert!(text.contains(key), "{text}");
    }
    assert!(format!("{dt:?}").contains("Delaunay"));
    assert_eq!(dt.vertex_tets().len(), 400);
}

#[test]
fn delaunay_is_send_and_sync() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<Delaunay>();
    // Lazy queries from several threads at once.
    let dt = Delaunay::new(&samples::uniform_cube(500, 9)).unwrap();
    std::thread::scope(|s| {
        let h: Vec<_> = (0..3)
            .map(|_| s.spawn(|| dt.edges_of_vertex(7).len() + dt.facets().len()))
            .collect();
        let r: Vec<usize> = h.into_iter().map(|h| h.join().unwrap()).collect();
        assert!(r.windows(2).all(|w| w[0] == w[1]));
    });
}
