//! The local feature line of sharp MLS (seed 002 §6.4, thesis §4.3.3): a cubic Bézier
//! through unordered feature points, its evaluation and the closest point on it.
//!
//! The construction assumes the feature is almost straight inside one neighbourhood:
//! the two farthest-apart features are the end points `b0`, `b3` (interpolated), two
//! others become the inner control points `b1`, `b2`. On a straight, exactly sampled
//! edge all four lie on the edge and so does the whole curve (Table 3's zero error for
//! the cube); on a curved edge the curve stays inside its control polygon and
//! undershoots.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Uniform samples of the coarse closest-point search (seed 002 §6.4).
const CLOSEST_SAMPLES: usize = 65;
/// Newton refinements of the closest-point parameter (seed 002 §6.4).
const NEWTON_STEPS: usize = 8;

/// How the inner control points are chosen among the remaining features.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BezierInner {
    /// ASSUMPTION W-34 (default): `b1` = the feature of `b0`'s half whose chord
    /// parameter is closest to 1/3 of the chord, `b2` = the one of `b3`'s half closest to
    /// 2/3 (deterministic).
    #[default]
    ChordThirds,
    /// The thesis's literal "one arbitrary point" of each half, drawn with a seeded hash
    /// (deterministic per seed and query).
    Random,
}

/// A cubic Bézier curve `B(t) = sum_i C(3, i) (1 - t)^(3 - i) t^i b_i`, `t in [0, 1]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CubicBezier {
    /// Control points `b0..b3`.
    pub ctrl: [DVec3; 4],
}

impl CubicBezier {
    /// `B(t)`.
    pub fn eval(&self, t: f64) -> DVec3 {
        let [b0, b1, b2, b3] = self.ctrl;
        let s = 1.0 - t;
        s * s * s * b0 + 3.0 * s * s * t * b1 + 3.0 * s * t * t * b2 + t * t * t * b3
    }

    /// `B'(t)`.
    pub fn deriv(&self, t: f64) -> DVec3 {
        let [b0, b1, b2, b3] = self.ctrl;
        let s = 1.0 - t;
        3.0 * (s * s * (b1 - b0) + 2.0 * s * t * (b2 - b1) + t * t * (b3 - b2))
    }

    /// `B''(t)`.
    pub fn deriv2(&self, t: f64) -> DVec3 {
        let [b0, b1, b2, b3] = self.ctrl;
        6.0 * ((1.0 - t) * (b2 - 2.0 * b1 + b0) + t * (b3 - 2.0 * b2 + b1))
    }

    /// Parameter in `[0, 1]` of the point of the curve closest to `x`: the best of 65
    /// uniform samples refined by at most 8 Newton steps on `(B(t) - x) . B'(t) = 0`,
    /// clamped to the interval (the better of the sample and the refinement is kept).
    pub fn closest_param(&self, x: DVec3) -> f64 {
        let mut best_t = 0.0;
        let mut best_d = f64::INFINITY;
        for j in 0..CLOSEST_SAMPLES {
            let t = j as f64 / (CLOSEST_SAMPLES - 1) as f64;
            let d = (self.eval(t) - x).length_squared();
            if d < best_d {
                best_d = d;
                best_t = t;
            }
        }
        let mut t = best_t;
        for _ in 0..NEWTON_STEPS {
            let e = self.eval(t) - x;
            let d1 = self.deriv(t);
            let g = e.dot(d1);
            let dg = d1.length_squared() + e.dot(self.deriv2(t));
            if dg.is_nan() || dg <= 0.0 {
                break;
            }
            let next = (t - g / dg).clamp(0.0, 1.0);
            let done = (next - t).abs() < 1e-12;
            t = next;
            if done {
                break;
            }
        }
        if (self.eval(t) - x).length_squared() <= best_d {
            t
        } else {
            best_t
        }
    }

    /// The point of the line closest to `x`: on the curve, or with `extend` on the
    /// tangent rays beyond its end points when the closest parameter is an end.
    pub fn closest_point(&self, x: DVec3, extend: bool) -> DVec3 {
        let t = self.closest_param(x);
        let p = self.eval(t);
        if extend && (t == 0.0 || t == 1.0) {
            let d = self.deriv(t);
            let l2 = d.length_squared();
            if l2 > 0.0 {
                let s = (x - p).dot(d) / l2;
                if (t == 0.0 && s < 0.0) || (t == 1.0 && s > 0.0) {
                    return p + s * d;
                }
            }
        }
        p
    }
}

/// splitmix64: the hash behind [`BezierInner::Random`].
fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The cubic Bézier through the unordered features `e` (point index, position), seed
/// 002 §6.4; `None` with fewer than 4 features or all of them coincident. `seed` only
/// matters for [`BezierInner::Random`]. Ties are broken by point index, so the curve
/// does not depend on the order of `e`.
pub fn bezier_from_features(
    e: &[(u32, DVec3)],
    inner: BezierInner,
    seed: u64,
) -> Option<CubicBezier> {
    if e.len() < 4 {
        return None;
    }
    // 1. The farthest pair; ties to the lexicographically smaller index pair.
    let key = |a: usize, b: usize| {
        let (x, y) = (e[a].0.min(e[b].0), e[a].0.max(e[b].0));
        (x, y)
    };
    let (mut ia, mut ib, mut dmax) = (0, 1, -1.0);
    for a in 0..e.len() {
        for b in a + 1..e.len() {
            let d = (e[a].1 - e[b].1).length_squared();
            if d > dmax || (d == dmax && key(a, b) < key(ia, ib)) {
                (ia, ib, dmax) = (a, b, d);
            }
        }
    }
    if dmax.is_nan() || dmax <= 0.0 {
        return None;
    }
    // ASSUMPTION W-35: b0 = the end point with the smaller point index.
    if e[ib].0 < e[ia].0 {
        std::mem::swap(&mut ia, &mut ib);
    }
    let (b0, b3) = (e[ia].1, e[ib].1);
    let rest = || {
        e.iter()
            .enumerate()
            .filter(move |&(j, _)| j != ia && j != ib)
            .map(|(_, x)| *x)
    };
    if e.len() == 4 {
        // Two inner points: ordered by distance to b0 (ties by index).
        let mut it = rest();
        let (mut x, mut y) = (it.next()?, it.next()?);
        let order = (x.1 - b0)
            .length_squared()
            .total_cmp(&(y.1 - b0).length_squared())
            .then(x.0.cmp(&y.0));
        if order == std::cmp::Ordering::Greater {
            std::mem::swap(&mut x, &mut y);
        }
        return Some(CubicBezier {
            ctrl: [b0, x.1, y.1, b3],
        });
    }
    let len = dmax.sqrt();
    let u = (b3 - b0) / len;
    let chord = |p: DVec3| (p - b0).dot(u);
    // The feature of `it` whose chord parameter is closest to `target` (ties by index),
    // skipping index `skip`.
    let closest_to = |target: f64, half: Option<bool>, skip: Option<u32>| {
        rest()
            .filter(|x| Some(x.0) != skip)
            .filter(|x| half.is_none_or(|first| (chord(x.1) < 0.5 * len) == first))
            .min_by(|x, y| {
                (chord(x.1) - target)
                    .abs()
                    .total_cmp(&(chord(y.1) - target).abs())
                    .then(x.0.cmp(&y.0))
            })
    };
    let n0 = rest().filter(|x| chord(x.1) < 0.5 * len).count();
    let n1 = e.len() - 2 - n0;
    if n0 == 0 || n1 == 0 {
        // One half empty: the two distinct points closest to the chord thirds.
        let p1 = closest_to(len / 3.0, None, None)?;
        let p2 = closest_to(2.0 * len / 3.0, None, Some(p1.0))?;
        return Some(CubicBezier {
            ctrl: [b0, p1.1, p2.1, b3],
        });
    }
    let (p1, p2) = match inner {
        BezierInner::ChordThirds => (
            closest_to(len / 3.0, Some(true), None)?,
            closest_to(2.0 * len / 3.0, Some(false), None)?,
        ),
        BezierInner::Random => {
            // The j-th member of each half by point index, j drawn from a hash of the
            // seed and the end points (an ablation of the thesis's literal reading).
            let r0 = splitmix(seed ^ (u64::from(e[ia].0) << 32) ^ u64::from(e[ib].0));
            let r1 = splitmix(r0);
            let nth = |first: bool, j: u64| {
                let m = if first { n0 } else { n1 };
                let rank = (j % m as u64) as usize;
                let members = || rest().filter(move |x| (chord(x.1) < 0.5 * len) == first);
                members().find(|c| members().filter(|y| y.0 < c.0).count() == rank)
            };
            (nth(true, r0)?, nth(false, r1)?)
        }
    };
    Some(CubicBezier {
        ctrl: [b0, p1.1, p2.1, b3],
    })
}
