//! Filters for reconbench: cloud in, cloud out. In a pipeline a filter's output replaces
//! the cloud the following steps see.
//!
//! | registry name | module | source |
//! |---|---|---|
//! | `statistical-outliers` | [`statistical_outliers`] | statistical outlier removal (Rusu et al. 2008; PCL, Open3D) |
//! | `mls` | [`mls`] | projection MLS (seed 002 §2.5, §6.9; Levin, Alexa et al.) |
//! | `mls-sharp` | [`mls_sharp`] | sharp MLS by neighbourhood modification (seed 002 §6) |
//! | `blend` | [`blend`] | NURBS tube blended into the scan through a thinned collar, then sharp MLS (seed 002 §7) |
//! | `ebt-thinning`, `random-thinning`, `grid-thinning` | [`thinning`] | EBT's error-bounded voxel thinning (seed 004 §4) and its budget baselines |

pub mod blend;
pub mod mls;
pub mod mls_sharp;
pub mod statistical_outliers;
pub mod thinning;

pub use blend::{Blend, BlendParams};
pub use mls::{Mls, MlsParams};
pub use mls_sharp::{MlsSharp, MlsSharpParams};
pub use statistical_outliers::{StatisticalOutliers, StatisticalOutliersParams};
pub use thinning::{EbtThinning, GridThinning, RandomThinning};
