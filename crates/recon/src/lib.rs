//! Surface reconstructors of reconbench, one module per method.
//!
//! * [`ebt`] — `ebt`, error-bounded thinning and seed-grown triangulation of Sun,
//!   Bradley, Zhang & Loh (CAD 2001), spec 004.
//! * [`hc_it`] — `hc-it`, hierarchical clustering and incremental triangulation of
//!   Sritrakulchai & Sangveraphunsiri, spec 003.
//! * [`priority_front`] — `priority-front`, the priority-driven advancing front of Li,
//!   Han & Wee (CAD 2009), spec 001.
//! * [`ufm`] — `ufm`, Umbrella Facet Matching (Ma 2011, ch. 3, spec 000 §1.1): a
//!   watertight manifold Delaunay reconstruction, and `ufm-mesh`, its local-mesh
//!   normal estimator (ch. 4, Algorithm B).
//!
//! * [`cocone`] — `cocone` (Amenta, Choi, Dey & Leekha 2002) and `tight-cocone` (Dey &
//!   Goswami 2003), the Delaunay baselines of seeds 000 and 001.
//!
//! * [`ball_pivoting`] — `ball-pivoting`, the Ball-Pivoting Algorithm (Bernardini et
//!   al. 1999), the interpolating baseline of seed 001.
//! * [`poisson`] — `poisson`, screened Poisson surface reconstruction (Kazhdan & Hoppe
//!   2013; `screening = 0`: Kazhdan, Bolitho & Hoppe 2006), our own multigrid solver on
//!   a regular grid; approximating.
//!
//! Every method implements [`reconbench_geom::method::Reconstructor`] and has a serde
//! `Params` struct with documented defaults.

mod angle;
pub mod ball_pivoting;
pub mod cocone;
mod diag;
pub mod ebt;
pub mod hc_it;
pub mod poisson;
pub mod priority_front;
pub mod scale;
pub mod ufm;

pub use ball_pivoting::{BallPivoting, BallPivotingParams};
pub use cocone::{Cocone, CoconeParams, TightCocone, TightCoconeParams};
pub use ebt::{Ebt, EbtParams};
pub use hc_it::{HcIt, HcItParams};
pub use poisson::{Poisson, PoissonParams, VertexFit as PoissonVertexFit};
pub use priority_front::{PriorityFront, PriorityFrontParams};
pub use ufm::{Ufm, UfmMesh, UfmMeshParams, UfmParams};
