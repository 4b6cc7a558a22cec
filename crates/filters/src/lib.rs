//! Filters for reconbench: cloud in, cloud out. In a pipeline a filter's output replaces
//! the cloud the following steps see.
//!
//! | registry name | module | source |
//! |---|---|---|
//! | `statistical-outliers` | [`statistical_outliers`] | statistical outlier removal (Rusu et al. 2008; PCL, Open3D) |

pub mod statistical_outliers;

pub use statistical_outliers::{StatisticalOutliers, StatisticalOutliersParams};
