//! A user's triangle mesh as a [`Shape`], so that it can be sampled and scanned like the
//! analytic shapes (closest points and ray casts through the geom crate's BVH), and its
//! own vertices used as the input (the seeds' protocol on their real data sets).

use glam::DVec3;
use rand::Rng;
use reconbench_geom::spatial::closest_point_on_segment;
use reconbench_geom::topology::{self, MeshTopology};
use reconbench_geom::{Aabb, MeshBvh, TriMesh};

use crate::error::{Result, SynthError};
use crate::shape::{FeatureCurve, Sample, Shape, SurfacePoint};
use crate::util::{cumulative, pick_weighted, unit};

/// Default sharp-edge threshold of a mesh ground truth, degrees: above the facet angles of
/// the tessellated smooth parts of the seeds' meshes (fandisk: 876 edges at 20 degrees,
/// 722 at 30, 710 at 40, 700 at 60, so 30 keeps the creases and few facet edges).
pub const DEFAULT_MESH_FEATURE_ANGLE_DEG: f64 = 30.0;

/// How a mesh becomes ground truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshShapeOptions {
    /// An edge is a sharp feature when its two face normals differ by at least this
    /// angle, degrees ([`DEFAULT_MESH_FEATURE_ANGLE_DEG`]).
    pub feature_angle_deg: f64,
    /// Declared closedness, overriding the measured watertightness (the thesis treats
    /// the open bunny scan as a closed surface).
    pub closed: Option<bool>,
}

impl Default for MeshShapeOptions {
    fn default() -> Self {
        Self {
            feature_angle_deg: DEFAULT_MESH_FEATURE_ANGLE_DEG,
            closed: None,
        }
    }
}

/// A triangle mesh with exact (piecewise-planar) ground truth. It keeps its own
/// coordinates (`scale() == 1`, no normalisation); normals are face normals (right-hand
/// rule, so the mesh should be consistently oriented outwards); feature curves are its
/// chained sharp edges ([`MeshShapeOptions::feature_angle_deg`]) and the vertices where
/// three or more of them meet. A non-manifold mesh has no genus; it is reported as 0.
#[derive(Debug)]
pub struct MeshShape {
    name: String,
    mesh: TriMesh,
    bvh: MeshBvh,
    cum: Vec<f64>,
    genus: u32,
    components: u32,
    closed: bool,
    curves: Vec<FeatureCurve>,
    segments: Vec<(DVec3, DVec3)>,
}

impl MeshShape {
    /// Wraps `mesh` (at least one non-degenerate face) with the default options.
    pub fn new(name: &str, mesh: TriMesh) -> Result<Self> {
        Self::with_options(name, mesh, MeshShapeOptions::default())
    }

    /// Wraps `mesh` (at least one non-degenerate face).
    pub fn with_options(name: &str, mesh: TriMesh, opts: MeshShapeOptions) -> Result<Self> {
        if !(opts.feature_angle_deg.is_finite() && opts.feature_angle_deg > 0.0) {
            return Err(SynthError::invalid(
                "mesh shape",
                "feature_angle_deg",
                format!("{} must be a positive angle", opts.feature_angle_deg),
            ));
        }
        let bvh = MeshBvh::new(&mesh)?;
        let areas: Vec<f64> = (0..mesh.n_faces()).map(|f| mesh.face_area(f)).collect();
        if areas.iter().sum::<f64>() <= 0.0 {
            return Err(SynthError::Unsatisfiable("the mesh has zero area".into()));
        }
        let topo = MeshTopology::new(&mesh);
        let report = topology::analyze_with(&mesh, &topo);
        let (curves, segments) = mesh_features(&mesh, &topo, opts.feature_angle_deg);
        Ok(Self {
            name: name.to_string(),
            cum: cumulative(&areas),
            genus: report.genus.unwrap_or(0),
            components: report.components as u32,
            closed: opts.closed.unwrap_or(report.watertight),
            curves,
            segments,
            bvh,
            mesh,
        })
    }

    /// The mesh.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }
}

/// The chained sharp edges and corners of a mesh as feature curves (dihedral angle
/// `180 - normal angle`, the sharpest along a chain), and every sharp edge as a segment.
fn mesh_features(
    mesh: &TriMesh,
    topo: &MeshTopology,
    min_angle_deg: f64,
) -> (Vec<FeatureCurve>, Vec<(DVec3, DVec3)>) {
    let v = mesh.vertices();
    let sharp = topology::sharp_edges(mesh, topo, min_angle_deg);
    let (chains, corners) = topology::feature_chains(mesh.n_vertices(), &sharp);
    let mut curves: Vec<FeatureCurve> = chains
        .into_iter()
        .map(|c| FeatureCurve {
            points: c.vertices.iter().map(|&i| v[i as usize]).collect(),
            dihedral_deg: 180.0 - c.max_angle_deg,
            is_corner: false,
        })
        .collect();
    curves.extend(corners.into_iter().map(|(i, a)| FeatureCurve {
        points: vec![v[i as usize]],
        dihedral_deg: 180.0 - a,
        is_corner: true,
    }));
    let segments = sharp
        .iter()
        .map(|e| (v[e.v[0] as usize], v[e.v[1] as usize]))
        .collect();
    (curves, segments)
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
    fn feature_curves(&self) -> Vec<FeatureCurve> {
        self.curves.clone()
    }
    /// Exact distance to the nearest sharp edge (corners are edge ends).
    fn feature_distance(&self, p: DVec3) -> f64 {
        self.segments
            .iter()
            .map(|&(a, b)| (closest_point_on_segment(p, a, b).0 - p).length())
            .fold(f64::INFINITY, f64::min)
    }
    /// The de-duplicated vertices (every vertex, referenced or not, once per distinct
    /// position, in first-occurrence order) with area-weighted vertex normals (seed
    /// 000's type-2 reference normals); a vertex no face uses takes the face normal of
    /// its closest point.
    fn vertex_samples(&self) -> Option<Vec<Sample>> {
        let normals = self.mesh.area_weighted_normals();
        let mut seen = std::collections::HashSet::with_capacity(self.mesh.n_vertices());
        let mut out = Vec::with_capacity(self.mesh.n_vertices());
        for (&p, &n) in self.mesh.vertices().iter().zip(&normals) {
            if !seen.insert([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]) {
                continue;
            }
            let normal = if n == DVec3::ZERO {
                self.closest_point(p).normal
            } else {
                n
            };
            out.push(Sample {
                position: p,
                normal,
            });
        }
        Some(out)
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
