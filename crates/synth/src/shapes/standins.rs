//! Open height-field stand-ins for the parts of seed 004 (Sun et al. 2001, spec §6 item
//! 1), in millimetres before normalisation:
//!
//! * `mask` (250 x 200 x 60 mm): a free-form dome with a nose ridge, a narrow brow ridge
//!   and two eye hollows (the face mask);
//! * `poly-part` (150 x 150 x 30 mm): a plane carrying a cylindrical ridge (radius 25 mm,
//!   20 mm high, along y) and a spherical cap (radius 40 mm, 30 mm high); the patches
//!   meet the plane in creases (the polyhedral object);
//! * `blade` (240 x 180 x 65 mm): a twisted, cambered plate (the turbine blade).
//!
//! Closest points: multi-start Newton on the parameter rectangle from the 12
//! nearest of a 129 x 129 seed grid (exact to solver tolerance on the smooth parts; at
//! the creases of `poly-part` the best of the local minima). Ray casts: marching in
//! steps of 1/800 of the box diagonal with bisection (the scanner's line-of-sight query).

use glam::{DVec2, DVec3};
use rand::Rng;
use reconbench_geom::{Aabb, PointIndex, TriMesh};

use super::Geometry;
use crate::shape::{Sample, SurfacePoint};
use crate::util::{uniform, unit};

/// Grid refinement of the reference mesh over the requested resolution.
const MESH_REFINE: usize = 4;

/// Which stand-in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StandInKind {
    /// The face mask.
    Mask,
    /// The plane with a cylindrical and a spherical patch.
    PolyPart,
    /// The twisted blade.
    Blade,
}

fn gauss(x: f64) -> f64 {
    (-x * x).exp()
}

/// Height (mm) of `kind` at `(x, y)` (mm).
pub fn height(kind: StandInKind, x: f64, y: f64) -> f64 {
    match kind {
        StandInKind::Mask => {
            let dome = 40.0 * (1.0 - (x / 135.0).powi(2) - (y / 110.0).powi(2)).max(0.0);
            let nose = 18.0 * gauss(x / 11.0) * gauss((y + 5.0) / 40.0);
            let brow = 5.0 * gauss((y - 48.0) / 3.0) * gauss(x / 70.0);
            let eyes = -9.0
                * (gauss((x - 45.0) / 20.0) * gauss((y - 25.0) / 14.0)
                    + gauss((x + 45.0) / 20.0) * gauss((y - 25.0) / 14.0));
            dome + nose + brow + eyes
        }
        StandInKind::PolyPart => {
            let (rc, xc) = (25.0, -35.0);
            let dx = x - xc;
            let cyl = if dx.abs() < rc {
                (rc * rc - dx * dx).sqrt() - (rc - 20.0)
            } else {
                f64::NEG_INFINITY
            };
            let rs = 40.0;
            let d2 = (x - 35.0).powi(2) + (y - 15.0).powi(2);
            let sph = if d2 < rs * rs {
                (rs * rs - d2).sqrt() - (rs - 30.0)
            } else {
                f64::NEG_INFINITY
            };
            0f64.max(cyl).max(sph)
        }
        StandInKind::Blade => {
            let twist = 0.26 * x / 120.0;
            y * twist.tan() + 26.0 * (1.0 - (y / 90.0).powi(2)) - 0.0008 * x * x
        }
    }
}

/// Half extents (mm) of the parameter rectangle.
fn half(kind: StandInKind) -> DVec2 {
    match kind {
        StandInKind::Mask => DVec2::new(125.0, 100.0),
        StandInKind::PolyPart => DVec2::new(75.0, 75.0),
        StandInKind::Blade => DVec2::new(120.0, 90.0),
    }
}

/// One stand-in as a [`Geometry`].
#[derive(Debug)]
pub struct StandIn {
    kind: StandInKind,
    h: DVec2,
    area: f64,
    jac_max: f64,
    zmin: f64,
    zmax: f64,
    seeds: PointIndex,
    seed_uv: Vec<DVec2>,
}

impl StandIn {
    /// The stand-in `kind`.
    pub fn new(kind: StandInKind) -> Self {
        let h = half(kind);
        let n = 129;
        let uv: Vec<DVec2> = (0..n * n)
            .map(|k| {
                DVec2::new(
                    -h.x + 2.0 * h.x * (k % n) as f64 / (n - 1) as f64,
                    -h.y + 2.0 * h.y * (k / n) as f64 / (n - 1) as f64,
                )
            })
            .collect();
        let pts: Vec<DVec3> = uv
            .iter()
            .map(|q| DVec3::new(q.x, q.y, height(kind, q.x, q.y)))
            .collect();
        let mut s = Self {
            kind,
            h,
            area: 0.0,
            jac_max: 1.0,
            zmin: pts.iter().map(|p| p.z).fold(f64::INFINITY, f64::min),
            zmax: pts.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max),
            seeds: PointIndex::new(&pts).expect("finite seeds"),
            seed_uv: uv,
        };
        // Area and the Jacobian bound of the rejection sampler on a 400 x 400 midpoint grid.
        let m = 400;
        let (dx, dy) = (2.0 * h.x / m as f64, 2.0 * h.y / m as f64);
        let (mut area, mut jmax) = (0.0, 1.0f64);
        for j in 0..m {
            for i in 0..m {
                let x = -h.x + (i as f64 + 0.5) * dx;
                let y = -h.y + (j as f64 + 0.5) * dy;
                let jac = s.jac(x, y);
                area += jac * dx * dy;
                jmax = jmax.max(jac);
            }
        }
        s.area = area;
        s.jac_max = jmax * 1.25;
        s
    }

    fn f(&self, x: f64, y: f64) -> f64 {
        height(self.kind, x, y)
    }

    fn at(&self, q: DVec2) -> DVec3 {
        DVec3::new(q.x, q.y, self.f(q.x, q.y))
    }

    /// Central-difference gradient (one-sided at the rectangle's edges).
    fn grad(&self, x: f64, y: f64) -> DVec2 {
        let e = 1e-5 * self.h.max_element();
        let (x0, x1) = ((x - e).max(-self.h.x), (x + e).min(self.h.x));
        let (y0, y1) = ((y - e).max(-self.h.y), (y + e).min(self.h.y));
        DVec2::new(
            (self.f(x1, y) - self.f(x0, y)) / (x1 - x0),
            (self.f(x, y1) - self.f(x, y0)) / (y1 - y0),
        )
    }

    fn normal(&self, x: f64, y: f64) -> DVec3 {
        let g = self.grad(x, y);
        DVec3::new(-g.x, -g.y, 1.0).normalize()
    }

    fn jac(&self, x: f64, y: f64) -> f64 {
        let g = self.grad(x, y);
        (1.0 + g.length_squared()).sqrt()
    }

    /// Central-difference second derivatives (fxx, fxy, fyy).
    fn hess(&self, x: f64, y: f64) -> (f64, f64, f64) {
        let e = 1e-4 * self.h.max_element();
        let f0 = self.f(x, y);
        let fxx = (self.f(x + e, y) - 2.0 * f0 + self.f(x - e, y)) / (e * e);
        let fyy = (self.f(x, y + e) - 2.0 * f0 + self.f(x, y - e)) / (e * e);
        let fxy = (self.f(x + e, y + e) - self.f(x + e, y - e) - self.f(x - e, y + e)
            + self.f(x - e, y - e))
            / (4.0 * e * e);
        (fxx, fxy, fyy)
    }

    /// Newton (Gauss-Newton where the Hessian is not positive definite) with
    /// backtracking on the box from `q0`, then the same with the Gauss-Newton step.
    fn descend(&self, p: DVec3, q0: DVec2) -> DVec2 {
        let obj = |q: DVec2| (self.at(q) - p).length_squared();
        let (lo, hi) = (-self.h, self.h);
        let mut q = q0;
        let mut fq = obj(q);
        for it in 0..120 {
            let g = self.grad(q.x, q.y);
            let r = self.at(q) - p;
            // Gradient of |r|^2 / 2 and its (Gauss-)Newton matrix.
            let gr = DVec2::new(r.x + r.z * g.x, r.y + r.z * g.y);
            let (mut a, mut b, mut c) = (1.0 + g.x * g.x, g.x * g.y, 1.0 + g.y * g.y);
            if it % 2 == 0 {
                let (fxx, fxy, fyy) = self.hess(q.x, q.y);
                let (na, nb, nc) = (a + r.z * fxx, b + r.z * fxy, c + r.z * fyy);
                if na > 0.0 && na * nc - nb * nb > 0.0 {
                    (a, b, c) = (na, nb, nc);
                }
            }
            // Active bounds (at a bound with the gradient pushing outwards): Newton in
            // the free coordinate only.
            let act = [
                (q.x <= lo.x && gr.x > 0.0) || (q.x >= hi.x && gr.x < 0.0),
                (q.y <= lo.y && gr.y > 0.0) || (q.y >= hi.y && gr.y < 0.0),
            ];
            let step = match act {
                [false, false] => {
                    let det = a * c - b * b;
                    -DVec2::new(c * gr.x - b * gr.y, a * gr.y - b * gr.x) / det
                }
                [true, false] => DVec2::new(0.0, -gr.y / c),
                [false, true] => DVec2::new(-gr.x / a, 0.0),
                [true, true] => break,
            };
            let mut t = 1.0;
            let mut moved = false;
            for _ in 0..50 {
                let cand = (q + step * t).clamp(lo, hi);
                let fc = obj(cand);
                if fc < fq {
                    moved = true;
                    q = cand;
                    fq = fc;
                    break;
                }
                t *= 0.5;
            }
            if !moved && it % 2 == 1 {
                break;
            }
        }
        q
    }
}

impl Geometry for StandIn {
    fn closest(&self, p: DVec3) -> SurfacePoint {
        let cands = self.seeds.knn(p, 12).expect("finite query");
        let mut best: Option<(f64, DVec2)> = None;
        for c in cands {
            let q = self.descend(p, self.seed_uv[c.index as usize]);
            let d = (self.at(q) - p).length();
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, q));
            }
        }
        let (distance, q) = best.expect("candidates");
        SurfacePoint {
            point: self.at(q),
            normal: self.normal(q.x, q.y),
            distance,
        }
    }

    fn sample(&self, rng: &mut dyn Rng) -> Sample {
        loop {
            let x = uniform(rng, -self.h.x, self.h.x);
            let y = uniform(rng, -self.h.y, self.h.y);
            if unit(rng) * self.jac_max <= self.jac(x, y) {
                return Sample {
                    position: DVec3::new(x, y, self.f(x, y)),
                    normal: self.normal(x, y),
                };
            }
        }
    }

    fn aabb(&self) -> Aabb {
        Aabb {
            min: DVec3::new(-self.h.x, -self.h.y, self.zmin),
            max: DVec3::new(self.h.x, self.h.y, self.zmax),
        }
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

    fn mesh(&self, resolution: usize) -> Option<TriMesh> {
        // Four times the requested grid: the creases of `poly-part` meet the plane with
        // near-vertical walls, which a coarse grid cuts.
        let n = MESH_REFINE * resolution.max(2) + 1;
        let verts = self
            .grid(n, n)
            .expect("grid")
            .into_iter()
            .map(|s| s.position)
            .collect();
        let mut faces = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = (j * n + i) as u32;
                let (b, c, d) = (a + 1, a + 1 + n as u32, a + n as u32);
                faces.push([a, b, c]);
                faces.push([a, c, d]);
            }
        }
        Some(TriMesh::new(verts, faces).expect("valid stand-in mesh"))
    }

    fn grid(&self, nu: usize, nv: usize) -> Option<Vec<Sample>> {
        let (nu, nv) = (nu.max(2), nv.max(2));
        let mut out = Vec::with_capacity(nu * nv);
        for j in 0..nv {
            for i in 0..nu {
                let x = -self.h.x + 2.0 * self.h.x * i as f64 / (nu - 1) as f64;
                let y = -self.h.y + 2.0 * self.h.y * j as f64 / (nv - 1) as f64;
                out.push(Sample {
                    position: DVec3::new(x, y, self.f(x, y)),
                    normal: self.normal(x, y),
                });
            }
        }
        Some(out)
    }

    fn grid_dims(&self, count: usize) -> (usize, usize) {
        let r = self.h.x / self.h.y;
        let nv = ((count as f64 / r).sqrt().round() as usize).max(2);
        (((nv as f64) * r).round().max(2.0) as usize, nv)
    }

    fn ray(&self, origin: DVec3, dir: DVec3, max_t: f64) -> Option<Option<f64>> {
        // The signed height above the surface along the ray; first sign change inside
        // the rectangle, refined by bisection.
        let side = |t: f64| {
            let p = origin + dir * t;
            if p.x.abs() > self.h.x || p.y.abs() > self.h.y {
                None
            } else {
                Some(p.z - self.f(p.x, p.y))
            }
        };
        // March only inside the bounding box (slab test).
        let bb = self.aabb();
        let (mut t0, mut t1) = (0.0f64, max_t);
        for k in 0..3 {
            let (o, d) = (origin[k], dir[k]);
            if d.abs() < 1e-300 {
                if o < bb.min[k] || o > bb.max[k] {
                    return Some(None);
                }
            } else {
                let (a, b) = ((bb.min[k] - o) / d, (bb.max[k] - o) / d);
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
        }
        if t0 > t1 {
            return Some(None);
        }
        let dt = (bb.max - bb.min).length() / 800.0;
        let mut t = t0;
        let mut prev: Option<(f64, f64)> = None;
        while t <= t1 + dt {
            let s = side(t);
            if let (Some((tp, sp)), Some(sc)) = (prev, s)
                && sp.signum() != sc.signum()
            {
                let (mut a, mut b) = (tp, t);
                for _ in 0..60 {
                    let m = 0.5 * (a + b);
                    match side(m) {
                        Some(sm) if sm.signum() == sp.signum() => a = m,
                        _ => b = m,
                    }
                }
                return Some(Some(0.5 * (a + b)));
            }
            prev = s.map(|v| (t, v));
            t += dt;
        }
        Some(None)
    }
}
