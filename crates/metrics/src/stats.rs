//! Deterministic summary statistics over flat `f64` arrays.
//!
//! Sums are sequential (a parallel float reduction would depend on the thread split), so
//! every number is bit-identical whatever the thread count. Quantiles use the
//! nearest-rank definition (no interpolation): `q`-quantile of `n` values is the value of
//! rank `ceil(q n)` (1-based) in ascending order, found with `select_nth_unstable`.

use serde::Serialize;

/// Mean, RMS, nearest-rank p95, max (and min, std, median) of a set of values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Summary {
    /// Number of values.
    pub count: usize,
    /// Arithmetic mean.
    pub mean: f64,
    /// Root mean square `sqrt(mean(x^2))`.
    pub rms: f64,
    /// Population standard deviation `sqrt(mean((x - mean)^2))`.
    pub std: f64,
    /// Nearest-rank median (rank `ceil(n / 2)`).
    pub median: f64,
    /// Nearest-rank 95th percentile (rank `ceil(0.95 n)`).
    pub p95: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

impl Summary {
    /// All-NaN summary of an empty set (serialised as `null`).
    pub const EMPTY: Summary = Summary {
        count: 0,
        mean: f64::NAN,
        rms: f64::NAN,
        std: f64::NAN,
        median: f64::NAN,
        p95: f64::NAN,
        min: f64::NAN,
        max: f64::NAN,
    };

    /// Summary of `values` (NaNs must have been removed by the caller; they sort last).
    pub fn of(values: &[f64]) -> Summary {
        let n = values.len();
        if n == 0 {
            return Self::EMPTY;
        }
        let mut sum = 0.0;
        let mut sum2 = 0.0;
        let mut min = f64::INFINITY;
        let mut max = f64::NEG_INFINITY;
        for &v in values {
            sum += v;
            sum2 += v * v;
            min = min.min(v);
            max = max.max(v);
        }
        let mean = sum / n as f64;
        let mut dev2 = 0.0;
        for &v in values {
            dev2 += (v - mean) * (v - mean);
        }
        let mut scratch = values.to_vec();
        let median = quantile_in_place(&mut scratch, 0.5);
        let p95 = quantile_in_place(&mut scratch, 0.95);
        Summary {
            count: n,
            mean,
            rms: (sum2 / n as f64).sqrt(),
            std: (dev2 / n as f64).sqrt(),
            median,
            p95,
            min,
            max,
        }
    }

    /// This summary with every length multiplied by `s` (count unchanged).
    pub fn scaled(&self, s: f64) -> Summary {
        Summary {
            count: self.count,
            mean: self.mean * s,
            rms: self.rms * s,
            std: self.std * s,
            median: self.median * s,
            p95: self.p95 * s,
            min: self.min * s,
            max: self.max * s,
        }
    }
}

/// Nearest-rank index of the `q`-quantile among `n` values (0-based): `ceil(q n) - 1`,
/// clamped to `0..n`.
pub fn quantile_rank(n: usize, q: f64) -> usize {
    let r = (q * n as f64).ceil() as usize;
    r.clamp(1, n.max(1)) - 1
}

/// Nearest-rank `q`-quantile of `values`, reordering them (`select_nth_unstable` with a
/// total order, so the result is deterministic). NaN for an empty slice.
pub fn quantile_in_place(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let k = quantile_rank(values.len(), q);
    *values.select_nth_unstable_by(k, f64::total_cmp).1
}

/// Share (in `[0, 1]`) of `values` that satisfy `pred`; NaN for an empty slice.
pub fn share(values: &[f64], pred: impl Fn(f64) -> bool) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.iter().filter(|&&v| pred(v)).count() as f64 / values.len() as f64
}

/// Harmonic mean `2 p r / (p + r)`, 0 when both are 0.
pub fn harmonic(p: f64, r: f64) -> f64 {
    if p + r > 0.0 {
        2.0 * p * r / (p + r)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn p95_matches_sorted_nearest_rank() {
        let mut rng = 12345u64;
        for n in [1usize, 2, 19, 20, 21, 100, 1001] {
            let v: Vec<f64> = (0..n)
                .map(|_| {
                    rng = rng
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    (rng >> 11) as f64 / (1u64 << 53) as f64
                })
                .collect();
            let mut sorted = v.clone();
            sorted.sort_by(f64::total_cmp);
            let s = Summary::of(&v);
            let rank = (0.95 * n as f64).ceil() as usize;
            assert_eq!(s.p95, sorted[rank - 1], "n = {n}");
            assert_eq!(s.median, sorted[n.div_ceil(2) - 1], "n = {n}");
            assert_eq!(s.max, sorted[n - 1]);
            assert_eq!(s.min, sorted[0]);
        }
    }

    #[test]
    fn summary_of_constants() {
        let s = Summary::of(&[2.0; 10]);
        assert_eq!(
            (s.mean, s.rms, s.std, s.p95, s.max),
            (2.0, 2.0, 0.0, 2.0, 2.0)
        );
        let s = Summary::of(&[3.0, 4.0]);
        assert!((s.rms - (12.5f64).sqrt()).abs() < 1e-15);
        assert!(Summary::of(&[]).mean.is_nan());
    }

    #[test]
    fn harmonic_mean() {
        assert_eq!(harmonic(0.0, 0.0), 0.0);
        assert!((harmonic(1.0, 0.5) - 2.0 / 3.0).abs() < 1e-15);
    }
}
