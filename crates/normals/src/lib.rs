//! Normal estimators for reconbench and the orientation step that can follow any of them.
//!
//! | registry name | module | source |
//! |---|---|---|
//! | `pf` | [`plane_fit`] | plane fitting, Hoppe et al. 1992 (seed 000 §1.2.4) |
//! | `wpf` | [`plane_fit`] | Gaussian-weighted plane fitting, Pauly et al. 2003 (seed 000 §1.2.5) |
//! | `jet` | [`jet`] | degree-2 osculating jet, Cazals & Pouget 2005 (the CGAL estimator) |
//! | `lvm-approx` | [`lvm_approx`] | stand-in for OuYang & Feng's local Voronoi mesh (seed 000 §1.2.6, ASSUMPTION B-09) |
//!
//! Every estimator returns unit normals (zero where the neighbourhood is degenerate:
//! all points coincident or collinear) and, unless `orient_k = 0`, orients them
//! consistently by minimum-spanning-tree propagation ([`orient`]).

pub mod jet;
pub mod lvm_approx;
pub mod neighbors;
pub mod orient;
pub mod plane_fit;

pub use jet::{Jet, JetParams};
pub use lvm_approx::{LvmApprox, LvmApproxParams};
pub use orient::{OrientReport, orient_mst};
pub use plane_fit::{
    PlaneFit, PlaneFitParams, SigmaRule, WeightedPlaneFit, WeightedPlaneFitParams,
};
