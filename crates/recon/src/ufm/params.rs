//! Parameters of `ufm` (spec 000 §1.1 and the assumption register, Appendix A).

use reconbench_geom::method::{Describe, MethodError, ParamDoc, Unit};
use serde::{Deserialize, Serialize};

/// Where the initial umbrellas (Step 2) start from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Init {
    /// Gabriel triangles `GT_v`, falling back to all of `DT_v` (the thesis, Step 2.1/2.4).
    #[default]
    Gabriel,
    /// All Delaunay triangles `DT_v` (ablation, spec §4.3).
    Delaunay,
}

/// Direction of the size level inside a matching class during the update (ASSUMPTION
/// The initial queue is always large-first (Step 2.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum SizeOrder {
    /// Larger minimum circumsphere removed first (the default, as the initial queue).
    #[default]
    LargeFirst,
    /// Smaller first (ablation).
    SmallFirst,
}

/// What `ufm` outputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// The loop's output closed by the Delaunay hole closure (`closure.rs`, a deviation):
    /// watertight on the seed's real data sets.
    #[default]
    Closed,
    /// The thesis as written: the loop's matched facets only (Table 3.2 as published is
    /// run in this mode).
    Literal,
}

/// The output triangle set (ASSUMPTION A-11).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum OutputSet {
    /// Every facet with `M_f = 3` (the default).
    #[default]
    MatchedFacets,
    /// Only facets of fully matched umbrellas, `⋃_{G_v = 1} U_v` (literal reading).
    FullUmbrellas,
}

/// Update scheme of Step 3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Update {
    /// Synchronous: every umbrella is rebuilt from the previous iteration's state
    /// ("in parallel" in the thesis); the result does not depend on the thread count.
    #[default]
    Jacobi,
    /// Vertices in index order, matching indices updated in place after each rebuild
    /// (non-faithful ablation of spec §1.1.5; sequential).
    GaussSeidel,
}

/// Normal Vector Cone filtering (Algorithm C of the thesis, chapter 5, spec §1.3;
/// `super::nvc`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Nvc {
    /// Chapter 3's loop (no cone level in the key).
    #[default]
    Off,
    /// Every point with `G_v = 0` gets the generic cone `α_gen` around its nominal
    /// normal (the thesis: "can help the algorithm converge").
    Generic,
    /// Algorithm C: points with a potentially flat umbrella get the
    /// flatness-sensitive cone `α_flat = nvc_flat_factor · θ̄` (θ̄ = mean dihedral
    /// angle of the matched mesh), all others the generic cone.
    Flatness,
    /// Ablation (not in the thesis): only the points with a potentially flat umbrella
    /// get a cone (`α_flat`); all others keep chapter 3's key. Measured: the generic
    /// cone around an averaged normal at points on a sharp edge protects the triangles
    /// that cut the edge off (docs/methods/ufm.md).
    FlatOnly,
}

/// When NVC filtering starts (ASSUMPTION C-06).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum NvcStart {
    /// From the first update iteration on (the spec's reading).
    #[default]
    First,
    /// Only once the plain loop reaches a fixed point or limit cycle (ablation).
    Stagnation,
}

/// Where NVC membership sits in the update key.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum NvcLevel {
    /// The thesis (Fig. 5.5): the new top level, above the matching indices (for
    /// unmatched triangles; matched ones stay last, ASSUMPTION C-05).
    #[default]
    Top,
    /// Ablation: inside each Table 3.1 class, above the size level only.
    BelowClass,
}

/// Parameters of [`super::Ufm`]. Defaults are the thesis's and the spec's ASSUMPTION
/// choices.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct UfmParams {
    /// `closed` (the loop, then the Delaunay hole closure) or `literal` (the thesis's
    /// output).
    pub mode: Mode,
    /// Starting cluster of the initial umbrellas.
    pub init: Init,
    /// ASSUMPTION A-09: make `(3)` facets non-removable during the update (with the A-04
    /// cascade rule and a rebuild without locks when the result is invalid).
    pub lock_matched: bool,
    /// ASSUMPTION A-08: keep fully matched umbrellas as they are (exact optimisation:
    /// a rebuild reproduces them).
    pub freeze_full: bool,
    /// ASSUMPTION A-06: size direction inside a matching class during the update.
    pub size_order: SizeOrder,
    /// ASSUMPTION A-11: output triangle set.
    pub output: OutputSet,
    /// Update scheme (the thesis: synchronous).
    pub update: Update,
    /// ASSUMPTION A-07 (iv): at most this many update iterations (0 = initial
    /// umbrellas only).
    pub max_iter: usize,
    /// ASSUMPTION A-07 (iii): stop when the best matching has not improved for this many
    /// iterations.
    pub patience: usize,
    /// Non-faithful extension (not in the thesis): when the loop reaches a fixed point
    /// or limit cycle below 100 %, run up to this many "escape" updates that ignore the
    /// membership level (M_f then size); 0 = the thesis's loop.
    pub escapes: usize,
    /// Fold repair (a documented deviation, not in the thesis's pseudo-code; see
    /// `docs/methods/ufm.md`): an umbrella whose two facets at some rib have normals
    /// (oriented by the umbrella's cyclic order) more than `max_fold` degrees apart
    /// folds back over itself; its most folded facet is made removable first and
    /// unlocked, and the umbrella rebuilt (up to 3 times). Folded fully matched
    /// umbrellas are not frozen. `0` = off (the thesis's literal loop).
    #[serde(rename = "max_fold_deg", alias = "max_fold")]
    pub max_fold: f64,
    /// Delaunay hole closure (`mode = "closed"`, a deviation; `closure.rs`): after the
    /// loop, the holes are closed from their boundaries with the Delaunay triangles that
    /// continue the surface most flatly, each turning by at most this many degrees
    /// against its neighbour (120); `0` = no closure.
    #[serde(rename = "close_max_turn_deg")]
    pub close_max_turn: f64,
    /// Algorithm C (chapter 5): NVC filtering in the update; `off` = chapter 3.
    pub nvc: Nvc,
    /// Generic cone angle `α_gen` in degrees (spec: 45 = π/4); also the clamp of
    /// `α_flat` (ASSUMPTION C-02).
    #[serde(rename = "nvc_angle_deg", alias = "nvc_angle")]
    pub nvc_angle: f64,
    /// `α_flat = nvc_flat_factor · θ̄` (spec: 2, "doubling the average dihedral angle").
    pub nvc_flat_factor: f64,
    /// Limitation range `R` in umbrella rings: 1 or 2 (spec: 2).
    pub nvc_range: u32,
    /// ASSUMPTION C-06: when NVC filtering starts.
    pub nvc_start: NvcStart,
    /// ASSUMPTION C-05: where NVC membership sits in the key.
    pub nvc_level: NvcLevel,
    /// Run on the points in Morton order (memory locality; 2-8x faster per-vertex
    /// phases on large clouds). Changes only which of exactly tied triangles the
    /// A-02 tie-break (facet id = lexicographic rank of the vertex triple) puts first;
    /// `false` = vertex ids in input order. `ufm-mesh` always uses input order.
    pub reorder: bool,
    /// Known genus of the object (metadata, as in the thesis): when given, the result
    /// reports `delta_f = |2V + 4(G - 1) - F|` (Eq. 3.2) with V the deduplicated count.
    pub genus: Option<u32>,
}

impl Default for UfmParams {
    fn default() -> Self {
        Self {
            mode: Mode::Closed,
            init: Init::Gabriel,
            lock_matched: true,
            freeze_full: true,
            size_order: SizeOrder::LargeFirst,
            output: OutputSet::MatchedFacets,
            update: Update::Jacobi,
            max_iter: 200,
            patience: 20,
            escapes: 0,
            max_fold: 0.0,
            close_max_turn: 120.0,
            nvc: Nvc::Off,
            nvc_angle: 45.0,
            nvc_flat_factor: 2.0,
            nvc_range: 2,
            nvc_start: NvcStart::First,
            nvc_level: NvcLevel::Top,
            reorder: true,
            genus: None,
        }
    }
}

impl UfmParams {
    /// Checks ranges; returns the first offending parameter.
    pub fn validate(&self) -> Result<(), MethodError> {
        if self.max_iter > 100_000 {
            return Err(MethodError::InvalidParameter {
                name: "max_iter".into(),
                message: format!("must be <= 100000, got {}", self.max_iter),
            });
        }
        if self.patience == 0 {
            return Err(MethodError::InvalidParameter {
                name: "patience".into(),
                message: "must be >= 1".into(),
            });
        }
        if !(0.0..=180.0).contains(&self.max_fold) {
            return Err(MethodError::InvalidParameter {
                name: "max_fold_deg".into(),
                message: format!("must be in [0, 180] degrees, got {}", self.max_fold),
            });
        }
        if !(0.0..=180.0).contains(&self.close_max_turn) {
            return Err(MethodError::InvalidParameter {
                name: "close_max_turn_deg".into(),
                message: format!("must be in [0, 180] degrees, got {}", self.close_max_turn),
            });
        }
        if !(self.nvc_angle > 0.0 && self.nvc_angle <= 90.0) {
            return Err(MethodError::InvalidParameter {
                name: "nvc_angle_deg".into(),
                message: format!("must be in (0, 90] degrees, got {}", self.nvc_angle),
            });
        }
        if !(self.nvc_flat_factor > 0.0 && self.nvc_flat_factor <= 100.0) {
            return Err(MethodError::InvalidParameter {
                name: "nvc_flat_factor".into(),
                message: format!("must be in (0, 100], got {}", self.nvc_flat_factor),
            });
        }
        if !(1..=2).contains(&self.nvc_range) {
            return Err(MethodError::InvalidParameter {
                name: "nvc_range".into(),
                message: format!("must be 1 or 2 rings, got {}", self.nvc_range),
            });
        }
        if self.genus.is_some_and(|g| g > 1_000_000) {
            return Err(MethodError::InvalidParameter {
                name: "genus".into(),
                message: "must be <= 1000000".into(),
            });
        }
        Ok(())
    }
}

/// Docs of every parameter of [`UfmParams`], in `list` order.
pub const PARAM_DOCS: &[ParamDoc] = &[
    ParamDoc::new(
        "mode",
        Unit::Choice,
        "closed (the loop, then the Delaunay hole closure; watertight) or literal (the thesis's output)",
    ),
    ParamDoc::new(
        "init",
        Unit::Choice,
        "initial cluster: gabriel (Step 2, falls back to all DT_v) or delaunay",
    ),
    ParamDoc::new(
        "lock_matched",
        Unit::Flag,
        "A-09: (3) facets are non-removable during the update (A-04 cascade rule)",
    ),
    ParamDoc::new(
        "freeze_full",
        Unit::Flag,
        "A-08: keep fully matched umbrellas (exact optimisation)",
    ),
    ParamDoc::new(
        "size_order",
        Unit::Choice,
        "A-06: size order inside a class: large-first or small-first",
    ),
    ParamDoc::new(
        "output",
        Unit::Choice,
        "A-11: output set: matched-facets (M_f = 3) or full-umbrellas",
    ),
    ParamDoc::new(
        "update",
        Unit::Choice,
        "jacobi (synchronous, the thesis) or gauss-seidel (sequential ablation)",
    ),
    ParamDoc::new(
        "max_iter",
        Unit::Count,
        "A-07 (iv): most update iterations (0 = initial umbrellas only)",
    ),
    ParamDoc::new(
        "patience",
        Unit::Count,
        "A-07 (iii): stop after this many iterations without a better matching",
    ),
    ParamDoc::new(
        "escapes",
        Unit::Count,
        "extension: updates ignoring M_f(v) when stuck below 100 % (0 = thesis)",
    ),
    ParamDoc::new(
        "max_fold_deg",
        Unit::Deg,
        "deviation: rebuild umbrellas folding back by more than this angle (0 = thesis)",
    ),
    ParamDoc::new(
        "close_max_turn_deg",
        Unit::Deg,
        "closed mode: close the loop's holes with Delaunay triangles turning at most this (0 = none)",
    ),
    ParamDoc::new(
        "nvc",
        Unit::Choice,
        "Algorithm C (ch. 5) normal vector cones: off, generic (pi/4), flatness, flat-only",
    ),
    ParamDoc::new(
        "nvc_angle_deg",
        Unit::Deg,
        "generic cone angle (45 = pi/4); also the clamp of the flatness cone (C-02)",
    ),
    ParamDoc::new(
        "nvc_flat_factor",
        Unit::None,
        "flatness cone = this x mean dihedral angle of matched edges (2 = thesis)",
    ),
    ParamDoc::new(
        "nvc_range",
        Unit::Count,
        "limitation range in umbrella rings: 1 or 2 (thesis: 2)",
    ),
    ParamDoc::new(
        "nvc_start",
        Unit::Choice,
        "C-06: NVC from the first update (first) or after plain UFM stagnates",
    ),
    ParamDoc::new(
        "nvc_level",
        Unit::Choice,
        "C-05: NVC level in the key: top (thesis) or below-class (inside a class)",
    ),
    ParamDoc::new(
        "reorder",
        Unit::Flag,
        "run on Morton-ordered points (locality; changes only A-02 tie order)",
    ),
    ParamDoc::new(
        "genus",
        Unit::Count,
        "known genus (metadata) for the delta_f diagnostic; none = not reported",
    ),
];

impl Describe for super::Ufm {
    const NAME: &'static str = super::NAME;
    const SOURCE: &'static str = "seed 000 §1.1";
    const SUMMARY: &'static str =
        "Umbrella Facet Matching on the 3D Delaunay triangulation (Ma 2011 ch. 3)";
    type Params = UfmParams;
    const PARAMS: &'static [ParamDoc] = PARAM_DOCS;

    fn from_params(params: UfmParams) -> Result<Self, MethodError> {
        Self::new(params)
    }
}
