//! Test support for the reconbench workspace: deterministic fixtures shared by the
//! crates' tests, benches and the probes in `tools/`. Not part of any public API.
//!
//! * [`points`]: seeded point sets for the Delaunay tests (cube, torus, sphere, grids).
//! * [`surfaces`]: parametric test surfaces and samplers for the reconstructors.
//! * [`meshes`]: small meshes with known topology (tetrahedron, cube, spheres, tori...).
//! * [`metric_fixtures`]: an analytic sphere `Shape`, mesh edits, brute-force distance.
//! * [`feature_fixtures`]: clouds with exact feature ground truth, labelling scores.
//! * [`box_edges`]: the box sampled with its edges, and edge-preservation measures.
//! * [`hc_it_inputs`]: the sheets, sphere and noisy height field of the `hc-it` tests,
//!   bench and probe.

pub mod box_edges;
pub mod feature_fixtures;
pub mod hc_it_inputs;
pub mod meshes;
pub mod metric_fixtures;
pub mod points;
pub mod surfaces;
