//! Fixtures of the metric tests and benches: a tiny analytic sphere implementing
//! `Shape`, small meshes and mesh edits, a brute-force distance.

use std::f64::consts::PI;

use glam::DVec3;
use rand::{Rng, RngExt};
use reconbench_geom::{Aabb, TriMesh};
use reconbench_synth::{Sample, Shape, SurfacePoint};

/// Sphere of `radius` around `center` (not normalised to unit diagonal: metrics take
/// the diagonal from `aabb()`).
#[derive(Debug, Clone, Copy)]
pub struct TestSphere {
    /// Centre.
    pub center: DVec3,
    /// Radius.
    pub radius: f64,
}

impl TestSphere {
    /// The unit sphere at the origin.
    pub fn unit() -> Self {
        TestSphere {
            center: DVec3::ZERO,
            radius: 1.0,
        }
    }
}

impl Shape for TestSphere {
    fn name(&self) -> &str {
        "test-sphere"
    }
    fn closest_point(&self, p: DVec3) -> SurfacePoint {
        let d = p - self.center;
        let l = d.length();
        let normal = if l > 0.0 { d / l } else { DVec3::Z };
        SurfacePoint {
            point: self.center + self.radius * normal,
            normal,
            distance: (l - self.radius).abs(),
        }
    }
    fn is_inside(&self, p: DVec3) -> bool {
        (p - self.center).length() < self.radius
    }
    fn sample_uniform(&self, n: usize, rng: &mut dyn Rng) -> Vec<Sample> {
        (0..n)
            .map(|_| {
                let z: f64 = 2.0 * rng.random::<f64>() - 1.0;
                let phi: f64 = 2.0 * PI * rng.random::<f64>();
                let r = (1.0 - z * z).max(0.0).sqrt();
                let normal = DVec3::new(r * phi.cos(), r * phi.sin(), z);
                Sample {
                    position: self.center + self.radius * normal,
                    normal,
                }
            })
            .collect()
    }
    fn aabb(&self) -> Aabb {
        Aabb {
            min: self.center - DVec3::splat(self.radius),
            max: self.center + DVec3::splat(self.radius),
        }
    }
    fn scale(&self) -> f64 {
        1.0
    }
    fn area(&self) -> f64 {
        4.0 * PI * self.radius * self.radius
    }
    fn genus(&self) -> u32 {
        0
    }
    fn reference_mesh(&self, resolution: usize) -> TriMesh {
        let m = crate::meshes::uv_sphere(resolution.max(2), 2 * resolution.max(2), self.radius);
        translate(&m, self.center)
    }
}

/// The regular icosahedron inscribed in the unit sphere (outward faces).
pub fn icosahedron() -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let v: Vec<DVec3> = [
        [-1., t, 0.],
        [1., t, 0.],
        [-1., -t, 0.],
        [1., -t, 0.],
        [0., -1., t],
        [0., 1., t],
        [0., -1., -t],
        [0., 1., -t],
        [t, 0., -1.],
        [t, 0., 1.],
        [-t, 0., -1.],
        [-t, 0., 1.],
    ]
    .iter()
    .map(|a| DVec3::from_array(*a).normalize())
    .collect();
    let f = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    TriMesh::new(v, f).unwrap()
}

/// `mesh` moved by `d`.
pub fn translate(mesh: &TriMesh, d: DVec3) -> TriMesh {
    TriMesh::new(
        mesh.vertices().iter().map(|&p| p + d).collect(),
        mesh.faces().to_vec(),
    )
    .unwrap()
}

/// Two meshes as one (vertices of `b` renumbered).
pub fn concat(a: &TriMesh, b: &TriMesh) -> TriMesh {
    let n = a.n_vertices() as u32;
    let mut v = a.vertices().to_vec();
    v.extend_from_slice(b.vertices());
    let mut f = a.faces().to_vec();
    f.extend(b.faces().iter().map(|t| t.map(|i| i + n)));
    TriMesh::new(v, f).unwrap()
}

/// `mesh` without face `k`.
pub fn without_face(mesh: &TriMesh, k: usize) -> TriMesh {
    let mut f = mesh.faces().to_vec();
    f.remove(k);
    TriMesh::new(mesh.vertices().to_vec(), f).unwrap()
}

/// Each face with its own three vertices (an STL-like soup).
pub fn unweld(mesh: &TriMesh) -> TriMesh {
    let mut v = Vec::new();
    let mut f = Vec::new();
    for i in 0..mesh.n_faces() {
        let t = mesh.triangle(i);
        let b = v.len() as u32;
        v.extend_from_slice(&t);
        f.push([b, b + 1, b + 2]);
    }
    TriMesh::new(v, f).unwrap()
}

/// Brute-force unsigned distance from `p` to a mesh.
pub fn brute_distance(mesh: &TriMesh, p: DVec3) -> f64 {
    (0..mesh.n_faces())
        .map(|f| {
            let [a, b, c] = mesh.triangle(f);
            (reconbench_geom::closest_point_on_triangle(p, a, b, c) - p).length()
        })
        .fold(f64::INFINITY, f64::min)
}

/// A small deterministic generator for test data.
#[derive(Debug)]
pub struct Lcg(pub u64);

impl Lcg {
    /// The next uniform number in `[0, 1)`.
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    /// A uniformly distributed unit vector.
    pub fn unit_vector(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                2.0 * self.next_f64() - 1.0,
                2.0 * self.next_f64() - 1.0,
                2.0 * self.next_f64() - 1.0,
            );
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}
