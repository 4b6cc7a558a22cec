//! Right prisms over a planar region bounded by segments and arcs: the extrusion of `S`
//! (in the xy plane) over `z in [z0, z1]`. Exact closest point: the nearer of the wall
//! (closest boundary point of `S`, height clamped) and the two caps (clamped into `S`).
//! Sharp features: the boundary loops at both caps (90 degrees) and a vertical edge at
//! every corner of `S` (its dihedral angle). Genus = number of holes of `S`.
//!
//! Normals on sharp edges: the wall's, unless a cap is strictly closer.

use glam::{DVec2, DVec3};
use rand::Rng;
use reconbench_geom::Aabb;

use super::Geometry;
use crate::features::{Feature, FeatureGeom, dihedral_deg};
use crate::geom2d::{Elem2, Region2};
use crate::shape::{Sample, SurfacePoint};
use crate::util::{cumulative, pick_weighted, uniform};

/// An extruded region.
#[derive(Debug, Clone)]
pub struct Prism {
    region: Region2,
    z0: f64,
    z1: f64,
    elems: Vec<Elem2>,
    cum: Vec<f64>,
    area: f64,
}

impl Prism {
    /// Extrusion of `region` over `[z0, z1]`.
    pub fn new(region: Region2, z0: f64, z1: f64) -> Result<Self, String> {
        region.check_closed()?;
        let a = region.area();
        let elems: Vec<Elem2> = region.elems().copied().collect();
        let mut w = vec![a, a];
        w.extend(elems.iter().map(|e| e.length() * (z1 - z0)));
        let area = w.iter().sum();
        Ok(Self {
            cum: cumulative(&w),
            region,
            z0,
            z1,
            elems,
            area,
        })
    }
}

fn lift(q: DVec2, z: f64) -> DVec3 {
    DVec3::new(q.x, q.y, z)
}

impl Geometry for Prism {
    fn closest(&self, p: DVec3) -> SurfacePoint {
        let q = DVec2::new(p.x, p.y);
        let cb = self.region.closest_boundary(q);
        let wall = lift(cb.point, p.z.clamp(self.z0, self.z1));
        let mut best = SurfacePoint {
            point: wall,
            normal: lift(cb.normal, 0.0),
            distance: (p - wall).length(),
        };
        let c = if self.region.contains(q) { q } else { cb.point };
        for (z, nz) in [(self.z0, -1.0), (self.z1, 1.0)] {
            let cap = lift(c, z);
            let d = (p - cap).length();
            if d < best.distance {
                best = SurfacePoint {
                    point: cap,
                    normal: DVec3::Z * nz,
                    distance: d,
                };
            }
        }
        best
    }

    fn inside(&self, p: DVec3) -> bool {
        p.z > self.z0 && p.z < self.z1 && self.region.contains(DVec2::new(p.x, p.y))
    }

    fn sample(&self, rng: &mut dyn Rng) -> Sample {
        let k = pick_weighted(rng, &self.cum);
        if k < 2 {
            let q = self.region.sample_interior(rng);
            let (z, nz) = if k == 0 {
                (self.z0, -1.0)
            } else {
                (self.z1, 1.0)
            };
            return Sample {
                position: lift(q, z),
                normal: DVec3::Z * nz,
            };
        }
        let (q, n) = self.elems[k - 2].sample(rng);
        Sample {
            position: lift(q, uniform(rng, self.z0, self.z1)),
            normal: lift(n, 0.0),
        }
    }

    fn aabb(&self) -> Aabb {
        let (lo, hi) = self.region.bounds();
        Aabb {
            min: lift(lo, self.z0),
            max: lift(hi, self.z1),
        }
    }

    fn area(&self) -> f64 {
        self.area
    }

    fn genus(&self) -> u32 {
        (self.region.loops.len() - 1) as u32
    }

    fn features(&self) -> Vec<Feature> {
        let mut out = Vec::new();
        for z in [self.z0, self.z1] {
            for e in &self.elems {
                let geom = match *e {
                    Elem2::Seg { a, b } => FeatureGeom::Segment {
                        a: lift(a, z),
                        b: lift(b, z),
                    },
                    Elem2::Arc { c, r, a0, sweep } => FeatureGeom::Arc {
                        center: lift(c, z),
                        u: DVec3::X,
                        v: DVec3::Y,
                        r,
                        t0: if sweep >= 0.0 { a0 } else { a0 + sweep },
                        sweep: sweep.abs(),
                    },
                };
                out.push(Feature {
                    geom,
                    dihedral_deg: 90.0,
                });
            }
        }
        for j in self.region.junctions() {
            if j.is_corner() {
                out.push(Feature {
                    geom: FeatureGeom::Segment {
                        a: lift(j.point, self.z0),
                        b: lift(j.point, self.z1),
                    },
                    dihedral_deg: dihedral_deg(lift(j.n_in, 0.0), lift(j.n_out, 0.0)),
                });
                for z in [self.z0, self.z1] {
                    out.push(Feature {
                        geom: FeatureGeom::Point(lift(j.point, z)),
                        dihedral_deg: dihedral_deg(lift(j.n_in, 0.0), lift(j.n_out, 0.0)).min(90.0),
                    });
                }
            }
        }
        out
    }
}
