//! [`MeshBvh`]: closest point, distance and ray casts against a triangle mesh.

use glam::DVec3;
use parry3d_f64::query::{PointQueryWithLocation, Ray, RayCast};
use parry3d_f64::shape::{TriMesh as ParryTriMesh, TriMeshFlags};
use rayon::prelude::*;

use super::checks::check_query;
use crate::error::{GeomError, Result, check_finite};
use crate::mesh::TriMesh;

/// Result of a closest-point query on a mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestHit {
    /// Closest point on the surface.
    pub point: DVec3,
    /// Distance from the query to `point`.
    pub distance: f64,
    /// Index of the face `point` lies on (one of them when it is on a shared edge or
    /// vertex, or when faces coincide).
    pub face: u32,
}

/// Result of a ray cast on a mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit {
    /// Ray parameter of the hit: `point = origin + t * dir` (a distance only for unit
    /// `dir`).
    pub t: f64,
    /// Hit point.
    pub point: DVec3,
    /// Index of the face hit.
    pub face: u32,
    /// Unit normal of the hit face following its winding (right-hand rule), whichever
    /// side was hit; compare with `dir` to tell front from back hits.
    pub normal: DVec3,
}

/// A bounding-volume hierarchy over a triangle mesh for closest-point, distance and
/// ray-cast queries.
///
/// Backed by parry3d-f64 0.31's `TriMesh` (its BVH, `PointQueryWithLocation` and
/// `RayCast`) rather than a hand-rolled BVH: parry is maintained, `Sync` (so batch
/// queries run under rayon), measured exact to ~1e-17 against brute force, and uses
/// glam 0.33's `DVec3` directly (no conversion). It is built with empty
/// `TriMeshFlags`: no half-edge topology, no merging or deletion of triangles, so
/// non-manifold, duplicate and degenerate faces are accepted and face ids stay those of
/// the input mesh. Parry projects onto a collinear (zero-area) triangle as onto its
/// longest edge, so degenerate faces do not produce NaN; ray casts simply miss them.
pub struct MeshBvh {
    shape: ParryTriMesh,
    normals: Vec<DVec3>,
}

impl std::fmt::Debug for MeshBvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MeshBvh")
            .field("faces", &self.normals.len())
            .finish_non_exhaustive()
    }
}

impl MeshBvh {
    /// Builds the BVH. Errors on a mesh without faces.
    pub fn new(mesh: &TriMesh) -> Result<Self> {
        if mesh.n_faces() == 0 {
            return Err(GeomError::InvalidInput(
                "cannot build a BVH over a mesh without faces".to_string(),
            ));
        }
        let shape = ParryTriMesh::with_flags(
            mesh.vertices().to_vec(),
            mesh.faces().to_vec(),
            TriMeshFlags::empty(),
        )
        .map_err(|e| GeomError::InvalidInput(format!("BVH construction failed: {e}")))?;
        let normals = (0..mesh.n_faces()).map(|f| mesh.face_normal(f)).collect();
        Ok(Self { shape, normals })
    }

    /// Number of faces.
    pub fn n_faces(&self) -> usize {
        self.normals.len()
    }

    fn closest_unchecked(&self, p: DVec3) -> Result<ClosestHit> {
        let (proj, (face, _)) = self
            .shape
            .project_local_point_and_get_location_with_max_dist(p, false, f64::MAX)
            .ok_or_else(|| {
                GeomError::InvalidInput(format!("closest-point query at {p} found no face"))
            })?;
        Ok(ClosestHit {
            point: proj.point,
            distance: (proj.point - p).length(),
            face,
        })
    }

    /// Closest point of the surface to `p`. Errors on a non-finite `p`.
    pub fn closest_point(&self, p: DVec3) -> Result<ClosestHit> {
        check_query(p)?;
        self.closest_unchecked(p)
    }

    /// Unsigned distance from `p` to the surface.
    pub fn distance(&self, p: DVec3) -> Result<f64> {
        Ok(self.closest_point(p)?.distance)
    }

    /// [`closest_point`](Self::closest_point) for many queries, in parallel, in input
    /// order. Errors on the first non-finite query (naming its index).
    pub fn closest_points(&self, queries: &[DVec3]) -> Result<Vec<ClosestHit>> {
        check_finite("query point", queries)?;
        queries
            .par_iter()
            .map(|&p| self.closest_unchecked(p))
            .collect()
    }

    /// Distances of many queries, in parallel.
    pub fn distances(&self, queries: &[DVec3]) -> Result<Vec<f64>> {
        Ok(self
            .closest_points(queries)?
            .into_iter()
            .map(|h| h.distance)
            .collect())
    }

    /// First intersection of the ray `origin + t dir`, `0 <= t <= max_t`, with the surface
    /// (either side of a face). A ray starting on the surface hits it at `t = 0`.
    ///
    /// Errors on a non-finite origin or direction, a zero direction or a negative/NaN
    /// `max_t` (`f64::INFINITY` is allowed).
    pub fn ray_cast(&self, origin: DVec3, dir: DVec3, max_t: f64) -> Result<Option<RayHit>> {
        check_finite("ray origin", &[origin])?;
        check_finite("ray direction", &[dir])?;
        if dir == DVec3::ZERO {
            return Err(GeomError::InvalidParameter {
                name: "ray direction",
                message: "must be non-zero".to_string(),
            });
        }
        if max_t.is_nan() || max_t < 0.0 {
            return Err(GeomError::InvalidParameter {
                name: "max_t",
                message: format!("{max_t} must be >= 0"),
            });
        }
        let ray = Ray::new(origin, dir);
        Ok(self
            .shape
            .cast_local_ray_and_get_normal(&ray, max_t.min(f64::MAX), false)
            .map(|hit| {
                let face = hit.subshape;
                RayHit {
                    t: hit.time_of_impact,
                    point: origin + hit.time_of_impact * dir,
                    face,
                    normal: self.normals[face as usize],
                }
            }))
    }
}
