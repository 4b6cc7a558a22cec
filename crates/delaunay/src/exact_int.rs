//! Fast exact predicates for coordinates that are small integers after a common
//! power-of-two scaling (grids, integer points on spheres, CAD data with a common
//! spacing...): the coordinates are converted to `i64`, and the determinants evaluated
//! with `i128` and a fixed 384-bit two's-complement integer. This is much faster than the
//! general expansion arithmetic on exactly degenerate input (determinant exactly 0),
//! which is precisely the case of grids and exactly co-spherical points.

use crate::point::P3;

/// Mantissa and exponent of a non-zero finite double: `x = m · 2^e`, `m` odd.
#[inline]
pub(crate) fn decompose(x: f64) -> (i64, i32) {
    let bits = x.to_bits();
    let exp = ((bits >> 52) & 0x7ff) as i32;
    let frac = bits & ((1u64 << 52) - 1);
    let (m, e) = if exp == 0 {
        (frac, -1074)
    } else {
        (frac | (1u64 << 52), exp - 1075)
    };
    let tz = m.trailing_zeros();
    let m = (m >> tz) as i64;
    (if x < 0.0 { -m } else { m }, e + tz as i32)
}

/// The coordinates as integers `c · 2^-E` for a common `E`, all below `2^61` in
/// magnitude, or `None` if they do not fit.
#[inline]
fn to_ints<const N: usize>(pts: [&P3; N]) -> Option<[[i64; 3]; N]> {
    let mut parts = [[(0i64, 0i32); 3]; N];
    let mut emin = i32::MAX;
    let mut top = i32::MIN;
    for (k, p) in pts.iter().enumerate() {
        for a in 0..3 {
            if p[a] != 0.0 {
                let (m, e) = decompose(p[a]);
                parts[k][a] = (m, e);
                emin = emin.min(e);
                top = top.max(e + 64 - m.unsigned_abs().leading_zeros() as i32);
            }
        }
    }
    if emin == i32::MAX {
        return Some([[0; 3]; N]);
    }
    if top - emin > 61 {
        return None;
    }
    let mut out = [[0i64; 3]; N];
    for k in 0..N {
        for a in 0..3 {
            let (m, e) = parts[k][a];
            if m != 0 {
                out[k][a] = m << (e - emin);
            }
        }
    }
    Some(out)
}

/// 384-bit two's-complement integer, little-endian limbs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Big([u64; 6]);

impl Big {
    fn from_i128(x: i128) -> Big {
        let lo = x as u128;
        let ext = if x < 0 { u64::MAX } else { 0 };
        Big([lo as u64, (lo >> 64) as u64, ext, ext, ext, ext])
    }

    fn is_neg(&self) -> bool {
        (self.0[5] >> 63) == 1
    }

    fn neg(&self) -> Big {
        let mut out = [0u64; 6];
        let mut carry = 1u64;
        for i in 0..6 {
            let (s, c) = (!self.0[i]).overflowing_add(carry);
            out[i] = s;
            carry = u64::from(c);
        }
        Big(out)
    }

    fn add(&self, o: &Big) -> Big {
        let mut out = [0u64; 6];
        let mut carry = false;
        for i in 0..6 {
            let (s1, c1) = self.0[i].overflowing_add(o.0[i]);
            let (s2, c2) = s1.overflowing_add(u64::from(carry));
            out[i] = s2;
            carry = c1 || c2;
        }
        Big(out)
    }

    fn sub(&self, o: &Big) -> Big {
        self.add(&o.neg())
    }

    /// `self · b`; the caller guarantees that the product fits.
    fn mul(&self, b: i128) -> Big {
        let neg = self.is_neg() != (b < 0);
        let a = if self.is_neg() { self.neg() } else { *self };
        let bu = b.unsigned_abs();
        let bl = [bu as u64, (bu >> 64) as u64];
        let mut out = [0u64; 6];
        for (j, &bj) in bl.iter().enumerate() {
            if bj == 0 {
                continue;
            }
            let mut carry = 0u128;
            for i in 0..6 - j {
                let cur = u128::from(out[i + j]) + u128::from(a.0[i]) * u128::from(bj) + carry;
                out[i + j] = cur as u64;
                carry = cur >> 64;
            }
        }
        let r = Big(out);
        if neg { r.neg() } else { r }
    }

    fn sign(&self) -> i32 {
        if self.is_neg() {
            -1
        } else if self.0.iter().all(|&x| x == 0) {
            0
        } else {
            1
        }
    }
}

#[inline]
fn mul64(a: i64, b: i64) -> i128 {
    i128::from(a) * i128::from(b)
}

/// Exact sign of `(b − a) · ((c − a) × (d − a))`, or `None` if the coordinates are not
/// small scaled integers.
pub(crate) fn orient3d(a: &P3, b: &P3, c: &P3, d: &P3) -> Option<i32> {
    let [a, b, c, d] = to_ints([a, b, c, d])?;
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let w = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
    let m0 = mul64(v[1], w[2]) - mul64(v[2], w[1]);
    let m1 = mul64(v[2], w[0]) - mul64(v[0], w[2]);
    let m2 = mul64(v[0], w[1]) - mul64(v[1], w[0]);
    let det = Big::from_i128(m0)
        .mul(i128::from(u[0]))
        .add(&Big::from_i128(m1).mul(i128::from(u[1])))
        .add(&Big::from_i128(m2).mul(i128::from(u[2])));
    Some(det.sign())
}

/// Exact insphere sign (positive: `e` inside the sphere of the positively oriented
/// `a, b, c, d`), or `None` if the coordinates are not small scaled integers.
pub(crate) fn insphere(a: &P3, b: &P3, c: &P3, d: &P3, e: &P3) -> Option<i32> {
    let [a, b, c, d, e] = to_ints([a, b, c, d, e])?;
    let q = |p: [i64; 3]| [p[0] - e[0], p[1] - e[1], p[2] - e[2]];
    let (a, b, c, d) = (q(a), q(b), q(c), q(d));
    // Same expression as Shewchuk's insphere (whose sign is the opposite of ours).
    let ab = mul64(a[0], b[1]) - mul64(b[0], a[1]);
    let bc = mul64(b[0], c[1]) - mul64(c[0], b[1]);
    let cd = mul64(c[0], d[1]) - mul64(d[0], c[1]);
    let da = mul64(d[0], a[1]) - mul64(a[0], d[1]);
    let ac = mul64(a[0], c[1]) - mul64(c[0], a[1]);
    let bd = mul64(b[0], d[1]) - mul64(d[0], b[1]);
    let m3 = |z0: i64, m0: i128, z1: i64, m1: i128, z2: i64, m2: i128| {
        Big::from_i128(m0)
            .mul(i128::from(z0))
            .add(&Big::from_i128(m1).mul(i128::from(z1)))
            .add(&Big::from_i128(m2).mul(i128::from(z2)))
    };
    let abc = m3(a[2], bc, -b[2], ac, c[2], ab);
    let bcd = m3(b[2], cd, -c[2], bd, d[2], bc);
    let cda = m3(c[2], da, d[2], ac, a[2], cd);
    let dab = m3(d[2], ab, a[2], bd, b[2], da);
    let lift = |p: [i64; 3]| mul64(p[0], p[0]) + mul64(p[1], p[1]) + mul64(p[2], p[2]);
    let det = abc
        .mul(lift(d))
        .sub(&dab.mul(lift(c)))
        .add(&cda.mul(lift(b)).sub(&bcd.mul(lift(a))));
    Some(-det.sign())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn big_arithmetic() {
        let x = Big::from_i128(-(1i128 << 100));
        let y = x.mul(1i128 << 120).mul(-(1i128 << 100));
        // 2^320 > 0
        assert_eq!(y.sign(), 1);
        assert_eq!(y.sub(&y).sign(), 0);
        assert_eq!(Big::from_i128(-5).add(&Big::from_i128(5)).sign(), 0);
        assert_eq!(Big::from_i128(3).mul(-7), Big::from_i128(-21));
    }
}
