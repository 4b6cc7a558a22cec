//! Spatial queries: k-nearest neighbours and radius search over points ([`PointIndex`]),
//! and closest point / distance / ray casts against a triangle mesh ([`MeshBvh`]).
//!
//! Both are deterministic: neighbour lists are ordered by (squared distance, index), so
//! ties are broken by the lower index whatever the tree layout or thread count, and batch
//! queries return their results in input order.
//!
//! One file per concept: `kd_tree` ([`PointIndex`] on kiddo, [`mean_spacing`]),
//! `self_knn` (the all-points kNN tree), `mesh_bvh` ([`MeshBvh`]), `triangle`
//! (closest points on a triangle or segment), `morton` (query ordering), `tables`
//! (neighbour tables) and the shared argument checks.

mod checks;
mod kd_tree;
mod mesh_bvh;
mod morton;
mod self_knn;
mod tables;
mod tri_intersect;
mod triangle;

pub use kd_tree::{DEFAULT_SPACING_K, PointIndex, mean_spacing};
pub use mesh_bvh::{ClosestHit, MeshBvh, RayHit};
pub use morton::morton_order;
pub use self_knn::{KnnHit, knn_self_map, knn_self_table};
pub use tables::{KnnTable, Neighbor, RadiusTable};
pub use tri_intersect::{exactly_collinear, tri_tri_intersect};
pub use triangle::{
    closest_point_on_segment, closest_point_on_triangle, closest_point_on_triangle_bary,
};
