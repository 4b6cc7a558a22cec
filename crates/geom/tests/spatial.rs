//! PointIndex and MeshBvh against brute force.

use reconbench_geom::spatial::{
    MeshBvh, Neighbor, PointIndex, closest_point_on_segment, closest_point_on_triangle,
    closest_point_on_triangle_bary, knn_self_map, knn_self_table, mean_spacing,
};
use reconbench_geom::{DVec3, GeomError, TriMesh};
use reconbench_testkit::meshes as examples;

/// SplitMix64: a tiny deterministic generator (no rand dependency needed).
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn vec(&mut self, lo: f64, hi: f64) -> DVec3 {
        DVec3::new(
            lo + (hi - lo) * self.f64(),
            lo + (hi - lo) * self.f64(),
            lo + (hi - lo) * self.f64(),
        )
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

fn brute_sorted(points: &[DVec3], p: DVec3) -> Vec<Neighbor> {
    let mut v: Vec<Neighbor> = points
        .iter()
        .enumerate()
        .map(|(i, q)| Neighbor {
            index: i as u32,
            dist2: (p - *q).length_squared(),
        })
        .collect();
    v.sort_by(|a, b| a.dist2.total_cmp(&b.dist2).then(a.index.cmp(&b.index)));
    v
}

fn brute_knn(points: &[DVec3], p: DVec3, k: usize) -> Vec<Neighbor> {
    let mut v = brute_sorted(points, p);
    v.truncate(k);
    v
}

fn random_points(rng: &mut Rng, n: usize) -> Vec<DVec3> {
    (0..n).map(|_| rng.vec(-1.0, 1.0)).collect()
}

fn grid(n: usize, h: f64) -> Vec<DVec3> {
    let mut v = Vec::new();
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                v.push(DVec3::new(i as f64, j as f64, k as f64) * h);
            }
        }
    }
    v
}

/// A random set where many points are exact duplicates (some 40 times).
fn duplicated(rng: &mut Rng) -> Vec<DVec3> {
    let base = random_points(rng, 300);
    let mut v = Vec::new();
    for (i, p) in base.iter().enumerate() {
        for _ in 0..1 + i % 4 {
            v.push(*p);
        }
    }
    v.extend(std::iter::repeat_n(DVec3::splat(0.25), 40));
    // Shuffle so duplicates are not adjacent in index order.
    for i in (1..v.len()).rev() {
        let j = rng.below(i + 1);
        v.swap(i, j);
    }
    v
}

fn check_knn_exact(points: &[DVec3], queries: &[DVec3]) {
    let idx = PointIndex::new(points).unwrap();
    for &q in queries {
        for k in [1, 2, 5, 16, 33] {
            assert_eq!(
                idx.knn(q, k).unwrap(),
                brute_knn(points, q, k),
                "k {k} q {q}"
            );
        }
        assert_eq!(idx.nearest(q).unwrap(), brute_knn(points, q, 1)[0]);
    }
    let table = idx.knn_batch(queries, 7).unwrap();
    for (i, &q) in queries.iter().enumerate() {
        let b = brute_knn(points, q, 7);
        assert_eq!(
            table.indices(i),
            b.iter().map(|n| n.index).collect::<Vec<_>>()
        );
        assert_eq!(
            table.dist2(i),
            b.iter().map(|n| n.dist2).collect::<Vec<_>>()
        );
    }
    let nb = idx.nearest_batch(queries).unwrap();
    for (i, &q) in queries.iter().enumerate() {
        assert_eq!(nb[i], brute_knn(points, q, 1)[0]);
    }
}

fn check_knn_all(points: &[DVec3], k: usize) {
    let idx = PointIndex::new(points).unwrap();
    let t = idx.knn_all(k, true).unwrap();
    assert_eq!(t.rows(), points.len());
    for (i, &p) in points.iter().enumerate() {
        let b: Vec<Neighbor> = brute_sorted(points, p)
            .into_iter()
            .filter(|n| n.index as usize != i)
            .take(k)
            .collect();
        assert_eq!(
            t.indices(i),
            b.iter().map(|n| n.index).collect::<Vec<_>>(),
            "row {i}"
        );
        assert_eq!(t.dist2(i), b.iter().map(|n| n.dist2).collect::<Vec<_>>());
    }
    let t = idx.knn_all(k, false).unwrap();
    for (i, &p) in points.iter().enumerate().step_by(7) {
        let b = brute_knn(points, p, k);
        assert_eq!(t.indices(i), b.iter().map(|n| n.index).collect::<Vec<_>>());
    }
}

#[test]
fn knn_random_matches_brute_force() {
    let mut rng = Rng(1);
    let pts = random_points(&mut rng, 3000);
    let queries: Vec<DVec3> = (0..150).map(|_| rng.vec(-1.2, 1.2)).collect();
    check_knn_exact(&pts, &queries);
    check_knn_all(&pts[..800], 8);
}

/// The all-points kNN shares one candidate list per tree leaf and falls back to per-point
/// queries where the list would be long: a surface sample (the shared path), a dense
/// cluster inside a sparse cloud (long lists near the cluster's rim) and a point far out
/// all match brute force, for k below, at and above the leaf size.
#[test]
fn knn_all_matches_brute_force_across_densities() {
    let mut rng = Rng(11);
    let mut pts: Vec<DVec3> = (0..1500)
        .map(|_| {
            let v = rng.vec(-1.0, 1.0);
            let (u, w) = (v.x * std::f64::consts::PI, v.y * std::f64::consts::PI);
            let c = 1.0 + 0.4 * w.cos();
            DVec3::new(c * u.cos(), c * u.sin(), 0.4 * w.sin())
        })
        .collect();
    pts.extend((0..600).map(|_| rng.vec(-1e-3, 1e-3) + DVec3::new(1.4, 0.0, 0.0)));
    pts.extend(random_points(&mut rng, 200).into_iter().map(|p| p * 3.0));
    pts.push(DVec3::new(50.0, -20.0, 7.0));
    for k in [1, 5, 16, 40] {
        check_knn_all(&pts, k);
    }
}

#[test]
fn knn_grid_ties_broken_by_index() {
    let pts = grid(9, 0.5);
    let mut rng = Rng(2);
    // Grid points, cell centres, face centres: many exact ties.
    let mut queries: Vec<DVec3> = (0..60).map(|_| pts[rng.below(pts.len())]).collect();
    queries.extend((0..30).map(|_| {
        let p = pts[rng.below(pts.len())];
        p + DVec3::new(0.25, 0.25, 0.25)
    }));
    queries.extend((0..30).map(|_| pts[rng.below(pts.len())] + DVec3::new(0.25, 0.0, 0.25)));
    check_knn_exact(&pts, &queries);
    check_knn_all(&pts, 6);
    check_knn_all(&pts, 19);
}

#[test]
fn knn_with_duplicates() {
    let mut rng = Rng(3);
    let pts = duplicated(&mut rng);
    let mut queries: Vec<DVec3> = (0..50).map(|_| pts[rng.below(pts.len())]).collect();
    queries.push(DVec3::splat(0.25));
    queries.extend((0..50).map(|_| rng.vec(-1.0, 1.0)));
    check_knn_exact(&pts, &queries);
    check_knn_all(&pts, 1);
    check_knn_all(&pts, 12);
    // The 40 copies: excluding self leaves the 39 others (lowest indices first), at 0.
    let idx = PointIndex::new(&pts).unwrap();
    let t = idx.knn_all(45, true).unwrap();
    let i = pts.iter().position(|p| *p == DVec3::splat(0.25)).unwrap();
    assert!(t.dist2(i)[..39].iter().all(|&d| d == 0.0));
    assert!(t.dist2(i)[39] > 0.0);
    assert!(!t.indices(i).contains(&(i as u32)));
}

#[test]
fn all_points_identical() {
    let pts = vec![DVec3::new(1.0, 2.0, 3.0); 100];
    let idx = PointIndex::new(&pts).unwrap();
    let r = idx.knn(DVec3::ZERO, 5).unwrap();
    assert_eq!(
        r.iter().map(|n| n.index).collect::<Vec<_>>(),
        vec![0, 1, 2, 3, 4]
    );
    let t = idx.knn_all(3, true).unwrap();
    assert_eq!(t.indices(0), &[1, 2, 3]);
    assert_eq!(t.indices(50), &[0, 1, 2]);
    assert!(mean_spacing(&pts, 1).is_err());
}

#[test]
fn radius_matches_brute_force() {
    let mut rng = Rng(4);
    let pts = random_points(&mut rng, 2000);
    let idx = PointIndex::new(&pts).unwrap();
    let queries: Vec<DVec3> = (0..100).map(|_| rng.vec(-1.0, 1.0)).collect();
    for &q in &queries {
        for r in [0.0, 0.05, 0.2, 0.5] {
            let b: Vec<Neighbor> = brute_sorted(&pts, q)
                .into_iter()
                .filter(|n| n.dist2 <= r * r)
                .collect();
            assert_eq!(idx.radius(q, r).unwrap(), b);
        }
    }
    let t = idx.radius_batch(&queries, 0.2).unwrap();
    assert_eq!(t.rows(), queries.len());
    for (i, &q) in queries.iter().enumerate() {
        let b = idx.radius(q, 0.2).unwrap();
        assert_eq!(t.indices(i), b.iter().map(|n| n.index).collect::<Vec<_>>());
        assert_eq!(t.dist2(i), b.iter().map(|n| n.dist2).collect::<Vec<_>>());
    }
    // Grid: the radius is inclusive.
    let g = grid(5, 1.0);
    let gi = PointIndex::new(&g).unwrap();
    assert_eq!(gi.radius(DVec3::splat(2.0), 1.0).unwrap().len(), 7);
}

#[test]
fn bad_input_is_an_error() {
    assert!(PointIndex::new(&[]).is_err());
    assert!(matches!(
        PointIndex::new(&[DVec3::ZERO, DVec3::new(f64::NAN, 0.0, 0.0)]),
        Err(GeomError::NonFinite { index: 1, .. })
    ));
    let idx = PointIndex::new(&[DVec3::ZERO, DVec3::X, DVec3::Y]).unwrap();
    assert!(idx.knn(DVec3::splat(f64::INFINITY), 2).is_err());
    assert!(idx.nearest(DVec3::splat(f64::NAN)).is_err());
    assert!(idx.radius(DVec3::ZERO, -1.0).is_err());
    assert!(idx.radius(DVec3::ZERO, f64::NAN).is_err());
    assert!(idx.knn_all(0, true).is_err());
    assert!(
        idx.knn_batch(&[DVec3::ZERO, DVec3::splat(f64::NAN)], 1)
            .is_err()
    );
    assert_eq!(idx.knn(DVec3::ZERO, 0).unwrap(), vec![]);
    // k > n is clamped.
    assert_eq!(idx.knn(DVec3::ZERO, 10).unwrap().len(), 3);
    let t = idx.knn_all(10, true).unwrap();
    assert_eq!(t.k, 2);
    assert_eq!(t.indices(0), &[1, 2]);
    assert_eq!(idx.knn_all(10, false).unwrap().k, 3);
    let single = PointIndex::new(&[DVec3::ZERO]).unwrap();
    assert!(single.knn_all(1, true).is_err());
    assert_eq!(single.knn_all(1, false).unwrap().indices, vec![0]);
    assert!(mean_spacing(&[], 1).is_err());
    assert!(mean_spacing(&[DVec3::ZERO, DVec3::X], 0).is_err());
}

#[test]
fn mean_spacing_of_grid_and_duplicates() {
    let g = grid(6, 0.1);
    assert!((mean_spacing(&g, 1).unwrap() - 0.1).abs() < 1e-12);
    let mut d = g.clone();
    d.extend_from_slice(&g);
    d.extend_from_slice(&g[..50]);
    assert!((mean_spacing(&d, 1).unwrap() - 0.1).abs() < 1e-12);
    // -0.0 and 0.0 are the same position.
    let s = mean_spacing(&[DVec3::ZERO, DVec3::new(-0.0, 0.0, 0.0), DVec3::X], 1).unwrap();
    assert_eq!(s, 1.0);
    // k clamped to distinct - 1.
    let s = mean_spacing(&[DVec3::ZERO, DVec3::X, DVec3::ZERO], 5).unwrap();
    assert_eq!(s, 1.0);
}

/// Distance from p to triangle abc by dense sampling (an upper bound of the true one).
fn sampled_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3, n: usize) -> f64 {
    let mut best = f64::INFINITY;
    for i in 0..=n {
        for j in 0..=n - i {
            let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
            let x = a + u * (b - a) + v * (c - a);
            best = best.min((x - p).length());
        }
    }
    best
}

#[test]
fn closest_point_on_triangle_is_optimal() {
    let mut rng = Rng(5);
    for _ in 0..300 {
        let (a, b, c) = (rng.vec(-1.0, 1.0), rng.vec(-1.0, 1.0), rng.vec(-1.0, 1.0));
        let p = rng.vec(-2.0, 2.0);
        let (q, w) = closest_point_on_triangle_bary(p, a, b, c);
        assert!(w.iter().all(|&x| (-1e-12..=1.0 + 1e-12).contains(&x)));
        assert!((w[0] + w[1] + w[2] - 1.0).abs() < 1e-12);
        assert!((w[0] * a + w[1] * b + w[2] * c - q).length() < 1e-12);
        let d = (q - p).length();
        assert!(d <= sampled_distance(p, a, b, c, 60) + 1e-12);
        // First-order optimality: no random point of the triangle is closer.
        for _ in 0..20 {
            let (mut u, mut v) = (rng.f64(), rng.f64());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let x = a + u * (b - a) + v * (c - a);
            assert!(d <= (x - p).length() + 1e-12);
        }
    }
}

#[test]
fn closest_point_on_degenerate_triangles() {
    let p = DVec3::new(0.3, 1.0, 0.0);
    // Collinear.
    let q = closest_point_on_triangle(p, DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0));
    assert!((q - DVec3::new(0.3, 0.0, 0.0)).length() < 1e-15);
    // All corners equal.
    let q = closest_point_on_triangle(p, DVec3::ONE, DVec3::ONE, DVec3::ONE);
    assert_eq!(q, DVec3::ONE);
    // Two corners equal.
    let q = closest_point_on_triangle(p, DVec3::ZERO, DVec3::ZERO, DVec3::X);
    assert!((q - DVec3::new(0.3, 0.0, 0.0)).length() < 1e-15);
    let (q, t) = closest_point_on_segment(DVec3::new(5.0, 1.0, 0.0), DVec3::ZERO, DVec3::X);
    assert_eq!((q, t), (DVec3::X, 1.0));
}

fn brute_mesh_distance(m: &TriMesh, p: DVec3) -> f64 {
    (0..m.n_faces())
        .map(|f| {
            let [a, b, c] = m.triangle(f);
            (closest_point_on_triangle(p, a, b, c) - p).length()
        })
        .fold(f64::INFINITY, f64::min)
}

fn check_bvh(m: &TriMesh, queries: &[DVec3]) {
    let bvh = MeshBvh::new(m).unwrap();
    let hits = bvh.closest_points(queries).unwrap();
    let mut max_err: f64 = 0.0;
    for (&q, h) in queries.iter().zip(&hits) {
        let d = brute_mesh_distance(m, q);
        max_err = max_err.max((h.distance - d).abs());
        assert!(h.distance.is_finite() && h.point.is_finite());
        assert!(((h.point - q).length() - h.distance).abs() < 1e-15);
        // The reported face really contains the point.
        let [a, b, c] = m.triangle(h.face as usize);
        assert!((closest_point_on_triangle(q, a, b, c) - q).length() - h.distance < 1e-12);
        assert_eq!(*h, bvh.closest_point(q).unwrap());
    }
    assert!(max_err < 1e-12, "max error {max_err}");
}

#[test]
fn bvh_matches_brute_force_on_random_soup() {
    let mut rng = Rng(6);
    let v: Vec<DVec3> = (0..600).map(|_| rng.vec(-1.0, 1.0)).collect();
    let f: Vec<[u32; 3]> = (0..200)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2].map(|x| x as u32))
        .collect();
    let m = TriMesh::new(v, f).unwrap();
    let queries: Vec<DVec3> = (0..2000).map(|_| rng.vec(-1.5, 1.5)).collect();
    check_bvh(&m, &queries);
}

#[test]
fn bvh_matches_brute_force_on_a_torus() {
    let mut rng = Rng(7);
    let m = examples::torus_grid(40, 20, 2.0, 0.6);
    let queries: Vec<DVec3> = (0..1000).map(|_| rng.vec(-3.0, 3.0)).collect();
    check_bvh(&m, &queries);
    // Points on the surface have distance ~0.
    let bvh = MeshBvh::new(&m).unwrap();
    for &v in m.vertices().iter().step_by(13) {
        assert!(bvh.distance(v).unwrap() < 1e-15);
    }
}

#[test]
fn bvh_accepts_degenerate_duplicate_and_non_manifold_faces() {
    let mut rng = Rng(8);
    let mut v = examples::cube().vertices().to_vec();
    v.push(DVec3::new(2.0, 0.0, 0.0)); // 8
    v.push(DVec3::new(3.0, 0.0, 0.0)); // 9
    v.push(DVec3::new(0.5, 0.5, 2.0)); // 10
    let mut f = examples::cube().faces().to_vec();
    f.push([1, 8, 9]); // collinear
    f.push([8, 8, 8]); // a point
    f.push([9, 9, 10]); // a segment
    f.push(f[0]); // duplicate
    f.push([f[0][0], f[0][2], f[0][1]]); // flipped duplicate
    f.push([4, 5, 10]); // third face on edge 4-5
    let m = TriMesh::new(v, f).unwrap();
    let queries: Vec<DVec3> = (0..1500).map(|_| rng.vec(-1.0, 4.0)).collect();
    check_bvh(&m, &queries);
    let bvh = MeshBvh::new(&m).unwrap();
    let h = bvh.closest_point(DVec3::new(2.5, -1.0, 0.0)).unwrap();
    assert!((h.distance - 1.0).abs() < 1e-15);
    // Only degenerate faces.
    let m = TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0], vec![[0, 1, 2]]).unwrap();
    let bvh = MeshBvh::new(&m).unwrap();
    assert!((bvh.distance(DVec3::new(1.5, 2.0, 0.0)).unwrap() - 2.0).abs() < 1e-15);
    assert!(
        bvh.ray_cast(DVec3::new(1.0, -1.0, 0.0), DVec3::Y, 10.0)
            .unwrap()
            .is_none_or(|h| h.t.is_finite())
    );
}

#[test]
fn bvh_errors() {
    assert!(MeshBvh::new(&TriMesh::default()).is_err());
    assert!(MeshBvh::new(&TriMesh::new(vec![DVec3::ZERO; 3], vec![]).unwrap()).is_err());
    let bvh = MeshBvh::new(&examples::cube()).unwrap();
    assert!(bvh.closest_point(DVec3::splat(f64::NAN)).is_err());
    assert!(matches!(
        bvh.closest_points(&[DVec3::ZERO, DVec3::splat(f64::INFINITY)]),
        Err(GeomError::NonFinite { index: 1, .. })
    ));
    assert!(bvh.ray_cast(DVec3::ZERO, DVec3::ZERO, 1.0).is_err());
    assert!(bvh.ray_cast(DVec3::ZERO, DVec3::X, f64::NAN).is_err());
    assert!(bvh.ray_cast(DVec3::splat(f64::NAN), DVec3::X, 1.0).is_err());
}

#[test]
fn ray_casts_on_a_cube() {
    let m = examples::cube();
    let bvh = MeshBvh::new(&m).unwrap();
    // From outside, towards -x: hits the +x face (faces 10, 11) at x = 1.
    let h = bvh
        .ray_cast(DVec3::new(3.0, 0.3, 0.6), -DVec3::X, f64::INFINITY)
        .unwrap()
        .unwrap();
    assert!((h.t - 2.0).abs() < 1e-12);
    assert!((h.point - DVec3::new(1.0, 0.3, 0.6)).length() < 1e-12);
    assert!(h.face == 10 || h.face == 11, "face {}", h.face);
    assert_eq!(h.normal, DVec3::X);
    // Non-unit direction: t is in units of dir.
    let h = bvh
        .ray_cast(DVec3::new(0.5, 0.5, 4.0), DVec3::new(0.0, 0.0, -2.0), 100.0)
        .unwrap()
        .unwrap();
    assert!((h.t - 1.5).abs() < 1e-12);
    assert_eq!(h.normal, DVec3::Z);
    // From inside: hits the far wall from behind; normal still outward.
    let h = bvh
        .ray_cast(DVec3::splat(0.5), DVec3::Y, f64::INFINITY)
        .unwrap()
        .unwrap();
    assert!((h.t - 0.5).abs() < 1e-12);
    assert_eq!(h.normal, DVec3::Y);
    assert!(h.face == 6 || h.face == 7);
    // Too short, or missing.
    assert!(
        bvh.ray_cast(DVec3::new(3.0, 0.5, 0.5), -DVec3::X, 1.9)
            .unwrap()
            .is_none()
    );
    assert!(
        bvh.ray_cast(DVec3::new(3.0, 0.5, 0.5), DVec3::X, f64::INFINITY)
            .unwrap()
            .is_none()
    );
    assert!(
        bvh.ray_cast(DVec3::new(3.0, 2.0, 0.5), -DVec3::X, f64::INFINITY)
            .unwrap()
            .is_none()
    );
    // Random rays from outside towards the centre always hit, at distance matching the
    // analytic box intersection.
    let mut rng = Rng(9);
    for _ in 0..200 {
        let o = DVec3::splat(0.5) + 3.0 * rng.vec(-1.0, 1.0).normalize();
        let dir = (DVec3::splat(0.5) - o).normalize();
        let h = bvh.ray_cast(o, dir, f64::INFINITY).unwrap().unwrap();
        // Slab method.
        let inv = dir.recip();
        let t0 = (DVec3::ZERO - o) * inv;
        let t1 = (DVec3::ONE - o) * inv;
        let tmin = t0.min(t1).max_element();
        assert!((h.t - tmin).abs() < 1e-12);
        assert!(h.normal.dot(dir) < 0.0);
    }
}

/// `knn_self_map` sees exactly the rows of `knn_self_table` (= `knn_all`), with the right
/// positions, on random, grid and duplicated sets, with and without the point itself.
#[test]
fn knn_self_map_matches_the_table() {
    let mut rng = Rng(9);
    let sets = [
        random_points(&mut rng, 700),
        grid(7, 0.5),
        duplicated(&mut rng),
    ];
    for pts in &sets {
        for (k, excl) in [(1, true), (9, true), (16, false), (40, false)] {
            let t = knn_self_table(pts, k, excl).unwrap();
            let idx = PointIndex::new(pts).unwrap();
            assert_eq!(idx.knn_all(k, excl).unwrap(), t);
            let ok = knn_self_map(
                pts,
                k,
                excl,
                || (),
                |_, i, hits| {
                    hits.len() == t.k
                        && hits.iter().enumerate().all(|(j, h)| {
                            h.index == t.indices(i)[j]
                                && h.dist2 == t.dist2(i)[j]
                                && h.point == pts[h.index as usize]
                        })
                },
            )
            .unwrap();
            assert!(ok.iter().all(|&b| b), "k = {k}, exclude_self = {excl}");
        }
    }
    // Many exact copies: the lowest indices win (and the query stays cheap).
    let pts = vec![DVec3::new(0.5, -1.0, 2.0); 5000];
    let t = knn_self_table(&pts, 4, false).unwrap();
    assert_eq!(t.indices(4999), &[0, 1, 2, 3]);
    assert!(knn_self_table(&[], 3, false).is_err());
    assert!(knn_self_table(&[DVec3::ZERO], 1, true).is_err());
    assert!(knn_self_map(&[DVec3::splat(f64::NAN)], 1, false, || (), |_, _, _| 0).is_err());
}
