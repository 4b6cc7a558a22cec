//! A user's triangle mesh as a [`Shape`], so that it can be sampled and scanned like the
//! analytic shapes (closest points and ray casts through the geom crate's BVH).

use glam::DVec3;
use rand::Rng;
use reconbench_geom::{Aabb, MeshBvh, TriMesh, topology};

use crate::error::{Result, SynthError};
use crate::shape::{Sample, Shape, SurfacePoint};
use crate::util::{cumulative, pick_weighted, unit};

/// A triangle mesh with exact (piecewise-planar) ground truth. It keeps its own
/// coordinates (`scale() == 1`, no normalisation); normals are face normals (right-hand
/// rule, so the mesh should be consistently oriented outwards); no feature curves.
#[derive(Debug)]
pub struct MeshShape {
    name: String,
    mesh: TriMesh,
    bvh: MeshBvh,
    cum: Vec<f64>,
    genus: u32,
    components: u32,
    closed: bool,
}

impl MeshShape {
    /// Wraps `mesh` (at least one non-degenerate face).
    pub fn new(name: &str, mesh: TriMesh) -> Result<Self> {
        let bvh = MeshBvh::new(&mesh)?;
        let areas: Vec<f64> = (0..mesh.n_faces()).map(|f| mesh.face_area(f)).collect();
        if areas.iter().sum::<f64>() <= 0.0 {
            return Err(SynthError::Unsatisfiable("the mesh has zero area".into()));
        }
        let report = topology::analyze(&mesh);
        Ok(Self {
            name: name.to_string(),
            cum: cumulative(&areas),
            genus: report.genus.unwrap_or(0),
            components: report.components as u32,
            closed: report.watertight,
            bvh,
            mesh,
        })
    }
}

impl Shape for MeshShape {
    fn name(&self) -> &str {
        &self.name
    }
    fn closest_point(&self, p: DVec3) -> SurfacePoint {
        let h = self.bvh.closest_point(p).expect("finite query");
        SurfacePoint {
            point: h.point,
            normal: self.mesh.face_normal(h.face as usize),
            distance: h.distance,
        }
    }
    /// Parity of the crossings of a fixed oblique ray.
    fn is_inside(&self, p: DVec3) -> bool {
        let dir = DVec3::new(0.5773, 0.5774, 0.5775).normalize();
        let eps = 1e-10 * self.aabb().diagonal();
        let mut o = p;
        let mut odd = false;
        for _ in 0..10_000 {
            match self.bvh.ray_cast(o, dir, f64::INFINITY).ok().flatten() {
                Some(hit) => {
                    odd = !odd;
                    o = hit.point + dir * eps;
                }
                None => break,
            }
        }
        odd
    }
    fn sample_uniform(&self, n: usize, rng: &mut dyn Rng) -> Vec<Sample> {
        (0..n)
            .map(|_| {
                let f = pick_weighted(rng, &self.cum);
                let [a, b, c] = self.mesh.triangle(f);
                let (mut u, mut v) = (unit(rng), unit(rng));
                if u + v > 1.0 {
                    u = 1.0 - u;
                    v = 1.0 - v;
                }
                Sample {
                    position: a + (b - a) * u + (c - a) * v,
                    normal: self.mesh.face_normal(f),
                }
            })
            .collect()
    }
    fn aabb(&self) -> Aabb {
        self.mesh.aabb()
    }
    fn scale(&self) -> f64 {
        1.0
    }
    fn area(&self) -> f64 {
        self.mesh.area()
    }
    fn genus(&self) -> u32 {
        self.genus
    }
    fn components(&self) -> u32 {
        self.components
    }
    fn is_closed(&self) -> bool {
        self.closed
    }
    /// The mesh itself, whatever the resolution.
    fn reference_mesh(&self, _resolution: usize) -> TriMesh {
        self.mesh.clone()
    }
    fn ray_intersect(&self, origin: DVec3, dir: DVec3, max_t: f64) -> Option<f64> {
        self.bvh
            .ray_cast(origin, dir, max_t)
            .ok()
            .flatten()
            .map(|h| h.t)
    }
}
