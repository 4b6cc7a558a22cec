//! Open surfaces with a boundary: the wedge (two planar sheets at a chosen dihedral
//! angle) and a smooth height field.

use glam::{DVec2, DVec3};
use rand::Rng;
use reconbench_geom::{Aabb, PointIndex, TriMesh};

use super::Geometry;
use crate::features::{Feature, FeatureGeom, dihedral_deg};
use crate::shape::{Sample, SurfacePoint};
use crate::util::{integrate, uniform, unit};

/// Two `l x w` rectangles sharing the ridge `x in [-l/2, l/2]`, opening downwards with
/// dihedral angle `angle` (degrees) between them; normals point to the convex (upper)
/// side. The ridge is a sharp feature with that dihedral angle (Weber's "planes" data at
/// a fixed angle). Open, genus 0. Closest-point normals on the ridge are sheet A's
/// (`y >= 0`); grid samples on the ridge get the normalised bisector.
#[derive(Debug, Clone)]
pub struct Wedge {
    l: f64,
    w: f64,
    angle_deg: f64,
    origin: DVec3,
    u: [DVec3; 2],
    n: [DVec3; 2],
}

impl Wedge {
    /// A wedge with dihedral `angle_deg`, ridge length `l`, sheet width `w`.
    pub fn new(angle_deg: f64, l: f64, w: f64) -> Self {
        let half = 0.5 * angle_deg.to_radians();
        let (s, c) = half.sin_cos();
        Self {
            l,
            w,
            angle_deg,
            origin: DVec3::new(0.0, 0.0, 0.5 * w * c),
            u: [DVec3::new(0.0, s, -c), DVec3::new(0.0, -s, -c)],
            n: [DVec3::new(0.0, c, s), DVec3::new(0.0, -c, s)],
        }
    }

    fn on_sheet(&self, k: usize, a: f64, b: f64) -> DVec3 {
        self.origin + DVec3::X * a + self.u[k] * b
    }
}

impl Geometry for Wedge {
    fn closest(&self, p: DVec3) -> SurfacePoint {
        let mut best: Option<SurfacePoint> = None;
        for k in 0..2 {
            let d = p - self.origin;
            let a = d.x.clamp(-0.5 * self.l, 0.5 * self.l);
            let b = d.dot(self.u[k]).clamp(0.0, self.w);
            let point = self.on_sheet(k, a, b);
            let dist = (p - point).length();
            if best.is_none_or(|bs| dist < bs.distance) {
                best = Some(SurfacePoint {
                    point,
                    normal: self.n[k],
                    distance: dist,
                });
            }
        }
        best.expect("two sheets")
    }

    fn sample(&self, rng: &mut dyn Rng) -> Sample {
        let k = usize::from(unit(rng) >= 0.5);
        let a = uniform(rng, -0.5 * self.l, 0.5 * self.l);
        let b = uniform(rng, 0.0, self.w);
        Sample {
            position: self.on_sheet(k, a, b),
            normal: self.n[k],
        }
    }

    fn aabb(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for k in 0..2 {
            for a in [-0.5 * self.l, 0.5 * self.l] {
                for s in [0.0, self.w] {
                    b = b.grow(self.on_sheet(k, a, s));
                }
            }
        }
        b
    }

    fn area(&self) -> f64 {
        2.0 * self.l * self.w
    }

    fn genus(&self) -> u32 {
        0
    }

    fn closed(&self) -> bool {
        false
    }

    fn features(&self) -> Vec<Feature> {
        let _ = self.angle_deg;
        vec![Feature {
            geom: FeatureGeom::Segment {
                a: self.on_sheet(0, -0.5 * self.l, 0.0),
                b: self.on_sheet(0, 0.5 * self.l, 0.0),
            },
            dihedral_deg: dihedral_deg(self.n[0], self.n[1]),
        }]
    }

    fn mesh(&self, resolution: usize) -> Option<TriMesh> {
        let nx = resolution.max(1);
        let ns = ((self.w / self.l * nx as f64).ceil() as usize).max(1);
        let g = self.grid(nx + 1, ns + 1).expect("grid");
        let verts = g.into_iter().map(|s| s.position).collect();
        let faces = two_sheet_faces(nx, ns);
        Some(TriMesh::new(verts, faces).expect("valid wedge mesh"))
    }

    /// `nu` points along the ridge times `nv` rows per sheet (the ridge row shared):
    /// `nu (2 nv - 1)` points, ridge first, then sheet A's rows, then sheet B's.
    fn grid(&self, nu: usize, nv: usize) -> Option<Vec<Sample>> {
        let (nu, nv) = (nu.max(2), nv.max(2));
        let mut out = Vec::new();
        let a = |i: usize| -0.5 * self.l + self.l * i as f64 / (nu - 1) as f64;
        let ridge_n = (self.n[0] + self.n[1]).normalize();
        for i in 0..nu {
            out.push(Sample {
                position: self.on_sheet(0, a(i), 0.0),
                normal: ridge_n,
            });
        }
        for k in 0..2 {
            for j in 1..nv {
                for i in 0..nu {
                    out.push(Sample {
                        position: self.on_sheet(k, a(i), self.w * j as f64 / (nv - 1) as f64),
                        normal: self.n[k],
                    });
                }
            }
        }
        Some(out)
    }
}

/// Height field `z = amp sin(pi f x) cos(pi f y)` over `[-1, 1]^2`: an open smooth sheet
/// with a square boundary. Normals point to `+z`. Closest points: projected Newton
/// (box-constrained) from the 12 nearest points of a 129 x 129 parameter grid, the best
/// local minimum kept; converged to machine precision.
#[derive(Debug)]
pub struct HeightField {
    amp: f64,
    om: f64,
    area: f64,
    seeds: PointIndex,
    seed_uv: Vec<DVec2>,
}

impl HeightField {
    /// A height field of amplitude `amp` and frequency `freq` (half-waves per unit).
    pub fn new(amp: f64, freq: f64) -> Self {
        let om = std::f64::consts::PI * freq;
        let mut hf = Self {
            amp,
            om,
            area: 0.0,
            seeds: PointIndex::new(&[DVec3::ZERO]).expect("one point"),
            seed_uv: Vec::new(),
        };
        hf.area = integrate(
            |y| integrate(|x| hf.jac(x, y), -1.0, 1.0, 16),
            -1.0,
            1.0,
            16,
        );
        let n = 129;
        let uv: Vec<DVec2> = (0..n * n)
            .map(|k| {
                DVec2::new(
                    -1.0 + 2.0 * (k % n) as f64 / (n - 1) as f64,
                    -1.0 + 2.0 * (k / n) as f64 / (n - 1) as f64,
                )
            })
            .collect();
        let pts: Vec<DVec3> = uv.iter().map(|q| hf.at(q.x, q.y)).collect();
        hf.seeds = PointIndex::new(&pts).expect("finite seeds");
        hf.seed_uv = uv;
        hf
    }

    fn f(&self, x: f64, y: f64) -> f64 {
        self.amp * (self.om * x).sin() * (self.om * y).cos()
    }

    /// (fx, fy, fxx, fxy, fyy).
    fn derivs(&self, x: f64, y: f64) -> (f64, f64, f64, f64, f64) {
        let (sx, cx) = (self.om * x).sin_cos();
        let (sy, cy) = (self.om * y).sin_cos();
        let (a, w) = (self.amp, self.om);
        (
            a * w * cx * cy,
            -a * w * sx * sy,
            -a * w * w * sx * cy,
            -a * w * w * cx * sy,
            -a * w * w * sx * cy,
        )
    }

    fn at(&self, x: f64, y: f64) -> DVec3 {
        DVec3::new(x, y, self.f(x, y))
    }

    fn normal(&self, x: f64, y: f64) -> DVec3 {
        let (fx, fy, ..) = self.derivs(x, y);
        DVec3::new(-fx, -fy, 1.0).normalize()
    }

    fn jac(&self, x: f64, y: f64) -> f64 {
        let (fx, fy, ..) = self.derivs(x, y);
        (1.0 + fx * fx + fy * fy).sqrt()
    }

    /// Box-constrained Newton from `q0`; returns the parameter of a local minimum of the
    /// squared distance.
    fn newton(&self, p: DVec3, q0: DVec2) -> DVec2 {
        let obj = |q: DVec2| (self.at(q.x, q.y) - p).length_squared();
        let mut q = q0;
        let mut fq = obj(q);
        for _ in 0..200 {
            let (fx, fy, fxx, fxy, fyy) = self.derivs(q.x, q.y);
            let r = self.at(q.x, q.y) - p;
            let g = DVec2::new(r.x + r.z * fx, r.y + r.z * fy);
            let mut h = [
                [1.0 + fx * fx + r.z * fxx, fx * fy + r.z * fxy],
                [0.0, 1.0 + fy * fy + r.z * fyy],
            ];
            h[1][0] = h[0][1];
            // Active bounds: at a bound with the gradient pushing outwards.
            let act = [
                (q.x <= -1.0 && g.x > 0.0) || (q.x >= 1.0 && g.x < 0.0),
                (q.y <= -1.0 && g.y > 0.0) || (q.y >= 1.0 && g.y < 0.0),
            ];
            let mut step = DVec2::ZERO;
            match act {
                [false, false] => {
                    let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
                    if h[0][0] > 0.0 && det > 0.0 {
                        step = DVec2::new(
                            -(h[1][1] * g.x - h[0][1] * g.y) / det,
                            -(-h[1][0] * g.x + h[0][0] * g.y) / det,
                        );
                    } else {
                        step = -g;
                    }
                }
                [true, false] => step.y = if h[1][1] > 0.0 { -g.y / h[1][1] } else { -g.y },
                [false, true] => step.x = if h[0][0] > 0.0 { -g.x / h[0][0] } else { -g.x },
                [true, true] => {}
            }
            if step == DVec2::ZERO {
                break;
            }
            // Backtracking on the projected step.
            let mut t = 1.0;
            let mut moved = false;
            for _ in 0..60 {
                let cand = (q + step * t).clamp(DVec2::splat(-1.0), DVec2::splat(1.0));
                let fc = obj(cand);
                if fc <= fq {
                    moved = cand != q;
                    let small = (cand - q).length() < 1e-15;
                    q = cand;
                    fq = fc;
                    if small {
                        return q;
                    }
                    break;
                }
                t *= 0.5;
            }
            if !moved {
                break;
            }
        }
        q
    }
}

impl Geometry for HeightField {
    fn closest(&self, p: DVec3) -> SurfacePoint {
        let cands = self.seeds.knn(p, 12).expect("finite query");
        let mut best: Option<(f64, DVec2)> = None;
        for c in cands {
            let q = self.newton(p, self.seed_uv[c.index as usize]);
            let d = (self.at(q.x, q.y) - p).length();
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, q));
            }
        }
        let (distance, q) = best.expect("candidates");
        SurfacePoint {
            point: self.at(q.x, q.y),
            normal: self.normal(q.x, q.y),
            distance,
        }
    }

    fn sample(&self, rng: &mut dyn Rng) -> Sample {
        let aw = self.amp * self.om;
        let bound = (1.0 + 2.0 * aw * aw).sqrt();
        loop {
            let (x, y) = (uniform(rng, -1.0, 1.0), uniform(rng, -1.0, 1.0));
            if unit(rng) * bound <= self.jac(x, y) {
                return Sample {
                    position: self.at(x, y),
                    normal: self.normal(x, y),
                };
            }
        }
    }

    fn aabb(&self) -> Aabb {
        let m = self
            .seeds
            .points()
            .iter()
            .map(|p| p.z.abs())
            .fold(0.0, f64::max);
        let z = if self.om >= std::f64::consts::FRAC_PI_2 {
            self.amp
        } else {
            m
        };
        Aabb {
            min: DVec3::new(-1.0, -1.0, -z),
            max: DVec3::new(1.0, 1.0, z),
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
        let n = resolution.max(2) + 1;
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
        Some(TriMesh::new(verts, faces).expect("valid height-field mesh"))
    }

    /// `nu x nv` points on the parameter square, boundaries included, x fastest.
    fn grid(&self, nu: usize, nv: usize) -> Option<Vec<Sample>> {
        let (nu, nv) = (nu.max(2), nv.max(2));
        let mut out = Vec::with_capacity(nu * nv);
        for j in 0..nv {
            for i in 0..nu {
                let x = -1.0 + 2.0 * i as f64 / (nu - 1) as f64;
                let y = -1.0 + 2.0 * j as f64 / (nv - 1) as f64;
                out.push(Sample {
                    position: self.at(x, y),
                    normal: self.normal(x, y),
                });
            }
        }
        Some(out)
    }
}

/// Faces of two sheets that share a ridge row, for vertices in the order of the
/// wedge-like grids (`nx + 1` ridge points, then `ns` rows of sheet A, then `ns` rows of
/// sheet B): `nx x ns` quads per sheet, two triangles each, sheet B wound the other
/// way so both face outwards. Shared by the `wedge` and `planes` meshes.
pub(crate) fn two_sheet_faces(nx: usize, ns: usize) -> Vec<[u32; 3]> {
    // Vertex (i, j) of sheet k: ridge row j = 0 shared.
    let idx = |k: usize, i: usize, j: usize| -> u32 {
        if j == 0 {
            i as u32
        } else {
            ((nx + 1) * (1 + k * ns + (j - 1)) + i) as u32
        }
    };
    let mut faces = Vec::with_capacity(4 * nx * ns);
    for k in 0..2 {
        for j in 0..ns {
            for i in 0..nx {
                let (a, b, c, d) = (
                    idx(k, i, j),
                    idx(k, i + 1, j),
                    idx(k, i + 1, j + 1),
                    idx(k, i, j + 1),
                );
                if k == 0 {
                    faces.push([a, b, c]);
                    faces.push([a, c, d]);
                } else {
                    faces.push([a, c, b]);
                    faces.push([a, d, c]);
                }
            }
        }
    }
    faces
}
