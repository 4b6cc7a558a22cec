//! Diagnostics every reconstructor reports the same way.

use reconbench_geom::method::{Diagnostic, Diagnostics};
use reconbench_geom::topology::TopologyReport;

/// Records a number.
pub(crate) fn num(d: &mut Diagnostics, k: &str, v: f64) {
    d.insert(k.to_string(), Diagnostic::Number(v));
}

/// Records the output mesh's topology counts: pinched vertices, non-manifold and boundary
/// edges, boundary loops, components and watertightness.
pub(crate) fn topology(d: &mut Diagnostics, rep: &TopologyReport) {
    num(d, "pinched_vertices", rep.non_manifold_vertices as f64);
    num(d, "non_manifold_edges", rep.non_manifold_edges as f64);
    num(d, "boundary_edges", rep.boundary_edges as f64);
    num(d, "boundary_loops", rep.n_boundary_loops() as f64);
    num(d, "components", rep.components as f64);
    num(d, "watertight", rep.watertight as u8 as f64);
}
