//! The ground-truth surface a reconstruction is compared with: an analytic [`Shape`]
//! (exact closest points) or a triangle mesh (exact point-to-triangle distances through
//! geom's [`MeshBvh`]). Every metric takes a [`Reference`], so each works against either.

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::topology::{self, MeshTopology};
use reconbench_geom::{Aabb, MeshBvh, TriMesh};
use reconbench_synth::{DEFAULT_MESH_FEATURE_ANGLE_DEG, FeatureCurve, Shape};

use crate::error::{MetricsError, Result};
use crate::sampling::{AreaSampler, SurfaceSamples, sample_shape};

/// Closest reference point to a query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceHit {
    /// Closest point on the reference surface.
    pub point: DVec3,
    /// Unit normal there: the shape's exact normal, or the face normal of the mesh face
    /// hit (zero on a degenerate face).
    pub normal: DVec3,
    /// Euclidean distance from the query to `point`.
    pub distance: f64,
}

/// A mesh reference: the mesh, its BVH, face normals, an area sampler and its topology.
#[derive(Debug)]
pub struct MeshReference {
    mesh: TriMesh,
    bvh: MeshBvh,
    sampler: AreaSampler,
    genus: Option<u32>,
    components: usize,
    watertight: bool,
}

impl MeshReference {
    /// The mesh.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// Its BVH.
    pub fn bvh(&self) -> &MeshBvh {
        &self.bvh
    }
}

/// A shape, borrowed or owned.
#[derive(Debug)]
enum ShapeRef<'a> {
    Borrowed(&'a dyn Shape),
    Owned(Box<dyn Shape>),
}

impl<'a> std::ops::Deref for ShapeRef<'a> {
    type Target = dyn Shape + 'a;
    fn deref(&self) -> &Self::Target {
        match self {
            ShapeRef::Borrowed(s) => *s,
            ShapeRef::Owned(s) => &**s,
        }
    }
}

#[derive(Debug)]
enum Inner<'a> {
    Analytic(ShapeRef<'a>),
    Mesh(Box<MeshReference>),
}

/// Ground truth: an analytic shape or a triangle mesh.
#[derive(Debug)]
pub struct Reference<'a> {
    inner: Inner<'a>,
    aabb: Aabb,
}

impl<'a> Reference<'a> {
    /// An analytic shape (borrowed).
    pub fn analytic(shape: &'a dyn Shape) -> Self {
        Reference {
            aabb: shape.aabb(),
            inner: Inner::Analytic(ShapeRef::Borrowed(shape)),
        }
    }

    /// An analytic shape (owned), e.g. the result of `reconbench_synth::from_spec`.
    pub fn analytic_owned(shape: Box<dyn Shape>) -> Reference<'static> {
        Reference {
            aabb: shape.aabb(),
            inner: Inner::Analytic(ShapeRef::Owned(shape)),
        }
    }

    /// The reference named by a command-line argument: a mesh file if `arg` is an
    /// existing file (any format `reconbench_geom::io::read_mesh` reads), otherwise a
    /// shape spec for `reconbench_synth::from_spec` (e.g. `torus`, `box`).
    pub fn from_arg(arg: &str) -> Result<Reference<'static>> {
        if std::path::Path::new(arg).is_file() {
            let mesh = reconbench_geom::io::read_mesh(arg)?;
            Reference::mesh(mesh)
        } else {
            let shape = reconbench_synth::from_spec(arg).map_err(|e| {
                MetricsError::InvalidInput(format!(
                    "reference '{arg}' is neither an existing mesh file nor a shape spec: {e}"
                ))
            })?;
            Ok(Reference::analytic_owned(shape))
        }
    }

    /// A triangle mesh. Builds the BVH, the area sampler and the topology (for the ground
    /// truth genus and component count). Errors on a mesh without faces or of zero area.
    pub fn mesh(mesh: TriMesh) -> Result<Reference<'static>> {
        let bvh = MeshBvh::new(&mesh)?;
        let sampler = AreaSampler::new(&mesh)?;
        let topo = topology::analyze(&mesh);
        let aabb = aabb_of_referenced(&mesh);
        Ok(Reference {
            aabb,
            inner: Inner::Mesh(Box::new(MeshReference {
                bvh,
                sampler,
                genus: topo.genus,
                components: topo.components,
                watertight: topo.watertight,
                mesh,
            })),
        })
    }

    /// Short description for reports: the shape name, or `mesh(F faces)`.
    pub fn name(&self) -> String {
        match &self.inner {
            Inner::Analytic(s) => s.name().to_string(),
            Inner::Mesh(m) => format!("mesh({} faces)", m.mesh.n_faces()),
        }
    }

    /// The shape, for an analytic reference.
    pub fn as_shape(&self) -> Option<&dyn Shape> {
        match &self.inner {
            Inner::Analytic(s) => Some(&**s),
            Inner::Mesh(_) => None,
        }
    }

    /// The mesh reference, for a mesh reference.
    pub fn as_mesh(&self) -> Option<&MeshReference> {
        match &self.inner {
            Inner::Analytic(_) => None,
            Inner::Mesh(m) => Some(m),
        }
    }

    /// Bounding box (of the referenced vertices for a mesh).
    pub fn aabb(&self) -> Aabb {
        self.aabb
    }

    /// Bounding-box diagonal: the unit of the relative distances.
    pub fn diagonal(&self) -> f64 {
        self.aabb.diagonal()
    }

    /// Surface area.
    pub fn area(&self) -> f64 {
        match &self.inner {
            Inner::Analytic(s) => s.area(),
            Inner::Mesh(m) => m.sampler.area(),
        }
    }

    /// Number of faces of a mesh reference (`None` for an analytic one).
    pub fn n_faces(&self) -> Option<usize> {
        self.as_mesh().map(|m| m.mesh.n_faces())
    }

    /// Genus of the ground truth (a mesh's genus may be undefined: non-manifold).
    pub fn genus(&self) -> Option<u32> {
        match &self.inner {
            Inner::Analytic(s) => Some(s.genus()),
            Inner::Mesh(m) => m.genus,
        }
    }

    /// Number of connected components of the ground truth.
    pub fn components(&self) -> usize {
        match &self.inner {
            Inner::Analytic(s) => s.components() as usize,
            Inner::Mesh(m) => m.components,
        }
    }

    /// Whether the ground truth is closed (a shape's declaration; a mesh's watertightness).
    pub fn is_closed(&self) -> bool {
        match &self.inner {
            Inner::Analytic(s) => s.is_closed(),
            Inner::Mesh(m) => m.watertight,
        }
    }

    /// Ground-truth sharp feature curves. A shape gives its declared curves. A mesh gives
    /// each manifold edge whose face normals differ by at least `min_angle_deg`, and at
    /// least synth's [`DEFAULT_MESH_FEATURE_ANGLE_DEG`] (so a mesh file and the same mesh
    /// as an experiment's data set have the same features), as a two-point curve with
    /// `dihedral_deg = 180 - angle between the normals`.
    pub fn feature_curves(&self, min_angle_deg: f64) -> Vec<FeatureCurve> {
        let min_angle_deg = min_angle_deg.max(DEFAULT_MESH_FEATURE_ANGLE_DEG);
        match &self.inner {
            Inner::Analytic(s) => s.feature_curves(),
            Inner::Mesh(m) => mesh_sharp_edges(&m.mesh, &MeshTopology::new(&m.mesh), min_angle_deg)
                .into_iter()
                .map(|(a, b, dev)| FeatureCurve {
                    points: vec![a, b],
                    dihedral_deg: 180.0 - dev,
                    is_corner: false,
                })
                .collect(),
        }
    }

    /// Closest reference point to `p`.
    pub fn closest(&self, p: DVec3) -> Result<SurfaceHit> {
        match &self.inner {
            Inner::Analytic(s) => {
                let sp = s.closest_point(p);
                Ok(SurfaceHit {
                    point: sp.point,
                    normal: sp.normal,
                    distance: sp.distance,
                })
            }
            Inner::Mesh(m) => {
                let h = m.bvh.closest_point(p)?;
                Ok(SurfaceHit {
                    point: h.point,
                    normal: m.sampler.face_normals()[h.face as usize],
                    distance: h.distance,
                })
            }
        }
    }

    /// [`closest`](Self::closest) for many queries, in parallel, in input order.
    pub fn closest_batch(&self, queries: &[DVec3]) -> Result<Vec<SurfaceHit>> {
        match &self.inner {
            Inner::Analytic(s) => Ok(queries
                .par_iter()
                .map(|&p| {
                    let sp = s.closest_point(p);
                    SurfaceHit {
                        point: sp.point,
                        normal: sp.normal,
                        distance: sp.distance,
                    }
                })
                .collect()),
            Inner::Mesh(m) => {
                let normals = m.sampler.face_normals();
                let hits = bvh_closest_coherent(&m.bvh, queries)?;
                Ok(hits
                    .into_par_iter()
                    .map(|h| SurfaceHit {
                        point: h.point,
                        normal: normals[h.face as usize],
                        distance: h.distance,
                    })
                    .collect())
            }
        }
    }

    /// Distances of many queries to the reference, in parallel, in input order.
    pub fn distances(&self, queries: &[DVec3]) -> Result<Vec<f64>> {
        match &self.inner {
            Inner::Analytic(s) => Ok(queries.par_iter().map(|&p| s.distance(p)).collect()),
            Inner::Mesh(m) => Ok(bvh_closest_coherent(&m.bvh, queries)?
                .into_iter()
                .map(|h| h.distance)
                .collect()),
        }
    }

    /// `n` area-uniform samples with exact normals (deterministic for a seed).
    pub fn sample(&self, n: usize, seed: u64) -> SurfaceSamples {
        match &self.inner {
            Inner::Analytic(s) => sample_shape(&**s, n, seed),
            Inner::Mesh(m) => m.sampler.sample(&m.mesh, n, seed),
        }
    }
}

/// Bounding box of the vertices used by at least one face (all vertices if none is).
pub(crate) fn aabb_of_referenced(mesh: &TriMesh) -> Aabb {
    let mut used = vec![false; mesh.n_vertices()];
    for f in mesh.faces() {
        for &v in f {
            used[v as usize] = true;
        }
    }
    let b = mesh
        .vertices()
        .iter()
        .zip(&used)
        .filter(|(_, u)| **u)
        .fold(Aabb::EMPTY, |b, (p, _)| b.grow(*p));
    if b.is_empty() { mesh.aabb() } else { b }
}

/// Manifold edges (exactly two faces of non-zero area) whose unit face normals differ by
/// at least `min_angle_deg` (see [`topology::sharp_edges`]). Returns `(a, b, angle_deg)`
/// per edge.
pub(crate) fn mesh_sharp_edges(
    mesh: &TriMesh,
    topo: &MeshTopology,
    min_angle_deg: f64,
) -> Vec<(DVec3, DVec3, f64)> {
    let v = mesh.vertices();
    topology::sharp_edges(mesh, topo, min_angle_deg)
        .into_iter()
        .map(|e| (v[e.v[0] as usize], v[e.v[1] as usize], e.angle_deg))
        .collect()
}

/// Closest points of many queries, issued in Morton order so that consecutive queries
/// walk the same BVH nodes (much better cache behaviour on large meshes), returned in
/// input order.
pub fn bvh_closest_coherent(
    bvh: &MeshBvh,
    queries: &[DVec3],
) -> Result<Vec<reconbench_geom::ClosestHit>> {
    if queries.len() < 4096 {
        return Ok(bvh.closest_points(queries)?);
    }
    let order = reconbench_geom::spatial::morton_order(queries);
    let sorted: Vec<DVec3> = order.par_iter().map(|&i| queries[i as usize]).collect();
    let hits = bvh.closest_points(&sorted)?;
    let mut out = vec![
        reconbench_geom::ClosestHit {
            point: DVec3::ZERO,
            distance: 0.0,
            face: 0,
        };
        queries.len()
    ];
    for (h, &i) in hits.into_iter().zip(&order) {
        out[i as usize] = h;
    }
    Ok(out)
}

/// Errors unless the mesh has at least one face.
pub(crate) fn require_faces(mesh: &TriMesh, what: &str) -> Result<()> {
    if mesh.n_faces() == 0 {
        return Err(MetricsError::InvalidInput(format!(
            "the {what} mesh has no faces"
        )));
    }
    Ok(())
}
