//! Cube `[-1, 1]^3` with a cylindrical **blind** hole of radius `r` drilled along -z from
//! the top face to the depth `d` (floor at `z = 1 - d`): seed 002's cube with hole
//! (§10.2: side 9.8, radius 2.45, depth 4.9, i.e. `r = 0.5`, `d = 1` in these units).
//! Features: the 12 cube edges and 8 corners (90 deg), the convex top rim and the
//! concave floor rim (both 90 deg). Genus 0.
//!
//! The surface is the union of five full squares, the top square minus the open disk,
//! the wall (cylinder, `z in [1 - d, 1]`) and the floor disk; the exact closest point is
//! the nearest of the closest points of these eight patches (each in closed form).
//!
//! Normals on sharp edges: the patch that wins the distance comparison (first in the
//! order faces, wall, floor on ties); grid samples exactly on a feature get the
//! normalised sum of the incident patch normals.

use std::f64::consts::{PI, TAU};

use glam::{DVec2, DVec3};
use rand::Rng;
use reconbench_geom::Aabb;

use super::Geometry;
use crate::features::{Feature, FeatureGeom};
use crate::shape::{Sample, SurfacePoint};
use crate::util::{cumulative, pick_weighted, uniform};

/// The blind-hole cube (natural units: half side 1).
#[derive(Debug, Clone)]
pub struct BlindHoleCube {
    r: f64,
    d: f64,
    cum: Vec<f64>,
}

impl BlindHoleCube {
    /// Hole radius `r` in (0, 0.95], depth `d` in (0, 1.9] (checked by the catalogue).
    pub fn new(r: f64, d: f64) -> Self {
        // Patches: 0..6 the faces (axis = f / 2, sign from parity; face 5 = top, holed),
        // 6 the wall, 7 the floor.
        let mut w = vec![4.0; 6];
        w[5] = 4.0 - PI * r * r;
        w.push(TAU * r * d);
        w.push(PI * r * r);
        Self {
            r,
            d,
            cum: cumulative(&w),
        }
    }

    fn floor_z(&self) -> f64 {
        1.0 - self.d
    }

    /// Closest point of face `f` (axis `f / 2`, side `+-1`), the top face minus the disk.
    fn face_closest(&self, p: DVec3, f: usize) -> (DVec3, DVec3) {
        let axis = f / 2;
        let s = if f.is_multiple_of(2) { -1.0 } else { 1.0 };
        let mut q = p.clamp(DVec3::NEG_ONE, DVec3::ONE);
        q[axis] = s;
        if f == 5 {
            let xy = DVec2::new(q.x, q.y);
            let l = xy.length();
            if l < self.r {
                // Inside the hole's disk: the closest point of the holed square is the
                // radial projection onto the rim (the disk lies inside the square).
                let dir = if l > 0.0 { xy / l } else { DVec2::X };
                q.x = dir.x * self.r;
                q.y = dir.y * self.r;
            }
        }
        let mut n = DVec3::ZERO;
        n[axis] = s;
        (q, n)
    }
}

impl Geometry for BlindHoleCube {
    fn closest(&self, p: DVec3) -> SurfacePoint {
        let mut best = SurfacePoint {
            point: DVec3::ZERO,
            normal: DVec3::Z,
            distance: f64::INFINITY,
        };
        let mut consider = |q: DVec3, n: DVec3| {
            let dist = (p - q).length();
            if dist < best.distance {
                best = SurfacePoint {
                    point: q,
                    normal: n,
                    distance: dist,
                };
            }
        };
        for f in 0..6 {
            let (q, n) = self.face_closest(p, f);
            consider(q, n);
        }
        let xy = DVec2::new(p.x, p.y);
        let l = xy.length();
        let dir = if l > 0.0 { xy / l } else { DVec2::X };
        // Wall: radial projection, height clamped; its normal points to the axis.
        let zw = p.z.clamp(self.floor_z(), 1.0);
        consider(
            DVec3::new(dir.x * self.r, dir.y * self.r, zw),
            DVec3::new(-dir.x, -dir.y, 0.0),
        );
        // Floor: clamp into the disk; normal up (into the hole).
        let fl = if l > self.r { dir * self.r } else { xy };
        consider(DVec3::new(fl.x, fl.y, self.floor_z()), DVec3::Z);
        best
    }

    fn inside(&self, p: DVec3) -> bool {
        let in_cube = p.abs().cmplt(DVec3::ONE).all();
        let in_hole = p.x * p.x + p.y * p.y < self.r * self.r && p.z > self.floor_z();
        in_cube && !in_hole
    }

    fn sample(&self, rng: &mut dyn Rng) -> Sample {
        let k = pick_weighted(rng, &self.cum);
        match k {
            0..=5 => loop {
                let mut p = DVec3::new(
                    uniform(rng, -1.0, 1.0),
                    uniform(rng, -1.0, 1.0),
                    uniform(rng, -1.0, 1.0),
                );
                let axis = k / 2;
                let s = if k.is_multiple_of(2) { -1.0 } else { 1.0 };
                p[axis] = s;
                if k == 5 && p.x * p.x + p.y * p.y < self.r * self.r {
                    continue; // rejection: the top face minus the disk
                }
                let mut n = DVec3::ZERO;
                n[axis] = s;
                break Sample {
                    position: p,
                    normal: n,
                };
            },
            6 => {
                let t = uniform(rng, 0.0, TAU);
                let (sn, cs) = t.sin_cos();
                Sample {
                    position: DVec3::new(
                        self.r * cs,
                        self.r * sn,
                        uniform(rng, self.floor_z(), 1.0),
                    ),
                    normal: DVec3::new(-cs, -sn, 0.0),
                }
            }
            _ => {
                // Area-uniform in the disk: radius sqrt(U).
                let rho = self.r * uniform(rng, 0.0, 1.0).sqrt();
                let (sn, cs) = uniform(rng, 0.0, TAU).sin_cos();
                Sample {
                    position: DVec3::new(rho * cs, rho * sn, self.floor_z()),
                    normal: DVec3::Z,
                }
            }
        }
    }

    fn aabb(&self) -> Aabb {
        Aabb {
            min: DVec3::NEG_ONE,
            max: DVec3::ONE,
        }
    }

    fn area(&self) -> f64 {
        24.0 + TAU * self.r * self.d
    }

    fn genus(&self) -> u32 {
        0
    }

    fn features(&self) -> Vec<Feature> {
        let mut out = Vec::new();
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for su in [-1.0, 1.0] {
                for sv in [-1.0, 1.0] {
                    let mut a = DVec3::ZERO;
                    a[u] = su;
                    a[v] = sv;
                    a[axis] = -1.0;
                    let mut b = a;
                    b[axis] = 1.0;
                    out.push(Feature {
                        geom: FeatureGeom::Segment { a, b },
                        dihedral_deg: 90.0,
                    });
                }
            }
        }
        for k in 0..8 {
            let s = [k & 1, (k >> 1) & 1, (k >> 2) & 1].map(|b| if b == 1 { 1.0 } else { -1.0 });
            out.push(Feature {
                geom: FeatureGeom::Point(DVec3::from_array(s)),
                dihedral_deg: 90.0,
            });
        }
        for z in [1.0, self.floor_z()] {
            out.push(Feature {
                geom: FeatureGeom::Arc {
                    center: DVec3::new(0.0, 0.0, z),
                    u: DVec3::X,
                    v: DVec3::Y,
                    r: self.r,
                    t0: 0.0,
                    sweep: TAU,
                },
                dihedral_deg: 90.0,
            });
        }
        out
    }

    /// Grid with samples exactly on every feature (seed 002's Table 1-2 data): the cube
    /// lattice with `nu` points per edge (spacing `h = 2 / (nu - 1)`), top-face points
    /// within `r + h / 2` of the axis removed; `m = round(2 pi r / h)` samples on each
    /// rim and on each of the `round(d / h) - 1` wall rings between them; the floor as
    /// concentric rings of radius `r i / n_r` (`n_r = round(r / h)`) with
    /// `round(2 pi rho / h)` samples each, plus its centre. `nv` is ignored.
    fn grid(&self, nu: usize, _nv: usize) -> Option<Vec<Sample>> {
        let n = nu.max(2) - 1;
        let h = 2.0 / n as f64;
        let ni = n as i32;
        let mut out = Vec::new();
        let side = |c: i32| -> f64 {
            if c == 0 {
                -1.0
            } else if c == ni {
                1.0
            } else {
                0.0
            }
        };
        for k in 0..=ni {
            for j in 0..=ni {
                for i in 0..=ni {
                    let nrm = DVec3::new(side(i), side(j), side(k));
                    if nrm == DVec3::ZERO {
                        continue;
                    }
                    let p = DVec3::new(i as f64, j as f64, k as f64) * h - DVec3::ONE;
                    if k == ni && p.x.hypot(p.y) < self.r + 0.5 * h {
                        continue;
                    }
                    out.push(Sample {
                        position: p,
                        normal: nrm.normalize(),
                    });
                }
            }
        }
        let m = ((TAU * self.r / h).round() as usize).max(3);
        let nz = ((self.d / h).round() as usize).max(1);
        let z0 = self.floor_z();
        for jz in 0..=nz {
            let z = z0 + self.d * jz as f64 / nz as f64;
            for t in 0..m {
                let (sn, cs) = (TAU * t as f64 / m as f64).sin_cos();
                let wall = DVec3::new(-cs, -sn, 0.0);
                let normal = if jz == 0 || jz == nz {
                    // Rims: floor (+z, concave) or top face (+z, convex) and the wall.
                    (wall + DVec3::Z).normalize()
                } else {
                    wall
                };
                out.push(Sample {
                    position: DVec3::new(self.r * cs, self.r * sn, z),
                    normal,
                });
            }
        }
        let nr = ((self.r / h).round() as usize).max(1);
        out.push(Sample {
            position: DVec3::new(0.0, 0.0, z0),
            normal: DVec3::Z,
        });
        for ir in 1..nr {
            let rho = self.r * ir as f64 / nr as f64;
            let mr = ((TAU * rho / h).round() as usize).max(3);
            for t in 0..mr {
                let (sn, cs) = (TAU * t as f64 / mr as f64).sin_cos();
                out.push(Sample {
                    position: DVec3::new(rho * cs, rho * sn, z0),
                    normal: DVec3::Z,
                });
            }
        }
        Some(out)
    }

    /// Points per cube edge whose grid size is closest to `count`.
    fn grid_dims(&self, count: usize) -> (usize, usize) {
        let size = |n: usize| self.grid(n, n).map_or(0, |g| g.len());
        let mut best = 3;
        let mut best_size = size(best);
        for n in 4..2000 {
            let s = size(n);
            if s.abs_diff(count) < best_size.abs_diff(count) {
                best = n;
                best_size = s;
            }
            if s > count {
                break;
            }
        }
        (best, best)
    }
}
