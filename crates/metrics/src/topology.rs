//! Topology of a reconstructed mesh: geom's [`TopologyReport`] plus the seed's Delta F,
//! `topology_ok` against the ground truth, and self-intersecting face pairs.
//!
//! * `delta_f = |2V + 4(G - 1) - F|` (seed 000, eq. 3.2) with V and F the raw vertex and
//!   face counts of the mesh (the seed's V is the number of input points, which an
//!   interpolating mesh uses as its vertices) and G the ground-truth genus; only for a
//!   closed ground truth of known genus.
//! * `topology_type_ok` = watertight, same number of components and same genus as the
//!   ground truth (the topological type alone; the meaning `topology_ok` had before).
//! * `topology_ok` = `topology_type_ok` and no self-intersecting face pair (when they are
//!   counted): a surface that passes through itself is not an embedding of the true one,
//!   however right its Euler characteristic. Dropped input points are not a topology
//!   defect; they are counted apart (`unreferenced_vertices`).
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

    /// Watertight, same component count and same genus as the ground truth: the
    /// topological type alone, self-intersections allowed.
    pub fn topology_type_ok(&self) -> Option<bool> {
        let gt = self.ground_truth?;
        let g = gt.genus?;
        Some(
            self.report.watertight
                && self.report.components == gt.components
                && self.report.genus == Some(g),
        )
    }

    /// [`topology_type_ok`](Self::topology_type_ok) and no self-intersecting face pair
    /// (when self-intersections were counted).
    pub fn topology_ok(&self) -> Option<bool> {
        let type_ok = self.topology_type_ok()?;
        Some(type_ok && self.self_intersections.unwrap_or(0) == 0)
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
        put(&mut e, "topology_type_ok", self.topology_type_ok());
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
    let live: Vec<bool> = tris.par_iter().map(|t| !exactly_collinear(t)).collect();
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

use reconbench_geom::spatial::exactly_collinear;
pub use reconbench_geom::spatial::tri_tri_intersect;
