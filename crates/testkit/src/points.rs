//! Deterministic point sets for the Delaunay tests, benchmarks and probes (uniform,
//! torus surface, sphere, grids, cube surface). Each generator is seeded and
//! self-contained.

use glam::DVec3;

/// SplitMix64, the generator of the Delaunay crate's insertion order: the point sets
/// below are the ones its tests were written against.
#[derive(Clone, Debug)]
struct SplitMix(u64);

impl SplitMix {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

fn unit(rng: &mut SplitMix) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// `n` points uniform in the cube `[0, 1]³`.
pub fn uniform_cube(n: usize, seed: u64) -> Vec<DVec3> {
    let mut r = SplitMix(seed);
    (0..n)
        .map(|_| DVec3::new(unit(&mut r), unit(&mut r), unit(&mut r)))
        .collect()
}

/// `n` points on the surface of a torus (major radius 1, minor radius `0.35`), uniform in
/// the two angles.
pub fn torus_surface(n: usize, seed: u64) -> Vec<DVec3> {
    let mut r = SplitMix(seed);
    let (big, small) = (1.0, 0.35);
    (0..n)
        .map(|_| {
            let u = unit(&mut r) * std::f64::consts::TAU;
            let v = unit(&mut r) * std::f64::consts::TAU;
            DVec3::new(
                (big + small * v.cos()) * u.cos(),
                (big + small * v.cos()) * u.sin(),
                small * v.sin(),
            )
        })
        .collect()
}

/// `n` random unit vectors (normalised, so only nearly co-spherical).
pub fn sphere(n: usize, seed: u64) -> Vec<DVec3> {
    let mut r = SplitMix(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let p = DVec3::new(
            2.0 * unit(&mut r) - 1.0,
            2.0 * unit(&mut r) - 1.0,
            2.0 * unit(&mut r) - 1.0,
        );
        let l = p.length();
        if l > 0.1 && l <= 1.0 {
            out.push(p / l);
        }
    }
    out
}

/// All integer points `(x, y, z)` with `x² + y² + z² = r2`: exactly co-spherical.
/// For example `r2 = 27` gives the cube corners `(±3, ±3, ±3)` and the permutations of
/// `(±1, ±1, ±5)`.
pub fn integer_sphere(r2: i64) -> Vec<DVec3> {
    let r = (r2 as f64).sqrt() as i64 + 1;
    let mut out = Vec::new();
    for x in -r..=r {
        for y in -r..=r {
            let z2 = r2 - x * x - y * y;
            if z2 < 0 {
                continue;
            }
            let z = (z2 as f64).sqrt().round() as i64;
            if z * z == z2 {
                out.push(DVec3::new(x as f64, y as f64, z as f64));
                if z != 0 {
                    out.push(DVec3::new(x as f64, y as f64, -z as f64));
                }
            }
        }
    }
    out
}

/// The regular grid `{0..n}³` with spacing `h`.
pub fn grid(n: usize, h: f64) -> Vec<DVec3> {
    let mut out = Vec::with_capacity(n * n * n);
    for x in 0..n {
        for y in 0..n {
            for z in 0..n {
                out.push(DVec3::new(x as f64, y as f64, z as f64) * h);
            }
        }
    }
    out
}

/// The points of the grid `{0..=n}³` that lie on the surface of the cube.
pub fn cube_surface_grid(n: usize) -> Vec<DVec3> {
    let mut out = Vec::new();
    for x in 0..=n {
        for y in 0..=n {
            for z in 0..=n {
                if [x, y, z].iter().any(|&c| c == 0 || c == n) {
                    out.push(DVec3::new(x as f64, y as f64, z as f64) / n as f64);
                }
            }
        }
    }
    out
}
