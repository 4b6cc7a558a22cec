//! Surfaces of revolution about the z axis whose meridian profile is a chain of
//! segments and arcs: sphere, torus, cylinder, cone. The closest point is exact: the
//! closest point of the profile in the query's meridian half-plane, rotated back.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use glam::{DVec2, DVec3};
use rand::Rng;
use reconbench_geom::{Aabb, TriMesh};

use super::Geometry;
use crate::features::{Feature, FeatureGeom, dihedral_deg};
use crate::geom2d::{Elem2, Region2, loops};
use crate::shape::{Sample, SurfacePoint};
use crate::util::{cumulative, pick_weighted, uniform, unit};

/// A surface of revolution. The profile lives in the `(rho, z)` half-plane, `rho >= 0`,
/// oriented so that the solid's meridian section is on its left (counter-clockwise).
#[derive(Debug, Clone)]
pub struct Revolved {
    /// Surface elements of the profile (axis segments excluded).
    profile: Vec<Elem2>,
    /// The closed meridian section (profile plus the closing axis segment, if any).
    region: Region2,
    /// Whether the profile is a closed loop (torus) rather than an axis-to-axis chain.
    loop_profile: bool,
    genus: u32,
    weights: Vec<f64>,
    cum: Vec<f64>,
}

impl Revolved {
    /// From an axis-to-axis chain (`loop_profile = false`) or a closed loop.
    pub fn new(profile: Vec<Elem2>, loop_profile: bool) -> Self {
        let mut boundary = profile.clone();
        if !loop_profile {
            boundary.push(Elem2::Seg {
                a: profile.last().expect("non-empty profile").end(),
                b: profile[0].start(),
            });
        }
        let region = Region2::new(vec![boundary]);
        debug_assert!(region.check_closed().is_ok());
        let weights: Vec<f64> = profile.iter().map(revolved_area).collect();
        let cum = cumulative(&weights);
        Self {
            profile,
            region,
            loop_profile,
            genus: u32::from(loop_profile),
            weights,
            cum,
        }
    }

    /// Sphere of radius `r`.
    pub fn sphere(r: f64) -> Self {
        Self::new(
            vec![Elem2::Arc {
                c: DVec2::ZERO,
                r,
                a0: -FRAC_PI_2,
                sweep: PI,
            }],
            false,
        )
    }

    /// Torus with major radius `big` and tube radius `r`. Profile angle 0 is the outer
    /// equator.
    pub fn torus(big: f64, r: f64) -> Self {
        Self::new(
            vec![Elem2::Arc {
                c: DVec2::new(big, 0.0),
                r,
                a0: 0.0,
                sweep: TAU,
            }],
            true,
        )
    }

    /// Closed cylinder of radius `r`, height `h`, centred at the origin.
    pub fn cylinder(r: f64, h: f64) -> Self {
        let z = 0.5 * h;
        Self::new(
            loops::polygon(&[
                DVec2::new(0.0, -z),
                DVec2::new(r, -z),
                DVec2::new(r, z),
                DVec2::new(0.0, z),
            ])[..3]
                .to_vec(),
            false,
        )
    }

    /// Closed cone with base radius `r` at `z = -h/2` and apex at `z = h/2`.
    pub fn cone(r: f64, h: f64) -> Self {
        let z = 0.5 * h;
        Self::new(
            loops::polygon(&[DVec2::new(0.0, -z), DVec2::new(r, -z), DVec2::new(0.0, z)])[..2]
                .to_vec(),
            false,
        )
    }

    fn to3(q: DVec2, w: DVec2) -> DVec3 {
        DVec3::new(q.x * w.x, q.x * w.y, q.y)
    }

    fn profile_length(&self) -> f64 {
        self.profile.iter().map(Elem2::length).sum()
    }

    /// Profile point and outward 2D normal at arc length `s` along the whole profile.
    fn profile_at(&self, mut s: f64) -> (DVec2, DVec2) {
        for (i, e) in self.profile.iter().enumerate() {
            let l = e.length();
            if s <= l || i + 1 == self.profile.len() {
                let s = s.min(l);
                return (e.point_at(s), e.normal_at(s));
            }
            s -= l;
        }
        unreachable!("non-empty profile")
    }
}

/// Area swept by one profile element: 2 pi times the integral of rho along it.
fn revolved_area(e: &Elem2) -> f64 {
    match *e {
        Elem2::Seg { a, b } => TAU * (b - a).length() * 0.5 * (a.x + b.x),
        Elem2::Arc { c, r, a0, sweep } => {
            TAU * r * (c.x * sweep + r * ((a0 + sweep).sin() - a0.sin())) * sweep.signum()
        }
    }
}

/// Largest rho on an element (bound for rejection sampling).
fn rho_max(e: &Elem2) -> f64 {
    match *e {
        Elem2::Seg { a, b } => a.x.max(b.x),
        Elem2::Arc { c, r, .. } => c.x + r,
    }
}

impl Geometry for Revolved {
    fn closest(&self, p: DVec3) -> SurfacePoint {
        let rho = p.x.hypot(p.y);
        let w = if rho > 0.0 {
            DVec2::new(p.x / rho, p.y / rho)
        } else {
            DVec2::X
        };
        let q = DVec2::new(rho, p.z);
        let mut best = self.profile[0].closest(q);
        for e in &self.profile[1..] {
            let c = e.closest(q);
            if c.dist2 < best.dist2 {
                best = c;
            }
        }
        SurfacePoint {
            point: Self::to3(best.point, w),
            normal: Self::to3(best.normal, w),
            distance: best.dist2.sqrt(),
        }
    }

    fn inside(&self, p: DVec3) -> bool {
        self.region.contains(DVec2::new(p.x.hypot(p.y), p.z))
    }

    fn sample(&self, rng: &mut dyn Rng) -> Sample {
        let e = &self.profile[pick_weighted(rng, &self.cum)];
        let bound = rho_max(e);
        let (q, n) = loop {
            let s = uniform(rng, 0.0, e.length());
            let q = e.point_at(s);
            if unit(rng) * bound <= q.x {
                break (q, e.normal_at(s));
            }
        };
        let w = DVec2::from_angle(uniform(rng, 0.0, TAU));
        Sample {
            position: Self::to3(q, w),
            normal: Self::to3(n, w),
        }
    }

    fn aabb(&self) -> Aabb {
        let (lo, hi) = self.region.bounds();
        Aabb {
            min: DVec3::new(-hi.x, -hi.x, lo.y),
            max: DVec3::new(hi.x, hi.x, hi.y),
        }
    }

    fn area(&self) -> f64 {
        self.weights.iter().sum()
    }

    fn genus(&self) -> u32 {
        self.genus
    }

    fn features(&self) -> Vec<Feature> {
        let mut out = Vec::new();
        let n = self.profile.len();
        let junctions = if self.loop_profile { n } else { n - 1 };
        for i in 0..junctions {
            let a = &self.profile[i];
            let b = &self.profile[(i + 1) % n];
            let (na, nb) = (a.normal_at(a.length()), b.normal_at(0.0));
            if na.dot(nb) < 1.0 - 1e-12 {
                let v = b.start();
                out.push(Feature {
                    geom: FeatureGeom::Arc {
                        center: DVec3::new(0.0, 0.0, v.y),
                        u: DVec3::X,
                        v: DVec3::Y,
                        r: v.x,
                        t0: 0.0,
                        sweep: TAU,
                    },
                    dihedral_deg: dihedral_deg(
                        DVec3::new(na.x, 0.0, na.y),
                        DVec3::new(nb.x, 0.0, nb.y),
                    ),
                });
            }
        }
        if !self.loop_profile {
            // Apexes: the profile meets the axis at a non-right angle.
            for (e, s) in [
                (&self.profile[0], 0.0),
                (&self.profile[n - 1], self.profile[n - 1].length()),
            ] {
                let nrm = e.normal_at(s);
                if nrm.x.abs() > 1e-12 {
                    out.push(Feature {
                        geom: FeatureGeom::Point(DVec3::new(0.0, 0.0, e.point_at(s).y)),
                        dihedral_deg: dihedral_deg(
                            DVec3::new(nrm.x, 0.0, nrm.y),
                            DVec3::new(-nrm.x, 0.0, nrm.y),
                        ),
                    });
                }
            }
        }
        out
    }

    fn mesh(&self, resolution: usize) -> Option<TriMesh> {
        let na = resolution.max(8);
        let (_, hi) = self.region.bounds();
        let h = TAU * hi.x / na as f64;
        // Profile points: every element split evenly, junctions shared.
        let mut prof: Vec<DVec2> = Vec::new();
        for e in &self.profile {
            let k = ((e.length() / h).ceil() as usize).max(if matches!(e, Elem2::Arc { .. }) {
                4
            } else {
                1
            });
            let pts = e.polyline(k);
            let skip = usize::from(!prof.is_empty());
            prof.extend_from_slice(&pts[skip..]);
        }
        if self.loop_profile {
            prof.pop(); // the loop's end repeats its start
        }
        let on_axis = |q: DVec2| q.x.abs() < 1e-12;
        let mut verts = Vec::new();
        let mut ring: Vec<Vec<u32>> = Vec::new();
        for &q in &prof {
            if on_axis(q) {
                verts.push(DVec3::new(0.0, 0.0, q.y));
                ring.push(vec![(verts.len() - 1) as u32; na]);
            } else {
                let start = verts.len() as u32;
                for i in 0..na {
                    verts.push(Self::to3(q, DVec2::from_angle(TAU * i as f64 / na as f64)));
                }
                ring.push((0..na as u32).map(|i| start + i).collect());
            }
        }
        let mut faces = Vec::new();
        let m = prof.len();
        let strips = if self.loop_profile { m } else { m - 1 };
        for j in 0..strips {
            let (r0, r1) = (&ring[j], &ring[(j + 1) % m]);
            for i in 0..na {
                let i1 = (i + 1) % na;
                let (a, b, c, d) = (r0[i], r0[i1], r1[i1], r1[i]);
                if a != b {
                    faces.push([a, b, c]);
                }
                if c != d {
                    faces.push([a, c, d]);
                }
            }
        }
        Some(TriMesh::new(verts, faces).expect("valid revolved mesh"))
    }

    fn grid(&self, nu: usize, nv: usize) -> Option<Vec<Sample>> {
        let (nu, nv) = (nu.max(1), nv.max(1));
        let l = self.profile_length();
        let mut out = Vec::with_capacity(nu * nv);
        for j in 0..nv {
            let s = if self.loop_profile {
                l * j as f64 / nv as f64
            } else {
                l * (j + 1) as f64 / (nv + 1) as f64
            };
            let (q, n) = self.profile_at(s);
            for i in 0..nu {
                let w = DVec2::from_angle(TAU * i as f64 / nu as f64);
                out.push(Sample {
                    position: Self::to3(q, w),
                    normal: Self::to3(n, w),
                });
            }
        }
        Some(out)
    }
}
