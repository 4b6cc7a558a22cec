//! Filters for reconbench: cloud in, cloud out. In a pipeline a filter's output replaces
//! the cloud the following steps see.
//!
//! | registry name | module | source |
//! |---|---|---|
//! | `statistical-outliers` | [`statistical_outliers`] | statistical outlier removal (Rusu et al. 2008; PCL, Open3D) |
//! | `mls` | [`mls`] | projection MLS (seed 002 §2.5, §6.9; Levin, Alexa et al.) |
//! | `mls-sharp` | [`mls_sharp`] | sharp MLS by neighbourhood modification (seed 002 §6) |

pub mod mls;
pub mod mls_sharp;
pub mod statistical_outliers;

pub use mls::{Mls, MlsParams};
pub use mls_sharp::{MlsSharp, MlsSharpParams};
pub use statistical_outliers::{StatisticalOutliers, StatisticalOutliersParams};
