//! Parameters of `ball-pivoting`.

use reconbench_geom::method::{MethodError, ParamDoc, Unit};
use serde::{Deserialize, Serialize};

/// Parameters of `ball-pivoting`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BallPivotingParams {
    /// Ball radii as multiples of the mean nearest-neighbour spacing, one pass each, in
    /// increasing order (Open3D and MeshLab take a list of radii; the spacing multiple
    /// makes one default fit every sampling density).
    pub radii_spacing: Vec<f64>,
    /// Explicit ball radii in the cloud's own units; when non-empty they replace
    /// `radii_spacing` (what Open3D's `radii` argument is).
    pub radii: Vec<f64>,
    /// Largest share of points whose nearest neighbour has an opposite normal
    /// (`n_i . n_j < 0`) before the input is refused as unoriented.
    pub max_flipped_share: f64,
}

impl Default for BallPivotingParams {
    fn default() -> Self {
        Self {
            radii_spacing: vec![2.0, 3.0, 5.0],
            radii: Vec::new(),
            max_flipped_share: 0.2,
        }
    }
}

/// One doc per field of [`BallPivotingParams`].
pub const PARAM_DOCS: &[ParamDoc] = &[
    ParamDoc::new(
        "radii_spacing",
        Unit::Spacing,
        "ball radii, one pass each in increasing order, as multiples of the mean nearest-neighbour spacing",
    ),
    ParamDoc::new(
        "radii",
        Unit::None,
        "explicit ball radii in the cloud's units (replace radii_spacing when non-empty)",
    ),
    ParamDoc::new(
        "max_flipped_share",
        Unit::Fraction,
        "largest share of points whose nearest neighbour's normal is opposite before the normals count as unoriented",
    ),
];

fn check_list(name: &str, v: &[f64]) -> Result<(), MethodError> {
    let bad = |message: String| MethodError::InvalidParameter {
        name: name.into(),
        message,
    };
    if let Some(x) = v.iter().find(|x| !(x.is_finite() && **x > 0.0)) {
        return Err(bad(format!("every radius must be finite and > 0, got {x}")));
    }
    if v.windows(2).any(|w| w[1] <= w[0]) {
        return Err(bad(format!("radii must be strictly increasing, got {v:?}")));
    }
    if v.len() > 16 {
        return Err(bad(format!("at most 16 radii, got {}", v.len())));
    }
    Ok(())
}

impl BallPivotingParams {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), MethodError> {
        check_list("radii_spacing", &self.radii_spacing)?;
        check_list("radii", &self.radii)?;
        if self.radii.is_empty() && self.radii_spacing.is_empty() {
            return Err(MethodError::InvalidParameter {
                name: "radii_spacing".into(),
                message: "needs at least one radius (or give radii)".into(),
            });
        }
        if !(0.0..=1.0).contains(&self.max_flipped_share) {
            return Err(MethodError::InvalidParameter {
                name: "max_flipped_share".into(),
                message: format!("must be in [0, 1], got {}", self.max_flipped_share),
            });
        }
        Ok(())
    }
}
