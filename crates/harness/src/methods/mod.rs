//! Methods the harness registers: ground-truth oracles, test-only methods, and the
//! entries of the algorithm crates ([`algorithms`]).

pub mod algorithms;
pub mod debug;
pub mod oracle;
