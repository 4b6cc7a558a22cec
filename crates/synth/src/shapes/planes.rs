//! Seed 002's "planes": two ruled (bilinear) sheets meeting at a straight ridge whose
//! opening angle varies monotonically from `a0` at one end to `a1` at the other (thesis
//! Table 1 and figure 22: 45 -> 140 degrees; spec §10.2).
//!
//! Ridge along x in `[-l/2, l/2]`, `xi = x / l + 1/2`. Sheet A is
//! `P(xi, s) = (x(xi), s d_y(xi), z0 + s d_z(xi))`, `s in [0, w]`, with the ruling
//! direction interpolated linearly (bilinearly in the patch) between the end rulings,
//! `d(xi) = (1 - xi) (0, sin(a0/2), -cos(a0/2)) + xi (0, sin(a1/2), -cos(a1/2))`; sheet B
//! is its mirror `y -> -y`. The rulings lie in the planes `x = const`, so the distance to
//! the ruling at `xi` is closed form and the closest point is the minimum over `xi` of a
//! smooth 1-D function: 129 samples, then golden-section refinement of the bracket of
//! every sampled local minimum to machine precision (the global minimum is kept).
//!
//! Feature: the ridge, reported as 32 equal segments, each with the smallest dihedral
//! angle over the piece (the angle between `d` and its mirror, monotonic along the
//! ridge; the geometry is exact, the per-piece angle samples the continuous variation). Normals: sheet A `(0, cos, sin)`-like
//! (as `wedge`), sheet B its mirror; ridge grid samples get the normalised sum.

use glam::{DVec2, DVec3};
use rand::Rng;
use reconbench_geom::{Aabb, TriMesh};

use super::Geometry;
use crate::features::{Feature, FeatureGeom};
use crate::shape::{Sample, SurfacePoint};
use crate::util::{gauss_legendre, uniform, unit};

/// Number of ridge pieces in [`Geometry::features`].
const RIDGE_PIECES: usize = 32;
/// Samples of the 1-D closest-point search.
const SEARCH_SAMPLES: usize = 129;

/// The varying-angle planes.
#[derive(Debug, Clone)]
pub struct Planes {
    l: f64,
    w: f64,
    z0: f64,
    d0: DVec2,
    d1: DVec2,
    area: f64,
    nmax: f64,
}

impl Planes {
    /// Opening angles `a0_deg` (at x = -l/2) and `a1_deg` (at x = l/2), ridge length
    /// `l`, ruling parameter range `w` (checked by the catalogue).
    pub fn new(a0_deg: f64, a1_deg: f64, l: f64, w: f64) -> Self {
        let dir = |a: f64| {
            let (s, c) = (0.5 * a.to_radians()).sin_cos();
            DVec2::new(s, -c)
        };
        let (d0, d1) = (dir(a0_deg), dir(a1_deg));
        // Centre the bounding box in z: the deepest ruling end is the more acute one.
        let zmin = w * d0.y.min(d1.y);
        let mut p = Self {
            l,
            w,
            z0: -0.5 * zmin,
            d0,
            d1,
            area: 0.0,
            nmax: 0.0,
        };
        // |n|^2 = l^2 |d|^2 + s^2 (d' x d)^2: |d|^2 is convex and d' x d linear in xi,
        // so both are largest at an end and the bound is exact.
        let c = |xi: f64| p.dprime().perp_dot(p.d(xi));
        p.nmax = (l * l * d0.length_squared().max(d1.length_squared())
            + w * w * c(0.0).abs().max(c(1.0).abs()).powi(2))
        .sqrt();
        let gl = gauss_legendre(24);
        let mut area = 0.0;
        for &(x, wx) in &gl {
            for &(y, wy) in &gl {
                let xi = 0.5 * (x + 1.0);
                let s = 0.5 * w * (y + 1.0);
                area += wx * wy * p.normal_raw(xi, s).length() * 0.5 * 0.5 * w;
            }
        }
        p.area = 2.0 * area;
        p
    }

    fn d(&self, xi: f64) -> DVec2 {
        self.d0 + (self.d1 - self.d0) * xi
    }

    fn dprime(&self) -> DVec2 {
        self.d1 - self.d0
    }

    fn x(&self, xi: f64) -> f64 {
        (xi - 0.5) * self.l
    }

    /// Point of sheet `k` (0 = A, y >= 0; 1 = B) at `(xi, s)`.
    fn point(&self, k: usize, xi: f64, s: f64) -> DVec3 {
        let d = self.d(xi);
        let y = s * d.x;
        DVec3::new(self.x(xi), if k == 0 { y } else { -y }, self.z0 + s * d.y)
    }

    /// dP/dxi x dP/ds of sheet A (unnormalised; its length is the area element in
    /// (xi, s)).
    fn normal_raw(&self, xi: f64, s: f64) -> DVec3 {
        let (d, dp) = (self.d(xi), self.dprime());
        let pxi = DVec3::new(self.l, s * dp.x, s * dp.y);
        let ps = DVec3::new(0.0, d.x, d.y);
        pxi.cross(ps)
    }

    fn normal(&self, k: usize, xi: f64, s: f64) -> DVec3 {
        let n = self.normal_raw(xi, s).normalize();
        if k == 0 {
            n
        } else {
            DVec3::new(n.x, -n.y, n.z)
        }
    }

    /// Closest point of the ruling at `xi` on sheet A to `q` (y folded to >= 0 by the
    /// caller for sheet B): returns (squared distance, s).
    fn ruling(&self, q: DVec3, xi: f64) -> (f64, f64) {
        let d = self.d(xi);
        let r = DVec2::new(q.y, q.z - self.z0);
        let s = (r.dot(d) / d.length_squared()).clamp(0.0, self.w);
        let dx = q.x - self.x(xi);
        (dx * dx + (r - d * s).length_squared(), s)
    }

    /// Global minimum over xi of the ruling distance: (squared distance, xi, s).
    fn closest_on_sheet(&self, q: DVec3) -> (f64, f64, f64) {
        let n = SEARCH_SAMPLES - 1;
        let g: Vec<f64> = (0..=n)
            .map(|i| self.ruling(q, i as f64 / n as f64).0)
            .collect();
        let mut best = (f64::INFINITY, 0.0, 0.0);
        for i in 0..=n {
            let left = if i == 0 { f64::INFINITY } else { g[i - 1] };
            let right = if i == n { f64::INFINITY } else { g[i + 1] };
            if g[i] > left || g[i] > right {
                continue; // not a sampled local minimum
            }
            let lo = i.saturating_sub(1) as f64 / n as f64;
            let hi = (i + 1).min(n) as f64 / n as f64;
            let xi = self.golden(q, lo, hi);
            for x in [xi, i as f64 / n as f64] {
                let (d2, s) = self.ruling(q, x);
                if d2 < best.0 {
                    best = (d2, x, s);
                }
            }
        }
        best
    }

    fn golden(&self, q: DVec3, mut a: f64, mut b: f64) -> f64 {
        let r = 0.5 * (5f64.sqrt() - 1.0);
        let f = |x: f64| self.ruling(q, x).0;
        let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
        let (mut fc, mut fd) = (f(c), f(d));
        for _ in 0..80 {
            if fc <= fd {
                b = d;
                d = c;
                fd = fc;
                c = b - r * (b - a);
                fc = f(c);
            } else {
                a = c;
                c = d;
                fc = fd;
                d = a + r * (b - a);
                fd = f(d);
            }
            if b - a < 1e-15 {
                break;
            }
        }
        let mid = 0.5 * (a + b);
        // The end points can be the minimum (boundary of the patch).
        [a, b, mid]
            .into_iter()
            .min_by(|x, y| f(*x).total_cmp(&f(*y)))
            .unwrap_or(mid)
    }

    /// Opening angle at `xi`, degrees.
    fn angle_deg(&self, xi: f64) -> f64 {
        let d = self.d(xi);
        2.0 * d.x.atan2(-d.y).to_degrees()
    }
}

impl Geometry for Planes {
    fn closest(&self, p: DVec3) -> SurfacePoint {
        let mut best: Option<SurfacePoint> = None;
        for k in 0..2 {
            let q = if k == 0 {
                p
            } else {
                DVec3::new(p.x, -p.y, p.z)
            };
            let (d2, xi, s) = self.closest_on_sheet(q);
            let _ = d2;
            let point = self.point(k, xi, s);
            let dist = (p - point).length();
            if best.is_none_or(|b| dist < b.distance) {
                best = Some(SurfacePoint {
                    point,
                    normal: self.normal(k, xi, s),
                    distance: dist,
                });
            }
        }
        best.expect("two sheets")
    }

    fn sample(&self, rng: &mut dyn Rng) -> Sample {
        let k = usize::from(unit(rng) >= 0.5);
        loop {
            let xi = unit(rng);
            let s = uniform(rng, 0.0, self.w);
            if unit(rng) * self.nmax <= self.normal_raw(xi, s).length() {
                return Sample {
                    position: self.point(k, xi, s),
                    normal: self.normal(k, xi, s),
                };
            }
        }
    }

    fn aabb(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for k in 0..2 {
            for xi in [0.0, 1.0] {
                for s in [0.0, self.w] {
                    b = b.grow(self.point(k, xi, s));
                }
            }
        }
        b
    }

    fn area(&self) -> f64 {
        self.area
    }

    fn genus(&self) -> u32 {
        0
    }

    fn closed(&self) -> bool {
        false
    }

    fn features(&self) -> Vec<Feature> {
        (0..RIDGE_PIECES)
            .map(|i| {
                let (t0, t1) = (
                    i as f64 / RIDGE_PIECES as f64,
                    (i + 1) as f64 / RIDGE_PIECES as f64,
                );
                Feature {
                    geom: FeatureGeom::Segment {
                        a: self.point(0, t0, 0.0),
                        b: self.point(0, t1, 0.0),
                    },
                    dihedral_deg: self.angle_deg(t0).min(self.angle_deg(t1)),
                }
            })
            .collect()
    }

    fn mesh(&self, resolution: usize) -> Option<TriMesh> {
        let nx = resolution.max(1);
        let ns = ((self.w / self.l * nx as f64).ceil() as usize).max(1);
        let g = self.grid(nx + 1, ns + 1).expect("grid");
        let verts = g.into_iter().map(|s| s.position).collect();
        let faces = super::sheet::two_sheet_faces(nx, ns);
        Some(TriMesh::new(verts, faces).expect("valid planes mesh"))
    }

    /// `nu` points along the ridge times `nv` rows per sheet (uniform in `(xi, s)`, the
    /// ridge row shared): `nu (2 nv - 1)` points, ridge first, then sheet A, sheet B.
    fn grid(&self, nu: usize, nv: usize) -> Option<Vec<Sample>> {
        let (nu, nv) = (nu.max(2), nv.max(2));
        let xi = |i: usize| i as f64 / (nu - 1) as f64;
        let mut out = Vec::new();
        for i in 0..nu {
            let n = (self.normal(0, xi(i), 0.0) + self.normal(1, xi(i), 0.0)).normalize();
            out.push(Sample {
                position: self.point(0, xi(i), 0.0),
                normal: n,
            });
        }
        for k in 0..2 {
            for j in 1..nv {
                let s = self.w * j as f64 / (nv - 1) as f64;
                for i in 0..nu {
                    out.push(Sample {
                        position: self.point(k, xi(i), s),
                        normal: self.normal(k, xi(i), s),
                    });
                }
            }
        }
        Some(out)
    }

    /// Square-ish cells: `nv / nu` about `w / l`.
    fn grid_dims(&self, count: usize) -> (usize, usize) {
        let ratio = self.w / self.l;
        // nu (2 nv - 1) = count with nv = ratio nu.
        let nu = ((count as f64 / (2.0 * ratio)).sqrt().round() as usize).max(2);
        let nv = ((ratio * nu as f64).round() as usize).max(2);
        (nu, nv)
    }
}
