//! Topology of a reconstructed mesh: geom's [`TopologyReport`] plus the seed's Delta F,
//! `topology_ok` against the ground truth, and self-intersecting face pairs.
//!
//! * `delta_f = |2V + 4(G - 1) - F|` (seed 000, eq. 3.2) with V and F the raw vertex and
//!   face counts of the mesh (the seed's V is the number of input points, which an
//!   interpolating mesh uses as its vertices) and G the ground-truth genus; only for a
//!   closed ground truth of known genus.
//! * `topology_ok` = watertight, same number of components and same genus as the ground
//!   truth.
//! * Self-intersections: pairs of faces `(f, g)`, `f < g`, that are not adjacent and
//!   whose closed triangles intersect. Broad phase: a bounding-box hierarchy; narrow
//!   phase: an exact test on Shewchuk's robust `orient3d` / `orient2d` (the `robust`
//!   crate), coplanar pairs included. Two faces are adjacent when they share a vertex,
//!   compared by *position* (so unwelded meshes such as STL soups do not report every
//!   pair of neighbours); exactly degenerate (collinear) faces are skipped.

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::topology::{self as gtopo, TopologyReport};
use reconbench_geom::{Aabb, TriMesh};
use robust::{Coord, Coord3D, orient2d, orient3d};
use serde::{Deserialize, Serialize};

use crate::boxtree::BoxTree;
use crate::reference::Reference;
use crate::report::{Entries, Report, put, serialize_as_entries};

/// Options of [`eval_topology`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TopologyOptions {
    /// Count self-intersecting face pairs (true).
    pub self_intersections: bool,
}

impl Default for TopologyOptions {
    fn default() -> Self {
        Self {
            self_intersections: true,
        }
    }
}

/// Ground-truth topology to compare with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct GroundTruthTopology {
    /// Genus (None when unknown).
    pub genus: Option<u32>,
    /// Number of connected components.
    pub components: usize,
    /// Whether the ground truth is closed.
    pub closed: bool,
}

impl GroundTruthTopology {
    /// The topology of a reference.
    pub fn of(reference: &Reference) -> Self {
        GroundTruthTopology {
            genus: reference.genus(),
            components: reference.components(),
            closed: reference.is_closed(),
        }
    }
}

/// Result of [`eval_topology`].
#[derive(Debug, Clone, PartialEq)]
pub struct TopologyEval {
    /// geom's analysis.
    pub report: TopologyReport,
    /// Self-intersecting face pairs (None when not computed).
    pub self_intersections: Option<usize>,
    /// Ground truth (None when not given).
    pub ground_truth: Option<GroundTruthTopology>,
}

impl TopologyEval {
    /// `|2V + 4(G - 1) - F|` for a closed ground truth of known genus.
    pub fn delta_f(&self) -> Option<u64> {
        let gt = self.ground_truth?;
        if !gt.closed {
            return None;
        }
        let g = gt.genus? as i64;
        let v = self.report.vertices as i64;
        let f = self.report.faces as i64;
        Some((2 * v + 4 * (g - 1) - f).unsigned_abs())
    }

    /// Watertight, same component count and same genus as the ground truth.
    pub fn topology_ok(&self) -> Option<bool> {
        let gt = self.ground_truth?;
        let g = gt.genus?;
        Some(
            self.report.watertight
                && self.report.components == gt.components
                && self.report.genus == Some(g),
        )
    }
}

impl Report for TopologyEval {
    fn entries(&self) -> Entries {
        let r = &self.report;
        let mut e = Entries::new();
        put(&mut e, "vertices", r.vertices);
        put(&mut e, "referenced_vertices", r.referenced_vertices);
        put(&mut e, "faces", r.faces);
        put(&mut e, "valid_faces", r.valid_faces);
        put(&mut e, "edges", r.edges);
        put(&mut e, "euler", r.euler);
        put(&mut e, "components", r.components);
        put(&mut e, "boundary_edges", r.boundary_edges);
        put(&mut e, "boundary_loops", r.n_boundary_loops());
        put(
            &mut e,
            "boundary_length_abs",
            r.boundary_loops.iter().map(|l| l.length).sum::<f64>(),
        );
        put(&mut e, "non_manifold_edges", r.non_manifold_edges);
        put(&mut e, "non_manifold_vertices", r.non_manifold_vertices);
        put(&mut e, "orientable", r.orientable);
        put(&mut e, "consistently_oriented", r.consistently_oriented);
        put(&mut e, "watertight", r.watertight);
        put(&mut e, "genus", r.genus);
        put(&mut e, "degenerate_faces", r.degenerate_faces);
        put(&mut e, "collapsed_faces", r.collapsed_faces);
        put(&mut e, "duplicate_faces", r.duplicate_faces);
        put(&mut e, "unreferenced_vertices", r.unreferenced_vertices);
        put(&mut e, "self_intersections", self.self_intersections);
        put(&mut e, "gt_genus", self.ground_truth.and_then(|g| g.genus));
        put(
            &mut e,
            "gt_components",
            self.ground_truth.map(|g| g.components),
        );
        put(&mut e, "delta_f", self.delta_f());
        put(&mut e, "topology_ok", self.topology_ok());
        e
    }
}
serialize_as_entries!(TopologyEval);

/// Topology of `mesh`, compared with `ground_truth` when given.
pub fn eval_topology(
    mesh: &TriMesh,
    ground_truth: Option<GroundTruthTopology>,
    opts: &TopologyOptions,
) -> TopologyEval {
    TopologyEval {
        report: gtopo::analyze(mesh),
        self_intersections: opts
            .self_intersections
            .then(|| count_self_intersections(mesh)),
        ground_truth,
    }
}

/// Number of self-intersecting face pairs (see the module docs).
pub fn count_self_intersections(mesh: &TriMesh) -> usize {
    self_intersecting_pairs(mesh).len()
}

/// The self-intersecting face pairs `(f, g)`, `f < g`, sorted.
pub fn self_intersecting_pairs(mesh: &TriMesh) -> Vec<(u32, u32)> {
    let canon = canonical_vertex_ids(mesh.vertices());
    let faces = mesh.faces();
    let cf: Vec<[u32; 3]> = faces.iter().map(|f| f.map(|v| canon[v as usize])).collect();
    let tris: Vec<[DVec3; 3]> = (0..faces.len()).map(|f| mesh.triangle(f)).collect();
    let live: Vec<bool> = tris.par_iter().map(|t| !collinear(t)).collect();
    let boxes: Vec<Aabb> = tris
        .iter()
        .zip(&live)
        .map(|(t, &l)| if l { Aabb::from_points(t) } else { Aabb::EMPTY })
        .collect();
    let tree = BoxTree::new(&boxes);
    let mut pairs: Vec<(u32, u32)> = (0..faces.len() as u32)
        .into_par_iter()
        .filter(|&f| live[f as usize])
        .map_init(Vec::new, |stack, f| {
            let mut out = Vec::new();
            let a = cf[f as usize];
            tree.for_each_overlap_with(&boxes[f as usize], stack, |g| {
                if g <= f {
                    return;
                }
                let b = cf[g as usize];
                if a.iter().any(|v| b.contains(v)) {
                    return;
                }
                if tri_tri_intersect(&tris[f as usize], &tris[g as usize]) {
                    out.push((f, g));
                }
            });
            out
        })
        .flatten_iter()
        .collect();
    pairs.sort_unstable();
    pairs
}

/// Maps each vertex to the lowest index of a vertex at exactly the same position.
fn canonical_vertex_ids(v: &[DVec3]) -> Vec<u32> {
    let mut keyed: Vec<([u64; 3], u32)> = v
        .iter()
        .enumerate()
        .map(|(i, p)| ((*p + DVec3::ZERO).to_array().map(f64::to_bits), i as u32))
        .collect();
    keyed.par_sort_unstable();
    let mut canon = vec![0u32; v.len()];
    let mut i = 0;
    while i < keyed.len() {
        let mut j = i;
        while j < keyed.len() && keyed[j].0 == keyed[i].0 {
            canon[keyed[j].1 as usize] = keyed[i].1;
            j += 1;
        }
        i = j;
    }
    canon
}

fn c3(p: DVec3) -> Coord3D<f64> {
    Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

fn o3(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> i8 {
    sign(orient3d(c3(a), c3(b), c3(c), c3(d)))
}

fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// Drops coordinate `axis`.
fn proj(p: DVec3, axis: usize) -> Coord<f64> {
    match axis {
        0 => Coord { x: p.y, y: p.z },
        1 => Coord { x: p.z, y: p.x },
        _ => Coord { x: p.x, y: p.y },
    }
}

fn o2(a: DVec3, b: DVec3, c: DVec3, axis: usize) -> i8 {
    sign(orient2d(proj(a, axis), proj(b, axis), proj(c, axis)))
}

/// Exactly collinear (or coincident) corners.
fn collinear(t: &[DVec3; 3]) -> bool {
    (0..3).all(|ax| o2(t[0], t[1], t[2], ax) == 0)
}

/// An axis whose projection keeps triangle `t` non-degenerate (exact test).
fn projection_axis(t: &[DVec3; 3]) -> usize {
    let n = (t[1] - t[0]).cross(t[2] - t[0]).abs();
    let mut axes = [0usize, 1, 2];
    axes.sort_by(|&a, &b| n[b].total_cmp(&n[a]));
    axes.into_iter()
        .find(|&ax| o2(t[0], t[1], t[2], ax) != 0)
        .unwrap_or(axes[0])
}

/// Mixed strict signs among `s`.
fn mixed(s: &[i8]) -> bool {
    s.iter().any(|&x| x > 0) && s.iter().any(|&x| x < 0)
}

/// Closed segments `p1 p2` and `q1 q2` in the projection `axis` intersect.
fn seg_seg_2d(p1: DVec3, p2: DVec3, q1: DVec3, q2: DVec3, axis: usize) -> bool {
    let d1 = o2(q1, q2, p1, axis);
    let d2 = o2(q1, q2, p2, axis);
    let d3 = o2(p1, p2, q1, axis);
    let d4 = o2(p1, p2, q2, axis);
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    let on = |a: DVec3, b: DVec3, c: DVec3| {
        let (a, b, c) = (proj(a, axis), proj(b, axis), proj(c, axis));
        c.x >= a.x.min(b.x) && c.x <= a.x.max(b.x) && c.y >= a.y.min(b.y) && c.y <= a.y.max(b.y)
    };
    (d1 == 0 && on(q1, q2, p1))
        || (d2 == 0 && on(q1, q2, p2))
        || (d3 == 0 && on(p1, p2, q1))
        || (d4 == 0 && on(p1, p2, q2))
}

/// `p` in the closed triangle `t` in the projection `axis`.
fn point_in_tri_2d(p: DVec3, t: &[DVec3; 3], axis: usize) -> bool {
    !mixed(&[
        o2(t[0], t[1], p, axis),
        o2(t[1], t[2], p, axis),
        o2(t[2], t[0], p, axis),
    ])
}

/// Closed segment `pq` and closed triangle `t`, all in one plane.
fn seg_tri_coplanar(p: DVec3, q: DVec3, t: &[DVec3; 3]) -> bool {
    let ax = projection_axis(t);
    point_in_tri_2d(p, t, ax) || (0..3).any(|k| seg_seg_2d(p, q, t[k], t[(k + 1) % 3], ax))
}

/// Closed triangles in one plane.
fn tri_tri_coplanar(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    let ax = projection_axis(a);
    (0..3).any(|i| (0..3).any(|j| seg_seg_2d(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3], ax)))
        || point_in_tri_2d(a[0], b, ax)
        || point_in_tri_2d(b[0], a, ax)
}

/// Closed segment `pq` (with the signs `sp`, `sq` of its ends against the plane of `t`)
/// and closed triangle `t`.
fn seg_tri(p: DVec3, q: DVec3, sp: i8, sq: i8, t: &[DVec3; 3]) -> bool {
    if sp == sq && sp != 0 {
        return false;
    }
    if sp == 0 && sq == 0 {
        return seg_tri_coplanar(p, q, t);
    }
    // The segment meets the plane; the line pq passes through the closed triangle iff
    // the three orientations have no strictly opposite signs.
    !mixed(&[
        o3(p, q, t[0], t[1]),
        o3(p, q, t[1], t[2]),
        o3(p, q, t[2], t[0]),
    ])
}

/// Exact intersection test of two non-degenerate closed triangles.
pub fn tri_tri_intersect(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    let sb = [0, 1, 2].map(|k| o3(a[0], a[1], a[2], b[k]));
    if sb.iter().all(|&s| s > 0) || sb.iter().all(|&s| s < 0) {
        return false;
    }
    if sb.iter().all(|&s| s == 0) {
        return tri_tri_coplanar(a, b);
    }
    let sa = [0, 1, 2].map(|k| o3(b[0], b[1], b[2], a[k]));
    if sa.iter().all(|&s| s > 0) || sa.iter().all(|&s| s < 0) {
        return false;
    }
    (0..3).any(|k| seg_tri(a[k], a[(k + 1) % 3], sa[k], sa[(k + 1) % 3], b))
        || (0..3).any(|k| seg_tri(b[k], b[(k + 1) % 3], sb[k], sb[(k + 1) % 3], a))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [DVec3; 3] {
        [a, b, c].map(DVec3::from_array)
    }

    #[test]
    fn tri_tri_cases() {
        let base = t([0., 0., 0.], [1., 0., 0.], [0., 1., 0.]);
        // Piercing.
        assert!(tri_tri_intersect(
            &base,
            &t([0.2, 0.2, -1.], [0.3, 0.2, 1.], [0.2, 0.3, 1.])
        ));
        // Above.
        assert!(!tri_tri_intersect(
            &base,
            &t([0., 0., 1.], [1., 0., 1.], [0., 1., 1.])
        ));
        // Touching at a point on the plane (vertex on the interior).
        assert!(tri_tri_intersect(
            &base,
            &t([0.2, 0.2, 0.], [0.3, 0.2, 1.], [0.2, 0.3, 1.])
        ));
        // Near miss beside the hypotenuse.
        assert!(!tri_tri_intersect(
            &base,
            &t([0.6, 0.6, -1.], [0.6, 0.6, 1.], [2., 2., 0.])
        ));
        // Coplanar overlap and coplanar disjoint.
        assert!(tri_tri_intersect(
            &base,
            &t([0.2, 0.2, 0.], [2., 0.2, 0.], [0.2, 2., 0.])
        ));
        assert!(!tri_tri_intersect(
            &base,
            &t([2., 2., 0.], [3., 2., 0.], [2., 3., 0.])
        ));
        // Coplanar, one inside the other.
        assert!(tri_tri_intersect(
            &base,
            &t([0.1, 0.1, 0.], [0.2, 0.1, 0.], [0.1, 0.2, 0.])
        ));
        // An edge lying in the plane, crossing the triangle.
        assert!(tri_tri_intersect(
            &base,
            &t([-1., 0.25, 0.], [2., 0.25, 0.], [0.5, 0.25, 1.])
        ));
    }
}
