//! Spatial sorting: Biased Randomized Insertion Order (Amenta, Choi, Rote 2003) with each
//! round sorted along a 3D Hilbert curve.

use rayon::prelude::*;

use crate::point::P3;

/// Bits per axis of the Hilbert grid (3 × 21 = 63-bit keys).
const BITS: u32 = 21;

/// SplitMix64: a tiny, good-enough PRNG so the crate needs no `rand` dependency.
#[derive(Clone, Debug)]
pub(crate) struct SplitMix(pub(crate) u64);

impl SplitMix {
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `0..n` (n > 0), by multiply-shift.
    #[cfg(test)]
    pub(crate) fn below(&mut self, n: usize) -> usize {
        (((self.next_u64() >> 32) * n as u64) >> 32) as usize
    }
}

/// Hilbert key of a grid cell (Skilling's "AxestoTranspose" followed by bit interleaving).
fn hilbert_key(mut x: [u32; 3]) -> u64 {
    let m = 1u32 << (BITS - 1);
    let mut q = m;
    while q > 1 {
        let p = q - 1;
        for i in 0..3 {
            if x[i] & q != 0 {
                x[0] ^= p;
            } else {
                let t = (x[0] ^ x[i]) & p;
                x[0] ^= t;
                x[i] ^= t;
            }
        }
        q >>= 1;
    }
    for i in 1..3 {
        x[i] ^= x[i - 1];
    }
    let mut t = 0;
    q = m;
    while q > 1 {
        if x[2] & q != 0 {
            t ^= q - 1;
        }
        q >>= 1;
    }
    for v in &mut x {
        *v ^= t;
    }
    (spread3(x[0]) << 2) | (spread3(x[1]) << 1) | spread3(x[2])
}

/// Spreads the 21 low bits of `v` so that bit `k` lands on bit `3k`.
#[inline]
fn spread3(v: u32) -> u64 {
    let mut x = u64::from(v) & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// Hilbert keys of all points on a cubic grid fitted to their bounding box.
fn hilbert_keys(pts: &[P3]) -> Vec<u64> {
    let (lo, hi) = pts
        .par_iter()
        .fold(
            || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
            |(mut lo, mut hi), p| {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
                (lo, hi)
            },
        )
        .reduce(
            || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
            |(l1, h1), (l2, h2)| {
                (
                    [l1[0].min(l2[0]), l1[1].min(l2[1]), l1[2].min(l2[2])],
                    [h1[0].max(h2[0]), h1[1].max(h2[1]), h1[2].max(h2[2])],
                )
            },
        );
    let ext = (0..3).map(|k| hi[k] - lo[k]).fold(0.0f64, f64::max);
    let max_cell = f64::from((1u32 << BITS) - 1);
    let scale = if ext > 0.0 && ext.is_finite() {
        max_cell / ext
    } else {
        0.0
    };
    pts.par_iter()
        .map(|p| {
            let mut c = [0u32; 3];
            for k in 0..3 {
                let v = ((p[k] - lo[k]) * scale).clamp(0.0, max_cell);
                c[k] = v as u32;
            }
            hilbert_key(c)
        })
        .collect()
}

/// BRIO order of `pts`: every point is given a random round (the last round holds about
/// 7/8 of the points, the one before 7/64, ...; the first rounds together at least 64),
/// and the points are sorted by round, then along the Hilbert curve, in one parallel
/// sort. Deterministic for a given `seed`.
pub(crate) fn brio_order(pts: &[P3], seed: u64) -> Vec<u32> {
    let n = pts.len();
    let keys = hilbert_keys(pts);
    // Number of rounds so that the first one has about 64 points.
    let mut levels = 0u32;
    let mut m = n;
    while m > 64 && levels < 7 {
        m /= 8;
        levels += 1;
    }
    let mut tagged: Vec<(u64, u32)> = keys
        .par_iter()
        .enumerate()
        .map(|(i, &k)| {
            // Round from a hash of (seed, i): P(level >= l) = 8^-l.
            let mut h = SplitMix(seed ^ (i as u64).wrapping_mul(0xD1B5_4A32_D192_ED03));
            let r = h.next_u64();
            let level = (r.leading_zeros() / 3).min(levels);
            // Earliest round (highest level) first; 60-bit Hilbert key below.
            let round = u64::from(levels - level);
            ((round << 60) | (k >> 3), i as u32)
        })
        .collect();
    tagged.par_sort_unstable();
    tagged.into_iter().map(|(_, i)| i).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hilbert_is_a_bijection_on_small_grid() {
        // On the coarse level, consecutive keys of a full 2^BITS grid are adjacent cells;
        // here just check distinctness on a sample and a permutation of the order.
        let mut keys = std::collections::HashSet::new();
        for x in 0..8u32 {
            for y in 0..8u32 {
                for z in 0..8u32 {
                    assert!(keys.insert(hilbert_key([x << 18, y << 18, z << 18])));
                }
            }
        }
        let pts: Vec<P3> = (0..1000)
            .map(|i| [i as f64, (i * 7 % 13) as f64, 0.5])
            .collect();
        let mut o = brio_order(&pts, 1);
        o.sort_unstable();
        assert_eq!(o, (0..1000u32).collect::<Vec<_>>());
    }

    #[test]
    fn spread_matches_bit_loop() {
        let mut r = SplitMix(3);
        for _ in 0..1000 {
            let v = (r.next_u64() as u32) & 0x1f_ffff;
            let mut want = 0u64;
            for b in 0..21 {
                want |= u64::from((v >> b) & 1) << (3 * b);
            }
            assert_eq!(spread3(v), want);
        }
    }

    #[test]
    fn hilbert_adjacent_cells() {
        // Sort all cells of an 8^3 grid by key: consecutive cells are face neighbours.
        let mut cells: Vec<(u64, [u32; 3])> = Vec::new();
        for x in 0..8u32 {
            for y in 0..8u32 {
                for z in 0..8u32 {
                    let c = [x << 18, y << 18, z << 18];
                    cells.push((hilbert_key(c), [x, y, z]));
                }
            }
        }
        cells.sort_unstable();
        for w in cells.windows(2) {
            let d: u32 = (0..3).map(|k| w[0].1[k].abs_diff(w[1].1[k])).sum();
            assert_eq!(d, 1);
        }
    }
}
