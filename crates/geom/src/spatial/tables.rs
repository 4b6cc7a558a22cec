//! Neighbour types and tables returned by the point queries.

/// One neighbour: the point index and its squared distance to the query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Neighbor {
    /// Index of the point in the slice the index was built from.
    pub index: u32,
    /// Squared Euclidean distance to the query, `(p - q).length_squared()`.
    pub dist2: f64,
}

/// Fixed-`k` neighbour lists of many queries, row-major: row `i` is
/// `indices[i * k..(i + 1) * k]` (and the same for `dist2`), sorted by (distance, index).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KnnTable {
    /// Neighbours per row (after clamping to the number of available points).
    pub k: usize,
    /// Neighbour indices, `rows * k` values.
    pub indices: Vec<u32>,
    /// Squared distances, `rows * k` values.
    pub dist2: Vec<f64>,
}

impl KnnTable {
    /// Number of rows (queries).
    pub fn rows(&self) -> usize {
        self.indices.len().checked_div(self.k).unwrap_or(0)
    }

    /// Neighbour indices of row `i`.
    pub fn indices(&self, i: usize) -> &[u32] {
        &self.indices[i * self.k..(i + 1) * self.k]
    }

    /// Squared distances of row `i`.
    pub fn dist2(&self, i: usize) -> &[f64] {
        &self.dist2[i * self.k..(i + 1) * self.k]
    }
}

/// Variable-length neighbour lists (radius queries) in CSR form: row `i` is
/// `offsets[i]..offsets[i + 1]` of `indices` / `dist2`, sorted by (distance, index).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RadiusTable {
    /// `rows + 1` offsets.
    pub offsets: Vec<usize>,
    /// Neighbour indices.
    pub indices: Vec<u32>,
    /// Squared distances.
    pub dist2: Vec<f64>,
}

impl RadiusTable {
    /// Number of rows (queries).
    pub fn rows(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Neighbour indices of row `i`.
    pub fn indices(&self, i: usize) -> &[u32] {
        &self.indices[self.offsets[i]..self.offsets[i + 1]]
    }

    /// Squared distances of row `i`.
    pub fn dist2(&self, i: usize) -> &[f64] {
        &self.dist2[self.offsets[i]..self.offsets[i + 1]]
    }
}
