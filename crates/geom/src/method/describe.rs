//! The descriptor each method implements once, next to its code: registry name, source,
//! summary, documented parameters with units, what its input must carry, and a
//! constructor that validates every parameter.
//!
//! The harness registers a method from this alone (one line per method), and a registry
//! test checks every name, doc and default against it.

use serde::Serialize;
use serde::de::DeserializeOwned;

use super::MethodError;

/// Unit of a parameter, as `reconbench list` prints it.
///
/// Angle convention: an angle parameter's unit is [`Unit::Deg`] or [`Unit::Rad`] and its
/// name ends in `_deg` or `_rad` accordingly, unless it is a symbol of the source paper
/// (`sigma`, `theta`, ...) documented with its unit; a registry test enforces this.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Unit {
    /// Dimensionless number (ratio, factor, sine, threshold of a unitless statistic).
    None,
    /// A count (neighbours, iterations, points).
    Count,
    /// Fraction of the input's bounding-box diagonal.
    Diag,
    /// Multiple of the mean point spacing.
    Spacing,
    /// Degrees.
    Deg,
    /// Radians.
    Rad,
    /// Seconds.
    Seconds,
    /// Mebibytes.
    MiB,
    /// A fraction in `[0, 1]` (share of points, probability).
    Fraction,
    /// One of a fixed set of names (the doc lists them).
    Choice,
    /// A boolean switch.
    Flag,
}

impl Unit {
    /// Short name printed by `list` (empty for [`Unit::None`]).
    pub fn as_str(self) -> &'static str {
        match self {
            Unit::None => "",
            Unit::Count => "count",
            Unit::Diag => "diag",
            Unit::Spacing => "spacing",
            Unit::Deg => "deg",
            Unit::Rad => "rad",
            Unit::Seconds => "s",
            Unit::MiB => "MiB",
            Unit::Fraction => "fraction",
            Unit::Choice => "choice",
            Unit::Flag => "flag",
        }
    }

    /// Whether the unit is an angle.
    pub fn is_angle(self) -> bool {
        matches!(self, Unit::Deg | Unit::Rad)
    }
}

impl std::fmt::Display for Unit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Documentation of one parameter (its default comes from the `Params` type).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct ParamDoc {
    /// Name as written in experiment files and `--set`.
    pub name: &'static str,
    /// Unit.
    pub unit: Unit,
    /// One sentence; names the ASSUMPTION it implements where there is one.
    pub doc: &'static str,
}

impl ParamDoc {
    /// A parameter doc (usable in `const` tables).
    pub const fn new(name: &'static str, unit: Unit, doc: &'static str) -> Self {
        Self { name, unit, doc }
    }
}

/// What a method needs attached to its input cloud beyond positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Needs {
    /// Positions only.
    Positions,
    /// Normals, orientation not required.
    Normals,
    /// Consistently oriented normals.
    OrientedNormals,
}

impl Needs {
    /// Human-readable requirement.
    pub fn as_str(self) -> &'static str {
        match self {
            Needs::Positions => "positions",
            Needs::Normals => "normals",
            Needs::OrientedNormals => "oriented normals",
        }
    }
}

/// The static description of a method and its validated construction.
///
/// Implemented once per method, beside it; the registry entry is then one line
/// (`normals::<PlaneFit>()`).
pub trait Describe: Sized {
    /// Stable kebab-case registry name.
    const NAME: &'static str;
    /// Section of the source it implements (`"seed 001 §4"`, `"baseline (CGAL)"`).
    const SOURCE: &'static str;
    /// One-line summary for `list`.
    const SUMMARY: &'static str;
    /// What the input cloud must carry (default: positions only).
    const NEEDS: Needs = Needs::Positions;
    /// Typed parameters: serde with `#[serde(default, deny_unknown_fields)]`.
    type Params: Serialize + DeserializeOwned + Default;
    /// One doc per field of [`Self::Params`], in `list` order.
    const PARAMS: &'static [ParamDoc];
    /// Builds the method, checking every parameter (so a bad value fails when the
    /// experiment file loads, not in every worker).
    fn from_params(params: Self::Params) -> Result<Self, MethodError>;
}
