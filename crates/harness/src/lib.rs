//! reconbench-harness: the method registry, experiment files, the isolated runner, the
//! results store, aggregation, tables, plots, renders and regression tracking.
//!
//! Data flow: an experiment file ([`experiment`]) expands into a grid of cells with
//! stable keys; the [`runner`] runs each cell in a worker process ([`worker`], which
//! calls [`cell`]) and appends one JSON line per cell ([`store`]); [`aggregate`] turns
//! rows into statistics over seeds, which [`tables`], [`plots`], [`render`] and
//! [`report`] write out; [`compare`] checks results against a saved baseline.

pub mod aggregate;
pub mod cell;
pub mod compare;
pub mod entry;
pub mod error;
pub mod experiment;
pub mod inputs;
pub mod key;
pub mod lock;
pub mod methods;
pub mod metric_spec;
pub mod oneshot;
pub mod pipeline;
pub mod plots;
pub mod progress;
pub mod provenance;
pub mod registry;
pub mod render;
pub mod report;
pub mod runner;
pub mod store;
pub mod tables;
pub mod worker;

pub use error::{HarnessError, Result};
pub use experiment::{Cell, CellSpec, Experiment};
pub use registry::{GroundTruth, MethodEntry, MethodEnv, MethodKind, registry};
pub use runner::{RunOptions, RunSummary, merge, run};
pub use store::{Row, Status};
