//! The built-in shapes, their catalogue and the `name:key=value` spec syntax.
//!
//! Every shape is defined in its natural units by a [`Geometry`] and wrapped in a
//! [`Normalized`] that scales it (about the origin) to unit bounding-box diagonal. The
//! natural definitions are centred at the origin.

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

use glam::DVec3;
use rand::Rng;
use reconbench_geom::{Aabb, TriMesh};
use serde::{Deserialize, Serialize};

use glam::DVec2;

use crate::error::{Result, SynthError};
use crate::features::{Feature, feature_distance};
use crate::geom2d::{Elem2, Region2, loops};
use crate::shape::{FeatureCurve, Sample, Shape, ShapeInfo, SurfacePoint};
use crate::spec::{fmt_f64, format_kv, parse_f64, parse_kv, resolve_params};

pub mod blend_shapes;
pub mod blind_hole;
pub mod boxes;
pub mod ellipsoid;
pub mod hcit_standins;
pub mod knot;
pub mod mesh_shape;
pub mod planes;
pub mod prism;
pub mod revolved;
pub mod sheet;
pub mod slab;
pub mod standins;

pub use mesh_shape::{DEFAULT_MESH_FEATURE_ANGLE_DEG, MeshShape, MeshShapeOptions};

/// A surface in its natural units (crate-internal building block of [`Normalized`]).
pub trait Geometry: Send + Sync + fmt::Debug {
    /// Exact closest point.
    fn closest(&self, p: DVec3) -> SurfacePoint;
    /// Inside test; default: on the side the closest normal points away from.
    fn inside(&self, p: DVec3) -> bool {
        let c = self.closest(p);
        (p - c.point).dot(c.normal) < 0.0
    }
    /// One area-uniform random sample.
    fn sample(&self, rng: &mut dyn Rng) -> Sample;
    /// Bounding box.
    fn aabb(&self) -> Aabb;
    /// Surface area.
    fn area(&self) -> f64;
    /// Genus.
    fn genus(&self) -> u32;
    /// Connected components.
    fn components(&self) -> u32 {
        1
    }
    /// Closed surface?
    fn closed(&self) -> bool {
        true
    }
    /// Boundary loops (0 closed; an open sheet 1, plus one per through-hole).
    fn boundary_loops(&self) -> u32 {
        u32::from(!self.closed())
    }
    /// Exact sharp features.
    fn features(&self) -> Vec<Feature> {
        Vec::new()
    }
    /// Reference mesh in natural units; `None` to polygonise the signed distance
    /// (marching tetrahedra, vertices projected onto the surface).
    fn mesh(&self, resolution: usize) -> Option<TriMesh> {
        let _ = resolution;
        None
    }
    /// Parametric grid samples.
    fn grid(&self, nu: usize, nv: usize) -> Option<Vec<Sample>> {
        let _ = (nu, nv);
        None
    }
    /// Grid dimensions for about `count` points.
    fn grid_dims(&self, count: usize) -> (usize, usize) {
        let n = (count as f64).sqrt().round().max(1.0) as usize;
        (n, n)
    }
    /// Closed-form ray intersection in natural units (`dir` unit); `None` = use the
    /// generic sphere tracer.
    fn ray(&self, origin: DVec3, dir: DVec3, max_t: f64) -> Option<Option<f64>> {
        let _ = (origin, dir, max_t);
        None
    }
}

/// A [`Geometry`] scaled to unit bounding-box diagonal: the public [`Shape`].
#[derive(Debug)]
pub struct Normalized<G> {
    name: String,
    g: G,
    s: f64,
    features: Vec<Feature>,
}

impl<G: Geometry> Normalized<G> {
    /// Wraps `g`, computing the scale from its bounding box.
    pub fn new(name: &str, g: G) -> Self {
        let s = 1.0 / g.aabb().diagonal();
        let features = g
            .features()
            .into_iter()
            .map(|f| Feature {
                geom: f.geom.scaled(s),
                dihedral_deg: f.dihedral_deg,
            })
            .collect();
        Self {
            name: name.to_string(),
            g,
            s,
            features,
        }
    }

    /// The natural-units geometry.
    pub fn geometry(&self) -> &G {
        &self.g
    }

    fn out(&self, sp: Sample) -> Sample {
        Sample {
            position: sp.position * self.s,
            normal: sp.normal,
        }
    }
}

impl<G: Geometry> Shape for Normalized<G> {
    fn name(&self) -> &str {
        &self.name
    }
    fn closest_point(&self, p: DVec3) -> SurfacePoint {
        let c = self.g.closest(p / self.s);
        SurfacePoint {
            point: c.point * self.s,
            normal: c.normal,
            distance: c.distance * self.s,
        }
    }
    fn is_inside(&self, p: DVec3) -> bool {
        self.g.inside(p / self.s)
    }
    fn sample_uniform(&self, n: usize, rng: &mut dyn Rng) -> Vec<Sample> {
        (0..n).map(|_| self.out(self.g.sample(rng))).collect()
    }
    fn aabb(&self) -> Aabb {
        let b = self.g.aabb();
        Aabb {
            min: b.min * self.s,
            max: b.max * self.s,
        }
    }
    fn scale(&self) -> f64 {
        self.s
    }
    fn area(&self) -> f64 {
        self.g.area() * self.s * self.s
    }
    fn genus(&self) -> u32 {
        self.g.genus()
    }
    fn components(&self) -> u32 {
        self.g.components()
    }
    fn is_closed(&self) -> bool {
        self.g.closed()
    }
    fn boundary_loops(&self) -> u32 {
        self.g.boundary_loops()
    }
    fn feature_curves(&self) -> Vec<FeatureCurve> {
        self.features.iter().map(|f| f.to_curve(1e-5)).collect()
    }
    fn feature_distance(&self, p: DVec3) -> f64 {
        feature_distance(&self.features, p)
    }
    fn reference_mesh(&self, resolution: usize) -> TriMesh {
        let resolution = resolution.max(4);
        let (v, f) = match self.g.mesh(resolution) {
            Some(m) => (m.vertices().to_vec(), m.faces().to_vec()),
            None => {
                let sdf = |p: DVec3| {
                    let c = self.g.closest(p);
                    if self.g.inside(p) {
                        -c.distance
                    } else {
                        c.distance
                    }
                };
                let (v, f) =
                    crate::polygonize::marching_tetrahedra(&sdf, self.g.aabb(), resolution);
                let v = v.into_iter().map(|p| self.g.closest(p).point).collect();
                (v, f)
            }
        };
        let v: Vec<DVec3> = v.into_iter().map(|p| p * self.s).collect();
        TriMesh::new(v, f).expect("generated meshes are finite and indexed")
    }
    fn ray_intersect(&self, origin: DVec3, dir: DVec3, max_t: f64) -> Option<f64> {
        let len = dir.length();
        if len == 0.0 {
            return None;
        }
        match self.g.ray(origin / self.s, dir / len, max_t * len / self.s) {
            Some(hit) => hit.map(|t| t * self.s / len),
            None => crate::raycast::sphere_trace(
                &|p: DVec3| {
                    let q = p / self.s;
                    let c = self.g.closest(q);
                    let d = if self.g.inside(q) {
                        -c.distance
                    } else {
                        c.distance
                    };
                    (d * self.s, c.normal)
                },
                origin,
                dir,
                max_t,
                1.0,
            ),
        }
    }
    fn parametric_grid(&self, nu: usize, nv: usize) -> Option<Vec<Sample>> {
        self.g
            .grid(nu, nv)
            .map(|v| v.into_iter().map(|s| self.out(s)).collect())
    }
    fn grid_dims_for_count(&self, count: usize) -> (usize, usize) {
        self.g.grid_dims(count)
    }
}

/// A shape by name and parameters; round-trips to the string `name:key=value,...`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShapeSpec {
    /// Catalogue name, e.g. `torus`.
    pub name: String,
    /// Parameters given (others take their defaults).
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
}

impl ShapeSpec {
    /// A spec without parameters.
    pub fn named(name: &str) -> Self {
        Self {
            name: name.to_string(),
            params: BTreeMap::new(),
        }
    }

    /// Builds the shape.
    pub fn build(&self) -> Result<Box<dyn Shape>> {
        let def = find_def(&self.name)?;
        let owner = format!("shape '{}'", def.name);
        let p = resolve_params(&owner, def.params, &self.params)?;
        (def.build)(&Params { owner, map: p })
    }
}

impl fmt::Display for ShapeSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&format_kv(
            &self.name,
            self.params.iter().map(|(k, v)| (k.as_str(), fmt_f64(*v))),
        ))
    }
}

impl FromStr for ShapeSpec {
    type Err = SynthError;
    fn from_str(s: &str) -> Result<Self> {
        let kv = parse_kv("shape", s, true)?;
        let owner = format!("shape '{}'", kv.name);
        let mut params = BTreeMap::new();
        for (k, v) in kv.params {
            let x = parse_f64(&owner, &k, &v)?;
            params.insert(k, x);
        }
        Ok(Self {
            name: kv.name,
            params,
        })
    }
}

/// Resolved parameters of one shape, with range checks that name the shape.
#[derive(Debug)]
pub struct Params {
    owner: String,
    map: BTreeMap<String, f64>,
}

impl Params {
    /// A parameter value (present by construction).
    pub fn get(&self, k: &str) -> f64 {
        self.map[k]
    }
    /// A parameter that must be strictly positive.
    pub fn positive(&self, k: &str) -> Result<f64> {
        let v = self.get(k);
        if v > 0.0 {
            Ok(v)
        } else {
            Err(SynthError::invalid(
                &self.owner,
                k,
                format!("{v} must be > 0"),
            ))
        }
    }
    /// A parameter in `[lo, hi]`.
    pub fn in_range(&self, k: &str, lo: f64, hi: f64) -> Result<f64> {
        let v = self.get(k);
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(SynthError::invalid(
                &self.owner,
                k,
                format!("{v} must be in [{lo}, {hi}]"),
            ))
        }
    }
    /// A positive integer parameter.
    pub fn count(&self, k: &str, min: usize) -> Result<usize> {
        let v = self.get(k);
        if v.fract() == 0.0 && v >= min as f64 && v < 1e6 {
            Ok(v as usize)
        } else {
            Err(SynthError::invalid(
                &self.owner,
                k,
                format!("{v} must be an integer >= {min}"),
            ))
        }
    }
    /// An error about parameter `k`.
    pub fn error(&self, k: &str, message: impl Into<String>) -> SynthError {
        SynthError::invalid(&self.owner, k, message)
    }
}

/// One catalogue entry.
#[derive(Debug)]
pub struct ShapeDef {
    /// Name.
    pub name: &'static str,
    /// One-line description.
    pub summary: &'static str,
    /// Parameters with their defaults (natural units, before normalisation).
    pub params: &'static [(&'static str, f64)],
    /// Constructor.
    pub build: fn(&Params) -> Result<Box<dyn Shape>>,
}

fn boxed<G: Geometry + 'static>(name: &str, g: G) -> Box<dyn Shape> {
    Box::new(Normalized::new(name, g))
}

/// The catalogue of built-in shapes.
pub fn definitions() -> &'static [ShapeDef] {
    DEFS
}

static DEFS: &[ShapeDef] = &[
    ShapeDef {
        name: "sphere",
        summary: "sphere of radius r",
        params: &[("r", 1.0)],
        build: |p| {
            Ok(boxed(
                "sphere",
                revolved::Revolved::sphere(p.positive("r")?),
            ))
        },
    },
    ShapeDef {
        name: "ellipsoid",
        summary: "ellipsoid with semi-axes a, b, c (default 3:1:1, seed 000's high-curvature one)",
        params: &[("a", 3.0), ("b", 1.0), ("c", 1.0)],
        build: |p| {
            Ok(boxed(
                "ellipsoid",
                ellipsoid::Ellipsoid::new(p.positive("a")?, p.positive("b")?, p.positive("c")?),
            ))
        },
    },
    ShapeDef {
        name: "torus",
        summary: "torus with major radius R and tube radius r < R (genus 1)",
        params: &[("R", 2.0), ("r", 1.0)],
        build: |p| {
            let (big, r) = (p.positive("R")?, p.positive("r")?);
            if r >= big {
                return Err(p.error("r", format!("{r} must be < R = {big}")));
            }
            Ok(boxed("torus", revolved::Revolved::torus(big, r)))
        },
    },
    ShapeDef {
        name: "box",
        summary: "axis-aligned box with half-extents a, b, c: 12 edges (90 deg), 8 corners",
        params: &[("a", 1.0), ("b", 1.0), ("c", 1.0)],
        build: |p| {
            Ok(boxed(
                "box",
                boxes::BoxShape::new(DVec3::new(
                    p.positive("a")?,
                    p.positive("b")?,
                    p.positive("c")?,
                )),
            ))
        },
    },
    ShapeDef {
        name: "cylinder",
        summary: "closed cylinder of radius r and height h with sharp (90 deg) rims",
        params: &[("r", 1.0), ("h", 2.0)],
        build: |p| {
            Ok(boxed(
                "cylinder",
                revolved::Revolved::cylinder(p.positive("r")?, p.positive("h")?),
            ))
        },
    },
    ShapeDef {
        name: "cone",
        summary: "closed cone of base radius r and height h: sharp base rim and apex",
        params: &[("r", 1.0), ("h", 2.0)],
        build: |p| {
            Ok(boxed(
                "cone",
                revolved::Revolved::cone(p.positive("r")?, p.positive("h")?),
            ))
        },
    },
    ShapeDef {
        name: "wedge",
        summary: "open surface: two w x l rectangles meeting at a ridge with dihedral angle `angle` (deg)",
        params: &[("angle", 90.0), ("l", 2.0), ("w", 1.0)],
        build: |p| {
            Ok(boxed(
                "wedge",
                sheet::Wedge::new(
                    p.in_range("angle", 1.0, 179.0)?,
                    p.positive("l")?,
                    p.positive("w")?,
                ),
            ))
        },
    },
    ShapeDef {
        name: "planes",
        summary: "open surface: two ruled sheets (l x w) meeting at a straight ridge whose opening angle varies from a0 to a1 (deg; seed 002's 45 -> 140 planes)",
        params: &[("a0", 45.0), ("a1", 140.0), ("l", 2.0), ("w", 1.0)],
        build: |p| {
            Ok(boxed(
                "planes",
                planes::Planes::new(
                    p.in_range("a0", 1.0, 179.0)?,
                    p.in_range("a1", 1.0, 179.0)?,
                    p.positive("l")?,
                    p.positive("w")?,
                ),
            ))
        },
    },
    ShapeDef {
        name: "height-field",
        summary: "open sheet z = amp sin(freq pi x) cos(freq pi y) over [-1, 1]^2 with a boundary",
        params: &[("amp", 0.15), ("freq", 1.0)],
        build: |p| {
            let amp = p.in_range("amp", 0.0, 0.5)?;
            let freq = p.in_range("freq", 0.0, 3.0)?;
            Ok(boxed("height-field", sheet::HeightField::new(amp, freq)))
        },
    },
    ShapeDef {
        name: "mask",
        summary: "seed 004 stand-in: open mask-like free-form height field, 250 x 200 x 60 mm (dome, nose, brow ridge, eye hollows)",
        params: &[],
        build: |_| {
            Ok(boxed(
                "mask",
                standins::StandIn::new(standins::StandInKind::Mask),
            ))
        },
    },
    ShapeDef {
        name: "poly-part",
        summary: "seed 004 stand-in: 150 x 150 mm plane with a cylindrical ridge (r 25, 20 high) and a spherical cap (r 40, 30 high), creased",
        params: &[],
        build: |_| {
            Ok(boxed(
                "poly-part",
                standins::StandIn::new(standins::StandInKind::PolyPart),
            ))
        },
    },
    ShapeDef {
        name: "blade",
        summary: "seed 004 stand-in: twisted, cambered blade-like plate, 240 x 180 x 65 mm",
        params: &[],
        build: |_| {
            Ok(boxed(
                "blade",
                standins::StandIn::new(standins::StandInKind::Blade),
            ))
        },
    },
    ShapeDef {
        name: "bolt-plate",
        summary: "seed 003 stand-in (spare part): open flat plate, 150 x 100 mm, two bolt holes of radius 8 mm (3 boundary loops)",
        params: &[],
        build: |_| Ok(boxed("bolt-plate", hcit_standins::HoledPatch::bolt_plate())),
    },
    ShapeDef {
        name: "eye-face",
        summary: "seed 003 stand-in (face 2): open dome (sphere of radius 200 mm over 200 x 240 mm) with two eye holes of radius 14 mm (3 boundary loops)",
        params: &[],
        build: |_| Ok(boxed("eye-face", hcit_standins::HoledPatch::eye_face())),
    },
    ShapeDef {
        name: "grooved-handle",
        summary: "seed 003 stand-in (pan handle): closed capsule, radius 12 mm, 120 mm long, with three 3 mm grooves (sharp groove edges)",
        params: &[],
        build: |_| Ok(boxed("grooved-handle", hcit_standins::grooved_handle())),
    },
    ShapeDef {
        name: "bottle",
        summary: "seed 003 stand-in: closed bottle of revolution, 160 mm tall (filleted base, body radius 30 mm, shoulder, neck radius 10 mm)",
        params: &[],
        build: |_| Ok(boxed("bottle", hcit_standins::bottle())),
    },
    ShapeDef {
        name: "double-torus",
        summary: "genus-2 pretzel slab: offset by r of a stadium (half-length d, radius ro) with two holes of radius ri",
        params: &[("d", 1.0), ("ro", 1.0), ("ri", 0.4), ("r", 0.25)],
        build: |p| {
            let (d, ro, ri, r) = (
                p.positive("d")?,
                p.positive("ro")?,
                p.positive("ri")?,
                p.positive("r")?,
            );
            holed_slab(p, "double-torus", d, ro, ri, r, &[-d, d])
        },
    },
    ShapeDef {
        name: "three-holes",
        summary: "genus-3 slab: offset by r of a stadium (half-length d, radius ro) with three holes of radius ri",
        params: &[("d", 2.0), ("ro", 1.0), ("ri", 0.45), ("r", 0.25)],
        build: |p| {
            let (d, ro, ri, r) = (
                p.positive("d")?,
                p.positive("ro")?,
                p.positive("ri")?,
                p.positive("r")?,
            );
            holed_slab(p, "three-holes", d, ro, ri, r, &[-d, 0.0, d])
        },
    },
    ShapeDef {
        name: "torus-knot",
        summary: "tube of radius r around the (p, q) torus knot on the torus (R, a); genus 1, smooth",
        params: &[("p", 2.0), ("q", 3.0), ("R", 1.0), ("a", 0.4), ("r", 0.12)],
        build: |p| {
            let k = knot::KnotTube::new(
                p.count("p", 1)? as u32,
                p.count("q", 1)? as u32,
                p.positive("R")?,
                p.positive("a")?,
                p.positive("r")?,
            )
            .map_err(|m| p.error("r", m))?;
            Ok(boxed("torus-knot", k))
        },
    },
    ShapeDef {
        name: "cube-with-hole",
        summary: "cube of side 2 with a cylindrical through hole of radius rh along z (genus 1; seed 002's proportions)",
        params: &[("rh", 0.5)],
        build: |p| {
            let rh = p.positive("rh")?;
            if rh >= 0.95 {
                return Err(p.error("rh", format!("{rh} must be < 0.95")));
            }
            let g = prism::Prism::new(cube_with_hole_region(rh), -1.0, 1.0)
                .map_err(|m| p.error("rh", m))?;
            Ok(boxed("cube-with-hole", g))
        },
    },
    ShapeDef {
        name: "cube-with-blind-hole",
        summary: "cube of side 2 with a cylindrical blind hole of radius rh and depth d from the top face (genus 0; seed 002 §10.2: rh = 0.5, d = 1)",
        params: &[("rh", 0.5), ("d", 1.0)],
        build: |p| {
            let rh = p.positive("rh")?;
            if rh >= 0.95 {
                return Err(p.error("rh", format!("{rh} must be < 0.95")));
            }
            let d = p.positive("d")?;
            if d > 1.9 {
                return Err(p.error("d", format!("{d} must be <= 1.9")));
            }
            Ok(boxed(
                "cube-with-blind-hole",
                blind_hole::BlindHoleCube::new(rh, d),
            ))
        },
    },
    ShapeDef {
        name: "star-sharp",
        summary: "extruded star with k tips (outer radius 1, inner radius ri), thickness h: sharp tips, reflex edges and rims",
        params: &[("k", 5.0), ("ri", 0.5), ("h", 0.4)],
        build: |p| {
            let region = star_region(p.count("k", 3)?, p.in_range("ri", 0.05, 0.95)?);
            let h = p.positive("h")?;
            let g = prism::Prism::new(region, -0.5 * h, 0.5 * h).map_err(|m| p.error("ri", m))?;
            Ok(boxed("star-sharp", g))
        },
    },
    ShapeDef {
        name: "star-smooth",
        summary: "smooth star slab: offset by r of a star (k tips, inner radius ri) with inner corners filleted (radius f > r)",
        params: &[("k", 5.0), ("ri", 0.5), ("f", 0.15), ("r", 0.1)],
        build: |p| {
            let region = star_smooth_region(
                p.count("k", 3)?,
                p.in_range("ri", 0.05, 0.95)?,
                p.positive("f")?,
            );
            let g = slab::Slab::new(region, p.positive("r")?).map_err(|m| p.error("r", m))?;
            Ok(boxed("star-smooth", g))
        },
    },
    ShapeDef {
        name: "star-half",
        summary: "half-smooth star: extruded star (k tips, inner radius ri, thickness h) with sharp tips and rims and inner corners filleted by radius f (smooth walls)",
        params: &[("k", 5.0), ("ri", 0.5), ("h", 0.4), ("f", 0.15)],
        build: |p| {
            let region = star_smooth_region(
                p.count("k", 3)?,
                p.in_range("ri", 0.05, 0.95)?,
                p.positive("f")?,
            );
            let h = p.positive("h")?;
            let g = prism::Prism::new(region, -0.5 * h, 0.5 * h).map_err(|m| p.error("f", m))?;
            Ok(boxed("star-half", g))
        },
    },
    ShapeDef {
        name: "fandisk-like",
        summary: "CAD part: extruded profile with planar faces, a concave cylindrical cut and a 30-deg spike; dihedral angles 30-150",
        params: &[("depth", 1.0)],
        build: |p| {
            let d = p.positive("depth")?;
            let g = prism::Prism::new(Region2::new(vec![fandisk_profile()]), -0.5 * d, 0.5 * d)
                .map_err(|m| p.error("depth", m))?;
            Ok(boxed("fandisk-like", g))
        },
    },
    ShapeDef {
        name: "box-tube",
        summary: "seed 002 ch. 5 blend truth: box (half-extents a, b, c) with an open tube standing on it, placed like the blend filter's (foot cx, cy, cz of the box; axis ax, ay, az; radius, length out, depth in: fractions of the box diagonal); scans see the box only",
        params: &[
            ("a", 1.0),
            ("b", 1.0),
            ("c", 1.0),
            ("cx", 0.5),
            ("cy", 0.5),
            ("cz", 1.0),
            ("ax", 0.0),
            ("ay", 0.0),
            ("az", 1.0),
            ("radius_rel", 0.1),
            ("length_rel", 0.2),
            ("depth_rel", 0.1),
        ],
        build: blend_shapes::box_tube,
    },
    ShapeDef {
        name: "fandisk-tube",
        summary: "seed 002 ch. 5 blend truth: the fandisk-like part with an open tube across its edge E and concave cut (placement as box-tube); scans see the part only",
        params: &[
            ("depth", 1.0),
            ("cx", 0.8),
            ("cy", 0.546),
            ("cz", 0.5),
            ("ax", 0.0),
            ("ay", 1.0),
            ("az", 0.0),
            ("radius_rel", 0.05),
            ("length_rel", 0.15),
            ("depth_rel", 0.05),
        ],
        build: blend_shapes::fandisk_tube,
    },
];

fn find_def(name: &str) -> Result<&'static ShapeDef> {
    DEFS.iter()
        .find(|d| d.name == name)
        .ok_or_else(|| SynthError::UnknownName {
            what: "shape",
            name: name.to_string(),
            valid: DEFS.iter().map(|d| d.name).collect::<Vec<_>>().join(", "),
        })
}

/// Builds a shape from its spec string, e.g. `torus:R=0.5,r=0.2`.
pub fn from_spec(spec: &str) -> Result<Box<dyn Shape>> {
    spec.parse::<ShapeSpec>()?.build()
}

/// Listing of every built-in shape with its default parameters.
pub fn catalog() -> Vec<ShapeInfo> {
    DEFS.iter()
        .map(|d| {
            ShapeSpec::named(d.name)
                .build()
                .expect("defaults are valid")
                .info()
        })
        .collect()
}

/// A slab (offset region) over a stadium with circular holes centred at `xs` on the x axis.
fn holed_slab(
    p: &Params,
    name: &str,
    d: f64,
    ro: f64,
    ri: f64,
    r: f64,
    xs: &[f64],
) -> Result<Box<dyn Shape>> {
    if ri <= r {
        return Err(p.error("ri", format!("{ri} must exceed the offset r = {r}")));
    }
    if ri >= ro {
        return Err(p.error("ri", format!("{ri} must be < ro = {ro}")));
    }
    let gap = xs
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    if 2.0 * ri >= gap {
        return Err(p.error(
            "ri",
            format!("holes of radius {ri} overlap (centres {gap} apart)"),
        ));
    }
    let g = slab::Slab::new(holed_region(d, ro, ri, xs), r).map_err(|m| p.error("r", m))?;
    Ok(boxed(name, g))
}

/// A stadium (half-length `d`, radius `ro`) with circular holes of radius `ri` centred at
/// `xs` on the x axis.
fn holed_region(d: f64, ro: f64, ri: f64, xs: &[f64]) -> Region2 {
    let mut lps = vec![loops::stadium(d, ro)];
    lps.extend(
        xs.iter()
            .map(|&x| loops::circle(DVec2::new(x, 0.0), ri, false)),
    );
    Region2::new(lps)
}

/// The square [-1, 1]^2 with a central circular hole of radius `rh`.
fn cube_with_hole_region(rh: f64) -> Region2 {
    Region2::new(vec![
        loops::rect(DVec2::splat(-1.0), DVec2::splat(1.0)),
        loops::circle(DVec2::ZERO, rh, false),
    ])
}

/// The sharp star polygon of [`star_points`].
fn star_region(k: usize, ri: f64) -> Region2 {
    Region2::new(vec![loops::polygon(&star_points(k, ri))])
}

/// The star of [`star_points`] with its inner (reflex) corners filleted by radius `f`.
fn star_smooth_region(k: usize, ri: f64, f: f64) -> Region2 {
    let radii: Vec<f64> = (0..2 * k)
        .map(|i| if i % 2 == 1 { f } else { 0.0 })
        .collect();
    Region2::new(vec![loops::filleted_polygon(&star_points(k, ri), &radii)])
}

/// Star polygon, counter-clockwise: tips at radius 1 (angle 90 deg first), inner
/// vertices at radius `ri`.
fn star_points(k: usize, ri: f64) -> Vec<DVec2> {
    (0..2 * k)
        .map(|i| {
            let ang = std::f64::consts::FRAC_PI_2 + std::f64::consts::PI * i as f64 / k as f64;
            DVec2::from_angle(ang) * if i % 2 == 0 { 1.0 } else { ri }
        })
        .collect()
}

/// The fandisk-like profile (counter-clockwise). Corners and their dihedral angles:
/// A 90, B 90, C 150, D 120, E 150 and F 150 (the ends of the concave cylindrical cut),
/// G 120 (reflex), T 30 (spike tip), U 90 (reflex), V 90.
fn fandisk_profile() -> Vec<Elem2> {
    let deg = |a: f64| DVec2::from_angle(a.to_radians());
    let a = DVec2::new(-1.5, 0.0);
    let b = DVec2::new(1.5, 0.0);
    let c = DVec2::new(1.5, 0.4);
    let dd = c + deg(120.0) * 0.5;
    let e = DVec2::new(0.9, dd.y);
    let f = DVec2::new(0.3, dd.y);
    let g = DVec2::new(-0.2, dd.y);
    let t = g + deg(120.0) * 0.8;
    let u = DVec2::new(t.x, 0.8);
    let v = DVec2::new(-1.5, 0.8);
    // Concave cut from e to f: the circle below the chord at 30 deg from the top face.
    let beta = 30f64.to_radians();
    let rho = 0.5 * (e.x - f.x) / beta.sin();
    let centre = DVec2::new(0.5 * (e.x + f.x), dd.y + rho * beta.cos());
    let a0 = (e - centre).y.atan2((e - centre).x);
    let cut = Elem2::Arc {
        c: centre,
        r: rho,
        a0,
        sweep: -2.0 * beta,
    };
    // Neighbouring segments end exactly where the arc does.
    let (e, f) = (cut.start(), cut.end());
    vec![
        Elem2::Seg { a, b },
        Elem2::Seg { a: b, b: c },
        Elem2::Seg { a: c, b: dd },
        Elem2::Seg { a: dd, b: e },
        cut,
        Elem2::Seg { a: f, b: g },
        Elem2::Seg { a: g, b: t },
        Elem2::Seg { a: t, b: u },
        Elem2::Seg { a: u, b: v },
        Elem2::Seg { a: v, b: a },
    ]
}

/// One row of `reconbench shapes`: the summary plus the description and default
/// parameters (natural units, before normalisation to unit diagonal).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShapeListing {
    /// Genus, components, features, area (normalised).
    #[serde(flatten)]
    pub info: ShapeInfo,
    /// One-line description.
    pub summary: String,
    /// Parameters with their defaults.
    pub params: BTreeMap<String, f64>,
    /// Scale applied to the natural definition to reach unit diagonal.
    pub scale: f64,
}

/// [`catalog`] with descriptions and parameters, for `reconbench shapes [--json]`.
pub fn listing() -> Vec<ShapeListing> {
    DEFS.iter()
        .map(|d| {
            let s = ShapeSpec::named(d.name)
                .build()
                .expect("defaults are valid");
            ShapeListing {
                info: s.info(),
                summary: d.summary.to_string(),
                params: d.params.iter().map(|&(k, v)| (k.to_string(), v)).collect(),
                scale: s.scale(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn default(shape: &str, key: &str) -> f64 {
        let d = find_def(shape).unwrap();
        d.params.iter().find(|p| p.0 == key).unwrap().1
    }

    /// The planar regions of every built-in prism and slab, with default parameters.
    fn builtin_regions() -> Vec<(&'static str, Region2)> {
        let dt = |k: &str| default("double-torus", k);
        let th = |k: &str| default("three-holes", k);
        let ss = |k: &str| default("star-smooth", k);
        vec![
            (
                "double-torus",
                holed_region(dt("d"), dt("ro"), dt("ri"), &[-dt("d"), dt("d")]),
            ),
            (
                "three-holes",
                holed_region(th("d"), th("ro"), th("ri"), &[-th("d"), 0.0, th("d")]),
            ),
            (
                "cube-with-hole",
                cube_with_hole_region(default("cube-with-hole", "rh")),
            ),
            (
                "star-sharp",
                star_region(
                    default("star-sharp", "k") as usize,
                    default("star-sharp", "ri"),
                ),
            ),
            (
                "star-smooth",
                star_smooth_region(ss("k") as usize, ss("ri"), ss("f")),
            ),
            ("fandisk-like", Region2::new(vec![fandisk_profile()])),
        ]
    }

    /// Winding number of the boundary (arcs as fine polylines) around `q`.
    fn winding(region: &Region2, q: DVec2) -> f64 {
        let mut w = 0.0;
        for e in region.elems() {
            let n = if matches!(e, Elem2::Arc { .. }) {
                256
            } else {
                1
            };
            for s in e.polyline(n).windows(2) {
                let (a, b) = (s[0] - q, s[1] - q);
                w += a.perp_dot(b).atan2(a.dot(b));
            }
        }
        w / std::f64::consts::TAU
    }

    /// The parity test of `Region2::contains` (which decides cap vs. rim in every slab and
    /// prism closest point) casts a horizontal ray: check it exactly on the degenerate
    /// lines, i.e. at the heights of every element end point, arc centre and arc extreme
    /// (the double-torus' holes have their rim end points on the line through their
    /// centres), against an independent winding number.
    #[test]
    fn region_containment_is_exact_on_degenerate_rays() {
        for (name, region) in builtin_regions() {
            region.check_closed().unwrap();
            let mut ys = Vec::new();
            for e in region.elems() {
                ys.extend([e.start().y, e.end().y]);
                if let Elem2::Arc { c, r, .. } = *e {
                    ys.extend([c.y, c.y + r, c.y - r]);
                }
            }
            let (lo, hi) = region.bounds();
            let mut xs: Vec<f64> = (0..=200)
                .map(|i| lo.x - 0.1 + (hi.x - lo.x + 0.2) * i as f64 / 200.0)
                .collect();
            xs.push(0.0);
            ys.sort_by(f64::total_cmp);
            ys.dedup();
            for y in ys {
                for &x in &xs {
                    let q = DVec2::new(x, y);
                    if region.closest_boundary(q).dist2 < 1e-6 {
                        continue; // on (or within polyline error of) the boundary
                    }
                    let inside = winding(&region, q).abs() > 0.5;
                    assert_eq!(region.contains(q), inside, "{name}: contains({q})");
                }
            }
        }
    }
}
