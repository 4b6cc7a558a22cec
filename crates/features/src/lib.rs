//! Sharp-feature detectors for reconbench (seed 002: Weber 2011, ch. 3, and the PCA
//! baseline it compares with).
//!
//! | registry name | type | params | source |
//! |---|---|---|---|
//! | `gauss-map` | [`GaussMap`] | [`GaussMapParams`] | Gauss-map clustering, global method (seed 002 §3) |
//! | `gauss-map-adaptive` | [`GaussMapAdaptive`] | [`GaussMapAdaptiveParams`] | local-adaptive variant (seed 002 §4) |
//! | `pca-variation` | [`PcaVariation`] | [`PcaVariationParams`] | surface variation, single and multi-scale (Pauly et al. 2003; seed 002 §5.1) |
//!
//! All three implement [`reconbench_geom::method::FeatureDetector`]. Labels are
//! [`FeatureClass::None`], `Edge` or `Corner` per input point; `scores` hold the surviving
//! Gauss-map cluster count, or the surface variation (single scale) / feature weight
//! omega (multi-scale) for PCA, so sweeps can re-threshold. Results do not depend on the
//! number of threads.
//!
//! Every choice the thesis leaves open is marked `ASSUMPTION W-NN` at the line that
//! implements it and listed in `docs/methods/features.md`; those that change results are
//! parameters.
//!
//! [`FeatureClass::None`]: reconbench_geom::method::FeatureClass::None

pub mod clustering;
mod common;
pub mod gauss_map;
pub mod gauss_map_adaptive;
pub mod pca_variation;

pub use clustering::{AverageLinkage, average_linkage_naive, line_distance};
pub use gauss_map::{
    FlatReference, GaussMap, GaussMapParams, GaussTest, GaussWorkspace, PointOutcome, Stage,
    THESIS_FLAT_TAU,
};
pub use gauss_map_adaptive::{GaussMapAdaptive, GaussMapAdaptiveParams};
pub use pca_variation::{PcaMode, PcaVariation, PcaVariationParams, sym3_eigenvalues};
