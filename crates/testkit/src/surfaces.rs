//! Small deterministic point-set generators for the reconstruction tests, benches and
//! probes (sphere, torus, open sheet, two parallel sheets, uniform outliers, blue noise).

use std::collections::HashMap;
use std::f64::consts::TAU;

use glam::DVec3;
use rand::{Rng, RngExt};

/// A parametric test surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Surface {
    /// Sphere of this radius at the origin (genus 0).
    Sphere(f64),
    /// Torus with major radius `R` and minor radius `r` around the z axis (genus 1).
    Torus(f64, f64),
    /// Open wavy sheet `z = amp sin(x) cos(y)` over `[-size/2, size/2]^2` (one boundary).
    Sheet {
        /// Side of the square domain.
        size: f64,
        /// Amplitude of the waves.
        amp: f64,
    },
    /// Two parallel unit squares `z = 0` and `z = gap` (two boundaries).
    TwoSheets {
        /// Distance between the sheets.
        gap: f64,
    },
}

impl Surface {
    /// Surface area (exact for sphere / torus / two sheets; the sheet's by quadrature).
    pub fn area(&self) -> f64 {
        match *self {
            Surface::Sphere(r) => 2.0 * TAU * r * r,
            Surface::Torus(rr, r) => TAU * TAU * rr * r,
            Surface::Sheet { size, amp } => {
                let m = 200;
                let h = size / m as f64;
                let mut a = 0.0;
                for i in 0..m {
                    for j in 0..m {
                        let x = -size / 2.0 + (i as f64 + 0.5) * h;
                        let y = -size / 2.0 + (j as f64 + 0.5) * h;
                        let (fx, fy) = (amp * x.cos() * y.cos(), -amp * x.sin() * y.sin());
                        a += (1.0 + fx * fx + fy * fy).sqrt() * h * h;
                    }
                }
                a
            }
            Surface::TwoSheets { .. } => 2.0,
        }
    }

    /// One uniform (area-weighted) random point, by rejection.
    pub fn sample_one<R: Rng + ?Sized>(&self, rng: &mut R) -> DVec3 {
        match *self {
            Surface::Sphere(r) => {
                let z: f64 = rng.random_range(-1.0..1.0);
                let phi: f64 = rng.random_range(0.0..TAU);
                let s = (1.0 - z * z).max(0.0).sqrt();
                DVec3::new(s * phi.cos(), s * phi.sin(), z) * r
            }
            Surface::Torus(rr, r) => loop {
                let u: f64 = rng.random_range(0.0..TAU);
                let v: f64 = rng.random_range(0.0..TAU);
                let w = (rr + r * v.cos()) / (rr + r);
                if rng.random_range(0.0..1.0) <= w {
                    let c = rr + r * v.cos();
                    return DVec3::new(c * u.cos(), c * u.sin(), r * v.sin());
                }
            },
            Surface::Sheet { size, amp } => loop {
                let x: f64 = rng.random_range(-size / 2.0..size / 2.0);
                let y: f64 = rng.random_range(-size / 2.0..size / 2.0);
                let (fx, fy) = (amp * x.cos() * y.cos(), -amp * x.sin() * y.sin());
                let w = (1.0 + fx * fx + fy * fy).sqrt() / (1.0 + 2.0 * amp * amp).sqrt();
                if rng.random_range(0.0..1.0) <= w {
                    return DVec3::new(x, y, amp * x.sin() * y.cos());
                }
            },
            Surface::TwoSheets { gap } => {
                let x: f64 = rng.random_range(-0.5..0.5);
                let y: f64 = rng.random_range(-0.5..0.5);
                let z = if rng.random_range(0.0..1.0) < 0.5 {
                    0.0
                } else {
                    gap
                };
                DVec3::new(x, y, z)
            }
        }
    }

    /// `n` uniform random points.
    pub fn sample_uniform<R: Rng + ?Sized>(&self, n: usize, rng: &mut R) -> Vec<DVec3> {
        (0..n).map(|_| self.sample_one(rng)).collect()
    }

    /// About `n` blue-noise points (Poisson-disk dart throwing over a uniform oversample;
    /// the minimum distance is chosen so that the first `n` accepted darts cover the
    /// surface; returns exactly `n` unless the oversample runs dry).
    pub fn sample_blue_noise<R: Rng + ?Sized>(&self, n: usize, rng: &mut R) -> Vec<DVec3> {
        // Random sequential addition saturates near coverage 0.547 of disks of radius
        // r/2; aim a little below it so 6 n darts suffice.
        let rmin = (0.5 * self.area() / n.max(1) as f64).sqrt();
        let cell = rmin;
        let inv = 1.0 / cell;
        let key = |p: DVec3| {
            let c = (p * inv).floor();
            (c.x as i64, c.y as i64, c.z as i64)
        };
        let mut grid: HashMap<(i64, i64, i64), Vec<u32>> = HashMap::with_capacity(n);
        let mut out: Vec<DVec3> = Vec::with_capacity(n);
        let r2 = rmin * rmin;
        for _ in 0..6 * n {
            if out.len() >= n {
                break;
            }
            let p = self.sample_one(rng);
            let k = key(p);
            let mut ok = true;
            'outer: for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        if let Some(v) = grid.get(&(k.0 + dx, k.1 + dy, k.2 + dz)) {
                            for &i in v {
                                if (out[i as usize] - p).length_squared() < r2 {
                                    ok = false;
                                    break 'outer;
                                }
                            }
                        }
                    }
                }
            }
            if ok {
                grid.entry(k).or_default().push(out.len() as u32);
                out.push(p);
            }
        }
        out
    }

    /// Distance from `p` to the surface (exact for sphere, torus and two sheets;
    /// vertical distance for the wavy sheet).
    pub fn distance(&self, p: DVec3) -> f64 {
        match *self {
            Surface::Sphere(r) => (p.length() - r).abs(),
            Surface::Torus(rr, r) => {
                let q = (p.x * p.x + p.y * p.y).sqrt() - rr;
                ((q * q + p.z * p.z).sqrt() - r).abs()
            }
            Surface::Sheet { amp, .. } => (p.z - amp * p.x.sin() * p.y.cos()).abs(),
            Surface::TwoSheets { gap } => p.z.abs().min((p.z - gap).abs()),
        }
    }
}

/// `count` outliers uniform in the axis-aligned bounding box of `pts` (spec N1).
pub fn uniform_outliers<R: Rng + ?Sized>(pts: &[DVec3], count: usize, rng: &mut R) -> Vec<DVec3> {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for &p in pts {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    (0..count)
        .map(|_| {
            DVec3::new(
                rng.random_range(lo.x..=hi.x),
                rng.random_range(lo.y..=hi.y),
                rng.random_range(lo.z..=hi.z),
            )
        })
        .collect()
}
