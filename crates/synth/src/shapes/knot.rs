//! Torus-knot tube: the boundary of `{ p : dist(p, C) <= r }` for the (p, q) torus knot
//! `C(t) = ((R + a cos qt) cos pt, (R + a cos qt) sin pt, a sin qt)`. Genus 1, smooth.
//! Closest point on `C`: every discrete local minimum of the distance among the curve
//! samples within `d_nearest + spacing` of the query is refined by safeguarded Newton on
//! the derivative (bracketed by the neighbouring samples) to machine precision; the
//! surface point is `C(t*) + r (p - C(t*)) / |p - C(t*)|`.

use std::f64::consts::TAU;

use glam::DVec3;
use rand::Rng;
use reconbench_geom::{Aabb, PointIndex};

use super::Geometry;
use crate::shape::{Sample, SurfacePoint};
use crate::util::{integrate, uniform, unit};

const SAMPLES: usize = 4096;

/// A tube around a torus knot.
#[derive(Debug)]
pub struct KnotTube {
    p: f64,
    q: f64,
    big: f64,
    a: f64,
    r: f64,
    length: f64,
    speed_max: f64,
    kappa_max: f64,
    bbox: Aabb,
    index: PointIndex,
    spacing: f64,
}

impl KnotTube {
    /// The (p, q) torus knot on the torus (R, a) with tube radius `r`. Fails when the
    /// tube would self-intersect (r above the curve's reach).
    pub fn new(p: u32, q: u32, big: f64, a: f64, r: f64) -> Result<Self, String> {
        if gcd(p, q) != 1 {
            return Err(format!("p = {p} and q = {q} must be coprime"));
        }
        let mut k = Self {
            p: f64::from(p),
            q: f64::from(q),
            big,
            a,
            r,
            length: 0.0,
            speed_max: 0.0,
            kappa_max: 0.0,
            bbox: Aabb::EMPTY,
            index: PointIndex::new(&[DVec3::ZERO]).map_err(|e| e.to_string())?,
            spacing: 0.0,
        };
        let ts: Vec<f64> = (0..SAMPLES)
            .map(|i| TAU * i as f64 / SAMPLES as f64)
            .collect();
        let pts: Vec<DVec3> = ts.iter().map(|&t| k.c(t)).collect();
        k.length = integrate(|t| k.d1(t).length(), 0.0, TAU, 64);
        for &t in &ts {
            let (d1, d2) = (k.d1(t), k.d2(t));
            k.speed_max = k.speed_max.max(d1.length());
            k.kappa_max = k.kappa_max.max(d1.cross(d2).length() / d1.length().powi(3));
        }
        k.speed_max *= 1.001;
        k.spacing = (0..SAMPLES)
            .map(|i| (pts[(i + 1) % SAMPLES] - pts[i]).length())
            .fold(0.0, f64::max);
        if r * k.kappa_max >= 0.9 {
            return Err(format!(
                "tube radius {r} exceeds 0.9 x the minimum radius of curvature {}",
                1.0 / k.kappa_max
            ));
        }
        // Non-local self distance: samples more than pi r apart along the curve.
        let coarse: Vec<DVec3> = (0..512).map(|i| k.c(TAU * i as f64 / 512.0)).collect();
        let window = ((std::f64::consts::PI * r / (k.length / 512.0)).ceil() as usize).max(1);
        for i in 0..512 {
            for j in i + window..512 {
                if 512 - (j - i) < window {
                    continue;
                }
                let d = (coarse[i] - coarse[j]).length();
                if d < 2.2 * r {
                    return Err(format!(
                        "tube radius {r} too large: strands pass within {d}"
                    ));
                }
            }
        }
        // Tight box: the support function of the tube is max_t C(t).e + r.
        let mut lo = DVec3::ZERO;
        let mut hi = DVec3::ZERO;
        for axis in 0..3 {
            for s in [-1.0, 1.0] {
                let mut e = DVec3::ZERO;
                e[axis] = s;
                let i = (0..SAMPLES)
                    .max_by(|&i, &j| pts[i].dot(e).total_cmp(&pts[j].dot(e)))
                    .unwrap_or(0);
                let mut t = ts[i];
                for _ in 0..50 {
                    let h = k.d2(t).dot(e);
                    if h >= 0.0 {
                        break;
                    }
                    let step = -k.d1(t).dot(e) / h;
                    t += step.clamp(-TAU / SAMPLES as f64, TAU / SAMPLES as f64);
                    if step.abs() < 1e-15 {
                        break;
                    }
                }
                let v = k.c(t).dot(e).max(pts[i].dot(e)) + r;
                if s > 0.0 {
                    hi[axis] = v;
                } else {
                    lo[axis] = -v;
                }
            }
        }
        k.bbox = Aabb { min: lo, max: hi };
        k.index = PointIndex::new(&pts).map_err(|e| e.to_string())?;
        Ok(k)
    }

    fn c(&self, t: f64) -> DVec3 {
        let (sp, cp) = (self.p * t).sin_cos();
        let (sq, cq) = (self.q * t).sin_cos();
        let w = self.big + self.a * cq;
        DVec3::new(w * cp, w * sp, self.a * sq)
    }

    fn d1(&self, t: f64) -> DVec3 {
        let (p, q, a) = (self.p, self.q, self.a);
        let (sp, cp) = (p * t).sin_cos();
        let (sq, cq) = (q * t).sin_cos();
        let w = self.big + a * cq;
        let dw = -a * q * sq;
        DVec3::new(dw * cp - w * p * sp, dw * sp + w * p * cp, a * q * cq)
    }

    fn d2(&self, t: f64) -> DVec3 {
        let (p, q, a) = (self.p, self.q, self.a);
        let (sp, cp) = (p * t).sin_cos();
        let (sq, cq) = (q * t).sin_cos();
        let w = self.big + a * cq;
        let dw = -a * q * sq;
        let ddw = -a * q * q * cq;
        DVec3::new(
            ddw * cp - 2.0 * dw * p * sp - w * p * p * cp,
            ddw * sp + 2.0 * dw * p * cp - w * p * p * sp,
            -a * q * q * sq,
        )
    }

    /// Minimises `|C(t) - x|^2` on `[lo, hi]` (derivative bracketed when possible).
    fn refine(&self, x: DVec3, lo: f64, hi: f64) -> f64 {
        let g = |t: f64| self.d1(t).dot(self.c(t) - x);
        let (mut a, mut b) = (lo, hi);
        let (ga, gb) = (g(a), g(b));
        if !(ga < 0.0 && gb > 0.0) {
            // No interior critical point: the better end.
            return if (self.c(a) - x).length_squared() <= (self.c(b) - x).length_squared() {
                a
            } else {
                b
            };
        }
        let mut t = 0.5 * (a + b);
        for _ in 0..100 {
            let gt = g(t);
            if gt < 0.0 {
                a = t;
            } else {
                b = t;
            }
            let h = self.d2(t).dot(self.c(t) - x) + self.d1(t).length_squared();
            let mut next = if h > 0.0 { t - gt / h } else { 0.5 * (a + b) };
            if !(next > a && next < b) {
                next = 0.5 * (a + b);
            }
            if (next - t).abs() <= 1e-16 * (1.0 + t.abs()) || b - a <= 1e-15 {
                return next;
            }
            t = next;
        }
        t
    }

    /// Parameter and point of the closest curve point.
    fn closest_on_curve(&self, x: DVec3) -> (f64, DVec3) {
        let near = self.index.nearest(x).expect("finite query");
        let rad = near.dist2.sqrt() + self.spacing;
        let cands = self.index.radius(x, rad).expect("finite query");
        let n = SAMPLES;
        let pts = self.index.points();
        let dt = TAU / n as f64;
        let d2 = |i: usize| (pts[i % n] - x).length_squared();
        let mut best = (f64::INFINITY, 0.0);
        for c in cands {
            let i = c.index as usize;
            let here = c.dist2;
            if here <= d2(i + 1) && here <= d2(i + n - 1) {
                let t0 = i as f64 * dt;
                let t = self.refine(x, t0 - dt, t0 + dt);
                let d = (self.c(t) - x).length_squared();
                if d < best.0 {
                    best = (d, t);
                }
            }
        }
        (best.1, self.c(best.1))
    }
}

fn gcd(a: u32, b: u32) -> u32 {
    if b == 0 { a } else { gcd(b, a % b) }
}

impl Geometry for KnotTube {
    fn closest(&self, x: DVec3) -> SurfacePoint {
        let (_, c) = self.closest_on_curve(x);
        let v = x - c;
        let d = v.length();
        let n = if d > 0.0 {
            v / d
        } else {
            crate::util::frame(self.d1(0.0).normalize()).0
        };
        SurfacePoint {
            point: c + n * self.r,
            normal: n,
            distance: (d - self.r).abs(),
        }
    }

    fn inside(&self, x: DVec3) -> bool {
        (x - self.closest_on_curve(x).1).length() < self.r
    }

    fn sample(&self, rng: &mut dyn Rng) -> Sample {
        loop {
            let t = uniform(rng, 0.0, TAU);
            let (d1, d2) = (self.d1(t), self.d2(t));
            let speed = d1.length();
            if unit(rng) * self.speed_max > speed {
                continue;
            }
            let tan = d1 / speed;
            let kappa = d1.cross(d2).length() / speed.powi(3);
            let nrm = (d2 - tan * d2.dot(tan)).normalize();
            let bin = tan.cross(nrm);
            let psi = uniform(rng, 0.0, TAU);
            if unit(rng) * (1.0 + self.kappa_max * self.r) > 1.0 - kappa * self.r * psi.cos() {
                continue;
            }
            let n = nrm * psi.cos() + bin * psi.sin();
            return Sample {
                position: self.c(t) + n * self.r,
                normal: n,
            };
        }
    }

    fn aabb(&self) -> Aabb {
        self.bbox
    }

    fn area(&self) -> f64 {
        TAU * self.r * self.length
    }

    fn genus(&self) -> u32 {
        1
    }
}
