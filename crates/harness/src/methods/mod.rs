//! Methods the harness registers: ground-truth oracles, test-only methods, external
//! programs ([`external`]) and the entries of the algorithm crates ([`algorithms`]).

pub mod algorithms;
pub mod debug;
pub mod external;
pub mod oracle;
