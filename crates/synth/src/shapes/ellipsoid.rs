//! Ellipsoid `(x/a)^2 + (y/b)^2 + (z/c)^2 = 1` with Eberly's robust closest point:
//! bisection on the Lagrange parameter to machine precision ("Distance from a Point to
//! an Ellipse, an Ellipsoid, or a Hyperellipsoid", Geometric Tools, 2013).

use std::f64::consts::{PI, TAU};

use glam::DVec3;
use rand::Rng;
use reconbench_geom::{Aabb, TriMesh};

use super::Geometry;
use crate::shape::{Sample, SurfacePoint};
use crate::util::{gauss_legendre, unit, unit_vector};

/// An axis-aligned ellipsoid centred at the origin.
#[derive(Debug, Clone)]
pub struct Ellipsoid {
    e: DVec3,
    area: f64,
}

impl Ellipsoid {
    /// Semi-axes along x, y, z.
    pub fn new(a: f64, b: f64, c: f64) -> Self {
        let e = DVec3::new(a, b, c);
        Self { e, area: area(e) }
    }

    fn grad_normal(&self, x: DVec3) -> DVec3 {
        (x / (self.e * self.e)).normalize()
    }
}

/// Area by Gauss–Legendre in cos(theta) times the trapezoid rule in phi (spectral for
/// the periodic integrand): `abc * |D^-1 u|` over the unit sphere.
fn area(e: DVec3) -> f64 {
    let gl = gauss_legendre(64);
    let panels = 8;
    let nphi = 512;
    let mut s = 0.0;
    for k in 0..panels {
        let c = -1.0 + (2.0 * k as f64 + 1.0) / panels as f64;
        let hw = 1.0 / panels as f64;
        for &(x, w) in &gl {
            let ct = c + hw * x;
            let st = (1.0 - ct * ct).max(0.0).sqrt();
            let mut ring = 0.0;
            for j in 0..nphi {
                let ph = TAU * j as f64 / nphi as f64;
                let u = DVec3::new(st * ph.cos(), st * ph.sin(), ct);
                ring += (u / e).length();
            }
            s += w * hw * ring * TAU / nphi as f64;
        }
    }
    s * e.x * e.y * e.z
}

fn robust_length2(a: f64, b: f64) -> f64 {
    a.hypot(b)
}

fn robust_length3(a: f64, b: f64, c: f64) -> f64 {
    let m = a.abs().max(b.abs()).max(c.abs());
    if m == 0.0 {
        0.0
    } else {
        m * ((a / m).powi(2) + (b / m).powi(2) + (c / m).powi(2)).sqrt()
    }
}

fn get_root2(r0: f64, z0: f64, z1: f64, mut g: f64) -> f64 {
    let n0 = r0 * z0;
    let mut s0 = z1 - 1.0;
    let mut s1 = if g < 0.0 {
        0.0
    } else {
        robust_length2(n0, z1) - 1.0
    };
    let mut s = 0.0;
    for _ in 0..2200 {
        s = 0.5 * (s0 + s1);
        if s == s0 || s == s1 {
            break;
        }
        let ratio0 = n0 / (s + r0);
        let ratio1 = z1 / (s + 1.0);
        g = ratio0 * ratio0 + ratio1 * ratio1 - 1.0;
        if g > 0.0 {
            s0 = s;
        } else if g < 0.0 {
            s1 = s;
        } else {
            break;
        }
    }
    s
}

/// Closest point on the ellipse `e0 >= e1 > 0` to `(y0, y1)`, both `>= 0`.
fn ellipse(e0: f64, e1: f64, y0: f64, y1: f64) -> (f64, f64) {
    if y1 > 0.0 {
        if y0 > 0.0 {
            let z0 = y0 / e0;
            let z1 = y1 / e1;
            let g = z0 * z0 + z1 * z1 - 1.0;
            if g != 0.0 {
                let r0 = (e0 / e1).powi(2);
                let sbar = get_root2(r0, z0, z1, g);
                (r0 * y0 / (sbar + r0), y1 / (sbar + 1.0))
            } else {
                (y0, y1)
            }
        } else {
            (0.0, e1)
        }
    } else {
        let numer0 = e0 * y0;
        let denom0 = e0 * e0 - e1 * e1;
        if numer0 < denom0 {
            let xde0 = numer0 / denom0;
            (e0 * xde0, e1 * (1.0 - xde0 * xde0).max(0.0).sqrt())
        } else {
            (e0, 0.0)
        }
    }
}

fn get_root3(r0: f64, r1: f64, z0: f64, z1: f64, z2: f64, mut g: f64) -> f64 {
    let n0 = r0 * z0;
    let n1 = r1 * z1;
    let mut s0 = z2 - 1.0;
    let mut s1 = if g < 0.0 {
        0.0
    } else {
        robust_length3(n0, n1, z2) - 1.0
    };
    let mut s = 0.0;
    for _ in 0..2200 {
        s = 0.5 * (s0 + s1);
        if s == s0 || s == s1 {
            break;
        }
        let ratio0 = n0 / (s + r0);
        let ratio1 = n1 / (s + r1);
        let ratio2 = z2 / (s + 1.0);
        g = ratio0 * ratio0 + ratio1 * ratio1 + ratio2 * ratio2 - 1.0;
        if g > 0.0 {
            s0 = s;
        } else if g < 0.0 {
            s1 = s;
        } else {
            break;
        }
    }
    s
}

/// Closest point on the ellipsoid `e0 >= e1 >= e2 > 0` to `y` (all components `>= 0`).
fn ellipsoid_sorted(e: [f64; 3], y: [f64; 3]) -> [f64; 3] {
    let [e0, e1, e2] = e;
    let [y0, y1, y2] = y;
    if y2 > 0.0 {
        if y1 > 0.0 {
            if y0 > 0.0 {
                let (z0, z1, z2) = (y0 / e0, y1 / e1, y2 / e2);
                let g = z0 * z0 + z1 * z1 + z2 * z2 - 1.0;
                if g != 0.0 {
                    let r0 = (e0 / e2).powi(2);
                    let r1 = (e1 / e2).powi(2);
                    let sbar = get_root3(r0, r1, z0, z1, z2, g);
                    [
                        r0 * y0 / (sbar + r0),
                        r1 * y1 / (sbar + r1),
                        y2 / (sbar + 1.0),
                    ]
                } else {
                    y
                }
            } else {
                let (x1, x2) = ellipse(e1, e2, y1, y2);
                [0.0, x1, x2]
            }
        } else if y0 > 0.0 {
            let (x0, x2) = ellipse(e0, e2, y0, y2);
            [x0, 0.0, x2]
        } else {
            [0.0, 0.0, e2]
        }
    } else {
        let denom0 = e0 * e0 - e2 * e2;
        let denom1 = e1 * e1 - e2 * e2;
        let numer0 = e0 * y0;
        let numer1 = e1 * y1;
        if numer0 < denom0 && numer1 < denom1 {
            let xde0 = numer0 / denom0;
            let xde1 = numer1 / denom1;
            let discr = 1.0 - xde0 * xde0 - xde1 * xde1;
            if discr > 0.0 {
                return [e0 * xde0, e1 * xde1, e2 * discr.sqrt()];
            }
        }
        let (x0, x1) = ellipse(e0, e1, y0, y1);
        [x0, x1, 0.0]
    }
}

impl Geometry for Ellipsoid {
    fn closest(&self, p: DVec3) -> SurfacePoint {
        // Sort the axes decreasingly, reflect into the first octant.
        let e = self.e.to_array();
        let mut idx = [0usize, 1, 2];
        idx.sort_by(|&i, &j| e[j].total_cmp(&e[i]).then(i.cmp(&j)));
        let pa = p.to_array();
        let es = idx.map(|i| e[i]);
        let ys = idx.map(|i| pa[i].abs());
        let xs = ellipsoid_sorted(es, ys);
        let mut x = [0.0; 3];
        for k in 0..3 {
            x[idx[k]] = xs[k].copysign(if pa[idx[k]] == 0.0 { 1.0 } else { pa[idx[k]] });
        }
        let point = DVec3::from_array(x);
        SurfacePoint {
            point,
            normal: self.grad_normal(point),
            distance: (p - point).length(),
        }
    }

    fn inside(&self, p: DVec3) -> bool {
        (p / self.e).length_squared() < 1.0
    }

    fn sample(&self, rng: &mut dyn Rng) -> Sample {
        let bound = 1.0 / self.e.min_element();
        loop {
            let u = unit_vector(rng);
            if unit(rng) * bound <= (u / self.e).length() {
                let x = u * self.e;
                return Sample {
                    position: x,
                    normal: self.grad_normal(x),
                };
            }
        }
    }

    fn aabb(&self) -> Aabb {
        Aabb {
            min: -self.e,
            max: self.e,
        }
    }

    fn area(&self) -> f64 {
        self.area
    }

    fn genus(&self) -> u32 {
        0
    }

    /// Latitude-longitude mesh with one vertex per pole.
    fn mesh(&self, resolution: usize) -> Option<TriMesh> {
        let nu = resolution.max(8);
        let nv = (nu / 2).max(4);
        let g = self.grid(nu, nv - 1).expect("grid");
        let mut verts: Vec<DVec3> = g.into_iter().map(|s| s.position).collect();
        let south = verts.len() as u32;
        verts.push(DVec3::new(0.0, 0.0, -self.e.z));
        let north = verts.len() as u32;
        verts.push(DVec3::new(0.0, 0.0, self.e.z));
        let rings = nv - 1;
        let at = |j: usize, i: usize| (j * nu + i % nu) as u32;
        let mut faces = Vec::new();
        for i in 0..nu {
            faces.push([south, at(0, i + 1), at(0, i)]);
            faces.push([north, at(rings - 1, i), at(rings - 1, i + 1)]);
        }
        for j in 0..rings - 1 {
            for i in 0..nu {
                faces.push([at(j, i), at(j, i + 1), at(j + 1, i + 1)]);
                faces.push([at(j, i), at(j + 1, i + 1), at(j + 1, i)]);
            }
        }
        Some(TriMesh::new(verts, faces).expect("valid ellipsoid mesh"))
    }

    /// `nu` longitudes times `nv` latitude rings at polar angles `pi (j + 1) / (nv + 1)`
    /// from the south pole, poles excluded (seed 000's 9,950 = 199 x 50).
    fn grid(&self, nu: usize, nv: usize) -> Option<Vec<Sample>> {
        let mut out = Vec::with_capacity(nu * nv);
        for j in 0..nv {
            let th = PI * (j + 1) as f64 / (nv + 1) as f64;
            for i in 0..nu {
                let ph = TAU * i as f64 / nu as f64;
                let x = self.e * DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), -th.cos());
                out.push(Sample {
                    position: x,
                    normal: self.grad_normal(x),
                });
            }
        }
        Some(out)
    }
}
