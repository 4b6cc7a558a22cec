//! `lvm-approx`: the stand-in for OuYang & Feng's local Voronoi mesh normals, exactly as
//! seed 000's ASSUMPTION B-09 defines it (the original paper is not available, so this is
//! labelled "LVM-approx", never "LVM").
//!
//! Steps: k = 15 nearest neighbours; a provisional plane-fit normal `n0`; projection onto
//! the plane through the point with normal `n0`, whose 2D Delaunay one-ring gives the
//! natural neighbours; with at least 5 of them a fit of `z = a x^2 + b xy + c y^2 + d x +
//! e y` (through the point) giving `(-d, -e, 1)`; with 3-4, the angle-weighted mean of the
//! one-ring triangle normals; otherwise `n0`.

use glam::{DVec2, DVec3};
use nalgebra::{SMatrix, SVector};
use reconbench_geom::PointCloud;
use reconbench_geom::method::{
    Describe, MethodError, NormalEstimator, Normals, ParamDoc, RunCtx, Unit,
};
use serde::{Deserialize, Serialize};

use crate::neighbors::{ORIENT_K_DOC, check_k, estimate_per_point};
use crate::plane_fit::fit_plane_normal;

/// Largest supported k: neighbourhoods live in fixed-size stack buffers.
pub const MAX_K: usize = 64;

/// Parameters of `lvm-approx`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LvmApproxParams {
    /// Neighbourhood size, the point itself included (ASSUMPTION B-09: 15).
    pub k: usize,
    /// Neighbours of the MST orientation graph; 0 leaves normals unoriented.
    pub orient_k: usize,
}

impl Default for LvmApproxParams {
    fn default() -> Self {
        Self {
            k: 15,
            orient_k: 18,
        }
    }
}

/// `lvm-approx` normal estimator.
#[derive(Debug, Clone, Default)]
pub struct LvmApprox {
    /// Parameters.
    pub params: LvmApproxParams,
}

/// Whether the 2D segment from the origin to `q` is a Delaunay edge of `pts` (which
/// contains the origin and `q` themselves; co-circular ties count as edges).
///
/// Circles through 0 and q have centres `m + t n` on the bisector; a point r on the
/// left of the segment excludes centres beyond a bound, one on the right centres before
/// one: the edge exists when some t satisfies every bound.
fn is_delaunay_edge(q: DVec2, pts: &[DVec2]) -> bool {
    let m = 0.5 * q;
    let n = q.perp().normalize();
    let rv = m.length_squared();
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for &r in pts {
        if r == DVec2::ZERO || r == q {
            continue;
        }
        let s = n.dot(r - m);
        let a = (r - m).length_squared() - rv;
        if s > 0.0 {
            hi = hi.min(a / (2.0 * s));
        } else if s < 0.0 {
            lo = lo.max(a / (2.0 * s));
        } else if a < 0.0 {
            return false; // r lies strictly between the two ends
        }
    }
    lo <= hi
}

/// The LVM-approx normal of `points[row[0]]`.
pub fn lvm_normal(points: &[DVec3], row: &[u32]) -> DVec3 {
    let p = points[row[0] as usize];
    let n0 = fit_plane_normal(points, row, |_| 1.0);
    if n0 == DVec3::ZERO {
        return n0;
    }
    let (ex, ey) = n0.any_orthonormal_pair();
    let mut local = [DVec3::ZERO; MAX_K];
    let mut plane = [DVec2::ZERO; MAX_K];
    let m = row.len().min(MAX_K);
    let scale = row
        .iter()
        .map(|&j| points[j as usize].distance(p))
        .fold(0.0, f64::max);
    if scale == 0.0 {
        return n0;
    }
    for (i, &j) in row[..m].iter().enumerate() {
        let d = (points[j as usize] - p) / scale;
        local[i] = DVec3::new(d.dot(ex), d.dot(ey), d.dot(n0));
        plane[i] = local[i].truncate();
    }
    // Natural neighbours: the Delaunay one-ring of the point in the tangent plane.
    let mut ring = [0usize; MAX_K];
    let mut nr = 0;
    for i in 1..m {
        if plane[i] != DVec2::ZERO && is_delaunay_edge(plane[i], &plane[..m]) {
            ring[nr] = i;
            nr += 1;
        }
    }
    let ring = &mut ring[..nr];
    let n_local = if nr >= 5 {
        quadric_normal(ring, &local)
    } else if nr >= 3 {
        one_ring_normal(ring, &local)
    } else {
        None
    };
    match n_local {
        Some(n) => (n.x * ex + n.y * ey + n.z * n0).normalize(),
        None => n0,
    }
}

/// Normal at the origin of `z = a x^2 + b xy + c y^2 + d x + e y` fitted to the ring.
fn quadric_normal(ring: &[usize], local: &[DVec3]) -> Option<DVec3> {
    let mut ata = SMatrix::<f64, 5, 5>::zeros();
    let mut atb = SVector::<f64, 5>::zeros();
    for &i in ring {
        let q = local[i];
        let r = SVector::<f64, 5>::new(q.x * q.x, q.x * q.y, q.y * q.y, q.x, q.y);
        ata += r * r.transpose();
        atb += r * q.z;
    }
    let c = ata.cholesky()?.solve(&atb);
    let n = DVec3::new(-c[3], -c[4], 1.0).normalize();
    n.is_finite().then_some(n)
}

/// Angle-weighted mean normal of the one-ring triangles (consecutive ring neighbours by
/// angle around the point, skipping gaps of half a turn or more, i.e. the boundary).
fn one_ring_normal(ring: &mut [usize], local: &[DVec3]) -> Option<DVec3> {
    ring.sort_by(|&a, &b| {
        let ta = local[a].y.atan2(local[a].x);
        let tb = local[b].y.atan2(local[b].x);
        ta.total_cmp(&tb)
    });
    let mut acc = DVec3::ZERO;
    for w in 0..ring.len() {
        let (a, b) = (local[ring[w]], local[ring[(w + 1) % ring.len()]]);
        let gap = a.truncate().perp_dot(b.truncate());
        if gap <= 0.0 {
            continue; // consecutive neighbours span half a turn or more: no triangle
        }
        let n = a.cross(b).normalize_or_zero();
        acc += a.angle_between(b) * n;
    }
    let n = acc.normalize_or_zero();
    (n != DVec3::ZERO).then_some(n)
}

fn check_max_k(k: usize) -> Result<(), MethodError> {
    if k > MAX_K {
        return Err(MethodError::InvalidParameter {
            name: "k".into(),
            message: format!("at most {MAX_K}, got {k}"),
        });
    }
    Ok(())
}

impl Describe for LvmApprox {
    const NAME: &'static str = "lvm-approx";
    const SOURCE: &'static str = "seed 000 §1.2.6";
    const SUMMARY: &'static str = "local Voronoi mesh stand-in (ASSUMPTION B-09)";
    type Params = LvmApproxParams;
    const PARAMS: &'static [ParamDoc] = &[
        ParamDoc::new(
            "k",
            Unit::Count,
            "neighbourhood size incl. the point itself (ASSUMPTION B-09: 15; at most 64)",
        ),
        ORIENT_K_DOC,
    ];

    fn from_params(params: LvmApproxParams) -> Result<Self, MethodError> {
        check_k("k", params.k, 4)?;
        check_max_k(params.k)?;
        Ok(Self { params })
    }
}

impl NormalEstimator for LvmApprox {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn estimate(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Normals, MethodError> {
        check_max_k(self.params.k)?;
        let p = &self.params;
        estimate_per_point(cloud, ctx, p.k, 4, p.orient_k, lvm_normal)
    }
}
