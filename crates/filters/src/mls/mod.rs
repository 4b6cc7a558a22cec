//! `mls`: projection MLS ("smooth standard MLS", seed 002 §2.5 and §6.9; Levin 2003,
//! Alexa et al. 2003). Every point is projected once onto the MLS surface of its `k`
//! nearest points (itself included) with the Gaussian weight `exp(-d^2 / h^2)`,
//! `h = h_rel x mean spacing`; the output is the projected points with their reference
//! plane normals, one per input point, in input order.
//!
//! The operator ([`project::mls_project`]) and the local feature line
//! ([`bezier::CubicBezier`]) are shared with `mls-sharp` ([`crate::mls_sharp`]), which
//! edits the neighbourhood before the same projection.

pub mod bezier;
pub mod project;

use rayon::prelude::*;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{
    Describe, Diagnostic, Diagnostics, Filter, Filtered, MethodError, ParamDoc, RunCtx, Unit,
};
use reconbench_geom::spatial::{KnnHit, knn_self_map, mean_spacing};
use serde::{Deserialize, Serialize};

use glam::DVec3;
pub use project::{MlsConfig, PolyDegree, Projection, mls_project};

/// Parameters shared by `mls` and `mls-sharp`: the neighbourhood and the projection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MlsParams {
    /// Neighbourhood size, the query's own sample included (thesis: 20; 40 at 2 %
    /// noise).
    pub k: usize,
    /// `h` in mean nearest-neighbour spacings (ASSUMPTION W-33: 0.8 = the thesis's
    /// h = 0.1 at its spacing 0.125; 4.0 = h 0.5; 7.2 = h 0.9).
    pub h_rel: f64,
    /// Plane fixed-point iterations (ASSUMPTION W-30; 1 = non-iterative).
    pub plane_iters: usize,
    /// Height polynomial degree (ASSUMPTION W-32).
    pub degree: PolyDegree,
}

impl Default for MlsParams {
    fn default() -> Self {
        Self {
            k: 20,
            h_rel: 0.8,
            plane_iters: 10,
            degree: PolyDegree::Quadratic,
        }
    }
}

/// The parameter docs of [`MlsParams`], in field order.
pub const MLS_PARAM_DOCS: [ParamDoc; 4] = [
    ParamDoc::new(
        "k",
        Unit::Count,
        "neighbourhood size, the query included (thesis: 20; 40 at 2 % noise)",
    ),
    ParamDoc::new(
        "h_rel",
        Unit::Spacing,
        "Gaussian width h in mean spacings (ASSUMPTION W-33: 0.8 = thesis h 0.1, 4.0 = h 0.5)",
    ),
    ParamDoc::new(
        "plane_iters",
        Unit::Count,
        "reference-plane fixed-point iterations (ASSUMPTION W-30; 1 = non-iterative)",
    ),
    ParamDoc::new(
        "degree",
        Unit::Choice,
        "height polynomial: constant, linear, quadratic (ASSUMPTION W-32: quadratic)",
    ),
];

impl MlsParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), MethodError> {
        let bad = |name: &str, message: String| {
            Err(MethodError::InvalidParameter {
                name: name.into(),
                message,
            })
        };
        if self.k < 3 {
            return bad("k", format!("must be at least 3, got {}", self.k));
        }
        if !(self.h_rel.is_finite() && self.h_rel > 0.0) {
            return bad(
                "h_rel",
                format!("must be a finite number > 0, got {}", self.h_rel),
            );
        }
        if self.plane_iters == 0 || self.plane_iters > 1000 {
            return bad(
                "plane_iters",
                format!("must be in 1..=1000, got {}", self.plane_iters),
            );
        }
        Ok(())
    }
}

/// What the projection of a cloud needs besides the neighbourhoods: the spacing and the
/// resulting operator settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setup {
    /// Mean nearest-neighbour spacing of the input (duplicates merged).
    pub spacing: f64,
    /// The projection settings (absolute `h`).
    pub cfg: MlsConfig,
}

/// Checks the cloud and derives `h` from its spacing: errors name the problem (too few
/// points, all points coincident).
pub fn setup(cloud: &PointCloud, p: &MlsParams) -> Result<Setup, MethodError> {
    let n = cloud.len();
    if n < 3 {
        return Err(MethodError::InvalidInput(format!(
            "MLS projection needs at least 3 points, got {n}"
        )));
    }
    let spacing = mean_spacing(cloud.positions(), 1)
        .map_err(|e| MethodError::InvalidInput(format!("MLS projection: {e}")))?;
    let diag = cloud.aabb().diagonal();
    // ASSUMPTION W-33: h relative to the mean spacing (seed 002 §6.6).
    let h = p.h_rel * spacing;
    Ok(Setup {
        spacing,
        cfg: MlsConfig {
            h,
            plane_iters: p.plane_iters,
            // seed 002 §2.5: stop when the foot moves less than 1e-9 of the diagonal.
            tolerance: 1e-9 * diag,
            degree: p.degree,
        },
    })
}

/// One output point of a projection pass (plain data so the parallel map can collect
/// it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projected {
    /// Output position.
    pub point: DVec3,
    /// Output normal (zero when the neighbourhood spans no plane).
    pub normal: DVec3,
    /// Bit flags: [`FLAG_UNPROJECTED`], [`FLAG_LOWERED`], [`FLAG_UNWEIGHTED`],
    /// [`FLAG_SHARP`].
    pub flags: u8,
    /// Plane iterations done.
    pub iterations: u8,
}

/// The neighbourhood spans no plane: the point is kept where it was, normal zero.
pub const FLAG_UNPROJECTED: u8 = 1;
/// The height polynomial fell back to a lower degree.
pub const FLAG_LOWERED: u8 = 2;
/// A plane step used unit weights.
pub const FLAG_UNWEIGHTED: u8 = 4;
/// `mls-sharp` edited the neighbourhood (a feature line was used).
pub const FLAG_SHARP: u8 = 8;

/// The projection of `r` as a [`Projected`], the point unchanged if it cannot be
/// projected.
pub fn project_or_keep(
    r: DVec3,
    nbrs: &[DVec3],
    cfg: &MlsConfig,
    hint: DVec3,
    w: &mut Vec<f64>,
) -> Projected {
    match mls_project(r, nbrs, cfg, hint, w) {
        Some(p) => Projected {
            point: p.point,
            normal: p.normal,
            flags: u8::from(p.lowered_degree) * FLAG_LOWERED
                + u8::from(p.unweighted) * FLAG_UNWEIGHTED,
            iterations: p.iterations.min(255) as u8,
        },
        None => Projected {
            point: r,
            normal: DVec3::ZERO,
            flags: FLAG_UNPROJECTED,
            iterations: 0,
        },
    }
}

/// Builds the output of a projection pass: positions and normals replaced, every other
/// attribute kept, source = identity; diagnostics count the flags.
pub fn finish(
    cloud: &PointCloud,
    out: Vec<Projected>,
    setup: &Setup,
    p: &MlsParams,
    mut diagnostics: Diagnostics,
) -> Result<Filtered, MethodError> {
    let n = out.len();
    let count = |f: u8| out.iter().filter(|o| o.flags & f != 0).count() as f64;
    diagnostics.insert("h".into(), Diagnostic::Number(setup.cfg.h));
    diagnostics.insert("h_rel".into(), Diagnostic::Number(p.h_rel));
    diagnostics.insert("spacing".into(), Diagnostic::Number(setup.spacing));
    diagnostics.insert(
        "unprojected".into(),
        Diagnostic::Number(count(FLAG_UNPROJECTED)),
    );
    diagnostics.insert(
        "lowered_degree".into(),
        Diagnostic::Number(count(FLAG_LOWERED)),
    );
    diagnostics.insert(
        "unweighted".into(),
        Diagnostic::Number(count(FLAG_UNWEIGHTED)),
    );
    let iters: u64 = out.iter().map(|o| o.iterations as u64).sum();
    diagnostics.insert(
        "plane_iterations_mean".into(),
        Diagnostic::Number(iters as f64 / n.max(1) as f64),
    );
    let (positions, normals): (Vec<DVec3>, Vec<DVec3>) =
        out.par_iter().map(|o| (o.point, o.normal)).unzip();
    let cloud = cloud
        .clone()
        .with_positions(positions)?
        .with_normals(normals)?;
    Ok(Filtered {
        cloud,
        source: Some((0..n as u32).collect()),
        diagnostics,
    })
}

/// The `mls` filter: smooth projection MLS of every point.
#[derive(Debug, Clone, Default)]
pub struct Mls {
    /// Parameters.
    pub params: MlsParams,
}

/// Per-rayon-job scratch of a projection pass.
#[derive(Debug, Default)]
pub struct Scratch {
    /// Neighbour positions.
    pub nbrs: Vec<DVec3>,
    /// Weights.
    pub w: Vec<f64>,
}

impl Describe for Mls {
    const NAME: &'static str = "mls";
    const SOURCE: &'static str = "seed 002 §2.5, §6.9 (Levin; Alexa et al. projection MLS)";
    const SUMMARY: &'static str =
        "projection MLS: each point onto the MLS surface of its k neighbours, with plane normals";
    type Params = MlsParams;
    const PARAMS: &'static [ParamDoc] = &MLS_PARAM_DOCS;

    fn from_params(params: MlsParams) -> Result<Self, MethodError> {
        params.validate()?;
        Ok(Self { params })
    }
}

impl Filter for Mls {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn filter(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Filtered, MethodError> {
        let s = ctx.phase("spacing", || setup(cloud, &self.params))?;
        ctx.checkpoint()?;
        let hints = cloud.normals();
        let out = ctx.phase("project", || {
            knn_self_map(
                cloud.positions(),
                self.params.k,
                false,
                Scratch::default,
                |sc: &mut Scratch, i: usize, hits: &[KnnHit]| {
                    sc.nbrs.clear();
                    sc.nbrs.extend(hits.iter().map(|h| h.point));
                    let hint = hints.map_or(DVec3::ZERO, |n| n[i]);
                    project_or_keep(cloud.positions()[i], &sc.nbrs, &s.cfg, hint, &mut sc.w)
                },
            )
        })?;
        ctx.checkpoint()?;
        finish(cloud, out, &s, &self.params, Diagnostics::new())
    }
}
