//! The point representation shared by the predicates, the exact integer predicates, the
//! insertion order and the builder.

/// A point as its three coordinates.
pub(crate) type P3 = [f64; 3];
