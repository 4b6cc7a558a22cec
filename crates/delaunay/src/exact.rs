//! Minimal exact floating-point expansion arithmetic (Shewchuk 1997).
//!
//! An [`Expansion`] is a sum of non-overlapping `f64` components sorted by increasing
//! magnitude; sums, differences and products of expansions are exact (barring overflow
//! and underflow). Only used on the rare slow paths (exact Gabriel test), so it favours
//! simplicity over speed.

/// `2^27 + 1`, the splitter of Dekker's product.
const SPLITTER: f64 = 134_217_729.0;

#[inline]
pub(crate) fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let x = a + b;
    let bv = x - a;
    let av = x - bv;
    (x, (a - av) + (b - bv))
}

#[inline]
fn fast_two_sum(a: f64, b: f64) -> (f64, f64) {
    let x = a + b;
    (x, b - (x - a))
}

#[inline]
fn split(a: f64) -> (f64, f64) {
    let c = SPLITTER * a;
    let hi = c - (c - a);
    (hi, a - hi)
}

#[inline]
pub(crate) fn two_product(a: f64, b: f64) -> (f64, f64) {
    let x = a * b;
    let (ahi, alo) = split(a);
    let (bhi, blo) = split(b);
    let err = x - ahi * bhi - alo * bhi - ahi * blo;
    (x, alo * blo - err)
}

/// An exact sum of non-overlapping doubles, by increasing magnitude.
#[derive(Clone, Debug, Default)]
pub(crate) struct Expansion(Vec<f64>);

impl Expansion {
    /// `a - b`, exactly.
    pub(crate) fn diff(a: f64, b: f64) -> Self {
        let x = a - b;
        let bv = a - x;
        let av = x + bv;
        let err = (a - av) + (bv - b);
        let mut v = Vec::with_capacity(2);
        if err != 0.0 {
            v.push(err);
        }
        if x != 0.0 {
            v.push(x);
        }
        Expansion(v)
    }

    /// Sign of the exact value: -1, 0 or 1.
    pub(crate) fn sign(&self) -> i32 {
        match self.0.last() {
            Some(&x) if x > 0.0 => 1,
            Some(&x) if x < 0.0 => -1,
            _ => 0,
        }
    }

    /// `self + b` for one double `b` (Shewchuk's GROW-EXPANSION with zero elimination).
    fn grow(&self, b: f64) -> Self {
        let mut out = Vec::with_capacity(self.0.len() + 1);
        let mut q = b;
        for &e in &self.0 {
            let (s, h) = two_sum(q, e);
            q = s;
            if h != 0.0 {
                out.push(h);
            }
        }
        if q != 0.0 {
            out.push(q);
        }
        Expansion(out)
    }

    /// `self * b` for one double `b` (SCALE-EXPANSION with zero elimination).
    fn scale(&self, b: f64) -> Self {
        let mut out = Vec::with_capacity(2 * self.0.len());
        let Some((&first, rest)) = self.0.split_first() else {
            return Expansion(out);
        };
        let (mut q, h) = two_product(first, b);
        if h != 0.0 {
            out.push(h);
        }
        for &e in rest {
            let (p1, p0) = two_product(e, b);
            let (sum, h) = two_sum(q, p0);
            if h != 0.0 {
                out.push(h);
            }
            let (nq, h) = fast_two_sum(p1, sum);
            q = nq;
            if h != 0.0 {
                out.push(h);
            }
        }
        if q != 0.0 {
            out.push(q);
        }
        Expansion(out)
    }

    pub(crate) fn add(&self, other: &Self) -> Self {
        let (big, small) = if self.0.len() >= other.0.len() {
            (self, other)
        } else {
            (other, self)
        };
        let mut acc = big.clone();
        for &x in &small.0 {
            acc = acc.grow(x);
        }
        acc
    }

    pub(crate) fn neg(&self) -> Self {
        Expansion(self.0.iter().map(|x| -x).collect())
    }

    pub(crate) fn sub(&self, other: &Self) -> Self {
        self.add(&other.neg())
    }

    pub(crate) fn mul(&self, other: &Self) -> Self {
        let (big, small) = if self.0.len() >= other.0.len() {
            (self, other)
        } else {
            (other, self)
        };
        let mut acc = Expansion::default();
        for &x in &small.0 {
            acc = acc.add(&big.scale(x));
        }
        acc
    }

    /// Approximate value (sum of the components).
    #[cfg(test)]
    pub(crate) fn approx(&self) -> f64 {
        self.0.iter().sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_cancellation() {
        let a = Expansion::diff(1.0, 1e-30);
        let b = Expansion::diff(1.0, 0.0);
        let d = a.sub(&b); // -1e-30 exactly representable as two parts
        assert_eq!(d.sign(), -1);
        assert!((d.approx() + 1e-30).abs() < 1e-45);
        // (1 + 2^-60)^2 - 1 - 2^-59 = 2^-120
        let x = Expansion::diff(1.0, -(2f64.powi(-60)));
        let sq = x.mul(&x);
        let r = sq
            .sub(&Expansion::diff(1.0, 0.0))
            .sub(&Expansion::diff(2f64.powi(-59), 0.0));
        assert_eq!(r.approx(), 2f64.powi(-120));
    }
}
