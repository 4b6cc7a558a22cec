//! Exact sharp-feature primitives (segments, circular arcs, corner points) with their
//! dihedral angles; converted to [`FeatureCurve`] polylines for the public API.

use glam::DVec3;

use crate::shape::FeatureCurve;

/// An exact feature curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FeatureGeom {
    /// Straight edge.
    Segment {
        /// Start.
        a: DVec3,
        /// End.
        b: DVec3,
    },
    /// Circular arc: `center + r (cos t u + sin t v)`, `t` in `[t0, t0 + sweep]`.
    Arc {
        /// Centre.
        center: DVec3,
        /// First in-plane axis (unit).
        u: DVec3,
        /// Second in-plane axis (unit, orthogonal to `u`).
        v: DVec3,
        /// Radius.
        r: f64,
        /// Start angle.
        t0: f64,
        /// Sweep (positive, at most 2 pi).
        sweep: f64,
    },
    /// A corner or apex.
    Point(DVec3),
}

/// A feature primitive with its dihedral angle in degrees (see [`FeatureCurve`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Feature {
    /// Geometry.
    pub geom: FeatureGeom,
    /// Dihedral angle in degrees.
    pub dihedral_deg: f64,
}

/// Dihedral angle in degrees between faces with unit normals `n1`, `n2`:
/// 180 minus the angle between the normals.
pub fn dihedral_deg(n1: DVec3, n2: DVec3) -> f64 {
    180.0 - n1.dot(n2).clamp(-1.0, 1.0).acos().to_degrees()
}

impl FeatureGeom {
    /// Exact distance from `p`.
    pub fn distance(&self, p: DVec3) -> f64 {
        match *self {
            FeatureGeom::Segment { a, b } => {
                let d = b - a;
                let l2 = d.length_squared();
                let t = if l2 == 0.0 {
                    0.0
                } else {
                    ((p - a).dot(d) / l2).clamp(0.0, 1.0)
                };
                (p - (a + d * t)).length()
            }
            FeatureGeom::Arc {
                center,
                u,
                v,
                r,
                t0,
                sweep,
            } => {
                let q = p - center;
                let (x, y) = (q.dot(u), q.dot(v));
                let ang = crate::util::wrap_tau(y.atan2(x) - t0);
                let t = if (x == 0.0 && y == 0.0) || ang <= sweep {
                    ang
                } else if std::f64::consts::TAU - ang <= ang - sweep {
                    0.0
                } else {
                    sweep
                };
                let pt = center + r * ((t0 + t).cos() * u + (t0 + t).sin() * v);
                (p - pt).length()
            }
            FeatureGeom::Point(c) => (p - c).length(),
        }
    }

    /// Polyline approximation within `tol` (exact for segments and points).
    pub fn polyline(&self, tol: f64) -> Vec<DVec3> {
        match *self {
            FeatureGeom::Segment { a, b } => vec![a, b],
            FeatureGeom::Arc {
                center,
                u,
                v,
                r,
                t0,
                sweep,
            } => {
                // Sagitta r (1 - cos(dt/2)) <= tol.
                let dt = 2.0 * (1.0 - (tol / r).min(1.0)).acos();
                let n = ((sweep / dt).ceil() as usize).clamp(4, 100_000);
                (0..=n)
                    .map(|i| {
                        let t = t0 + sweep * i as f64 / n as f64;
                        center + r * (t.cos() * u + t.sin() * v)
                    })
                    .collect()
            }
            FeatureGeom::Point(c) => vec![c],
        }
    }

    /// The primitive scaled by `s` about the origin.
    pub fn scaled(&self, s: f64) -> Self {
        match *self {
            FeatureGeom::Segment { a, b } => FeatureGeom::Segment { a: a * s, b: b * s },
            FeatureGeom::Arc {
                center,
                u,
                v,
                r,
                t0,
                sweep,
            } => FeatureGeom::Arc {
                center: center * s,
                u,
                v,
                r: r * s,
                t0,
                sweep,
            },
            FeatureGeom::Point(c) => FeatureGeom::Point(c * s),
        }
    }
}

impl Feature {
    /// The public polyline form; `tol` is the chordal tolerance.
    pub fn to_curve(&self, tol: f64) -> FeatureCurve {
        let mut points = self.geom.polyline(tol);
        let closed = matches!(self.geom, FeatureGeom::Arc { sweep, .. } if sweep >= std::f64::consts::TAU - 1e-12);
        if closed {
            // Closed: repeat the first point exactly.
            let first = points[0];
            *points.last_mut().expect("non-empty") = first;
        }
        FeatureCurve {
            points,
            dihedral_deg: self.dihedral_deg,
            is_corner: matches!(self.geom, FeatureGeom::Point(_)),
        }
    }
}

/// Exact distance from `p` to the nearest feature, `f64::INFINITY` without features.
pub fn feature_distance(features: &[Feature], p: DVec3) -> f64 {
    features
        .iter()
        .map(|f| f.geom.distance(p))
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_distance_and_polyline() {
        let f = FeatureGeom::Arc {
            center: DVec3::ZERO,
            u: DVec3::X,
            v: DVec3::Y,
            r: 1.0,
            t0: 0.0,
            sweep: std::f64::consts::TAU,
        };
        assert!((f.distance(DVec3::new(2.0, 0.0, 1.0)) - 2f64.sqrt()).abs() < 1e-15);
        assert!((f.distance(DVec3::ZERO) - 1.0).abs() < 1e-15);
        let pl = f.polyline(1e-4);
        for w in pl.windows(2) {
            let mid = 0.5 * (w[0] + w[1]);
            assert!(1.0 - mid.length() <= 1e-4 + 1e-15);
        }
        assert!((dihedral_deg(DVec3::X, DVec3::Y) - 90.0).abs() < 1e-12);
    }
}
