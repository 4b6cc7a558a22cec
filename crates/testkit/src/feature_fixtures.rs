//! Feature-detection fixtures: test clouds with exact ground truth and point-labelling
//! scores.

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reconbench_geom::PointCloud;
use reconbench_geom::method::FeatureClass;

/// A test cloud with its sharp feature segments and corners.
#[derive(Debug)]
pub struct Truth {
    /// The sample points.
    pub points: Vec<DVec3>,
    /// Sharp feature segments.
    pub edges: Vec<(DVec3, DVec3)>,
    /// Corners (three or more patches meet).
    pub corners: Vec<DVec3>,
    /// Sampling spacing.
    pub spacing: f64,
}

impl Truth {
    /// The points as a cloud.
    pub fn cloud(&self) -> PointCloud {
        PointCloud::new(self.points.clone()).unwrap()
    }

    /// Distance from `p` to the nearest feature segment.
    pub fn edge_distance(&self, p: DVec3) -> f64 {
        self.edges
            .iter()
            .map(|&(a, b)| {
                let ab = b - a;
                let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
                (a + t * ab - p).length()
            })
            .fold(f64::INFINITY, f64::min)
    }
}

/// Surface of the cube `[0, side]^3` sampled on the grid of `m` intervals per edge:
/// samples lie exactly on every edge and corner (seed 002 §10.2).
pub fn grid_box(side: f64, m: usize) -> Truth {
    let h = side / m as f64;
    let mut points = Vec::new();
    for i in 0..=m {
        for j in 0..=m {
            for l in 0..=m {
                let on = |c: usize| c == 0 || c == m;
                if on(i) || on(j) || on(l) {
                    points.push(DVec3::new(i as f64, j as f64, l as f64) * h);
                }
            }
        }
    }
    let c = |x: usize, y: usize, z: usize| DVec3::new(x as f64, y as f64, z as f64) * side;
    let corners: Vec<DVec3> = (0..8)
        .map(|b| c(b & 1, (b >> 1) & 1, (b >> 2) & 1))
        .collect();
    let mut edges = Vec::new();
    for a in 0..8usize {
        for bit in [1usize, 2, 4] {
            if a & bit == 0 {
                edges.push((corners[a], corners[a | bit]));
            }
        }
    }
    Truth {
        points,
        edges,
        corners,
        spacing: h,
    }
}

/// `n` area-uniform random samples of the surface of `[0, side]^3`.
pub fn random_box(side: f64, n: usize, seed: u64) -> Truth {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let points = (0..n)
        .map(|_| {
            let face: usize = rng.random_range(0..6);
            let u: f64 = rng.random::<f64>() * side;
            let v: f64 = rng.random::<f64>() * side;
            let w = if face >= 3 { side } else { 0.0 };
            match face % 3 {
                0 => DVec3::new(w, u, v),
                1 => DVec3::new(u, w, v),
                _ => DVec3::new(u, v, w),
            }
        })
        .collect();
    let g = grid_box(side, 1);
    let spacing = side * (6.0 / n as f64).sqrt();
    Truth {
        points,
        edges: g.edges,
        corners: g.corners,
        spacing,
    }
}

/// Fibonacci sphere of radius 1 (smooth: no features).
pub fn sphere(n: usize) -> Vec<DVec3> {
    let ga = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let t = ga * i as f64;
            DVec3::new(r * t.cos(), r * t.sin(), z)
        })
        .collect()
}

/// Two `length x width` sheets sharing the edge `x in [0, length]` at opening (dihedral)
/// angle `deg`, grid spacing `h` (samples on the edge).
pub fn wedge(deg: f64, length: f64, width: f64, h: f64) -> Truth {
    let phi = deg.to_radians();
    let ua = DVec3::new(0.0, (phi / 2.0).sin(), -(phi / 2.0).cos());
    let ub = DVec3::new(0.0, -(phi / 2.0).sin(), -(phi / 2.0).cos());
    let nx = (length / h).round() as usize;
    let ns = (width / h).round() as usize;
    let mut points = Vec::new();
    for i in 0..=nx {
        let x = DVec3::new(i as f64 * h, 0.0, 0.0);
        points.push(x);
        for j in 1..=ns {
            points.push(x + j as f64 * h * ua);
            points.push(x + j as f64 * h * ub);
        }
    }
    Truth {
        points,
        edges: vec![(DVec3::ZERO, DVec3::new(nx as f64 * h, 0.0, 0.0))],
        corners: Vec::new(),
        spacing: h,
    }
}

/// Point-labelling scores of a detector against exact feature segments.
#[derive(Debug, Clone, Copy)]
pub struct Scores {
    /// Detected points.
    pub detected: usize,
    /// Share of detected points within `r` of a feature segment.
    pub precision: f64,
    /// Share of the points lying on a segment (distance < 1e-9) that are detected (the
    /// thesis's Table 1 recall; needs samples on the features).
    pub recall_on_curve: f64,
    /// Share of segment length (sampled every spacing / 2) with a detected point within r.
    pub coverage: f64,
}

/// Scores `labels` against the truth, with a detected point counting within `r`.
pub fn score(t: &Truth, labels: &[FeatureClass], r: f64) -> Scores {
    let det: Vec<DVec3> = t
        .points
        .iter()
        .zip(labels)
        .filter(|(_, c)| **c != FeatureClass::None)
        .map(|(p, _)| *p)
        .collect();
    let tp = det.iter().filter(|p| t.edge_distance(**p) <= r).count();
    let on: Vec<usize> = (0..t.points.len())
        .filter(|&i| t.edge_distance(t.points[i]) < 1e-9)
        .collect();
    let on_hit = on
        .iter()
        .filter(|&&i| labels[i] != FeatureClass::None)
        .count();
    let mut samples = 0usize;
    let mut covered = 0usize;
    for &(a, b) in &t.edges {
        let m = ((b - a).length() / (t.spacing / 2.0)).ceil() as usize;
        for s in 0..=m {
            let q = a + (b - a) * (s as f64 / m as f64);
            samples += 1;
            if det.iter().any(|p| (*p - q).length() <= r) {
                covered += 1;
            }
        }
    }
    Scores {
        detected: det.len(),
        precision: if det.is_empty() {
            1.0
        } else {
            tp as f64 / det.len() as f64
        },
        recall_on_curve: if on.is_empty() {
            f64::NAN
        } else {
            on_hit as f64 / on.len() as f64
        },
        coverage: covered as f64 / samples.max(1) as f64,
    }
}

/// Number of points labelled edge or corner.
pub fn count_features(labels: &[FeatureClass]) -> usize {
    labels.iter().filter(|c| **c != FeatureClass::None).count()
}

/// Ball-uniform noise of radius `rho` (seed 002 §1.4 generator).
pub fn add_noise(points: &[DVec3], rho: f64, seed: u64) -> Vec<DVec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    points
        .iter()
        .map(|&p| {
            loop {
                let v = DVec3::new(
                    rng.random::<f64>() * 2.0 - 1.0,
                    rng.random::<f64>() * 2.0 - 1.0,
                    rng.random::<f64>() * 2.0 - 1.0,
                );
                if v.length_squared() <= 1.0 {
                    break p + rho * v;
                }
            }
        })
        .collect()
}
