//! Geometry core of reconbench: point clouds, triangle meshes, mesh topology analysis,
//! file formats, spatial queries and small linear algebra.
//!
//! Geometry (where things are: [`PointCloud`], [`TriMesh`]) is kept apart from topology
//! (who is adjacent to whom: [`topology`]). Everything is `f64`; inputs are validated on
//! construction so that downstream code may assume finite coordinates and valid indices.

pub mod aabb;
pub mod cloud;
pub mod error;
pub mod io;
pub mod linalg;
pub mod mesh;
pub mod method;
pub mod spatial;
pub mod topology;

pub use aabb::Aabb;
pub use cloud::{Channel, PointCloud};
pub use error::{GeomError, Location, Result};
pub use glam::DVec3;
pub use linalg::{Covariance, SymEigen3, covariance, sym_eigen3, weighted_least_squares};
pub use mesh::TriMesh;
pub use spatial::{
    ClosestHit, KnnTable, MeshBvh, Neighbor, PointIndex, RadiusTable, RayHit,
    closest_point_on_triangle, mean_spacing,
};
pub use topology::{MeshTopology, OrientReport, TopologyReport};
