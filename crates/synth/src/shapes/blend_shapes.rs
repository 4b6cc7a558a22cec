//! The test objects of seed 002 ch. 5 (Weber 2011, blending, experiment E18) as exact
//! ground truth: a part with a designed tube standing on it, the union that the `blend`
//! filter of `reconbench-filters` approximates by blending its NURBS tube into a scan of
//! the part.
//!
//! * [`TubePlacement`] is the one placement rule of the tube, relative to a bounding box
//!   (fractions of the box per axis for the foot, of its diagonal for the lengths). The
//!   filter places its NURBS tube with it relative to the scan's box (or a given frame);
//!   these shapes place the analytic tube with it relative to the part's box.
//! * [`BlendShape`] is the union surface: the part's surface outside the (open) tube
//!   solid, and the tube wall outside the part, from where it leaves the part up to the
//!   open outer rim (the filter samples no cap: the end is open, so the surface has one
//!   boundary loop, genus 0, and is not closed). The junction curve J (where the wall
//!   leaves the part) is a sharp feature curve; the part's feature curves are trimmed by
//!   the tube, and the points where they meet J are corners.
//! * What a scanner sees is the part alone ([`Shape::scanned_part`]): a dataset with
//!   `shape = "box-tube"` samples the box (at the union's scale) and measures the result
//!   against the union.
//!
//! Natural units: the part as in its catalogue entry (box `[-a, a] x [-b, b] x [-c, c]`;
//! the fandisk-like prism), the tube placed in the part's box, the union scaled to unit
//! bounding-box diagonal.
//!
//! Exact closest point. The part is a right prism (the box over a rectangle); its
//! patches are the two caps, a rectangle per profile segment and a cylinder strip per
//! profile arc. Every patch has at most one interior local minimum of the distance (its
//! unconstrained closest point), the rectangles are convex and no two arcs meet, so the
//! closest point of the union is the nearest of (a) the part's closest point when it is
//! outside the tube solid, otherwise every patch's closest point outside it, (b) the
//! wall's closest point when it is outside the part, and (c) when (a) or (b) was
//! rejected, the closest point of J (the restricted minimum of a patch whose own minimum
//! lies in the removed region is on its trimming curve, which is J). J is known in closed
//! form per angle around the axis (the first hit of the wall line with the part from the
//! rim); its closest point is found on 1024 samples and refined by golden-section search
//! to 1e-15 rad. Normals on J are the tube wall's; elsewhere as in the part.

use std::f64::consts::TAU;

use glam::{DVec2, DVec3};
use rand::Rng;
use reconbench_geom::{Aabb, TriMesh};

use super::{Geometry, Normalized, Params};
use crate::error::Result;
use crate::features::{Feature, FeatureGeom, dihedral_deg};
use crate::geom2d::{Elem2, Region2, loops};
use crate::shape::{FeatureCurve, Sample, Shape, SurfacePoint};
use crate::shapes::boxes::BoxShape;
use crate::shapes::prism::Prism;
use crate::util::{cumulative, pick_weighted, uniform, wrap_tau};

/// Samples of the junction curve around the axis.
const J_SAMPLES: usize = 1024;

/// A unit vector perpendicular to the unit vector `a` (the tube's angle origin).
pub fn perpendicular(a: DVec3) -> DVec3 {
    let helper = if a.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    a.cross(helper).normalize()
}

/// Where a designed tube stands, in absolute coordinates: the one placement rule shared
/// by the `blend` filter and the blend shapes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TubePlacement {
    /// Where the axis meets the part.
    pub foot: DVec3,
    /// Unit axis, pointing away from the part towards the open outer rim.
    pub axis: DVec3,
    /// Angle origin around the axis (unit, perpendicular to it).
    pub e1: DVec3,
    /// `axis x e1`: angle 90 degrees.
    pub e2: DVec3,
    /// Radius.
    pub radius: f64,
    /// Length outside the part: the outer rim is at `foot + length axis`.
    pub length: f64,
    /// Length into the part: the inner end is at `foot - depth axis`.
    pub depth: f64,
}

impl TubePlacement {
    /// The tube for the box `[min, max]`: the foot at `min + center_rel (max - min)`,
    /// the axis along `axis` (any nonzero length), radius, length and depth as fractions
    /// of the box's diagonal. Errors name the offending parameter.
    pub fn new(
        center_rel: [f64; 3],
        axis: [f64; 3],
        radius_rel: f64,
        length_rel: f64,
        depth_rel: f64,
        min: DVec3,
        max: DVec3,
    ) -> std::result::Result<Self, (&'static str, String)> {
        if !center_rel.iter().all(|c| c.is_finite()) {
            return Err(("center_rel", format!("must be finite, got {center_rel:?}")));
        }
        let a = DVec3::from_array(axis);
        if !(a.is_finite() && a.length() > 0.0) {
            return Err((
                "axis",
                format!("must be a finite nonzero vector, got {axis:?}"),
            ));
        }
        for (name, v, strict) in [
            ("radius_rel", radius_rel, true),
            ("length_rel", length_rel, true),
            ("depth_rel", depth_rel, false),
        ] {
            if !(v.is_finite() && (v > 0.0 || (!strict && v == 0.0))) {
                let op = if strict { ">" } else { ">=" };
                return Err((name, format!("must be finite and {op} 0, got {v}")));
            }
        }
        let diag = (max - min).length();
        if !(diag.is_finite() && diag > 0.0) {
            return Err((
                "frame",
                format!("the bounding box [{min}, {max}] has no positive finite diagonal"),
            ));
        }
        let axis = a.normalize();
        let e1 = perpendicular(axis);
        Ok(Self {
            foot: min + DVec3::from_array(center_rel) * (max - min),
            axis,
            e1,
            e2: axis.cross(e1),
            radius: radius_rel * diag,
            length: length_rel * diag,
            depth: depth_rel * diag,
        })
    }

    /// Centre of the outer rim.
    pub fn outer_centre(&self) -> DVec3 {
        self.foot + self.axis * self.length
    }

    /// Centre of the inner end.
    pub fn inner_centre(&self) -> DVec3 {
        self.foot - self.axis * self.depth
    }

    /// Unit radial direction at angle `theta` (0 = `e1`).
    pub fn radial(&self, theta: f64) -> DVec3 {
        let (s, c) = theta.sin_cos();
        self.e1 * c + self.e2 * s
    }

    /// Angle around the axis (in `(-pi, pi]`) and distance from it.
    pub fn polar(&self, p: DVec3) -> (f64, f64) {
        let q = p - self.foot;
        let radial = q - self.axis * q.dot(self.axis);
        (
            radial.dot(self.e2).atan2(radial.dot(self.e1)),
            radial.length(),
        )
    }

    /// Position along the axis from the foot.
    pub fn axial(&self, p: DVec3) -> f64 {
        (p - self.foot).dot(self.axis)
    }

    /// Whether `p` is strictly inside the tube solid (between inner end and outer rim).
    pub fn contains(&self, p: DVec3) -> bool {
        let s = self.axial(p);
        s > -self.depth && s < self.length && self.polar(p).1 < self.radius
    }

    /// Closest point of the wall (axial position clamped to the tube) and its outward
    /// (radial) normal.
    pub fn wall_closest(&self, p: DVec3) -> (DVec3, DVec3) {
        let q = p - self.foot;
        let s = q.dot(self.axis);
        let radial = q - self.axis * s;
        let dir = if radial.length_squared() > 0.0 {
            radial.normalize()
        } else {
            self.e1
        };
        let sc = s.clamp(-self.depth, self.length);
        (self.foot + self.axis * sc + dir * self.radius, dir)
    }

    /// The placement scaled by `s` about the origin.
    fn scaled(&self, s: f64) -> Self {
        Self {
            foot: self.foot * s,
            radius: self.radius * s,
            length: self.length * s,
            depth: self.depth * s,
            ..*self
        }
    }
}

fn lift(q: DVec2, z: f64) -> DVec3 {
    DVec3::new(q.x, q.y, z)
}

/// The part as a right prism split into patches (caps, one wall per profile element).
#[derive(Debug, Clone)]
struct PrismPatches {
    prism: Prism,
    region: Region2,
    elems: Vec<Elem2>,
    z0: f64,
    z1: f64,
}

impl PrismPatches {
    fn new(region: Region2, z0: f64, z1: f64) -> std::result::Result<Self, String> {
        let prism = Prism::new(region.clone(), z0, z1)?;
        let elems = region.elems().copied().collect();
        Ok(Self {
            prism,
            region,
            elems,
            z0,
            z1,
        })
    }

    fn n_patches(&self) -> usize {
        2 + self.elems.len()
    }

    /// Closest point of patch `k` (0, 1 the caps, then the walls) and its normal.
    fn patch_closest(&self, p: DVec3, k: usize) -> (DVec3, DVec3) {
        let q = DVec2::new(p.x, p.y);
        match k {
            0 | 1 => {
                let (z, nz) = if k == 0 {
                    (self.z0, -1.0)
                } else {
                    (self.z1, 1.0)
                };
                (lift(self.region.clamp(q), z), DVec3::Z * nz)
            }
            _ => {
                let c = self.elems[k - 2].closest(q);
                (
                    lift(c.point, p.z.clamp(self.z0, self.z1)),
                    lift(c.normal, 0.0),
                )
            }
        }
    }

    /// First crossing `t >= 0` of the ray `o + t d` with the part's surface, and the
    /// surface normal there.
    fn first_hit(&self, o: DVec3, d: DVec3) -> Option<(f64, DVec3)> {
        let mut best: Option<(f64, DVec3)> = None;
        let mut take = |t: f64, n: DVec3| {
            if t >= 0.0 && best.is_none_or(|b| t < b.0) {
                best = Some((t, n));
            }
        };
        if d.z != 0.0 {
            for (z, nz) in [(self.z0, -1.0), (self.z1, 1.0)] {
                let t = (z - o.z) / d.z;
                let x = o + d * t;
                if self.region.contains(DVec2::new(x.x, x.y)) {
                    take(t, DVec3::Z * nz);
                }
            }
        }
        let (o2, d2) = (DVec2::new(o.x, o.y), DVec2::new(d.x, d.y));
        if d2.length_squared() == 0.0 {
            return best;
        }
        let z_ok = |t: f64| {
            let z = o.z + d.z * t;
            z >= self.z0 && z <= self.z1
        };
        for e in &self.elems {
            match *e {
                Elem2::Seg { a, b } => {
                    let ab = b - a;
                    let den = d2.perp_dot(ab);
                    if den == 0.0 {
                        continue;
                    }
                    let t = (a - o2).perp_dot(ab) / den;
                    let u = (a - o2).perp_dot(d2) / den;
                    if (0.0..=1.0).contains(&u) && z_ok(t) {
                        take(t, lift(e.closest(o2 + d2 * t).normal, 0.0));
                    }
                }
                Elem2::Arc { c, r, a0, sweep } => {
                    let oc = o2 - c;
                    let (qa, qb, qc) = (d2.dot(d2), 2.0 * d2.dot(oc), oc.dot(oc) - r * r);
                    let disc = qb * qb - 4.0 * qa * qc;
                    if disc < 0.0 {
                        continue;
                    }
                    let sq = disc.sqrt();
                    for t in [(-qb - sq) / (2.0 * qa), (-qb + sq) / (2.0 * qa)] {
                        let x = o2 + d2 * t - c;
                        let ang = wrap_tau((x.y.atan2(x.x) - a0) * sweep.signum());
                        if ang <= sweep.abs() && z_ok(t) {
                            take(t, lift(e.closest(o2 + d2 * t).normal, 0.0));
                        }
                    }
                }
            }
        }
        best
    }
}

/// A part with a designed tube standing on it: the union surface (see the module docs).
#[derive(Debug)]
pub struct BlendShape {
    name: String,
    part: PrismPatches,
    /// What the scanner sees: the part at the union's scale.
    scanned: Box<dyn Shape>,
    /// The tube in natural units.
    tube: TubePlacement,
    /// Scale to unit diagonal.
    s: f64,
    /// Natural-units bounding box of the union.
    bounds: Aabb,
    /// J at `J_SAMPLES` equally spaced angles (natural units).
    junction: Vec<DVec3>,
    /// Smallest dihedral angle along J.
    junction_dihedral: f64,
    /// The part's features outside the tube plus the corners where they meet J
    /// (natural units).
    features: Vec<Feature>,
    /// Natural-units area of the union, and of the whole part and the whole wall (the
    /// rejection sampler's weights).
    area: f64,
    cum: Vec<f64>,
}

impl BlendShape {
    /// The union of `part` (its patches) and `tube` (natural units); `scanned` builds
    /// the scanned part at a given scale. Errors when the tube does not enter the part
    /// from outside all round, or crosses a curved feature.
    fn new(
        name: &str,
        part: PrismPatches,
        tube: TubePlacement,
        scanned: impl FnOnce(f64) -> Box<dyn Shape>,
    ) -> std::result::Result<Self, String> {
        let mut junction = Vec::with_capacity(J_SAMPLES);
        let mut junction_dihedral = 180.0f64;
        let mut wall_out = 0.0;
        for k in 0..J_SAMPLES {
            let th = TAU * k as f64 / J_SAMPLES as f64;
            let rim = tube.outer_centre() + tube.radial(th) * tube.radius;
            if part.prism.inside(rim) {
                return Err(format!(
                    "the tube's outer rim lies inside the part (angle {th:.3} rad): lengthen it (length_rel) or move it (c*, a*)"
                ));
            }
            let (p, n) = junction_at(&part, &tube, th).ok_or_else(|| {
                format!("the tube does not reach into the part at angle {th:.3} rad: deepen it (depth_rel) or move it (c*, a*)")
            })?;
            junction.push(p);
            junction_dihedral = junction_dihedral.min(dihedral_deg(n, tube.radial(th)));
            wall_out += tube.radius * (tube.length - tube.axial(p)) * TAU / J_SAMPLES as f64;
        }
        let features = trim_features(&part, &tube, junction_dihedral)?;
        let footprint = footprint_area(&part, &tube);
        let part_area = part.prism.area();
        let wall_area = TAU * tube.radius * (tube.length + tube.depth);
        let lo_s = junction
            .iter()
            .map(|&p| tube.axial(p))
            .fold(f64::INFINITY, f64::min);
        let mut bounds = part.prism.aabb();
        for s in [lo_s, tube.length] {
            let c = tube.foot + tube.axis * s;
            // A circle of radius rho normal to the unit axis a spans rho sqrt(1 - a_i^2)
            // along axis i.
            let ext = DVec3::ONE - tube.axis * tube.axis;
            let r = DVec3::new(
                ext.x.max(0.0).sqrt(),
                ext.y.max(0.0).sqrt(),
                ext.z.max(0.0).sqrt(),
            ) * tube.radius;
            bounds = bounds.union(Aabb {
                min: c - r,
                max: c + r,
            });
        }
        let s = 1.0 / bounds.diagonal();
        Ok(Self {
            name: name.to_string(),
            scanned: scanned(s),
            part,
            tube,
            s,
            bounds,
            junction,
            junction_dihedral,
            features,
            area: part_area - footprint + wall_out,
            cum: cumulative(&[part_area, wall_area]),
        })
    }

    /// The tube in the normalised frame.
    pub fn tube(&self) -> TubePlacement {
        self.tube.scaled(self.s)
    }

    /// J at angle `theta` (natural units); the last resort for a numerically missing
    /// hit is the sample.
    fn junction_point(&self, theta: f64) -> DVec3 {
        junction_at(&self.part, &self.tube, theta).map_or_else(
            || {
                let k = (wrap_tau(theta) / TAU * J_SAMPLES as f64).round() as usize % J_SAMPLES;
                self.junction[k]
            },
            |h| h.0,
        )
    }

    /// Closest point of J to `q` (natural units).
    fn junction_closest(&self, q: DVec3) -> DVec3 {
        let (k, _) = self
            .junction
            .iter()
            .enumerate()
            .map(|(i, p)| (i, (*p - q).length_squared()))
            .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
        let h = TAU / J_SAMPLES as f64;
        let th0 = h * k as f64;
        let f = |t: f64| (self.junction_point(t) - q).length_squared();
        // Golden-section search on the bracket of the nearest sample.
        let g = 0.5 * (5f64.sqrt() - 1.0);
        let (mut a, mut b) = (th0 - h, th0 + h);
        let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
        let (mut fc, mut fd) = (f(c), f(d));
        // 0.618^75 * 2h < 1e-15: the bracket reaches rounding within the bound.
        for _ in 0..100 {
            if b - a <= 1e-15 {
                break;
            }
            if fc < fd {
                b = d;
                d = c;
                fd = fc;
                c = b - g * (b - a);
                fc = f(c);
            } else {
                a = c;
                c = d;
                fc = fd;
                d = a + g * (b - a);
                fd = f(d);
            }
        }
        let best = self.junction_point(0.5 * (a + b));
        if (best - q).length_squared() <= (self.junction[k] - q).length_squared() {
            best
        } else {
            self.junction[k]
        }
    }

    /// Exact closest point of the union (natural units).
    fn closest_natural(&self, p: DVec3) -> SurfacePoint {
        let mut best = SurfacePoint {
            point: p,
            normal: DVec3::Z,
            distance: f64::INFINITY,
        };
        let mut consider = |q: DVec3, n: DVec3| {
            let d = (p - q).length();
            if d < best.distance {
                best = SurfacePoint {
                    point: q,
                    normal: n,
                    distance: d,
                };
            }
        };
        let mut need_junction = false;
        let ca = self.part.prism.closest(p);
        if self.tube.contains(ca.point) {
            need_junction = true;
            for k in 0..self.part.n_patches() {
                let (q, n) = self.part.patch_closest(p, k);
                if !self.tube.contains(q) {
                    consider(q, n);
                }
            }
        } else {
            consider(ca.point, ca.normal);
        }
        let (w, wn) = self.tube.wall_closest(p);
        if self.part.prism.inside(w) {
            need_junction = true;
        } else {
            consider(w, wn);
        }
        if need_junction {
            let j = self.junction_closest(p);
            let (_, n) = self.tube.wall_closest(j);
            consider(j, n);
        }
        best
    }

    /// Whether `p` (natural units) is inside the union solid (the part, or the tube
    /// between its inner end and its open rim).
    fn inside_natural(&self, p: DVec3) -> bool {
        self.part.prism.inside(p) || self.tube.contains(p)
    }

    /// Closest point of the union closed by the rim disc (for the reference mesh).
    fn closest_capped(&self, p: DVec3) -> SurfacePoint {
        let open = self.closest_natural(p);
        let c = self.tube.outer_centre();
        let q = p - c;
        let radial = q - self.tube.axis * q.dot(self.tube.axis);
        let r = radial.length();
        let on = c + if r > self.tube.radius {
            radial * (self.tube.radius / r)
        } else {
            radial
        };
        let d = (p - on).length();
        if d < open.distance {
            SurfacePoint {
                point: on,
                normal: self.tube.axis,
                distance: d,
            }
        } else {
            open
        }
    }

    fn on_rim_disc(&self, p: DVec3) -> bool {
        let tol = 1e-9 * self.bounds.diagonal();
        (self.tube.axial(p) - self.tube.length).abs() <= tol
            && self.tube.polar(p).1 <= self.tube.radius + tol
    }
}

/// J at angle `theta`: the first crossing of the wall line, followed from the rim
/// towards the inner end, with the part, and the part's normal there. `None` when the
/// line misses the part before the inner end.
fn junction_at(part: &PrismPatches, tube: &TubePlacement, theta: f64) -> Option<(DVec3, DVec3)> {
    let o = tube.outer_centre() + tube.radial(theta) * tube.radius;
    let (t, n) = part.first_hit(o, -tube.axis)?;
    (t <= tube.length + tube.depth).then_some((o - tube.axis * t, n))
}

/// Area of the part's surface inside the tube (midpoint rule over the tube's cross
/// section: area element `r dr dtheta / |n . axis|` at the first hit from the rim).
fn footprint_area(part: &PrismPatches, tube: &TubePlacement) -> f64 {
    let (nr, nt) = (64, 512);
    let (dr, dt) = (tube.radius / nr as f64, TAU / nt as f64);
    let mut a = 0.0;
    for i in 0..nr {
        let r = (i as f64 + 0.5) * dr;
        for j in 0..nt {
            let th = (j as f64 + 0.5) * dt;
            let o = tube.outer_centre() + tube.radial(th) * r;
            if let Some((_, n)) = part.first_hit(o, -tube.axis) {
                let c = n.dot(tube.axis).abs();
                if c > 1e-9 {
                    a += r * dr * dt / c;
                }
            }
        }
    }
    a
}

/// The part's features outside the tube solid, plus a corner wherever a part edge
/// crosses J. Errors when the tube crosses a curved feature.
fn trim_features(
    part: &PrismPatches,
    tube: &TubePlacement,
    junction_dihedral: f64,
) -> std::result::Result<Vec<Feature>, String> {
    let mut out = Vec::new();
    for f in part.prism.features() {
        match f.geom {
            FeatureGeom::Point(c) => {
                if !tube.contains(c) {
                    out.push(f);
                }
            }
            FeatureGeom::Arc { .. } => {
                if f.geom.polyline(1e-6).iter().any(|&p| tube.contains(p)) {
                    return Err("the tube crosses a curved feature edge of the part".into());
                }
                out.push(f);
            }
            FeatureGeom::Segment { a, b } => {
                let Some((t0, t1)) = segment_in_tube(tube, a, b) else {
                    out.push(f);
                    continue;
                };
                let at = |t: f64| a + (b - a) * t;
                for (u, v) in [(0.0, t0), (t1, 1.0)] {
                    if v > u {
                        out.push(Feature {
                            geom: FeatureGeom::Segment { a: at(u), b: at(v) },
                            dihedral_deg: f.dihedral_deg,
                        });
                    }
                }
                for t in [t0, t1] {
                    if t > 0.0 && t < 1.0 {
                        out.push(Feature {
                            geom: FeatureGeom::Point(at(t)),
                            dihedral_deg: f.dihedral_deg.min(junction_dihedral),
                        });
                    }
                }
            }
        }
    }
    Ok(out)
}

/// The parameter interval `(t0, t1)` of the segment `a b` inside the tube solid (a
/// convex set, so one interval), clipped to `[0, 1]`; `None` when empty.
fn segment_in_tube(tube: &TubePlacement, a: DVec3, b: DVec3) -> Option<(f64, f64)> {
    let d = b - a;
    let (sa, sd) = (tube.axial(a), d.dot(tube.axis));
    // Axial slab.
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    if sd == 0.0 {
        if !(sa > -tube.depth && sa < tube.length) {
            return None;
        }
    } else {
        let (u, v) = ((-tube.depth - sa) / sd, (tube.length - sa) / sd);
        lo = lo.max(u.min(v));
        hi = hi.min(u.max(v));
    }
    // Radial: |ra + t rd|^2 < radius^2.
    let q = a - tube.foot;
    let ra = q - tube.axis * q.dot(tube.axis);
    let rd = d - tube.axis * sd;
    let (qa, qb, qc) = (
        rd.dot(rd),
        2.0 * ra.dot(rd),
        ra.dot(ra) - tube.radius * tube.radius,
    );
    if qa == 0.0 {
        if qc >= 0.0 {
            return None;
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc <= 0.0 {
            return None;
        }
        let sq = disc.sqrt();
        lo = lo.max((-qb - sq) / (2.0 * qa));
        hi = hi.min((-qb + sq) / (2.0 * qa));
    }
    (hi > lo).then_some((lo, hi))
}

impl Shape for BlendShape {
    fn name(&self) -> &str {
        &self.name
    }

    fn closest_point(&self, p: DVec3) -> SurfacePoint {
        let c = self.closest_natural(p / self.s);
        SurfacePoint {
            point: c.point * self.s,
            normal: c.normal,
            distance: c.distance * self.s,
        }
    }

    fn is_inside(&self, p: DVec3) -> bool {
        self.inside_natural(p / self.s)
    }

    /// Rejection sampling: a point of the whole part or of the whole wall (by area),
    /// kept when it is on the union.
    fn sample_uniform(&self, n: usize, rng: &mut dyn Rng) -> Vec<Sample> {
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            let x = if pick_weighted(rng, &self.cum) == 0 {
                let x = self.part.prism.sample(rng);
                if self.tube.contains(x.position) {
                    continue;
                }
                x
            } else {
                let th = uniform(rng, 0.0, TAU);
                let s = uniform(rng, -self.tube.depth, self.tube.length);
                let dir = self.tube.radial(th);
                let p = self.tube.foot + self.tube.axis * s + dir * self.tube.radius;
                if self.part.prism.inside(p) {
                    continue;
                }
                Sample {
                    position: p,
                    normal: dir,
                }
            };
            out.push(Sample {
                position: x.position * self.s,
                normal: x.normal,
            });
        }
        out
    }

    fn aabb(&self) -> Aabb {
        Aabb {
            min: self.bounds.min * self.s,
            max: self.bounds.max * self.s,
        }
    }

    fn scale(&self) -> f64 {
        self.s
    }

    /// The part's area minus its footprint in the tube (midpoint rule, relative error
    /// about 1e-5; exact for a footprint on a plane normal to the axis) plus the wall
    /// outside the part (trapezoid rule over the J samples).
    fn area(&self) -> f64 {
        self.area * self.s * self.s
    }

    fn genus(&self) -> u32 {
        0
    }

    fn is_closed(&self) -> bool {
        false
    }

    fn feature_curves(&self) -> Vec<FeatureCurve> {
        let mut out: Vec<FeatureCurve> = self
            .features
            .iter()
            .map(|f| {
                Feature {
                    geom: f.geom.scaled(self.s),
                    dihedral_deg: f.dihedral_deg,
                }
                .to_curve(1e-5)
            })
            .collect();
        let mut points: Vec<DVec3> = self.junction.iter().map(|&p| p * self.s).collect();
        points.push(points[0]);
        out.push(FeatureCurve {
            points,
            dihedral_deg: self.junction_dihedral,
            is_corner: false,
        });
        out
    }

    fn feature_distance(&self, p: DVec3) -> f64 {
        let q = p / self.s;
        let part = crate::features::feature_distance(&self.features, q);
        part.min((self.junction_closest(q) - q).length()) * self.s
    }

    /// Marching tetrahedra of the union closed by its rim disc, vertices projected onto
    /// that closed surface, the faces on the disc removed and the vertices left on it
    /// moved radially onto the rim: an open mesh with one boundary loop.
    fn reference_mesh(&self, resolution: usize) -> TriMesh {
        let sdf = |p: DVec3| {
            let d = self.closest_capped(p).distance;
            if self.inside_natural(p) { -d } else { d }
        };
        let (v, f) = crate::polygonize::marching_tetrahedra(&sdf, self.bounds, resolution.max(4));
        let mut v: Vec<DVec3> = v
            .into_iter()
            .map(|p| self.closest_capped(p).point)
            .collect();
        let on: Vec<bool> = v.iter().map(|&p| self.on_rim_disc(p)).collect();
        let f: Vec<[u32; 3]> = f
            .into_iter()
            .filter(|t| !t.iter().all(|&i| on[i as usize]))
            .collect();
        for (i, p) in v.iter_mut().enumerate() {
            if on[i] {
                let (_, dir) = self.tube.wall_closest(*p);
                *p = self.tube.outer_centre() + dir * self.tube.radius;
            }
        }
        let mut map = vec![u32::MAX; v.len()];
        let mut verts = Vec::new();
        let faces: Vec<[u32; 3]> = f
            .iter()
            .map(|t| {
                t.map(|i| {
                    if map[i as usize] == u32::MAX {
                        map[i as usize] = verts.len() as u32;
                        verts.push(v[i as usize] * self.s);
                    }
                    map[i as usize]
                })
            })
            .collect();
        TriMesh::new(verts, faces).expect("generated meshes are finite and indexed")
    }

    fn scanned_part(&self) -> Option<&dyn Shape> {
        Some(self.scanned.as_ref())
    }
}

/// The part `g` as a catalogue shape at scale `s` (instead of its own unit-diagonal
/// scale): what the scanner sees of a blend shape.
fn part_at_scale<G: Geometry + 'static>(name: &str, g: G, s: f64) -> Box<dyn Shape> {
    let features = g
        .features()
        .into_iter()
        .map(|f| Feature {
            geom: f.geom.scaled(s),
            dihedral_deg: f.dihedral_deg,
        })
        .collect();
    Box::new(Normalized {
        name: name.to_string(),
        g,
        s,
        features,
    })
}

/// The tube of a catalogue entry's parameters (`cx, cy, cz`, `ax, ay, az`,
/// `radius_rel`, `length_rel`, `depth_rel`) in the part's natural bounding box.
fn tube_params(p: &Params, part_box: Aabb) -> Result<TubePlacement> {
    TubePlacement::new(
        [p.get("cx"), p.get("cy"), p.get("cz")],
        [p.get("ax"), p.get("ay"), p.get("az")],
        p.get("radius_rel"),
        p.get("length_rel"),
        p.get("depth_rel"),
        part_box.min,
        part_box.max,
    )
    .map_err(|(k, m)| {
        let key = match k {
            "center_rel" => "cx",
            "axis" => "ax",
            other => other,
        };
        p.error(key, m)
    })
}

/// `box-tube`: the box of half-extents `a, b, c` with the tube (see [`tube_params`]).
pub(super) fn box_tube(p: &Params) -> Result<Box<dyn Shape>> {
    let h = DVec3::new(p.positive("a")?, p.positive("b")?, p.positive("c")?);
    let part = PrismPatches::new(
        Region2::new(vec![loops::rect(
            DVec2::new(-h.x, -h.y),
            DVec2::new(h.x, h.y),
        )]),
        -h.z,
        h.z,
    )
    .map_err(|m| p.error("a", m))?;
    let tube = tube_params(p, part.prism.aabb())?;
    let shape = BlendShape::new("box-tube", part, tube, |s| {
        part_at_scale("box", BoxShape::new(h), s)
    })
    .map_err(|m| p.error("cx", m))?;
    Ok(Box::new(shape))
}

/// `fandisk-tube`: the fandisk-like part of extrusion depth `depth` with the tube.
pub(super) fn fandisk_tube(p: &Params) -> Result<Box<dyn Shape>> {
    let d = p.positive("depth")?;
    let region = Region2::new(vec![super::fandisk_profile()]);
    let part =
        PrismPatches::new(region.clone(), -0.5 * d, 0.5 * d).map_err(|m| p.error("depth", m))?;
    let tube = tube_params(p, part.prism.aabb())?;
    let scanned_prism = part.prism.clone();
    let shape = BlendShape::new("fandisk-tube", part, tube, |s| {
        part_at_scale("fandisk-like", scanned_prism, s)
    })
    .map_err(|m| p.error("cx", m))?;
    Ok(Box::new(shape))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::ShapeSpec;

    #[test]
    fn the_box_tube_junction_is_the_circle_on_the_top_face() {
        let s = ShapeSpec::named("box-tube").build().unwrap();
        let scan = s.scanned_part().unwrap();
        // The scanned part is the box at the union's scale.
        assert_eq!(scan.name(), "box");
        let b = scan.aabb();
        assert!((b.max.z - s.aabb().max.z).abs() > 0.1);
        let j = s.feature_curves().pop().unwrap();
        assert!((j.dihedral_deg - 90.0).abs() < 1e-9);
        let top = b.max.z;
        let centre = DVec3::new(0.0, 0.0, top);
        let r = 0.1 * b.diagonal();
        for p in &j.points {
            assert!((p.z - top).abs() < 1e-12);
            assert!(((*p - centre).length() - r).abs() < 1e-12);
        }
        // Area: box minus the disc plus the wall of height 0.2 part diagonals.
        let h = 0.2 * b.diagonal();
        let want = 6.0 * (b.max.x - b.min.x).powi(2) - std::f64::consts::PI * r * r + TAU * r * h;
        assert!(
            (s.area() - want).abs() < 1e-12 * want,
            "{} vs {want}",
            s.area()
        );
    }

    #[test]
    fn closest_points_match_the_union_in_closed_form_on_the_box_tube() {
        let s = ShapeSpec::named("box-tube").build().unwrap();
        let b = s.scanned_part().unwrap().aabb();
        let hx = b.max.x;
        let (top, r) = (b.max.z, 0.1 * b.diagonal());
        let h = 0.2 * b.diagonal();
        // Independent closed form: the cube, the disc removed, the wall outside the cube.
        let exact = |q: DVec3| -> f64 {
            let mut best = f64::INFINITY;
            for axis in 0..3 {
                for sign in [-1.0, 1.0] {
                    let mut c = q.clamp(DVec3::splat(-hx), DVec3::splat(hx));
                    c[axis] = sign * hx;
                    if axis == 2 && sign > 0.0 {
                        let l = c.truncate().length();
                        if l < r {
                            let d = if l > 0.0 { c.truncate() / l } else { DVec2::X };
                            c = (d * r).extend(top);
                        }
                    }
                    best = best.min((q - c).length());
                }
            }
            let l = q.truncate().length();
            let d = if l > 0.0 { q.truncate() / l } else { DVec2::X };
            let w = (d * r).extend(q.z.clamp(top, top + h));
            best.min((q - w).length())
        };
        let mut rng = crate::util::rng_for(3, "box-tube", 0);
        for _ in 0..4000 {
            let q = DVec3::new(
                uniform(&mut rng, -0.4, 0.4),
                uniform(&mut rng, -0.4, 0.4),
                uniform(&mut rng, -0.4, 0.6),
            );
            let got = s.distance(q);
            assert!((got - exact(q)).abs() < 1e-12, "{q}: {got} vs {}", exact(q));
        }
    }

    /// The blend experiments place the filter's tube in the scanned part's box (`frame`),
    /// written out as numbers: they must be that box.
    #[test]
    fn the_frames_of_the_blend_experiments_are_the_scanned_parts_boxes() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../experiments/paper");
        for file in ["weber_blend.toml", "weber_blend_fandisk.toml"] {
            let text = std::fs::read_to_string(dir.join(file)).unwrap();
            let doc: toml::Table = toml::from_str(&text).unwrap();
            let shape = doc["datasets"].as_array().unwrap()[0]["shape"]
                .as_str()
                .unwrap()
                .to_string();
            let b = ShapeSpec::named(&shape)
                .build()
                .unwrap()
                .scanned_part()
                .unwrap()
                .aabb();
            let mut checked = 0;
            for m in doc["methods"].as_array().unwrap() {
                // `frame = [[min, max]]`: a grid of one value.
                let f = &m["params"]["frame"].as_array().unwrap()[0];
                for (k, want) in [(0, b.min), (1, b.max)] {
                    let v = f.as_array().unwrap()[k].as_array().unwrap();
                    for i in 0..3 {
                        let x = v[i].as_float().unwrap();
                        assert!(
                            (x - want[i]).abs() < 1e-15,
                            "{file}: frame {x} vs {}",
                            want[i]
                        );
                    }
                }
                checked += 1;
            }
            assert!(checked > 0, "{file}");
        }
    }

    #[test]
    fn the_fandisk_tube_is_trimmed_at_the_edge_it_straddles() {
        let s = ShapeSpec::named("fandisk-tube").build().unwrap();
        let info = s.info();
        assert!(!info.closed);
        assert_eq!(info.genus, 0);
        // The edge E under the tube is cut in two, with a corner at each end on J.
        let corners_on_j = s
            .feature_curves()
            .iter()
            .filter(|c| c.is_corner && s.feature_distance(c.points[0]) < 1e-12)
            .count();
        assert!(corners_on_j >= 2);
        // No part edge runs through the tube: every edge point is on the union (an
        // untrimmed edge E would run inside the tube, off the surface).
        let curves = s.feature_curves();
        for c in curves[..curves.len() - 1].iter().filter(|c| !c.is_corner) {
            for w in c.points.windows(2) {
                let m = 0.5 * (w[0] + w[1]);
                // Chords of arcs are within their 1e-5 tolerance.
                assert!(s.distance(m) < 1.1e-5, "{m}: {}", s.distance(m));
            }
        }
    }
}
