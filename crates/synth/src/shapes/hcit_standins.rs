//! Scan-like stand-ins for the models of seed 003 (Sritrakulchai & Sangveraphunsiri,
//! Table 1; spec §6 item 1), in millimetres before normalisation:
//!
//! * `bolt-plate` (spare part, 150 x 100 mm): a flat open plate with two circular bolt
//!   holes of radius 8 mm: 3 boundary loops (the outer rim and the two holes);
//! * `eye-face` (human face 2, 200 x 240 mm): an open dome, the part of a sphere of
//!   radius 200 mm over a rectangle, with two round eye holes (radius 14 mm): 3 boundary
//!   loops;
//! * `grooved-handle` (pan handle): a closed capsule (radius 12 mm, 120 mm long) with
//!   three circumferential grooves of radius 3 mm (sharp 90-degree groove edges);
//! * `bottle`: a closed bottle of revolution (body, filleted base, shoulder, neck).
//!
//! The two open patches are height fields over a rectangle, cut by round holes (a disc
//! on the plane; on the sphere a spherical cap, whose rim is a circle). Their closest
//! points are exact: the projection onto the plane or sphere when it falls on the patch,
//! else the nearest point of the boundary circles and arcs (the distance along either
//! surface has no other critical point). Their parametric grid is the orthographic range
//! image from +z, the rows over y and columns over x, with the points in the holes left
//! out: a scan-like sampling. The two closed ones are [`Revolved`] profiles.

use std::f64::consts::{FRAC_PI_2, PI};

use glam::{DVec2, DVec3};
use rand::Rng;
use reconbench_geom::{Aabb, TriMesh};

use super::Geometry;
use super::revolved::Revolved;
use crate::geom2d::Elem2;
use crate::shape::{Sample, SurfacePoint};
use crate::util::{uniform, unit};

/// Grid refinement of the reference mesh over the requested resolution.
const MESH_REFINE: usize = 4;

/// The surface a [`HoledPatch`] lies on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Carrier {
    /// The plane z = 0.
    Plane,
    /// The sphere of radius `r` centred at (0, 0, `zc`); the patch is its upper part.
    Sphere {
        /// Radius.
        r: f64,
        /// Height of the centre.
        zc: f64,
    },
}

/// A round hole: on the plane the disc of radius `r` around `(c, 0)`; on the sphere the
/// spherical cap around the surface point above `c` whose rim is at angle `r / R` from
/// its axis (the same geodesic radius).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hole {
    /// Centre in the (x, y) domain.
    pub c: DVec2,
    /// Radius (geodesic on the sphere).
    pub r: f64,
}

/// An open patch over the rectangle `[-a, a] x [-b, b]` of the (x, y) domain, lifted onto
/// its carrier, with round holes; its boundary loops are the rectangle's rim and one per
/// hole (the holes lie inside the rectangle and apart).
#[derive(Debug, Clone)]
pub struct HoledPatch {
    carrier: Carrier,
    half: DVec2,
    holes: Vec<Hole>,
    /// Per hole: unit axis (from the sphere centre) and cosine of its angular radius.
    caps: Vec<(DVec3, f64)>,
    area: f64,
    jac_max: f64,
}

/// A boundary circle in 3-D: centre, unit axis, radius.
#[derive(Debug, Clone, Copy)]
struct Circle3 {
    centre: DVec3,
    axis: DVec3,
    radius: f64,
}

impl Circle3 {
    /// The point of the circle nearest to `p` and its direction from the centre.
    fn closest(&self, p: DVec3) -> DVec3 {
        let v = p - self.centre;
        let mut w = v - self.axis * v.dot(self.axis);
        if w.length_squared() < 1e-300 {
            // On the axis: every point is nearest; take one.
            w = self.axis.any_orthonormal_vector();
        }
        self.centre + w.normalize() * self.radius
    }
}

impl HoledPatch {
    /// A patch; `holes` must lie inside the rectangle and apart (checked by the caller's
    /// constants).
    pub fn new(carrier: Carrier, half: DVec2, holes: Vec<Hole>) -> Self {
        let caps = match carrier {
            Carrier::Plane => Vec::new(),
            Carrier::Sphere { r, .. } => holes
                .iter()
                .map(|h| {
                    // The axis through the surface point above the centre.
                    let z = (r * r - h.c.length_squared()).sqrt();
                    (DVec3::new(h.c.x, h.c.y, z).normalize(), (h.r / r).cos())
                })
                .collect(),
        };
        let mut s = Self {
            carrier,
            half,
            holes,
            caps,
            area: 0.0,
            jac_max: 1.0,
        };
        // Area of the rectangle patch by the midpoint rule on a fine grid (exact for the
        // plane), minus the holes' exact areas.
        let m = 1000;
        let (dx, dy) = (2.0 * half.x / m as f64, 2.0 * half.y / m as f64);
        let (mut area, mut jmax) = (0.0, 1.0f64);
        for j in 0..m {
            for i in 0..m {
                let q = DVec2::new(
                    -half.x + (i as f64 + 0.5) * dx,
                    -half.y + (j as f64 + 0.5) * dy,
                );
                let jac = s.jac(q);
                area += jac * dx * dy;
                jmax = jmax.max(jac);
            }
        }
        // The corners have the steepest slope.
        jmax = jmax.max(s.jac(half));
        for h in &s.holes {
            area -= match carrier {
                Carrier::Plane => PI * h.r * h.r,
                Carrier::Sphere { r, .. } => 2.0 * PI * r * r * (1.0 - (h.r / r).cos()),
            };
        }
        s.area = area;
        s.jac_max = jmax;
        s
    }

    /// The spare-part stand-in.
    pub fn bolt_plate() -> Self {
        Self::new(
            Carrier::Plane,
            DVec2::new(75.0, 50.0),
            vec![
                Hole {
                    c: DVec2::new(-40.0, 5.0),
                    r: 8.0,
                },
                Hole {
                    c: DVec2::new(40.0, 5.0),
                    r: 8.0,
                },
            ],
        )
    }

    /// The face-2 stand-in.
    pub fn eye_face() -> Self {
        let r = 200.0;
        Self::new(
            Carrier::Sphere { r, zc: -r },
            DVec2::new(100.0, 120.0),
            vec![
                Hole {
                    c: DVec2::new(-38.0, 30.0),
                    r: 14.0,
                },
                Hole {
                    c: DVec2::new(38.0, 30.0),
                    r: 14.0,
                },
            ],
        )
    }

    /// Height of the carrier over `q`.
    fn z(&self, q: DVec2) -> f64 {
        match self.carrier {
            Carrier::Plane => 0.0,
            Carrier::Sphere { r, zc } => zc + (r * r - q.length_squared()).max(0.0).sqrt(),
        }
    }

    fn lift(&self, q: DVec2) -> DVec3 {
        DVec3::new(q.x, q.y, self.z(q))
    }

    /// Unit normal of the carrier at the surface point `x` (pointing up).
    fn normal(&self, x: DVec3) -> DVec3 {
        match self.carrier {
            Carrier::Plane => DVec3::Z,
            Carrier::Sphere { zc, .. } => (x - DVec3::new(0.0, 0.0, zc)).normalize(),
        }
    }

    /// Area element of the lift (1 / n_z).
    fn jac(&self, q: DVec2) -> f64 {
        match self.carrier {
            Carrier::Plane => 1.0,
            Carrier::Sphere { r, .. } => r / (r * r - q.length_squared()).sqrt(),
        }
    }

    /// Whether the surface point `x` (on the carrier) lies in hole `k`.
    fn in_hole(&self, k: usize, x: DVec3) -> bool {
        let h = &self.holes[k];
        match self.carrier {
            Carrier::Plane => (DVec2::new(x.x, x.y) - h.c).length_squared() < h.r * h.r,
            Carrier::Sphere { r, zc } => {
                let (axis, cosb) = self.caps[k];
                (x - DVec3::new(0.0, 0.0, zc)).dot(axis) > r * cosb
            }
        }
    }

    /// Whether the carrier point `x` belongs to the patch.
    fn on_patch(&self, x: DVec3) -> bool {
        let upper = match self.carrier {
            Carrier::Plane => true,
            Carrier::Sphere { zc, .. } => x.z > zc,
        };
        upper
            && x.x.abs() <= self.half.x
            && x.y.abs() <= self.half.y
            && (0..self.holes.len()).all(|k| !self.in_hole(k, x))
    }

    /// The rim circle of hole `k`.
    fn rim(&self, k: usize) -> Circle3 {
        let h = &self.holes[k];
        match self.carrier {
            Carrier::Plane => Circle3 {
                centre: DVec3::new(h.c.x, h.c.y, 0.0),
                axis: DVec3::Z,
                radius: h.r,
            },
            Carrier::Sphere { r, zc } => {
                let (axis, cosb) = self.caps[k];
                Circle3 {
                    centre: DVec3::new(0.0, 0.0, zc) + axis * (r * cosb),
                    axis,
                    radius: r * (1.0 - cosb * cosb).sqrt(),
                }
            }
        }
    }

    /// Nearest point to `p` of the rectangle's rim edge on the line `coord = side`
    /// (`coord` 0 = x, 1 = y): a segment on the plane, a circular arc on the sphere,
    /// clamped to the edge's end points.
    fn rect_edge_closest(&self, p: DVec3, coord: usize, side: f64) -> DVec3 {
        let other = 1 - coord;
        let lim = self.half[other];
        let at = |t: f64| {
            let mut q = DVec2::ZERO;
            q[coord] = side;
            q[other] = t;
            self.lift(q)
        };
        match self.carrier {
            Carrier::Plane => at(p[other].clamp(-lim, lim)),
            Carrier::Sphere { r, zc } => {
                // The circle in the plane coord = side: centre (side, 0, zc) in that
                // plane, radius sqrt(r^2 - side^2); the arc is its upper part with
                // |t| <= lim.
                let rr = (r * r - side * side).sqrt();
                let (u, v) = (p[other], p.z - zc);
                let ang = if u == 0.0 && v == 0.0 {
                    FRAC_PI_2
                } else {
                    v.atan2(u)
                };
                let amax = (lim / rr).acos();
                // Arc angles from amax (t = +lim) to pi - amax (t = -lim).
                let a = ang.clamp(amax, PI - amax);
                let a = if ang < -FRAC_PI_2 { PI - amax } else { a };
                let mut x = DVec3::ZERO;
                x[coord] = side;
                x[other] = rr * a.cos();
                x.z = zc + rr * a.sin();
                x
            }
        }
    }

    /// Whether the (x, y) domain point `q` lies in a hole (for grids and meshes).
    fn q_in_hole(&self, q: DVec2) -> Option<usize> {
        let x = self.lift(q);
        (0..self.holes.len()).find(|&k| self.in_hole(k, x))
    }
}

impl Geometry for HoledPatch {
    fn closest(&self, p: DVec3) -> SurfacePoint {
        let proj = match self.carrier {
            Carrier::Plane => DVec3::new(p.x, p.y, 0.0),
            Carrier::Sphere { r, zc } => {
                let c = DVec3::new(0.0, 0.0, zc);
                let v = p - c;
                if v.length_squared() > 0.0 {
                    c + v.normalize() * r
                } else {
                    c + DVec3::Z * r
                }
            }
        };
        let best = if self.on_patch(proj) {
            proj
        } else {
            // The nearest point of the boundary: rectangle rim edges and hole rims.
            let mut cands = vec![
                self.rect_edge_closest(p, 0, self.half.x),
                self.rect_edge_closest(p, 0, -self.half.x),
                self.rect_edge_closest(p, 1, self.half.y),
                self.rect_edge_closest(p, 1, -self.half.y),
            ];
            cands.extend((0..self.holes.len()).map(|k| self.rim(k).closest(p)));
            cands
                .into_iter()
                .min_by(|a, b| {
                    (*a - p)
                        .length_squared()
                        .total_cmp(&(*b - p).length_squared())
                })
                .expect("candidates")
        };
        SurfacePoint {
            point: best,
            normal: self.normal(best),
            distance: (p - best).length(),
        }
    }

    fn sample(&self, rng: &mut dyn Rng) -> Sample {
        loop {
            let q = DVec2::new(
                uniform(rng, -self.half.x, self.half.x),
                uniform(rng, -self.half.y, self.half.y),
            );
            if unit(rng) * self.jac_max <= self.jac(q) && self.q_in_hole(q).is_none() {
                let x = self.lift(q);
                return Sample {
                    position: x,
                    normal: self.normal(x),
                };
            }
        }
    }

    fn aabb(&self) -> Aabb {
        let zmin = self.z(self.half);
        let zmax = self.z(DVec2::ZERO);
        Aabb {
            min: DVec3::new(-self.half.x, -self.half.y, zmin),
            max: DVec3::new(self.half.x, self.half.y, zmax),
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

    fn boundary_loops(&self) -> u32 {
        1 + self.holes.len() as u32
    }

    fn mesh(&self, resolution: usize) -> Option<TriMesh> {
        Some(self.holed_grid_mesh(MESH_REFINE * resolution.max(2)))
    }

    fn grid(&self, nu: usize, nv: usize) -> Option<Vec<Sample>> {
        let (nu, nv) = (nu.max(2), nv.max(2));
        let mut out = Vec::with_capacity(nu * nv);
        for j in 0..nv {
            for i in 0..nu {
                let q = DVec2::new(
                    -self.half.x + 2.0 * self.half.x * i as f64 / (nu - 1) as f64,
                    -self.half.y + 2.0 * self.half.y * j as f64 / (nv - 1) as f64,
                );
                if self.q_in_hole(q).is_none() {
                    let x = self.lift(q);
                    out.push(Sample {
                        position: x,
                        normal: self.normal(x),
                    });
                }
            }
        }
        Some(out)
    }

    fn grid_dims(&self, count: usize) -> (usize, usize) {
        // Enough grid nodes that about `count` fall outside the holes.
        let hole_share: f64 = self.holes.iter().map(|h| PI * h.r * h.r).sum::<f64>()
            / (4.0 * self.half.x * self.half.y);
        let nodes = count as f64 / (1.0 - hole_share);
        let ratio = self.half.x / self.half.y;
        let nv = ((nodes / ratio).sqrt().round() as usize).max(2);
        (((nv as f64) * ratio).round().max(2.0) as usize, nv)
    }

    fn ray(&self, origin: DVec3, dir: DVec3, max_t: f64) -> Option<Option<f64>> {
        let mut ts: Vec<f64> = match self.carrier {
            Carrier::Plane => {
                if dir.z == 0.0 {
                    Vec::new()
                } else {
                    vec![-origin.z / dir.z]
                }
            }
            Carrier::Sphere { r, zc } => {
                let o = origin - DVec3::new(0.0, 0.0, zc);
                let b = o.dot(dir);
                let disc = b * b - (o.length_squared() - r * r);
                if disc < 0.0 {
                    Vec::new()
                } else {
                    let s = disc.sqrt();
                    // The nearer root without cancellation, then the other.
                    let q = -b - s.copysign(b);
                    let c = o.length_squared() - r * r;
                    let (t0, t1) = if q != 0.0 { (q, c / q) } else { (-b, -b) };
                    vec![t0.min(t1), t0.max(t1)]
                }
            }
        };
        ts.retain(|&t| t >= 0.0 && t <= max_t);
        Some(ts.into_iter().find(|&t| {
            let x = origin + dir * t;
            let on = match self.carrier {
                Carrier::Plane => DVec3::new(x.x, x.y, 0.0),
                Carrier::Sphere { .. } => self.closest_on_carrier(x),
            };
            self.on_patch(on)
        }))
    }
}

impl HoledPatch {
    /// Projection onto the carrier (for points already on it up to rounding).
    fn closest_on_carrier(&self, x: DVec3) -> DVec3 {
        match self.carrier {
            Carrier::Plane => DVec3::new(x.x, x.y, 0.0),
            Carrier::Sphere { r, zc } => {
                let c = DVec3::new(0.0, 0.0, zc);
                c + (x - c).normalize() * r
            }
        }
    }

    /// The reference mesh: an `n`-cell grid over the rectangle, every cell that touches a
    /// hole removed (whole rows of cells, contiguous, so no vertex is pinched) and the
    /// vertices left on a hole's rim loop moved onto the rim circle.
    fn holed_grid_mesh(&self, n: usize) -> TriMesh {
        let ratio = self.half.x / self.half.y;
        let (nx, ny) = if ratio >= 1.0 {
            (n, ((n as f64 / ratio).round() as usize).max(2))
        } else {
            (((n as f64 * ratio).round() as usize).max(2), n)
        };
        let q_at = |i: usize, j: usize| {
            DVec2::new(
                -self.half.x + 2.0 * self.half.x * i as f64 / nx as f64,
                -self.half.y + 2.0 * self.half.y * j as f64 / ny as f64,
            )
        };
        let vid = |i: usize, j: usize| j * (nx + 1) + i;
        let hole_of: Vec<Option<usize>> = (0..=ny)
            .flat_map(|j| (0..=nx).map(move |i| (i, j)))
            .map(|(i, j)| self.q_in_hole(q_at(i, j)))
            .collect();
        // A cell is removed when a corner lies in a hole or a hole centre lies in it.
        let removed = |i: usize, j: usize| -> Option<usize> {
            for (a, b) in [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)] {
                if let Some(k) = hole_of[vid(a, b)] {
                    return Some(k);
                }
            }
            let (lo, hi) = (q_at(i, j), q_at(i + 1, j + 1));
            self.holes
                .iter()
                .position(|h| h.c.cmpge(lo).all() && h.c.cmplt(hi).all())
        };
        let mut cell_hole = vec![None; nx * ny];
        for j in 0..ny {
            for i in 0..nx {
                cell_hole[j * nx + i] = removed(i, j);
            }
        }
        let mut snap: Vec<Option<usize>> = vec![None; (nx + 1) * (ny + 1)];
        let mut used = vec![false; (nx + 1) * (ny + 1)];
        let mut faces = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let corners = [vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)];
                match cell_hole[j * nx + i] {
                    Some(k) => {
                        for c in corners {
                            snap[c] = Some(k);
                        }
                    }
                    None => {
                        for c in corners {
                            used[c] = true;
                        }
                        let [a, b, c, d] = corners.map(|v| v as u32);
                        faces.push([a, b, c]);
                        faces.push([a, c, d]);
                    }
                }
            }
        }
        let mut remap = vec![u32::MAX; used.len()];
        let mut verts = Vec::new();
        for j in 0..=ny {
            for i in 0..=nx {
                let v = vid(i, j);
                if !used[v] {
                    continue;
                }
                let x = self.lift(q_at(i, j));
                let x = match snap[v] {
                    Some(k) => self.rim(k).closest(x),
                    None => x,
                };
                remap[v] = verts.len() as u32;
                verts.push(x);
            }
        }
        for f in &mut faces {
            *f = f.map(|v| remap[v as usize]);
        }
        TriMesh::new(verts, faces).expect("valid holed patch mesh")
    }
}

/// The grooved pan-handle stand-in: a capsule of radius 12 mm along z (cylinder from
/// z = -48 to 48 mm, hemispherical ends) with three grooves of radius 3 mm at z = -24,
/// 0 and 24 mm.
pub fn grooved_handle() -> Revolved {
    let (rad, half, g) = (12.0, 48.0, 3.0);
    let mut profile = vec![Elem2::Arc {
        c: DVec2::new(0.0, -half),
        r: rad,
        a0: -FRAC_PI_2,
        sweep: FRAC_PI_2,
    }];
    let mut z = -half;
    for zg in [-24.0, 0.0, 24.0] {
        profile.push(Elem2::Seg {
            a: DVec2::new(rad, z),
            b: DVec2::new(rad, zg - g),
        });
        // Concave (clockwise) semicircle cut into the wall.
        profile.push(Elem2::Arc {
            c: DVec2::new(rad, zg),
            r: g,
            a0: -FRAC_PI_2,
            sweep: -PI,
        });
        z = zg + g;
    }
    profile.push(Elem2::Seg {
        a: DVec2::new(rad, z),
        b: DVec2::new(rad, half),
    });
    profile.push(Elem2::Arc {
        c: DVec2::new(0.0, half),
        r: rad,
        a0: 0.0,
        sweep: FRAC_PI_2,
    });
    Revolved::new(profile, false)
}

/// The bottle stand-in: base radius 30 mm with a 5 mm fillet at z = -100 mm, straight
/// body to z = 20 mm, a quarter-circle shoulder (radius 20 mm) to the neck (radius 10 mm)
/// and a flat top at z = 60 mm.
pub fn bottle() -> Revolved {
    let profile = vec![
        Elem2::Seg {
            a: DVec2::new(0.0, -100.0),
            b: DVec2::new(25.0, -100.0),
        },
        Elem2::Arc {
            c: DVec2::new(25.0, -95.0),
            r: 5.0,
            a0: -FRAC_PI_2,
            sweep: FRAC_PI_2,
        },
        Elem2::Seg {
            a: DVec2::new(30.0, -95.0),
            b: DVec2::new(30.0, 20.0),
        },
        Elem2::Arc {
            c: DVec2::new(10.0, 20.0),
            r: 20.0,
            a0: 0.0,
            sweep: FRAC_PI_2,
        },
        Elem2::Seg {
            a: DVec2::new(10.0, 40.0),
            b: DVec2::new(10.0, 60.0),
        },
        Elem2::Seg {
            a: DVec2::new(10.0, 60.0),
            b: DVec2::new(0.0, 60.0),
        },
    ];
    Revolved::new(profile, false)
}
