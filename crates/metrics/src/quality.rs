//! Triangle quality and edge lengths.
//!
//! Per face (non-degenerate, i.e. positive area): the three interior angles, and the
//! aspect ratio `R / (2 r)` = `a b c (a + b + c) / (16 A^2)` (circumradius over twice the
//! inradius; 1 for an equilateral triangle, growing without bound as it degenerates).
//! Faces of zero area have no aspect ratio; they count as min angle 0 and max angle 180
//! and are counted in `degenerate_triangles`. Edge lengths are over distinct undirected
//! edges (shared edges counted once).

use rayon::prelude::*;
use reconbench_geom::TriMesh;
use reconbench_geom::topology::MeshTopology;
use serde::{Deserialize, Serialize};

use crate::report::{Entries, Report, put, serialize_as_entries};
use crate::stats::Summary;

/// The "small angle" threshold of `share_min_angle_below_12`.
pub const SMALL_ANGLE_DEG: f64 = 12.0;

/// Options of [`eval_quality`].
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct QualityOptions {
    /// Target edge length (absolute, e.g. the error-bounded method's Omega): the report
    /// gives the share of edges longer than it.
    pub target_edge_length: Option<f64>,
}

/// Result of [`eval_quality`].
#[derive(Debug, Clone, PartialEq)]
pub struct QualityEval {
    /// Faces evaluated (faces with three distinct vertex indices).
    pub triangles: usize,
    /// Of which zero-area.
    pub degenerate: usize,
    /// Per-face minimum angle (degrees).
    pub min_angle: Summary,
    /// Per-face maximum angle (degrees).
    pub max_angle: Summary,
    /// Aspect ratio `R / 2r` over non-degenerate faces.
    pub aspect: Summary,
    /// Share of faces with minimum angle < 12 degrees.
    pub share_min_angle_below_12: f64,
    /// Edge lengths over distinct edges (absolute).
    pub edge_length: Summary,
    /// Target edge length, if given.
    pub target_edge_length: Option<f64>,
    /// Share of edges longer than the target.
    pub share_edges_above_target: Option<f64>,
}

impl Report for QualityEval {
    fn entries(&self) -> Entries {
        let mut e = Entries::new();
        put(&mut e, "min_angle_deg", self.min_angle.min);
        put(&mut e, "min_angle_mean_deg", self.min_angle.mean);
        put(&mut e, "max_angle_deg", self.max_angle.max);
        put(&mut e, "max_angle_mean_deg", self.max_angle.mean);
        put(&mut e, "aspect_ratio_mean", self.aspect.mean);
        put(&mut e, "aspect_ratio_p95", self.aspect.p95);
        put(&mut e, "aspect_ratio_max", self.aspect.max);
        put(
            &mut e,
            "share_min_angle_below_12",
            self.share_min_angle_below_12,
        );
        put(&mut e, "degenerate_triangles", self.degenerate);
        put(&mut e, "edge_length_min_abs", self.edge_length.min);
        put(&mut e, "edge_length_mean_abs", self.edge_length.mean);
        put(&mut e, "edge_length_max_abs", self.edge_length.max);
        put(&mut e, "edge_length_std_abs", self.edge_length.std);
        put(&mut e, "edge_length_target_abs", self.target_edge_length);
        put(
            &mut e,
            "share_edges_above_target",
            self.share_edges_above_target,
        );
        e
    }
}
serialize_as_entries!(QualityEval);

/// Angles (degrees) and aspect ratio of one triangle; `None` aspect for zero area.
pub fn triangle_quality(t: [glam::DVec3; 3]) -> ([f64; 3], Option<f64>) {
    let [p0, p1, p2] = t;
    let a = (p1 - p2).length(); // opposite p0
    let b = (p2 - p0).length(); // opposite p1
    let c = (p0 - p1).length(); // opposite p2
    let area2 = (p1 - p0).cross(p2 - p0).length(); // 2A
    if area2.is_nan() || area2 <= 0.0 || a == 0.0 || b == 0.0 || c == 0.0 {
        return ([0.0, 0.0, 180.0], None);
    }
    let ang = |u: glam::DVec3, v: glam::DVec3| u.angle_between(v).to_degrees();
    let angles = [
        ang(p1 - p0, p2 - p0),
        ang(p0 - p1, p2 - p1),
        ang(p0 - p2, p1 - p2),
    ];
    // R = abc / 4A, r = 2A / (a + b + c)  =>  R / 2r = abc (a + b + c) / (16 A^2)
    //   = abc (a + b + c) / (4 (2A)^2).
    let aspect = a * b * c * (a + b + c) / (4.0 * area2 * area2);
    (angles, Some(aspect))
}

/// Quality statistics of `mesh` (see the module docs).
pub fn eval_quality(mesh: &TriMesh, opts: &QualityOptions) -> QualityEval {
    let faces: Vec<usize> = (0..mesh.n_faces())
        .filter(|&f| {
            let [a, b, c] = mesh.faces()[f];
            a != b && b != c && a != c
        })
        .collect();
    let per: Vec<([f64; 3], Option<f64>)> = faces
        .par_iter()
        .map(|&f| triangle_quality(mesh.triangle(f)))
        .collect();
    let mins: Vec<f64> = per.iter().map(|(a, _)| a[0].min(a[1]).min(a[2])).collect();
    let maxs: Vec<f64> = per.iter().map(|(a, _)| a[0].max(a[1]).max(a[2])).collect();
    let aspects: Vec<f64> = per.iter().filter_map(|p| p.1).collect();
    let topo = MeshTopology::new(mesh);
    let v = mesh.vertices();
    let lengths: Vec<f64> = topo
        .edges()
        .iter()
        .map(|&[a, b]| (v[a as usize] - v[b as usize]).length())
        .collect();
    let share_edges_above_target = opts.target_edge_length.and_then(|t| {
        (!lengths.is_empty())
            .then(|| lengths.iter().filter(|&&l| l > t).count() as f64 / lengths.len() as f64)
    });
    QualityEval {
        triangles: faces.len(),
        degenerate: per.len() - aspects.len(),
        min_angle: Summary::of(&mins),
        max_angle: Summary::of(&maxs),
        aspect: Summary::of(&aspects),
        share_min_angle_below_12: crate::stats::share(&mins, |m| m < SMALL_ANGLE_DEG),
        edge_length: Summary::of(&lengths),
        target_edge_length: opts.target_edge_length,
        share_edges_above_target,
    }
}
