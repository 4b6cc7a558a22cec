//! Axis-aligned bounding boxes.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// An axis-aligned bounding box. An empty box has `min > max` on every axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    /// Lower corner.
    pub min: DVec3,
    /// Upper corner.
    pub max: DVec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box, the neutral element of [`Aabb::grow`].
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    /// The smallest box containing all `points` (empty for no points).
    pub fn from_points(points: &[DVec3]) -> Self {
        points.iter().fold(Self::EMPTY, |b, &p| b.grow(p))
    }

    /// This box enlarged to contain `p`.
    #[must_use]
    pub fn grow(self, p: DVec3) -> Self {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Union of two boxes.
    #[must_use]
    pub fn union(self, o: Aabb) -> Self {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// True when the box contains no point.
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// Extent along each axis (zero for an empty box).
    pub fn size(&self) -> DVec3 {
        if self.is_empty() {
            DVec3::ZERO
        } else {
            self.max - self.min
        }
    }

    /// Length of the diagonal: the unit of lengths in reconbench reports.
    pub fn diagonal(&self) -> f64 {
        self.size().length()
    }

    /// Centre of the box.
    pub fn center(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }

    /// True when `p` lies in the closed box.
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diagonal_of_unit_cube_is_sqrt3() {
        let b = Aabb::from_points(&[DVec3::ZERO, DVec3::ONE, DVec3::splat(0.5)]);
        assert!((b.diagonal() - 3f64.sqrt()).abs() < 1e-15);
        assert!(b.contains(DVec3::splat(0.25)));
        assert!(!b.contains(DVec3::splat(1.5)));
    }

    #[test]
    fn empty_box_has_zero_size() {
        let b = Aabb::from_points(&[]);
        assert!(b.is_empty());
        assert_eq!(b.diagonal(), 0.0);
    }
}
