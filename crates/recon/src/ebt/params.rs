//! Parameters of `ebt` and of the thinning stage it shares with the `ebt-thinning`
//! filter, with their validation and the documentation `reconbench list` prints.

use reconbench_geom::method::{MethodError, ParamDoc, Unit};
use serde::{Deserialize, Serialize};

/// How the N points of a local quadric patch are chosen (ASSUMPTION E2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Neighborhood {
    /// The N nearest neighbours of the centre (the centre included).
    Nearest,
    /// N drawn at random (seeded) from the 2N nearest: the paper's "randomly sampled in
    /// the locality".
    Random,
}

/// How the quadric coefficients become second derivatives (ASSUMPTION E5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Derivatives {
    /// `(|a|, |b|, |c|)`, as printed in the paper's Eq. 4 (half the true value of the
    /// pure second derivatives).
    Literal,
    /// `(2|a|, |b|, 2|c|)`, the true second derivatives of `a u^2 + b uv + c v^2`.
    Exact,
}

/// How the per-patch derivatives are combined into M1, M2, M3 (ASSUMPTION E6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Aggregation {
    /// Per-component maximum over the patches.
    Max,
    /// The patch with the largest `M1 + 2 M2 + M3`.
    SumMax,
    /// Per-component 95th percentile (nearest rank).
    P95,
}

/// Which error bound gives the maximum edge length Omega (ASSUMPTION E7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OmegaRule {
    /// Eq. 13, `Omega = 2 sqrt(2 eps / M)`, the paper's sharpened bound.
    Eq13,
    /// Eq. 11, `Omega = 3 sqrt(eps / (2 M))`, the cited tessellation bound.
    Eq11,
}

/// Which adjacency the bin size B is derived for (ASSUMPTION E8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BinRule {
    /// Eq. 1, `B = Omega / sqrt 2` (edge-adjacent bins); matches Table 1.
    Eq1,
    /// Eq. 16, `B = Omega / sqrt 3` (corner-adjacent bins stay within Omega).
    Eq16,
}

/// The thinning stage of EBT (paper §4.1-4.3): curvature estimate, Omega, B, binning.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ThinningParams {
    /// Error tolerance epsilon, a fraction of the input's bounding-box diagonal.
    pub epsilon: f64,
    /// Points per local quadric fit N (paper: 24-32).
    pub n_neighbors: usize,
    /// How the N points are chosen.
    pub neighborhood: Neighborhood,
    /// Number of local patches K; 0 = ASSUMPTION E1's `min(200, max(20, n / 500))`.
    pub patches: usize,
    /// Coefficients or true second derivatives.
    pub derivatives: Derivatives,
    /// Combination of the per-patch values.
    pub aggregation: Aggregation,
    /// Formula for Omega.
    pub omega_rule: OmegaRule,
    /// Formula for B.
    pub bin_rule: BinRule,
    /// Bin size forced (fraction of the diagonal); 0 = derived from Omega. When forced,
    /// Omega follows from B through the inverse of `bin_rule`.
    pub bin_size: f64,
    /// Upper bound on Omega (fraction of the diagonal), used when the estimated
    /// curvature is (near) zero and Eq. 13 gives an unbounded edge.
    pub omega_cap: f64,
    /// Bounding-box padding TOL (fraction of the diagonal).
    pub tol: f64,
}

impl Default for ThinningParams {
    fn default() -> Self {
        Self {
            epsilon: 0.002,
            n_neighbors: 28,
            neighborhood: Neighborhood::Nearest,
            patches: 0,
            derivatives: Derivatives::Literal,
            aggregation: Aggregation::Max,
            omega_rule: OmegaRule::Eq13,
            bin_rule: BinRule::Eq1,
            bin_size: 0.0,
            omega_cap: 0.1,
            tol: 1e-6,
        }
    }
}

/// Documentation of [`ThinningParams`], in field order.
pub const THINNING_DOCS: &[ParamDoc] = &[
    ParamDoc::new(
        "epsilon",
        Unit::Diag,
        "error tolerance: max allowed deviation of the data from the mesh",
    ),
    ParamDoc::new(
        "n_neighbors",
        Unit::Count,
        "points per local quadric fit N (paper 24-32; ASSUMPTION E2: 28)",
    ),
    ParamDoc::new(
        "neighborhood",
        Unit::Choice,
        "nearest (ASSUMPTION E2) | random: N of the 2N nearest",
    ),
    ParamDoc::new(
        "patches",
        Unit::Count,
        "local patches K; 0 = min(200, max(20, n/500)) (ASSUMPTION E1)",
    ),
    ParamDoc::new(
        "derivatives",
        Unit::Choice,
        "literal (|a|,|b|,|c|), as printed (ASSUMPTION E5) | exact (2|a|,|b|,2|c|)",
    ),
    ParamDoc::new(
        "aggregation",
        Unit::Choice,
        "max per component (ASSUMPTION E6) | sum-max | p95",
    ),
    ParamDoc::new(
        "omega_rule",
        Unit::Choice,
        "eq13: 2 sqrt(2 eps/M) (ASSUMPTION E7) | eq11: 3 sqrt(eps/(2M))",
    ),
    ParamDoc::new(
        "bin_rule",
        Unit::Choice,
        "eq1: B = Omega/sqrt2, matches Table 1 (ASSUMPTION E8) | eq16: B = Omega/sqrt3",
    ),
    ParamDoc::new(
        "bin_size",
        Unit::Diag,
        "bin size B forced; 0 = from Omega (Omega then follows from B)",
    ),
    ParamDoc::new(
        "omega_cap",
        Unit::Diag,
        "upper bound on Omega when the curvature estimate is (near) zero",
    ),
    ParamDoc::new(
        "tol",
        Unit::Diag,
        "bounding-box padding TOL (ASSUMPTION E9: 1e-6)",
    ),
];

fn bad(name: &str, message: String) -> MethodError {
    MethodError::InvalidParameter {
        name: name.into(),
        message,
    }
}

fn positive(name: &str, v: f64) -> Result<(), MethodError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(bad(name, format!("must be a finite number > 0, got {v}")))
    }
}

fn non_negative(name: &str, v: f64) -> Result<(), MethodError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(bad(name, format!("must be a finite number >= 0, got {v}")))
    }
}

impl ThinningParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), MethodError> {
        positive("epsilon", self.epsilon)?;
        if self.n_neighbors < 6 {
            return Err(bad(
                "n_neighbors",
                format!(
                    "must be at least 6 (a quadric has 3 unknowns), got {}",
                    self.n_neighbors
                ),
            ));
        }
        non_negative("bin_size", self.bin_size)?;
        positive("omega_cap", self.omega_cap)?;
        non_negative("tol", self.tol)?;
        Ok(())
    }
}

/// Parameters of `ebt`: the thinning stage plus the mesh growth (paper §5) and the
/// optional enhancements (§3.6 of the spec).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EbtParams {
    /// Error tolerance epsilon, a fraction of the input's bounding-box diagonal.
    pub epsilon: f64,
    /// Points per local quadric fit N.
    pub n_neighbors: usize,
    /// How the N points are chosen.
    pub neighborhood: Neighborhood,
    /// Number of local patches K; 0 = ASSUMPTION E1.
    pub patches: usize,
    /// Coefficients or true second derivatives.
    pub derivatives: Derivatives,
    /// Combination of the per-patch values.
    pub aggregation: Aggregation,
    /// Formula for Omega.
    pub omega_rule: OmegaRule,
    /// Formula for B.
    pub bin_rule: BinRule,
    /// Bin size forced; 0 = derived from Omega.
    pub bin_size: f64,
    /// Upper bound on Omega.
    pub omega_cap: f64,
    /// Bounding-box padding TOL.
    pub tol: f64,
    /// Minimum triangle angle theta (Rule 2), degrees.
    pub min_angle_deg: f64,
    /// Seed point: index into the input cloud; -1 = ASSUMPTION E11 (the thinned point
    /// nearest the centroid of Q).
    pub seed_point: i64,
    /// ASSUMPTION E19: close ears of gap angle < 90 degrees after each insertion.
    pub ear_filling: bool,
    /// Largest gap angle (degrees) an ear may close; E19 says 90.
    pub ear_angle_deg: f64,
    /// Retry deferred points as soon as a point within Omega joins (E18 refinement);
    /// false = only in the next pass (G4 as written).
    pub wake_deferred: bool,
    /// ASSUMPTION E21: feature-alignment swaps (ABN cost), then lock feature edges.
    pub feature_align: bool,
    /// Dihedral above which an edge counts as a feature edge (E21), degrees.
    pub feature_angle_deg: f64,
    /// ASSUMPTION E20: constrained Lawson swaps towards equilateral triangles.
    pub equilateral: bool,
    /// Crack closing after the growth (a named deviation, docs/methods/ebt.md): the
    /// longest closing edge as a multiple of Omega; 0 = the literal growth.
    pub crack_closing: f64,
    /// Longest edge of a growth facet as a multiple of Omega (a named deviation,
    /// docs/methods/ebt.md): above 1, a facet with a longer edge must fit in a disc of
    /// radius Omega / sqrt 2; 1 = Rule 1 and ASSUMPTION E13 literally.
    pub link_edge: f64,
    /// With crack closing: a crack ear that would break Rule 2 (a sliver) is closed
    /// together with an edge flip against the facet next to it when both facets then
    /// pass (a named deviation, docs/methods/ebt.md); false = such cracks stay open.
    pub sliver_flip: bool,
    /// With crack closing, after the growth: a crack that neither a Rule-2 ear nor a
    /// flip closes is closed by its ear when the ear's smallest angle exceeds this
    /// (degrees); such facets are bad facets (R2) (a named deviation, docs/methods/ebt.md).
    /// 0 = off (the default: such cracks stay open, Rule 2 holds on every facet).
    pub sliver_angle_deg: f64,
    /// Measure the distance of every input point to the mesh (diagnostics `dev_*`).
    pub deviation: bool,
}

impl Default for EbtParams {
    fn default() -> Self {
        let t = ThinningParams::default();
        Self {
            epsilon: t.epsilon,
            n_neighbors: t.n_neighbors,
            neighborhood: t.neighborhood,
            patches: t.patches,
            derivatives: t.derivatives,
            aggregation: t.aggregation,
            omega_rule: t.omega_rule,
            bin_rule: t.bin_rule,
            bin_size: t.bin_size,
            omega_cap: t.omega_cap,
            tol: t.tol,
            min_angle_deg: 12.0,
            seed_point: -1,
            ear_filling: true,
            ear_angle_deg: 90.0,
            wake_deferred: true,
            feature_align: false,
            feature_angle_deg: 30.0,
            equilateral: false,
            crack_closing: std::f64::consts::SQRT_2,
            link_edge: std::f64::consts::SQRT_2,
            sliver_flip: true,
            sliver_angle_deg: 0.0,
            deviation: true,
        }
    }
}

/// Documentation of [`EbtParams`], in field order.
pub const EBT_DOCS: &[ParamDoc] = &[
    THINNING_DOCS[0],
    THINNING_DOCS[1],
    THINNING_DOCS[2],
    THINNING_DOCS[3],
    THINNING_DOCS[4],
    THINNING_DOCS[5],
    THINNING_DOCS[6],
    THINNING_DOCS[7],
    THINNING_DOCS[8],
    THINNING_DOCS[9],
    THINNING_DOCS[10],
    ParamDoc::new(
        "min_angle_deg",
        Unit::Deg,
        "Rule 2: every facet's smallest angle exceeds this (paper: 12)",
    ),
    ParamDoc::new(
        "seed_point",
        Unit::Count,
        "seed: input point index; -1 = the thinned point nearest Q's centroid (ASSUMPTION E11)",
    ),
    ParamDoc::new(
        "ear_filling",
        Unit::Flag,
        "close gaps of angle < 90 deg after each insertion (ASSUMPTION E19; off = literal)",
    ),
    ParamDoc::new(
        "ear_angle_deg",
        Unit::Deg,
        "largest gap angle an ear may close (ASSUMPTION E19: 90)",
    ),
    ParamDoc::new(
        "wake_deferred",
        Unit::Flag,
        "retry a deferred point when a point within Omega joins (E18); off = next pass only (G4)",
    ),
    ParamDoc::new(
        "feature_align",
        Unit::Flag,
        "ABN-cost edge swaps, then feature edges locked (ASSUMPTION E21; not the paper's)",
    ),
    ParamDoc::new(
        "feature_angle_deg",
        Unit::Deg,
        "dihedral above which an edge is a locked feature edge (E21: 30)",
    ),
    ParamDoc::new(
        "equilateral",
        Unit::Flag,
        "constrained Lawson max-min-angle swaps (ASSUMPTION E20; not the paper's)",
    ),
    ParamDoc::new(
        "crack_closing",
        Unit::None,
        "close cracks by ears up to this x Omega after the growth (deviation; sqrt 2 = 1.414); 0 = literal",
    ),
    ParamDoc::new(
        "link_edge",
        Unit::None,
        "longest growth edge x Omega if the facet fits in a disc of radius Omega/sqrt 2 (deviation; 1.414); 1 = literal",
    ),
    ParamDoc::new(
        "sliver_flip",
        Unit::Flag,
        "with crack closing: close a sliver crack ear by flipping an edge with its neighbour facet (deviation); off = leave it open",
    ),
    ParamDoc::new(
        "sliver_angle_deg",
        Unit::Deg,
        "with crack closing: close a crack no Rule-2 facet closes by a sliver above this angle, counted bad (R2; deviation); 0 = off",
    ),
    ParamDoc::new(
        "deviation",
        Unit::Flag,
        "measure every input point's distance to the mesh (dev_* diagnostics)",
    ),
];

impl EbtParams {
    /// The thinning stage's parameters.
    pub fn thinning(&self) -> ThinningParams {
        ThinningParams {
            epsilon: self.epsilon,
            n_neighbors: self.n_neighbors,
            neighborhood: self.neighborhood,
            patches: self.patches,
            derivatives: self.derivatives,
            aggregation: self.aggregation,
            omega_rule: self.omega_rule,
            bin_rule: self.bin_rule,
            bin_size: self.bin_size,
            omega_cap: self.omega_cap,
            tol: self.tol,
        }
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), MethodError> {
        self.thinning().validate()?;
        if !(self.min_angle_deg.is_finite() && (0.0..60.0).contains(&self.min_angle_deg)) {
            return Err(bad(
                "min_angle_deg",
                format!("must be in [0, 60), got {}", self.min_angle_deg),
            ));
        }
        if !(self.ear_angle_deg.is_finite()
            && self.ear_angle_deg > 0.0
            && self.ear_angle_deg < 180.0)
        {
            return Err(bad(
                "ear_angle_deg",
                format!("must be in (0, 180), got {}", self.ear_angle_deg),
            ));
        }
        if self.seed_point < -1 || self.seed_point > u32::MAX as i64 {
            return Err(bad(
                "seed_point",
                format!("must be -1 or a point index, got {}", self.seed_point),
            ));
        }
        if !(self.crack_closing == 0.0 || (1.0..=2.0).contains(&self.crack_closing)) {
            return Err(bad(
                "crack_closing",
                format!(
                    "must be 0 (off) or in [1, 2] (a multiple of Omega), got {}",
                    self.crack_closing
                ),
            ));
        }
        if !(1.0..=std::f64::consts::SQRT_2).contains(&self.link_edge) {
            return Err(bad(
                "link_edge",
                format!(
                    "must be in [1, sqrt 2 = 1.4142135623730951] (a multiple of Omega), got {}",
                    self.link_edge
                ),
            ));
        }
        if !(self.sliver_angle_deg == 0.0
            || (self.sliver_angle_deg > 0.0 && self.sliver_angle_deg < self.min_angle_deg))
        {
            return Err(bad(
                "sliver_angle_deg",
                format!(
                    "must be 0 (off) or in (0, min_angle_deg = {}) degrees, got {}",
                    self.min_angle_deg, self.sliver_angle_deg
                ),
            ));
        }
        if !(self.feature_angle_deg.is_finite()
            && self.feature_angle_deg > 0.0
            && self.feature_angle_deg < 180.0)
        {
            return Err(bad(
                "feature_angle_deg",
                format!("must be in (0, 180), got {}", self.feature_angle_deg),
            ));
        }
        Ok(())
    }
}
