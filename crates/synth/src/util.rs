//! Small numeric helpers: seeded RNGs, random directions, quadrature, orthonormal frames.

use glam::{DVec2, DVec3};
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The one RNG of the crate.
pub type SynthRng = ChaCha8Rng;

/// SplitMix64 finaliser: a bijective 64-bit mix.
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A sub-seed derived from `seed`, a stream label and an index: independent streams for
/// the sampler, each perturbation step, each scan, each parallel chunk, ...
pub fn derive_seed(seed: u64, label: &str, index: u64) -> u64 {
    let mut h = mix64(seed);
    for b in label.bytes() {
        h = mix64(h ^ u64::from(b));
    }
    mix64(h ^ mix64(index.wrapping_add(0x5151)))
}

/// A ChaCha8 RNG for a derived stream.
pub fn rng_for(seed: u64, label: &str, index: u64) -> SynthRng {
    SynthRng::seed_from_u64(derive_seed(seed, label, index))
}

/// Uniform in `[0, 1)`.
pub fn unit(rng: &mut dyn Rng) -> f64 {
    rng.random::<f64>()
}

/// Uniform in `[a, b)`.
pub fn uniform(rng: &mut dyn Rng, a: f64, b: f64) -> f64 {
    a + (b - a) * rng.random::<f64>()
}

/// Uniform index in `0..n` (`n > 0`).
pub fn index(rng: &mut dyn Rng, n: usize) -> usize {
    rng.random_range(0..n)
}

/// A standard normal variate (Box–Muller on the polar form, deterministic given the RNG).
pub fn std_normal(rng: &mut dyn Rng) -> f64 {
    use rand_distr::Distribution;
    rand_distr::StandardNormal.sample(rng)
}

/// Uniform direction on the unit sphere.
pub fn unit_vector(rng: &mut dyn Rng) -> DVec3 {
    let z = uniform(rng, -1.0, 1.0);
    let phi = uniform(rng, 0.0, std::f64::consts::TAU);
    let s = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// Uniform in the unit ball.
pub fn in_unit_ball(rng: &mut dyn Rng) -> DVec3 {
    unit_vector(rng) * unit(rng).cbrt()
}

/// Picks an index with probability proportional to `weights` (non-negative, not all 0),
/// given the prefix sums `cumulative` (last element = total).
pub fn pick_weighted(rng: &mut dyn Rng, cumulative: &[f64]) -> usize {
    let total = *cumulative.last().expect("non-empty weights");
    let x = unit(rng) * total;
    cumulative
        .partition_point(|&c| c <= x)
        .min(cumulative.len() - 1)
}

/// Prefix sums of `w`.
pub fn cumulative(w: &[f64]) -> Vec<f64> {
    let mut acc = 0.0;
    w.iter()
        .map(|x| {
            acc += x;
            acc
        })
        .collect()
}

/// Two unit vectors completing `n` (unit) to a right-handed orthonormal frame `(u, v, n)`.
pub fn frame(n: DVec3) -> (DVec3, DVec3) {
    let a = if n.x.abs() < 0.7 { DVec3::X } else { DVec3::Y };
    let u = a.cross(n).normalize();
    let v = n.cross(u);
    (u, v)
}

/// Gauss–Legendre nodes and weights on `[-1, 1]`.
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let k = k as f64;
                let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 0 { 1.0 } else { p1 };
            let pnm1 = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (x * pn - pnm1) / (x * x - 1.0);
            let dx = pn / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

/// Composite Gauss–Legendre integral of `f` over `[a, b]` with `panels` panels of order 16.
pub fn integrate(f: impl Fn(f64) -> f64, a: f64, b: f64, panels: usize) -> f64 {
    let gl = gauss_legendre(16);
    let h = (b - a) / panels as f64;
    let mut s = 0.0;
    for k in 0..panels {
        let c = a + (k as f64 + 0.5) * h;
        for &(x, w) in &gl {
            s += w * f(c + 0.5 * h * x);
        }
    }
    s * 0.5 * h
}

/// 2D rotation of `v` by +90 degrees.
pub fn perp(v: DVec2) -> DVec2 {
    DVec2::new(-v.y, v.x)
}

/// Wraps an angle into `[0, 2 pi)`.
pub fn wrap_tau(a: f64) -> f64 {
    let t = a.rem_euclid(std::f64::consts::TAU);
    if t >= std::f64::consts::TAU { 0.0 } else { t }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_and_smooth_functions() {
        let s: f64 = gauss_legendre(8).iter().map(|(x, w)| w * x.powi(14)).sum();
        assert!((s - 2.0 / 15.0).abs() < 1e-14, "{s}");
        let i = integrate(f64::sin, 0.0, std::f64::consts::PI, 4);
        assert!((i - 2.0).abs() < 1e-14, "{i}");
    }

    #[test]
    fn derived_seeds_differ() {
        assert_ne!(derive_seed(1, "a", 0), derive_seed(1, "a", 1));
        assert_ne!(derive_seed(1, "a", 0), derive_seed(1, "b", 0));
        assert_ne!(derive_seed(1, "a", 0), derive_seed(2, "a", 0));
    }
}
