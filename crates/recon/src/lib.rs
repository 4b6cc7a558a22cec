//! Surface reconstructors of reconbench, one module per method.
//!
//! * [`priority_front`] — `priority-front`, the priority-driven advancing front of Li,
//!   Han & Wee (CAD 2009), spec 001.
//!
//! Every method implements [`reconbench_geom::method::Reconstructor`] and has a serde
//! `Params` struct with documented defaults. [`samples`] holds small point-set
//! generators for this crate's tests and benches.

pub mod priority_front;
pub mod samples;

pub use priority_front::{PriorityFront, PriorityFrontParams};
