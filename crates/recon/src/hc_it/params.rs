//! Parameters of `hc-it`, their validation and the documentation `reconbench list` prints.

use std::f64::consts::PI;

use reconbench_geom::method::{MethodError, ParamDoc, Unit};
use serde::{Deserialize, Serialize};

/// How the point-to-boundary-edge distance of the winner search is computed
/// (ASSUMPTION H7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EdgeDistance {
    /// Exact point-to-segment distance.
    Segment,
    /// The paper's two-branch formula (Fig. 12): `|P - y|` beyond `y`, else the
    /// perpendicular distance, also when the projection falls before `x`.
    Literal,
}

/// Which boundary edges the winner search scans.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WinnerScan {
    /// Boundary edges with an endpoint among the point's rho-neighbours of the cluster
    /// (falls back to `all` when there is none).
    Local,
    /// Every boundary edge of the cluster's mesh (the paper; O(|BTM|) per point).
    All,
}

/// Which of two conflicting neighbourhood triangles is tried first (ASSUMPTION H12).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ConflictRule {
    /// Smaller wedge angle at the shared boundary vertex.
    Wedge,
    /// Smaller paper-phi (angle between the normals with the shared edge in the same
    /// direction, i.e. the more folded candidate).
    Phi,
}

/// What runs after the sweep (a named deviation; `none` is the literal method).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Closure {
    /// Nothing: the sweep's mesh as it is (the paper).
    None,
    /// The closure pass: mesh the points the sweep never revisited and zip the cracks
    /// between NC meshes under the fold test, with triangles of circumradius at most
    /// `zip_radius` rho, so wider holes stay open.
    Zip,
}

/// Parameters of `hc-it` (spec 003 §1, §3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HcItParams {
    /// rho, the clustering distance and "max edge length", as a multiple of the mean
    /// nearest-neighbour spacing (spec §6: 1.5-3).
    pub rho: f64,
    /// theta threshold of the fold / steepness test (paper: pi/2), radians.
    pub theta_rad: f64,
    /// psi threshold of the split test (paper: pi/12), radians, in (0, pi/2).
    pub psi_rad: f64,
    /// Reference vector k orienting the first triangle of each cluster.
    pub reference: [f64; 3],
    /// ASSUMPTION H8: only boundary edges with both endpoints within rho can win.
    pub strict_rho: bool,
    /// ASSUMPTION H7: exact segment distance or the paper's formula.
    pub edge_distance: EdgeDistance,
    /// Boundary edges scanned by the winner search.
    pub winner_scan: WinnerScan,
    /// Add the neighbourhood triangles of paper §3.3 (ASSUMPTION H11).
    pub neighbourhood: bool,
    /// Cap on a neighbourhood triangle's new edge, as a multiple of rho; 0 = no cap
    /// (the literal H11 with `strict_rho` off).
    pub ear_max_edge: f64,
    /// ASSUMPTION H12: order of conflicting neighbourhood candidates.
    pub conflict_rule: ConflictRule,
    /// Shortest-diagonal flips of paper §3.4 (ASSUMPTION H13).
    pub flips: bool,
    /// Slab planes along x as fractions of the x-extent, ascending in [0, 1]; the slabs
    /// are the intervals between consecutive planes (the first closed below, the rest
    /// open below, paper O2-O3) and points outside every slab are ignored. Empty = one
    /// slab over everything.
    pub slabs: Vec<f64>,
    /// ASSUMPTION H15: mesh every slab separately (fresh clustering and mesh state) and
    /// concatenate, as the paper's example 9; off = ASSUMPTION H3, one sweep whose state
    /// carries over from slab to slab.
    pub portions: bool,
    /// Deviation: the closure pass after the sweep (`zip`, default) or none (literal).
    pub closure: Closure,
    /// Largest circumradius of a closing triangle, as a multiple of rho: gaps a ball of
    /// this radius cannot pass stay open.
    pub zip_radius: f64,
    /// ASSUMPTION H14: flip every mesh component whose area-weighted normal points away
    /// from k (off = literal: each NC keeps the orientation of its first triangle).
    pub orient_by_k: bool,
}

impl Default for HcItParams {
    fn default() -> Self {
        Self {
            rho: 2.0,
            theta_rad: PI / 2.0,
            psi_rad: PI / 12.0,
            reference: [0.0, 0.0, 1.0],
            strict_rho: false,
            edge_distance: EdgeDistance::Segment,
            winner_scan: WinnerScan::Local,
            neighbourhood: true,
            ear_max_edge: 1.0,
            conflict_rule: ConflictRule::Wedge,
            flips: true,
            slabs: Vec::new(),
            portions: false,
            closure: Closure::Zip,
            zip_radius: 1.0,
            orient_by_k: false,
        }
    }
}

fn bad(name: &str, message: String) -> MethodError {
    MethodError::InvalidParameter {
        name: name.into(),
        message,
    }
}

impl HcItParams {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), MethodError> {
        if !(self.rho.is_finite() && self.rho > 0.0) {
            return Err(bad("rho", format!("must be > 0, got {}", self.rho)));
        }
        if !(self.theta_rad > 0.0 && self.theta_rad < PI) {
            return Err(bad(
                "theta_rad",
                format!("must be in (0, pi), got {}", self.theta_rad),
            ));
        }
        if !(self.psi_rad > 0.0 && self.psi_rad < PI / 2.0) {
            return Err(bad(
                "psi_rad",
                format!("must be in (0, pi/2), got {}", self.psi_rad),
            ));
        }
        let k = self.reference;
        let len = (k[0] * k[0] + k[1] * k[1] + k[2] * k[2]).sqrt();
        if !(len.is_finite() && len > 0.0) {
            return Err(bad(
                "reference",
                format!("must be a finite non-zero vector, got {k:?}"),
            ));
        }
        if !(self.ear_max_edge.is_finite() && self.ear_max_edge >= 0.0) {
            return Err(bad(
                "ear_max_edge",
                format!("must be >= 0, got {}", self.ear_max_edge),
            ));
        }
        if !(self.zip_radius.is_finite() && self.zip_radius > 0.0) {
            return Err(bad(
                "zip_radius",
                format!("must be > 0, got {}", self.zip_radius),
            ));
        }
        if self.slabs.len() == 1 {
            return Err(bad("slabs", "needs at least two planes (or none)".into()));
        }
        for w in self.slabs.windows(2) {
            if w[0] >= w[1] || w[0].is_nan() || w[1].is_nan() {
                return Err(bad(
                    "slabs",
                    format!("planes must ascend strictly, got {:?}", self.slabs),
                ));
            }
        }
        if self.slabs.iter().any(|x| !(0.0..=1.0).contains(x)) {
            return Err(bad(
                "slabs",
                format!("planes must lie in [0, 1], got {:?}", self.slabs),
            ));
        }
        Ok(())
    }
}

/// Documentation of [`HcItParams`], in field order.
pub const HC_IT_DOCS: &[ParamDoc] = &[
    ParamDoc::new(
        "rho",
        Unit::Spacing,
        "rho: clustering threshold and max edge length (paper's 'max edge length')",
    ),
    ParamDoc::new(
        "theta_rad",
        Unit::Rad,
        "fold / steepness threshold on the angle between new and winner normals (paper pi/2)",
    ),
    ParamDoc::new(
        "psi_rad",
        Unit::Rad,
        "split threshold: P nearly inside the winner triangle (paper pi/12)",
    ),
    ParamDoc::new(
        "reference",
        Unit::None,
        "reference vector k orienting each cluster's first triangle (paper: +z)",
    ),
    ParamDoc::new(
        "strict_rho",
        Unit::Flag,
        "ASSUMPTION H8: winner edges need both endpoints within rho (off = literal)",
    ),
    ParamDoc::new(
        "edge_distance",
        Unit::Choice,
        "ASSUMPTION H7: segment (exact) or literal (paper Fig. 12 formula)",
    ),
    ParamDoc::new(
        "winner_scan",
        Unit::Choice,
        "local (boundary edges at the rho-neighbours) or all (every BTM edge, the paper)",
    ),
    ParamDoc::new(
        "neighbourhood",
        Unit::Flag,
        "ASSUMPTION H11: add the neighbourhood (ear / fan) triangles of paper §3.3",
    ),
    ParamDoc::new(
        "ear_max_edge",
        Unit::None,
        "cap on a neighbourhood triangle's new edge in multiples of rho (0 = uncapped)",
    ),
    ParamDoc::new(
        "conflict_rule",
        Unit::Choice,
        "ASSUMPTION H12: wedge (smaller wedge angle) or phi (paper's smaller phi)",
    ),
    ParamDoc::new(
        "flips",
        Unit::Flag,
        "ASSUMPTION H13: shortest-diagonal flips (self-adjustable connectivity, §3.4)",
    ),
    ParamDoc::new(
        "slabs",
        Unit::Fraction,
        "slab planes along x (fractions of the x-extent, ascending); outside points ignored",
    ),
    ParamDoc::new(
        "portions",
        Unit::Flag,
        "ASSUMPTION H15: mesh each slab separately and concatenate (paper example 9)",
    ),
    ParamDoc::new(
        "closure",
        Unit::Choice,
        "deviation: zip (mesh unmeshed points, zip cracks between NC meshes) or none (literal)",
    ),
    ParamDoc::new(
        "zip_radius",
        Unit::None,
        "largest circumradius of a closing triangle in multiples of rho (wider holes stay open)",
    ),
    ParamDoc::new(
        "orient_by_k",
        Unit::Flag,
        "ASSUMPTION H14: orient every mesh component so its normals agree with k on average",
    ),
];
