//! Offset solids of a planar region: `{ p : dist(p, S) <= r }` for a region `S` in the
//! plane `z = 0` bounded by segments and arcs. The surface is C1: flat caps `z = +-r`
//! over `S`, half-tubes (cylinder / torus patches) around the boundary, spherical lunes
//! at convex corners. Its distance field is exact in closed form,
//! `d(p) = |dist(p, S) - r|`, the normal is the gradient of `dist(p, S)`. The genus is the
//! number of holes of `S`. Valid while `r` is below the reach of `S` (concave arcs and
//! holes of radius > `r`, no concave corners), which the constructor checks.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use glam::{DVec2, DVec3};
use rand::Rng;
use reconbench_geom::Aabb;

use super::Geometry;
use crate::geom2d::{Elem2, Junction, Region2};
use crate::shape::{Sample, SurfacePoint};
use crate::util::{cumulative, pick_weighted, uniform, unit, unit_vector};

#[derive(Debug, Clone, Copy)]
enum Piece {
    Cap(f64),
    Tube(Elem2),
    Lune(Junction),
}

/// The offset of a planar region by `r`.
#[derive(Debug, Clone)]
pub struct Slab {
    region: Region2,
    r: f64,
    pieces: Vec<Piece>,
    weights: Vec<f64>,
    cum: Vec<f64>,
}

impl Slab {
    /// Offset of `region` (one outer loop, any number of hole loops) by `r`.
    pub fn new(region: Region2, r: f64) -> Result<Self, String> {
        region.check_closed()?;
        let mut pieces = vec![Piece::Cap(1.0), Piece::Cap(-1.0)];
        let mut weights = vec![region.area(); 2];
        for e in region.elems() {
            let w = match *e {
                Elem2::Seg { a, b } => PI * r * (b - a).length(),
                Elem2::Arc { r: rho, sweep, .. } => {
                    if sweep < 0.0 && rho <= r {
                        return Err(format!("concave arc of radius {rho} <= offset {r}"));
                    }
                    sweep.abs() * r * (PI * rho + 2.0 * r * sweep.signum())
                }
            };
            pieces.push(Piece::Tube(*e));
            weights.push(w);
        }
        for j in region.junctions() {
            if j.turn < -1e-9 {
                return Err(format!(
                    "concave corner at {} (fillet it with a radius > {r})",
                    j.point
                ));
            }
            if j.turn > 1e-9 {
                pieces.push(Piece::Lune(j));
                weights.push(2.0 * j.turn * r * r);
            }
        }
        let cum = cumulative(&weights);
        Ok(Self {
            region,
            r,
            pieces,
            weights,
            cum,
        })
    }

    /// Closest point of the region (in the plane) to `p`.
    fn base(&self, p: DVec3) -> DVec3 {
        let c = self.region.clamp(DVec2::new(p.x, p.y));
        DVec3::new(c.x, c.y, 0.0)
    }
}

impl Geometry for Slab {
    fn closest(&self, p: DVec3) -> SurfacePoint {
        let b = self.base(p);
        let v = p - b;
        let d = v.length();
        let n = if d > 0.0 { v / d } else { DVec3::Z };
        SurfacePoint {
            point: b + n * self.r,
            normal: n,
            distance: (d - self.r).abs(),
        }
    }

    fn inside(&self, p: DVec3) -> bool {
        (p - self.base(p)).length() < self.r
    }

    fn sample(&self, rng: &mut dyn Rng) -> Sample {
        let r = self.r;
        let (base, n) = match self.pieces[pick_weighted(rng, &self.cum)] {
            Piece::Cap(s) => {
                let q = self.region.sample_interior(rng);
                (DVec3::new(q.x, q.y, 0.0), DVec3::Z * s)
            }
            Piece::Tube(e) => {
                let (rho, sigma) = match e {
                    Elem2::Arc { r: rho, sweep, .. } => (rho, sweep.signum()),
                    Elem2::Seg { .. } => (f64::INFINITY, 0.0),
                };
                let psi = loop {
                    let psi = uniform(rng, -FRAC_PI_2, FRAC_PI_2);
                    if !rho.is_finite() || unit(rng) * (rho + r) <= rho + sigma * r * psi.cos() {
                        break psi;
                    }
                };
                let (q, n2) = e.sample(rng);
                (
                    DVec3::new(q.x, q.y, 0.0),
                    DVec3::new(n2.x, n2.y, 0.0) * psi.cos() + DVec3::Z * psi.sin(),
                )
            }
            Piece::Lune(j) => loop {
                let w = unit_vector(rng);
                let h = DVec2::new(w.x, w.y);
                let ang = j.n_in.perp_dot(h).atan2(j.n_in.dot(h)).rem_euclid(TAU);
                if ang <= j.turn {
                    break (DVec3::new(j.point.x, j.point.y, 0.0), w);
                }
            },
        };
        Sample {
            position: base + n * r,
            normal: n,
        }
    }

    fn aabb(&self) -> Aabb {
        let (lo, hi) = self.region.bounds();
        Aabb {
            min: DVec3::new(lo.x - self.r, lo.y - self.r, -self.r),
            max: DVec3::new(hi.x + self.r, hi.y + self.r, self.r),
        }
    }

    fn area(&self) -> f64 {
        self.weights.iter().sum()
    }

    fn genus(&self) -> u32 {
        (self.region.loops.len() - 1) as u32
    }
}
