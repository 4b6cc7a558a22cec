//! Axis-aligned box with exact sharp edges and corners.

use std::collections::HashMap;

use glam::{DVec3, IVec3};
use rand::Rng;
use reconbench_geom::{Aabb, TriMesh};

use super::Geometry;
use crate::features::{Feature, FeatureGeom};
use crate::shape::{Sample, SurfacePoint};
use crate::util::{cumulative, pick_weighted, uniform};

/// Box `[-h, h]` (half-extents `h`).
///
/// Normals on edges and corners: [`Geometry::closest`] returns the normal of the face
/// whose outward excess `|p_i| - h_i` is largest (lowest axis on ties); parametric grid
/// samples exactly on an edge or corner get the normalised sum of the incident face
/// normals (what seed 000's mesh-derived reference normals give).
#[derive(Debug, Clone)]
pub struct BoxShape {
    h: DVec3,
    cum: Vec<f64>,
}

impl BoxShape {
    /// A box with half-extents `h`.
    pub fn new(h: DVec3) -> Self {
        let w = [
            h.y * h.z,
            h.y * h.z,
            h.x * h.z,
            h.x * h.z,
            h.x * h.y,
            h.x * h.y,
        ];
        Self {
            h,
            cum: cumulative(&w),
        }
    }

    /// The surface points of the lattice with `m + 1` points per edge on every axis.
    fn lattice(&self, m: usize) -> Vec<IVec3> {
        let m = m as i32;
        let mut out = Vec::new();
        for k in 0..=m {
            for j in 0..=m {
                for i in 0..=m {
                    if i == 0 || j == 0 || k == 0 || i == m || j == m || k == m {
                        out.push(IVec3::new(i, j, k));
                    }
                }
            }
        }
        out
    }

    fn lattice_point(&self, c: IVec3, m: usize) -> DVec3 {
        -self.h + 2.0 * self.h * c.as_dvec3() / m as f64
    }
}

impl Geometry for BoxShape {
    fn closest(&self, p: DVec3) -> SurfacePoint {
        let a = p.abs();
        let excess = a - self.h;
        let axis = if excess.x >= excess.y && excess.x >= excess.z {
            0
        } else if excess.y >= excess.z {
            1
        } else {
            2
        };
        let sign = |v: f64| if v < 0.0 { -1.0 } else { 1.0 };
        let mut normal = DVec3::ZERO;
        normal[axis] = sign(p[axis]);
        let point = if excess.max_element() > 0.0 {
            p.clamp(-self.h, self.h)
        } else {
            // Inside: project onto the nearest face.
            let mut q = p;
            q[axis] = sign(p[axis]) * self.h[axis];
            q
        };
        SurfacePoint {
            point,
            normal,
            distance: (p - point).length(),
        }
    }

    fn inside(&self, p: DVec3) -> bool {
        p.abs().cmplt(self.h).all()
    }

    fn sample(&self, rng: &mut dyn Rng) -> Sample {
        let f = pick_weighted(rng, &self.cum);
        let axis = f / 2;
        let s = if f.is_multiple_of(2) { -1.0 } else { 1.0 };
        let mut p = DVec3::new(
            uniform(rng, -self.h.x, self.h.x),
            uniform(rng, -self.h.y, self.h.y),
            uniform(rng, -self.h.z, self.h.z),
        );
        p[axis] = s * self.h[axis];
        let mut n = DVec3::ZERO;
        n[axis] = s;
        Sample {
            position: p,
            normal: n,
        }
    }

    fn aabb(&self) -> Aabb {
        Aabb {
            min: -self.h,
            max: self.h,
        }
    }

    fn area(&self) -> f64 {
        8.0 * (self.h.x * self.h.y + self.h.y * self.h.z + self.h.x * self.h.z)
    }

    fn genus(&self) -> u32 {
        0
    }

    fn features(&self) -> Vec<Feature> {
        let mut out = Vec::new();
        let corner = |s: [f64; 3]| DVec3::from_array(s) * self.h;
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for su in [-1.0, 1.0] {
                for sv in [-1.0, 1.0] {
                    let mut a = [0.0; 3];
                    a[u] = su;
                    a[v] = sv;
                    a[axis] = -1.0;
                    let mut b = a;
                    b[axis] = 1.0;
                    out.push(Feature {
                        geom: FeatureGeom::Segment {
                            a: corner(a),
                            b: corner(b),
                        },
                        dihedral_deg: 90.0,
                    });
                }
            }
        }
        for k in 0..8 {
            let s = [k & 1, (k >> 1) & 1, (k >> 2) & 1].map(|b| if b == 1 { 1.0 } else { -1.0 });
            out.push(Feature {
                geom: FeatureGeom::Point(corner(s)),
                dihedral_deg: 90.0,
            });
        }
        out
    }

    /// Uniform grid of `resolution` cells per edge on every face, shared edge vertices.
    fn mesh(&self, resolution: usize) -> Option<TriMesh> {
        let m = resolution.max(1);
        let pts = self.lattice(m);
        let index: HashMap<IVec3, u32> = pts
            .iter()
            .enumerate()
            .map(|(i, &c)| (c, i as u32))
            .collect();
        let verts = pts.iter().map(|&c| self.lattice_point(c, m)).collect();
        let mut faces = Vec::new();
        let mi = m as i32;
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for side in [0, mi] {
                for a in 0..mi {
                    for b in 0..mi {
                        let at = |da: i32, db: i32| {
                            let mut c = IVec3::ZERO;
                            c[axis] = side;
                            c[u] = a + da;
                            c[v] = b + db;
                            index[&c]
                        };
                        let (p00, p10, p11, p01) = (at(0, 0), at(1, 0), at(1, 1), at(0, 1));
                        // (u, v, axis) is right-handed: counter-clockwise in (u, v) faces +axis.
                        if side == mi {
                            faces.push([p00, p10, p11]);
                            faces.push([p00, p11, p01]);
                        } else {
                            faces.push([p00, p11, p10]);
                            faces.push([p00, p01, p11]);
                        }
                    }
                }
            }
        }
        Some(TriMesh::new(verts, faces).expect("valid box mesh"))
    }

    /// `nu` points per edge on every axis (seed 000's cube: 13 per edge = 866 points);
    /// `nv` is ignored.
    fn grid(&self, nu: usize, _nv: usize) -> Option<Vec<Sample>> {
        let m = nu.max(2) - 1;
        Some(
            self.lattice(m)
                .into_iter()
                .map(|c| {
                    let n = DVec3::new(face_sign(c.x, m), face_sign(c.y, m), face_sign(c.z, m));
                    Sample {
                        position: self.lattice_point(c, m),
                        normal: n.normalize(),
                    }
                })
                .collect(),
        )
    }

    /// Points per edge `n` with `6 (n-2)^2 + 12 (n-2) + 8` closest to `count`.
    fn grid_dims(&self, count: usize) -> (usize, usize) {
        let total = |n: usize| if n < 2 { 0 } else { n.pow(3) - (n - 2).pow(3) };
        let mut best = 2;
        for n in 2..2000 {
            if total(n).abs_diff(count) < total(best).abs_diff(count) {
                best = n;
            }
            if total(n) > count {
                break;
            }
        }
        (best, best)
    }

    fn ray(&self, origin: DVec3, dir: DVec3, max_t: f64) -> Option<Option<f64>> {
        // Slab method; a ray starting inside hits the exit face.
        let inv = dir.recip();
        let t1 = (-self.h - origin) * inv;
        let t2 = (self.h - origin) * inv;
        let tmin = t1.min(t2).max_element();
        let tmax = t1.max(t2).min_element();
        if tmax < tmin.max(0.0) {
            return Some(None);
        }
        let t = if tmin >= 0.0 { tmin } else { tmax };
        Some(if t <= max_t { Some(t) } else { None })
    }
}

fn face_sign(c: i32, m: usize) -> f64 {
    if c == 0 {
        -1.0
    } else if c == m as i32 {
        1.0
    } else {
        0.0
    }
}
