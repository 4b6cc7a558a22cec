//! `jet`: normal of a degree-2 osculating jet (Cazals & Pouget 2005), the estimator CGAL
//! ships as `jet_estimate_normals` and most papers compare against.
//!
//! In the PCA frame of the k nearest neighbours, with the query point at the origin, the
//! height function `w = c0 + c1 u + c2 v + c3 u^2 + c4 u v + c5 v^2` is fitted by least
//! squares; the normal is that of the jet above the query point, `(-c1, -c2, 1)`.

use glam::{DMat3, DVec3};
use nalgebra::{SMatrix, SVector};
use reconbench_geom::PointCloud;
use reconbench_geom::linalg::sym_eigen3;
use reconbench_geom::method::{
    Describe, MethodError, NormalEstimator, Normals, ParamDoc, RunCtx, Unit,
};
use serde::{Deserialize, Serialize};

use crate::neighbors::{ORIENT_K_DOC, check_k, estimate_per_point};
use crate::plane_fit::fit_plane_normal;

/// Parameters of `jet`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct JetParams {
    /// Neighbourhood size, the point itself included (CGAL's examples use 18).
    pub k: usize,
    /// Neighbours of the MST orientation graph; 0 leaves normals unoriented.
    pub orient_k: usize,
}

impl Default for JetParams {
    fn default() -> Self {
        Self {
            k: 18,
            orient_k: 18,
        }
    }
}

/// `jet` normal estimator.
#[derive(Debug, Clone, Default)]
pub struct Jet {
    /// Parameters.
    pub params: JetParams,
}

/// Monomials of the degree-2 jet at `(u, v)`.
fn monomials(u: f64, v: f64) -> SVector<f64, 6> {
    SVector::<f64, 6>::new(1.0, u, v, u * u, u * v, v * v)
}

/// The jet normal at `points[row[0]]` from its neighbour `row`; falls back to the plane
/// fit when the least-squares system is singular (fewer than 6 points in general
/// position), and returns zero for a degenerate neighbourhood.
pub fn jet_normal(points: &[DVec3], row: &[u32]) -> DVec3 {
    let p = points[row[0] as usize];
    let mut cov = DMat3::ZERO;
    let c = row.iter().map(|&j| points[j as usize]).sum::<DVec3>() / row.len() as f64;
    let mut scale: f64 = 0.0;
    for &j in row {
        let d = points[j as usize] - c;
        cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        scale = scale.max(points[j as usize].distance(p));
    }
    let Ok(eig) = sym_eigen3(cov) else {
        return DVec3::ZERO;
    };
    let plane = fit_plane_normal(points, row, |_| 1.0);
    if plane == DVec3::ZERO || row.len() < 6 || scale == 0.0 {
        return plane;
    }
    let (e_u, e_v, e_w) = (eig.vectors[2], eig.vectors[1], eig.vectors[0]);
    // Normal equations in coordinates scaled to the neighbourhood radius: well
    // conditioned for degree 2 and allocation free.
    let mut ata = SMatrix::<f64, 6, 6>::zeros();
    let mut atb = SVector::<f64, 6>::zeros();
    for &j in row {
        let d = (points[j as usize] - p) / scale;
        let m = monomials(d.dot(e_u), d.dot(e_v));
        ata += m * m.transpose();
        atb += m * d.dot(e_w);
    }
    let Some(chol) = ata.cholesky() else {
        return plane;
    };
    let coef = chol.solve(&atb);
    let n = (-coef[1] * e_u - coef[2] * e_v + e_w).normalize_or_zero();
    if n.is_finite() && n != DVec3::ZERO {
        n
    } else {
        plane
    }
}

impl Describe for Jet {
    const NAME: &'static str = "jet";
    const SOURCE: &'static str = "baseline (CGAL)";
    const SUMMARY: &'static str = "degree-2 osculating jet (Cazals & Pouget 2005)";
    type Params = JetParams;
    const PARAMS: &'static [ParamDoc] = &[
        ParamDoc::new(
            "k",
            Unit::Count,
            "neighbourhood size incl. the point itself (CGAL examples: 18)",
        ),
        ORIENT_K_DOC,
    ];

    fn from_params(params: JetParams) -> Result<Self, MethodError> {
        check_k("k", params.k, 6)?;
        Ok(Self { params })
    }
}

impl NormalEstimator for Jet {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn estimate(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Normals, MethodError> {
        let p = &self.params;
        estimate_per_point(cloud, ctx, p.k, 6, p.orient_k, jet_normal)
    }
}
