//! The [`Shape`] trait: an analytic surface with exact ground truth.
//!
//! Every metric in reconbench compares against a `Shape`, so its answers must be exact
//! (closed form) or converged to 1e-12 of the bounding-box diagonal.

use glam::DVec3;
use rand::Rng;
use reconbench_geom::{Aabb, TriMesh};
use serde::{Deserialize, Serialize};

/// The closest surface point to a query, with everything a metric needs about it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// The closest point on the surface.
    pub point: DVec3,
    /// Unit outward normal there. On a sharp edge or corner the normal is not unique:
    /// it is the normal of one of the incident smooth patches (documented per shape).
    pub normal: DVec3,
    /// Euclidean distance from the query to `point` (unsigned).
    pub distance: f64,
}

/// One surface sample: where it is, its exact normal, and its ground-truth annotations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Position on the surface.
    pub position: DVec3,
    /// Exact unit outward normal at `position`.
    pub normal: DVec3,
}

/// A sharp feature curve: a polyline on the surface along which the normal is
/// discontinuous, with the dihedral angle across it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FeatureCurve {
    /// Polyline vertices, densely enough that the polyline is within 1e-4 of the
    /// diagonal of the exact curve (exact for straight edges). Closed curves repeat
    /// the first point at the end.
    pub points: Vec<DVec3>,
    /// Dihedral angle in degrees: 180 minus the angle between the two face normals,
    /// i.e. 90 for a cube edge, so a flat (non-)feature would be 180. When it varies
    /// along the curve, the smallest (sharpest) value.
    pub dihedral_deg: f64,
    /// Whether this curve is a corner (a single point where three or more patches meet).
    /// Corners have one point in `points`.
    pub is_corner: bool,
}

/// Summary of a shape for listings (`reconbench shapes`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShapeInfo {
    /// Stable kebab-case name.
    pub name: String,
    /// Genus of the (closed) surface; 0 for an open sheet.
    pub genus: u32,
    /// Number of connected components.
    pub components: u32,
    /// Whether the surface is closed (watertight).
    pub closed: bool,
    /// Number of sharp feature curves (excluding corners).
    pub feature_curves: usize,
    /// Number of corners.
    pub corners: usize,
    /// Surface area (in the normalised unit-diagonal frame).
    pub area: f64,
}

/// An analytic surface with exact ground truth, scaled so that its bounding box has unit
/// diagonal (the original scale factor is kept by the implementation).
///
/// Implementations must be cheap to share across threads.
pub trait Shape: Send + Sync + std::fmt::Debug {
    /// Stable kebab-case name, e.g. `torus`, `double-torus`, `box`.
    fn name(&self) -> &str;
    /// Exact closest surface point to `p` (closed form or converged to 1e-12 diag).
    fn closest_point(&self, p: DVec3) -> SurfacePoint;
    /// Unsigned distance from `p` to the surface.
    fn distance(&self, p: DVec3) -> f64 {
        self.closest_point(p).distance
    }
    /// Whether `p` is inside the solid. For open surfaces: the side the normal points
    /// away from.
    fn is_inside(&self, p: DVec3) -> bool;
    /// `n` area-uniform random samples with exact normals.
    fn sample_uniform(&self, n: usize, rng: &mut dyn Rng) -> Vec<Sample>;
    /// Bounding box of the surface (unit diagonal).
    fn aabb(&self) -> Aabb;
    /// Scale factor applied to the shape's natural definition to reach unit diagonal.
    fn scale(&self) -> f64;
    /// Total surface area.
    fn area(&self) -> f64;
    /// Genus of the surface (0 for open sheets and spheres).
    fn genus(&self) -> u32;
    /// Number of connected components.
    fn components(&self) -> u32 {
        1
    }
    /// Whether the surface is closed.
    fn is_closed(&self) -> bool {
        true
    }
    /// Number of boundary loops: 0 for a closed surface, 1 for an open sheet by default,
    /// plus one per through-hole of a holed sheet (the truth the hole counts of a
    /// reconstruction are compared with).
    fn boundary_loops(&self) -> u32 {
        u32::from(!self.is_closed())
    }
    /// Sharp feature curves and corners (empty for smooth shapes).
    fn feature_curves(&self) -> Vec<FeatureCurve> {
        Vec::new()
    }
    /// A reference triangle mesh; `resolution` is the approximate number of segments
    /// along the longest parametric direction. Watertight with the declared genus for
    /// closed shapes.
    fn reference_mesh(&self, resolution: usize) -> TriMesh;
    /// Signed distance: negative inside (for open surfaces: on the side the normal points
    /// away from).
    fn signed_distance(&self, p: DVec3) -> f64 {
        let d = self.distance(p);
        if self.is_inside(p) { -d } else { d }
    }
    /// Unit outward normal at (or of the surface point closest to) `p`.
    fn normal_at(&self, p: DVec3) -> DVec3 {
        self.closest_point(p).normal
    }
    /// Distance from `p` to the nearest sharp feature curve or corner; `f64::INFINITY`
    /// for shapes without features. The default measures to the polylines of
    /// [`Shape::feature_curves`] (within their 1e-4 tolerance); the built-in shapes
    /// override it with the exact distance to the exact curves.
    fn feature_distance(&self, p: DVec3) -> f64 {
        let mut best = f64::INFINITY;
        for c in self.feature_curves() {
            if c.points.len() == 1 {
                best = best.min((p - c.points[0]).length());
            }
            for w in c.points.windows(2) {
                let d = w[1] - w[0];
                let l2 = d.length_squared();
                let t = if l2 == 0.0 {
                    0.0
                } else {
                    ((p - w[0]).dot(d) / l2).clamp(0.0, 1.0)
                };
                best = best.min((p - (w[0] + d * t)).length());
            }
        }
        best
    }
    /// First intersection `t` in `[0, max_t]` of the ray `origin + t dir` with the surface
    /// (`dir` need not be unit; `t` is in units of `dir`). The default sphere-traces the
    /// exact distance and finishes with safeguarded Newton steps on the signed distance,
    /// converged to 1e-12 of the bounding-box diagonal; it may miss a hit that only grazes
    /// the surface tangentially.
    fn ray_intersect(&self, origin: DVec3, dir: DVec3, max_t: f64) -> Option<f64> {
        crate::raycast::sphere_trace(
            &|p: DVec3| {
                let sp = self.closest_point(p);
                let s = if self.is_inside(p) {
                    -sp.distance
                } else {
                    sp.distance
                };
                (s, sp.normal)
            },
            origin,
            dir,
            max_t,
            self.aabb().diagonal(),
        )
    }
    /// Samples on a parametric grid of `nu` x `nv` (meaning per shape, see the shape's
    /// documentation), or `None` when the shape has no natural parametrisation.
    fn parametric_grid(&self, nu: usize, nv: usize) -> Option<Vec<Sample>> {
        let _ = (nu, nv);
        None
    }
    /// The shape's own vertices as samples (a mesh's; `None` for analytic shapes), for
    /// the `vertices` sampler.
    fn vertex_samples(&self) -> Option<Vec<Sample>> {
        None
    }
    /// Grid dimensions for about `count` grid points (square root by default).
    fn grid_dims_for_count(&self, count: usize) -> (usize, usize) {
        let n = (count as f64).sqrt().round().max(1.0) as usize;
        (n, n)
    }
    /// What a scanner sees of this shape, when that is not the shape itself: the part of
    /// a blend shape (`box-tube`, `fandisk-tube`), whose designed tube is added to the
    /// scan by the `blend` filter. Samplers and the range scanner of a dataset use it;
    /// the metrics measure against the whole shape. `None` (default): the shape itself.
    fn scanned_part(&self) -> Option<&dyn Shape> {
        None
    }
    /// Listing summary.
    fn info(&self) -> ShapeInfo {
        let curves = self.feature_curves();
        ShapeInfo {
            name: self.name().to_string(),
            genus: self.genus(),
            components: self.components(),
            closed: self.is_closed(),
            feature_curves: curves.iter().filter(|c| !c.is_corner).count(),
            corners: curves.iter().filter(|c| c.is_corner).count(),
            area: self.area(),
        }
    }
}
