//! Methods the harness registers itself: ground-truth oracles and test-only methods.
//! Real algorithms live in their own crates and are registered in [`crate::registry`].

pub mod debug;
pub mod oracle;
