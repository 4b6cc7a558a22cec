//! Exact power-of-two rescaling of the input into the predicates' safe exponent window.
//!
//! Multiplying every coordinate by the same power of two is exact (as long as nothing
//! overflows or drops below the subnormal grid) and multiplies every orientation and
//! in-sphere determinant by a positive power of two, so every sign, and hence the whole
//! triangulation, is unchanged. The construction, the validation and the Gabriel test
//! all evaluate their predicates on the rescaled coordinates; the public vertex
//! coordinates stay the input's.
//!
//! **Window.** Every coordinate is `m · 2^q` with `m` an odd integer, so every
//! coordinate difference is a multiple of `2^qmin` (`qmin`: the lowest set bit over all
//! non-zero coordinates) and below `2^(emax + 1)` (`emax`: the exponent bound of the
//! largest magnitude, `|x| < 2^emax`). The highest-degree polynomial evaluated exactly is
//! the Gabriel test's (degree 6; `insphere` is degree 5), so every term of every
//! expansion is a multiple of `2^(6 qmin)` and below about `2^(6 (emax + 1) + 10)`.
//! Expansion arithmetic (two-sum, two-product, Dekker's split) is exact while those stay
//! above the subnormal grid `2^-1074` and below the overflow threshold `2^1024` (the
//! split multiplies by `2^27 + 1`); with margin for the adaptive stages' error bounds
//! (a factor of about `2^-110`) the rescaled coordinates must satisfy
//! `qmin >= WINDOW_LOW` and `emax <= WINDOW_HIGH`. A cloud whose `emax - qmin` exceeds
//! [`MAX_SPAN_BITS`](crate::MAX_SPAN_BITS) cannot be placed in the window by any exact
//! scaling and is refused.

use glam::DVec3;

use crate::DelaunayError;
use crate::point::P3;

/// Lowest set bit allowed after rescaling: `6 · (-150) - 110 = -1010 > -1074`.
const WINDOW_LOW: i32 = -150;
/// Magnitude bound allowed after rescaling: `6 · (150 + 1) + 10 + 27 = 943 < 1024`.
const WINDOW_HIGH: i32 = 150;

/// Widest `emax - qmin` (bits) that fits the window.
pub(crate) const MAX_SPAN_BITS: i32 = WINDOW_HIGH - WINDOW_LOW;

/// Exponent of the lowest set bit of a non-zero finite `x` (`x = m · 2^q`, `m` odd).
fn lowest_bit(x: f64) -> i32 {
    crate::exact_int::decompose(x).1
}

/// Smallest `e` with `|x| < 2^e`, for a non-zero finite `x`.
fn magnitude_bound(x: f64) -> i32 {
    let bits = x.to_bits();
    let exp = ((bits >> 52) & 0x7ff) as i32;
    if exp == 0 {
        let frac = bits & ((1u64 << 52) - 1);
        -1074 + (64 - frac.leading_zeros() as i32)
    } else {
        exp - 1022
    }
}

/// `(qmin, emax)` over the non-zero coordinates, `None` when every coordinate is zero.
fn exponent_range(points: &[DVec3]) -> Option<(i32, i32)> {
    let mut qmin = i32::MAX;
    let mut emax = i32::MIN;
    for x in points.iter().flat_map(|p| p.to_array()) {
        if x != 0.0 {
            qmin = qmin.min(lowest_bit(x));
            emax = emax.max(magnitude_bound(x));
        }
    }
    (qmin != i32::MAX).then_some((qmin, emax))
}

/// The power-of-two exponent `s` to multiply the (finite) coordinates by: 0 when they
/// already lie in the window (the common case: no copy), otherwise the one centring
/// `[qmin, emax]` in it; an error when the span does not fit.
pub(crate) fn scale_exponent(points: &[DVec3]) -> Result<i32, DelaunayError> {
    let Some((qmin, emax)) = exponent_range(points) else {
        return Ok(0);
    };
    if emax - qmin > MAX_SPAN_BITS {
        return Err(DelaunayError::SpanTooWide {
            bits: emax - qmin,
            lowest: qmin,
            highest: emax,
        });
    }
    if qmin >= WINDOW_LOW && emax <= WINDOW_HIGH {
        return Ok(0);
    }
    // Centre: s = -(qmin + emax) / 2, rounded toward the low end; both ends then fit.
    Ok(-(qmin + emax).div_euclid(2))
}

/// `2^e` as a double, for `-1022 <= e <= 1023`.
fn pow2(e: i32) -> f64 {
    f64::from_bits(((1023 + e) as u64) << 52)
}

/// The coordinates multiplied by `2^s` (exact: two steps of at most `2^±600` each, every
/// intermediate stays inside the double range and on the subnormal grid because the
/// final values lie in the window).
pub(crate) fn scaled(points: &[DVec3], s: i32) -> Vec<P3> {
    let h = s / 2;
    let (f1, f2) = (pow2(h), pow2(s - h));
    points
        .iter()
        .map(|p| p.to_array().map(|x| (x * f1) * f2))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bit_exponents() {
        assert_eq!(lowest_bit(1.0), 0);
        assert_eq!(lowest_bit(0.75), -2);
        assert_eq!(lowest_bit(f64::from_bits(1)), -1074);
        assert_eq!(magnitude_bound(1.0), 1);
        assert_eq!(magnitude_bound(0.75), 0);
        assert_eq!(magnitude_bound(f64::MAX), 1024);
        assert_eq!(magnitude_bound(f64::from_bits(1)), -1073);
    }

    #[test]
    fn unit_clouds_are_not_copied() {
        let pts = [DVec3::new(0.1, -0.7, 0.3), DVec3::new(1e-17, 2.0, 0.0)];
        assert_eq!(scale_exponent(&pts), Ok(0));
    }

    #[test]
    fn extreme_clouds_land_in_the_window_exactly() {
        for k in [-1074, -1000, -600, -300, 250, 600, 900, 971] {
            let f = 2f64.powi(k.max(-1022)) * if k < -1022 { 2f64.powi(k + 1022) } else { 1.0 };
            let pts = [
                DVec3::new(0.1, -0.7, 0.3) * f,
                DVec3::new(1.0, 0.5, -0.25) * f,
            ];
            let s = scale_exponent(&pts).unwrap();
            let q = scaled(&pts, s);
            let back: Vec<DVec3> = q.iter().map(|c| DVec3::from_array(*c)).collect();
            let (qmin, emax) = exponent_range(&back).unwrap();
            assert!(
                qmin >= WINDOW_LOW && emax <= WINDOW_HIGH,
                "k = {k}: {qmin} {emax}"
            );
            // Exact: scaling back recovers every bit.
            assert_eq!(
                scaled(&back, -s),
                pts.map(|p| p.to_array()).to_vec(),
                "k = {k}"
            );
        }
    }

    #[test]
    fn too_wide_spans_are_refused() {
        let pts = [DVec3::new(1.0, 1e-200, 0.0), DVec3::splat(1e200)];
        assert!(matches!(
            scale_exponent(&pts),
            Err(DelaunayError::SpanTooWide { .. })
        ));
    }
}
